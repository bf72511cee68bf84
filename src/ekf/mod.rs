//! The six-state half-EKF: state `[φ, θ, ψ, bp, bq, br]`, covariance P, the
//! predict step and sequential scalar updates with `H = [I₃ 0]`.
//!
//! This module knows nothing about sensors or measurement models; it is driven
//! by [`crate::Ahrs`].

pub mod fix_noise;
pub mod process;

use crate::math::{wrap_pi, Mat3, Mat6, Vec3, PI};
pub use process::State;

/// Smallest allowed variance on any diagonal entry (keeps P PD in f32).
const VAR_FLOOR: f32 = 1e-12;

/// Noise terms of one predict step (continuous densities, see [`crate::Config`]).
#[derive(Debug, Clone, Copy)]
pub struct ProcessNoise {
    /// Gyro white-noise spectral density, (rad/s)²/Hz = rad²/s.
    pub gyro_psd: f32,
    /// Bias driving-noise spectral density, (rad/s)²/s, before λ².
    pub bias_psd: f32,
    /// λ of G (thesis eq 5.6).
    pub lambda: f32,
    /// Extra attitude spectral density, rad²/s.
    pub attitude_psd: f32,
    /// 1/τ of the bias model (0: random walk).
    pub inv_tau: f32,
}

/// Caps on the covariance diagonal (attitude rad², bias (rad/s)²): long outages
/// must not grow P without bound in f32.
#[derive(Debug, Clone, Copy)]
pub struct VarianceCaps {
    /// Largest attitude variance, rad².
    pub attitude: f32,
    /// Largest bias variance, (rad/s)².
    pub bias: f32,
}

/// The filter state and covariance.
#[derive(Debug, Clone, Copy)]
pub struct Ekf {
    /// State estimate.
    pub x: State,
    /// Error covariance, symmetric positive definite.
    pub p: Mat6,
}

/// Result of one scalar update.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScalarUpdate {
    /// Innovation ν, rad (wrapped).
    pub innovation: f32,
    /// Innovation variance S, rad².
    pub variance: f32,
    /// Whether the update was applied (false: gated or invalid).
    pub applied: bool,
}

/// Linearisations accumulated since the last covariance propagation (decimated predict,
/// see [`Ekf::predict_decimated`]). Only the entries of A and B that can be non-zero are
/// summed (A = [[·, ·, 0], [·, 0, 0], [·, ·, 0]], B's first column is [−1, 0, 0]ᵀ).
#[derive(Debug, Clone, Copy, Default)]
pub struct PendingCovariance {
    /// Accumulated Δt, s.
    dt: f32,
    /// Sums of A₀₀, A₀₁, A₁₀, A₂₀, A₂₁.
    a: [f32; 5],
    /// Sums of B₀₁, B₀₂, B₁₁, B₁₂, B₂₁, B₂₂.
    b: [f32; 6],
    /// Samples accumulated.
    n: u32,
}

impl PendingCovariance {
    fn add(&mut self, dt: f32, a: &Mat3, b: &Mat3) {
        self.dt += dt;
        let av = [a[0][0], a[0][1], a[1][0], a[2][0], a[2][1]];
        let bv = [b[0][1], b[0][2], b[1][1], b[1][2], b[2][1], b[2][2]];
        for i in 0..5 {
            self.a[i] += av[i];
        }
        for i in 0..6 {
            self.b[i] += bv[i];
        }
        self.n += 1;
    }

    /// The block's mean A and B (samples are equally spaced to within IMU jitter).
    fn mean(&self) -> (Mat3, Mat3) {
        let k = 1.0 / self.n as f32;
        let a = self.a.map(|v| v * k);
        let b = self.b.map(|v| v * k);
        ([[a[0], a[1], 0.0], [a[2], 0.0, 0.0], [a[3], a[4], 0.0]], [[-1.0, b[0], b[1]], [0.0, b[2], b[3]], [0.0, b[4], b[5]]])
    }

    /// Samples whose covariance propagation is still pending.
    pub fn samples(&self) -> u32 {
        self.n
    }
}

impl Ekf {
    /// A filter at `x` with diagonal covariance `var`.
    pub fn new(x: State, var: [f32; 6]) -> Self {
        let mut p = [[0.0; 6]; 6];
        for i in 0..6 {
            p[i][i] = var[i];
        }
        Ekf { x, p }
    }

    /// One predict step of length `dt` s with gyro `gyro` (rad/s, body FRD).
    ///
    /// Euler step `x += f·Δt`; `Φ ≈ I + FΔt + (FΔt)²/2`; `P = ΦPΦᵀ + Qd` with
    /// `Qd = G·Qc·Gᵀ·Δt` (first-order hold of the continuous densities), computed
    /// blockwise. Returns the linearisation used (Euler rates, pitch-guard flag).
    pub fn predict(&mut self, dt: f32, gyro: Vec3, n: &ProcessNoise, min_cos_pitch: f32, caps: VarianceCaps) -> process::Linearization {
        let lin = process::linearize(&self.x, gyro, min_cos_pitch);
        self.propagate_covariance(dt, &lin.a, &lin.b, n);
        self.step_state(dt, &lin, n.inv_tau);
        self.condition(caps);
        lin
    }

    /// A predict step whose covariance propagation is decimated: the state is integrated
    /// now; the linearisation is accumulated in `pending`, and every `every` samples (or on
    /// [`Ekf::flush`]) P is propagated once over the accumulated Δt with the mean A and B
    /// of the block. `every ≤ 1` is [`Ekf::predict`] exactly. Standard practice on small
    /// CPUs (PX4 EKF2 also propagates its covariance at a lower rate than its state); the
    /// cost is a P that lags the state by at most `every − 1` samples between flushes.
    pub fn predict_decimated(&mut self, dt: f32, gyro: Vec3, n: &ProcessNoise, min_cos_pitch: f32, caps: VarianceCaps, pending: &mut PendingCovariance, every: u8) -> process::Linearization {
        if every <= 1 {
            return self.predict(dt, gyro, n, min_cos_pitch, caps);
        }
        let lin = process::linearize(&self.x, gyro, min_cos_pitch);
        pending.add(dt, &lin.a, &lin.b);
        self.step_state(dt, &lin, n.inv_tau);
        if pending.n >= every as u32 {
            self.flush(pending, n, caps);
        }
        lin
    }

    /// Propagates P over everything accumulated in `pending` (no-op when empty). Call before
    /// anything reads or updates P.
    pub fn flush(&mut self, pending: &mut PendingCovariance, n: &ProcessNoise, caps: VarianceCaps) {
        if pending.n == 0 {
            return;
        }
        let (a, b) = pending.mean();
        self.propagate_covariance(pending.dt, &a, &b, n);
        *pending = PendingCovariance::default();
        self.condition(caps);
    }

    /// State: Euler step, bias decay, angle normalisation.
    #[inline(always)]
    fn step_state(&mut self, dt: f32, lin: &process::Linearization, inv_tau: f32) {
        let kb = -inv_tau;
        for i in 0..3 {
            self.x[i] += lin.euler_rates[i] * dt;
            self.x[i + 3] += kb * self.x[i + 3] * dt;
        }
        self.normalize_angles();
    }

    /// `P = ΦPΦᵀ + Qd` over `dt` for the linearisation blocks `a`, `b` (see [`Ekf::predict`]).
    #[inline(always)]
    fn propagate_covariance(&mut self, dt: f32, a: &Mat3, b: &Mat3, n: &ProcessNoise) {
        // The structural zeros and −1 of A and B as constants (they are exactly so in every
        // linearisation), so the products below fold them away on both call paths.
        let a = &[[a[0][0], a[0][1], 0.0], [a[1][0], 0.0, 0.0], [a[2][0], a[2][1], 0.0]];
        let b = &[[-1.0, b[0][1], b[0][2]], [0.0, b[1][1], b[1][2]], [0.0, b[2][1], b[2][2]]];
        let kb = -n.inv_tau;
        let h = 0.5 * dt * dt;

        // Φ blocks: Φa = I + AΔt + A²Δt²/2, Φb = BΔt + (AB + k_b B)Δt²/2, φd scalar.
        // A's third column is zero (ψ does not enter f), so A² and AB need only k ∈ {0, 1}
        // and Φa's third column is exactly e₂ — used below to skip those products.
        let mut g = [[0.0f32; 6]; 3]; // G = [Φa | Φb]
        for i in 0..3 {
            for j in 0..3 {
                let a2 = a[i][0] * a[0][j] + a[i][1] * a[1][j];
                let ab = a[i][0] * b[0][j] + a[i][1] * b[1][j];
                g[i][j] = a[i][j] * dt + a2 * h + if i == j { 1.0 } else { 0.0 };
                g[i][j + 3] = b[i][j] * dt + (ab + kb * b[i][j]) * h;
            }
        }
        let phi_d = 1.0 + kb * dt + kb * kb * h;

        // W = G·P (3×6). Then Paa' = W·Gᵀ + Qd_aa, Pab' = W[:, 3..6]·φd, Pbb' = φd²·Pbb + Qd_bb:
        // one 3×6·6×6 product instead of six 3×3 ones (cost: this runs every IMU sample).
        let mut w = [[0.0f32; 6]; 3];
        for i in 0..3 {
            for k in 0..6 {
                let p = &self.p;
                let mut acc = g[i][0] * p[0][k] + g[i][1] * p[1][k];
                for j in 3..6 {
                    acc += g[i][j] * p[j][k];
                }
                w[i][k] = if i == 2 { acc + p[2][k] } else { acc };
            }
        }
        let q_att = n.gyro_psd * dt;
        let q_extra = n.attitude_psd * dt;
        let q_bias = n.lambda * n.lambda * n.bias_psd * dt;
        for i in 0..3 {
            for l in i..3 {
                let mut v = w[i][0] * g[l][0] + w[i][1] * g[l][1];
                for k in 3..6 {
                    v += w[i][k] * g[l][k];
                }
                if l == 2 {
                    v += w[i][2];
                }
                // Qd_aa = q·B·Bᵀ (B's first column is [−1, 0, 0]ᵀ).
                let mut bbt = b[i][1] * b[l][1] + b[i][2] * b[l][2];
                if i == 0 && l == 0 {
                    bbt += 1.0;
                }
                v += q_att * bbt;
                if i == l {
                    v += q_extra;
                }
                self.p[i][l] = v;
                self.p[l][i] = v;
            }
            for m in 0..3 {
                let v = w[i][m + 3] * phi_d;
                self.p[i][m + 3] = v;
                self.p[m + 3][i] = v;
            }
        }
        let pd2 = phi_d * phi_d;
        for i in 3..6 {
            for j in i..6 {
                let v = pd2 * self.p[i][j] + if i == j { q_bias } else { 0.0 };
                self.p[i][j] = v;
                self.p[j][i] = v;
            }
        }
    }

    /// Scalar update of attitude axis `i` (0 roll, 1 pitch, 2 yaw) with measurement
    /// `z` (rad) of variance `r` (rad²). The innovation is wrapped to (−π, π].
    /// If `gate` is finite and ν²/S exceeds it, nothing is applied.
    ///
    /// `P ← P − P·eᵢ·eᵢᵀ·P / S` computed on the upper triangle and mirrored, so P
    /// stays exactly symmetric; with S = Pᵢᵢ + r > Pᵢᵢ this keeps P PD. (For H = eᵢ
    /// this equals the Joseph form with the optimal gain.) The angles are not
    /// re-normalised here: call [`Ekf::normalize_angles`] after the batch of axes.
    pub fn update_axis(&mut self, i: usize, z: f32, r: f32, gate: f32) -> ScalarUpdate {
        let nu = wrap_pi(z - self.x[i]);
        let s = self.p[i][i] + r;
        // Float comparisons (false for NaN) rather than bit tests: fewer instructions on the M4F.
        if !(libm::fabsf(nu) < f32::INFINITY && s > 0.0 && s < f32::INFINITY) {
            return ScalarUpdate { innovation: nu, variance: s, applied: false };
        }
        if nu * nu > gate * s {
            return ScalarUpdate { innovation: nu, variance: s, applied: false };
        }
        let col: [f32; 6] = core::array::from_fn(|k| self.p[k][i]);
        let inv_s = 1.0 / s;
        // Gain K = P·eᵢ/S, once: one multiply per P entry below instead of two.
        let gain: [f32; 6] = core::array::from_fn(|k| col[k] * inv_s);
        for k in 0..6 {
            self.x[k] += gain[k] * nu;
        }
        for j in 0..6 {
            // Diagonal: floored in the same pass (S > Pᵢᵢ keeps it ≥ 0 but f32 can round to 0).
            let d = self.p[j][j] - gain[j] * col[j];
            self.p[j][j] = if d < VAR_FLOOR { VAR_FLOOR } else { d };
            for k in j + 1..6 {
                let v = self.p[j][k] - gain[j] * col[k];
                self.p[j][k] = v;
                self.p[k][j] = v;
            }
        }
        ScalarUpdate { innovation: nu, variance: s, applied: true }
    }

    /// Raises the variance of axis `i` to at least `var`, scaling its row and column
    /// so correlations (and positive definiteness) are preserved.
    pub fn inflate_axis(&mut self, i: usize, var: f32) {
        let old = self.p[i][i];
        if !(var > old) {
            return;
        }
        let k = libm::sqrtf(var / old.max(VAR_FLOOR));
        for j in 0..6 {
            self.p[i][j] *= k;
            self.p[j][i] *= k;
        }
        self.p[i][i] = var;
    }

    /// Sets attitude axis `i` to `value`, decorrelates it and gives it variance `var`
    /// (initialisation from a measurement).
    pub fn reset_axis(&mut self, i: usize, value: f32, var: f32) {
        self.x[i] = value;
        for j in 0..6 {
            self.p[i][j] = 0.0;
            self.p[j][i] = 0.0;
        }
        self.p[i][i] = var;
        self.normalize_angles();
    }

    /// Keeps roll and yaw in (−π, π] and pitch in [−π/2, π/2] (an over-the-top pitch
    /// is the same attitude as (φ+π, π−θ, ψ+π)). [`Ekf::update_axis`] leaves this to the
    /// caller, once after a batch of axes (innovations are wrapped, so order is immaterial).
    pub fn normalize_angles(&mut self) {
        let half = 0.5 * PI;
        if self.x[1] > half || self.x[1] < -half {
            let sgn = if self.x[1] > 0.0 { 1.0 } else { -1.0 };
            self.x[1] = sgn * PI - self.x[1];
            self.x[0] += PI;
            self.x[2] += PI;
        }
        self.x[0] = wrap_pi(self.x[0]);
        self.x[2] = wrap_pi(self.x[2]);
    }

    /// Floors, caps and checks the diagonal. Returns whether anything was repaired.
    ///
    /// A capped P is one the data no longer constrains (e.g. roll and yaw near
    /// gimbal lock, where only φ ± ψ is observable): its correlations approach ±1 and
    /// f32 rounding can make it indefinite. Whenever a cap applies, the correlation
    /// matrix is loaded by `CAP_LOADING` (Pᵢᵢ ×= 1 + ε), which bounds its smallest
    /// eigenvalue away from the rounding noise (~n·2⁻²⁴) at negligible cost to accuracy.
    pub fn condition(&mut self, caps: VarianceCaps) -> bool {
        const CAP_LOADING: f32 = 1e-4;
        let mut repaired = false;
        let mut capped = false;
        for i in 0..6 {
            let cap = if i < 3 { caps.attitude } else { caps.bias };
            let d = self.p[i][i];
            if !d.is_finite() {
                repaired = true;
                continue;
            }
            if d < VAR_FLOOR {
                self.p[i][i] = VAR_FLOOR;
                repaired = true;
            } else if d > cap {
                let k = libm::sqrtf(cap / d);
                for j in 0..6 {
                    self.p[i][j] *= k;
                    self.p[j][i] *= k;
                }
                self.p[i][i] = cap;
                capped = true;
            }
        }
        if capped {
            for i in 0..6 {
                self.p[i][i] *= 1.0 + CAP_LOADING;
            }
        }
        // The diagonal is capped, so |Pᵢⱼ| ≤ √(PᵢᵢPⱼⱼ) ≤ cap: an off-diagonal can only go
        // non-finite through a non-finite diagonal. Check the 6 variances and 6 states (one
        // sum: any NaN or ±Inf makes it non-finite) — this runs every IMU sample.
        let mut sum = 0.0f32;
        for i in 0..6 {
            sum += self.p[i][i] * 0.0 + self.x[i] * 0.0;
        }
        if !sum.is_finite() {
            // Should be unreachable (inputs are validated); never let NaN persist.
            let mut fresh = Ekf::new([0.0; 6], [caps.attitude, caps.attitude, caps.attitude, caps.bias, caps.bias, caps.bias]);
            for i in 0..6 {
                if self.x[i].is_finite() {
                    fresh.x[i] = self.x[i];
                }
            }
            *self = fresh;
            repaired = true;
        }
        repaired
    }
}
