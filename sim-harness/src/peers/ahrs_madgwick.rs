//! Madgwick's gradient-descent filter, crate `ahrs` (jmagnuson/ahrs-rs), IMU-only form.
//!
//! Conventions (ahrs 0.8, `update_imu`): gyro in rad/s; the accelerometer only as a
//! direction, expected "up" when level and still → we pass [`gravity_up`]. The
//! quaternion rotates sensor vectors into the Earth frame. β = 0.1 rad/s, the
//! reference implementation's default. No gyro-bias state.

use super::{euler_of_quat, gravity_up, Estimator, StepClock};
use crate::log::LogRow;
use ahrs::Ahrs as _;
use nalgebra::Vector3;

/// Madgwick β used here, rad/s (Madgwick's reference code default `betaDef`).
pub const BETA: f64 = 0.1;

/// Madgwick adapter.
pub struct Madgwick {
    f: ahrs::Madgwick<f64>,
    clock: StepClock,
}

impl Madgwick {
    /// A filter at identity with nominal IMU period `dt`, s.
    pub fn new(dt: f64) -> Self {
        Madgwick { f: ahrs::Madgwick::new(dt, BETA), clock: StepClock::new(dt) }
    }
}

impl Estimator for Madgwick {
    fn name(&self) -> &str {
        "Madgwick (ahrs)"
    }
    fn step(&mut self, row: &LogRow) {
        // ahrs 0.8 exposes no period setter (its `field_access` feature is not published);
        // the filter state is only (period, β, q), so rebuilding it is exact and cheap.
        self.f = ahrs::Madgwick::new_with_quat(self.clock.dt(row.t), BETA, self.f.quat);
        let g = Vector3::from(row.gyro);
        let a = Vector3::from(gravity_up(row.accel));
        if self.f.update_imu(&g, &a).is_err() {
            // Zero accelerometer norm: the authors' fallback is a gyro-only step.
            self.f.update_gyro(&g);
        }
    }
    fn attitude(&self) -> [f64; 3] {
        let q = self.f.quat;
        euler_of_quat(q.w, q.i, q.j, q.k)
    }
    fn estimates_bias(&self) -> bool {
        false
    }
}
