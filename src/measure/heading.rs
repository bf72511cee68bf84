//! Yaw measurement from the GPS course (thesis eq 4.36), optionally corrected for
//! the nose-to-velocity offset in banked flight (docs/design.md, heading from the course; thesis eq 5.9).
//!
//! With β = 0 the velocity is `V·[cα, 0, sα]` in body axes, which gives
//! `sin γ = cα sθ − sα cφ cθ` and `ψ = χ + atan2(sα sφ, cα cθ + sα cφ sθ)`.
//! α is recovered from the predicted φ, θ and the GPS γ with the shared solver.
//!
//! The update path ([`RollPitchTrig`], [`angle_of_attack_trig`], [`yaw_and_sin_cos_from_velocity`])
//! takes sin/cos of φ, θ computed once, gets sin α, cos α from the solver's algebra and
//! adds χ and ψ − χ as one complex product, so the corrected yaw costs one atan2 instead
//! of three atan2, an acos and seven sincos (cost: the update runs in the IMU interrupt).
//! The angle-based forms of the same models are test oracles (`tests/common/heading.rs`).

use super::solver::nearest_root;
use crate::math::Vec3;

/// sin and cos of the predicted roll φ and pitch θ, computed once per update.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RollPitchTrig {
    /// sin φ.
    pub sf: f32,
    /// cos φ.
    pub cf: f32,
    /// sin θ.
    pub st: f32,
    /// cos θ.
    pub ct: f32,
}

impl RollPitchTrig {
    /// From roll and pitch (rad).
    #[cfg(any(test, feature = "internals"))]
    pub fn new(roll: f32, pitch: f32) -> Self {
        let (sf, cf) = crate::math::sincos(roll);
        let (st, ct) = crate::math::sincos(pitch);
        RollPitchTrig { sf, cf, st, ct }
    }

    /// From `[(sin φ, cos φ), (sin θ, cos θ)]`.
    pub fn from_sin_cos([(sf, cf), (st, ct)]: [(f32, f32); 2]) -> Self {
        RollPitchTrig { sf, cf, st, ct }
    }
}

/// Angle of attack as solved: `(sin α, cos α)` (α itself is one atan2 away, [`Aoa::alpha`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aoa {
    /// (sin α, cos α).
    pub sin_cos: (f32, f32),
}

impl Aoa {
    /// α, rad.
    #[cfg(any(test, feature = "internals"))]
    pub fn alpha(&self) -> f32 {
        crate::math::atan2(self.sin_cos.0, self.sin_cos.1)
    }
}

/// Course over ground χ = atan2(vE, vN), rad in (−π, π].
pub fn course(vn: f32, ve: f32) -> f32 {
    crate::math::atan2(ve, vn)
}

/// sin γ = −vD/|v| of NED velocity `v` (no trigonometry); 0 when |v| = 0.
pub fn sin_flight_path_angle(v: Vec3) -> f32 {
    let n2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    if n2 > 0.0 {
        -v[2] / crate::math::sqrt(n2)
    } else {
        0.0
    }
}

/// Angle of attack from `sin γ = cα sθ − sα cφ cθ`, the root nearer zero.
/// `None` when degenerate (|cos φ cos θ| and |sin θ| both ≈ 0).
pub fn angle_of_attack_trig(t: &RollPitchTrig, sin_gamma: f32) -> Option<Aoa> {
    // Prediction α = 0: (sin, cos) = (0, 1).
    nearest_root(-t.cf * t.ct, t.st, sin_gamma, (0.0, 1.0), 1e-3)
        .map(|r| Aoa { sin_cos: r.sin_cos })
}

/// Yaw measured from NED velocity (vN, vE) — the course χ, plus `ψ − χ` for angle of
/// attack `aoa` = (sin α, cos α) when given, rad in (−π, π] — and its `(sin, cos)`, both
/// from the same complex number: its argument, and the number over its modulus (a √ and a
/// division instead of a sincos of the angle, off the update's dependency chain — the yaw
/// is the heading that rotates the GPS acceleration). Falls back to a sincos when the
/// modulus is 0 or not finite.
pub fn yaw_and_sin_cos_from_velocity(
    vn: f32,
    ve: f32,
    t: &RollPitchTrig,
    aoa: Option<(f32, f32)>,
) -> (f32, (f32, f32)) {
    let (y, x) = yaw_vector(vn, ve, t, aoa);
    let yaw = crate::math::atan2(y, x);
    let n2 = x * x + y * y;
    let sc = if n2 > 0.0 && n2 < f32::INFINITY {
        let k = 1.0 / crate::math::sqrt(n2);
        (y * k, x * k)
    } else {
        crate::math::sincos(yaw)
    };
    (yaw, sc)
}

/// `(Y, X)` with ψ = arg(X + iY): the course's (vE, vN), turned by ψ − χ when α is given.
#[inline(always)]
fn yaw_vector(vn: f32, ve: f32, t: &RollPitchTrig, aoa: Option<(f32, f32)>) -> (f32, f32) {
    match aoa {
        Some((sa, ca)) => {
            // ψ − χ = arg(X + iY); ψ = arg((vN + i vE)·(X + iY)).
            let y = sa * t.sf;
            let x = ca * t.ct + sa * t.cf * t.st;
            (ve * x + vn * y, vn * x - ve * y)
        }
        None => (ve, vn),
    }
}
