//! Accuracy against simulated truth (thesis-spec sensors, seed 1) with the bounds of
//! issue 4 / docs/design.md, thesis reference numbers, and the 24-hour run. Numbers are printed; the bounds are asserted.
use sim_harness::estimate::replay_estimates;
use sim_harness::metrics::{compare, error_at, symmetric_pd};
use sim_harness::sim;
use wing_ahrs::{Config, MeasNoise, Model};

const DEG: f64 = 180.0 / std::f64::consts::PI;
/// Convergence time excluded from the statistics, s.
const FROM: f64 = 10.0;

fn run(
    name: &str,
    model: Model,
) -> (sim_harness::log::FlightLog, Vec<sim_harness::estimate::EstimateRow>) {
    let sc = sim::load_scenario(name).unwrap().with_spec(sim::SensorSpec::Thesis);
    let log = sim::run(&sc, 1).unwrap().log;
    let (est, _) = replay_estimates(&log, Config::euler().with_model(model));
    (log, est)
}

fn stats(name: &str, model: Model) -> ([f64; 3], [f64; 3]) {
    let (log, est) = run(name, model);
    let c = compare(&log, &est, FROM).unwrap();
    let std = c.att.map(|s| s.std * DEG);
    let rms = c.att.map(|s| s.rms * DEG);
    println!(
        "{name} {}: error std {:.3}/{:.3}/{:.3}°, RMS {:.3}/{:.3}/{:.3}°",
        if matches!(model, Model::Ekf1(_)) { "EKF1" } else { "EKF2" },
        std[0],
        std[1],
        std[2],
        rms[0],
        rms[1],
        rms[2]
    );
    (std, rms)
}

fn le(v: [f64; 3], lim: [f64; 3], what: &str) {
    for i in 0..3 {
        assert!(v[i] <= lim[i], "{what}: axis {i}: {:.3}° > {:.3}° (all: {v:?})", v[i], lim[i]);
    }
}

#[test]
fn flight1_ekf1_beats_thesis_table_5_2() {
    let (std, rms) = stats("flight1", Model::Ekf1(Default::default()));
    le(std, [0.135, 0.136, 0.759], "flight1 EKF1 std vs thesis Table 5.2");
    le(rms, [0.10, 0.10, 0.5], "flight1 EKF1 RMS vs the issue's aim");
}

/// flight2 flies with sideslip: the course-derived yaw assumes β = 0, which the
/// sideslip rule (no yaw update while |mean Ay| is large) and the 2° yaw floor of R
/// absorb; pitch depends on it through the heading-frame rotation.
#[test]
fn flight2_ekf1_within_issue_bounds() {
    let (_, rms) = stats("flight2", Model::Ekf1(Default::default()));
    le(rms, [0.3, 0.3, 1.0], "flight2 EKF1 RMS");
}

/// EKF2 (windowed form, the default) against Tables 5.6 and 5.8 (std). Measured, seed 1:
/// flight1 0.106/0.115/0.109°, flight2 0.511/0.145/0.263° (`report --from 20`). Before the
/// windowed form flight2 pitch was 0.381° > 0.356° (0.31° after the random-walk bias model);
/// the slip limit (`ekf2.max_lateral_accel`) takes it to 0.15°.
#[test]
fn ekf2_flight1_and_flight2_no_worse_than_thesis_tables_5_6_and_5_8() {
    let (std1, _) = stats("flight1", Model::Ekf2(Default::default()));
    le(std1, [0.704, 0.355, 0.751], "flight1 EKF2 std vs Table 5.6");
    let (std2, _) = stats("flight2", Model::Ekf2(Default::default()));
    le(std2, [1.753, 0.356, 1.810], "flight2 EKF2 std vs Table 5.8");
}

/// The thesis' EKF2 form (`ekf2.window = 0`: latest samples at each fix) still tracks
/// flight1; measured (from 10 s) 0.184/0.260/0.134°.
#[test]
fn ekf2_thesis_form_flight1_within_table_5_6() {
    let sc = sim::load_scenario("flight1").unwrap().with_spec(sim::SensorSpec::Thesis);
    let log = sim::run(&sc, 1).unwrap().log;
    let mut cfg = Config::euler().with_model(Model::Ekf2(Default::default()));
    cfg.ekf2_mut().unwrap().window = 0.0;
    let (est, _) = replay_estimates(&log, cfg);
    let c = compare(&log, &est, FROM).unwrap();
    let std = c.att.map(|s| s.std * DEG);
    println!("flight1 EKF2 thesis form: error std {:.3}/{:.3}/{:.3}°", std[0], std[1], std[2]);
    le(std, [0.704, 0.355, 0.751], "flight1 EKF2 (window = 0) std vs Table 5.6");
}

#[test]
fn error_after_20s_outage_within_thesis_table_5_10() {
    let (log, est) = run("flight1_outage", Model::Ekf1(Default::default()));
    let e = error_at(&log, &est, 79.99).unwrap().map(|x| x * DEG);
    println!("flight1_outage EKF1: error at t = 79.99 s: {:.3}/{:.3}/{:.3}° (thesis 0.557/−1.412/−3.081°, aim ≤ 1°)", e[0], e[1], e[2]);
    // The thesis' figure is one realisation; compare the attitude error magnitude
    // (RMS over the three axes): thesis 1.98°.
    let mag = |v: [f64; 3]| ((v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) / 3.0).sqrt();
    assert!(
        mag(e) <= mag([0.557, 1.412, 3.081]),
        "error after outage {:.3}° (RMS over axes) > thesis {:.3}°",
        mag(e),
        mag([0.557, 1.412, 3.081])
    );
    // Per axis: no worse than the thesis' realisation, and within the issue's 1° aim.
    for (i, lim) in [0.557f64, 1.412, 3.081].iter().enumerate() {
        assert!(
            e[i].abs() <= lim.min(1.0),
            "axis {i}: |{:.3}|° after the outage > min(thesis {lim}°, 1°)",
            e[i]
        );
    }
}

/// 24 simulated hours (8.64 M IMU steps) of level/loiter flight: no NaN, P stays
/// symmetric positive definite. Long: `cargo test --release -p sim-harness --test
/// harness_accuracy -- --ignored day_long`.
#[test]
#[ignore]
fn day_long_flight_stays_finite_and_pd() {
    let sc = sim::load_scenario("level")
        .unwrap()
        .with_spec(sim::SensorSpec::Thesis)
        .with_duration(86_400.0);
    let log = sim::run(&sc, 1).unwrap().log;
    assert!(log.rows.len() >= 8_640_000 - 10, "{} rows", log.rows.len());
    let mut bad = 0usize;
    let mut max_err = [0.0f64; 3];
    let mut k = 0usize;
    let ahrs = sim_harness::replay::run(&log, Config::euler(), |row, a| {
        k += 1;
        let x = a.state();
        if !x.iter().all(|v| v.is_finite())
            || (k.is_multiple_of(1000) && !symmetric_pd(&a.covariance(), 1e-4))
        {
            bad += 1;
        }
        if let (Some(t), true) = (row.truth, row.t > FROM) {
            for i in 0..3 {
                max_err[i] =
                    max_err[i].max(sim_harness::metrics::wrap(x[i] as f64 - t[i]).abs() * DEG);
            }
        }
    });
    println!(
        "24 h: {} steps, {bad} bad, max |err| {:.3}/{:.3}/{:.3}°, final sd {:?}",
        k,
        max_err[0],
        max_err[1],
        max_err[2],
        ahrs.std_dev()
    );
    assert_eq!(bad, 0);
    assert!(symmetric_pd(&ahrs.covariance(), 1e-4));
}

/// Issue 6: in straight and level flight the GPS velocity noise is most of the EKF1
/// measurement noise, and consecutive differences share a fix. Carrying that fix as states
/// (`MeasNoise::FromSensors::correlated_fix_noise`, the default) must beat taking the differences as
/// white on roll and on pitch, over 10 seeds (Monte Carlo mean of the per-run RMS), and
/// must not cost accuracy in the turning flight1. Measured: level 0.033/0.036° (white) →
/// 0.022/0.022°; flight1 0.051/0.045/0.123° → 0.045/0.029/0.096° (from 20 s).
#[test]
fn shared_fix_states_beat_white_differences() {
    use sim_harness::montecarlo;
    let mc = |name: &str, correlated: bool, from: f64| {
        let sc = sim::load_scenario(name).unwrap().with_spec(sim::SensorSpec::Thesis);
        let mut cfg = Config::euler();
        let e = cfg.euler_mut().unwrap();
        if let MeasNoise::FromSensors { correlated_fix_noise, .. } = &mut e.meas_noise {
            *correlated_fix_noise = correlated;
        }
        let r = montecarlo::run(10, 1, cfg, from, false, |s| Ok(sim::run(&sc, s)?.log)).unwrap();
        let rms = r.err_rms.map(|v| v * DEG);
        println!(
            "{name} correlated={correlated}: mean RMS {:.3}/{:.3}/{:.3}°",
            rms[0], rms[1], rms[2]
        );
        rms
    };
    let (white, corr) = (mc("level", false, FROM), mc("level", true, FROM));
    for i in 0..2 {
        assert!(
            corr[i] < 0.8 * white[i],
            "level axis {i}: {:.3}° not 20 % below white {:.3}°",
            corr[i],
            white[i]
        );
    }
    let (white, corr) = (mc("flight1", false, 20.0), mc("flight1", true, 20.0));
    le(corr, white, "flight1: shared-fix states vs white");
}
