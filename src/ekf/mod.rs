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
pub(crate) const VAR_FLOOR: f32 = 1e-12;

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
    /// State estimate (read-out: [`Ekf::state`]).
    pub(crate) x: State,
    /// Error covariance, symmetric positive definite: changed only by the predict, the
    /// updates and the repairs here (read-out: [`Ekf::covariance`]).
    pub(crate) p: Mat6,
    /// sin/cos of roll and pitch, carried from sample to sample by the decimated predict.
    trig: TrigCache,
    /// Times [`Ekf::condition`] repaired P during a predict, [`Ekf::ensure_positive_definite`]
    /// shrank its correlations, or [`Ekf::check_state`] re-seeded the filter (wrapping).
    repairs: u32,
    /// Over-the-top reflections of the pitch so far (wrapping; see [`Ekf::normalize_angles`]).
    flips: u32,
    /// Times the state or P was found invalid and the filter re-seeded (wrapping).
    resets: u32,
}

/// `(sin, cos)` of roll and pitch for the angles in `at`, advanced each predict step by the
/// step's own small rotation (angle addition with Taylor sin/cos of the increment) instead
/// of two full sincos per sample — those were a fifth of the host step. Invariant:
/// `sc ≈ (sin, cos)(at)`. Any angles within 0.05 rad of `at` — the next step's after an
/// update's correction or a roll wrap, the update's interval-mean attitude — are rotated
/// from it ([`TrigCache::sin_cos`]); larger offsets and pitch flips recompute. Refreshed with
/// full sincos after every covariance propagation, so rounding cannot accumulate beyond one
/// block (≲ 1e-6).
#[derive(Debug, Clone, Copy)]
struct TrigCache {
    at: [f32; 2],
    sc: [(f32, f32); 2],
}

impl TrigCache {
    /// Nothing cached (NaN never equals a state angle).
    const EMPTY: TrigCache = TrigCache { at: [f32::NAN; 2], sc: [(0.0, 1.0); 2] };

    /// `(sin, cos)` of `angles` (roll, pitch; rad): the cached ones if they are `at` (bit
    /// for bit: every predict step without an update), rotated by `angles − at` if both
    /// offsets are below 0.05 rad, otherwise two full sincos.
    #[inline(always)]
    fn sin_cos(&self, angles: [f32; 2]) -> [(f32, f32); 2] {
        if angles[0].to_bits() == self.at[0].to_bits()
            && angles[1].to_bits() == self.at[1].to_bits()
        {
            return self.sc;
        }
        let d = [wrap_pi(angles[0] - self.at[0]), angles[1] - self.at[1]];
        if small(d) {
            [rotate(self.sc[0], d[0]), rotate(self.sc[1], d[1])]
        } else {
            [crate::math::sincos(angles[0]), crate::math::sincos(angles[1])]
        }
    }

    /// Caches `sc` rotated by `d` (rad) as the sin/cos of `x[0]`, `x[1]`; increments
    /// beyond 0.05 rad (Taylor error > 3e-9) leave the cache empty.
    #[inline(always)]
    fn advance(&mut self, sc: [(f32, f32); 2], d: [f32; 2], x: &State) {
        if !small(d) {
            *self = Self::EMPTY;
            return;
        }
        for i in 0..2 {
            self.sc[i] = rotate(sc[i], d[i]);
            self.at[i] = x[i];
        }
    }
}

/// Both increments below 0.05 rad, where [`rotate`]'s Taylor terms are exact to 3e-9.
#[inline(always)]
fn small(d: [f32; 2]) -> bool {
    (libm::fabsf(d[0]) < 0.05) & (libm::fabsf(d[1]) < 0.05)
}

/// `(sin, cos)` of `a + d` from `(sin a, cos a)` and a small `d` (rad) by angle addition:
/// sin d = d − d³/6 + O(d⁵), cos d = 1 − d²/2 + d⁴/24 + O(d⁶).
#[inline(always)]
fn rotate((s, c): (f32, f32), d: f32) -> (f32, f32) {
    let dd = d * d;
    let sd = d - d * dd * (1.0 / 6.0);
    let cd = 1.0 - dd * (0.5 - dd * (1.0 / 24.0));
    (s * cd + c * sd, c * cd - s * sd)
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

/// What a decimated predict accumulates between covariance propagations (see
/// [`Ekf::predict_decimated`]): the time, the gyro sum and where the block started — the
/// Jacobian itself is evaluated once per block, not every sample.
#[derive(Debug, Clone, Copy, Default)]
pub struct PendingCovariance {
    /// Accumulated Δt, s.
    dt: f32,
    /// Sum of the raw gyro samples, rad/s.
    gyro: Vec3,
    /// Roll and pitch at the start of the block, rad.
    start: [f32; 2],
    /// Samples accumulated.
    n: u32,
    /// Samples at which to propagate (0: the decimation factor); see [`PendingCovariance::stagger`].
    due: u32,
    /// Samples since the last measurement update (kept across propagations).
    since_update: u32,
}

impl PendingCovariance {
    /// Called at a measurement update instead of propagating: the propagation that would
    /// fall due at or before the next update (expected as many samples away as the last
    /// one was) comes half an update interval from now instead, so with periodic fixes
    /// propagation and update never share an interrupt (worst-case interrupt cost: the
    /// larger of the two, not their sum). With N ≥ 2 intervals per block (20 samples,
    /// 10 Hz fixes at 100 Hz) that is one propagation every ⌈N / interval⌉ intervals, mid-way
    /// between two fixes. The update uses P up to `every − 1` samples old (the missing Q and
    /// rotation over ≤ 0.2 s are ~0.1 % of P; `tests/filter.rs` bounds the effect).
    pub fn stagger(&mut self, every: u8) {
        let every = every as u32;
        let interval = self.since_update.max(1);
        self.since_update = 0;
        if every > 1 && self.n + interval >= every {
            // Half the shorter of the update interval and the block: mid-way to the next
            // update, or (fixes slower than blocks) half a block from this one, so the
            // propagations that follow every `every` samples miss the next update too. Never
            // later than `every` samples: fast fixes must not postpone it for ever.
            let half = (interval.min(every) / 2).max(1);
            self.due = (self.n + half).min(every);
        }
    }

    #[inline(always)]
    fn add(&mut self, dt: f32, gyro: Vec3, x: &State) {
        if self.n == 0 {
            self.start = [x[0], x[1]];
        }
        self.dt += dt;
        for i in 0..3 {
            self.gyro[i] += gyro[i];
        }
        self.n += 1;
        self.since_update += 1;
    }

    /// The state to linearise the block at: roll and pitch at the block's midpoint (mean
    /// of its ends; second-order accurate like the mean of the per-sample Jacobians), yaw
    /// and biases as now (ψ does not enter the kinematics; b changes only in updates, so a
    /// block that straddles one is linearised with the corrected bias). And the block's
    /// mean gyro.
    fn midpoint(&self, x: &State) -> (State, Vec3) {
        let k = 1.0 / self.n as f32;
        let dphi = wrap_pi(x[0] - self.start[0]);
        let dtheta = x[1] - self.start[1];
        let mut mid = *x;
        // Over the top (|Δθ| can only exceed π/2 through the pitch re-normalisation): the
        // ends are not comparable, keep the present attitude.
        if libm::fabsf(dtheta) < 0.5 * PI {
            mid[0] = wrap_pi(self.start[0] + 0.5 * dphi);
            mid[1] = self.start[1] + 0.5 * dtheta;
        }
        (mid, self.gyro.map(|g| g * k))
    }

    /// Samples whose covariance propagation is still pending.
    #[cfg(any(test, feature = "internals"))]
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
        Ekf { x, p, trig: TrigCache::EMPTY, repairs: 0, flips: 0, resets: 0 }
    }

    /// The state estimate `[roll, pitch, yaw (rad), gyro biases (rad/s)]`.
    #[cfg(any(test, feature = "internals"))]
    pub fn state(&self) -> &State {
        &self.x
    }

    /// The error covariance, symmetric positive definite.
    #[cfg(any(test, feature = "internals"))]
    pub fn covariance(&self) -> &Mat6 {
        &self.p
    }

    /// Replaces the covariance, for tests that start from a dense P. The caller keeps it
    /// symmetric positive definite.
    #[cfg(any(test, feature = "internals"))]
    pub fn set_covariance(&mut self, p: Mat6) {
        self.p = p;
    }

    /// `(sin, cos)` of a roll and a pitch near the state's (rad): from the sin/cos the
    /// predict carries, rotated by the offsets when they are below 0.05 rad (the update's
    /// interval-mean attitude); otherwise two full sincos.
    pub fn roll_pitch_sin_cos(&self, roll: f32, pitch: f32) -> [(f32, f32); 2] {
        self.trig.sin_cos([roll, pitch])
    }

    /// One predict step of length `dt` s with gyro `gyro` (rad/s, body FRD).
    ///
    /// Euler step `x += f·Δt`; `Φ ≈ I + FΔt + (FΔt)²/2`; `P = ΦPΦᵀ + Qd` with
    /// `Qd = G·Qc·Gᵀ·Δt` (first-order hold of the continuous densities), computed
    /// blockwise. Returns the linearisation used (Euler rates, pitch-guard flag).
    pub fn predict(
        &mut self,
        dt: f32,
        gyro: Vec3,
        n: &ProcessNoise,
        min_cos_pitch: f32,
        caps: VarianceCaps,
    ) -> process::Linearization {
        let lin = process::linearize(&self.x, gyro, min_cos_pitch);
        self.propagate_covariance(dt, &lin.a, &lin.b, n);
        self.step_state(dt, &lin.euler_rates, n.inv_tau);
        self.count_condition(caps);
        lin
    }

    /// A predict step whose covariance propagation is decimated: the state is integrated
    /// every sample (Euler rates only, no Jacobian); every `every` samples — sooner after
    /// [`PendingCovariance::stagger`], or on [`Ekf::flush`] — P is propagated once over the
    /// accumulated Δt, linearised at the block's midpoint roll/pitch with its mean gyro.
    /// `every ≤ 1` is [`Ekf::predict`] exactly. Standard practice on small CPUs (PX4 EKF2
    /// also propagates its covariance at a lower rate than its state); the cost is a P that
    /// lags the state by at most `every − 1` samples between flushes. Returns the Euler
    /// rates (rad/s) and whether the pitch guard applied.
    pub fn predict_decimated(
        &mut self,
        dt: f32,
        gyro: Vec3,
        n: &ProcessNoise,
        min_cos_pitch: f32,
        caps: VarianceCaps,
        pending: &mut PendingCovariance,
        every: u8,
    ) -> (Vec3, bool) {
        if every <= 1 {
            let lin = self.predict(dt, gyro, n, min_cos_pitch, caps);
            return (lin.euler_rates, lin.guarded);
        }
        let sc = self.trig.sin_cos([self.x[0], self.x[1]]);
        let (rates, guarded) = process::euler_rates_sc(&self.x, sc[0], sc[1], gyro, min_cos_pitch);
        pending.add(dt, gyro, &self.x);
        self.integrate(dt, &rates, n.inv_tau);
        self.trig.advance(sc, [rates[0] * dt, rates[1] * dt], &self.x);
        // A wrap or an over-the-top flip changes the angles after the cache took them: the
        // next step's `TrigCache::sin_cos` rotates across the wrap and recomputes after a flip.
        self.normalize_angles();
        let due = if pending.due == 0 { every as u32 } else { pending.due };
        if pending.n >= due {
            self.flush(pending, n, min_cos_pitch, caps);
        }
        (rates, guarded)
    }

    /// Propagates P over everything accumulated in `pending` (no-op when empty), for a caller
    /// that needs P current now ([`crate::Ahrs`] does not: its updates use the staggered P).
    pub fn flush(
        &mut self,
        pending: &mut PendingCovariance,
        n: &ProcessNoise,
        min_cos_pitch: f32,
        caps: VarianceCaps,
    ) {
        if pending.n == 0 {
            return;
        }
        let (mid, gyro) = pending.midpoint(&self.x);
        let lin = process::linearize(&mid, gyro, min_cos_pitch);
        self.propagate_covariance(pending.dt, &lin.a, &lin.b, n);
        *pending = PendingCovariance {
            since_update: pending.since_update,
            ..PendingCovariance::default()
        };
        self.count_condition(caps);
        // Bounds the recurrence's rounding to one block.
        self.trig = TrigCache::EMPTY;
    }

    /// State: Euler step, bias decay, angle normalisation.
    #[inline(always)]
    fn step_state(&mut self, dt: f32, rates: &Vec3, inv_tau: f32) {
        self.integrate(dt, rates, inv_tau);
        self.normalize_angles();
    }

    /// Euler step and bias decay, angles not yet normalised.
    #[inline(always)]
    fn integrate(&mut self, dt: f32, rates: &Vec3, inv_tau: f32) {
        for i in 0..3 {
            self.x[i] += rates[i] * dt;
        }
        // Gauss-Markov decay; a random walk (the default) has none.
        if inv_tau != 0.0 {
            let kb = -inv_tau;
            for i in 3..6 {
                self.x[i] += kb * self.x[i] * dt;
            }
        }
    }

    /// `P = ΦPΦᵀ + Qd` over `dt` for the linearisation blocks `a`, `b` (see [`Ekf::predict`]).
    #[inline(always)]
    fn propagate_covariance(&mut self, dt: f32, a: &Mat3, b: &Mat3, n: &ProcessNoise) {
        let kb = -n.inv_tau;
        let h = 0.5 * dt * dt;
        let g = transition_rows(dt, a, b, kb, h);
        let phi_d = 1.0 + kb * dt + kb * kb * h;
        let w = self.rows_times_p(&g);
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

    /// `W = G·P` (3×6) for the attitude rows `g` of Φ (their third column e₂ implied).
    #[inline(always)]
    fn rows_times_p(&self, g: &[[f32; 6]; 3]) -> [[f32; 6]; 3] {

        // W = G·P (3×6). Then Paa' = W·Gᵀ + Qd_aa, Pab' = W[:, 3..6]·φd, Pbb' = φd²·Pbb + Qd_bb:
        // one 3×6·6×6 product instead of six 3×3 ones (cost: this runs every propagation — every
        // sample in `predict`, every N-th in `predict_decimated`).
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
        w
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
        self.apply_gain(&gain, &col, nu);
        ScalarUpdate { innovation: nu, variance: s, applied: true }
    }

    /// The state and covariance half of a scalar update: `x += K·ν`, `P −= K·colᵀ` (col =
    /// P·Hᵀ, K = col/S) on the upper triangle, mirrored, so P stays exactly symmetric.
    #[inline(always)]
    pub(crate) fn apply_gain(&mut self, gain: &[f32; 6], col: &[f32; 6], nu: f32) {
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
    }

    /// Raises the variance of axis `i` to at least `var`, scaling its row and column
    /// so correlations (and positive definiteness) are preserved.
    pub fn inflate_axis(&mut self, i: usize, var: f32) {
        let old = self.p[i][i];
        if !(var > old) {
            return;
        }
        let k = crate::math::sqrt(var / old.max(VAR_FLOOR));
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
    /// The reflection's Jacobian is diag(1, −1, 1, 1, 1, 1): P's pitch row and column change
    /// sign with it (counted in [`Ekf::flips`], for the fix-noise cross-covariance).
    #[inline(always)]
    pub fn normalize_angles(&mut self) {
        // Fast path (every predict step, inlined): all three already in range, three compares.
        if (libm::fabsf(self.x[0]) < PI)
            & (libm::fabsf(self.x[1]) <= 0.5 * PI)
            & (libm::fabsf(self.x[2]) < PI)
        {
            return;
        }
        self.normalize_slow();
    }

    #[inline(never)]
    fn normalize_slow(&mut self) {
        let half = 0.5 * PI;
        // An update can move θ by more than π (found by proptest: θ = −4.77); wrapped first,
        // the reflection below lands it in [−π/2, π/2].
        self.x[1] = wrap_pi(self.x[1]);
        if self.x[1] > half || self.x[1] < -half {
            let sgn = if self.x[1] > 0.0 { 1.0 } else { -1.0 };
            self.x[1] = sgn * PI - self.x[1];
            self.x[0] += PI;
            self.x[2] += PI;
            // δθ' = −δθ: without this, every pitch–bias correlation points the wrong way
            // after a loop's top and the pitch updates drive the bias away.
            for j in 0..6 {
                if j != 1 {
                    self.p[1][j] = -self.p[1][j];
                    self.p[j][1] = -self.p[j][1];
                }
            }
            self.flips = self.flips.wrapping_add(1);
        }
        self.x[0] = wrap_pi(self.x[0]);
        self.x[2] = wrap_pi(self.x[2]);
    }

    /// Times the predict steps' [`Ekf::condition`] floored a variance or replaced a
    /// non-finite P, [`Ekf::ensure_positive_definite`] shrank an indefinite P's
    /// correlations, or [`Ekf::check_state`] re-seeded the filter
    /// (`Health::covariance_repairs`; wraps).
    pub fn repairs(&self) -> u32 {
        self.repairs
    }

    /// Counts a repair made outside this type (the fix-noise cross-covariance bounded).
    pub(crate) fn count_repair(&mut self) {
        self.repairs = self.repairs.wrapping_add(1);
    }

    /// Over-the-top pitch reflections so far (wraps): each one changes the sign of
    /// everything correlated with the pitch error.
    pub fn flips(&self) -> u32 {
        self.flips
    }

    /// Times the filter was re-seeded because its state or P was invalid (wraps;
    /// [`Ekf::check_state`], and the non-finite branch of [`Ekf::condition`]).
    pub fn resets(&self) -> u32 {
        self.resets
    }

    /// Checks that P is positive definite (its Cholesky factor exists) and returns the
    /// factor. If it is not — a sequence of f32 updates with correlations near ±1, or an
    /// update through an inconsistent cross-covariance, can leave it indefinite, and
    /// [`Ekf::apply_gain`]'s variance floor then hides the negative variance — the
    /// correlations are halved until it is (after 8 halvings, ≤ 0.4 % of them left, P
    /// is made diagonal), and a repair is counted. An indefinite P makes the gains
    /// meaningless: one update can then throw the bias anywhere.
    pub fn ensure_positive_definite(&mut self) -> Mat6 {
        if let Some(l) = cholesky(&self.p) {
            return l;
        }
        self.repairs = self.repairs.wrapping_add(1);
        for _ in 0..8 {
            for i in 0..6 {
                for j in 0..6 {
                    if i != j {
                        self.p[i][j] *= 0.5;
                    }
                }
            }
            if let Some(l) = cholesky(&self.p) {
                return l;
            }
        }
        let mut l = [[0.0; 6]; 6];
        for i in 0..6 {
            let d = self.p[i][i];
            let d = if (VAR_FLOOR..f32::INFINITY).contains(&d) { d } else { VAR_FLOOR };
            for j in 0..6 {
                self.p[i][j] = 0.0;
            }
            self.p[i][i] = d;
            l[i][i] = crate::math::sqrt(d);
        }
        l
    }

    /// Re-seeds the filter if its state is invalid: a non-finite angle, or a gyro bias
    /// beyond `bias_limit` (rad/s; false for NaN) — a bias no gyro has is a diverged
    /// filter, not an estimate. The attitude keeps its finite angles, the bias restarts at 0,
    /// P at the caps (counted as a repair and a reset). Returns whether it re-seeded.
    pub fn check_state(&mut self, caps: VarianceCaps, bias_limit: f32) -> bool {
        let ok_bias = (libm::fabsf(self.x[3]) <= bias_limit)
            & (libm::fabsf(self.x[4]) <= bias_limit)
            & (libm::fabsf(self.x[5]) <= bias_limit);
        let finite_att = (self.x[0] * 0.0 + self.x[1] * 0.0 + self.x[2] * 0.0) == 0.0;
        if ok_bias & finite_att {
            return false;
        }
        self.reseed(caps, [false; 6]);
        true
    }

    /// A fresh filter at the caps' variances, keeping the angles that are finite (and the
    /// finite biases `keep_bias` selects; the others restart at 0) and the counters;
    /// counts a repair and a reset.
    fn reseed(&mut self, caps: VarianceCaps, keep_bias: [bool; 6]) {
        let mut fresh = Ekf::new(
            [0.0; 6],
            [caps.attitude, caps.attitude, caps.attitude, caps.bias, caps.bias, caps.bias],
        );
        for i in 0..6 {
            if (i < 3 || keep_bias[i]) && self.x[i].is_finite() {
                fresh.x[i] = self.x[i];
            }
        }
        fresh.repairs = self.repairs.wrapping_add(1);
        fresh.flips = self.flips;
        fresh.resets = self.resets.wrapping_add(1);
        *self = fresh;
        self.normalize_angles();
    }

    /// [`Ekf::condition`], counting a repair.
    fn count_condition(&mut self, caps: VarianceCaps) {
        let repaired = self.condition(caps);
        self.repairs = self.repairs.wrapping_add(repaired as u32);
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
        // Fast path (every flush): every variance already inside [floor, cap] (false for NaN).
        let in_range = |i: usize, cap: f32| (self.p[i][i] >= VAR_FLOOR) & (self.p[i][i] <= cap);
        let ok_att =
            in_range(0, caps.attitude) & in_range(1, caps.attitude) & in_range(2, caps.attitude);
        let ok_bias = in_range(3, caps.bias) & in_range(4, caps.bias) & in_range(5, caps.bias);
        let finite_x = (self.x[0] * 0.0
            + self.x[1] * 0.0
            + self.x[2] * 0.0
            + self.x[3] * 0.0
            + self.x[4] * 0.0
            + self.x[5] * 0.0)
            == 0.0;
        if ok_att & ok_bias & finite_x {
            return false;
        }
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
                let k = crate::math::sqrt(cap / d);
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
        // sum: any NaN or ±Inf makes it non-finite).
        let mut sum = 0.0f32;
        for i in 0..6 {
            sum += self.p[i][i] * 0.0 + self.x[i] * 0.0;
        }
        if !sum.is_finite() {
            // Should be unreachable (inputs are validated); never let NaN persist.
            let repairs = self.repairs;
            self.reseed(caps, [true; 6]);
            // Counted by the caller (`count_condition`), as every repair here.
            self.repairs = repairs;
            repaired = true;
        }
        repaired
    }
}

/// The Cholesky factor of a symmetric 6×6 matrix (lower triangle read), or `None` if a
/// pivot is not positive and finite.
fn cholesky(p: &Mat6) -> Option<Mat6> {
    let mut l = [[0.0f32; 6]; 6];
    for j in 0..6 {
        let mut d = p[j][j];
        for k in 0..j {
            d -= l[j][k] * l[j][k];
        }
        if !(d > 0.0 && d < f32::INFINITY) {
            return None;
        }
        let ljj = crate::math::sqrt(d);
        l[j][j] = ljj;
        let inv = 1.0 / ljj;
        for i in j + 1..6 {
            let mut v = p[i][j];
            for k in 0..j {
                v -= l[i][k] * l[j][k];
            }
            l[i][j] = v * inv;
        }
    }
    Some(l)
}

/// The attitude rows of Φ over `dt` (`h` = Δt²/2, `kb` = −1/τ of the bias model):
/// Φa = I + AΔt + A²Δt²/2, Φb = BΔt + (AB + k_b B)Δt²/2.
#[inline(always)]
fn transition_rows(dt: f32, a: &Mat3, b: &Mat3, kb: f32, h: f32) -> [[f32; 6]; 3] {
        // Φ blocks: Φa = I + AΔt + A²Δt²/2, Φb = BΔt + (AB + k_b B)Δt²/2, φd scalar.
        // Written out with A's and B's structural zeros removed: `x * 0.0` cannot be folded
        // in IEEE arithmetic (x may be ±Inf or NaN), so the compiler would multiply them.
        // A's third column is zero (ψ does not enter f): Φa's third column is exactly e₂.
        let (a00, a01, a10, a20, a21) = (a[0][0], a[0][1], a[1][0], a[2][0], a[2][1]);
        let (b01, b02, b11, b12, b21, b22) = (b[0][1], b[0][2], b[1][1], b[1][2], b[2][1], b[2][2]);
        let e = dt + kb * h; // B's factor in Φb: Δt + k_b·Δt²/2
        [
            [
                1.0 + a00 * dt + (a00 * a00 + a01 * a10) * h,
                a01 * dt + a00 * a01 * h,
                0.0,
                -e - a00 * h,
                b01 * e + (a00 * b01 + a01 * b11) * h,
                b02 * e + (a00 * b02 + a01 * b12) * h,
            ],
            [
                a10 * dt + a10 * a00 * h,
                1.0 + a10 * a01 * h,
                0.0,
                -a10 * h,
                b11 * e + a10 * b01 * h,
                b12 * e + a10 * b02 * h,
            ],
            [
                a20 * dt + (a20 * a00 + a21 * a10) * h,
                a21 * dt + a20 * a01 * h,
                1.0,
                -a20 * h,
                b21 * e + (a20 * b01 + a21 * b11) * h,
                b22 * e + (a20 * b02 + a21 * b12) * h,
            ],
        ]
}
