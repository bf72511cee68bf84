//! Angle-based forms of the core's heading model (`measure/heading.rs`, thesis eq 5.9): the
//! same equations written with angles instead of the update's sin/cos algebra, as oracles
//! for it.

use wing_ahrs::math::{sincos, wrap_pi};
use wing_ahrs::measure::heading::{angle_of_attack_trig, RollPitchTrig};

/// Angle of attack α from `sin γ = cα sθ − sα cφ cθ`, the root nearer zero.
/// `None` when degenerate (|cos φ cos θ| and |sin θ| both ≈ 0).
pub fn angle_of_attack(roll: f32, pitch: f32, gamma: f32) -> Option<f32> {
    angle_of_attack_trig(&RollPitchTrig::new(roll, pitch), wing_ahrs::math::sin(gamma))
        .map(|a| a.alpha())
}

/// `ψ − χ` for a body with angle of attack α at roll φ and pitch θ (β = 0), rad.
pub fn yaw_minus_course(roll: f32, pitch: f32, alpha: f32) -> f32 {
    let (sa, ca) = sincos(alpha);
    let t = RollPitchTrig::new(roll, pitch);
    wing_ahrs::math::atan2(sa * t.sf, ca * t.ct + sa * t.cf * t.st)
}

/// Yaw measured from course `chi`, corrected with α when `alpha` is given.
pub fn yaw_from_course(chi: f32, roll: f32, pitch: f32, alpha: Option<f32>) -> f32 {
    match alpha {
        Some(a) => wrap_pi(chi + yaw_minus_course(roll, pitch, a)),
        None => chi,
    }
}
