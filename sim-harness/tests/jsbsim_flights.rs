//! The default filter on flights from JSBSim, a flight-dynamics model we did not write
//! (`scripts/jsbsim_fly.py`), through our thesis-spec sensor models: an aerobatic sequence
//! (loop, axial roll, 75° turns, Immelmann, inverted, split-S, Cuban eight) and seeded random
//! flights (airframe, wind up to 10 m/s, turbulence, bank and height schedule). Bounds are
//! the aerobatic goal with a margin for one seed; the figures print.

use sim_harness::data;
use sim_harness::estimate::replay_estimates;
use sim_harness::jsbsim;
use sim_harness::metrics::{compare, Comparison};
use sim_harness::sim::sensors::SensorParams;
use wing_ahrs::Config;

const DEG: f64 = 180.0 / std::f64::consts::PI;

/// Flies `name`, exports it through the thesis sensors (seed 1) and compares the default
/// filter with JSBSim's truth from 20 s on; `None` (skipped, or failed under
/// `cargo xtask test`) without python3 + jsbsim.
fn fly(test: &str, name: &str) -> Option<Comparison> {
    if !data::python_has("jsbsim") {
        data::skip(test, "python3 with the PyPI package jsbsim absent (pip install jsbsim)");
        return None;
    }
    let dir = std::env::temp_dir().join(format!("wing-jsbsim-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let truth = dir.join("truth.csv");
    jsbsim::fly(name, &truth).unwrap();
    let log = jsbsim::export(&truth, &SensorParams::thesis(), 1).unwrap();
    let (est, _) = replay_estimates(&log, Config::default());
    let c = compare(&log, &est, 20.0).unwrap();
    println!(
        "jsbsim:{name}: roll/pitch/yaw RMS {:.3}/{:.3}/{:.3}°, tilt RMS {:.3}° max {:.3}°, total RMS {:.3}° max {:.3}°",
        c.att[0].rms * DEG,
        c.att[1].rms * DEG,
        c.att[2].rms * DEG,
        c.tilt.rms * DEG,
        c.tilt.max_abs * DEG,
        c.total.rms * DEG,
        c.total.max_abs * DEG
    );
    let _ = std::fs::remove_dir_all(&dir);
    Some(c)
}

#[test]
fn holds_the_attitude_through_jsbsim_aerobatics() {
    let Some(c) = fly("holds_the_attitude_through_jsbsim_aerobatics", "t6_aerobatics") else {
        return;
    };
    // The goal for thesis sensors in still air: tilt and total ≤ 0.5° RMS, ≤ 2° max.
    // Measured 0.126° / 0.185° RMS, 0.34° / 0.63° max.
    assert!(c.tilt.rms * DEG <= 0.5, "tilt RMS {:.3}°", c.tilt.rms * DEG);
    assert!(c.total.rms * DEG <= 0.5, "total RMS {:.3}°", c.total.rms * DEG);
    assert!(c.tilt.max_abs * DEG <= 2.0, "tilt max {:.3}°", c.tilt.max_abs * DEG);
    assert!(c.total.max_abs * DEG <= 2.0, "total max {:.3}°", c.total.max_abs * DEG);
}

#[test]
fn random_jsbsim_flights_keep_roll_and_pitch() {
    for n in 1..=4 {
        let name = format!("rand{n}");
        let Some(c) = fly("random_jsbsim_flights_keep_roll_and_pitch", &name) else {
            return;
        };
        // Tilt (Euler roll is ill-defined through a loop's vertical) against the wind goal's
        // 0.3° RMS and 1.5° max for roll and pitch; measured ≤ 0.18° and ≤ 0.56°.
        assert!(c.tilt.rms * DEG <= 0.3, "{name}: tilt RMS {:.3}°", c.tilt.rms * DEG);
        assert!(c.tilt.max_abs * DEG <= 1.5, "{name}: tilt max {:.3}°", c.tilt.max_abs * DEG);
        // Yaw waits for the first turn in wind (the crab angle), so only "not lost" here.
        assert!(c.total.max_abs * DEG <= 20.0, "{name}: total max {:.3}°", c.total.max_abs * DEG);
    }
}
