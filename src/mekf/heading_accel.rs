//! Aid source: the heading solved directly from the horizontal GPS acceleration, while
//! the heading is too uncertain for the linear GPS-acceleration update. Control policy
//! and solution.
//!
//! In a turn or a speed change the receiver's horizontal acceleration `a_h` and the
//! IMU's horizontal specific force in NED `f_h` (rotated with the estimated heading)
//! are the same vector turned by the heading error. Their angle is that error, with
//! no linearisation, no wind and no slip assumption: a linear Kalman step with a 1 rad
//! heading σ can turn the heading half a circle on one jolt (a real launch did). The
//! cross and dot products are summed over consecutive intervals (the estimated heading
//! moves only by the gyro meanwhile), so noise averages down over a turn:
//! `Δψ = atan2(Σ f×a, Σ f·a)`, `σ² ≈ Σ σₖ²|fₖ|² / |Σ|²`.

use crate::math::Vec3;

/// Above this heading variance (rad², (20°)²) the GPS acceleration does not fuse the
/// heading linearly, and this aid source solves it instead.
pub const COARSE_VAR: f32 = 0.1218;

/// Horizontal specific force below which an interval is not summed, m/s² (a 3 m/s²
/// turn: 17° of bank).
pub const MIN_HORIZONTAL: f32 = 3.0;

/// Whether a horizontal vector of squared norm `h2` ((m/s²)²) is a manoeuvre: at least
/// `MIN_HORIZONTAL`. Below it turbulence and noise, not the heading, dominate.
#[inline]
pub fn manoeuvre(h2: f32) -> bool {
    h2 >= MIN_HORIZONTAL * MIN_HORIZONTAL
}

/// The sums are applied once their heading σ is below this, rad² ((10°)²).
const APPLY_VAR: f32 = 0.0305;

/// The running sums while the heading is coarse.
#[derive(Debug, Clone, Copy, Default)]
pub struct HeadingFromAccel {
    /// Σ (f × a)_down, Σ f·a, (m/s²)².
    cross: f32,
    dot: f32,
    /// Σ σₖ²|fₖ|², (m/s²)⁴.
    noise: f32,
}

impl HeadingFromAccel {
    /// Forgets the sums (the heading was set or changed by another source).
    pub fn reset(&mut self) {
        *self = HeadingFromAccel::default();
    }

    /// One interval: the IMU's mean specific force in NED `f` and the GPS acceleration
    /// `a` (NED, m/s²; only the horizontal parts are used), and the noise variance of
    /// one horizontal axis of their difference `var` ((m/s²)²). Returns the heading
    /// correction (rad, about NED down) and its variance (rad²) once the sums know it
    /// better than `APPLY_VAR` and `heading_var` (the present heading variance); the
    /// caller applies it and resets.
    pub fn observe(&mut self, f: Vec3, a: Vec3, var: f32, heading_var: f32) -> Option<(f32, f32)> {
        let f2 = f[0] * f[0] + f[1] * f[1];
        let a2 = a[0] * a[0] + a[1] * a[1];
        if !manoeuvre(f2) || !manoeuvre(a2) {
            return None;
        }
        // The magnitudes do not depend on the heading: when they disagree (3σ) the
        // interval is a glitch or a latency jolt, not a rotation.
        let dm = crate::math::sqrt(f2) - crate::math::sqrt(a2);
        if dm * dm > 9.0 * 2.0 * var {
            return None;
        }
        self.cross += f[0] * a[1] - f[1] * a[0];
        self.dot += f[0] * a[0] + f[1] * a[1];
        self.noise += 2.0 * var * f2;
        let s2 = self.cross * self.cross + self.dot * self.dot;
        let psi_var = self.noise / crate::math::max(s2, 1e-6);
        (psi_var <= APPLY_VAR && psi_var < 0.5 * heading_var)
            .then(|| (crate::math::atan2(self.cross, self.dot), psi_var))
    }
}

impl super::QuatAhrs {
    /// Control policy while the heading is coarse: the interval is summed, and once the
    /// sums' σ is small enough the heading is set to their solution and counts as seen.
    /// `h_var`: one horizontal axis' noise with the tilt's, (m/s²)².
    pub(super) fn control_heading_accel(
        &mut self,
        t_us: u64,
        d: &crate::measure::gps_delta::GpsDelta,
        w: &super::dv_window::WindowMean,
        h_var: f32,
    ) {
        let pyaw = self.ekf.covariance()[2][2];
        let a = d.accel_ned;
        if let Some((dpsi, var)) = self.heading_accel.observe(w.f_ned, a, h_var, pyaw) {
            self.set_heading(dpsi, var);
            self.yaw_aligned = true;
            self.heading_seen_t = Some(t_us);
            self.last_update.axes[2].status = crate::health::AxisStatus::Initialised;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn turned(v: Vec3, psi: f32) -> Vec3 {
        let (s, c) = (libm::sinf(psi), libm::cosf(psi));
        [c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]]
    }

    /// A heading error of 150° (the IMU's force turned by −150°) is found exactly, on
    /// the first interval when it is clean, and the variance is the σ²/|f|² of the
    /// model.
    #[test]
    fn finds_a_large_heading_error_without_linearising() {
        let a = [3.0, 8.0, -9.8];
        let f = turned(a, -2.618);
        let mut h = HeadingFromAccel::default();
        let (psi, var) = h.observe(f, a, 0.1, 1.0).expect("clean interval");
        assert!((psi - 2.618).abs() < 1e-4, "{psi}");
        let f2 = 9.0 + 64.0;
        assert!((var - 2.0 * 0.1 * f2 / (f2 * f2)).abs() < 1e-6, "{var}");
    }

    /// Noisy intervals average down: a single one is not enough, several are; straight
    /// flight and magnitude disagreements are never summed.
    #[test]
    fn sums_noisy_intervals_and_skips_uninformative_ones() {
        let mut h = HeadingFromAccel::default();
        assert!(h.observe([0.5, 0.2, -9.8], [0.4, 0.3, -9.8], 1.0, 1.0).is_none());
        assert!(h.observe([9.0, 0.0, -9.8], [3.0, 0.0, -9.8], 0.5, 1.0).is_none());
        assert_eq!(h.noise, 0.0);
        let mut out = None;
        let mut n = 0;
        for k in 0..40 {
            let th = 0.3 * k as f32; // the turn rotates the force
            let a = [5.0 * libm::cosf(th), 5.0 * libm::sinf(th), -9.8];
            let e = if k % 2 == 0 { 0.8 } else { -0.8 }; // noise
            let f = turned([a[0] + e, a[1] - e, a[2]], -1.0);
            n += 1;
            if let Some(r) = h.observe(f, a, 1.0, 1.0) {
                out = Some(r);
                break;
            }
        }
        let (psi, var) = out.expect("applies within the turn");
        assert!(n > 1, "one interval of σ 1 m/s² on 5 m/s² is not enough");
        assert!((psi - 1.0).abs() < 3.0 * var.sqrt(), "{psi} ± {}", var.sqrt());
        // Not when the present heading is already better known.
        let mut h = HeadingFromAccel::default();
        assert!(h.observe(turned(a_of(5.0), -1.0), a_of(5.0), 0.01, 1e-4).is_none());
    }

    fn a_of(x: f32) -> Vec3 {
        [x, x, -9.8]
    }
}
