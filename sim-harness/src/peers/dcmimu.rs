//! Hyyti & Visala's DCM-IMU (a 6-state EKF on the DCM's third row plus gyro biases),
//! crate `dcmimu` (copterust), a port of the authors' C code.
//!
//! Conventions (dcmimu 0.3, `update_only`): SI units — gyro rad/s, accelerometer
//! m/s² with +g on the up axis when level (`x2 = 1` and `a ≈ x·g0`) → we pass
//! [`gravity_up`]; dt per sample. Angles come out in rad from `to_euler_angles`.
//! Default tuning of the crate (the authors' defaults).

use super::{gravity_up, Estimator, StepClock};
use crate::log::LogRow;

/// DCM-IMU adapter.
pub struct DcmImu {
    f: ::dcmimu::DCMIMU,
    clock: StepClock,
}

impl DcmImu {
    /// A filter in its initial state with nominal IMU period `dt`, s.
    pub fn new(dt: f64) -> Self {
        DcmImu { f: ::dcmimu::DCMIMU::new(), clock: StepClock::new(dt) }
    }
}

impl Estimator for DcmImu {
    fn name(&self) -> &str {
        "DCM-IMU (dcmimu)"
    }
    fn step(&mut self, row: &LogRow) {
        let dt = self.clock.dt(row.t) as f32;
        let g = row.gyro;
        let a = gravity_up(row.accel);
        self.f.update_only(
            (g[0] as f32, g[1] as f32, g[2] as f32),
            (a[0] as f32, a[1] as f32, a[2] as f32),
            dt,
        );
    }
    fn attitude(&self) -> [f64; 3] {
        let e = self.f.to_euler_angles();
        [e.roll as f64, e.pitch as f64, e.yaw as f64]
    }
    fn estimates_bias(&self) -> bool {
        true
    }
}
