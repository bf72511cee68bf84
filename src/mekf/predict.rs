//! The prediction of the quaternion filter: the attitude step per IMU sample, the NED
//! velocity increment into the GPS window, the covariance every N samples, and the
//! levelling and GPS timeout around them.

use super::{quat, QuatAhrs, UNKNOWN_HEADING_VAR};
use crate::health::Flags;
use crate::math::Vec3;
use crate::rotation::Euler;

impl QuatAhrs {
    /// The attitude step, the NED velocity increment at the step's mid-attitude
    /// (`R·(f − ½ φ × f)·Δt`) into the GPS window, and P every N samples.
    #[inline]
    pub(super) fn integrate(&mut self, t_us: u64, gyro: Vec3, accel: Vec3, dt: f32) {
        self.ekf.settle_coherent(&self.noise);
        let phi = self.ekf.step(gyro, dt);
        let c = quat::cross(phi, accel);
        let f_mid = [accel[0] - 0.5 * c[0], accel[1] - 0.5 * c[1], accel[2] - 0.5 * c[2]];
        let r = self.ekf.dcm();
        let dv = quat::rotate(r, [f_mid[0] * dt, f_mid[1] * dt, f_mid[2] * dt]);
        self.window.push(t_us, dv, accel, dt);
        self.since_propagation += 1;
        if self.since_propagation >= self.cfg.covariance_decimation.max(1) {
            self.propagate();
        }
    }

    pub(super) fn propagate(&mut self) {
        self.ekf.propagate(&self.noise);
        self.since_propagation = 0;
    }

    /// Before any GPS: roll and pitch from the accelerometer as if unaccelerated.
    pub(super) fn level_from_accel(&mut self, f: Vec3) {
        let roll = crate::math::atan2(-f[1], -f[2]);
        let pitch = crate::math::atan2(f[0], crate::math::hypot(f[1], f[2]));
        let va = self.cfg.init_sigma_attitude * self.cfg.init_sigma_attitude;
        let q = quat::from_euler(&Euler { roll, pitch, yaw: 0.0 });
        self.ekf.reset_attitude(q, [va, va, UNKNOWN_HEADING_VAR]);
    }

    pub(super) fn check_gps_timeout(&mut self, t_us: u64) {
        if let Some(tf) = self.last_fix_t {
            let lost = t_us.saturating_sub(tf) > self.lim.gps_timeout_us;
            if lost && !self.flags.has(Flags::GPS_LOST) {
                self.health.gps_outages = self.health.gps_outages.wrapping_add(1);
                self.gps.reset();
            }
            self.flags.set(Flags::GPS_LOST, lost);
        }
    }
}
