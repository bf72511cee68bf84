//! The IMU side of the GPS velocity difference: the mean specific force in NED over
//! the interval between two fixes, `f̄ = Σ R̂ₖ fₖ Δtₖ / Σ Δtₖ`, and the body-frame
//! statistics of the same samples (mean and its standard error, for the noise model
//! and for alignment). A short delay line holds the newest samples back by the
//! receiver's latency, so both sides of the comparison cover the same window.
//!
//! Summing in NED makes the window indifferent to how much the aircraft rotates
//! inside it (a roll at 300°/s, a loop): no mean attitude is needed.

use crate::math::Vec3;

/// Samples the delay line holds: 0.3 s at 160 Hz. A longer latency is capped to it.
pub const DELAY_SLOTS: usize = 48;

#[derive(Debug, Clone, Copy, Default)]
struct Slot {
    t_us: u64,
    dv_ned: Vec3,
    f_body: Vec3,
    dt: f32,
    dt_us: u32,
}

/// The window's means.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowMean {
    /// Mean specific force, NED, m/s².
    pub f_ned: Vec3,
    /// Mean specific force, body FRD, m/s².
    pub f_body: Vec3,
    /// Squared standard error of the body-frame mean, (m/s²)², per axis.
    pub sem_sq: Vec3,
    /// The same from the sample-to-sample scatter only (noise and vibration, not the
    /// manoeuvre), (m/s²)².
    pub noise_sq: Vec3,
    /// Time covered, s.
    pub duration: f32,
}

/// Delay line plus the running sums of the open window. O(1) per sample.
#[derive(Debug, Clone, Copy)]
pub struct DvWindow {
    delay_us: u64,
    ring: [Slot; DELAY_SLOTS],
    head: usize,
    len: usize,
    /// The fraction of the head slot already in the open window.
    head_done: f32,
    dv: Vec3,
    f: Vec3,
    f2: Vec3,
    /// Σ of squared successive differences of `f_body` (noise without the manoeuvre).
    d2: Vec3,
    prev: Option<Vec3>,
    nd: u32,
    t: f32,
    n: u32,
}

impl DvWindow {
    /// A window whose samples lag by `latency_s` (the receiver's delay), s.
    pub fn new(latency_s: f32) -> Self {
        DvWindow {
            delay_us: (latency_s.max(0.0) * 1e6) as u32 as u64,
            ring: [Slot::default(); DELAY_SLOTS],
            head: 0,
            len: 0,
            head_done: 0.0,
            dv: [0.0; 3],
            f: [0.0; 3],
            f2: [0.0; 3],
            d2: [0.0; 3],
            prev: None,
            nd: 0,
            t: 0.0,
            n: 0,
        }
    }

    /// Changes the delay to `latency_s` s (the latency tracker's new estimate). Samples
    /// already released stay in the open window.
    pub fn set_delay(&mut self, latency_s: f32) {
        // Through u32: f32 → u64 is a library call on the M4F.
        self.delay_us = (latency_s.max(0.0) * 1e6) as u32 as u64;
    }

    /// Adds one IMU sample: its NED velocity increment `dv_ned` (m/s), body specific
    /// force `f_body` (m/s²) and length `dt` (s), ending at local time `t_us`.
    #[inline]
    pub fn push(&mut self, t_us: u64, dv_ned: Vec3, f_body: Vec3, dt: f32) {
        let slot = Slot { t_us, dv_ned, f_body, dt, dt_us: (dt * 1e6) as u32 };
        if self.delay_us == 0 && self.len == 0 {
            self.add_part(&slot, 1.0);
            self.add_stats(&slot);
            return;
        }
        if self.len == DELAY_SLOTS {
            // Full: the oldest leaves early (latency beyond the line's length).
            let old = self.ring[self.head];
            self.add_part(&old, 1.0 - self.head_done);
            self.pop(&old);
        }
        self.ring[(self.head + self.len) % DELAY_SLOTS] = slot;
        self.len += 1;
        // Everything up to `boundary` is due; the sample straddling it is split, so a
        // delay that is not a whole number of samples is honoured exactly.
        let boundary = t_us.saturating_sub(self.delay_us);
        while self.len > 0 {
            let old = self.ring[self.head];
            let start = old.t_us.saturating_sub(old.dt_us as u64);
            if boundary <= start {
                break;
            }
            let due = if boundary >= old.t_us {
                1.0
            } else {
                (boundary - start) as u32 as f32 / old.dt_us.max(1) as f32
            };
            self.add_part(&old, due - self.head_done);
            if due < 1.0 {
                self.head_done = due;
                break;
            }
            self.pop(&old);
        }
    }

    /// Drops the fully released head slot `s`, adding it to the statistics.
    fn pop(&mut self, s: &Slot) {
        self.add_stats(s);
        self.head_done = 0.0;
        self.head = (self.head + 1) % DELAY_SLOTS;
        self.len -= 1;
    }

    /// Adds fraction `k` of sample `s` to the velocity increment and the duration.
    fn add_part(&mut self, s: &Slot, k: f32) {
        for i in 0..3 {
            self.dv[i] += k * s.dv_ned[i];
        }
        self.t += k * s.dt;
    }

    /// Adds sample `s` (whole) to the body-frame statistics.
    fn add_stats(&mut self, s: &Slot) {
        for i in 0..3 {
            self.f[i] += s.f_body[i];
            self.f2[i] += s.f_body[i] * s.f_body[i];
        }
        if let Some(p) = self.prev {
            for i in 0..3 {
                let d = s.f_body[i] - p[i];
                self.d2[i] += d * d;
            }
            self.nd += 1;
        }
        self.prev = Some(s.f_body);
        self.n += 1;
    }

    /// Closes the window at a fix and opens the next one; `None` if it holds fewer
    /// than two samples.
    pub fn take(&mut self) -> Option<WindowMean> {
        let (n, t) = (self.n, self.t);
        let out = if n >= 2 && t > 0.0 {
            let inv_t = 1.0 / t;
            let inv_n = 1.0 / n as f32;
            let inv_nd = 0.5 / self.nd.max(1) as f32;
            let mut m = WindowMean {
                f_ned: [0.0; 3],
                f_body: [0.0; 3],
                sem_sq: [0.0; 3],
                noise_sq: [0.0; 3],
                duration: t,
            };
            for i in 0..3 {
                m.f_ned[i] = self.dv[i] * inv_t;
                let mean = self.f[i] * inv_n;
                m.f_body[i] = mean;
                let var = (self.f2[i] * inv_n - mean * mean).max(0.0);
                m.sem_sq[i] = var / (n - 1) as f32;
                // Successive differences: white noise gives E[Δf²] = 2σ², a manoeuvre
                // (smooth at the IMU rate) almost nothing.
                m.noise_sq[i] = self.d2[i] * inv_nd * inv_n;
            }
            Some(m)
        } else {
            None
        };
        self.dv = [0.0; 3];
        self.f = [0.0; 3];
        self.f2 = [0.0; 3];
        self.d2 = [0.0; 3];
        self.nd = 0;
        self.t = 0.0;
        self.n = 0;
        out
    }

    /// Drops the open window (after a gap or a re-seed); the delay line is kept.
    pub fn restart(&mut self) {
        let _ = self.take();
    }
}
