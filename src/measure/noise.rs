//! Measurement noise: the variance of each measured angle, per update, propagated to
//! first order from the noise of what it was formed from — the GPS velocities (the
//! receiver's speed accuracy, or a configured σ) and the accelerometer's interval mean
//! (its standard error, which includes vibration).
//!
//! A fixed R cannot be right for both a 10 Hz receiver with 1 cm/s noise (≈ 0.8° per
//! EKF1 measurement) and a 5 Hz receiver with 0.1 m/s noise (≈ 4°): the differenced
//! acceleration's noise scales as σv/Δt. An unmodelled-error floor (misalignment,
//! lever arm, model error) is added in quadrature by the caller.

use crate::config::Ekf1Form;
use crate::math::Vec3;

/// Variance of each component of a GPS-differenced acceleration, (m/s²)²:
/// `(σ₀² + σ₁²)/Δt²` for fixes with per-component velocity σ₀, σ₁ (m/s), Δt s apart.
pub fn differenced_accel_variance(vel_var_sum: f32, dt: f32) -> f32 {
    vel_var_sum / (dt * dt)
}

/// Variances (rad²) of the EKF1 roll and pitch measurements of
/// [`super::gps_accel::measure`], given the body specific force `accel` (m/s², FRD)
/// with per-axis standard error `accel_sem`, the heading-frame vector `r`, the
/// measured pitch, and the per-component variance `r_var` of `r` ((m/s²)²).
///
/// Pitch solves `−rz sθ + rx cθ = Ax`: `δθ = (δAx + sθ δrz − cθ δrx)/(−rθ)`, so
/// `var θ = (semₓ² + r_var)/rθ²`. Two-axis roll `φ = atan2(Ay, Az) − atan2(ry, rθ)`:
/// `var φ = (Az² sem_y² + Ay² sem_z²)/(Ay² + Az²)² + r_var/(ry² + rθ²)`; single-axis
/// roll solves `rθ sφ + ry cφ = Ay`: `var φ = (sem_y² + r_var)/Az²`.
/// Denominators are floored at `MIN_RADIUS²` so a near-degenerate geometry reports a
/// large but finite variance.
pub fn ekf1_roll_pitch_variance(form: Ekf1Form, accel: Vec3, accel_sem: Vec3, r: Vec3, pitch: f32, r_var: f32) -> (f32, f32) {
    ekf1_roll_pitch_variance_sc(form, accel, accel_sem.map(|s| s * s), r, crate::math::sincos(pitch), r_var)
}

/// [`ekf1_roll_pitch_variance`] from the squared standard errors and the measured pitch's
/// (sin, cos) — what the update already has (no √, no sincos in the interrupt).
pub fn ekf1_roll_pitch_variance_sc(form: Ekf1Form, accel: Vec3, accel_sem_sq: Vec3, r: Vec3, pitch_sc: (f32, f32), r_var: f32) -> (f32, f32) {
    const MIN_RADIUS2: f32 = 0.25;
    // Not `f32::max`: a libm call on the M4F; the arguments are finite sums of squares.
    let floor = |x: f32| if x > MIN_RADIUS2 { x } else { MIN_RADIUS2 };
    let (st, ct) = pitch_sc;
    let r_theta = r[0] * st + r[2] * ct;
    let sq = |x: f32| x * x;
    let var_pitch = (accel_sem_sq[0] + r_var) / floor(sq(r_theta));
    let var_roll = match form {
        Ekf1Form::RobustTwoAxis => {
            let a2 = floor(sq(accel[1]) + sq(accel[2]));
            let accel_part = (sq(accel[2]) * accel_sem_sq[1] + sq(accel[1]) * accel_sem_sq[2]) / (a2 * a2);
            accel_part + r_var / floor(sq(r[1]) + sq(r_theta))
        }
        Ekf1Form::RobustSingleAxis | Ekf1Form::ThesisExact => (accel_sem_sq[1] + r_var) / floor(sq(accel[2])),
    };
    (var_roll, var_pitch)
}

/// Variance (rad²) of the course `atan2(vE, vN)` of a velocity whose horizontal
/// components each have variance `vel_var` ((m/s)²): `vel_var / V²`, with the
/// ground speed floored at 1 m/s.
pub fn course_variance(vel_var: f32, vel: Vec3) -> f32 {
    let v2 = vel[0] * vel[0] + vel[1] * vel[1];
    vel_var / if v2 > 1.0 { v2 } else { 1.0 }
}
