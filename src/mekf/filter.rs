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

/// One row of an aid's Jacobian w.r.t. the attitude error `δθ` (NED, rad). Its gyro-bias
/// part is zero for every aid here (the biases are seen only through the propagation), so
/// the products with P run over 3 columns, not 6.
pub type AttRow = [f32; 3];

/// Process noise densities.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Noise {
    /// Gyro white noise PSD, rad²/s.
    pub gyro_psd: f32,
    /// Bias random-walk PSD, (rad/s)²/s.
    pub bias_psd: f32,
    /// Rate-proportional attitude noise, 1/s (times `|ω|²`: scale factor, misalignment).
    pub rate_psd: f32,
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
    /// `Σ |ω|²·Δt` since the last covariance propagation, rad²/s.
    w2: f32,
    /// The latest `R(q)` (kept: every user of the step needs it).
    r: Mat3,
    /// The last fix's velocity noise as a state (see [`FixNoise`]).
    fix: FixNoise,
    repairs: u32,
}

/// The velocity noise of the newest GPS fix, carried as a state between updates.
///
/// Consecutive velocity differences share a fix: `ā_k = (v_k − v_{k−1})/Δt` carries
/// `(e_k − e_{k−1})/Δt`, so their noise is correlated (lag-1 ρ = −½) and a filter that
/// takes it as white weighs a long run of differences as if their noise did not
/// telescope (under-confident, NEES ≈ ½). Instead each update estimates the new fix's
/// noise e_k along with the state (the augmented update of `[δx, e_{k−1}, e_k]`), and
/// the next update starts from its posterior: mean, covariance, and cross-covariance
/// with the error state (propagated like P).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FixNoise {
    /// Posterior mean of the last fix's velocity noise, m/s NED.
    mean: Vec3,
    /// Its covariance, (m/s)².
    cov: Mat3,
    /// Cross-covariance `E[δx·eᵀ]` (6×3).
    cross: [[f32; 3]; 6],
    /// Whether the state holds a fix (else the next update treats the previous fix's
    /// noise as fresh: zero mean, `prev_var`).
    valid: bool,
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
        Mekf {
            q,
            bias: [0.0; 3],
            p,
            m: [[0.0; 3]; 3],
            t: 0.0,
            w2: 0.0,
            r: quat::to_dcm(&q),
            fix: FixNoise::default(),
            repairs: 0,
        }
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
        let w = [gyro[0] - self.bias[0], gyro[1] - self.bias[1], gyro[2] - self.bias[2]];
        let phi = [w[0] * dt, w[1] * dt, w[2] * dt];
        self.w2 += (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]) * dt;
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
        if self.fix.valid {
            // C_θ ← C_θ − M·C_b (the transition acts on the error-state side only).
            let c = &mut self.fix.cross;
            for i in 0..3 {
                for j in 0..3 {
                    let d: f32 = (0..3).map(|k| m[i][k] * c[3 + k][j]).sum();
                    c[i][j] -= d;
                }
            }
        }
        let qa = noise.gyro_psd * self.t + noise.rate_psd * self.w2;
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
        self.w2 = 0.0;
        self.condition();
    }

    /// Fuses an m-dimensional measurement with residual `y = z − h(x̂)`, Jacobian `h`
    /// (w.r.t. `δθ`; zero w.r.t. `δb`) and diagonal noise `r`, unless its NIS exceeds `gate`.
    /// P must be current (call [`Mekf::propagate`] first).
    pub fn fuse<const M: usize>(
        &mut self,
        y: [f32; M],
        h: &[AttRow; M],
        r: [f32; M],
        gate: f32,
    ) -> Fused {
        // PHᵀ (6×M) and S = H P Hᵀ + R, over H's attitude columns only.
        let mut pht = [[0.0f32; M]; 6];
        for i in 0..6 {
            for k in 0..M {
                pht[i][k] = (0..3).map(|j| self.p[i][j] * h[k][j]).sum();
            }
        }
        let mut s = [[0.0f32; M]; M];
        for a in 0..M {
            for b in 0..M {
                s[a][b] = (0..3).map(|j| h[a][j] * pht[j][b]).sum();
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
        if self.fix.valid {
            // The carried fix noise is correlated with δx: C ← C − K·(H·C).
            let c = self.fix.cross;
            let mut hc = [[0.0f32; 3]; M];
            for a in 0..M {
                for j in 0..3 {
                    hc[a][j] = (0..3).map(|l| h[a][l] * c[l][j]).sum();
                }
            }
            for i in 0..6 {
                for j in 0..3 {
                    self.fix.cross[i][j] -= (0..M).map(|a| k[i][a] * hc[a][j]).sum::<f32>();
                }
            }
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
        self.fix.cross[2] = [0.0; 3];
    }

    /// Forgets the carried fix noise (a re-seed, an alignment, a gated update).
    pub fn forget_fix_noise(&mut self) {
        self.fix = FixNoise::default();
    }

    /// Fuses the GPS acceleration with the fix noise as states: `y = H·δx + (e_k −
    /// e_{k−1})/Δt + w`, w white with variance `r`. `prev_var`/`new_var`: the previous and
    /// the new fix's velocity variance per axis, (m/s)². On success e_k's posterior is
    /// kept for the next update.
    pub fn fuse_with_fix_noise(
        &mut self,
        y: [f32; 3],
        h: &[AttRow; 3],
        r: [f32; 3],
        prev_var: Vec3,
        new_var: Vec3,
        dt: f32,
        gate: f32,
    ) -> Fused {
        const N: usize = 12;
        let inv_dt = 1.0 / dt;
        // Augmented prior [δx, e_{k−1}, e_k] and its covariance.
        let f = if self.fix.valid {
            self.fix
        } else {
            let mut f = FixNoise::default();
            for i in 0..3 {
                f.cov[i][i] = prev_var[i];
            }
            f
        };
        // The augmented prior is read in place (no 12×12 copy: it was most of the IMU
        // interrupt's static stack bound): e_k starts uncorrelated, of variance new_var.
        let p = &self.p;
        let prior = |i: usize, j: usize| -> f32 {
            match (i, j) {
                (0..6, 0..6) => p[i][j],
                (0..6, 6..9) => f.cross[i][j - 6],
                (6..9, 0..6) => f.cross[j][i - 6],
                (6..9, 6..9) => f.cov[i - 6][j - 6],
                (9..N, 9..N) if i == j => new_var[i - 9],
                _ => 0.0,
            }
        };
        // The augmented H is [h_k, 0 at δb, −1/Δt at e_{k−1,k}, +1/Δt at e_{k,k}] per row:
        // its products are taken over those 5 non-zero entries only (the same terms in the
        // same order as the dense 12-wide product, so the same result).
        let mut nu = y;
        for k in 0..3 {
            nu[k] += f.mean[k] * inv_dt; // the prediction of y is −ê_{k−1}/Δt
        }
        let aug = |i: usize, hk: &AttRow, k: usize| {
            let v: f32 = (0..3).map(|j| prior(i, j) * hk[j]).sum();
            v + prior(i, 6 + k) * -inv_dt + prior(i, 9 + k) * inv_dt
        };
        let mut pht = [[0.0f32; 3]; N];
        for i in 0..N {
            for k in 0..3 {
                pht[i][k] = aug(i, &h[k], k);
            }
        }
        let mut s = [[0.0f32; 3]; 3];
        for x in 0..3 {
            for z in 0..3 {
                let v: f32 = (0..3).map(|j| h[x][j] * pht[j][z]).sum();
                s[x][z] = v + -inv_dt * pht[6 + x][z] + inv_dt * pht[9 + x][z];
            }
            s[x][x] += r[x];
        }
        let s_diag = [s[0][0], s[1][1], s[2][2]];
        let Some(s_inv) = spd_inverse(&s) else {
            self.forget_fix_noise();
            return Fused { nis: f32::INFINITY, applied: false, s_diag };
        };
        let siy: [f32; 3] = core::array::from_fn(|x| (0..3).map(|z| s_inv[x][z] * nu[z]).sum());
        let nis: f32 = (0..3).map(|x| nu[x] * siy[x]).sum();
        if !(nis <= gate) {
            self.forget_fix_noise();
            return Fused { nis, applied: false, s_diag };
        }
        // Only the blocks that are kept: δx (0..6) and e_k (9..12); e_{k−1} is dropped.
        let keep = |i: usize| if i < 6 { i } else { i + 3 };
        let mut k = [[0.0f32; 3]; N];
        for a_ in 0..9 {
            let i = keep(a_);
            for z in 0..3 {
                k[i][z] = (0..3).map(|x| pht[i][x] * s_inv[x][z]).sum();
            }
        }
        let mut dx = [0.0f32; N];
        for a_ in 0..9 {
            let i = keep(a_);
            dx[i] = (0..3).map(|x| pht[i][x] * siy[x]).sum();
        }
        // The posterior, written in place: each entry needs only its own prior. The kept
        // e_k is the new fix noise (its cross-covariance with δx and its covariance).
        let post = |i: usize, j: usize, prior: f32| {
            prior - (0..3).map(|x| k[i][x] * pht[j][x]).sum::<f32>()
        };
        let fix_cov: [[f32; 3]; 3] =
            core::array::from_fn(|a_| core::array::from_fn(|b_| {
                let (i, j) = (9 + a_.min(b_), 9 + a_.max(b_));
                post(i, j, if i == j { new_var[i - 9] } else { 0.0 })
            }));
        for i in 0..6 {
            for j in 0..3 {
                self.fix.cross[i][j] = post(i, 9 + j, 0.0);
            }
            for j in i..6 {
                let v = post(i, j, self.p[i][j]);
                self.p[i][j] = v;
                self.p[j][i] = v;
            }
        }
        self.fix.cov = fix_cov;
        self.fix.mean.copy_from_slice(&dx[9..12]);
        self.fix.valid = true;
        self.condition();
        let mut d6 = [0.0f32; 6];
        d6.copy_from_slice(&dx[..6]);
        self.inject(d6);
        Fused { nis, applied: true, s_diag }
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
        self.w2 = 0.0;
        self.forget_fix_noise();
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
