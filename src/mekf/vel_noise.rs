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
//! as the specific force changes and the latency error times the jerk; intervals with a
//! jerk whose latency share could reach the noise are not learnt from, so a manoeuvre
//! cannot inflate the estimate.
//!
//! The estimate is a running mean of `ln(|d|²/6n)` (n the axes measured), started from
//! the receiver's report (or `unreported_vel_sigma`) as a prior worth
//! [`PRIOR_WEIGHT`] samples, the weight of the newest sample `1/(n₀ + n)` down to
//! [`MIN_GAIN`]: the log makes one outlier move it by at most `MIN_GAIN·MAX_STEP`,
//! and a report off by 100× is forgotten in tens of fixes, not hundreds. The mean of
//! `ln(χ²ₙ/n)` is `ψ(n/2) + ln(2/n)`, not 0: [`LOG_BIAS`] takes it out.

use crate::math::Vec3;

/// The prior's weight, in samples.
const PRIOR_WEIGHT: f32 = 2.0;
/// The smallest weight of a new sample (a memory of ~64 learnt intervals).
const MIN_GAIN: f32 = 1.0 / 64.0;
/// The largest step of the log-variance per sample (a factor e³ ≈ 20).
const MAX_STEP: f32 = 3.0;
/// `E[ln(χ²ₙ/n)]` for n = 2 and 3 axes: `ψ(1) = −0.5772`, `ψ(3/2) + ln(2/3) = −0.3690`.
const LOG_BIAS: [f32; 2] = [-0.577_215_7, -0.368_98];
/// Bounds of the learnt σ, m/s: a receiver quieter than 5 mm/s or noisier than 3 m/s is
/// not one the estimate can be trusted on.
const MIN_SIGMA: f32 = 0.005;
const MAX_SIGMA: f32 = 3.0;
/// `ln(MIN_SIGMA²)` and `ln(MAX_SIGMA²)` (no `logf` in const context).
const LN_MIN_VAR: f32 = -10.596_635;
const LN_MAX_VAR: f32 = 2.197_224_6;

/// The learner's state.
#[derive(Debug, Clone, Copy, Default)]
pub struct VelNoise {
    /// The learnt log-variance, ln (m/s)².
    log_var: f32,
    /// The learnt variance, (m/s)² (`exp(log_var)`, kept: the hot path reads it).
    var: f32,
    /// Samples learnt from (saturating).
    n: u16,
    /// Whether a prior has been set.
    started: bool,
    /// The previous update's posterior residual, m/s NED, while the next interval
    /// follows on from it.
    prev: Option<Vec3>,
}

impl VelNoise {
    /// The variance in use, (m/s)²: the learnt one, else `prior_sigma²`.
    pub fn variance(&self, prior_sigma: f32) -> f32 {
        if self.started {
            self.var
        } else {
            prior_sigma * prior_sigma
        }
    }

    /// Sets the prior from the receiver's report (or the configured guess), m/s, once.
    pub fn prior(&mut self, sigma: f32) {
        if !self.started {
            let s = sigma.clamp(MIN_SIGMA, MAX_SIGMA);
            self.var = s * s;
            self.log_var = libm::logf(self.var);
            self.n = 0;
            self.started = true;
        }
    }

    /// The next interval does not follow on from the last (a re-seed, an alignment).
    pub fn restart(&mut self) {
        self.prev = None;
    }

    /// One GPS-acceleration update over `dt` s: the prior residual `y` (m/s², NED), the
    /// geometric Jacobian `h` (`−[f̄×]`), the correction it applied `dtheta` (rad NED, 0 if
    /// gated), whether `y[2]` is measured, and whether the interval is calm enough to
    /// learn from. Returns whether the estimate moved.
    pub fn observe(
        &mut self,
        y: Vec3,
        h: &crate::math::Mat3,
        dtheta: Vec3,
        dt: f32,
        vertical: bool,
        calm: bool,
    ) -> bool {
        let u: Vec3 = core::array::from_fn(|i| y[i] * dt);
        let post: Vec3 = core::array::from_fn(|i| {
            u[i] - dt * (h[i][0] * dtheta[0] + h[i][1] * dtheta[1] + h[i][2] * dtheta[2])
        });
        let prev = self.prev.replace(post);
        let Some(p) = prev.filter(|_| calm && self.started) else {
            return false;
        };
        let axes = if vertical { 3 } else { 2 };
        let d2: f32 = (0..axes).map(|i| (u[i] - p[i]) * (u[i] - p[i])).sum();
        let s = d2 / (6.0 * axes as f32);
        if !(s > 0.0 && s.is_finite()) {
            return false;
        }
        let step = (libm::logf(s) - LOG_BIAS[axes - 2] - self.log_var).clamp(-MAX_STEP, MAX_STEP);
        let gain = crate::math::max(1.0 / (PRIOR_WEIGHT + self.n as f32), MIN_GAIN);
        self.n = self.n.saturating_add(1);
        self.log_var = (self.log_var + gain * step).clamp(LN_MIN_VAR, LN_MAX_VAR);
        self.var = libm::expf(self.log_var);
        true
    }

    /// The learnt σ, m/s (the prior's before any sample), or `None` before the prior.
    pub fn sigma(&self) -> Option<f32> {
        self.started.then(|| crate::math::sqrt(self.var))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_bounds_match_the_sigma_bounds() {
        let ln = |s: f32| (s as f64 * s as f64).ln() as f32;
        assert!((LN_MIN_VAR - ln(MIN_SIGMA)).abs() < 1e-5);
        assert!((LN_MAX_VAR - ln(MAX_SIGMA)).abs() < 1e-5);
    }
}
