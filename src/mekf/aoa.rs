//! The angle of attack, for the wind aid's air-velocity direction (`QuatConfig::learn_alpha`,
//! off: by default both aids take the no-slip flow, `course::slip_free`, which needs no α).
//!
//! In a banked turn the air velocity is not along the body x-axis: it is pitched down
//! from it by α, and a bank turns that offset sideways (α·sin φ: ~7° at 8° and 60°,
//! 3 m/s of false wind at 25 m/s). α follows the wing's load: `α = a₀ + a₁·n_z/V_a²`,
//! `n_z = −f_z` the body-z specific force (m/s²), V_a the airspeed (m/s). The two
//! airframe coefficients are learnt in flight by recursive least squares from the
//! vertical: with no sideslip and no vertical wind, the GPS down velocity is
//! `v_D = V_a·(R₂₀ cos α + R₂₂ sin α)`, so each fix gives `α ≈ (v_D/V_a − R₂₀)/R₂₂`.
//! Vertical gusts are the noise of that sample (`VERTICAL_AIR_SIGMA`).
//!
//! Hand-written: two states, `no_std`, no allocation.

use super::dv_window::WindowMean;
use super::latency::EpochDcm;
use crate::math::{Mat3, Vec3};
use crate::measure::gps_delta::GpsDelta;

/// Vertical air motion allowed for in one α sample, m/s (light turbulence's σ_w).
const VERTICAL_AIR_SIGMA: f32 = 0.7;
/// Samples are taken while the body z-axis is this close to vertical (|R₂₂|), where
/// the vertical velocity resolves α well.
const MIN_COS_TILT: f32 = 0.3;
/// Below this airspeed (m/s) the aircraft is not flying on its wing.
const MIN_AIRSPEED: f32 = 8.0;
/// The α the model may give, rad (stall and negative-g margins).
const ALPHA_RANGE: (f32, f32) = (-0.15, 0.35);
/// Prior σ of `a₀` (rad) and `a₁` (rad·(m/s)²/(m/s²)).
const PRIOR_SIGMA: [f32; 2] = [0.1, 30.0];
/// Random walk of the coefficients per second of flight: `a₀` (rad/√s) and `a₁`
/// (flaps, a payload change).
const WALK: [f32; 2] = [1e-3, 0.1];

/// The learnt lift curve `α = a₀ + a₁·n_z/V_a²`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AngleOfAttack {
    a: [f32; 2],
    p: [[f32; 2]; 2],
}

impl Default for AngleOfAttack {
    fn default() -> Self {
        let s = PRIOR_SIGMA;
        AngleOfAttack { a: [0.0; 2], p: [[s[0] * s[0], 0.0], [0.0, s[1] * s[1]]] }
    }
}

impl AngleOfAttack {
    /// α (rad) at the body-z load `nz` (m/s², = −f_z) and airspeed `va` (m/s).
    pub fn alpha(&self, nz: f32, va: f32) -> f32 {
        if !(va >= MIN_AIRSPEED) {
            return 0.0;
        }
        let a = self.a[0] + self.a[1] * nz / (va * va);
        a.clamp(ALPHA_RANGE.0, ALPHA_RANGE.1)
    }

    /// Learns from one fix: attitude `r` (body → NED) at its epoch, down velocity `vd`
    /// (m/s), airspeed `va` (m/s), mean body-z load `nz` (m/s²) over `dt` s.
    pub fn learn(&mut self, r: &Mat3, vd: f32, va: f32, nz: f32, dt: f32) {
        let c = r[2][2];
        if !(va >= MIN_AIRSPEED && c.abs() >= MIN_COS_TILT && vd.is_finite() && nz.is_finite()) {
            return;
        }
        for i in 0..2 {
            self.p[i][i] += WALK[i] * WALK[i] * dt;
        }
        // `flow_axis`'s down component is `(1 − α²/2)·R₂₀ + α·R₂₂`: one fixed-point
        // step from the linear solution makes its α level the flow (α up to ~0.3 rad).
        let s = vd / va;
        let a = (s - r[2][0]) / c;
        let sample = (s - r[2][0] * (1.0 - 0.5 * a * a)) / c;
        let var = (VERTICAL_AIR_SIGMA / (va * c)) * (VERTICAL_AIR_SIGMA / (va * c));
        let h = [1.0, nz / (va * va)];
        let ph = [self.p[0][0] + self.p[0][1] * h[1], self.p[1][0] + self.p[1][1] * h[1]];
        let s = ph[0] + ph[1] * h[1] + var;
        let y = sample - (self.a[0] + self.a[1] * h[1]);
        if !(s > 0.0 && y.is_finite()) {
            return;
        }
        for i in 0..2 {
            self.a[i] += ph[i] / s * y;
            for j in 0..2 {
                self.p[i][j] -= ph[i] * ph[j] / s;
            }
        }
        for i in 0..2 {
            self.p[i][i] = crate::math::max(self.p[i][i], 1e-9);
        }
    }

    /// The air-velocity direction in NED (unit, to second order in α): the body x-axis
    /// pitched down toward body z by `alpha` (rad), no sideslip.
    pub fn flow_axis(r: &Mat3, alpha: f32) -> [f32; 3] {
        let c = 1.0 - 0.5 * alpha * alpha;
        core::array::from_fn(|i| c * r[i][0] + alpha * r[i][2])
    }
}

impl super::QuatAhrs {
    /// Teaches the angle-of-attack model this fix's vertical velocity, once the attitude
    /// has settled (an unsettled pitch would be learnt as α).
    pub(super) fn learn_alpha(&mut self, d: &GpsDelta, w: &WindowMean, dt: f32, epoch: &mut EpochDcm) {
        let c = self.ekf.covariance();
        if self.yaw_aligned && c[0][0] + c[1][1] < 3e-4 {
            let (va, nz) = (self.wind.airspeed(), -w.f_body[2]);
            let r = self.epoch_dcm(epoch);
            self.aoa.learn(&r, d.vel[2], va, nz, dt);
        }
    }

    /// The air-velocity direction at the fix epoch (`r`, the attitude then), NED: the body
    /// x-axis, pitched by the learnt α at the interval's load and the estimated airspeed
    /// (the wind aid's, with `learn_alpha`).
    pub(super) fn flow_axis(&self, w: &WindowMean, r: &Mat3) -> Vec3 {
        let alpha = self.aoa.alpha(-w.f_body[2], self.wind.airspeed());
        AngleOfAttack::flow_axis(r, alpha)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Body → NED for a bank `phi` and pitch `theta` (rad), heading north.
    fn dcm(phi: f32, theta: f32) -> Mat3 {
        let (sf, cf, st, ct) = (libm::sinf(phi), libm::cosf(phi), libm::sinf(theta), libm::cosf(theta));
        [[ct, sf * st, cf * st], [0.0, cf, -sf], [-st, sf * ct, cf * ct]]
    }

    /// A lift curve α = 0.02 + 8·n_z/V², flown level at banks 0–60° (n_z = g/cos φ):
    /// the learnt model gives α within 0.3° at a bank it was not shown, and the flow
    /// axis it gives is horizontal (the aircraft holds its height).
    #[test]
    fn the_lift_curve_is_learnt_from_the_vertical() {
        let (a0, a1, va, g) = (0.02, 8.0, 22.0, 9.80665);
        let mut m = AngleOfAttack::default();
        for k in 0..600 {
            let phi = (k % 7) as f32 * 0.15;
            let nz = g / libm::cosf(phi);
            let alpha = a0 + a1 * nz / (va * va);
            // Level flight: the flight path is horizontal, so θ = α·cos φ to first order.
            let theta = libm::atanf(libm::tanf(alpha) * libm::cosf(phi));
            m.learn(&dcm(phi, theta), 0.0, va, nz, 0.2);
        }
        let phi = 0.95;
        let nz = g / libm::cosf(phi);
        let truth = a0 + a1 * nz / (va * va);
        let got = m.alpha(nz, va);
        assert!((got - truth).abs() < 0.5f32.to_radians(), "α {got} against {truth}");
        // The flow axis is the true air-velocity direction R·[cos α, 0, sin α] within
        // 0.3°, where the body x-axis is α·sin φ (14°) off it.
        let r = dcm(phi, libm::atanf(libm::tanf(truth) * libm::cosf(phi)));
        let d = AngleOfAttack::flow_axis(&r, got);
        let t: [f32; 3] =
            core::array::from_fn(|i| libm::cosf(truth) * r[i][0] + libm::sinf(truth) * r[i][2]);
        let angle = |a: [f32; 3]| {
            let n = crate::math::norm3(a);
            libm::acosf((a.iter().zip(&t).map(|(x, y)| x * y).sum::<f32>() / n).min(1.0))
        };
        assert!(t[2].abs() < 1e-5, "the truth flies level: {t:?}");
        assert!(angle(d) < 0.3f32.to_radians(), "flow axis {d:?} against {t:?}");
        assert!(angle([r[0][0], r[1][0], r[2][0]]) > 10f32.to_radians());
    }

    #[test]
    fn unusable_samples_change_nothing() {
        let mut m = AngleOfAttack::default();
        m.learn(&dcm(1.5, 0.0), 0.0, 22.0, 9.8, 0.2); // knife edge: R₂₂ ≈ 0
        m.learn(&dcm(0.0, 0.1), f32::NAN, 22.0, 9.8, 0.2);
        m.learn(&dcm(0.0, 0.1), 0.0, 3.0, 9.8, 0.2); // not flying
        assert_eq!(m, AngleOfAttack::default());
        assert_eq!(m.alpha(9.8, 3.0), 0.0);
    }
}
