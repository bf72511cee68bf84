//! The GPS velocity noise, learnt from the fixes themselves.
//!
//! Receivers do not report their velocity accuracy honestly: u-blox `sAcc` is commonly
//! 5–10× the noise seen (a NEO-M8N at rest: 0.18 m/s reported for 0.015 m/s), NMEA
//! reports none, and a filter that takes the report as the truth weighs its best aid
//! 100× too little (docs/design.md, "GPS velocity noise, learnt").
//!
//! The residual of the GPS acceleration in velocity units, `u_k = y_k·Δt_k` (NED, m/s),
//! is `H_k·δθ_k + (e_k − e_{k−1})` plus the IMU's noise, e the fixes' velocity noise. The
//! attitude error moves only with the gyro between updates, so the difference of this
//! residual and the previous update's *posterior* residual `u⁺_{k−1} = u_{k−1} −
//! H_{k−1}·δθ̂_{k−1}Δt` (the correction it applied taken out) cancels it whatever the
//! filter's gains: `u_k − u⁺_{k−1} = e_k − 2e_{k−1} + e_{k−2}`, of variance `6σ²` per
//! axis for white fix noise of σ. What is left of the dynamics is the change of `H·δθ`
//! as the specific force changes, the latency error times the jerk and what no model here
//! holds (the antenna's lever arm in a roll): all of it is what the GPS acceleration must be
//! weighed with, so every interval is learnt from. One manoeuvre cannot move the estimate
//! far (a step is clamped in the log, and weighs 1/64 once settled); sustained aerobatics
//! raise it, as they should (learning from calm intervals only cost the real F3A flights
//! 0.1–0.6° of tilt against their autopilot's EKF3).
//!
//! What is learnt is the *scale* of the report, `k² = σ²/σ_r²`, σ_r the newest fix's speed
//! accuracy (or `unreported_vel_sigma` without one): receivers are wrong about the level
//! of their noise but not about its changes (a u-blox's sAcc rises ~1.5× in aerobatics, with
//! its noise), so the variance in use is `k²·σ_r²` per fix. The estimate is a running mean
//! of `ln(|d|²/(6n·σ_r²))` (n the axes measured), started at k = 1 (the report as given) as
//! a prior worth [`PRIOR_WEIGHT`] samples, the weight of the newest sample `1/(n₀ + n)` down
//! to [`MIN_GAIN`]: the log makes one outlier move it by at most `MIN_GAIN·MAX_STEP`, and a
//! report off by 100× is forgotten in tens of fixes, not hundreds. The mean of `ln(χ²ₙ/n)`
//! is `ψ(n/2) + ln(2/n)`, not 0: [`LOG_BIAS`] takes it out.
//!
//! Before the attitude is aligned there is no residual, but the lengths of the two
//! specific forces need none: `|ā − g| − |f̄|` does not depend on the attitude, and its
//! change between intervals, `f̂·(e_k − 2e_{k−1} + e_{k−2})/Δt`, is one axis of the same
//! statistic ([`VelNoise::observe_lengths`]). So the learner starts while the alignment
//! waits (a steady turn, the first fixes in the air), and the first updates after it are
//! weighed with the receiver's noise rather than its report: the error they leave about
//! the specific force in a steady turn stays until the turn ends.

use crate::math::Vec3;

/// The prior's weight, in samples.
const PRIOR_WEIGHT: f32 = 2.0;
/// The smallest weight of a new sample (a memory of ~64 learnt intervals).
const MIN_GAIN: f32 = 1.0 / 64.0;
/// The largest step of the log-variance per sample (a factor e³ ≈ 20).
const MAX_STEP: f32 = 3.0;
/// `E[ln(χ²ₙ/n)]` for n = 1, 2 and 3 axes: `ψ(1/2) + ln 2 = −1.2704`, `ψ(1) = −0.5772`,
/// `ψ(3/2) + ln(2/3) = −0.3690`.
const LOG_BIAS: [f32; 3] = [-1.270_362_8, -0.577_215_7, -0.368_98];
/// Bounds of the learnt scale k of the report: 1/100 to 10.
#[cfg(test)]
const MIN_SCALE: f32 = 0.01;
#[cfg(test)]
const MAX_SCALE: f32 = 10.0;
/// `ln(MIN_SCALE²)` and `ln(MAX_SCALE²)` (no `logf` in const context).
const LN_MIN_K2: f32 = -9.210_34;
const LN_MAX_K2: f32 = 4.605_17;
/// The smallest σ used, m/s (a report of 0 is not a receiver without noise).
const MIN_SIGMA: f32 = 0.005;

/// The learner's state.
#[derive(Debug, Clone, Copy, Default)]
pub struct VelNoise {
    /// The learnt `ln k²`.
    log_k2: f32,
    /// `k² = exp(log_k2)` (kept: the hot path reads it).
    k2: f32,
    /// Samples learnt from (saturating).
    n: u16,
    /// Whether the scale has been started.
    started: bool,
    /// The newest reference σ_r (the report, or the guess), m/s.
    reference: f32,
    /// The previous update's posterior residual, m/s NED, while the next interval
    /// follows on from it.
    prev: Option<Vec3>,
    /// The previous interval's difference of the specific forces' lengths times its
    /// duration, m/s, while aligning ([`VelNoise::observe_lengths`]).
    prev_lengths: Option<f32>,
}

impl VelNoise {
    /// The variance in use for a fix of reference σ `sigma_r` (its report, or the guess),
    /// (m/s)²: `k²·σ_r²`, k learnt (1 before any sample), σ at least 5 mm/s.
    pub fn variance(&self, sigma_r: f32) -> f32 {
        let s = crate::math::max(sigma_r, MIN_SIGMA);
        let k2 = if self.started { self.k2 } else { 1.0 };
        crate::math::max(k2 * s * s, MIN_SIGMA * MIN_SIGMA)
    }

    /// Sets the newest fix's reference σ (m/s): its report, or the configured guess.
    pub fn reference(&mut self, sigma_r: f32) {
        if !self.started {
            (self.log_k2, self.k2, self.n, self.started) = (0.0, 1.0, 0, true);
        }
        self.reference = crate::math::max(sigma_r, MIN_SIGMA);
    }

    /// The next interval does not follow on from the last (a re-seed, an alignment).
    pub fn restart(&mut self) {
        self.prev = None;
        self.prev_lengths = None;
    }

    /// One GPS-acceleration update over `dt` s: the prior residual `y` (m/s², NED), the
    /// window's mean specific force `f` (m/s², NED), the correction the update applied
    /// `dtheta` (rad NED, 0 if gated) and whether `y[2]` is measured. Returns whether the
    /// estimate moved.
    pub fn observe(&mut self, y: Vec3, f: Vec3, dtheta: Vec3, dt: f32, vertical: bool) -> bool {
        let u: Vec3 = core::array::from_fn(|i| y[i] * dt);
        // The whole correction the update applied, `−[f×]·δθ̂` (not the update's H, whose
        // heading column is zeroed where the heading is not fused), as `f × δθ̂`: the same
        // value as the skew product without its three multiplications by zero.
        let c = [
            f[1] * dtheta[2] - f[2] * dtheta[1],
            f[2] * dtheta[0] - f[0] * dtheta[2],
            f[0] * dtheta[1] - f[1] * dtheta[0],
        ];
        let post: Vec3 = core::array::from_fn(|i| u[i] + dt * c[i]);
        let prev = self.prev.replace(post);
        let Some(p) = prev.filter(|_| self.started) else {
            return false;
        };
        let axes = if vertical { 3 } else { 2 };
        let d2: f32 = (0..axes).map(|i| (u[i] - p[i]) * (u[i] - p[i])).sum();
        self.learn(d2, axes)
    }

    /// One fix interval before the attitude is aligned, of `dt` s: `lengths` =
    /// `|ā − g| − |f̄|`, the GPS specific force's length less the IMU's (m/s², both from
    /// the same interval, all three axes measured). Returns whether the estimate moved.
    pub fn observe_lengths(&mut self, lengths: f32, dt: f32) -> bool {
        let u = lengths * dt;
        let prev = self.prev_lengths.replace(u);
        let Some(p) = prev.filter(|_| self.started) else {
            return false;
        };
        self.learn((u - p) * (u - p), 1)
    }

    /// One sample: `d2`, the squared second difference of the fixes' noise summed over
    /// `axes` axes (m/s)², whose mean is `6·axes·σ²`. Inlined: out of line it cost the
    /// M4F GPS-update sample ~70 instructions.
    #[inline(always)]
    fn learn(&mut self, d2: f32, axes: usize) -> bool {
        let r2 = self.reference * self.reference;
        let s = d2 / (6.0 * axes as f32 * r2);
        if !(s > 0.0 && s.is_finite()) {
            return false;
        }
        let step = (libm::logf(s) - LOG_BIAS[axes - 1] - self.log_k2).clamp(-MAX_STEP, MAX_STEP);
        let gain = crate::math::max(1.0 / (PRIOR_WEIGHT + self.n as f32), MIN_GAIN);
        self.n = self.n.saturating_add(1);
        self.log_k2 = (self.log_k2 + gain * step).clamp(LN_MIN_K2, LN_MAX_K2);
        self.k2 = libm::expf(self.log_k2);
        true
    }

    /// The learnt σ of the newest fix, m/s (`k·σ_r`), or `None` before the first.
    pub fn sigma(&self) -> Option<f32> {
        self.started.then(|| crate::math::sqrt(self.variance(self.reference)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first aligned update after the lengths does not difference against them, and
    /// after a restart (an alignment) neither follows on from before it.
    #[test]
    fn the_residuals_do_not_follow_on_from_the_lengths() {
        let mut vn = VelNoise::default();
        vn.reference(0.05);
        vn.observe_lengths(0.3, 0.1);
        assert!(!vn.observe([0.1, 0.2, 0.0], [0.0, 0.0, -9.8], [0.0; 3], 0.1, true));
        vn.restart();
        assert!(!vn.observe_lengths(0.3, 0.1));
        assert!(vn.observe_lengths(0.2, 0.1));
    }

    #[test]
    fn log_bounds_match_the_scale_bounds() {
        let ln = |s: f32| (s as f64 * s as f64).ln() as f32;
        assert!((LN_MIN_K2 - ln(MIN_SCALE)).abs() < 1e-5);
        assert!((LN_MAX_K2 - ln(MAX_SCALE)).abs() < 1e-5);
    }
}
