//! The quaternion filter in wind against the simulator's truth: attitude, heading and
//! the wind estimate itself, with and without an airspeed sensor.

use sim_harness::estimate::replay_estimates;
use sim_harness::log::FlightLog;
use wing_ahrs::Config;

const DEG: f64 = 180.0 / std::f64::consts::PI;

fn flight(name: &str) -> FlightLog {
    let sc = sim_harness::sim::load_scenario(name).expect("scenario");
    sim_harness::sim::run(&sc, 3).expect("simulation").log
}

fn wrap(a: f64) -> f64 {
    (a + 3.0 * std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI
}

/// RMS roll/pitch/yaw error (deg) and RMS horizontal wind error (m/s) after `from` s,
/// the wind against the scenario's steady wind `steady` (turbulence is not the wind).
fn errors(log: &FlightLog, from: f64, steady: [f64; 2]) -> ([f64; 3], f64, usize) {
    let (est, _) = replay_estimates(log, Config::default());
    let (mut att, mut wind, mut n, mut nw) = ([0.0; 3], 0.0, 0usize, 0usize);
    for (row, e) in log.rows.iter().zip(&est) {
        if row.t < from {
            continue;
        }
        let tr = row.truth.expect("truth");
        for i in 0..3 {
            att[i] += wrap(e.att[i] - tr[i]).powi(2);
        }
        n += 1;
        if let Some((w, _)) = e.wind {
            wind += (w[0] - steady[0]).powi(2) + (w[1] - steady[1]).powi(2);
            nw += 1;
        }
    }
    (att.map(|s| (s / n as f64).sqrt() * DEG), (wind / nw.max(1) as f64).sqrt(), nw)
}

#[test]
fn wind_and_attitude_match_truth_with_and_without_an_airspeed_sensor() {
    // 6 m/s from the east, i.e. blowing west: [0, −6] NED. flight2's first full turn ends
    // at ~31 s.
    let log = flight("flight2+wind=6@90");
    assert!(log.rows.iter().any(|r| r.airspeed.is_some()), "the flight has an airspeed sensor");
    let truth_wind = log.rows.last().unwrap().truth_wind.expect("wind truth");
    assert!((truth_wind[1] + 6.0).abs() < 1e-6 && truth_wind[0].abs() < 1e-6);
    let (att, wind, nw) = errors(&log, 40.0, [0.0, -6.0]);
    println!("with airspeed: RMS {:.3}/{:.3}/{:.3}°, wind {wind:.2} m/s", att[0], att[1], att[2]);
    assert!(nw > 1000);
    assert!(att[0] < 0.3 && att[1] < 0.3, "roll/pitch {att:?}");
    assert!(att[2] < 1.0, "yaw {att:?} (the crab angle is 13.9°)");
    assert!(wind < 0.5, "wind error {wind:.2} m/s");

    let mut no_air = log.clone();
    for r in &mut no_air.rows {
        r.airspeed = None;
    }
    let (att, wind, _) = errors(&no_air, 40.0, [0.0, -6.0]);
    println!(
        "without airspeed: RMS {:.3}/{:.3}/{:.3}°, wind {wind:.2} m/s",
        att[0], att[1], att[2]
    );
    assert!(att[0] < 0.6 && att[1] < 0.6 && att[2] < 2.0, "{att:?}");
    assert!(wind < 1.0, "wind error {wind:.2} m/s");
}

#[test]
fn the_euler_filter_is_what_fails_in_the_same_wind() {
    // The measurement the quaternion filter exists for: the thesis filter takes the course
    // as heading, so in a crosswind its yaw sits on the crab angle.
    let log = flight("flight2+wind=6@90");
    let (est, _) = replay_estimates(&log, Config::euler());
    let yaw: f64 = log
        .rows
        .iter()
        .zip(&est)
        .filter(|(r, _)| r.t >= 40.0)
        .map(|(r, e)| wrap(e.att[2] - r.truth.unwrap()[2]).powi(2))
        .sum::<f64>();
    let n = log.rows.iter().filter(|r| r.t >= 40.0).count() as f64;
    let yaw = (yaw / n).sqrt() * DEG;
    println!("Euler filter yaw RMS in 6 m/s: {yaw:.2}°");
    assert!(yaw > 2.0, "{yaw}");
}
