//! The evidence behind docs/peers.md's reasons table: for each `compare` item (first seed),
//! ours and the two navigation peers in the matched configuration — tilt RMS from the
//! common settled time (30 s, as `compare`) and from a later time, yaw RMS, the time each
//! converged, and when EKF2's yaw was aligned and how often its yaw jumped (> 11° between
//! samples: its Gaussian-sum yaw estimator's resets).
//! `cargo run --release -p sim-harness --example peer_ratio -- [--late S] [--seed N] ITEM…`
//! (items as `sim-harness compare` takes them; truth logs only for `converged`).
use anyhow::{bail, Result};
use ekf2::params::ControlStatus;
use sim_harness::compare::{converged_at, nominal_dt, Against, Item};
use sim_harness::metrics::{tilt_error, wrap};
use sim_harness::peers::fusion_nav::FusionNav;
use sim_harness::peers::px4_ekf2::Px4Ekf2;
use sim_harness::peers::setup::{Setup, Tuning};
use sim_harness::peers::wing::Wing;
use sim_harness::peers::Estimator;

struct Score {
    tilt: (f64, usize),
    late: (f64, usize),
    yaw: (f64, usize),
    tilts: Vec<(f64, f64)>,
}

fn rms(s: (f64, usize)) -> f64 {
    (s.0 / s.1.max(1) as f64).sqrt().to_degrees()
}

fn main() -> Result<()> {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut late = 90.0;
    if let Some(k) = args.iter().position(|a| a == "--late") {
        late = args.get(k + 1).and_then(|s| s.parse().ok()).unwrap_or(late);
        args.drain(k..(k + 2).min(args.len()));
    }
    let mut seed = 1;
    if let Some(k) = args.iter().position(|a| a == "--seed") {
        seed = args.get(k + 1).and_then(|s| s.parse().ok()).unwrap_or(seed);
        args.drain(k..(k + 2).min(args.len()));
    }
    if args.is_empty() {
        bail!("usage: peer_ratio [--late S] ITEM… (compare's items)");
    }
    println!("| flight | estimator | tilt RMS from 30 s | from {late:.0} s | yaw RMS from 30 s | converged | EKF2 yaw aligned | EKF2 yaw jumps |");
    println!("|---|---|---|---|---|---|---|---|");
    for name in &args {
        let item = Item::resolve(name)?;
        let Some((log, against)) = item.log(seed)? else { continue };
        let tuning = Item::tuning(Tuning::Matched, against);
        let setup = Setup::for_log(&log, nominal_dt(&log), tuning, item.figures());
        let t0 = log.rows[0].t;
        let (mut from, mut to) = (t0 + 30.0, f64::INFINITY);
        if against == Against::Reference {
            let (takeoff, landing) = sim_harness::real_logs::airborne(&log);
            if let Some(t) = takeoff {
                from = from.max(t + sim_harness::real_logs::AFTER_TAKEOFF);
            }
            to = landing.unwrap_or(to);
        }
        let ests: Vec<Box<dyn Estimator>> = vec![
            Box::new(Wing::ekf1_with(&setup)),
            Box::new(FusionNav::with_setup(&setup)),
            Box::new(Px4Ekf2::with_setup(&setup)),
        ];
        for mut e in ests {
            let mut s = Score { tilt: (0.0, 0), late: (0.0, 0), yaw: (0.0, 0), tilts: vec![] };
            let (mut aligned, mut jumps, mut prev) = (None, 0usize, None::<f64>);
            let is_ekf2 = e.name() == sim_harness::peers::px4_ekf2::NAME;
            for row in &log.rows {
                e.step(row);
                let want = match against {
                    Against::Truth => row.truth,
                    Against::Reference => row.reference,
                };
                let a = e.attitude();
                if is_ekf2 {
                    // Read the status through a fresh borrow: `e` is a trait object here.
                    if let Some(p) = prev {
                        jumps += usize::from(wrap(a[2] - p).abs() > 0.2);
                    }
                    prev = Some(a[2]);
                }
                let Some(want) = want else { continue };
                let tilt = tilt_error(a, want);
                s.tilts.push((row.t, tilt));
                if row.t >= from && row.t <= to {
                    s.tilt.0 += tilt * tilt;
                    s.tilt.1 += 1;
                    let y = wrap(a[2] - want[2]);
                    s.yaw.0 += y * y;
                    s.yaw.1 += 1;
                }
                if row.t >= t0 + late && row.t <= to {
                    s.late.0 += tilt * tilt;
                    s.late.1 += 1;
                }
            }
            if is_ekf2 {
                // Replay once more for the status flag's first time (cheap next to the rest).
                let mut k = Px4Ekf2::with_setup(&setup);
                for row in &log.rows {
                    k.step(row);
                    if k.ekf().control_status().contains(ControlStatus::YAW_ALIGN) {
                        aligned = Some(row.t - t0);
                        break;
                    }
                }
            }
            let conv = if against == Against::Truth {
                converged_at(t0, &s.tilts).map_or("never".into(), |c| format!("{c:.0} s"))
            } else {
                "—".into()
            };
            println!(
                "| {} | {} | {:.2}° | {:.2}° | {:.1}° | {conv} | {} | {} |",
                item.name,
                e.name(),
                rms(s.tilt),
                rms(s.late),
                rms(s.yaw),
                if is_ekf2 {
                    aligned.map_or("never".into(), |t| format!("{t:.0} s"))
                } else {
                    "—".into()
                },
                if is_ekf2 { jumps.to_string() } else { "—".into() },
            );
        }
    }
    Ok(())
}
