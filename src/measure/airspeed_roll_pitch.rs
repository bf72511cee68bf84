//! Measurement model 2 (EKF2): roll and pitch from the accelerometer and airspeed
//! (thesis eq 4.52–4.67), re-derived from the forward model (docs/design.md, EKF2).
//!
//! `A = v̇_B + ω × v_B − g·[−sθ, sφcθ, cφcθ]` with `v_B = Va·[cα, 0, sα]`,
//! `α = θ − γ`, β = 0. Then
//! `Ax = a1 sθ + a2 cθ`, `a1 = V̇a sγ + Va k cγ + g`, `a2 = V̇a cγ − Va k sγ`,
//! `k = q − θ̇ + γ̇`, and `sφ = (−Ay + Va (r cα − p sα)) / (g cθ)`.
//! The thesis prints eq 4.62 with the opposite sign on the Va terms; in a
//! coordinated right turn (Ay ≈ 0, r > 0) φ must come out positive, which this form
//! gives and the round-trip test checks.

use super::solver::solve_sin_cos;
use super::RollPitch;
use crate::config::GRAVITY;
use crate::math::{wrap_pi, Vec3, PI};

/// Inputs of the airspeed model at one GPS epoch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AirData {
    /// True airspeed Va, m/s.
    pub va: f32,
    /// V̇a, m/s².
    pub va_dot: f32,
    /// Flight-path angle γ, rad.
    pub gamma: f32,
    /// γ̇, rad/s.
    pub gamma_dot: f32,
    /// θ̇ from the prediction, rad/s.
    pub theta_dot: f32,
    /// Bias-corrected body rates [p, q, r], rad/s.
    pub rates: Vec3,
}

/// Forward model: specific force for attitude (φ, θ) and `air` (β = 0, α = θ − γ).
#[cfg(any(test, feature = "internals"))]
pub fn forward(roll: f32, pitch: f32, air: &AirData) -> Vec3 {
    let alpha = pitch - air.gamma;
    let alpha_dot = air.theta_dot - air.gamma_dot;
    let (sa, ca) = crate::math::sincos(alpha);
    let (p, q, r) = (air.rates[0], air.rates[1], air.rates[2]);
    let v = [air.va * ca, 0.0, air.va * sa];
    let vdot =
        [air.va_dot * ca - air.va * alpha_dot * sa, 0.0, air.va_dot * sa + air.va * alpha_dot * ca];
    let w_x_v = [q * v[2], r * v[0] - p * v[2], -q * v[0]];
    let (sf, cf) = crate::math::sincos(roll);
    let (st, ct) = crate::math::sincos(pitch);
    let g_b = [-GRAVITY * st, GRAVITY * sf * ct, GRAVITY * cf * ct];
    [vdot[0] + w_x_v[0] - g_b[0], vdot[1] + w_x_v[1] - g_b[1], vdot[2] + w_x_v[2] - g_b[2]]
}

/// Measures roll and pitch from `accel` (m/s², FRD) and air data; `pred` = predicted
/// (roll, pitch) picks the roots. Requires `va ≥ min_va`.
pub fn measure(accel: Vec3, air: &AirData, pred: (f32, f32), min_va: f32) -> RollPitch {
    let mut out = RollPitch::default();
    if !(air.va >= min_va) {
        out.degenerate = true;
        return out;
    }
    let (sg, cg) = crate::math::sincos(air.gamma);
    let k = air.rates[1] - air.theta_dot + air.gamma_dot;
    let a1 = air.va_dot * sg + air.va * k * cg + GRAVITY;
    let a2 = air.va_dot * cg - air.va * k * sg;
    let Some(theta) = solve_sin_cos(a1, a2, accel[0], pred.1, 0.5) else {
        out.degenerate = true;
        return out;
    };
    out.clamped += theta.clamped as u8;
    let theta = theta.x;
    out.pitch = Some(theta);
    let ct = crate::math::cos(theta);
    if libm::fabsf(ct) < 1e-3 {
        out.degenerate = true;
        return out;
    }
    let alpha = theta - air.gamma;
    let (sa, ca) = crate::math::sincos(alpha);
    let mut s = (-accel[1] + air.va * (air.rates[2] * ca - air.rates[0] * sa)) / (GRAVITY * ct);
    if !(-1.0..=1.0).contains(&s) {
        out.clamped += 1;
        s = s.clamp(-1.0, 1.0);
    }
    if !s.is_finite() {
        out.degenerate = true;
        return out;
    }
    // sin φ = s has roots φ and π − φ: take the one nearer the prediction.
    let r1 = crate::math::asin(s);
    let r2 = wrap_pi(PI - r1);
    out.roll = Some(if libm::fabsf(wrap_pi(r1 - pred.0)) <= libm::fabsf(wrap_pi(r2 - pred.0)) {
        r1
    } else {
        r2
    });
    out
}
