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

use super::latency_consider::LatencyConsider;
use super::quat::{self, Quat};
use crate::math::{Mat3, Vec3};

/// Error-state covariance, `[δθ, δb]`.
pub type Mat6 = [[f32; 6]; 6];

/// One row of an aid's Jacobian w.r.t. the attitude error `δθ` (NED, rad). Its gyro-bias
/// part is zero for every aid here (the biases are seen only through the propagation), so
/// the products with P run over 3 columns, not 6.
pub type AttRow = [f32; 3];

/// The largest mean squared body rate [`Mekf::widen_biases`] scales by, (rad/s)² (a 20 °/s
/// turn): the heading a latency error leaves grows with the turn rate, but in rolls and
/// loops the rate is the roll's, and uncapped the widening cost the real F3A flights 15–28 %
/// of tilt agreement with their autopilot (CHANGELOG.md).
pub const WIDEN_MAX_RATE2: f32 = 0.12;

/// Process noise densities.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Noise {
    /// Gyro white noise PSD, rad²/s.
    pub gyro_psd: f32,
    /// Bias random-walk PSD, (rad/s)²/s.
    pub bias_psd: f32,
    /// Rate-proportional attitude noise, 1/s (times `|ω|²`: scale factor, misalignment).
    pub rate_psd: f32,
    /// Gyro scale-factor variance, dimensionless²: each propagation block adds
    /// `σ²·Δθᵢ²` about body axis i, Δθ the block's bias-corrected rotation (coherent:
    /// the error of a 90° roll is σ·90°, not a random walk).
    pub scale_var: f32,
    /// The same about body x and y: `scale_var`, or 0 where the scale states hold them.
    #[cfg(feature = "gyro-scale-states")]
    pub scale_var_xy: f32,
    /// Gyro axis-misalignment variance per cross-axis term, rad²: a block adds
    /// `σ²·(Δθⱼ² + Δθₖ²)` about body axis i.
    pub misalignment_var: f32,
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
    /// The attitude correction applied, rad NED (zero when not applied).
    pub dtheta: Vec3,
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
    /// `Σ (ω − b)·Δt` over the block, rad, body (held after the propagation until
    /// [`Mekf::settle_coherent`] clears it).
    dth: Vec3,
    /// The bias-corrected rotation about each body axis over the last ~[`SCALE_MEMORY_S`],
    /// rad (decayed per block): a scale factor's error is coherent over it.
    turned: Vec3,
    /// The last propagated block's length, s, until [`Mekf::settle_coherent`] (then 0);
    /// `dth` holds its rotation until then.
    last_t: f32,
    /// [`Mekf::widen_biases`]' factor for the next propagation, s² (0: none).
    bias_widen: f32,
    /// The latest `R(q)` (kept: every user of the step needs it).
    r: Mat3,
    /// The last fix's velocity noise as a state (see [`FixNoise`]).
    fix: FixNoise,
    /// The untracked receiver latency as a consider parameter.
    lat: LatencyConsider,
    repairs: u32,
    /// Gyro scale factors as states, when on.
    #[cfg(feature = "gyro-scale-states")]
    scale: Option<super::scale::Scale>,
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

/// The two axes other than each: the columns of a zero-diagonal row.
const OTHER: [[usize; 2]; 3] = [[1, 2], [0, 2], [0, 1]];

/// How long a scale factor's error stays coherent, s: a block's rotation adds to the
/// variance with the rotation of the blocks before it decayed over this. A constant scale
/// error turns the attitude by `s·Θ`, Θ the rotation since the GPS last corrected it, not
/// by a random walk of the blocks' rotations: block by block a 360° roll at 300 °/s was
/// covered ~12× too little (`aerobatics_realistic`: the scale factor alone made its 4σ tail
/// 0.98 % against 0.15 % without it). 0.5 s, about two 5 Hz GPS updates, chosen over the
/// robustness suite and the real aerobatic logs (docs/design.md, "Gyro scale factor,
/// coherent across blocks"): 1 s took the over-confident runs further down (106 → 61 of
/// 9,600, 69 at 0.5 s) but took the F3A logs' agreement with ArduPilot's EKF3 1.0–1.4×;
/// 0.3 s left 91.
const SCALE_MEMORY_S: f32 = 0.5;
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
            dth: [0.0; 3],
            turned: [0.0; 3],
            last_t: 0.0,
            bias_widen: 0.0,
            r: quat::to_dcm(&q),
            fix: FixNoise::default(),
            lat: LatencyConsider::default(),
            repairs: 0,
            #[cfg(feature = "gyro-scale-states")]
            scale: None,
        }
    }

    /// Carries the gyro scale factors about body x and y as states, prior σ `sigma`
    /// (dimensionless) each ([`super::scale`]).
    #[cfg(feature = "gyro-scale-states")]
    pub fn with_scale_states(mut self, sigma: f32) -> Self {
        self.scale = Some(super::scale::Scale::new(sigma));
        self
    }

    /// The gyro scale factors estimated about body x and y, when carried.
    #[cfg(feature = "gyro-scale-states")]
    pub fn scale(&self) -> Option<[f32; super::scale::N]> {
        self.scale.map(|s| s.estimate())
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
        #[allow(unused_mut)]
        let mut w = [gyro[0] - self.bias[0], gyro[1] - self.bias[1], gyro[2] - self.bias[2]];
        #[cfg(feature = "gyro-scale-states")]
        if let Some(sc) = &self.scale {
            sc.compensate(&mut w);
        }
        let phi = [w[0] * dt, w[1] * dt, w[2] * dt];
        self.w2 += (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]) * dt;
        for i in 0..3 {
            self.dth[i] += phi[i];
        }
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
            transition_fix_cross(&mut self.fix.cross, &m);
        }
        self.lat.transition(&m);
        let qa = noise.gyro_psd * self.t + noise.rate_psd * self.w2;
        let w2 = crate::math::min(self.w2 / self.t, WIDEN_MAX_RATE2);
        let qb = noise.bias_psd * self.t + self.bias_widen * w2;
        self.bias_widen = 0.0;
        for i in 0..3 {
            a[i][i] += qa;
        }
        if noise.scale_var > 0.0 || noise.misalignment_var > 0.0 {
            add_coherent_noise(noise, &self.dth.map(|v| v * v), &self.r, |i, k, v| a[i][k] += v);
        }
        for i in 0..3 {
            for j in 0..3 {
                p[i][j] = a[i][j];
                p[3 + j][i] = p[i][3 + j];
            }
            p[3 + i][3 + i] += qb;
        }
        #[cfg(feature = "gyro-scale-states")]
        if let Some(sc) = &mut self.scale {
            sc.propagate(&m, self.t, &self.dth, &mut self.p, &mut self.fix.cross);
        }
        // The rest of the block's coherent share, and clearing its rotation, wait for the
        // next sample (`settle_coherent`).
        self.last_t = self.t;
        self.clear_block();
        self.condition();
    }

    /// After a propagation, before the next step: adds to P what the propagated block's
    /// rotation adds, coherently, to the rotation turned before it (gyro scale factor and
    /// misalignment, [`coherent_rotation2`]), and clears the block's rotation. On the
    /// GPS-update sample it would not fit the M4F budget (~50 instructions); the next
    /// update sees it.
    #[inline(always)]
    pub fn settle_coherent(&mut self, noise: &Noise) {
        if self.last_t > 0.0 {
            self.settle_block(noise);
        }
    }

    /// Out of line and marked cold: one sample in `covariance_decimation` runs it, and the
    /// other samples' fall-through is what the mean predict budget counts.
    #[cold]
    #[inline(never)]
    fn settle_block(&mut self, noise: &Noise) {
        let t = self.last_t;
        self.last_t = 0.0;
        if noise.scale_var > 0.0 || noise.misalignment_var > 0.0 {
            // With the scale states on, `Noise::scale_var_xy` is 0: the states carry the
            // x and y scale errors' coherence themselves.
            let extra = coherent_rotation2(&mut self.turned, &self.dth, t);
            let p = &mut self.p;
            add_coherent_noise(noise, &extra, &self.r, |i, k, v| p[i][k] += v);
        }
        self.dth = [-0.0; 3];
    }

    /// Empties the pending propagation sums. They restart from −0.0, the additive identity
    /// of IEEE floats (`−0.0 + x` is `x` for every x; `+0.0 + x` is not for x = −0.0), so
    /// the sums are those from +0.0 but for the sign of an exact zero, and their 11 words
    /// are cleared by stores: +0.0 made them a `memclr` call, ~40 more M4F instructions on
    /// every propagation (the GPS-update sample's included).
    #[inline(always)]
    fn clear_block(&mut self) {
        self.m = [[-0.0; 3]; 3];
        self.t = -0.0;
        self.w2 = -0.0;
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
            return Fused { nis: f32::INFINITY, s_diag, ..Fused::default() };
        };
        let mut siy = [0.0f32; M];
        for a in 0..M {
            siy[a] = (0..M).map(|b| s_inv[a][b] * y[b]).sum();
        }
        let nis: f32 = (0..M).map(|a| y[a] * siy[a]).sum();
        if !(nis <= gate) {
            return Fused { nis, s_diag, ..Fused::default() };
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
        #[cfg(feature = "gyro-scale-states")]
        let ks = self.scale.as_mut().filter(|sc| sc.is_awake()).map(|sc| sc.fuse(h, &k, &s_inv, &siy));
        if self.fix.valid {
            // The carried fix noise is correlated with δx: C ← C − K·(H·C).
            let c = self.fix.cross;
            let mut hc = [[0.0f32; 3]; M];
            for a in 0..M {
                for j in 0..3 {
                    hc[a][j] = (0..3).map(|l| h[a][l] * c[l][j]).sum();
                }
            }
            #[cfg(feature = "gyro-scale-states")]
            if let (Some(sc), Some(ks)) = (&mut self.scale, ks) {
                sc.fix_noise_seen(&ks, &hc);
            }
            for i in 0..6 {
                for j in 0..3 {
                    self.fix.cross[i][j] -= (0..M).map(|a| k[i][a] * hc[a][j]).sum::<f32>();
                }
            }
            self.lat.fused(&k, h, &s_inv, Some(&hc));
        } else {
            self.lat.fused(&k, h, &s_inv, None);
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
        Fused { nis, applied: true, s_diag, dtheta: [dx[0], dx[1], dx[2]] }
    }

    /// At the next propagation, adds `k·⟨|ω|²⟩` ((rad/s)²; `k` in s², ⟨|ω|²⟩ the block's mean
    /// squared body rate, at most [`WIDEN_MAX_RATE2`]) to each gyro bias' variance: they took
    /// in an error P did not hold. Folded into the propagation's bias noise, where the
    /// block's rate is already summed (cheaper on the M4F's GPS-update sample than a pass of
    /// its own).
    pub fn widen_biases(&mut self, k: f32) {
        self.bias_widen = k;
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
        self.lat.zero(2);
        #[cfg(feature = "gyro-scale-states")]
        if let Some(sc) = &mut self.scale {
            sc.pxs[2] = [0.0; super::scale::N];
        }
    }

    /// Sets the gyro biases to zero with variance `var` ((rad/s)²) each, their
    /// correlations to zero: back to the turn-on prior (an implausible estimate).
    pub fn reset_bias(&mut self, var: f32) {
        self.bias = [0.0; 3];
        for i in 3..6 {
            for j in 0..6 {
                self.p[i][j] = 0.0;
                self.p[j][i] = 0.0;
            }
            self.p[i][i] = var;
            self.fix.cross[i] = [0.0; 3];
            self.lat.zero(i);
            #[cfg(feature = "gyro-scale-states")]
            if let Some(sc) = &mut self.scale {
                sc.pxs[i] = [0.0; super::scale::N];
            }
        }
    }

    /// Forgets the carried fix noise (a re-seed, an alignment, a gated update).
    pub fn forget_fix_noise(&mut self) {
        self.fix = FixNoise::default();
        self.lat.forget_fix();
        #[cfg(feature = "gyro-scale-states")]
        if let Some(sc) = &mut self.scale {
            sc.se = [[0.0; 3]; super::scale::N];
        }
    }

    /// Sets the untracked latency's variance σ_c² (s²) and the jerk of the next
    /// fix-noise update (m/s³ NED; zero: none) ([`LatencyConsider`]).
    pub fn consider_latency(&mut self, var: f32, jerk: Vec3) {
        self.lat.set(var, jerk);
    }

    /// Fuses the GPS acceleration with the fix noise as states: `y = H·δx + (e_k −
    /// e_{k−1})/Δt + w`, w white with variance `r`. `h` must have a zero diagonal (it is
    /// `−[f̄×]`, with the heading column zeroed where the heading is not fused): its
    /// diagonal is never read. `prev_var`/`new_var`: the previous and
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
        let inv_dt = 1.0 / dt;
        // The augmented state is [δx (6), e_{k−1} (3), e_k (3)]; its H row k is
        // [h_k, 0, −1/Δt at e_{k−1,k}, +1/Δt at e_{k,k}]. e_k is fresh: zero mean,
        // diagonal variance `new_var`, uncorrelated with the rest. The products below are
        // written per block, so no 12-wide zero is multiplied (M4F cost of the update).
        // The prior is read in place (a copy of its 31 floats was ~40 M4F instructions);
        // the posterior overwrites it only after its last read.
        if !self.fix.valid {
            self.fix = FixNoise::default();
            for i in 0..3 {
                self.fix.cov[i][i] = prev_var[i];
            }
        }
        let (mut px, d, mut s) = self.fix_noise_innovation_cov(h, r, new_var, inv_dt);
        let g = self.lat.augment(h, inv_dt, self.fix.valid, &mut px, &mut s);
        let f = &self.fix;
        let s_diag = [s[0][0], s[1][1], s[2][2]];
        let Some(s_inv) = spd_inverse(&s) else {
            self.forget_fix_noise();
            return Fused { nis: f32::INFINITY, s_diag, ..Fused::default() };
        };
        // The prediction of y is −ê_{k−1}/Δt.
        let nu: Vec3 = core::array::from_fn(|k| y[k] + f.mean[k] * inv_dt);
        let siy: Vec3 = core::array::from_fn(|x| (0..3).map(|z| s_inv[x][z] * nu[z]).sum());
        let nis: f32 = (0..3).map(|x| nu[x] * siy[x]).sum();
        if !(nis <= gate) {
            self.forget_fix_noise();
            return Fused { nis, s_diag, ..Fused::default() };
        }
        // Gains of the kept blocks, δx and e_k (e_{k−1} is dropped after the update).
        let mut kx = [[0.0f32; 3]; 6];
        for i in 0..6 {
            for z in 0..3 {
                kx[i][z] = (0..3).map(|x| px[i][x] * s_inv[x][z]).sum();
            }
        }
        let mut dx = [0.0f32; 6];
        for i in 0..6 {
            dx[i] = (0..3).map(|x| px[i][x] * siy[x]).sum();
        }
        #[cfg(feature = "gyro-scale-states")]
        if let Some(sc) = self.scale.as_mut().filter(|sc| sc.is_awake()) {
            sc.fuse_with_fix_noise(h, &kx, &s_inv, &siy, inv_dt, &d);
        }
        self.fix_noise_posterior(&kx, &px, &d, &s_inv, &siy, &new_var);
        if let Some(g) = g {
            self.lat.posterior(&g, &kx, &d, &s_inv, &self.p);
        }
        self.fix.valid = true;
        self.condition();
        self.inject(dx);
        Fused { nis, applied: true, s_diag, dtheta: [dx[0], dx[1], dx[2]] }
    }

    /// The augmented filter's PHᵀ per block (δx rows, e_{k−1} rows), e_k's diagonal PHᵀ
    /// `d` and `S = H·PHᵀ + R`, for [`Self::fuse_with_fix_noise`].
    #[inline(always)]
    fn fix_noise_innovation_cov(
        &self,
        h: &[AttRow; 3],
        r: [f32; 3],
        new_var: Vec3,
        inv_dt: f32,
    ) -> ([[f32; 3]; 6], Vec3, Mat3) {
        let f = &self.fix;
        // PHᵀ per block: δx rows, e_{k−1} rows; the e_k rows are diagonal, `d`.
        // H's diagonal is zero (`−[f̄×]`, a zeroed heading column keeps it so): each
        // product below runs over the two other columns only, the same sums as the full
        // ones without their `± 0` term (~70 M4F instructions on the GPS-update sample).
        let mut px = [[0.0f32; 3]; 6];
        for (i, row) in px.iter_mut().enumerate() {
            for k in 0..3 {
                let [a, b] = OTHER[k];
                let v = self.p[i][a] * h[k][a] + self.p[i][b] * h[k][b];
                row[k] = v - inv_dt * f.cross[i][k];
            }
        }
        let mut pe = [[0.0f32; 3]; 3];
        for (c, row) in pe.iter_mut().enumerate() {
            for k in 0..3 {
                let [a, b] = OTHER[k];
                let v = f.cross[a][c] * h[k][a] + f.cross[b][c] * h[k][b];
                row[k] = v - inv_dt * f.cov[c][k];
            }
        }
        let d: Vec3 = core::array::from_fn(|a| new_var[a] * inv_dt);
        // S = H·PHᵀ + R.
        let mut s = [[0.0f32; 3]; 3];
        for x in 0..3 {
            let [a, b] = OTHER[x];
            for z in 0..3 {
                let v = h[x][a] * px[a][z] + h[x][b] * px[b][z];
                s[x][z] = v - inv_dt * pe[x][z];
            }
            s[x][x] += inv_dt * d[x] + r[x];
        }
        (px, d, s)
    }

    /// The posterior of [`Self::fuse_with_fix_noise`] from the kept gains `kx`.
    #[inline(always)]
    fn fix_noise_posterior(
        &mut self,
        kx: &[[f32; 3]; 6],
        px: &[[f32; 3]; 6],
        d: &Vec3,
        s_inv: &Mat3,
        siy: &Vec3,
        new_var: &Vec3,
    ) {
        // Posterior: P −= Kx·PHᵀₓᵀ; cross(δx, e_k) = −Kx·(PHᵀ of e_k)ᵀ = −Kx[·][j]·d[j];
        // cov(e_k) = diag(new_var) − Ke·(PHᵀ of e_k)ᵀ, with e_k's gain Ke[a][·] = d[a]·S⁻¹[a][·]
        // (its PHᵀ rows are diagonal) taken only where the upper triangle needs it.
        for i in 0..6 {
            for j in 0..3 {
                self.fix.cross[i][j] = -(kx[i][j] * d[j]);
            }
            for j in i..6 {
                let v = self.p[i][j] - (0..3).map(|x| kx[i][x] * px[j][x]).sum::<f32>();
                self.p[i][j] = v;
                self.p[j][i] = v;
            }
        }
        for a in 0..3 {
            for b in a..3 {
                let prior = if a == b { new_var[a] } else { 0.0 };
                let v = prior - d[a] * s_inv[a][b] * d[b];
                self.fix.cov[a][b] = v;
                self.fix.cov[b][a] = v;
            }
            self.fix.mean[a] = d[a] * siy[a];
        }
    }

    /// Scales the attitude error's covariance by `k` (≥ 1; its correlations by √k, so P
    /// stays positive definite): a gated update says the attitude is further off than P
    /// claims, and P grows until the measurement passes its gate again.
    pub fn inflate_attitude(&mut self, k: f32) {
        let s = crate::math::sqrt(k);
        for i in 0..3 {
            for j in 0..6 {
                let f = if j < 3 { k } else { s };
                self.p[i][j] *= f;
                if j >= 3 {
                    self.p[j][i] *= s;
                }
            }
            for v in &mut self.fix.cross[i] {
                *v *= s;
            }
            self.lat.scale(i, s);
            #[cfg(feature = "gyro-scale-states")]
            if let Some(sc) = &mut self.scale {
                for v in &mut sc.pxs[i] {
                    *v *= s;
                }
            }
        }
        self.condition();
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
            self.lat.zero(i);
            #[cfg(feature = "gyro-scale-states")]
            if let Some(sc) = &mut self.scale {
                sc.pxs[i] = [0.0; super::scale::N];
            }
        }
        self.turned = [0.0; 3];
        self.last_t = 0.0;
        self.dth = [-0.0; 3];
        self.clear_block();
        self.forget_fix_noise();
    }

    /// Keeps P symmetric with a finite, positive, bounded diagonal; counts repairs.
    fn condition(&mut self) {
        for i in 0..6 {
            let cap = if i < 3 { MAX_ATT_VAR } else { f32::MAX };
            let d = self.p[i][i];
            if !in_var_range(d, cap) {
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
        // A NaN or ∞ entry leaves the sum of the 15 non-finite, so a finite sum clears them
        // all with one test (an add each, not a finiteness test each: ~40 M4F
        // instructions on every propagation and update); a sum that merely overflowed
        // falls through to the test per entry.
        let mut sum = 0.0f32;
        for i in 0..6 {
            for j in (i + 1)..6 {
                sum += self.p[i][j];
            }
        }
        if sum.is_finite() {
            return;
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

/// `MIN_VAR ≤ d ≤ cap` (false for NaN), for a finite `cap ≥ MIN_VAR`, as one unsigned
/// compare of the bit patterns: positive floats order as their bits, and every other
/// pattern (sign bit set, ∞, NaN) lies above `cap`'s. The same answer as the two float
/// compares, in about half the M4F instructions (six diagonals per `condition`, two or
/// three calls on a GPS-update sample).
#[inline(always)]
fn in_var_range(d: f32, cap: f32) -> bool {
    d.to_bits().wrapping_sub(MIN_VAR.to_bits()) <= cap.to_bits() - MIN_VAR.to_bits()
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

/// `C_θ ← C_θ − M·C_b`: the pending transition acts on the fix-noise cross-covariance's
/// error-state side only.
#[inline(always)]
fn transition_fix_cross(c: &mut [[f32; 3]; 6], m: &Mat3) {
    for i in 0..3 {
        for j in 0..3 {
            let d: f32 = (0..3).map(|k| m[i][k] * c[3 + k][j]).sum();
            c[i][j] -= d;
        }
    }
}

/// What a block's rotation adds, squared, to the rotation turned before it, about each
/// body axis, rad²: `2·λΘᵢ·Δθᵢ` (of `(λΘ + Δθ)² − (λΘ)²`, the block's own `Δθᵢ²` is
/// added at the propagation), at least 0 (turning back does not make the earlier turn
/// better known). `turned` holds Θ, the rotation of the blocks before, and is advanced:
/// decayed by `λ = 1 − t/SCALE_MEMORY_S` over the block's `t` s, plus its rotation `dth`
/// (rad, body).
fn coherent_rotation2(turned: &mut Vec3, dth: &Vec3, t: f32) -> Vec3 {
    let keep = crate::math::max(1.0 - t * (1.0 / SCALE_MEMORY_S), 0.0);
    core::array::from_fn(|i| {
        let (before, d) = (keep * turned[i], dth[i]);
        turned[i] = before + d;
        // 2·max(x, 0) as x + |x|.
        let x = before * d;
        x + libm::fabsf(x)
    })
}

/// Adds the gyro scale-factor and misalignment noise of the block to an attitude
/// covariance block through `add(i, k, v)` (row, column, rad²), from the block's squared
/// body rotations `d2` (rad², or what they add to the rotation before,
/// [`coherent_rotation2`]) turned into NED by `r`.
#[inline(always)]
fn add_coherent_noise(noise: &Noise, d2: &Vec3, r: &Mat3, mut add: impl FnMut(usize, usize, f32)) {
    // The body-rate error (S + N)·ω integrates to S·Δθ + N·Δθ, of variance
    // σ_s²·Δθᵢ² + σ_n²·(Δθⱼ² + Δθₖ²) about body axis i (independent terms), turned into NED
    // by R: R·diag(d)·Rᵀ (`unmodelled::add_to_ned`, term for term). In `propagate` it is
    // added to A before A is stored (through add_to_ned, a reload and a store of nine P
    // entries and a call: ~40 M4F instructions on the GPS-update sample).
    let sum = d2[0] + d2[1] + d2[2];
    let mv = noise.misalignment_var;
    let ds = noise.scale_var - mv;
    #[cfg(not(feature = "gyro-scale-states"))]
    let d: Vec3 = core::array::from_fn(|i| ds * d2[i] + mv * sum);
    #[cfg(feature = "gyro-scale-states")]
    let d = {
        let dxy = noise.scale_var_xy - mv;
        [dxy * d2[0] + mv * sum, dxy * d2[1] + mv * sum, ds * d2[2] + mv * sum]
    };
    if d != [0.0; 3] {
        for i in 0..3 {
            for k in i..3 {
                let v: f32 = (0..3).map(|l| r[i][l] * r[k][l] * d[l]).sum();
                add(i, k, v);
                if k != i {
                    add(k, i, v);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{rngs::StdRng, Rng, SeedableRng};

    /// A random SPD n×n matrix `A·Aᵀ + εI`, f64.
    fn spd(rng: &mut StdRng, n: usize, scale: f64) -> Vec<Vec<f64>> {
        let a: Vec<Vec<f64>> =
            (0..n).map(|_| (0..n).map(|_| rng.gen_range(-1.0..1.0) * scale).collect()).collect();
        (0..n)
            .map(|i| {
                (0..n)
                    .map(|j| {
                        let v: f64 = (0..n).map(|k| a[i][k] * a[j][k]).sum();
                        v + if i == j { 0.1 * scale * scale } else { 0.0 }
                    })
                    .collect()
            })
            .collect()
    }

    fn inv3(m: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
        let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
        core::array::from_fn(|i| {
            core::array::from_fn(|j| {
                let (a, b) = ((j + 1) % 3, (j + 2) % 3);
                let (c, d) = ((i + 1) % 3, (i + 2) % 3);
                (m[a][c] * m[b][d] - m[a][d] * m[b][c]) / det
            })
        })
    }

    /// A filter whose joint prior of `[δx, e_{k−1}]` (9×9: P, the fix-noise
    /// cross-covariance and covariance) and fix-noise mean are random.
    fn random_fix_prior(rng: &mut StdRng) -> Mekf {
        // Joint prior of [δx, e_{k−1}] (9×9): P, its cross-covariance and covariance.
        let j9 = spd(rng, 9, 0.05);
        let mean: Vec3 = core::array::from_fn(|_| rng.gen_range(-0.05..0.05));
        fix_prior(&j9, mean)
    }

    /// A filter whose `[δx, e_{k−1}]` prior is the top-left 9×9 of `j`, with e_{k−1}'s
    /// mean `mean`.
    fn fix_prior(j: &[Vec<f64>], mean: Vec3) -> Mekf {
        let mut ekf = Mekf::new(quat::IDENTITY, [1e-3; 6]);
        for i in 0..6 {
            for k in 0..6 {
                ekf.p[i][k] = j[i][k] as f32;
            }
            for a in 0..3 {
                ekf.fix.cross[i][a] = j[i][6 + a] as f32;
            }
        }
        for a in 0..3 {
            for b in 0..3 {
                ekf.fix.cov[a][b] = j[6 + a][6 + b] as f32;
            }
        }
        ekf.fix.mean = mean;
        ekf.fix.valid = true;
        ekf
    }

    /// The block-structured update is the Kalman update of the 12-state augmented
    /// system `[δx, e_{k−1}, e_k]`, computed densely in f64 from the textbook formulas:
    /// posterior mean, the kept covariance blocks, and e_k's cross-covariance.
    #[test]
    fn fix_noise_update_is_the_dense_augmented_kalman_update() {
        let mut rng = StdRng::seed_from_u64(7);
        for _ in 0..50 {
            let mut ekf = random_fix_prior(&mut rng);
            let mean = ekf.fix.mean;
            // The GPS acceleration's H: zero diagonal (`−[f̄×]`), the rest arbitrary.
            let h: [AttRow; 3] = core::array::from_fn(|k| {
                core::array::from_fn(|j| if j == k { 0.0 } else { rng.gen_range(-10.0..10.0) })
            });
            let r: Vec3 = core::array::from_fn(|_| rng.gen_range(0.01..0.1));
            let new_var: Vec3 = core::array::from_fn(|_| rng.gen_range(0.001..0.01));
            let y: Vec3 = core::array::from_fn(|_| rng.gen_range(-0.2..0.2));
            let dt = rng.gen_range(0.1..0.3f32);

            // Dense f64: prior x̂ = [0, ê_{k−1}, 0], P12, H12 = [h, 0, −I/Δt, I/Δt].
            let n = 12;
            let mut p12 = vec![vec![0.0f64; n]; n];
            for i in 0..9 {
                for j in 0..9 {
                    p12[i][j] = ekf_prior(&ekf, i, j);
                }
            }
            for a in 0..3 {
                p12[9 + a][9 + a] = new_var[a] as f64;
            }
            let mut x0 = vec![0.0f64; n];
            for a in 0..3 {
                x0[6 + a] = mean[a] as f64;
            }
            let idt = 1.0 / dt as f64;
            let mut h12 = vec![vec![0.0f64; n]; 3];
            for k in 0..3 {
                for j in 0..3 {
                    h12[k][j] = h[k][j] as f64;
                }
                h12[k][6 + k] = -idt;
                h12[k][9 + k] = idt;
            }
            let (x1, p1m) = dense_update(&x0, &p12, &h12, r, y);
            let p1 = |i: usize, j: usize| p1m[i][j];

            let fused = ekf.fuse_with_fix_noise(y, &h, r, [0.0; 3], new_var, dt, f32::INFINITY);
            assert!(fused.applied);
            let close = |got: f32, want: f64, what: &str| {
                let tol = 1e-4 * want.abs().max(1e-3);
                assert!((got as f64 - want).abs() <= tol, "{what}: {got} vs {want}");
            };
            let dtheta = injected(&ekf);
            for a in 0..3 {
                close(dtheta[a] as f32, x1[a], "attitude correction");
                close(ekf.bias()[a], x1[3 + a], "bias correction");
                close(ekf.fix.mean[a], x1[9 + a], "e_k mean");
                for b in 0..3 {
                    close(ekf.fix.cov[a][b], p1(9 + a, 9 + b), "e_k covariance");
                }
            }
            for i in 0..6 {
                for a in 0..3 {
                    close(ekf.fix.cross[i][a], p1(i, 9 + a), "cross-covariance");
                }
                for j in 0..6 {
                    close(ekf.covariance()[i][j], p1(i, j), "P");
                }
            }
        }
    }

    /// `got` within 2·10⁻⁴ of `want` (relative; absolute below 10⁻³): f32 against f64.
    #[cfg(any(feature = "latency-consider", feature = "gyro-scale-states"))]
    fn assert_close(got: f32, want: f64, what: &str) {
        let tol = 2e-4 * want.abs().max(1e-3);
        assert!((got as f64 - want).abs() <= tol, "{what}: {got} vs {want}");
    }

    #[cfg(feature = "latency-consider")]
    /// A filter whose `[δx, e_{k−1}, c]` prior is the random 10×10 `j` (c the latency
    /// error, s), with e_{k−1}'s mean `mean` and the next update's jerk `jerk`.
    fn latency_prior(j: &[Vec<f64>], mean: Vec3, jerk: Vec3) -> Mekf {
        let mut ekf = fix_prior(j, mean);
        for i in 0..6 {
            ekf.lat.cross[i] = j[i][9] as f32;
        }
        for a in 0..3 {
            ekf.lat.fix[a] = j[6 + a][9] as f32;
        }
        ekf.lat.var = j[9][9] as f32;
        ekf.lat.jerk = jerk;
        ekf
    }

    #[cfg(feature = "latency-consider")]
    /// Compares the filter's δx correction, P, fix noise and the cross-covariances with
    /// c against the dense posterior `(x1, p1)` of `[δx, e_{k−1}, e_k, c]` (13 states; with
    /// `e_k` absent, `ek` = None, e_{k−1} stays the carried noise).
    fn assert_latency_posterior(ekf: &Mekf, x1: &[f64], p1: &[Vec<f64>], ek: Option<usize>) {
        let close = assert_close;
        let c = p1.len() - 1;
        let dtheta = injected(ekf);
        for a in 0..3 {
            close(dtheta[a] as f32, x1[a], "attitude correction");
            close(ekf.bias()[a], x1[3 + a], "bias correction");
        }
        for i in 0..6 {
            for k in 0..6 {
                close(ekf.covariance()[i][k], p1[i][k], "P");
            }
            close(ekf.lat.cross[i], p1[i][c], "E[δx·c]");
        }
        let e = ek.unwrap_or(6);
        for a in 0..3 {
            close(ekf.lat.fix[a], p1[e + a][c], "E[e·c]");
            if ek.is_some() {
                close(ekf.fix.mean[a], x1[e + a], "e_k mean");
                for i in 0..6 {
                    close(ekf.fix.cross[i][a], p1[i][e + a], "E[δx·e]");
                }
            }
        }
    }

    #[cfg(feature = "latency-consider")]
    /// With the latency as a consider parameter the fix-noise update is, for every state
    /// but c, the Kalman update of `[δx, e_{k−1}, e_k, c]` with `y = H·δx + (e_k −
    /// e_{k−1})/Δt + ȧ·c + w`, computed densely in f64 (Schmidt: c's own mean and
    /// variance stay). And an update that does not see c (the course's) keeps c's
    /// cross-covariances as the dense update with a zero c column does.
    #[test]
    fn latency_consider_updates_are_the_dense_schmidt_update() {
        let mut rng = StdRng::seed_from_u64(13);
        for case in 0..60 {
            let j = spd(&mut rng, 10, 0.05);
            let mean: Vec3 = core::array::from_fn(|_| rng.gen_range(-0.05..0.05));
            let jerk: Vec3 = core::array::from_fn(|_| rng.gen_range(-20.0..20.0));
            let h: [AttRow; 3] = core::array::from_fn(|k| {
                core::array::from_fn(|j| if j == k { 0.0 } else { rng.gen_range(-10.0..10.0) })
            });
            let r: Vec3 = core::array::from_fn(|_| rng.gen_range(0.01..0.1));
            let y: Vec3 = core::array::from_fn(|_| rng.gen_range(-0.2..0.2));
            let mut ekf = latency_prior(&j, mean, jerk);
            if case % 2 == 0 {
                // The course-like update: c and e carried, neither measured.
                let mut x0 = vec![0.0; 10];
                x0[6..9].copy_from_slice(&mean.map(|v| v as f64));
                let mut hd = vec![vec![0.0f64; 10]; 3];
                for k in 0..3 {
                    for c in 0..3 {
                        hd[k][c] = h[k][c] as f64;
                    }
                }
                let (x1, p1) = dense_update(&x0, &j, &hd, r, y);
                assert!(ekf.fuse(y, &h, r, f32::INFINITY).applied);
                assert_latency_posterior(&ekf, &x1, &p1, None);
                continue;
            }
            let new_var: Vec3 = core::array::from_fn(|_| rng.gen_range(0.001..0.01));
            let dt = rng.gen_range(0.1..0.3f32);
            // [δx 0..6, e_{k−1} 6..9, e_k 9..12, c 12].
            let at = |i: usize| if i == 9 { 12 } else { i };
            let mut p = vec![vec![0.0f64; 13]; 13];
            for a in 0..10 {
                for b in 0..10 {
                    p[at(a)][at(b)] = j[a][b];
                }
            }
            let mut hd = vec![vec![0.0f64; 13]; 3];
            for k in 0..3 {
                for c in 0..3 {
                    hd[k][c] = h[k][c] as f64;
                }
                p[9 + k][9 + k] = new_var[k] as f64;
                hd[k][6 + k] = -1.0 / dt as f64;
                hd[k][9 + k] = 1.0 / dt as f64;
                hd[k][12] = jerk[k] as f64;
            }
            let mut x0 = vec![0.0; 13];
            x0[6..9].copy_from_slice(&mean.map(|v| v as f64));
            let (x1, p1) = dense_update(&x0, &p, &hd, r, y);
            assert!(ekf.fuse_with_fix_noise(y, &h, r, [0.0; 3], new_var, dt, f32::INFINITY).applied);
            assert_latency_posterior(&ekf, &x1, &p1, Some(9));
        }
    }

    #[cfg(feature = "latency-consider")]
    /// A propagation turns `E[δx·c]` as Φ does the state: `Φ·E[δx·c]`, Φ = `[[I, −M],
    /// [0, I]]`; switched off (σ_c² = 0) nothing is carried.
    #[test]
    fn latency_consider_propagates_with_the_state() {
        let mut rng = StdRng::seed_from_u64(17);
        let noise = coherent_noise(0.0, 0.0);
        for _ in 0..20 {
            let j = spd(&mut rng, 10, 0.05);
            let mut ekf = latency_prior(&j, [0.0; 3], [0.0; 3]);
            let w: Vec3 = core::array::from_fn(|_| rng.gen_range(-3.0..3.0));
            for _ in 0..10 {
                ekf.step(w, 0.01);
            }
            let m = ekf.m;
            let before = ekf.lat.cross;
            ekf.propagate(&noise);
            for i in 0..3 {
                let want = before[i] as f64
                    - (0..3).map(|k| m[i][k] as f64 * before[3 + k] as f64).sum::<f64>();
                let got = ekf.lat.cross[i] as f64;
                assert!((got - want).abs() <= 1e-5 * want.abs().max(1e-3), "{got} vs {want}");
                assert_eq!(ekf.lat.cross[3 + i], before[3 + i]);
            }
        }
        let mut off = Mekf::new(quat::IDENTITY, [1e-3; 6]);
        off.step([1.0, 0.0, 0.0], 0.01);
        off.propagate(&noise);
        let y = [0.1, -0.1, 0.05];
        let h: [AttRow; 3] = [[0.0, 9.8, 0.0], [-9.8, 0.0, 0.0], [0.0, 0.0, 0.0]];
        off.fuse(y, &h, [0.01; 3], f32::INFINITY);
        assert_eq!(off.lat, LatencyConsider::default());
    }

    /// Only the scale-factor (`scale`, all axes) and misalignment (`mis`) noise, rad².
    fn coherent_noise(scale: f32, mis: f32) -> Noise {
        Noise {
            gyro_psd: 0.0,
            bias_psd: 0.0,
            rate_psd: 0.0,
            scale_var: scale,
            #[cfg(feature = "gyro-scale-states")]
            scale_var_xy: scale,
            misalignment_var: mis,
        }
    }

    /// A 90° roll about body x in one block: the scale factor's variance σ_s²·Δθ² lies
    /// about NED north (the roll axis), the misalignment's σ_n²·Δθ² about east and down
    /// (the y–z plane turns about north, so each keeps it), uncorrelated; nothing for a
    /// roll and back within the block (a scale error of a rotation that returns is zero).
    #[test]
    fn scale_and_misalignment_noise_is_coherent_over_the_block() {
        let noise = coherent_noise(1e-4, 4e-6);
        let dth = core::f32::consts::FRAC_PI_2;
        let added = |rates: &[f32]| {
            let mut ekf = Mekf::new(quat::IDENTITY, [1e-6, 1e-6, 1e-6, 0.0, 0.0, 0.0]);
            let before = *ekf.covariance();
            for &w in rates {
                ekf.step([w, 0.0, 0.0], 0.01);
            }
            ekf.propagate(&noise);
            let p = ekf.covariance();
            let d: [[f32; 3]; 3] = core::array::from_fn(|i| core::array::from_fn(|j| p[i][j] - before[i][j]));
            d
        };
        let roll = [dth / 0.2; 20];
        let d = added(&roll);
        let (s, n) = (1e-4 * dth * dth, 4e-6 * dth * dth);
        assert!((d[0][0] - s).abs() < 1e-3 * s, "north {} vs {s}", d[0][0]);
        assert!((d[1][1] - n).abs() < 1e-3 * n && (d[2][2] - n).abs() < 1e-3 * n, "{d:?}");
        assert!(d[0][1].abs() < 1e-9 && d[0][2].abs() < 1e-9 && d[1][2].abs() < 1e-9, "{d:?}");
        let mut there_and_back = [dth / 0.1; 20];
        for w in &mut there_and_back[10..] {
            *w = -*w;
        }
        let d = added(&there_and_back);
        assert!(d.iter().flatten().all(|v| v.abs() < 1e-9), "{d:?}");
    }

    /// Block after block, a roll keeps adding to the scale factor's error coherently: the
    /// second of two 90° blocks (0.2 s each) adds `σ²·(Δθ² + 2λ·Δθ²)`, λ = 1 − 0.2 s /
    /// `SCALE_MEMORY_S`, the variance of `s·(λ·90° + 90°)` less that of `s·λ·90°`; a roll back adds only its own `σ²·Δθ²`,
    /// and so does a roll after 10 s without turning (the memory decays by λ per block).
    #[test]
    fn a_scale_factor_stays_coherent_across_blocks() {
        let noise = coherent_noise(1e-4, 0.0);
        let dth = core::f32::consts::FRAC_PI_2;
        let s = 1e-4 * dth * dth;
        let mut ekf = Mekf::new(quat::IDENTITY, [1e-6, 1e-6, 1e-6, 0.0, 0.0, 0.0]);
        let mut block = |w: f32| {
            let before = ekf.covariance()[0][0];
            for _ in 0..20 {
                ekf.step([w, 0.0, 0.0], 0.01);
            }
            ekf.propagate(&noise);
            ekf.settle_coherent(&noise);
            ekf.covariance()[0][0] - before
        };
        let close = |got: f32, want: f32| (got - want).abs() < 2e-3 * want;
        let first = block(dth / 0.2);
        assert!(close(first, s), "first block {first} vs {s}");
        let second = block(dth / 0.2);
        let want = (1.0 + 2.0 * (1.0 - 0.2 / SCALE_MEMORY_S)) * s;
        assert!(close(second, want), "second block {second} vs {want}");
        let back = block(-dth / 0.2);
        assert!(close(back, s), "roll back {back} vs {s}");
        for _ in 0..50 {
            block(0.0);
        }
        let fresh = block(dth / 0.2);
        assert!(close(fresh, s), "after 10 s still {fresh} vs {s}");
    }

    /// `widen_biases(k)` adds `k·⟨|ω|²⟩` to each bias variance at the next propagation, ⟨|ω|²⟩
    /// the block's mean squared rate up to `WIDEN_MAX_RATE2`, once: a 10 °/s turn in full, a
    /// 180 °/s roll at the cap, nothing without a call.
    #[test]
    fn the_bias_widening_is_the_blocks_rate_once() {
        let noise = Noise {
            gyro_psd: 0.0,
            bias_psd: 0.0,
            rate_psd: 0.0,
            scale_var: 0.0,
            #[cfg(feature = "gyro-scale-states")]
            scale_var_xy: 0.0,
            misalignment_var: 0.0,
        };
        let k = 2.5e-3 * 0.02 * 0.02;
        let added = |w: f32, widen: bool| {
            let mut ekf = Mekf::new(quat::IDENTITY, [1e-6, 1e-6, 1e-6, 1e-8, 1e-8, 1e-8]);
            if widen {
                ekf.widen_biases(k);
            }
            let mut out = [0.0f32; 2];
            for o in &mut out {
                let before = ekf.covariance()[3][3];
                for _ in 0..20 {
                    ekf.step([0.0, 0.0, w], 0.01);
                }
                ekf.propagate(&noise);
                *o = ekf.covariance()[3][3] - before;
            }
            out
        };
        let turn = 10f32.to_radians();
        let [first, second] = added(turn, true);
        assert!((first - k * turn * turn).abs() < 1e-3 * k * turn * turn, "{first}");
        assert_eq!(second, 0.0, "widened twice");
        let [roll, _] = added(180f32.to_radians(), true);
        assert!((roll - k * WIDEN_MAX_RATE2).abs() < 1e-3 * k * WIDEN_MAX_RATE2, "{roll}");
        assert_eq!(added(turn, false), [0.0, 0.0]);
    }

    /// The bit-pattern range test answers as `MIN_VAR <= d && d <= cap` for every class of
    /// f32: zeros of both signs, subnormals, the bounds and their neighbours, negatives,
    /// infinities and NaNs of both signs, and a sweep of bit patterns.
    #[test]
    fn the_variance_range_test_is_the_float_compare() {
        let mut xs = vec![
            0.0f32, -0.0, MIN_VAR, -MIN_VAR, 1.0, -1.0, f32::MAX, f32::MIN, f32::MIN_POSITIVE,
            1e-45, f32::INFINITY, f32::NEG_INFINITY, f32::NAN, -f32::NAN,
            f32::from_bits(0x7fc0_0001), f32::from_bits(0xffff_ffff), f32::from_bits(0x7f80_0001),
        ];
        for b in [MIN_VAR.to_bits(), 1.0f32.to_bits(), f32::MAX.to_bits()] {
            xs.extend([b - 1, b + 1].map(f32::from_bits));
        }
        xs.extend((0..=u32::MAX).step_by(65_521).map(f32::from_bits));
        for cap in [1.0, MAX_ATT_VAR, f32::MAX, MIN_VAR] {
            for &d in &xs {
                assert_eq!(in_var_range(d, cap), MIN_VAR <= d && d <= cap, "{d:e} ({:#x}) cap {cap}", d.to_bits());
            }
        }
    }

    fn ekf_prior(ekf: &Mekf, i: usize, j: usize) -> f64 {
        (match (i, j) {
            (0..6, 0..6) => ekf.p[i][j],
            (0..6, _) => ekf.fix.cross[i][j - 6],
            (_, 0..6) => ekf.fix.cross[j][i - 6],
            _ => ekf.fix.cov[i - 6][j - 6],
        }) as f64
    }

    /// The attitude correction injected into a filter that started at identity: its
    /// rotation vector (q ≈ [1, δθ/2]).
    fn injected(ekf: &Mekf) -> [f64; 3] {
        let q = ekf.quaternion().map(|v| v as f64);
        let qv = (q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
        let angle_per_qv = 2.0 * qv.atan2(q[0]) / qv;
        core::array::from_fn(|a| q[1 + a] * angle_per_qv)
    }

    /// Dense f64 Kalman update of an n-state prior `(x0, p)` with measurement rows `h`
    /// (3×n), noise `r` and value `y`: the posterior mean and covariance.
    fn dense_update(
        x0: &[f64],
        p: &[Vec<f64>],
        h: &[Vec<f64>],
        r: Vec3,
        y: Vec3,
    ) -> (Vec<f64>, Vec<Vec<f64>>) {
        let n = x0.len();
        let pht: Vec<[f64; 3]> = (0..n)
            .map(|i| core::array::from_fn(|k| (0..n).map(|j| p[i][j] * h[k][j]).sum()))
            .collect();
        let s: [[f64; 3]; 3] = core::array::from_fn(|a| {
            core::array::from_fn(|b| {
                let v: f64 = (0..n).map(|j| h[a][j] * pht[j][b]).sum();
                v + if a == b { r[a] as f64 } else { 0.0 }
            })
        });
        let si = inv3(s);
        let nu: [f64; 3] = core::array::from_fn(|k| {
            y[k] as f64 - (0..n).map(|j| h[k][j] * x0[j]).sum::<f64>()
        });
        let kg: Vec<[f64; 3]> = (0..n)
            .map(|i| core::array::from_fn(|b| (0..3).map(|a| pht[i][a] * si[a][b]).sum()))
            .collect();
        let x1 = (0..n).map(|i| x0[i] + (0..3).map(|a| kg[i][a] * nu[a]).sum::<f64>()).collect();
        let p1 = (0..n)
            .map(|i| {
                (0..n).map(|j| p[i][j] - (0..3).map(|a| kg[i][a] * pht[j][a]).sum::<f64>()).collect()
            })
            .collect();
        (x1, p1)
    }

    /// A filter with the scale states whose joint prior over `[δx (6), δs (2), e_{k−1} (3)]`
    /// is `j` (the fix noise carried when `fix`, with mean `mean`).
    #[cfg(feature = "gyro-scale-states")]
    fn with_joint_prior(j: &[Vec<f64>], fix: bool, mean: Vec3) -> Mekf {
        let mut ekf = Mekf::new(quat::IDENTITY, [1e-3; 6]).with_scale_states(0.002);
        let sc = ekf.scale.as_mut().unwrap();
        sc.awake = 1.0;
        for i in 0..6 {
            for k in 0..6 {
                ekf.p[i][k] = j[i][k] as f32;
            }
            for a in 0..2 {
                sc.pxs[i][a] = j[i][6 + a] as f32;
            }
        }
        for a in 0..2 {
            for b in 0..2 {
                sc.ps[a][b] = j[6 + a][6 + b] as f32;
            }
        }
        if fix {
            for c in 0..3 {
                for i in 0..6 {
                    ekf.fix.cross[i][c] = j[i][8 + c] as f32;
                }
                for a in 0..2 {
                    sc.se[a][c] = j[6 + a][8 + c] as f32;
                }
                for d in 0..3 {
                    ekf.fix.cov[c][d] = j[8 + c][8 + d] as f32;
                }
            }
            ekf.fix.mean = mean;
            ekf.fix.valid = true;
        }
        ekf
    }

    /// The filter's posterior against the dense one `(x1, p1)` over `[δx, δs, e]`, `e` at
    /// `e_at` (the fix noise kept after the update) when `fix`.
    #[cfg(feature = "gyro-scale-states")]
    fn assert_posterior(ekf: &Mekf, x1: &[f64], p1: &[Vec<f64>], e_at: Option<usize>) {
        let close = assert_close;
        let sc = ekf.scale.as_ref().unwrap();
        let dtheta = injected(ekf);
        for a in 0..3 {
            close(dtheta[a] as f32, x1[a], "attitude correction");
            close(ekf.bias()[a], x1[3 + a], "bias correction");
        }
        for a in 0..2 {
            close(sc.estimate()[a], x1[6 + a], "scale estimate");
            for b in 0..2 {
                close(sc.ps[a][b], p1[6 + a][6 + b], "P_ss");
            }
            for i in 0..6 {
                close(sc.pxs[i][a], p1[i][6 + a], "P_xs");
            }
        }
        for i in 0..6 {
            for k in 0..6 {
                close(ekf.covariance()[i][k], p1[i][k], "P");
            }
        }
        if let Some(e) = e_at {
            for c in 0..3 {
                close(ekf.fix.mean[c], x1[e + c], "fix noise mean");
                for i in 0..6 {
                    close(ekf.fix.cross[i][c], p1[i][e + c], "E[δx eᵀ]");
                }
                for a in 0..2 {
                    close(sc.se[a][c], p1[6 + a][e + c], "E[δs eᵀ]");
                }
                for d in 0..3 {
                    close(ekf.fix.cov[c][d], p1[e + c][e + d], "fix noise covariance");
                }
            }
        }
    }

    /// Both updates with the scale states are the Kalman update of the augmented system
    /// computed densely in f64: the white one over `[δx, δs, e]` (e carried, not measured),
    /// the one with the fix noise as states over `[δx, δs, e_{k−1}, e_k]`.
    #[test]
    #[cfg(feature = "gyro-scale-states")]
    fn scale_state_updates_are_the_dense_augmented_kalman_update() {
        let mut rng = StdRng::seed_from_u64(11);
        for case in 0..60 {
            let j = spd(&mut rng, 11, 0.05);
            let mean: Vec3 = core::array::from_fn(|_| rng.gen_range(-0.05..0.05));
            // The GPS acceleration's H: zero diagonal (`−[f̄×]`), the rest arbitrary.
            let h: [AttRow; 3] = core::array::from_fn(|k| {
                core::array::from_fn(|j| if j == k { 0.0 } else { rng.gen_range(-10.0..10.0) })
            });
            let r: Vec3 = core::array::from_fn(|_| rng.gen_range(0.01..0.1));
            let y: Vec3 = core::array::from_fn(|_| rng.gen_range(-0.2..0.2));
            let mut hd = vec![vec![0.0f64; 14]; 3];
            for k in 0..3 {
                for c in 0..3 {
                    hd[k][c] = h[k][c] as f64;
                }
            }
            if case % 2 == 0 {
                // White: the carried e is correlated with the state but not measured.
                let mut ekf = with_joint_prior(&j, true, mean);
                let mut x0 = vec![0.0; 11];
                x0[8..11].copy_from_slice(&mean.map(|v| v as f64));
                let hw: Vec<Vec<f64>> = hd.iter().map(|row| row[..11].to_vec()).collect();
                let (x1, p1) = dense_update(&x0, &j, &hw, r, y);
                assert!(ekf.fuse(y, &h, r, f32::INFINITY).applied);
                // The filter does not move e's mean in the white update; the dense one
                // does (its cross-covariance): compare everything else.
                let mut x1 = x1;
                x1[8..11].copy_from_slice(&mean.map(|v| v as f64));
                let mut p1 = p1;
                for c in 0..3 {
                    for d in 0..3 {
                        p1[8 + c][8 + d] = ekf.fix.cov[c][d] as f64;
                    }
                }
                assert_posterior(&ekf, &x1, &p1, Some(8));
            } else {
                let mut ekf = with_joint_prior(&j, true, mean);
                let new_var: Vec3 = core::array::from_fn(|_| rng.gen_range(0.001..0.01));
                let dt = rng.gen_range(0.1..0.3f32);
                let mut p = vec![vec![0.0f64; 14]; 14];
                for a in 0..11 {
                    for b in 0..11 {
                        p[a][b] = j[a][b];
                    }
                }
                for c in 0..3 {
                    p[11 + c][11 + c] = new_var[c] as f64;
                    hd[c][8 + c] = -1.0 / dt as f64;
                    hd[c][11 + c] = 1.0 / dt as f64;
                }
                let mut x0 = vec![0.0; 14];
                x0[8..11].copy_from_slice(&mean.map(|v| v as f64));
                let (x1, p1) = dense_update(&x0, &p, &hd, r, y);
                let fused = ekf.fuse_with_fix_noise(y, &h, r, [0.0; 3], new_var, dt, f32::INFINITY);
                assert!(fused.applied);
                assert_posterior(&ekf, &x1, &p1, Some(11));
            }
        }
    }

    /// The block propagation with the scale states is `Φ·P·Φᵀ` of the augmented
    /// transition `[[I, −M, G], [0, I, 0], [0, 0, I]]` in f64, `G = −(M/T)·diag(Δθ)` on
    /// body x and y, and the estimate scales the rate: a 1 % scale learnt turns a 100 °/s
    /// roll 1 % slower.
    #[test]
    #[cfg(feature = "gyro-scale-states")]
    fn scale_state_propagation_is_the_dense_augmented_transition() {
        let mut rng = StdRng::seed_from_u64(5);
        let noise = Noise {
            gyro_psd: 0.0,
            bias_psd: 0.0,
            rate_psd: 0.0,
            scale_var: 0.0,
            scale_var_xy: 0.0,
            misalignment_var: 0.0,
        };
        for _ in 0..20 {
            let j = spd(&mut rng, 11, 0.05);
            let mut ekf = with_joint_prior(&j, false, [0.0; 3]);
            let w: Vec3 = core::array::from_fn(|_| rng.gen_range(-3.0..3.0));
            for _ in 0..10 {
                ekf.step(w, 0.01);
            }
            let (m, t, dth) = (ekf.m, ekf.t as f64, ekf.dth);
            let mut phi = vec![vec![0.0f64; 8]; 8];
            for i in 0..8 {
                phi[i][i] = 1.0;
            }
            for i in 0..3 {
                for k in 0..3 {
                    phi[i][3 + k] = -m[i][k] as f64;
                }
                for a in 0..2 {
                    phi[i][6 + a] = -(m[i][a] as f64) * dth[a] as f64 / t;
                }
            }
            let want = |a: usize, b: usize| -> f64 {
                (0..8)
                    .map(|k| phi[a][k] * (0..8).map(|l| j[k][l] * phi[b][l]).sum::<f64>())
                    .sum()
            };
            ekf.propagate(&noise);
            let sc = ekf.scale.as_ref().unwrap();
            let close = |got: f32, want: f64, what: &str| {
                assert!((got as f64 - want).abs() <= 2e-4 * want.abs().max(1e-3), "{what}: {got} vs {want}");
            };
            for a in 0..6 {
                for b in 0..6 {
                    close(ekf.p[a][b], want(a, b), "P");
                }
                for s in 0..2 {
                    close(sc.pxs[a][s], want(a, 6 + s), "P_xs");
                }
            }
            for s in 0..2 {
                for u in 0..2 {
                    close(sc.ps[s][u], want(6 + s, 6 + u), "P_ss");
                }
            }
        }
        // The compensation: with ŝ_x = 1 %, 1 s at 100 °/s measured turns 99 °.
        let mut ekf = Mekf::new(quat::IDENTITY, [1e-6; 6]).with_scale_states(0.002);
        ekf.scale.as_mut().unwrap().gain = [0.99, 1.0];
        for _ in 0..100 {
            ekf.step([100f32.to_radians(), 0.0, 0.0], 0.01);
        }
        let q = ekf.quaternion();
        let roll = 2.0 * libm::atan2f(q[1], q[0]);
        assert!((roll.to_degrees() - 99.0).abs() < 0.01, "{}", roll.to_degrees());
    }
}
