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
/// [`super::accel_roll_pitch::measure`], given the body specific force `accel` (m/s², FRD)
/// with per-axis standard error `accel_sem`, the heading-frame vector `r`, the
/// measured pitch, and the per-component variance `r_var` of `r` ((m/s²)²).
///
/// Pitch solves `−rz sθ + rx cθ = Ax`: `δθ = (δAx + sθ δrz − cθ δrx)/(−rθ)`, so
/// `var θ = (semₓ² + r_var)/rθ²`. Two-axis roll `φ = atan2(Ay, Az) − atan2(ry, rθ)`:
/// `var φ = (Az² sem_y² + Ay² sem_z²)/(Ay² + Az²)² + r_var/(ry² + rθ²)`; single-axis
/// roll solves `rθ sφ + ry cφ = Ay`: `var φ = (sem_y² + r_var)/Az²`.
/// Denominators are floored at `MIN_RADIUS²` so a near-degenerate geometry reports a
/// large but finite variance.
#[cfg(any(test, feature = "internals"))]
pub fn ekf1_roll_pitch_variance(
    form: Ekf1Form,
    accel: Vec3,
    accel_sem: Vec3,
    r: Vec3,
    pitch: f32,
    r_var: f32,
) -> (f32, f32) {
    ekf1_roll_pitch_variance_sc(
        form,
        accel,
        accel_sem.map(|s| s * s),
        r,
        crate::math::sincos(pitch),
        r_var,
    )
}

/// [`ekf1_roll_pitch_variance`] from the squared standard errors and the measured pitch's
/// (sin, cos) — what the update already has (no √, no sincos in the interrupt).
#[cfg(any(test, feature = "internals"))]
pub fn ekf1_roll_pitch_variance_sc(
    form: Ekf1Form,
    accel: Vec3,
    accel_sem_sq: Vec3,
    r: Vec3,
    pitch_sc: (f32, f32),
    r_var: f32,
) -> (f32, f32) {
    let n = ekf1_roll_pitch_noise(form, accel, accel_sem_sq, r, pitch_sc);
    let [gr, gp] = n.gain_sq;
    (n.accel_var[0] + gr * r_var, n.accel_var[1] + gp * r_var)
}

/// How the noise of one EKF1 roll/pitch measurement is made up (see
/// [`ekf1_roll_pitch_variance`]): `var = accel_var + gain²·r_var`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ekf1Noise {
    /// Variance from the accelerometer's interval mean, rad² (roll, pitch).
    pub accel_var: [f32; 2],
    /// Squared sensitivity to the heading-frame GPS acceleration, (rad per m/s²)²
    /// (roll, pitch): the GPS part of the variance per (m/s²)² of `r_var`.
    pub gain_sq: [f32; 2],
    /// The sensitivity itself, signed (roll, pitch): an error `δa` of the GPS acceleration
    /// along the axis' direction (a unit vector, orthogonal for roll and pitch) moves the
    /// measurement by `gain·δa`. Two-axis roll and pitch need no √; `None` for
    /// the single-axis roll (computed only on request, [`Ekf1Noise::gain`]).
    gain_fast: [Option<f32>; 2],
    /// Sensitivity to an error of the heading that rotated the GPS acceleration into the
    /// heading frame, rad per rad (roll, pitch): `∂r/∂ψ = (ry, −rx, 0)` through the
    /// model. Zero in straight flight; ~|a_h|/g in a turn (pitch).
    pub heading_gain: [f32; 2],
}

impl Ekf1Noise {
    /// Signed sensitivity of roll (0) or pitch (1), rad per m/s².
    pub fn gain(&self, axis: usize) -> f32 {
        self.gain_fast[axis].unwrap_or_else(|| crate::math::sqrt(self.gain_sq[axis]))
    }
}

/// The parts of the EKF1 roll/pitch variances: accelerometer variance and the GPS
/// sensitivity (see [`ekf1_roll_pitch_variance`] for the derivation).
///
/// Pitch: `δθ = (cθ δrx − sθ δrz)/rθ`, the unit direction `(cθ, 0, −sθ)` over `rθ`.
/// Two-axis roll: `δφ = (ry sθ δrx − rθ δry + ry cθ δrz)/(ry² + rθ²) + c·δθ` with
/// `c = ry (rx cθ − rz sθ)/(ry² + rθ²)` (roll is solved with the measured pitch): a unit
/// direction orthogonal to pitch's over `√(ry² + rθ²)`, plus `c` times pitch's. `c` is 0 in
/// straight flight and ~0.01 in a coordinated turn; with a forward acceleration in a turn
/// the roll and pitch noises correlate (cosine 0.13 at 30° bank and 5.7 m/s², −0.27 at
/// −45° and 9.4 m/s²: `tests/fix_noise.rs`), which the
/// fix-noise states neglect. Single-axis roll: `δφ = −δry/Az` to first order at the
/// solution (`Ay = rθ sφ + ry cφ`, its derivative in φ is `Az`; the pitch chain and the
/// sφ terms are dropped).
pub fn ekf1_roll_pitch_noise(
    form: Ekf1Form,
    accel: Vec3,
    accel_sem_sq: Vec3,
    r: Vec3,
    pitch_sc: (f32, f32),
) -> Ekf1Noise {
    const MIN_RADIUS2: f32 = 0.25;
    const MIN_RADIUS: f32 = 0.5;
    // Not `f32::max`: a libm call on the M4F; the arguments are finite sums of squares.
    let floor = |x: f32| if x > MIN_RADIUS2 { x } else { MIN_RADIUS2 };
    // A signed radius floored in magnitude (same floor as the squares).
    let floor_signed = |x: f32| {
        if x >= MIN_RADIUS || x <= -MIN_RADIUS {
            x
        } else if x < 0.0 {
            -MIN_RADIUS
        } else {
            MIN_RADIUS
        }
    };
    let (st, ct) = pitch_sc;
    let r_theta = r[0] * st + r[2] * ct;
    let sq = |x: f32| x * x;
    let rt = floor_signed(r_theta);
    let gain_p = 1.0 / rt;
    let var_pitch = accel_sem_sq[0] * sq(gain_p);
    // δr = (ry, −rx, 0)·δψ.
    let heading_p = ct * r[1] * gain_p;
    let (accel_roll, gain_sq_roll, gain_roll, heading_r) = match form {
        Ekf1Form::RobustTwoAxis => {
            let a2 = floor(sq(accel[1]) + sq(accel[2]));
            let accel_part =
                (sq(accel[2]) * accel_sem_sq[1] + sq(accel[1]) * accel_sem_sq[2]) / (a2 * a2);
            let inv_rho2 = 1.0 / floor(sq(r[1]) + sq(r_theta));
            // δφ = −(rθ δry − ry δrθ)/ρ² with δrθ = sθ δrx + cθ δrz + (rx cθ − rz sθ)·δθ:
            // the measured pitch enters rθ, so roll also moves by c·δθ. The direct part is
            // orthogonal to pitch's direction, the c·δθ part is along it: |∇φ|² adds c²/rθ².
            let c = r[1] * (r[0] * ct - r[2] * st) * inv_rho2;
            let direct = (r_theta * r[0] + sq(r[1]) * st) * inv_rho2;
            (accel_part, inv_rho2 + sq(c * gain_p), None, direct + c * heading_p)
        }
        Ekf1Form::RobustSingleAxis | Ekf1Form::ThesisExact => {
            let az = floor_signed(accel[2]);
            let g = -1.0 / az;
            // δφ = −(sφ δrθ + cφ δry)/Az with sφ ≈ 0 dropped: the roll is not at hand here.
            (accel_sem_sq[1] * sq(g), sq(g), Some(g), -r[0] * g)
        }
    };
    Ekf1Noise {
        accel_var: [accel_roll, var_pitch],
        gain_sq: [gain_sq_roll, sq(gain_p)],
        gain_fast: [gain_roll, Some(gain_p)],
        heading_gain: [heading_r, heading_p],
    }
}

/// Variance (rad²) of the course `atan2(vE, vN)` of a velocity whose horizontal
/// components each have variance `vel_var` ((m/s)²): `vel_var / V²`, with the
/// ground speed floored at 1 m/s.
pub fn course_variance(vel_var: f32, vel: Vec3) -> f32 {
    let v2 = vel[0] * vel[0] + vel[1] * vel[1];
    vel_var / if v2 > 1.0 { v2 } else { 1.0 }
}
