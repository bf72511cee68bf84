//! Yaw measurement from the GPS course (thesis eq 4.36), optionally corrected for
//! the nose-to-velocity offset in banked flight (DESIGN §3.1, thesis eq 5.9).
//!
//! With β = 0 the velocity is `V·[cα, 0, sα]` in body axes, which gives
//! `sin γ = cα sθ − sα cφ cθ` and `ψ = χ + atan2(sα sφ, cα cθ + sα cφ sθ)`.
//! α is recovered from the predicted φ, θ and the GPS γ with the shared solver.

use super::solver::solve_sin_cos;
use crate::math::wrap_pi;

/// Course over ground χ = atan2(vE, vN), rad in (−π, π].
pub fn course(vn: f32, ve: f32) -> f32 {
    libm::atan2f(ve, vn)
}

/// Angle of attack α from `sin γ = cα sθ − sα cφ cθ`, the root nearer zero.
/// `None` when degenerate (|cos φ cos θ| and |sin θ| both ≈ 0).
pub fn angle_of_attack(roll: f32, pitch: f32, gamma: f32) -> Option<f32> {
    let (st, ct) = crate::math::sincos(pitch);
    let a = -crate::math::cos(roll) * ct;
    let b = st;
    solve_sin_cos(a, b, crate::math::sin(gamma), 0.0, 1e-3).map(|s| s.x)
}

/// `ψ − χ` for a body with angle of attack α at roll φ and pitch θ (β = 0), rad.
pub fn yaw_minus_course(roll: f32, pitch: f32, alpha: f32) -> f32 {
    let (sa, ca) = crate::math::sincos(alpha);
    let (sf, cf) = crate::math::sincos(roll);
    let (st, ct) = crate::math::sincos(pitch);
    libm::atan2f(sa * sf, ca * ct + sa * cf * st)
}

/// Yaw measured from course `chi`, corrected with α when `alpha` is given.
pub fn yaw_from_course(chi: f32, roll: f32, pitch: f32, alpha: Option<f32>) -> f32 {
    match alpha {
        Some(a) => wrap_pi(chi + yaw_minus_course(roll, pitch, a)),
        None => chi,
    }
}
