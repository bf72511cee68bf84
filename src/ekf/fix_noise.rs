//! The shared fix of consecutive GPS differences, as two extra states.
//!
//! EKF1 measures roll and pitch from `(v₁ − v₀)/Δt`; the next measurement uses
//! `(v₂ − v₁)/Δt`. The noise of v₁ enters both with opposite signs (lag-1 correlation
//! ρ = −½), so a sum of measurements telescopes: the noise of an average over k intervals
//! falls as 1/k, not 1/√k. A filter that takes the differences as white weighs them as
//! if it did not, and in straight flight — where the GPS noise is most of the
//! measurement noise — it follows the bias drift too slowly (README, consistency).
//!
//! Here the previous fix's velocity noise, projected on the roll and on the pitch
//! measurement's direction ([`crate::measure::noise::Ekf1Noise`]; the two are orthogonal),
//! is carried as states `q = [q_φ, q_θ]` (m/s) beside the filter: their mean, their
//! covariance `V` and their cross-covariance `C = cov(x, q)` with the six filter states.
//! A roll or pitch measurement is `z = xᵢ + h·(n − qᵢ) + w` with `h = gain/Δt`, the new
//! fix's projected noise `n` (prior 0, σ₁²) and white `w` (accelerometer, floor); after
//! the update `n` replaces `qᵢ`. This is the textbook augmented-state treatment of
//! coloured measurement noise, on an 8-state filter whose extra states have no dynamics,
//! so only `C` needs propagating — once per update with `Φ ≈ I + F·Δt` (cost: the
//! predict in the IMU interrupt stays as it was).
//!
//! Approximations: the projection direction of the old fix is the one of the new
//! measurement (the heading frame turns by ψ̇·Δt between fixes, ~3° in a hard turn);
//! initialisation and gate recovery drop the correlation with the reset axis.

use super::{Ekf, ScalarUpdate, VAR_FLOOR};
use crate::math::{wrap_pi, Mat3, Mat6};

/// The previous fix's noise states (see the module doc), and the heading error of the
/// update in progress.
#[derive(Debug, Clone, Copy, Default)]
pub struct FixNoise {
    /// Posterior mean of q (m/s).
    mean: [f32; 2],
    /// `C[j][k] = cov(x_k, q_j)`.
    cross: [[f32; 6]; 2],
    /// `V = cov(q)`, (m/s)².
    var: [[f32; 2]; 2],
    /// Whether q belongs to the fix the next difference starts from.
    valid: bool,
    /// The heading error e of this update (rad): mean, cov(x, e), cov(q, e), var e.
    e_mean: f32,
    e_cross: [f32; 6],
    e_q: [f32; 2],
    e_var: f32,
}

/// One measurement's coupling to the noise states: `z = xᵢ + h·(n − qᵢ) + k·e + w`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Coupling {
    /// `h = gain/Δt`, rad per m/s (0: no fix noise, e.g. yaw).
    pub h: f32,
    /// Variance of the new fix's projected velocity noise n, (m/s)² (with `h ≠ 0`).
    pub fresh_var: f32,
    /// `k`: rad of measurement per rad of heading error (1 for the yaw measurement whose
    /// course also rotated the GPS acceleration).
    pub k: f32,
    /// The measurement's variance were every noise taken as white and independent, rad²
    /// (for the updates that cannot use the states: initialisation, gate recovery).
    pub white_var: f32,
}

impl FixNoise {
    /// The next difference does not share a fix with the last one (a re-seed, an
    /// outage, disjoint pairs): q starts over from its prior.
    pub fn reset(&mut self) {
        self.valid = false;
    }

    /// Brings C to the time of the update that is about to run: `C ← Φ·C` with the
    /// first-order transition `Φ = I + F·Δt` of the interval (`a`, `b`: the blocks of F,
    /// see `process::linearize`; `inv_tau` as in the bias model). If q is not valid
    /// (first difference after a re-seed), it becomes the prior: mean 0, variance
    /// `prev_var` (the previous fix's per-component velocity variance, (m/s)²) on both.
    /// `heading_var`: the prior variance of this update's heading error e (rad²).
    pub fn begin(
        &mut self,
        a: &Mat3,
        b: &Mat3,
        inv_tau: f32,
        dt: f32,
        prev_var: f32,
        heading_var: f32,
    ) {
        self.e_mean = 0.0;
        self.e_cross = [0.0; 6];
        self.e_q = [0.0; 2];
        self.e_var = heading_var;
        if !self.valid {
            self.mean = [0.0; 2];
            self.cross = [[0.0; 6]; 2];
            self.var = [[prev_var, 0.0], [0.0, prev_var]];
            self.valid = true;
            return;
        }
        let decay = 1.0 - inv_tau * dt;
        // F·c with A's and B's structural zeros left out (A's third column and A₁₁ are 0,
        // B's first column is [−1, 0, 0]ᵀ; `x * 0.0` does not fold in IEEE arithmetic): this
        // runs in the update interrupt, whose budget is nearly full.
        for c in self.cross.iter_mut() {
            let (c0, c1, b0, b1, b2) = (c[0], c[1], c[3], c[4], c[5]);
            let d0 = a[0][0] * c0 + a[0][1] * c1 - b0 + b[0][1] * b1 + b[0][2] * b2;
            let d1 = a[1][0] * c0 + b[1][1] * b1 + b[1][2] * b2;
            let d2 = a[2][0] * c0 + a[2][1] * c1 + b[2][1] * b1 + b[2][2] * b2;
            c[0] += d0 * dt;
            c[1] += d1 * dt;
            c[2] += d2 * dt;
            if inv_tau != 0.0 {
                for v in &mut c[3..6] {
                    *v *= decay;
                }
            }
        }
    }

    /// Sequential scalar update of attitude axis `i` with measurement `z` (rad, referred
    /// to now), white variance `r` (rad²) and χ² gate `gate`, on the filter augmented by
    /// the noise states, coupled to them by `c` (all zero: not at all — the update still
    /// corrects the states through their correlation with x). With a fix-noise coupling
    /// (`h ≠ 0`, roll and pitch), the new fix's noise replaces `qᵢ` whether or not the
    /// update applies (gated: its prior).
    pub fn update_axis(
        &mut self,
        ekf: &mut Ekf,
        i: usize,
        z: f32,
        r: f32,
        c: Coupling,
        gate: f32,
    ) -> ScalarUpdate {
        // Two copies: without a fix-noise coupling (yaw) every `h·…` term is known to be
        // zero, which `h * x` with a runtime h = 0 cannot tell the compiler (x may be NaN).
        if i < 2 && c.h != 0.0 {
            self.update_axis_as::<true>(ekf, i, z, r, c, gate)
        } else {
            self.update_axis_as::<false>(ekf, i, z, r, c, gate)
        }
    }

    #[inline(always)]
    fn update_axis_as<const OWN: bool>(
        &mut self,
        ekf: &mut Ekf,
        i: usize,
        z: f32,
        r: f32,
        c: Coupling,
        gate: f32,
    ) -> ScalarUpdate {
        let k = c.k;
        let qi = if OWN { i } else { 0 };
        // h·v, dropped entirely without a coupling.
        let h = |v: f32| if OWN { c.h * v } else { 0.0 };
        // Columns of P_aug·Hᵀ with H = [eᵢ, −h on qᵢ, +h on n, +k on e].
        let col_x: [f32; 6] =
            core::array::from_fn(|m| ekf.p[m][i] - h(self.cross[qi][m]) + k * self.e_cross[m]);
        let col_q: [f32; 2] =
            core::array::from_fn(|m| self.cross[m][i] - h(self.var[m][qi]) + k * self.e_q[m]);
        let col_n = h(c.fresh_var);
        let col_e = self.e_cross[i] - h(self.e_q[qi]) + k * self.e_var;
        let s = col_x[i] - h(col_q[qi]) + h(col_n) + k * col_e + r;
        let nu = wrap_pi(z - ekf.x[i] + h(self.mean[qi]) - k * self.e_mean);
        let finite = libm::fabsf(nu) < f32::INFINITY && s > 0.0 && s < f32::INFINITY;
        if !(finite && nu * nu <= gate * s) {
            if OWN {
                self.forget(i, c.fresh_var);
            }
            return ScalarUpdate { innovation: nu, variance: s, applied: false };
        }
        let inv_s = 1.0 / s;
        let g_x: [f32; 6] = core::array::from_fn(|m| col_x[m] * inv_s);
        let g_q: [f32; 2] = core::array::from_fn(|m| col_q[m] * inv_s);
        let g_n = col_n * inv_s;
        let g_e = col_e * inv_s;
        ekf.apply_gain(&g_x, &col_x, nu);
        for m in 0..2 {
            self.mean[m] += g_q[m] * nu;
            for l in 0..6 {
                self.cross[m][l] -= g_q[m] * col_x[l];
            }
            self.e_q[m] -= g_q[m] * col_e;
        }
        let v01 = self.var[0][1] - g_q[0] * col_q[1];
        self.var[0][0] -= g_q[0] * col_q[0];
        self.var[1][1] -= g_q[1] * col_q[1];
        self.var[0][1] = v01;
        self.var[1][0] = v01;
        self.e_mean += g_e * nu;
        for l in 0..6 {
            self.e_cross[l] -= g_e * col_x[l];
        }
        let ve = self.e_var - g_e * col_e;
        self.e_var = if ve < VAR_FLOOR { VAR_FLOOR } else { ve };
        if OWN {
            // n replaces qᵢ: its posterior mean, cross-covariances and variance.
            let o = 1 - i;
            self.mean[i] = g_n * nu;
            for l in 0..6 {
                self.cross[i][l] = -g_n * col_x[l];
            }
            let vn = c.fresh_var - g_n * col_n;
            self.var[i][i] = if vn < VAR_FLOOR { VAR_FLOOR } else { vn };
            let von = -g_n * col_q[o];
            self.var[i][o] = von;
            self.var[o][i] = von;
            self.e_q[i] = -g_n * col_e;
        }
        ScalarUpdate { innovation: nu, variance: s, applied: true }
    }

    /// The new fix's noise on axis `i` (0 roll, 1 pitch) was not measured: it replaces
    /// `qᵢ` with its prior (mean 0, variance `fresh_var`, uncorrelated).
    pub fn forget(&mut self, i: usize, fresh_var: f32) {
        let o = 1 - i;
        self.mean[i] = 0.0;
        self.cross[i] = [0.0; 6];
        self.var[i] = [0.0; 2];
        self.var[i][i] = fresh_var;
        self.var[o][i] = 0.0;
        self.e_q[i] = 0.0;
    }

    /// The pitch was reflected over the top (`Ekf::flips`): its error changed sign, and
    /// so does its cross-covariance with q.
    pub fn flip_pitch(&mut self) {
        self.cross[0][1] = -self.cross[0][1];
        self.cross[1][1] = -self.cross[1][1];
        self.e_cross[1] = -self.e_cross[1];
    }

    /// Keeps the augmented covariance `[[P, Cᵀ], [C, V]]` positive definite, given the
    /// Cholesky factor `l` of P (`Ekf::ensure_positive_definite`); call after
    /// [`FixNoise::begin`]. `begin` carries C over the fix interval with a first-order
    /// transition at one attitude, P is propagated in decimated blocks: near ±90° pitch,
    /// where F holds 1/cos²θ, the two part ways and C can claim more correlation with x
    /// than P and V allow — then the scalar updates subtract more than the variance there
    /// is, P turns indefinite and the gains stop meaning anything. The joint is positive
    /// definite iff `V − YᵀY` is, `Y = L⁻¹Cᵀ`; if the largest generalised eigenvalue λ of
    /// (YᵀY, V) exceeds 0.999, C is scaled by √(0.999/λ) (a shrunk correlation, never a
    /// sign change). Returns whether it did.
    pub fn bound_cross(&mut self, l: &Mat6) -> bool {
        const MAX: f32 = 0.999;
        if !self.valid {
            return false;
        }
        // Y = L⁻¹ Cᵀ, one column per noise state (forward substitution).
        let mut y = [[0.0f32; 6]; 2];
        for (yj, c) in y.iter_mut().zip(self.cross.iter()) {
            for i in 0..6 {
                let mut v = c[i];
                for k in 0..i {
                    v -= l[i][k] * yj[k];
                }
                yj[i] = v / l[i][i];
            }
        }
        let dot = |a: &[f32; 6], b: &[f32; 6]| (0..6).map(|k| a[k] * b[k]).sum::<f32>();
        let (m00, m01, m11) = (dot(&y[0], &y[0]), dot(&y[0], &y[1]), dot(&y[1], &y[1]));
        let (v00, v01, v11) = (self.var[0][0], self.var[0][1], self.var[1][1]);
        // det(M − λV) = aλ² − bλ + c.
        let a = v00 * v11 - v01 * v01;
        let b = m00 * v11 + m11 * v00 - 2.0 * m01 * v01;
        let c = m00 * m11 - m01 * m01;
        if !(a > 0.0 && v00 > 0.0 && b < f32::INFINITY) {
            // V itself is degenerate (or C is not finite): q independent of x.
            let repaired = self.cross != [[0.0; 6]; 2];
            self.cross = [[0.0; 6]; 2];
            return repaired;
        }
        let lambda = (b + crate::math::sqrt((b * b - 4.0 * a * c).max(0.0))) / (2.0 * a);
        if !(lambda > MAX) {
            return false;
        }
        let k = crate::math::sqrt(MAX / lambda);
        for c in self.cross.iter_mut() {
            for v in c.iter_mut() {
                *v *= k;
            }
        }
        true
    }

    /// Drops the correlation of q with attitude axis `i` (the axis was reset or inflated).
    pub fn decorrelate(&mut self, i: usize) {
        self.cross[0][i] = 0.0;
        self.cross[1][i] = 0.0;
        self.e_cross[i] = 0.0;
    }
}
