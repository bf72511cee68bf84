//! Process model (thesis eq 4.29–4.34, docs/design.md, process model): Euler kinematics driven by the
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

/// sin/cos of roll and pitch with the pitch singularity guarded, shared by the
/// per-sample kinematics and the Jacobian.
#[derive(Debug, Clone, Copy)]
struct Trig {
    sf: f32,
    cf: f32,
    st: f32,
    /// tan θ, 1/cos θ (guarded).
    tt: f32,
    inv_c: f32,
    guarded: bool,
}

#[inline(always)]
fn trig(x: &State, min_cos_pitch: f32) -> Trig {
    trig_from(crate::math::sincos(x[0]), crate::math::sincos(x[1]), min_cos_pitch)
}

#[inline(always)]
fn trig_from((sf, cf): (f32, f32), (st, ct): (f32, f32), min_cos_pitch: f32) -> Trig {
    let mut ct = ct;
    let guarded = libm::fabsf(ct) < min_cos_pitch;
    if guarded {
        ct = if ct < 0.0 { -min_cos_pitch } else { min_cos_pitch };
    }
    // One division (this is on the sample-to-sample dependency chain of the predict).
    let inv_c = 1.0 / ct;
    Trig { sf, cf, st, tt: st * inv_c, inv_c, guarded }
}

/// `(q sφ + r cφ, q cφ − r sφ)` and the Euler rates for bias-corrected rates `p, q, r`.
#[inline(always)]
fn rates(t: &Trig, p: f32, q: f32, r: f32) -> (f32, f32, Vec3) {
    let qs_rc = q * t.sf + r * t.cf;
    let qc_rs = q * t.cf - r * t.sf;
    (qs_rc, qc_rs, [p + qs_rc * t.tt, qc_rs, qs_rc * t.inv_c])
}

/// The Euler angle rates `[φ̇, θ̇, ψ̇]` (rad/s) at `x` with gyro `gyro` (rad/s, body FRD),
/// and whether the pitch guard applied — the state derivative without the Jacobian
/// (what the decimated predict needs every sample; see [`linearize`]).
#[inline]
#[cfg(any(test, feature = "internals"))]
pub fn euler_rates(x: &State, gyro: Vec3, min_cos_pitch: f32) -> (Vec3, bool) {
    euler_rates_sc(x, crate::math::sincos(x[0]), crate::math::sincos(x[1]), gyro, min_cos_pitch)
}

/// [`euler_rates`] with `(sin, cos)` of roll and pitch given (the predict keeps them
/// from sample to sample).
#[inline(always)]
pub fn euler_rates_sc(
    x: &State,
    roll_sc: (f32, f32),
    pitch_sc: (f32, f32),
    gyro: Vec3,
    min_cos_pitch: f32,
) -> (Vec3, bool) {
    let t = trig_from(roll_sc, pitch_sc, min_cos_pitch);
    let (_, _, e) = rates(&t, gyro[0] - x[3], gyro[1] - x[4], gyro[2] - x[5]);
    (e, t.guarded)
}

/// Evaluates f and its Jacobian at `x` with gyro `gyro` (rad/s, body FRD).
///
/// `min_cos_pitch` guards the singularity at θ = ±90° (thesis eq 5.8): |cos θ| is
/// not allowed below it, so tan θ and 1/cos θ stay finite.
pub fn linearize(x: &State, gyro: Vec3, min_cos_pitch: f32) -> Linearization {
    blocks(&trig(x, min_cos_pitch), [gyro[0] - x[3], gyro[1] - x[4], gyro[2] - x[5]])
}

/// [`linearize`] at roll and pitch given by their `(sin, cos)`, with bias-corrected rates
/// `pqr` (rad/s): for a caller that already has them (the update's fix-noise propagation).
pub fn linearize_sc(
    roll_sc: (f32, f32),
    pitch_sc: (f32, f32),
    pqr: Vec3,
    min_cos_pitch: f32,
) -> Linearization {
    blocks(&trig_from(roll_sc, pitch_sc, min_cos_pitch), pqr)
}

#[inline(always)]
fn blocks(t: &Trig, pqr: Vec3) -> Linearization {
    let (qs_rc, qc_rs, euler_rates) = rates(t, pqr[0], pqr[1], pqr[2]);
    let (sf, cf, st, tt, inv_c) = (t.sf, t.cf, t.st, t.tt, t.inv_c);
    let a = [
        [qc_rs * tt, qs_rc * inv_c * inv_c, 0.0],
        [-qs_rc, 0.0, 0.0],
        [qc_rs * inv_c, qs_rc * st * inv_c * inv_c, 0.0],
    ];
    let b = [[-1.0, -sf * tt, -cf * tt], [0.0, -cf, sf], [0.0, -sf * inv_c, -cf * inv_c]];
    Linearization { euler_rates, a, b, guarded: t.guarded }
}

/// The continuous-time state derivative `f(x, ω)` (bias part `−b/τ`).
/// `inv_tau` is 1/τ (0 for a random walk).
#[cfg(any(test, feature = "internals"))]
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
#[cfg(any(test, feature = "internals"))]
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
