//! Laidig & Seel's VQF, crate `vqf-rs` (a port of the authors' C++), 6D (no magnetometer).
//!
//! Conventions (vqf-rs 0.3): gyro rad/s, accelerometer m/s² with +g up when level
//! (ENU-style Earth frame) → we pass [`gravity_up`]; `quat_6d` = (w, x, y, z) rotating
//! sensor vectors into the Earth frame. Default parameters (rest and motion bias
//! estimation on). The accelerometer low-pass runs at the nominal rate; the gyro
//! integrates each sample's own dt.

use super::{euler_of_quat, gravity_up, Estimator, StepClock};
use crate::log::LogRow;

/// VQF adapter.
pub struct Vqf {
    f: vqf_rs::VQF,
    clock: StepClock,
}

impl Vqf {
    /// A filter with nominal IMU period `dt`, s.
    pub fn new(dt: f64) -> Self {
        Vqf {
            f: vqf_rs::VQF::new(dt as vqf_rs::Float, None, None, None),
            clock: StepClock::new(dt),
        }
    }
}

impl Estimator for Vqf {
    fn name(&self) -> &str {
        "VQF (vqf-rs)"
    }
    fn step(&mut self, row: &LogRow) {
        let dt = self.clock.dt(row.t);
        self.f.update_gyr_with_ts(row.gyro, dt);
        self.f.update_acc(gravity_up(row.accel));
    }
    fn attitude(&self) -> [f64; 3] {
        let q = self.f.quat_6d();
        euler_of_quat(q.0, q.1, q.2, q.3)
    }
    fn estimates_bias(&self) -> bool {
        true
    }
}
