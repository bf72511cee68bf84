//! In-air switch-on in a 25–35° bank over the robustness suite's own worlds (every
//! `air-bank30` world of the given seeds, simulator and JSBSim, both sensor grades, every
//! rate, latency and wind, honest receiver): the tilt error 5 s after the first two fixes
//! and the tilt RMS from 15 s, against the goals (1° and 0.3°).
//! `cargo run --release -p sim-harness --example in_air_survey -- [SEEDS, e.g. 1-10] [-v]`
use sim_harness::robust::{self, Start};
use sim_harness::sim::SensorSpec;

fn main() {
    sim_harness::quiet_on_closed_pipe();
    let args: Vec<String> = std::env::args().skip(1).collect();
    let verbose = args.iter().any(|a| a == "-v");
    let seeds = args.iter().find(|a| *a != "-v").map_or("1-10", |s| s.as_str());
    let Some((a, b)) =
        seeds.split_once('-').and_then(|(a, b)| Some((a.parse().ok()?, b.parse().ok()?)))
    else {
        eprintln!("seeds: FIRST-LAST, e.g. 1-10 (got {seeds})");
        std::process::exit(2)
    };
    let (a, b): (u64, u64) = (a, b);
    // Per sensor grade: tilt at 5 s, RMS from 15 s.
    let mut at5: [Vec<f64>; 2] = Default::default();
    let mut late: [Vec<f64>; 2] = Default::default();
    for seed in a..=b {
        for w in robust::worlds(96, seed).into_iter().filter(|w| w.start == Start::AirBank) {
            let log = match robust::flight(&w, "honest".parse().unwrap()) {
                Ok(l) => l,
                Err(e) => {
                    eprintln!("{}: {e:#}", w.label());
                    continue;
                }
            };
            let g = usize::from(w.spec == SensorSpec::Realistic);
            let t0 = log.rows[0].t;
            let Some(tf) = log.rows.iter().filter(|r| r.gps.is_some()).map(|r| r.t).nth(1) else {
                continue;
            };
            let (mut e5, mut sq, mut n) = (f64::NAN, 0.0, 0usize);
            let cfg = robust::told(wing_ahrs::Config::default(), &w);
            sim_harness::replay::run(&log, cfg, |row, ahrs| {
                let (Some(tr), a) = (row.truth, ahrs.attitude()) else { return };
                let e =
                    sim_harness::metrics::tilt_error([a.roll, a.pitch, a.yaw].map(f64::from), tr);
                if e5.is_nan() && row.t >= tf + 5.0 {
                    e5 = e;
                }
                if row.t >= t0 + 15.0 {
                    sq += e * e;
                    n += 1;
                }
            });
            let rms = (sq / n.max(1) as f64).sqrt();
            if verbose {
                println!(
                    "{:60} seed {:4} tilt at 5 s {:5.2}°, RMS from 15 s {:5.3}°",
                    w.label(),
                    w.seed,
                    e5.to_degrees(),
                    rms.to_degrees()
                );
            }
            at5[g].push(e5.to_degrees());
            late[g].push(rms.to_degrees());
        }
    }
    for (g, name) in ["thesis", "realistic"].iter().enumerate() {
        let q = |v: &mut Vec<f64>, p: f64| {
            v.sort_by(f64::total_cmp);
            v.get(((v.len() as f64 - 1.0) * p).round() as usize).copied().unwrap_or(f64::NAN)
        };
        let (x, y) = (&mut at5[g].clone(), &mut late[g].clone());
        println!(
            "{name:9} {:3} runs | tilt at 5 s: median {:.2}°, 90 % {:.2}°, max {:.2}°, above 1°: {} | RMS from 15 s: median {:.3}°, 90 % {:.3}°, max {:.3}°, above 0.3°: {}",
            x.len(),
            q(x, 0.5),
            q(x, 0.9),
            q(x, 1.0),
            x.iter().filter(|e| **e > 1.0).count(),
            q(y, 0.5),
            q(y, 0.9),
            q(y, 1.0),
            y.iter().filter(|e| **e > 0.3).count()
        );
    }
}
