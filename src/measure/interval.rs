//! Pairs IMU data with GPS epochs (docs/design.md, EKF1): the GPS velocity difference is the
//! mean acceleration over the interval between two fixes, so the accelerometer (and
//! the predicted attitude it is compared against) are averaged over the same
//! interval. A receiver delivers each fix `latency` after its epoch; a short delay
//! line holds the newest IMU samples back by that latency before they enter the
//! interval sums, so both sides cover the same window.

use crate::math::{wrap_pi, Vec3};

/// Samples the delay line holds: 0.3 s at 160 Hz. A longer latency is capped to it.
pub const DELAY_SLOTS: usize = 48;

#[derive(Debug, Clone, Copy, Default)]
struct Slot {
    t_us: u64,
    accel: Vec3,
    att: Vec3,
}

/// Interval means at a GPS epoch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IntervalMean {
    /// Mean specific force over the interval, m/s², body FRD.
    pub accel: Vec3,
    /// Squared standard error of `accel` (sample variance / n), (m/s²)²: how much of the
    /// mean is noise. Squared because every user squares it (no √ in the interrupt);
    /// [`IntervalMean::accel_sem`] gives the standard error itself.
    pub accel_sem_sq: Vec3,
    /// Mean predicted attitude over the interval (roll, pitch, yaw), rad.
    pub att: Vec3,
    /// The newest sample that entered the interval (for latest-sample pairing).
    pub latest_accel: Vec3,
    /// The attitude at that sample.
    pub latest_att: Vec3,
}

impl IntervalMean {
    /// Standard error of `accel` (sample σ / √n), m/s².
    #[cfg(any(test, feature = "internals"))]
    pub fn accel_sem(&self) -> Vec3 {
        self.accel_sem_sq.map(crate::math::sqrt)
    }
}

/// Delay line plus running interval sums. O(1) per sample, fixed memory.
#[derive(Debug, Clone, Copy)]
pub struct IntervalAccumulator {
    delay_us: u64,
    ring: [Slot; DELAY_SLOTS],
    head: usize,
    len: usize,
    acc_sum: Vec3,
    acc_sq_sum: Vec3,
    att_ref: Vec3,
    att_off_sum: Vec3,
    n: u32,
    latest: Slot,
    // The last sample of the previous interval: the boundary shared by two intervals.
    boundary: Option<Slot>,
}

impl IntervalAccumulator {
    /// An accumulator whose IMU samples lag by `latency_s` (the receiver's delay).
    pub fn new(latency_s: f32) -> Self {
        IntervalAccumulator {
            delay_us: (latency_s.max(0.0) * 1e6) as u64,
            ring: [Slot::default(); DELAY_SLOTS],
            head: 0,
            len: 0,
            acc_sum: [0.0; 3],
            acc_sq_sum: [0.0; 3],
            att_ref: [0.0; 3],
            att_off_sum: [0.0; 3],
            n: 0,
            latest: Slot::default(),
            boundary: None,
        }
    }

    /// Adds an IMU sample (time, specific force, predicted attitude after the step).
    pub fn push(&mut self, t_us: u64, accel: Vec3, att: Vec3) {
        // No latency (the default) and nothing held back: the sample is due at once, so it
        // skips the ring (same sums, no slot write and read back every IMU sample).
        if self.delay_us == 0 && self.len == 0 {
            self.accumulate(Slot { t_us, accel, att });
            return;
        }
        if self.len == DELAY_SLOTS {
            self.drain_one();
        }
        self.ring[(self.head + self.len) % DELAY_SLOTS] = Slot { t_us, accel, att };
        self.len += 1;
        let due = t_us.saturating_sub(self.delay_us);
        while self.len > 0 && self.ring[self.head].t_us <= due {
            self.drain_one();
        }
    }

    fn drain_one(&mut self) {
        let s = self.ring[self.head];
        self.head = (self.head + 1) % DELAY_SLOTS;
        self.len -= 1;
        self.accumulate(s);
    }

    /// Adds a due sample to the interval sums (inlined: a call passes the slot through
    /// memory, which cost more than the sums on the host).
    #[inline(always)]
    fn accumulate(&mut self, s: Slot) {
        if self.n == 0 {
            self.att_ref = s.att;
            self.acc_sum = [0.0; 3];
            self.acc_sq_sum = [0.0; 3];
            self.att_off_sum = [0.0; 3];
        }
        for i in 0..3 {
            self.acc_sum[i] += s.accel[i];
            self.acc_sq_sum[i] += s.accel[i] * s.accel[i];
        }
        // Offsets from the interval's first attitude: wrap-around cannot bias the mean
        // (pitch lives in [−π/2, π/2]: its offsets need no wrap).
        self.att_off_sum[0] += wrap_pi(s.att[0] - self.att_ref[0]);
        self.att_off_sum[1] += s.att[1] - self.att_ref[1];
        self.att_off_sum[2] += wrap_pi(s.att[2] - self.att_ref[2]);
        self.n += 1;
        self.latest = s;
    }

    /// The means over the interval since the last call, and starts a new interval.
    /// `None` if no sample has entered the interval.
    ///
    /// Trapezoidal weights: the samples at the two ends of the interval count half, so
    /// the mean is centred on the interval's midpoint like the GPS difference (a plain
    /// mean over (t₀, t₁] is half a sample late: ~0.14° of yaw in a 0.5 rad/s turn).
    pub fn take(&mut self) -> Option<IntervalMean> {
        if self.n == 0 {
            return None;
        }
        let n = self.n as f32;
        // One division (the rest multiply: a division is a long-latency instruction on both
        // the host and the M4F).
        let inv_n = 1.0 / n;
        self.n = 0;
        let r = self.att_ref;
        let (mut acc, mut off) = (self.acc_sum, self.att_off_sum);
        if let Some(b) = self.boundary {
            for i in 0..3 {
                acc[i] += 0.5 * (b.accel[i] - self.latest.accel[i]);
                off[i] += 0.5 * (wrap_pi(b.att[i] - r[i]) - wrap_pi(self.latest.att[i] - r[i]));
            }
        }
        self.boundary = Some(self.latest);
        let sem_sq = |i: usize| {
            let m = self.acc_sum[i] * inv_n;
            let var = self.acc_sq_sum[i] * inv_n - m * m;
            // Not `f32::max`: that is a libm call on the M4F (NaN rules); var is finite here.
            if var > 0.0 {
                var * inv_n
            } else {
                0.0
            }
        };
        Some(IntervalMean {
            accel: [acc[0] * inv_n, acc[1] * inv_n, acc[2] * inv_n],
            accel_sem_sq: [sem_sq(0), sem_sq(1), sem_sq(2)],
            att: [
                wrap_pi(r[0] + off[0] * inv_n),
                r[1] + off[1] * inv_n,
                wrap_pi(r[2] + off[2] * inv_n),
            ],
            latest_accel: self.latest.accel,
            latest_att: self.latest.att,
        })
    }

    /// Starts a new interval without returning means (after a re-seed).
    pub fn restart(&mut self) {
        self.n = 0;
        self.boundary = None;
    }
}
