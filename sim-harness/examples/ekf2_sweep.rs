//! EKF2 setting sweep: error std (truth) / agreement std (ref_*) per flight for EKF2
//! settings given as `window,hold,ground[,slip[,min_airspeed]]` (s, s, m/s, m/s², m/s);
//! `SEEDS=n` averages the simulated flights over seeds 1..=n.
//! `SEEDS=6 cargo run --release -p sim-harness --example ekf2_sweep -- 0,0,0 0.5,3,2,3`
use sim_harness::estimate::replay_estimates;
use sim_harness::metrics::compare;
use sim_harness::{csv, data, sim};
use wing_ahrs::config::Ekf2Config;
use wing_ahrs::{Config, Model};

fn main() -> anyhow::Result<()> {
    let seeds: u64 = std::env::var("SEEDS").ok().and_then(|s| s.parse().ok()).unwrap_or(1);
    let mut logs: Vec<(String, Vec<sim_harness::log::FlightLog>)> = vec![];
    for name in ["flight1", "flight2", "aggressive", "level"] {
        let sc = sim::load_scenario(name)?.with_spec(sim::SensorSpec::Thesis);
        logs.push((name.to_string(), (1..=seeds).map(|s| sim::run(&sc, s).unwrap().log).collect()));
    }
    for name in data::REAL_FLIGHTS {
        if let Some(p) = data::real_log(name) {
            logs.push((name.to_string(), vec![csv::read_log(&p)?]));
        }
    }
    for arg in std::env::args().skip(1) {
        let v: Vec<f32> = arg.split(',').map(|s| s.parse()).collect::<Result<_, _>>()?;
        if v.len() < 3 {
            anyhow::bail!("setting {arg:?}: expected window,hold,ground[,slip[,min_airspeed]]");
        }
        let mut e2 = Ekf2Config {
            window: v[0],
            airborne_hold: v[1],
            ground_speed_static: v[2],
            ..Ekf2Config::default()
        };
        if let Some(m) = v.get(3) {
            e2.max_lateral_accel = *m;
        }
        if let Some(m) = v.get(4) {
            e2.min_airspeed = *m;
        }
        let cfg = Config::euler().with_model(Model::Ekf2(e2));
        print!("{arg:>12}:");
        for (name, runs) in &logs {
            // Mean over seeds of the per-run error std.
            let mut s = [0.0f64; 3];
            let mut worst = 0.0f64;
            for log in runs {
                let (est, _) = replay_estimates(log, cfg);
                let c = compare(log, &est, 20.0).unwrap();
                for i in 0..3 {
                    s[i] += c.att[i].std.to_degrees() / runs.len() as f64;
                    worst = worst.max(c.att[i].std.to_degrees());
                }
            }
            print!(" {}:{:.2}/{:.2}/{:.2}", &name[..name.len().min(10)], s[0], s[1], s[2]);
            if runs.len() > 1 {
                print!(" (worst {worst:.2})");
            }
        }
        println!();
    }
    Ok(())
}
