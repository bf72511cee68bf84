//! A real IMU's accelerometer bias, which no state of the six-state filter holds: learnt on
//! the host from one manoeuvring flight (`accel_cal`) and set in `Config::accel_bias`, the
//! tilt comes back to that of the same flight without the bias.

use sim_harness::{accel_cal, metrics, replay, sim};
use wing_ahrs::Config;

/// Tilt RMS of `log` replayed with `cfg` from 20 s, rad.
fn tilt_rms(log: &sim_harness::log::FlightLog, cfg: Config) -> f64 {
    let mut e = Vec::new();
    replay::run(log, cfg, |row, ahrs| {
        let (Some(tr), a) = (row.truth, ahrs.attitude()) else { return };
        if row.t >= 20.0 {
            e.push(metrics::tilt_error([a.roll, a.pitch, a.yaw].map(f64::from), tr));
        }
    });
    (e.iter().map(|x| x * x).sum::<f64>() / e.len() as f64).sqrt()
}

#[test]
fn a_learnt_accelerometer_bias_calibration_restores_the_tilt() {
    // 0.4 m/s² horizontal (body x and y) plus 0.1 m/s² on z, a poorly calibrated MEMS part.
    const BIAS: [f64; 3] = [0.3, -0.265, 0.1];
    for name in ["flight1", "aggressive"] {
        let clean = sim::run(&sim::load_scenario(name).unwrap(), 1).unwrap().log;
        let mut biased = clean.clone();
        for r in &mut biased.rows {
            for i in 0..3 {
                r.accel[i] += BIAS[i];
            }
        }
        let cal = accel_cal::learn(&biased, Config::default(), 20.0);
        let fixed = Config { accel_bias: cal.bias, ..Config::default() };
        let (t_clean, t_biased, t_cal) = (
            tilt_rms(&clean, Config::default()),
            tilt_rms(&biased, Config::default()),
            tilt_rms(&biased, fixed),
        );
        eprintln!(
            "{name}: learnt {:?} m/s² ({} replays) of {BIAS:?}; tilt RMS {:.3}° clean, {:.3}° biased, {:.3}° calibrated",
            cal.bias,
            cal.replays,
            t_clean.to_degrees(),
            t_biased.to_degrees(),
            t_cal.to_degrees()
        );
        for i in 0..2 {
            assert!((cal.bias[i] as f64 - BIAS[i]).abs() < 0.1, "{name}: axis {i}: {:?}", cal.bias);
        }
        assert!(
            t_biased > 2.0 * t_clean,
            "{name}: the bias does not show: {t_biased} vs {t_clean}"
        );
        assert!(t_cal <= 1.5 * t_clean, "{name}: calibrated {t_cal} vs clean {t_clean}");
    }
}
