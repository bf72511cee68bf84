//! Process model (thesis eq 4.29–4.34, DESIGN §3): Euler kinematics driven by the
//! bias-corrected gyro, gyro bias as Gauss-Markov or random walk.
//!
//! `F = [[A, B], [0, k_b·I]]` with `A = ∂ė/∂(φ,θ,ψ)`, `B = ∂ė/∂b = −E(φ,θ)` and
//! `k_b = −1/τ` (0 for a random walk). The block structure is what makes the
//! covariance propagation in [`super::Ekf::predict`] cheap.

use crate::math::{Mat3, Vec3};

/// The state vector `[φ, θ, ψ, bp, bq, br]` (rad, rad/s).
pub type State = [f32; 6];

/// Everything one predict step needs, evaluated once at the current state.
#[derive(Debug, Clone, Copy)]
pub struct Linearization {
    /// Euler angle rates `[φ̇, θ̇, ψ̇]`, rad/s.
    pub euler_rates: Vec3,
    /// `A = ∂ė/∂(φ, θ, ψ)` (third column is zero: ψ does not enter the kinematics).
    pub a: Mat3,
    /// `B = ∂ė/∂b = −E(φ, θ)`; also the gyro-noise input matrix.
    pub b: Mat3,
    /// Whether |θ| exceeded the gimbal limit and cos θ was guarded.
    pub guarded: bool,
}

/// Evaluates f and its Jacobian at `x` with gyro `gyro` (rad/s, body FRD).
///
/// `min_cos_pitch` guards the singularity at θ = ±90° (thesis eq 5.8): |cos θ| is
/// not allowed below it, so tan θ and 1/cos θ stay finite.
pub fn linearize(x: &State, gyro: Vec3, min_cos_pitch: f32) -> Linearization {
    // sincosf: one argument reduction for both (the predict runs in the IMU interrupt).
    let (sf, cf) = crate::math::sincos(x[0]);
    let (st, ct) = crate::math::sincos(x[1]);
    linearize_sc((sf, cf), (st, ct), [x[3], x[4], x[5]], gyro, min_cos_pitch)
}

/// [`linearize`] at roll and pitch given by their `(sin, cos)` and gyro bias `bias`
/// (rad/s): for callers that already have them (the update's noise-state propagation).
#[inline(always)]
pub fn linearize_sc(roll_sc: (f32, f32), pitch_sc: (f32, f32), bias: Vec3, gyro: Vec3, min_cos_pitch: f32) -> Linearization {
    let (sf, cf) = roll_sc;
    let (st, mut ct) = pitch_sc;
    let guarded = libm::fabsf(ct) < min_cos_pitch;
    if guarded {
        ct = if ct < 0.0 { -min_cos_pitch } else { min_cos_pitch };
    }
    let tt = st / ct;
    let inv_c = 1.0 / ct;
    let (p, q, r) = (gyro[0] - bias[0], gyro[1] - bias[1], gyro[2] - bias[2]);
    let qs_rc = q * sf + r * cf; // q sφ + r cφ
    let qc_rs = q * cf - r * sf; // q cφ − r sφ
    let euler_rates = [p + qs_rc * tt, qc_rs, qs_rc * inv_c];
    let a = [
        [qc_rs * tt, qs_rc * inv_c * inv_c, 0.0],
        [-qs_rc, 0.0, 0.0],
        [qc_rs * inv_c, qs_rc * st * inv_c * inv_c, 0.0],
    ];
    let b = [
        [-1.0, -sf * tt, -cf * tt],
        [0.0, -cf, sf],
        [0.0, -sf * inv_c, -cf * inv_c],
    ];
    Linearization { euler_rates, a, b, guarded }
}

/// The continuous-time state derivative `f(x, ω)` (bias part `−b/τ`).
/// `inv_tau` is 1/τ (0 for a random walk).
pub fn derivative(x: &State, gyro: Vec3, inv_tau: f32, min_cos_pitch: f32) -> State {
    let l = linearize(x, gyro, min_cos_pitch);
    [
        l.euler_rates[0],
        l.euler_rates[1],
        l.euler_rates[2],
        -x[3] * inv_tau,
        -x[4] * inv_tau,
        -x[5] * inv_tau,
    ]
}

/// The full 6×6 Jacobian `F = ∂f/∂x` (for tests and diagnostics; the filter uses
/// the blocks of [`Linearization`] directly).
pub fn jacobian(x: &State, gyro: Vec3, inv_tau: f32, min_cos_pitch: f32) -> [[f32; 6]; 6] {
    let l = linearize(x, gyro, min_cos_pitch);
    let mut f = [[0.0; 6]; 6];
    for i in 0..3 {
        for j in 0..3 {
            f[i][j] = l.a[i][j];
            f[i][j + 3] = l.b[i][j];
        }
        f[i + 3][i + 3] = -inv_tau;
    }
    f
}
