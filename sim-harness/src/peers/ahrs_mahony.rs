//! Mahony's nonlinear complementary filter, crate `ahrs` (jmagnuson/ahrs-rs), IMU-only form.
//!
//! Conventions (ahrs 0.8, `update_imu`): gyro in rad/s; accelerometer as a direction,
//! "up" when level → we pass [`gravity_up`]. Kp = 0.5 (Mahony's reference code
//! `twoKpDef = 2·0.5`); Ki = 0.05 rad/s per rad instead of the reference 0 so the
//! integral term estimates gyro bias, as Mahony et al. (2008) designed it. The crate
//! keeps its integral state private and has no period setter, so the period is the
//! log's nominal (median) one; on irregular real logs that is an approximation.

use super::{euler_of_quat, gravity_up, Estimator};
use crate::log::LogRow;
use ahrs::Ahrs as _;
use nalgebra::Vector3;

/// Proportional gain.
pub const KP: f64 = 0.5;
/// Integral gain (bias estimation).
pub const KI: f64 = 0.05;

/// Mahony adapter.
pub struct Mahony {
    f: ahrs::Mahony<f64>,
}

impl Mahony {
    /// A filter at identity with nominal IMU period `dt`, s.
    pub fn new(dt: f64) -> Self {
        Mahony { f: ahrs::Mahony::new(dt, KP, KI) }
    }
}

impl Estimator for Mahony {
    fn name(&self) -> &str {
        "Mahony (ahrs)"
    }
    fn step(&mut self, row: &LogRow) {
        let g = Vector3::from(row.gyro);
        let a = Vector3::from(gravity_up(row.accel));
        if self.f.update_imu(&g, &a).is_err() {
            self.f.update_gyro(&g);
        }
    }
    fn attitude(&self) -> [f64; 3] {
        let q = self.f.quat;
        euler_of_quat(q.w, q.i, q.j, q.k)
    }
    fn estimates_bias(&self) -> bool {
        true
    }
}
