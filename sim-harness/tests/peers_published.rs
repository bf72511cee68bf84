//! Each navigation peer against a published no-magnetometer accuracy (issue 33), on a
//! JSBSim flight that suits both: `rand3`, a Cessna 182 turning from early on (its
//! Gaussian-sum yaw estimators get acceleration soon; fusion-nav's known loss #218 — GNSS
//! velocity fused under an unmeasured yaw in a straight in-air start — is not what is
//! measured here), 5.6 m/s wind, moderate turbulence, thesis-spec sensors, the matched
//! configuration, scored from the comparison's common settled time. docs/peers.md,
//! "Published figures", has every candidate flight's figures, the ones that fail included.
//!
//! - fusion-nav publishes its accuracy (VALIDATION.md → validation/accuracy.md, scenario
//!   `no_mag`: GNSS, no magnetometer): tilt 0.729° RMS, heading 6.623° RMS. It must reach
//!   each within 1.5×.
//! - PX4 publishes no attitude-accuracy figure for EKF2. It is held to the same published
//!   no-magnetometer tilt figure, within 1.5×, on the median of its candidate flights
//!   ([`EKF2_FLIGHTS`]: its in-air start without heading varies too much from one to the next). (Its own covariance is no such claim to hold
//!   it to: it reports 0.1–0.5° of tilt σ where it errs 0.6–1.3°, docs/peers.md.)
//!
//! Needs python3 with the PyPI package jsbsim: skipped without it, failed under
//! `WING_AHRS_REQUIRE_DATA` (`cargo xtask test`).

use sim_harness::compare::{nominal_dt, DEFAULT_WARMUP};
use sim_harness::data;
use sim_harness::log::FlightLog;
use sim_harness::metrics::{tilt_error, wrap};
use sim_harness::peers::px4_ekf2::Px4Ekf2;
use sim_harness::peers::setup::{SensorFigures, Setup, Tuning};
use sim_harness::peers::{fusion_nav::FusionNav, Estimator};
use sim_harness::sim::sensors::SensorParams;

/// fusion-nav's published no-magnetometer accuracy, degrees RMS (tilt, heading).
const FUSION_NAV_NO_MAG: (f64, f64) = (0.729, 6.623);
/// The flight (see above).
const FLIGHT: &str = "rand3";
/// How far from the published figure a peer may be.
const MARGIN: f64 = 1.5;

fn flight(test: &str, name: &str) -> Option<FlightLog> {
    if !data::python_has("jsbsim") {
        data::skip(test, "python3 with the PyPI package jsbsim absent (pip install jsbsim)");
        return None;
    }
    let dir =
        std::env::temp_dir().join(format!("wing-published-{}-{test}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let truth = dir.join("truth.csv");
    sim_harness::jsbsim::fly(name, &truth).unwrap();
    let log = sim_harness::jsbsim::export(&truth, &SensorParams::thesis(), 1).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    Some(log)
}

/// Tilt and yaw error RMS from the settled time, degrees, calling `each` after every
/// settled sample.
fn score<E: Estimator>(log: &FlightLog, est: &mut E, mut each: impl FnMut(&E)) -> (f64, f64) {
    let (mut tilt, mut yaw, mut n) = (0.0, 0.0, 0usize);
    for row in &log.rows {
        est.step(row);
        let (Some(truth), true) = (row.truth, row.t >= DEFAULT_WARMUP) else { continue };
        let got = est.attitude();
        tilt += tilt_error(got, truth).powi(2);
        yaw += wrap(got[2] - truth[2]).powi(2);
        n += 1;
        each(est);
    }
    ((tilt / n as f64).sqrt().to_degrees(), (yaw / n as f64).sqrt().to_degrees())
}

#[test]
fn fusion_nav_reaches_its_published_no_magnetometer_accuracy() {
    let Some(log) = flight("fusion_nav_reaches_its_published_no_magnetometer_accuracy", FLIGHT)
    else {
        return;
    };
    let setup = Setup::for_log(&log, nominal_dt(&log), Tuning::Matched, SensorFigures::thesis());
    let (tilt, yaw) = score(&log, &mut FusionNav::with_setup(&setup), |_| {});
    println!("fusion-nav on jsbsim:{FLIGHT}: tilt {tilt:.3}° yaw {yaw:.3}° RMS (published {FUSION_NAV_NO_MAG:?})");
    assert!(tilt <= MARGIN * FUSION_NAV_NO_MAG.0, "tilt {tilt:.3}° RMS");
    assert!(yaw <= MARGIN * FUSION_NAV_NO_MAG.1, "yaw {yaw:.3}° RMS");
}

/// EKF2's candidate flights (docs/peers.md, "Published figures"): the JSBSim flights with
/// turns and no aerobatics. Its in-air start without a heading sensor decides its tilt from
/// 30 s flight by flight (matched, the spec's accelerometer bias: `c172_turns` 0.49°,
/// `j3cub_turns` 1.01°, `rand1` 0.98°, `rand3` 2.15° — there its GNSS velocity is gated
/// out from 15 s to 95 s after the start, `examples/ekf2_residual.rs --trace`), so it is
/// held to the figure on their median, not on one flight.
const EKF2_FLIGHTS: [&str; 4] = ["c172_turns", "j3cub_turns", "rand1", "rand3"];

#[test]
fn ekf2_reaches_the_published_no_magnetometer_tilt_accuracy() {
    let mut tilts = Vec::new();
    for name in EKF2_FLIGHTS {
        let Some(log) = flight("ekf2_reaches_the_published_no_magnetometer_tilt_accuracy", name)
        else {
            return;
        };
        let setup =
            Setup::for_log(&log, nominal_dt(&log), Tuning::Matched, SensorFigures::thesis());
        let (mut var, mut n) = (0.0, 0usize);
        let (tilt, yaw) = score(&log, &mut Px4Ekf2::with_setup(&setup), |e| {
            var += f64::from(e.ekf().tilt_variance());
            n += 1;
        });
        let sigma = (var / n as f64).sqrt().to_degrees();
        println!("EKF2 on jsbsim:{name}: tilt {tilt:.3}° yaw {yaw:.3}° RMS, its reported tilt σ {sigma:.3}° RMS");
        tilts.push(tilt);
    }
    tilts.sort_by(f64::total_cmp);
    let median = (tilts[1] + tilts[2]) / 2.0;
    println!("EKF2 median tilt {median:.3}° RMS (published {:.3}°)", FUSION_NAV_NO_MAG.0);
    assert!(median <= MARGIN * FUSION_NAV_NO_MAG.0, "median tilt {median:.3}° RMS");
}
