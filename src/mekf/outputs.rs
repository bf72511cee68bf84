//! The quaternion filter's read-outs: attitude, biases, covariance (with the error no
//! state holds), wind, health.

use super::{filter, quat, unmodelled, QuatAhrs};
use crate::config::Config;
use crate::health::{Flags, Health, UpdateRecord};
use crate::math::{Mat3, Vec3};
use crate::rotation::Euler;

impl QuatAhrs {
    /// The attitude as 3-2-1 Euler angles, rad.
    pub fn attitude(&self) -> Euler {
        quat::to_euler(&self.ekf.quaternion())
    }

    /// The attitude quaternion, body → NED.
    pub fn quaternion(&self) -> quat::Quat {
        self.ekf.quaternion()
    }

    /// Gyro bias estimate, rad/s.
    pub fn gyro_bias(&self) -> Vec3 {
        self.ekf.bias()
    }

    /// The gyro scale factors about body x and y, when carried.
    pub fn gyro_scale(&self) -> Option<[f32; 2]> {
        #[cfg(feature = "gyro-scale-states")]
        return self.ekf.scale();
        #[cfg(not(feature = "gyro-scale-states"))]
        None
    }

    /// The latest gyro sample minus the bias, rad/s.
    pub fn body_rates(&self) -> Vec3 {
        let b = self.ekf.bias();
        [self.gyro[0] - b[0], self.gyro[1] - b[1], self.gyro[2] - b[2]]
    }

    /// The error-state covariance `[δθ (NED), δb]` as of the last propagation, its attitude
    /// block scaled by the GPS acceleration's recent NIS where that says P is too small
    /// ([`consistency`](super::consistency)), with the attitude error no state holds added
    /// ([`unmodelled`]): the body terms, the heading share of the accelerometer bias and the
    /// heading drift since the GPS acceleration last saw the heading.
    pub fn error_covariance(&self) -> filter::Mat6 {
        let mut p = *self.ekf.covariance();
        let k = if self.quat.scale_sigma_by_nis { self.consistency.factor() } else { 1.0 };
        unmodelled::add_to_ned(&mut p, k, self.ekf.dcm(), self.unmodelled);
        p[2][2] += self.heading_bias.variance();
        p[2][2] += self.heading_drift;
        p
    }

    /// The covariance mapped to `[φ, θ, ψ, bp, bq, br]` (first order: `δe = E(φ,θ)·R̂ᵀ·δθ`;
    /// roll and yaw σ grow without bound towards ±90° pitch, where they are undefined).
    pub fn euler_covariance(&self) -> [[f32; 6]; 6] {
        let j = euler_jacobian(self.ekf.dcm(), &self.attitude());
        let p = &self.error_covariance();
        let mut t = [[0.0f32; 6]; 6];
        for i in 0..6 {
            for k in 0..6 {
                t[i][k] = if i < 3 { (0..3).map(|l| j[i][l] * p[l][k]).sum() } else { p[i][k] };
            }
        }
        let mut out = [[0.0f32; 6]; 6];
        for i in 0..6 {
            for k in 0..6 {
                out[i][k] = if k < 3 { (0..3).map(|l| t[i][l] * j[k][l]).sum() } else { t[i][k] };
            }
        }
        out
    }

    /// Wind estimate `[w_N, w_E, w_D]` (m/s, NED; w_D is not estimated: 0) and the σ of
    /// its horizontal components (m/s, [`super::wind::Wind::reported_sigma`]), once the wind filter has
    /// started.
    pub fn wind(&self) -> Option<(Vec3, [f32; 2])> {
        let heading_var = self.ekf.covariance()[2][2];
        self.wind.started().then(|| (self.wind.wind(), self.wind.reported_sigma(heading_var)))
    }

    /// See [`crate::Ahrs::health`].
    pub fn health(&self) -> Health {
        let mut h = self.health;
        h.covariance_repairs = self.ekf.repairs();
        h
    }

    /// See [`crate::Ahrs::flags`].
    pub fn flags(&self) -> Flags {
        self.flags
    }

    /// See [`crate::Ahrs::last_update`].
    pub fn last_update(&self) -> &UpdateRecord {
        &self.last_update
    }

    /// The fixes' velocity σ in use, m/s: learnt (`QuatConfig::learn_vel_noise`), or
    /// `None` before the first fix interval or without learning.
    pub fn gps_vel_sigma(&self) -> Option<f32> {
        self.vel_noise.sigma().filter(|_| self.quat.learn_vel_noise)
    }

    /// The receiver latency in use (configured, or as tracked), s.
    pub fn gps_latency(&self) -> f32 {
        self.latency.value()
    }

    /// The configuration in use.
    pub fn config(&self) -> &Config {
        &self.cfg
    }
}

/// `∂[φ, θ, ψ]/∂δθ_NED = E(φ, θ)·R̂ᵀ`, E the body-rate-to-Euler-rate matrix (|cos θ| ≥ 1e-3).
fn euler_jacobian(r: &Mat3, e: &Euler) -> Mat3 {
    let (sf, cf) = crate::math::sincos(e.roll);
    let (st, ct) = crate::math::sincos(e.pitch);
    let ct = if libm::fabsf(ct) < 1e-3 { 1e-3 } else { ct };
    let tt = st / ct;
    let em = [[1.0, sf * tt, cf * tt], [0.0, cf, -sf], [0.0, sf / ct, cf / ct]];
    let mut j = [[0.0f32; 3]; 3];
    for i in 0..3 {
        for k in 0..3 {
            // (E·Rᵀ)[i][k] = Σ_l E[i][l]·R[k][l].
            j[i][k] = (0..3).map(|l| em[i][l] * r[k][l]).sum();
        }
    }
    j
}
