//! The one robust solver for `a·sin x + b·cos x = c` (docs/design.md, sin/cos solver), shared by
//! every measurement model.
//!
//! `a·sin x + b·cos x = ρ·cos(x − β)` with `ρ = √(a² + b²)`, `β = atan2(a, b)`, so
//! `x = β ± d` with `cos d = c/ρ`, `sin d = s/ρ`, `s = √(ρ² − c²)`. Angle addition
//! gives each root's sine and cosine without trigonometry — `ρ²·(sin, cos)(x₁) =
//! (ac + bs, bc − as)`, `ρ²·(sin, cos)(x₂) = (ac − bs, bc + as)`. The root nearer the
//! prediction has the larger cos(x − x_pred), a dot product with (sin, cos)(x_pred); only
//! that root's angle is computed (one atan2, one √ — instead of atan2, acos and two √:
//! this runs in the GPS update on the MCU). |c| > ρ has no real root: c is clamped to ±ρ
//! (the closest consistent value) and the clamp is reported. ρ ≈ 0 is degenerate.

/// A solution of `a·sin x + b·cos x = c`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Solution {
    /// The root nearer the prediction, rad in (−π, π].
    pub x: f32,
    /// Whether |c| exceeded ρ and was clamped (the two roots then coincide).
    pub clamped: bool,
    /// `(sin x, cos x)` of the returned root, from the algebra (no trigonometry):
    /// callers that need them skip a sincos.
    pub sin_cos: (f32, f32),
    /// ρ²·(sin, cos) of the other root (its angle is computed only on request).
    other_sc: (f32, f32),
}

impl Solution {
    /// The other root, rad in (−π, π] (one atan2; the update never needs it).
    #[cfg(any(test, feature = "internals"))]
    pub fn other(&self) -> f32 {
        crate::math::atan2(self.other_sc.0, self.other_sc.1)
    }
}

/// Solves `a·sin x + b·cos x = c` for the root nearest `x_pred` (rad).
///
/// Returns `None` (no measurement) if any input is non-finite,
/// `√(a²+b²) ≤ min_radius`, or a² + b² > 1e37 (the products below would overflow f32;
/// no physical input comes near).
pub fn solve_sin_cos(a: f32, b: f32, c: f32, x_pred: f32, min_radius: f32) -> Option<Solution> {
    if !x_pred.is_finite() {
        return None;
    }
    solve_sin_cos_near(a, b, c, crate::math::sincos(x_pred), min_radius)
}

/// [`solve_sin_cos`] with the prediction given as `(sin x_pred, cos x_pred)` — the update
/// already has them. Ties go to the root β + d.
pub fn solve_sin_cos_near(
    a: f32,
    b: f32,
    c: f32,
    pred_sc: (f32, f32),
    min_radius: f32,
) -> Option<Solution> {
    nearest_root(a, b, c, pred_sc, min_radius).map(|r| Solution {
        x: crate::math::atan2(r.sin_cos.0, r.sin_cos.1),
        clamped: r.clamped,
        sin_cos: r.sin_cos,
        other_sc: r.other_sc,
    })
}

/// The nearest root as `(sin x, cos x)` only — for callers that need no angle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RootSinCos {
    /// `(sin x, cos x)` of the root nearer the prediction.
    pub sin_cos: (f32, f32),
    /// Whether |c| exceeded ρ and was clamped.
    pub clamped: bool,
    other_sc: (f32, f32),
}

/// [`solve_sin_cos_near`] without the atan2: the nearer root's sine and cosine.
pub fn nearest_root(
    a: f32,
    b: f32,
    c: f32,
    pred_sc: (f32, f32),
    min_radius: f32,
) -> Option<RootSinCos> {
    if !(a.is_finite()
        && b.is_finite()
        && c.is_finite()
        && pred_sc.0.is_finite()
        && pred_sc.1.is_finite())
    {
        return None;
    }
    let rho2 = a * a + b * b;
    if !(rho2 > min_radius * min_radius && rho2 <= 1e37) {
        return None;
    }
    let clamped = c * c > rho2;
    // Clamped: c = ±ρ, one double root (s = 0).
    let (c, s) = if clamped {
        (libm::copysignf(crate::math::sqrt(rho2), c), 0.0)
    } else {
        (c, crate::math::sqrt(rho2 - c * c))
    };
    let r1 = (a * c + b * s, b * c - a * s);
    let r2 = (a * c - b * s, b * c + a * s);
    // ρ²·cos(xₖ − x_pred): the larger is the nearer root.
    let near1 = r1.0 * pred_sc.0 + r1.1 * pred_sc.1 >= r2.0 * pred_sc.0 + r2.1 * pred_sc.1;
    let (sc, other_sc) = if near1 { (r1, r2) } else { (r2, r1) };
    let inv = 1.0 / rho2;
    Some(RootSinCos { sin_cos: (sc.0 * inv, sc.1 * inv), clamped, other_sc })
}
