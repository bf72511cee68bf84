//! The one robust solver for `a·sin x + b·cos x = c` (DESIGN §3.1), shared by
//! every measurement model.
//!
//! `a·sin x + b·cos x = ρ·cos(x − atan2(a, b))` with `ρ = √(a² + b²)`, so
//! `x = atan2(a, b) ± acos(c/ρ)`. Of the two roots the one nearer the prediction
//! is returned. |c| > ρ has no real root: c is clamped to ±ρ (the closest
//! consistent value) and the clamp is reported. ρ ≈ 0 is degenerate.

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
}

/// Solves `a·sin x + b·cos x = c` for the root nearest `x_pred`.
///
/// Returns `None` (no measurement) if any input is non-finite or
/// `√(a²+b²) ≤ min_radius`.
pub fn solve_sin_cos(a: f32, b: f32, c: f32, x_pred: f32, min_radius: f32) -> Option<Solution> {
    if !(a.is_finite() && b.is_finite() && c.is_finite() && x_pred.is_finite()) {
        return None;
    }
    let rho = crate::math::hypot(a, b);
    if !(rho > min_radius) {
        return None;
    }
    let mut ratio = c / rho;
    let clamped = !(-1.0..=1.0).contains(&ratio);
    ratio = ratio.clamp(-1.0, 1.0);
    let base = libm::atan2f(a, b);
    let d = libm::acosf(ratio);
    let r1 = wrap_pi(base + d);
    let r2 = wrap_pi(base - d);
    let (x, other) = if libm::fabsf(wrap_pi(r1 - x_pred)) <= libm::fabsf(wrap_pi(r2 - x_pred)) {
        (r1, r2)
    } else {
        (r2, r1)
    };
    Some(Solution { x, other, clamped })
}
