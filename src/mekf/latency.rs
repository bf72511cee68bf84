//! The receiver's latency, tracked online (a delay-locked loop on the GPS acceleration).
//!
//! The IMU window is held back by the latency estimate `d`; the receiver's fix describes
//! the aircraft `d₀` ago (its output delay plus its velocity filter's lag). Where the
//! acceleration changes, the GPS-acceleration residual then carries
//! `y ≈ (d − d₀)·ȧ`, with `ȧ` the jerk (NED). Correlating `y` with the jerk of the IMU
//! windows measures `d − d₀` without any model of the aircraft: each interval is one
//! scalar measurement `z = y·ȧ/|ȧ|²` of it, of variance `Σ sᵢ·ȧᵢ²/|ȧ|⁴` (sᵢ the
//! residual's variance per axis without the latency's own share), fused by a one-state
//! Kalman filter. Its variance is the latency's honest σ: large at switch-on (an
//! unknown receiver), small once manoeuvres have measured it, and the GPS acceleration
//! is widened by it (`gps_accel::widen_for_latency`). A fixed step would not do: at
//! 20 Hz a fix difference is ~2 m/s² noisy per axis, so one interval of a 2 m/s³ jerk
//! measures the latency to ±1 s, and a step tuned at 10 Hz walks it over its whole
//! range. Straight flight has no jerk and leaves `d` alone (its variance grows slowly).

use crate::math::{max, min, Mat3, Vec3};

/// Jerk below which an interval says nothing about the latency, m/s³ (GPS-acceleration
/// noise is ~1 m/s² per axis at 10 Hz: a 2 m/s³ jerk shows 0.1 s as 0.2 m/s²).
const MIN_JERK: f32 = 2.0;
/// The prior σ of the latency, s: a receiver's output delay plus its velocity filter's
/// lag, 0–0.3 s, not known before manoeuvres measure it.
const PRIOR_SIGMA: f32 = 0.1;
/// The latency's random walk, s²/s: (0.01 s)² per 10 s (a receiver's filter changes
/// with its dynamic model and its satellites, slowly).
const WALK: f32 = 1e-5;
/// χ² gate of one interval's measurement (1 dof, 99.99 %): a glitch is not a latency.
const GATE: f32 = 15.1;

/// The tracker's state.
#[derive(Debug, Clone, Copy)]
pub struct LatencyTracker {
    /// The estimate, s.
    d: f32,
    /// Its variance, s².
    var: f32,
    /// Largest estimate, s (the delay line's span).
    max: f32,
    /// Largest Kalman gain per interval (0: the latency stays at its configured value).
    gain: f32,
    /// The previous window's mean specific force (NED, m/s²) and length (s).
    prev: Option<(Vec3, f32)>,
}

impl LatencyTracker {
    /// Starts at `initial` s (σ [`PRIOR_SIGMA`]), its gain capped at `gain`, the estimate at
    /// `max` s.
    pub fn new(initial: f32, gain: f32, max: f32) -> Self {
        let max = max.max(0.0);
        let var = if gain > 0.0 { PRIOR_SIGMA * PRIOR_SIGMA } else { 0.0 };
        LatencyTracker { d: initial.max(0.0).min(max), var, max, gain, prev: None }
    }

    /// The latency estimate, s.
    pub fn value(&self) -> f32 {
        self.d
    }

    /// The variance of the estimate, s² (0 when not tracked).
    pub fn variance(&self) -> f32 {
        self.var
    }

    /// The jerk between the previous window and this one (mean specific force `f`, NED,
    /// m/s², over `t` s); `None` without a previous window.
    pub fn jerk(&self, f: Vec3, t: f32) -> Option<Jerk> {
        self.prev.map(|(f0, t0)| jerk_between(f0, t0, f, t))
    }

    /// Forgets the previous window (after a gap: its jerk would span the gap).
    pub fn restart(&mut self) {
        self.prev = None;
    }

    /// One accepted interval: the residual `y` (NED, m/s², before the update), `s` its
    /// variance per axis ((m/s²)², the update's S) with the latency variance (s²) that S
    /// was widened by (`σ_d²·ȧᵢ²` per axis, taken out again here), the window's mean
    /// specific force `f` (NED, m/s²), the variance of that mean from noise and vibration
    /// summed over the axes `f_var` ((m/s²)²), and its length `t` (s); `vertical`
    /// whether `y[2]` is measured; `jerk` what [`LatencyTracker::jerk`] gave for this
    /// window (the update's noise model took it first: not computed twice). Returns
    /// whether the estimate moved.
    #[allow(clippy::too_many_arguments)]
    pub fn observe(
        &mut self,
        y: Vec3,
        s: (Vec3, f32),
        f: Vec3,
        f_var: f32,
        t: f32,
        vertical: bool,
        jerk: Option<Jerk>,
    ) -> bool {
        self.prev = Some((f, t));
        if self.gain <= 0.0 {
            return false;
        }
        self.var = min(self.var + WALK * t, PRIOR_SIGMA * PRIOR_SIGMA);
        let Some(Jerk { mut j, inv }) = jerk else {
            return false;
        };
        if !vertical {
            j[2] = 0.0;
        }
        let j2 = j[0] * j[0] + j[1] * j[1] + j[2] * j[2];
        if j2 < MIN_JERK * MIN_JERK {
            return false;
        }
        // This window's noise is in both y (as −f) and j (as +f·inv): E[y·j] carries
        // −f_var·inv, which would bias d upwards (vibration made that 0.1 s).
        let axes = if vertical { 1.0 } else { 2.0 / 3.0 };
        let yj = y[0] * j[0] + y[1] * j[1] + y[2] * j[2] + axes * f_var * inv;
        let inv_j2 = 1.0 / j2;
        let z = yj * inv_j2;
        // Only on informative intervals (the rest return above): the M4F's GPS-update sample.
        let (s_diag, lat_var) = s;
        let sj: f32 = (0..3)
            .map(|i| {
                let j2i = j[i] * j[i];
                max(s_diag[i] - lat_var * j2i, 0.0) * j2i
            })
            .sum();
        let r = sj * inv_j2 * inv_j2;
        let sz = self.var + r;
        if !(z * z <= GATE * sz) {
            return false;
        }
        let k = min(self.var / sz, self.gain);
        // min/max, not clamp: clamp's assertion would pull float formatting into flash.
        self.d = min(max(self.d - k * z, 0.0), self.max);
        self.var *= 1.0 - k;
        true
    }
}

/// The jerk between two consecutive windows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Jerk {
    /// The jerk, m/s³ NED.
    pub j: Vec3,
    /// The inverse of the time between the windows' centres, 1/s.
    pub inv: f32,
}

/// The jerk from window means `f0` (over `t0` s) to `f` (over `t` s).
fn jerk_between(f0: Vec3, t0: f32, f: Vec3, t: f32) -> Jerk {
    let inv = 2.0 / max(t + t0, 1e-3);
    Jerk { j: [(f[0] - f0[0]) * inv, (f[1] - f0[1]) * inv, (f[2] - f0[2]) * inv], inv }
}

impl super::QuatAhrs {
    /// The attitude at the epoch of the newest fix, `gps_latency` ago: the present one
    /// turned back about NED down by the heading rate (the course is compared near
    /// wings-level, where that is the whole of the change). In a 13°/s turn a 0.2 s
    /// receiver delay is 2.6° of heading.
    pub(super) fn dcm_at_epoch(&self) -> Mat3 {
        let r = self.ekf.dcm();
        let w = self.body_rates();
        let psi_dot = r[2][0] * w[0] + r[2][1] * w[1] + r[2][2] * w[2];
        let (s, c) = crate::math::sincos(-psi_dot * self.latency.value());
        let mut out = *r;
        for j in 0..3 {
            out[0][j] = c * r[0][j] - s * r[1][j];
            out[1][j] = s * r[0][j] + c * r[1][j];
        }
        out
    }

    /// [`Self::dcm_at_epoch`] once per fix interval: the wind and the course read it after
    /// the last change of the attitude (the alignment or the GPS acceleration), and nothing
    /// they do before their last read moves it.
    pub(super) fn epoch_dcm(&self, cache: &mut EpochDcm) -> Mat3 {
        *cache.0.get_or_insert_with(|| self.dcm_at_epoch())
    }
}

/// The attitude at the newest fix's epoch, computed on first use in a fix interval
/// ([`super::QuatAhrs::epoch_dcm`]): a sine and cosine on the M4F's GPS-update sample.
#[derive(Debug, Default)]
pub(super) struct EpochDcm(Option<Mat3>);

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{rngs::StdRng, Rng, SeedableRng};

    /// A forward model of the residual: `y = (d − d₀)·ȧ + n`, n white with σ `noise` per
    /// axis, the jerk a rotating horizontal vector of `jerk` m/s³ (a turn). Returns the
    /// tracker after `n` intervals and the largest |d − d₀| over the last half.
    fn track(d0: f32, noise: f32, jerk: f32, n: usize, seed: u64) -> (LatencyTracker, f32) {
        let mut rng = StdRng::seed_from_u64(seed);
        let mut t = LatencyTracker::new(0.0, 0.3, 0.3);
        let mut worst = 0.0f32;
        for k in 0..n {
            let a = 0.3 * k as f32;
            let j = [jerk * libm::cosf(a), jerk * libm::sinf(a), 0.0];
            let g = |rng: &mut StdRng| noise * (rng.gen::<f32>() + rng.gen::<f32>() + rng.gen::<f32>() - 1.5) * 2.0;
            let e = t.value() - d0;
            let y = [e * j[0] + g(&mut rng), e * j[1] + g(&mut rng), g(&mut rng)];
            let s = ([noise * noise + t.variance() * jerk * jerk; 3], t.variance());
            t.observe(y, s, [0.0; 3], 0.0, 0.05, true, Some(Jerk { j, inv: 20.0 }));
            if k >= n / 2 {
                worst = worst.max((t.value() - d0).abs());
            }
        }
        (t, worst)
    }

    /// At 20 Hz a fix difference is ~2 m/s² noisy per axis: the tracker settles on the
    /// true latency with a σ that says how well it knows it, and stays there.
    #[test]
    fn the_latency_is_learnt_with_an_honest_variance() {
        for seed in 0..5 {
            let (t, worst) = track(0.16, 2.0, 4.0, 400, seed);
            let sd = t.variance().sqrt();
            assert!(sd < 0.05, "σ {sd} s after 400 informative intervals");
            assert!((t.value() - 0.16).abs() < 3.0 * sd + 0.005, "{} vs 0.16 (σ {sd})", t.value());
            assert!(worst < 0.08, "wandered {worst} s off in the second half");
        }
        // Before any manoeuvre it is the prior, with the prior's σ.
        let t = LatencyTracker::new(0.05, 0.3, 0.3);
        assert_eq!(t.value(), 0.05);
        assert!((t.variance().sqrt() - PRIOR_SIGMA).abs() < 1e-6);
        // Tracking off: no variance, no movement.
        let (off, _) = {
            let mut t = LatencyTracker::new(0.05, 0.0, 0.3);
            let j = Some(Jerk { j: [5.0, 0.0, 0.0], inv: 20.0 });
            t.observe([1.0; 3], ([0.1; 3], 0.0), [0.0; 3], 0.0, 0.05, true, j);
            (t, 0)
        };
        assert_eq!((off.value(), off.variance()), (0.05, 0.0));
    }

    /// The fixed step this replaced (a normalised LMS at gain 0.3, ±0.02 s per interval):
    /// with the same 20 Hz residuals it wanders over much of its range.
    #[test]
    fn a_fixed_step_would_wander_at_20_hz() {
        let mut rng = StdRng::seed_from_u64(1);
        let (d0, noise, jerk) = (0.16f32, 2.0f32, 4.0f32);
        let mut d = 0.0f32;
        let mut worst = 0.0f32;
        for k in 0..400 {
            let a = 0.3 * k as f32;
            let j = [jerk * libm::cosf(a), jerk * libm::sinf(a)];
            let g = |rng: &mut StdRng| noise * (rng.gen::<f32>() + rng.gen::<f32>() + rng.gen::<f32>() - 1.5) * 2.0;
            let y = [(d - d0) * j[0] + g(&mut rng), (d - d0) * j[1] + g(&mut rng)];
            let step = (0.3 * (y[0] * j[0] + y[1] * j[1]) / (jerk * jerk)).clamp(-0.02, 0.02);
            d = (d - step).clamp(0.0, 0.3);
            if k >= 200 {
                worst = worst.max((d - d0).abs());
            }
        }
        let (_, ours) = track(d0, noise, jerk, 400, 1);
        assert!(worst > 2.0 * ours, "fixed step {worst} s vs tracked {ours} s");
    }
}

