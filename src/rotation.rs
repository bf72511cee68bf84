//! Attitude conventions (docs/design.md, conventions): NED navigation frame, FRD body frame,
//! 3-2-1 Euler angles (yaw ψ, pitch θ, roll φ), all in radians.

use crate::math::Mat3;

/// Roll, pitch, yaw in radians (3-2-1 Euler, NED → FRD).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Euler {
    /// Roll φ, rad, (−π, π].
    pub roll: f32,
    /// Pitch θ, rad, [−π/2, π/2].
    pub pitch: f32,
    /// Yaw ψ, rad, (−π, π].
    pub yaw: f32,
}

/// `R_BN = Rx(φ)·Ry(θ)·Rz(ψ)`: maps NED vectors into body FRD axes.
pub fn r_bn(e: &Euler) -> Mat3 {
    let (sf, cf) = crate::math::sincos(e.roll);
    let (st, ct) = crate::math::sincos(e.pitch);
    let (sp, cp) = crate::math::sincos(e.yaw);
    [
        [ct * cp, ct * sp, -st],
        [sf * st * cp - cf * sp, sf * st * sp + cf * cp, sf * ct],
        [cf * st * cp + sf * sp, cf * st * sp - sf * cp, cf * ct],
    ]
}
