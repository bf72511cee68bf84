//! Replay of a flight log through the core facade, in the firmware's call order:
//! `Ahrs::step`: the IMU sample, its airspeed, then the row's GPS fix (`wing_ahrs::estimator`).

use crate::log::{FlightLog, LogRow};
use wing_ahrs::{Ahrs, Config, FixType, GpsFix};

/// Seconds → the core's µs clock. The firmware's HIL records carry the same integer.
pub fn to_us(t: f64) -> u64 {
    // Round half up by +0.5 and truncation (t ≥ 0; `f64::round` is a library call on
    // baseline x86-64, and this runs every row). Negative and NaN times give 0.
    let us = t * 1e6;
    if us > 0.0 {
        (us + 0.5) as i64 as u64 // via i64: one conversion instruction (t < 2⁶³ µs)
    } else {
        0
    }
}

/// The fix the replay hands the core for a row's GPS cells (a 3-D, valid fix).
pub fn fix_for_row(row: &LogRow) -> Option<GpsFix> {
    let g = row.gps?;
    Some(GpsFix {
        t_us: to_us(row.t),
        itow_ms: None,
        fix_type: FixType::Fix3D,
        fix_ok: true,
        vel_ne: [g.vel[0] as f32, g.vel[1] as f32],
        vel_d: Some(g.vel[2] as f32), // a flight log always has gps_vd
        speed_acc: g.speed_acc.map(|a| a as f32),
        num_sats: 10,
        ..GpsFix::default()
    })
}

/// Feeds one row to the estimator in the canonical order.
pub fn step(ahrs: &mut Ahrs, row: &LogRow) {
    let f = |v: [f64; 3]| [v[0] as f32, v[1] as f32, v[2] as f32];
    let sample = wing_ahrs::Sample {
        t_us: to_us(row.t),
        gyro: f(row.gyro),
        accel: f(row.accel),
        airspeed: row.airspeed.map(|va| va as f32),
    };
    let fix = fix_for_row(row);
    ahrs.step(&sample, fix.as_slice());
}

/// Runs a whole log, calling `each` after every row.
pub fn run(log: &FlightLog, cfg: Config, mut each: impl FnMut(&LogRow, &Ahrs)) -> Ahrs {
    let mut ahrs = Ahrs::try_new(cfg).expect("a valid configuration");
    for row in &log.rows {
        step(&mut ahrs, row);
        each(row, &ahrs);
    }
    ahrs
}
