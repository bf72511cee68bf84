//! The receiver's latency, tracked online (a delay-locked loop on the GPS acceleration).
//!
//! The IMU window is held back by the latency estimate `d`; the receiver's fix describes
//! the aircraft `d₀` ago (its output delay plus its velocity filter's lag). Where the
//! acceleration changes, the GPS-acceleration residual then carries
//! `y ≈ (d − d₀)·ȧ`, with `ȧ` the jerk (NED). Correlating `y` with the jerk of the IMU
//! windows measures `d − d₀` without any model of the aircraft; a normalised LMS step
//! moves `d` towards `d₀`. Straight flight has no jerk and leaves `d` alone.

use crate::math::{max, min, Mat3, Vec3};

/// Jerk below which an interval says nothing about the latency, m/s³ (GPS-acceleration
/// noise is ~1 m/s² per axis at 10 Hz: a 2 m/s³ jerk shows 0.1 s as 0.2 m/s²).
const MIN_JERK: f32 = 2.0;
/// How far above its own noise variance an interval's |jerk|² must be to count.
const JERK_SNR2: f32 = 9.0;
/// σ of a receiver's latency before the tracker has seen it, s.
const UNTRACKED_SIGMA: f32 = 0.1;
/// Informative intervals after which the untracked variance has halved.
const SETTLED_N: f32 = 20.0;
/// Weight of an informative interval in the running mean and scatter of the estimate.
const SCATTER_GAIN: f32 = 1.0 / 16.0;

/// The tracker's state.
#[derive(Debug, Clone, Copy)]
pub struct LatencyTracker {
    /// The estimate, s.
    d: f32,
    /// Largest estimate, s (the delay line's span).
    max: f32,
    /// LMS step (0: the latency stays at its configured value).
    gain: f32,
    /// The previous window's mean specific force (NED, m/s²) and length (s).
    prev: Option<(Vec3, f32)>,
    /// Running mean of |jerk|² over the informative intervals, (m/s³)².
    jj: f32,
    /// Informative intervals seen (saturating).
    n: u16,
    /// [`LatencyTracker::untracked_var`], s² (kept: every update reads it, and it changes
    /// only with an informative interval).
    untracked: f32,
    /// Running mean of the estimate over the informative intervals, s.
    mean: f32,
    /// Running mean square of the estimate about `mean`, s².
    scatter: f32,
}

impl LatencyTracker {
    /// Starts at `initial` s, moving by normalised step `gain`, capped at `max` s.
    pub fn new(initial: f32, gain: f32, max: f32) -> Self {
        let max = max.max(0.0);
        let d = initial.max(0.0).min(max);
        let mut t = LatencyTracker {
            d,
            max,
            gain,
            prev: None,
            jj: 0.0,
            n: 0,
            untracked: 0.0,
            mean: d,
            scatter: 0.0,
        };
        t.untracked = t.untracked_of_n();
        t
    }

    /// The latency estimate, s.
    pub fn value(&self) -> f32 {
        self.d
    }

    /// The jerk between the previous window and this one (mean specific force `f`, NED,
    /// m/s², over `t` s); `None` without a previous window.
    pub fn jerk(&self, f: Vec3, t: f32) -> Option<Jerk> {
        self.prev.map(|(f0, t0)| jerk_between(f0, t0, f, t))
    }

    /// The variance of the estimate beyond the configured σ, s²: a receiver's latency is
    /// unknown to `UNTRACKED_SIGMA` until the tracker has seen informative intervals,
    /// shrinking as `1/(1 + n/SETTLED_N)`; or, where larger, the estimate's own scatter
    /// about its running mean (a tracker still wandering; none while the tracker is off).
    pub fn untracked_var(&self) -> f32 {
        self.untracked
    }

    fn untracked_of_n(&self) -> f32 {
        if self.gain <= 0.0 {
            return 0.0;
        }
        UNTRACKED_SIGMA * UNTRACKED_SIGMA / (1.0 + self.n as f32 * (1.0 / SETTLED_N))
    }

    /// Forgets the previous window (after a gap: its jerk would span the gap).
    pub fn restart(&mut self) {
        self.prev = None;
    }

    /// One accepted interval: the residual `y` (NED, m/s², before the update), the
    /// window's mean specific force `f` (NED, m/s²), the variance of that mean from
    /// noise and vibration summed over the axes `f_var` ((m/s²)²), and its length `t`
    /// (s); `vertical` whether `y[2]` is measured; `jerk` what [`LatencyTracker::jerk`]
    /// gave for this window (the update's noise model took it first: not computed twice).
    /// Returns the step the estimate took (s, before the bounds), or `None` where the
    /// interval said nothing.
    pub fn observe(
        &mut self,
        y: Vec3,
        f: Vec3,
        f_var: f32,
        t: f32,
        vertical: bool,
        jerk: Option<Jerk>,
    ) -> Option<f32> {
        self.prev = Some((f, t));
        let Jerk { mut j, inv } = jerk?;
        if self.gain <= 0.0 {
            return None;
        }
        if !vertical {
            j[2] = 0.0;
        }
        let j2 = j[0] * j[0] + j[1] * j[1] + j[2] * j[2];
        // The jerk of two window means carries their noise, `2·f_var·inv²` summed over
        // the axes: at 20 Hz that alone exceeds MIN_JERK, so an interval must stand
        // JERK_SNR² above it.
        let axes = if vertical { 1.0 } else { 2.0 / 3.0 };
        let f_inv = axes * f_var * inv;
        if j2 < MIN_JERK * MIN_JERK || j2 < 2.0 * JERK_SNR2 * f_inv * inv {
            return None;
        }
        // y·j ≈ (d − d₀)|j|²; normalised by the running |j|² so one violent interval
        // moves d no more than a run of ordinary ones.
        self.jj = if self.jj > 0.0 { self.jj + 0.05 * (j2 - self.jj) } else { j2 };
        // This window's noise is in both y (as −f) and j (as +f·inv): E[y·j] carries
        // −f_var·inv, which would bias d upwards (vibration made that 0.1 s).
        let yj = y[0] * j[0] + y[1] * j[1] + y[2] * j[2] + f_inv;
        let step = (self.gain * yj / max(self.jj, j2)).clamp(-0.02, 0.02);
        // min/max, not clamp: clamp's assertion would pull float formatting into flash.
        self.d = min(max(self.d - step, 0.0), self.max);
        self.n = self.n.saturating_add(1);
        let e = self.d - self.mean;
        self.mean += SCATTER_GAIN * e;
        self.scatter += SCATTER_GAIN * (e * e - self.scatter);
        self.untracked = max(self.untracked_of_n(), self.scatter);
        Some(step)
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

    /// The untracked variance starts at `UNTRACKED_SIGMA²`, halves after `SETTLED_N`
    /// informative intervals, never counts an interval without jerk, and is zero with
    /// the tracker off.
    #[test]
    fn the_untracked_latency_variance_shrinks_with_informative_intervals() {
        let mut t = LatencyTracker::new(0.0, 0.3, 0.3);
        assert!((t.untracked_var() - UNTRACKED_SIGMA * UNTRACKED_SIGMA).abs() < 1e-9);
        let f = [0.0, 0.0, -9.8];
        let jerk = Some(Jerk { j: [5.0, 0.0, 0.0], inv: 0.0 });
        t.observe([0.0; 3], f, 0.0, 0.1, true, Some(Jerk { j: [0.0; 3], inv: 0.0 }));
        assert!((t.untracked_var() - UNTRACKED_SIGMA * UNTRACKED_SIGMA).abs() < 1e-9);
        for _ in 0..SETTLED_N as usize {
            assert!(t.observe([0.0; 3], f, 0.0, 0.1, true, jerk).is_some());
        }
        let half = 0.5 * UNTRACKED_SIGMA * UNTRACKED_SIGMA;
        assert!((t.untracked_var() - half).abs() < 1e-7, "{}", t.untracked_var());
        assert_eq!(LatencyTracker::new(0.1, 0.0, 0.3).untracked_var(), 0.0);
    }

    /// A jerk no larger than the window means' own noise makes (`2·f_var·inv²`, 20 Hz
    /// fixes and a vibrating accelerometer) neither moves the estimate nor counts as
    /// learnt; the same jerk over quiet windows does both.
    #[test]
    fn a_jerk_inside_its_own_noise_teaches_nothing() {
        let mut t = LatencyTracker::new(0.0, 0.3, 0.3);
        let jerk = Some(Jerk { j: [6.0, 0.0, 0.0], inv: 20.0 });
        let y = [-0.6, 0.0, 0.0];
        t.observe([0.0; 3], [0.0, 0.0, -9.8], 0.0, 0.05, true, None);
        // 0.3 m/s² of window noise per axis at 20 Hz: the jerk's noise σ is ~10 m/s³ summed.
        assert!(t.observe(y, [0.0, 0.0, -9.8], 0.27, 0.05, true, jerk).is_none());
        assert_eq!((t.value(), t.untracked_var()), (0.0, UNTRACKED_SIGMA * UNTRACKED_SIGMA));
        assert!(t.observe(y, [0.0, 0.0, -9.8], 0.0, 0.05, true, jerk).is_some());
        assert!(t.value() > 0.0 && t.untracked_var() < UNTRACKED_SIGMA * UNTRACKED_SIGMA);
    }

    /// A tracker that wanders reports at least its own scatter: long after the count of
    /// informative intervals has shrunk the untracked variance, an estimate swinging
    /// between two levels (a residual pushing one way, then the other) keeps a variance
    /// near the sample variance of its last values; a steady one keeps the count's.
    #[test]
    fn a_wandering_latency_estimate_reports_its_scatter() {
        let f = [0.0, 0.0, -9.8];
        let jerk = Some(Jerk { j: [5.0, 0.0, 0.0], inv: 0.0 });
        let (mut wander, mut steady) =
            (LatencyTracker::new(0.1, 0.3, 0.3), LatencyTracker::new(0.1, 0.3, 0.3));
        let mut last = [0.0f32; 64];
        for k in 0..640 {
            // y·j = ±2.5 (m/s²)(m/s³): a step of ∓0.02 s (the clamp) every interval.
            let y = if (k / 8) % 2 == 0 { [-0.5, 0.0, 0.0] } else { [0.5, 0.0, 0.0] };
            wander.observe(y, f, 0.0, 0.1, true, jerk);
            steady.observe([0.0; 3], f, 0.0, 0.1, true, jerk);
            last[k % 64] = wander.value();
        }
        let mean = last.iter().sum::<f32>() / 64.0;
        let var = last.iter().map(|d| (d - mean) * (d - mean)).sum::<f32>() / 64.0;
        let counted = steady.untracked_var();
        assert!(var > 5.0 * counted, "sample variance {var} s², counted {counted} s²");
        let v = wander.untracked_var();
        assert!(v > 0.5 * var && v < 2.0 * var, "reported {v} s², sample variance {var} s²");
    }
}
