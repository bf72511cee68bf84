//! The one robust solver for `a·sin x + b·cos x = c` (DESIGN §3.1), shared by
//! every measurement model.
//!
//! `a·sin x + b·cos x = ρ·cos(x − β)` with `ρ = √(a² + b²)`, `β = atan2(a, b)`, so
//! `x = β ± d` with `cos d = c/ρ`, `sin d = s/ρ`, `s = √(ρ² − c²)`. Angle addition
//! gives each root's sine and cosine without trigonometry —
//! `x₁ = atan2(ac + bs, bc − as)`, `x₂ = atan2(ac − bs, bc + as)` — two atan2 and one √
//! instead of atan2, acos (with its own √) and √ρ (cost: this runs in the GPS update on the MCU).
//! Of the two roots the one nearer the prediction is returned. |c| > ρ has no real
//! root: c is clamped to ±ρ (the closest consistent value) and the clamp is reported.
//! ρ ≈ 0 is degenerate.

use crate::math::wrap_pi;

/// A solution of `a·sin x + b·cos x = c`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Solution {
    /// The root nearer the prediction, rad in (−π, π].
    pub x: f32,
    /// The other root, rad in (−π, π].
    pub other: f32,
    /// Whether |c| exceeded ρ and was clamped (the two roots then coincide).
    pub clamped: bool,
    /// `(sin x, cos x)` of the returned root, from the algebra (no trigonometry):
    /// callers that need them skip a sincos.
    pub sin_cos: (f32, f32),
}

/// Solves `a·sin x + b·cos x = c` for the root nearest `x_pred`.
///
/// Returns `None` (no measurement) if any input is non-finite,
/// `√(a²+b²) ≤ min_radius`, or a² + b² > 1e37 (the products below would overflow f32;
/// no physical input comes near).
pub fn solve_sin_cos(a: f32, b: f32, c: f32, x_pred: f32, min_radius: f32) -> Option<Solution> {
    if !(a.is_finite() && b.is_finite() && c.is_finite() && x_pred.is_finite()) {
        return None;
    }
    let rho2 = a * a + b * b;
    if !(rho2 > min_radius * min_radius && rho2 <= 1e37) {
        return None;
    }
    let clamped = c * c > rho2;
    // Clamped: c = ±ρ, one double root (s = 0).
    let (c, s) = if clamped {
        (libm::copysignf(libm::sqrtf(rho2), c), 0.0)
    } else {
        (c, libm::sqrtf(rho2 - c * c))
    };
    let (s1, c1) = (a * c + b * s, b * c - a * s);
    let (s2, c2) = (a * c - b * s, b * c + a * s);
    let r1 = crate::math::atan2(s1, c1);
    let r2 = crate::math::atan2(s2, c2);
    let inv = 1.0 / rho2;
    let (x, other, sc) = if libm::fabsf(wrap_pi(r1 - x_pred)) <= libm::fabsf(wrap_pi(r2 - x_pred)) {
        (r1, r2, (s1, c1))
    } else {
        (r2, r1, (s2, c2))
    };
    Some(Solution { x, other, clamped, sin_cos: (sc.0 * inv, sc.1 * inv) })
}
