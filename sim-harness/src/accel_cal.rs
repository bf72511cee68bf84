//! The accelerometer bias, learnt on the host from one flight log, for `Config::accel_bias`.
//!
//! The six-state filter has no accelerometer-bias states (they would not fit the M4F
//! budget). A body-fixed bias is unobservable in straight flight, where the filter tilts
//! to absorb it (0.4 m/s² is 2.3° of tilt), but not in turns and figures: as the body turns
//! in NED the tilt that absorbed it no longer does, and the GPS acceleration disagrees with
//! the accelerometer until the filter tilts again. So the bias that minimises the GPS-
//! acceleration residuals over a manoeuvring flight is the accelerometer's. Each candidate is
//! one replay of the log (a fraction of a second); a coordinate search on the three board
//! axes, narrowing step by step, finds it to a few mm/s² in a few dozen replays.

use crate::log::FlightLog;
use wing_ahrs::Config;

/// Largest bias searched per axis, m/s².
pub const MAX_BIAS: f32 = 1.0;
/// The search stops when its step is below this, m/s².
const MIN_STEP: f32 = 0.005;

/// Mean squared GPS-acceleration residual (m/s²)² of `log` replayed with `cfg` from
/// `t_from` s on: what the calibration minimises.
pub fn residual_energy(log: &FlightLog, cfg: Config, t_from: f64) -> f64 {
    let (mut sum, mut n, mut seq) = (0.0f64, 0usize, 0u32);
    crate::replay::run(log, cfg, |row, ahrs| {
        let u = ahrs.last_update();
        if u.seq == seq {
            return;
        }
        seq = u.seq;
        if row.t < t_from {
            return;
        }
        for a in &u.axes {
            if a.innovation.is_finite() {
                sum += (a.innovation as f64).powi(2);
            }
        }
        n += 1;
    });
    if n == 0 {
        f64::INFINITY
    } else {
        sum / n as f64
    }
}

/// What [`learn`] found.
#[derive(Debug, Clone, Copy)]
pub struct Calibration {
    /// The bias per board axis, m/s² (what `Config::accel_bias` takes).
    pub bias: [f32; 3],
    /// The residual energy before and after, (m/s²)².
    pub before: f64,
    pub after: f64,
    /// Replays it took.
    pub replays: usize,
}

/// Learns the accelerometer bias of `log` (board axes, m/s²) starting from `cfg`'s, scoring
/// from `t_from` s on.
pub fn learn(log: &FlightLog, cfg: Config, t_from: f64) -> Calibration {
    let score = |b: [f32; 3]| residual_energy(log, Config { accel_bias: b, ..cfg }, t_from);
    let mut b = cfg.accel_bias;
    let before = score(b);
    let mut best = before;
    let mut replays = 1;
    let mut step = 0.2f32;
    while step >= MIN_STEP {
        let mut moved = false;
        for axis in 0..3 {
            for dir in [1.0f32, -1.0] {
                loop {
                    let mut c = b;
                    c[axis] = (c[axis] + dir * step).clamp(-MAX_BIAS, MAX_BIAS);
                    if c == b {
                        break;
                    }
                    let e = score(c);
                    replays += 1;
                    if e < best {
                        (b, best, moved) = (c, e, true);
                    } else {
                        break;
                    }
                }
            }
        }
        if !moved {
            step *= 0.5;
        }
    }
    Calibration { bias: b, before, after: best, replays }
}
