//! The six-state multiplicative EKF: a unit quaternion (body → NED) and the gyro
//! biases as the nominal state, and a six-element error state
//! `δx = [δθ (rad, NED), δb (rad/s, body)]` with covariance P.
//!
//! The attitude error is taken in the navigation frame, `R = exp([δθ×])·R̂`. Its
//! dynamics are then `δθ̇ = −R̂·δb − R̂·n_g`: the transition over any number of IMU
//! samples is `[[I, −M], [0, I]]` with `M = Σ R̂ₖ·Δtₖ`, exactly, and the gyro noise
//! adds `σ²·T·I` whatever the attitude. So P can be propagated every N samples (or
//! at each update) from one 3×3 sum, at no loss, and no Euler singularity exists
//! anywhere: the filter is valid at every attitude.
//!
//! Invariants, kept behind private fields: `q` has unit norm, P is symmetric with a
//! positive diagonal (repairs are counted).

use super::quat::{self, Quat};
use crate::math::{Mat3, Vec3};

/// Error-state covariance, `[δθ, δb]`.
pub type Mat6 = [[f32; 6]; 6];

/// Process noise densities.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Noise {
    /// Gyro white noise PSD, rad²/s.
    pub gyro_psd: f32,
    /// Bias random-walk PSD, (rad/s)²/s.
    pub bias_psd: f32,
}

/// What a vector update did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Fused {
    /// Normalised innovation squared `yᵀS⁻¹y` (χ² with m degrees of freedom).
    pub nis: f32,
    /// Whether the correction was applied (false: gated, or S not positive definite).
    pub applied: bool,
    /// The innovation variances, diagonal of S (the first M entries).
    pub s_diag: [f32; 3],
}

/// The filter: nominal state, covariance and the pending propagation sum.
#[derive(Debug, Clone, Copy)]
pub struct Mekf {
    q: Quat,
    bias: Vec3,
    p: Mat6,
    /// `Σ R̂·Δt` since the last covariance propagation.
    m: Mat3,
    /// `Σ Δt` since the last covariance propagation, s.
    t: f32,
    /// The latest `R(q)` (kept: every user of the step needs it).
    r: Mat3,
    repairs: u32,
}

/// Largest variance kept on the attitude error (rad²): beyond 1 rad nothing is linear.
const MAX_ATT_VAR: f32 = 1.0;
/// Smallest variance kept on any error state (f32 headroom for the update).
const MIN_VAR: f32 = 1e-12;

impl Mekf {
    /// A filter at attitude `q` with diagonal covariance `var` (rad², (rad/s)²).
    pub fn new(q: Quat, var: [f32; 6]) -> Self {
        let mut p = [[0.0; 6]; 6];
        for i in 0..6 {
            p[i][i] = var[i];
        }
        let q = quat::normalize(&q);
        Mekf { q, bias: [0.0; 3], p, m: [[0.0; 3]; 3], t: 0.0, r: quat::to_dcm(&q), repairs: 0 }
    }

    /// The attitude, body → NED.
    pub fn quaternion(&self) -> Quat {
        self.q
    }

    /// `R(q)`, body → NED, as of the latest step.
    pub fn dcm(&self) -> &Mat3 {
        &self.r
    }

    /// Gyro bias estimate, rad/s, body.
    pub fn bias(&self) -> Vec3 {
        self.bias
    }

    /// The error covariance as of the last propagation.
    pub fn covariance(&self) -> &Mat6 {
        &self.p
    }

    /// Covariance entries repaired so far (non-finite, or a non-positive diagonal).
    pub fn repairs(&self) -> u32 {
        self.repairs
    }

    /// One IMU step: rotates the nominal attitude by the bias-corrected gyro over `dt`
    /// and adds this step to the pending propagation sum. Returns the rotation vector
    /// of the step (rad, body), for the caller's mid-step specific force.
    #[inline]
    pub fn step(&mut self, gyro: Vec3, dt: f32) -> Vec3 {
        let phi = [
            (gyro[0] - self.bias[0]) * dt,
            (gyro[1] - self.bias[1]) * dt,
            (gyro[2] - self.bias[2]) * dt,
        ];
        self.q = quat::renormalize(&quat::mul(&self.q, &quat::from_rotation_vector(phi)));
        self.r = quat::to_dcm(&self.q);
        for i in 0..3 {
            for j in 0..3 {
                self.m[i][j] += self.r[i][j] * dt;
            }
        }
        self.t += dt;
        phi
    }

    /// Applies the pending transition `[[I, −M], [0, I]]` and process noise to P.
    pub fn propagate(&mut self, noise: &Noise) {
        if self.t <= 0.0 {
            return;
        }
        let m = self.m;
        let p = &mut self.p;
        // B' = B − M·C,  A' = A − M·Bᵀ − B'·Mᵀ (= A − M Bᵀ − B Mᵀ + M C Mᵀ).
        let mut mc = [[0.0f32; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                mc[i][j] = (0..3).map(|k| m[i][k] * p[3 + k][3 + j]).sum();
            }
        }
        let mut mbt = [[0.0f32; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                mbt[i][j] = (0..3).map(|k| m[i][k] * p[j][3 + k]).sum();
            }
        }
        for i in 0..3 {
            for j in 0..3 {
                p[i][3 + j] -= mc[i][j];
            }
        }
        let mut a = [[0.0f32; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                let bm: f32 = (0..3).map(|k| p[i][3 + k] * m[j][k]).sum();
                a[i][j] = p[i][j] - mbt[i][j] - bm;
            }
        }
        let qa = noise.gyro_psd * self.t;
        let qb = noise.bias_psd * self.t;
        for i in 0..3 {
            for j in 0..3 {
                p[i][j] = a[i][j];
                p[3 + j][i] = p[i][3 + j];
            }
            p[i][i] += qa;
            p[3 + i][3 + i] += qb;
        }
        self.m = [[0.0; 3]; 3];
        self.t = 0.0;
        self.condition();
    }

    /// Fuses an m-dimensional measurement with residual `y = z − h(x̂)`, Jacobian `h`
    /// (w.r.t. `[δθ, δb]`) and diagonal noise `r`, unless its NIS exceeds `gate`.
    /// P must be current (call [`Mekf::propagate`] first).
    pub fn fuse<const M: usize>(
        &mut self,
        y: [f32; M],
        h: &[[f32; 6]; M],
        r: [f32; M],
        gate: f32,
    ) -> Fused {
        // PHᵀ (6×M) and S = H P Hᵀ + R.
        let mut pht = [[0.0f32; M]; 6];
        for i in 0..6 {
            for k in 0..M {
                pht[i][k] = (0..6).map(|j| self.p[i][j] * h[k][j]).sum();
            }
        }
        let mut s = [[0.0f32; M]; M];
        for a in 0..M {
            for b in 0..M {
                s[a][b] = (0..6).map(|j| h[a][j] * pht[j][b]).sum();
            }
            s[a][a] += r[a];
        }
        let mut s_diag = [0.0f32; 3];
        for a in 0..M.min(3) {
            s_diag[a] = s[a][a];
        }
        let Some(s_inv) = spd_inverse(&s) else {
            return Fused { nis: f32::INFINITY, applied: false, s_diag };
        };
        let mut siy = [0.0f32; M];
        for a in 0..M {
            siy[a] = (0..M).map(|b| s_inv[a][b] * y[b]).sum();
        }
        let nis: f32 = (0..M).map(|a| y[a] * siy[a]).sum();
        if !(nis <= gate) {
            return Fused { nis, applied: false, s_diag };
        }
        // K = PHᵀ S⁻¹;  δx = K y = PHᵀ (S⁻¹ y);  P ← P − K (PHᵀ)ᵀ.
        let mut k = [[0.0f32; M]; 6];
        for i in 0..6 {
            for b in 0..M {
                k[i][b] = (0..M).map(|a| pht[i][a] * s_inv[a][b]).sum();
            }
        }
        let mut dx = [0.0f32; 6];
        for i in 0..6 {
            dx[i] = (0..M).map(|a| pht[i][a] * siy[a]).sum();
        }
        for i in 0..6 {
            for j in i..6 {
                let d: f32 = (0..M).map(|a| k[i][a] * pht[j][a]).sum();
                let v = self.p[i][j] - d;
                self.p[i][j] = v;
                self.p[j][i] = v;
            }
        }
        self.condition();
        self.inject(dx);
        Fused { nis, applied: true, s_diag }
    }

    /// Moves the estimated error into the nominal state (the error state is reset to 0).
    fn inject(&mut self, dx: [f32; 6]) {
        let dq = quat::from_rotation_vector([dx[0], dx[1], dx[2]]);
        self.q = quat::normalize(&quat::mul(&dq, &self.q));
        self.r = quat::to_dcm(&self.q);
        for i in 0..3 {
            self.bias[i] += dx[3 + i];
        }
    }

    /// Rotates the attitude by `angle` (rad) about NED down and sets the heading's
    /// variance to `var`, its correlations to zero (a heading (re)alignment).
    pub fn set_heading(&mut self, angle: f32, var: f32) {
        let (s, c) = crate::math::sincos(0.5 * angle);
        self.q = quat::normalize(&quat::mul(&[c, 0.0, 0.0, s], &self.q));
        self.r = quat::to_dcm(&self.q);
        for j in 0..6 {
            self.p[2][j] = 0.0;
            self.p[j][2] = 0.0;
        }
        self.p[2][2] = var;
    }

    /// Replaces the attitude (an alignment) with the attitude variances `att_var`
    /// (rad², NED axes); the bias estimate and its covariance are kept.
    pub fn reset_attitude(&mut self, q: Quat, att_var: Vec3) {
        self.q = quat::normalize(&q);
        self.r = quat::to_dcm(&self.q);
        for i in 0..3 {
            for j in 0..6 {
                self.p[i][j] = 0.0;
                self.p[j][i] = 0.0;
            }
            self.p[i][i] = att_var[i];
        }
        self.m = [[0.0; 3]; 3];
        self.t = 0.0;
    }

    /// Keeps P symmetric with a finite, positive, bounded diagonal; counts repairs.
    fn condition(&mut self) {
        for i in 0..6 {
            let cap = if i < 3 { MAX_ATT_VAR } else { f32::MAX };
            let d = self.p[i][i];
            if !(d >= MIN_VAR && d <= cap) {
                self.repairs = self.repairs.wrapping_add(1);
                let v = if d.is_finite() { d.clamp(MIN_VAR, cap) } else { cap.min(1.0) };
                // Rescale the row and column so the correlations stay ≤ 1.
                let k = if d > 0.0 && d.is_finite() { crate::math::sqrt(v / d) } else { 0.0 };
                for j in 0..6 {
                    if j != i {
                        self.p[i][j] *= k;
                        self.p[j][i] *= k;
                    }
                }
                self.p[i][i] = v;
            }
        }
        for i in 0..6 {
            for j in (i + 1)..6 {
                let v = self.p[i][j];
                if !v.is_finite() {
                    self.repairs = self.repairs.wrapping_add(1);
                    self.p[i][j] = 0.0;
                    self.p[j][i] = 0.0;
                }
            }
        }
    }
}

/// The inverse of a symmetric positive definite M×M matrix (M ≤ 3) by Cholesky,
/// or `None` when it is not positive definite.
fn spd_inverse<const M: usize>(s: &[[f32; M]; M]) -> Option<[[f32; M]; M]> {
    // L Lᵀ = S.
    let mut l = [[0.0f32; M]; M];
    for i in 0..M {
        for j in 0..=i {
            let mut v = s[i][j];
            for k in 0..j {
                v -= l[i][k] * l[j][k];
            }
            if i == j {
                if !(v > 0.0) {
                    return None;
                }
                l[i][i] = crate::math::sqrt(v);
            } else {
                l[i][j] = v / l[j][j];
            }
        }
    }
    // L⁻¹ (lower triangular), then S⁻¹ = L⁻ᵀ L⁻¹.
    let mut li = [[0.0f32; M]; M];
    for i in 0..M {
        li[i][i] = 1.0 / l[i][i];
        for j in 0..i {
            let mut v = 0.0;
            for k in j..i {
                v -= l[i][k] * li[k][j];
            }
            li[i][j] = v * li[i][i];
        }
    }
    let mut inv = [[0.0f32; M]; M];
    for i in 0..M {
        for j in 0..M {
            inv[i][j] = (i.max(j)..M).map(|k| li[k][i] * li[k][j]).sum();
        }
    }
    Some(inv)
}

/// `−[v×]`, the Jacobian of `v ↦ R·v` w.r.t. the NED attitude error, as its 3×3 block:
/// `exp([δθ×])·v ≈ v + δθ × v = v − [v×]·δθ`.
pub fn minus_skew(v: Vec3) -> Mat3 {
    [[0.0, v[2], -v[1]], [-v[2], 0.0, v[0]], [v[1], -v[0], 0.0]]
}
