//! The six-state half-EKF: state `[φ, θ, ψ, bp, bq, br]`, covariance P, the
//! predict step and sequential scalar updates with `H = [I₃ 0]`.
//!
//! This module knows nothing about sensors or measurement models; it is driven
//! by [`crate::Ahrs`].

pub mod process;

use crate::math::{mul3, mul3_bt, wrap_pi, Mat3, Mat6, Vec3, PI};
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
        let (a, b) = (lin.a, lin.b);
        let kb = -n.inv_tau;
        let h = 0.5 * dt * dt;

        // Φ blocks: Φa = I + AΔt + A²Δt²/2, Φb = BΔt + (AB + k_b B)Δt²/2, φd scalar.
        let a2 = mul3(&a, &a);
        let ab = mul3(&a, &b);
        let mut phi_a: Mat3 = [[0.0; 3]; 3];
        let mut phi_b: Mat3 = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                phi_a[i][j] = a[i][j] * dt + a2[i][j] * h + if i == j { 1.0 } else { 0.0 };
                phi_b[i][j] = b[i][j] * dt + (ab[i][j] + kb * b[i][j]) * h;
            }
        }
        let phi_d = 1.0 + kb * dt + kb * kb * h;

        // P blocks.
        let mut paa: Mat3 = [[0.0; 3]; 3];
        let mut pab: Mat3 = [[0.0; 3]; 3];
        let mut pbb: Mat3 = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                paa[i][j] = self.p[i][j];
                pab[i][j] = self.p[i][j + 3];
                pbb[i][j] = self.p[i + 3][j + 3];
            }
        }
        // M = Φa·Paa + Φb·Pabᵀ, N = Φa·Pab + Φb·Pbb.
        let mut m: Mat3 = mul3(&phi_a, &paa);
        let mut nn: Mat3 = mul3(&phi_a, &pab);
        let pb_t = mul3_bt(&phi_b, &pab); // Φb·Pabᵀ
        let pb_b = mul3(&phi_b, &pbb);
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] += pb_t[i][j];
                nn[i][j] += pb_b[i][j];
            }
        }
        // Paa' = M·Φaᵀ + N·Φbᵀ + Qd_aa; Pab' = N·φd; Pbb' = φd²·Pbb + Qd_bb.
        let t1 = mul3_bt(&m, &phi_a);
        let t2 = mul3_bt(&nn, &phi_b);
        let bbt = mul3_bt(&b, &b);
        let q_att = n.gyro_psd * dt;
        let q_extra = n.attitude_psd * dt;
        let q_bias = n.lambda * n.lambda * n.bias_psd * dt;
        for i in 0..3 {
            for j in i..3 {
                let mut v = 0.5 * (t1[i][j] + t2[i][j] + t1[j][i] + t2[j][i]) + q_att * bbt[i][j];
                if i == j {
                    v += q_extra;
                }
                self.p[i][j] = v;
                self.p[j][i] = v;
                let w = phi_d * phi_d * 0.5 * (pbb[i][j] + pbb[j][i]) + if i == j { q_bias } else { 0.0 };
                self.p[i + 3][j + 3] = w;
                self.p[j + 3][i + 3] = w;
            }
            for j in 0..3 {
                let v = nn[i][j] * phi_d;
                self.p[i][j + 3] = v;
                self.p[j + 3][i] = v;
            }
        }

        // State: Euler step.
        for i in 0..3 {
            self.x[i] += lin.euler_rates[i] * dt;
            self.x[i + 3] += kb * self.x[i + 3] * dt;
        }
        self.normalize_angles();
        self.condition(caps);
        lin
    }

    /// Scalar update of attitude axis `i` (0 roll, 1 pitch, 2 yaw) with measurement
    /// `z` (rad) of variance `r` (rad²). The innovation is wrapped to (−π, π].
    /// If `gate` is finite and ν²/S exceeds it, nothing is applied.
    ///
    /// `P ← P − P·eᵢ·eᵢᵀ·P / S` computed on the upper triangle and mirrored, so P
    /// stays exactly symmetric; with S = Pᵢᵢ + r > Pᵢᵢ this keeps P PD. (For H = eᵢ
    /// this equals the Joseph form with the optimal gain.)
    pub fn update_axis(&mut self, i: usize, z: f32, r: f32, gate: f32) -> ScalarUpdate {
        let nu = wrap_pi(z - self.x[i]);
        let s = self.p[i][i] + r;
        if !(nu.is_finite() && s.is_finite() && s > 0.0) {
            return ScalarUpdate { innovation: nu, variance: s, applied: false };
        }
        if nu * nu > gate * s {
            return ScalarUpdate { innovation: nu, variance: s, applied: false };
        }
        let col: [f32; 6] = core::array::from_fn(|k| self.p[k][i]);
        let inv_s = 1.0 / s;
        for k in 0..6 {
            self.x[k] += col[k] * inv_s * nu;
        }
        for j in 0..6 {
            for k in j..6 {
                let v = self.p[j][k] - col[j] * col[k] * inv_s;
                self.p[j][k] = v;
                self.p[k][j] = v;
            }
        }
        self.normalize_angles();
        for k in 0..6 {
            if self.p[k][k] < VAR_FLOOR {
                self.p[k][k] = VAR_FLOOR;
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
    /// is the same attitude as (φ+π, π−θ, ψ+π)).
    fn normalize_angles(&mut self) {
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
        const CAP_LOADING: f32 = 1e-5;
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
        if !self.p.iter().flatten().all(|v| v.is_finite()) || !self.x.iter().all(|v| v.is_finite()) {
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
