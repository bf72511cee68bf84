//! The windowed EKF2 measurement (measure::air_window) and its operational rules
//! (Ekf2Config: airborne_hold, ground_speed_static, max_lateral_accel), against
//! independent truth: exact window means of known signals, a parked tilted aircraft
//! whose specific force is gravity alone, and the forward model of a steady turn.

mod common;
use common::*;
use wing_ahrs::measure::air_window::AirWindow;
use wing_ahrs::{Ahrs, AxisStatus, Config, Model};

/// 100 Hz IMU, 10 Hz GPS, airspeed every IMU sample; steady inputs. The GPS velocity
/// `vel` turns at `turn_rate` (rad/s, about down) so that course follows the yaw.
#[derive(Clone, Copy)]
struct Steady {
    gyro: [f32; 3],
    accel: [f32; 3],
    vel: [f32; 3],
    va: f32,
    turn_rate: f64,
}

/// Feeds `s` for [t0, t1) s; returns the (roll, pitch) statuses of every update.
fn feed(ahrs: &mut Ahrs, t0: f64, t1: f64, s: &Steady) -> Vec<(f64, AxisStatus, AxisStatus)> {
    let mut out = Vec::new();
    let mut seq = ahrs.last_update().seq;
    let n0 = (t0 * 100.0).round() as u64;
    let n1 = (t1 * 100.0).round() as u64;
    for k in n0..n1 {
        let t_us = k * 10_000;
        ahrs.on_imu(t_us, s.gyro, s.accel);
        ahrs.on_airspeed(t_us, s.va);
        if k % 10 == 0 {
            let (sn, cs) = (s.turn_rate * k as f64 / 100.0).sin_cos();
            let v = [
                s.vel[0] as f64 * cs - s.vel[1] as f64 * sn,
                s.vel[0] as f64 * sn + s.vel[1] as f64 * cs,
                s.vel[2] as f64,
            ];
            ahrs.on_gps(&fix_at(t_us, v.map(|x| x as f32)));
        }
        let u = ahrs.last_update();
        if u.seq != seq {
            seq = u.seq;
            out.push((k as f64 / 100.0, u.axes[0].status, u.axes[1].status));
        }
    }
    out
}

fn measured(s: AxisStatus) -> bool {
    !matches!(s, AxisStatus::NotMeasured)
}

fn ekf2() -> Config {
    Config::euler().with_model(Model::Ekf2(Default::default()))
}

#[test]
fn window_means_and_airspeed_slope_are_exact_for_known_signals() {
    // Airspeed ramp va = 20 + 1.5 t at 50 Hz, accel/gyro linear in t at 100 Hz, GPS
    // intervals of uneven length: the window's means and slope must be the exact ones.
    let mut w = AirWindow::default();
    let fixes = [0.0, 0.1, 0.25, 0.3, 0.45, 0.6, 0.8];
    w.restart(0, [10.0, 0.0, -1.0]);
    let mut last = None;
    let mut k = 1u64;
    for (j, &tf) in fixes.iter().enumerate().skip(1) {
        while (k as f64) * 0.01 <= tf + 1e-9 {
            let t = k as f64 * 0.01;
            let a = 0.5 + 2.0 * t;
            let roll = 0.3 - 0.2 * t;
            w.push_imu([a as f32, 0.0, -9.8], [0.1, 0.0, 0.0], roll as f32, 0.05);
            if k % 2 == 0 {
                w.push_airspeed((t * 1e6).round() as u64, (20.0 + 1.5 * t) as f32);
            }
            k += 1;
        }
        let vel = [10.0 + j as f32, 0.0, -1.0];
        last = w.close_interval((tf * 1e6) as u64, vel, 0.5);
        if tf < 0.5 {
            assert!(last.is_none(), "window shorter than 0.5 s at {tf}");
        }
    }
    // At 0.8 s the newest intervals spanning ≥ 0.5 s start at 0.3 s: (0.3, 0.8], 3 intervals.
    let m = last.expect("window");
    assert_eq!(m.intervals, 3);
    assert!((m.duration - 0.5).abs() < 1e-6, "duration {}", m.duration);
    // Exact means over the samples at t ∈ (0.3, 0.8].
    let ts: Vec<f64> = (31..=80).map(|k| k as f64 * 0.01).collect();
    let mean = |f: &dyn Fn(f64) -> f64| ts.iter().map(|t| f(*t)).sum::<f64>() / ts.len() as f64;
    assert!((m.accel[0] as f64 - mean(&|t| 0.5 + 2.0 * t)).abs() < 1e-5, "accel {}", m.accel[0]);
    assert!((m.att[0] as f64 - mean(&|t| 0.3 - 0.2 * t)).abs() < 1e-5, "roll {}", m.att[0]);
    assert!((m.gyro[0] - 0.1).abs() < 1e-6);
    assert!((m.va_dot - 1.5).abs() < 1e-3, "slope {}", m.va_dot);
    let tv: Vec<f64> =
        ts.iter().copied().filter(|t| ((t * 100.0).round() as u64) % 2 == 0).collect();
    let va_mean = tv.iter().map(|t| 20.0 + 1.5 * t).sum::<f64>() / tv.len() as f64;
    assert!((m.va as f64 - va_mean).abs() < 1e-4, "va {} vs {va_mean}", m.va);
    // Velocity: the fixes at 0.3 s (j = 3) and 0.8 s (j = 6) averaged.
    assert!((m.vel[0] - 0.5 * (13.0 + 16.0)).abs() < 1e-6, "vel {:?}", m.vel);
    // A correction moves the stored trajectory (and so the mean) by the same amount.
    let mut w2 = w;
    w2.shift_att(0.1, -0.02);
    let m2 = w2.close_interval(900_000, [0.0; 3], 0.5).unwrap();
    let m1 = w.close_interval(900_000, [0.0; 3], 0.5).unwrap();
    assert!(
        (m2.att[0] - m1.att[0] - 0.1).abs() < 1e-5 && (m2.att[1] - m1.att[1] + 0.02).abs() < 1e-5
    );
}

#[test]
fn parked_tilted_aircraft_aligns_from_gravity_in_ground_mode_only() {
    // Parked at roll 20°, pitch −10°: specific force is −g in body axes, GPS still,
    // pitot 1.5 m/s. Ground mode measures that tilt; disabled, EKF2 measures nothing.
    let att = [20.0 * DEG, -10.0 * DEG, 0.0];
    let f = specific_force(att, [0.0; 3]);
    let s = Steady {
        gyro: [0.0; 3],
        accel: f.map(|v| v as f32),
        vel: [0.0, 0.0, 0.0],
        va: 1.5,
        turn_rate: 0.0,
    };
    let mut a = Ahrs::try_new(ekf2()).expect("a valid configuration");
    let ups = feed(&mut a, 0.0, 20.0, &s);
    assert!(ups.iter().any(|u| measured(u.1)), "ground mode measured nothing");
    let e = a.attitude();
    assert!(
        (e.roll as f64 - att[0]).abs() < 0.2 * DEG && (e.pitch as f64 - att[1]).abs() < 0.2 * DEG,
        "{e:?}"
    );

    let mut cfg = ekf2();
    cfg.ekf2_mut().unwrap().ground_speed_static = 0.0;
    let mut b = Ahrs::try_new(cfg).expect("a valid configuration");
    let ups = feed(&mut b, 0.0, 20.0, &s);
    assert!(ups.iter().all(|u| !measured(u.1) && !measured(u.2)), "measured without ground mode");
}

#[test]
fn pitot_gust_on_the_ground_and_a_launch_wait_for_the_airborne_hold() {
    // Straight and level at 20 m/s, nose 5° up (α = 5°): specific force is −g in body
    // axes (the forward model with no rates and constant airspeed).
    let pitch = 5.0 * DEG;
    let f = specific_force([0.0, pitch, 0.0], [0.0; 3]);
    let flying = Steady {
        gyro: [0.0; 3],
        accel: f.map(|v| v as f32),
        vel: [20.0, 0.0, 0.0],
        va: 20.0,
        turn_rate: 0.0,
    };
    let mut cfg = ekf2();
    cfg.ekf2_mut().unwrap().ground_speed_static = 0.0; // isolate the hold rule
    let hold = cfg.ekf2_mut().unwrap().airborne_hold as f64;
    let mut a = Ahrs::try_new(cfg).expect("a valid configuration");
    // Walking at 3 m/s with 1.5 m/s on the pitot, a 0.3 s gust of 13 m/s at 2 s.
    let walk = Steady {
        gyro: [0.0; 3],
        accel: [0.0, 0.0, -G as f32],
        vel: [3.0, 0.0, 0.0],
        va: 1.5,
        turn_rate: 0.0,
    };
    let gust = Steady { va: 13.0, ..walk };
    let mut ups = feed(&mut a, 0.0, 2.0, &walk);
    ups.extend(feed(&mut a, 2.0, 2.3, &gust));
    ups.extend(feed(&mut a, 2.3, 5.0, &walk));
    assert!(
        ups.iter().all(|u| !measured(u.1) && !measured(u.2)),
        "measured on the ground: {ups:?}"
    );
    // Launch at 5 s: nothing before the hold has elapsed, measurements after it.
    let ups = feed(&mut a, 5.0, 12.0, &flying);
    let first = ups.iter().find(|u| measured(u.1)).expect("never measured in flight").0;
    assert!(
        first >= 5.0 + hold - 1e-9 && first <= 5.0 + hold + 0.6,
        "first in-flight measurement at {first} s (hold {hold} s)"
    );
    // And it measures the flight's attitude.
    let e = a.attitude();
    assert!(
        (e.roll as f64).abs() < 0.2 * DEG && (e.pitch as f64 - pitch).abs() < 0.2 * DEG,
        "{e:?}"
    );
}

#[test]
fn lateral_specific_force_beyond_the_slip_limit_stops_roll_pitch_measurement() {
    // Wings level at 20 m/s with a steady 4 m/s² side force (a slip): β ≠ 0 breaks the model.
    let slip = Steady {
        gyro: [0.0; 3],
        accel: [0.0, 4.0, -G as f32],
        vel: [20.0, 0.0, 0.0],
        va: 20.0,
        turn_rate: 0.0,
    };
    let mut cfg = ekf2();
    let mut a = Ahrs::try_new(cfg).expect("a valid configuration");
    let ups = feed(&mut a, 0.0, 10.0, &slip);
    assert!(ups.iter().all(|u| !measured(u.1)), "measured in a slip");
    // The same data with the limit above 4 m/s² is measured (so the rule, not something else, stopped it).
    cfg.ekf2_mut().unwrap().max_lateral_accel = 5.0;
    let mut b = Ahrs::try_new(cfg).expect("a valid configuration");
    let ups = feed(&mut b, 0.0, 10.0, &slip);
    assert!(ups.iter().any(|u| measured(u.1)));
}

#[test]
fn a_slip_that_reverses_within_the_window_is_still_seen() {
    // Two 0.25 s intervals with Ay = +4 and −4 m/s² (a rudder doublet): the window mean
    // cancels, the per-interval maximum does not — and the estimator does not measure.
    let mut w = AirWindow::default();
    w.restart(0, [20.0, 0.0, 0.0]);
    for (j, ay) in [(1u64, 4.0f32), (2, -4.0)] {
        for _ in 0..25 {
            w.push_imu([0.0, ay, -9.8], [0.0; 3], 0.0, 0.0);
            w.push_airspeed(j * 250_000 - 1, 20.0);
        }
        let m = w.close_interval(j * 250_000, [20.0, 0.0, 0.0], 0.5);
        if j == 2 {
            let m = m.expect("window");
            assert!(m.accel[1].abs() < 1e-5 && (m.lateral_max - 4.0).abs() < 1e-5, "{m:?}");
        }
    }
    // In flight: ±4 m/s² reversing every 0.5 s (slower than a GPS interval, as doublets are).
    let doublet = |t: f64| if (t / 0.5) as u64 % 2 == 0 { 4.0 } else { -4.0 };
    let mut a = Ahrs::try_new(ekf2()).expect("a valid configuration");
    let mut seq = 0;
    for k in 0..1000u64 {
        let t_us = k * 10_000;
        a.on_imu(t_us, [0.0; 3], [0.0, doublet(k as f64 / 100.0), -G as f32]);
        a.on_airspeed(t_us, 20.0);
        if k % 10 == 0 {
            a.on_gps(&fix_at(t_us, [20.0, 0.0, 0.0]));
        }
        let u = a.last_update();
        if u.seq != seq {
            seq = u.seq;
            assert!(!measured(u.axes[0].status), "roll measured in a doublet at {k}");
        }
    }
}

#[test]
fn spread_is_the_sample_variance_of_the_per_interval_combination() {
    // Three intervals whose mean −Ay + 2·r are 1, 3, 5 → sample variance 4.
    let mut w = AirWindow::default();
    w.restart(0, [0.0; 3]);
    for (j, (ay, r)) in [(1u64, (1.0f32, 1.0f32)), (2, (-1.0, 1.0)), (3, (-1.0, 2.0))] {
        for _ in 0..10 {
            w.push_imu([0.0, ay, -9.8], [0.0, 0.0, r], 0.0, 0.0);
        }
        w.close_interval(j * 100_000, [0.0; 3], 10.0);
    }
    let v = w.spread(3, [0.0, -1.0, 0.0], [0.0, 0.0, 2.0]);
    assert!((v - 4.0).abs() < 1e-5, "spread {v}");
    assert_eq!(w.spread(1, [0.0, -1.0, 0.0], [0.0, 0.0, 2.0]), 0.0);
}

#[test]
fn yaw_rate_oscillation_inside_the_window_raises_the_roll_variance() {
    // Same straight flight twice; in the second, r alternates ±0.3 rad/s every GPS
    // interval (zero mean, as in Dutch roll): the window's roll R must grow with it.
    let run = |osc: f32| {
        let mut a = Ahrs::try_new(ekf2()).expect("a valid configuration");
        let mut s = [0.0f32; 2];
        for k in 0..1000u64 {
            let t_us = k * 10_000;
            let r = if (k / 10) % 2 == 0 { osc } else { -osc };
            a.on_imu(t_us, [0.0, 0.0, r], [0.0, 0.0, -G as f32]);
            a.on_airspeed(t_us, 20.0);
            if k % 10 == 0 {
                a.on_gps(&fix_at(t_us, [20.0, 0.0, 0.0]));
            }
            let u = a.last_update();
            if measured(u.axes[0].status) {
                s = [u.axes[0].variance, u.axes[1].variance];
            }
        }
        s
    };
    let (calm, osc) = (run(0.0), run(0.3));
    // Roll: Va·r scatters by 20·0.3 = 6 m/s² per interval → SEM ≈ 6/√(k−1)… ≫ R = 3°.
    assert!(osc[0] > 10.0 * calm[0], "roll S calm {} vs oscillating {}", calm[0], osc[0]);
    // Pitch does not involve r (α = 0 here): unchanged.
    assert!(
        (osc[1] - calm[1]).abs() < 0.1 * calm[1],
        "pitch S calm {} vs oscillating {}",
        calm[1],
        osc[1]
    );
}
