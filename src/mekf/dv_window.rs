//! The IMU side of the GPS velocity difference: the mean specific force in NED over
//! the interval between two fixes, `f̄ = Σ R̂ₖ fₖ Δtₖ / Σ Δtₖ`, and the body-frame
//! statistics of the same samples (mean and its standard error, for the noise model
//! and for alignment). A short delay line holds the newest samples back by the
//! receiver's latency, so both sides of the comparison cover the same window.
//!
//! Summing in NED makes the window indifferent to how much the aircraft rotates
//! inside it (a roll at 300°/s, a loop): no mean attitude is needed.

use crate::math::{max, Vec3};

/// Samples the delay line holds: 0.4 s at 160 Hz. A longer latency is capped to it.
/// A power of two: indices wrap by a mask, with no bounds check left to branch on.
pub const DELAY_SLOTS: usize = 64;
const MASK: usize = DELAY_SLOTS - 1;

/// One held-back sample. Times are µs modulo 2³² (only differences are taken: 32-bit
/// arithmetic is one instruction on the M4F, 64-bit several).
#[derive(Debug, Clone, Copy, Default)]
struct Slot {
    t_us: u32,
    dt_us: u32,
    dv_ned: Vec3,
    dt: f32,
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
    delay_us: u32,
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
    prev: Vec3,
    has_prev: bool,
    nd: u32,
    t: f32,
    n: u32,
}

impl DvWindow {
    /// A window whose samples lag by `latency_s` (the receiver's delay), s.
    pub fn new(latency_s: f32) -> Self {
        DvWindow {
            delay_us: (latency_s.max(0.0) * 1e6) as u32,
            ring: [Slot::default(); DELAY_SLOTS],
            head: 0,
            len: 0,
            head_done: 0.0,
            dv: [0.0; 3],
            f: [0.0; 3],
            f2: [0.0; 3],
            d2: [0.0; 3],
            prev: [0.0; 3],
            has_prev: false,
            nd: 0,
            t: 0.0,
            n: 0,
        }
    }

    /// Changes the delay to `latency_s` s (the latency tracker's new estimate). Samples
    /// already released stay in the open window.
    pub fn set_delay(&mut self, latency_s: f32) {
        self.delay_us = (max(latency_s, 0.0) * 1e6) as u32;
    }

    /// Adds one IMU sample: its NED velocity increment `dv_ned` (m/s), body specific
    /// force `f_body` (m/s²) and length `dt` (s), ending at local time `t_us`. Only the
    /// velocity increment is delayed; the body-frame statistics (noise, slip) need no
    /// latency precision.
    #[inline]
    pub fn push(&mut self, t_us: u64, dv_ned: Vec3, f_body: Vec3, dt: f32) {
        let now = t_us as u32;
        let dt_us = (dt * 1e6) as u32;
        self.add_stats(f_body);
        // A delay under half a sample is none (and costs nothing): the sample goes
        // straight in once the line has emptied.
        let delay = if 2 * self.delay_us < dt_us { 0 } else { self.delay_us };
        if delay == 0 && self.len == 0 {
            self.add_part(dv_ned, dt, 1.0);
            return;
        }
        if self.len == DELAY_SLOTS {
            // Full: the oldest leaves early (latency beyond the line's length).
            self.release_head(1.0);
        }
        self.ring[(self.head + self.len) & MASK] = Slot { t_us: now, dt_us, dv_ned, dt };
        self.len += 1;
        // Everything up to `now − delay` is due; the sample straddling it is split, so a
        // delay that is not a whole number of samples is honoured exactly.
        while self.len > 0 {
            let h = &self.ring[self.head & MASK];
            let (t_end, len_us) = (h.t_us, h.dt_us);
            let since_end = now.wrapping_sub(t_end);
            if since_end >= delay {
                self.release_head(1.0);
                continue;
            }
            let ahead = since_end + len_us; // now − the slot's start
            if ahead > delay {
                let due = (ahead - delay) as f32 / len_us as f32;
                self.release_head(due);
            }
            break;
        }
    }

    /// Brings the head slot's share up to fraction `due` of it; a whole slot leaves.
    #[inline]
    fn release_head(&mut self, due: f32) {
        let h = &self.ring[self.head & MASK];
        let (dv, dt) = (h.dv_ned, h.dt);
        self.add_part(dv, dt, due - self.head_done);
        if due < 1.0 {
            self.head_done = due;
            return;
        }
        self.head_done = 0.0;
        self.head = (self.head + 1) & MASK;
        self.len -= 1;
    }

    /// Adds fraction `k` of a sample's velocity increment `dv` and length `dt`.
    fn add_part(&mut self, dv: Vec3, dt: f32, k: f32) {
        for i in 0..3 {
            self.dv[i] += k * dv[i];
        }
        self.t += k * dt;
    }

    /// Adds a (whole) sample's body specific force to the statistics.
    fn add_stats(&mut self, f: Vec3) {
        // The first sample ever has no predecessor (a restart keeps the last one).
        let k = if self.has_prev { 1.0 } else { 0.0 };
        for i in 0..3 {
            let d = f[i] - self.prev[i];
            self.f[i] += f[i];
            self.f2[i] += f[i] * f[i];
            self.d2[i] += k * d * d;
        }
        self.nd += self.has_prev as u32;
        self.has_prev = true;
        self.prev = f;
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
                let var = max(self.f2[i] * inv_n - mean * mean, 0.0);
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
