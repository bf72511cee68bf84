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
    dv: Vec3,
    f: Vec3,
    f2: Vec3,
    t: f32,
    n: u32,
}

impl DvWindow {
    /// A window whose samples lag by `latency_s` (the receiver's delay), s.
    pub fn new(latency_s: f32) -> Self {
        DvWindow {
            delay_us: (latency_s.max(0.0) * 1e6) as u64,
            ring: [Slot::default(); DELAY_SLOTS],
            head: 0,
            len: 0,
            dv: [0.0; 3],
            f: [0.0; 3],
            f2: [0.0; 3],
            t: 0.0,
            n: 0,
        }
    }

    /// Adds one IMU sample: its NED velocity increment `dv_ned` (m/s), body specific
    /// force `f_body` (m/s²) and length `dt` (s), at local time `t_us`.
    #[inline]
    pub fn push(&mut self, t_us: u64, dv_ned: Vec3, f_body: Vec3, dt: f32) {
        let slot = Slot { t_us, dv_ned, f_body, dt };
        if self.delay_us == 0 {
            self.add(&slot);
            return;
        }
        if self.len == DELAY_SLOTS {
            // Full: the oldest leaves early (latency beyond the line's length).
            let old = self.ring[self.head];
            self.add(&old);
            self.head = (self.head + 1) % DELAY_SLOTS;
            self.len -= 1;
        }
        self.ring[(self.head + self.len) % DELAY_SLOTS] = slot;
        self.len += 1;
        while self.len > 0 {
            let old = self.ring[self.head];
            if old.t_us.saturating_add(self.delay_us) > t_us {
                break;
            }
            self.add(&old);
            self.head = (self.head + 1) % DELAY_SLOTS;
            self.len -= 1;
        }
    }

    fn add(&mut self, s: &Slot) {
        for i in 0..3 {
            self.dv[i] += s.dv_ned[i];
            self.f[i] += s.f_body[i];
            self.f2[i] += s.f_body[i] * s.f_body[i];
        }
        self.t += s.dt;
        self.n += 1;
    }

    /// Closes the window at a fix and opens the next one; `None` if it holds fewer
    /// than two samples.
    pub fn take(&mut self) -> Option<WindowMean> {
        let (n, t) = (self.n, self.t);
        let out = if n >= 2 && t > 0.0 {
            let inv_t = 1.0 / t;
            let inv_n = 1.0 / n as f32;
            let mut m =
                WindowMean { f_ned: [0.0; 3], f_body: [0.0; 3], sem_sq: [0.0; 3], duration: t };
            for i in 0..3 {
                m.f_ned[i] = self.dv[i] * inv_t;
                let mean = self.f[i] * inv_n;
                m.f_body[i] = mean;
                let var = (self.f2[i] * inv_n - mean * mean).max(0.0);
                m.sem_sq[i] = var / (n - 1) as f32;
            }
            Some(m)
        } else {
            None
        };
        self.dv = [0.0; 3];
        self.f = [0.0; 3];
        self.f2 = [0.0; 3];
        self.t = 0.0;
        self.n = 0;
        out
    }

    /// Drops the open window (after a gap or a re-seed); the delay line is kept.
    pub fn restart(&mut self) {
        let _ = self.take();
    }
}
