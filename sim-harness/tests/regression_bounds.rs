//! Regression bounds on the headline's simulated flights: the default filter's roll, pitch
//! and yaw RMS, tilt RMS and total attitude error RMS (deg, after 10 s, seed 1) may not grow
//! beyond 1.5× of what they measured when the bounds were last set (`MEASURED`, the
//! figures `sim-harness report FLIGHT --models quat --from 10` printed on 2026-12-02 at
//! the commit that added the gust variance). A 2× regression on any flight fails here.
//! Improvements pass; re-measure and lower the table when they land.

use sim_harness::estimate::replay_estimates;
use sim_harness::metrics::compare;
use sim_harness::sim;
use wing_ahrs::Config;

const DEG: f64 = 180.0 / std::f64::consts::PI;
const FROM: f64 = 10.0;
const FACTOR: f64 = 1.5;
/// Below this a figure is noise-level; its bound is `FACTOR × FLOOR`, deg.
const FLOOR: f64 = 0.02;

/// Flight, then roll, pitch, yaw, tilt and total RMS, deg. Euler roll and yaw RMS on the
/// aerobatic flights are large because they are undefined at ±90° pitch: tilt and total
/// are the figures there.
const MEASURED: [(&str, [f64; 5]); 11] = [
    ("level", [0.039, 0.060, 0.892, 0.072, 0.896]),
    ("flight1", [0.056, 0.132, 0.405, 0.144, 0.432]),
    ("flight2", [0.157, 0.079, 0.173, 0.175, 0.249]),
    ("aggressive", [0.161, 0.071, 0.220, 0.176, 0.282]),
    ("flight1_outage", [0.089, 0.196, 0.431, 0.215, 0.482]),
    ("coordinated_turn", [0.084, 0.106, 0.398, 0.135, 0.422]),
    ("flight2+wind=3@90", [0.157, 0.086, 0.185, 0.179, 0.260]),
    ("flight2+wind=6@90", [0.157, 0.095, 0.201, 0.183, 0.274]),
    ("aggressive+wind=6@45", [0.168, 0.080, 0.259, 0.186, 0.319]),
    ("aerobatics", [2.197, 0.134, 2.247, 0.247, 0.583]),
    ("aerobatics_wind5", [6.907, 1.373, 7.157, 1.562, 2.622]),
];

fn measure(name: &str) -> [f64; 5] {
    let sc = sim::load_scenario(name).expect("scenario");
    let log = sim::run(&sc, 1).expect("simulation").log;
    let (est, _) = replay_estimates(&log, Config::default());
    let c = compare(&log, &est, FROM).expect("truth");
    [c.att[0].rms, c.att[1].rms, c.att[2].rms, c.tilt.rms, c.total.rms].map(|v| v * DEG)
}

#[test]
fn headline_flights_stay_within_1_5x_of_their_measured_errors() {
    const WHAT: [&str; 5] = ["roll", "pitch", "yaw", "tilt", "total"];
    let mut failures = Vec::new();
    for (name, was) in MEASURED {
        let now = measure(name);
        println!(
            "(\"{name}\", [{:.3}, {:.3}, {:.3}, {:.3}, {:.3}]),",
            now[0], now[1], now[2], now[3], now[4]
        );
        for i in 0..5 {
            let bound = FACTOR * was[i].max(FLOOR);
            if now[i] > bound {
                failures.push(format!("{name} {}: {:.3}° > {bound:.3}°", WHAT[i], now[i]));
            }
        }
    }
    assert!(failures.is_empty(), "regressed beyond {FACTOR}×: {failures:#?}");
}
