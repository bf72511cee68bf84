//! Low-noise airspeed derivative V̇a for EKF2: least-squares line through the last
//! N airspeed samples, with their real timestamps. (The thesis' eq 5.10 4-point
//! difference was lost from the excerpt; a least-squares slope is its
//! well-founded generalisation and handles irregular sampling.)

/// Largest window the buffer holds.
pub const MAX_WINDOW: usize = 16;

/// Ring buffer of (time µs, airspeed m/s) with a least-squares slope.
#[derive(Debug, Clone, Copy)]
pub struct VaSlope {
    t: [u64; MAX_WINDOW],
    v: [f32; MAX_WINDOW],
    len: usize,
    head: usize,
}

impl Default for VaSlope {
    fn default() -> Self {
        VaSlope { t: [0; MAX_WINDOW], v: [0.0; MAX_WINDOW], len: 0, head: 0 }
    }
}

/// Airspeed and its rate at the newest sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VaEstimate {
    /// Fitted airspeed at the newest sample time, m/s.
    pub va: f32,
    /// Slope, m/s².
    pub va_dot: f32,
    /// Time of the newest sample, µs.
    pub t_us: u64,
}

impl VaSlope {
    /// Adds a sample (time must increase; older or equal times reset the window).
    pub fn push(&mut self, t_us: u64, va: f32) {
        if self.len > 0 {
            let newest = self.t[(self.head + MAX_WINDOW - 1) % MAX_WINDOW];
            if t_us <= newest {
                self.len = 0;
            }
        }
        self.t[self.head] = t_us;
        self.v[self.head] = va;
        self.head = (self.head + 1) % MAX_WINDOW;
        self.len = (self.len + 1).min(MAX_WINDOW);
    }

    /// Clears the window.
    pub fn reset(&mut self) {
        self.len = 0;
    }

    /// The fit over the last `window` samples (at least 2 are needed).
    pub fn estimate(&self, window: usize) -> Option<VaEstimate> {
        let n = window.clamp(2, MAX_WINDOW).min(self.len);
        if n < 2 {
            return None;
        }
        let newest = (self.head + MAX_WINDOW - 1) % MAX_WINDOW;
        let t0 = self.t[newest];
        // Times relative to the newest sample keep f32 precision over long flights.
        let (mut st, mut sv) = (0.0f32, 0.0f32);
        for k in 0..n {
            let i = (newest + MAX_WINDOW - k) % MAX_WINDOW;
            st += -((t0 - self.t[i]) as f32) * 1e-6;
            sv += self.v[i];
        }
        let (mt, mv) = (st / n as f32, sv / n as f32);
        let (mut stt, mut stv) = (0.0f32, 0.0f32);
        for k in 0..n {
            let i = (newest + MAX_WINDOW - k) % MAX_WINDOW;
            let dt = -((t0 - self.t[i]) as f32) * 1e-6 - mt;
            stt += dt * dt;
            stv += dt * (self.v[i] - mv);
        }
        if !(stt > 0.0) {
            return None;
        }
        let slope = stv / stt;
        Some(VaEstimate { va: mv - slope * mt, va_dot: slope, t_us: t0 })
    }
}
