//! The innovations' own verdict on P: the recent mean of the GPS acceleration's NIS per
//! degree of freedom. Where it runs above 1 the residuals are larger than P and R
//! explain (an error no state models: latency, accelerometer bias, a bias the update
//! mis-assigned), so the attitude covariance the filter *reports* grows by that ratio.
//! Like [`super::unmodelled`] it is added to the reported covariance only: the gains
//! stay as they are, and the estimate does not change.

/// Memory of the mean, s: long enough that χ² scatter stays near 1 (σ of the mean
/// ≈ √(2/(3N)) over N fixes), short enough to follow a manoeuvre.
const MEMORY_S: f32 = 10.0;
/// One interval counts at most this NIS per degree of freedom: a single outlier (a
/// glitch, a gated jolt) moves the mean by at most `MAX_PER_DOF·dt/MEMORY_S`.
const MAX_PER_DOF: f32 = 25.0;

/// The running mean of NIS per degree of freedom.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Consistency {
    mean: f32,
}

impl Default for Consistency {
    fn default() -> Self {
        Consistency { mean: 1.0 }
    }
}

impl Consistency {
    /// One fused (or gated) interval of `dt` s: its NIS over `dof` degrees of freedom.
    /// A non-finite NIS (S not positive definite) is not counted.
    pub fn observe(&mut self, nis: f32, dof: f32, dt: f32) {
        if !(nis.is_finite() && dof > 0.0 && dt > 0.0) {
            return;
        }
        let x = crate::math::min(nis / dof, MAX_PER_DOF);
        let a = crate::math::min(dt / MEMORY_S, 1.0);
        self.mean += a * (x - self.mean);
    }

    /// The factor on the reported attitude covariance: the mean, never below 1.
    pub fn factor(&self) -> f32 {
        crate::math::max(self.mean, 1.0)
    }

    /// Forgets the history (an alignment: the residuals described another attitude).
    pub fn reset(&mut self) {
        *self = Consistency::default();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Residuals exactly as P predicts (NIS = dof) leave the factor at 1; residuals
    /// twice as large as predicted (NIS = 4·dof) take it to 4 within a few memories;
    /// one gated jolt moves it by at most its clamp.
    #[test]
    fn follows_the_mean_ratio_and_clamps_a_jolt() {
        let mut c = Consistency::default();
        for _ in 0..1000 {
            c.observe(3.0, 3.0, 0.1);
        }
        assert!((c.factor() - 1.0).abs() < 1e-4);
        for _ in 0..500 {
            c.observe(12.0, 3.0, 0.1);
        }
        assert!((c.factor() - 4.0).abs() < 0.05, "{}", c.factor());
        let mut c = Consistency::default();
        c.observe(1e9, 3.0, 0.1);
        assert!(c.factor() <= 1.0 + MAX_PER_DOF * 0.1 / MEMORY_S + 1e-4);
        c.observe(f32::INFINITY, 3.0, 0.1);
        c.observe(f32::NAN, 3.0, 0.1);
        assert!(c.factor().is_finite());
    }
}
