//! Low-noise airspeed derivative V̇a for EKF2: airspeed samples are averaged into
//! fixed-length time bins and a least-squares line is fitted through the last N
//! bin means, with their real (mean) timestamps. (The thesis' eq 5.10 4-point
//! difference was lost from the excerpt; N = 4 bins of one GPS interval is its
//! analogue, and the binned least-squares slope handles any airspeed rate and
//! irregular sampling. A raw 100 Hz slope over a few samples amplifies 0.06 m/s
//! noise to ~1 m/s², i.e. ~5° of pitch.)

/// Most bins the window holds.
pub const MAX_BINS: usize = 16;

/// Airspeed and its rate at the newest bin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VaEstimate {
    /// Fitted airspeed at the newest sample time, m/s.
    pub va: f32,
    /// Slope, m/s².
    pub va_dot: f32,
    /// Time of the newest sample, µs.
    pub t_us: u64,
}

/// Binned airspeed history with a least-squares slope.
#[derive(Debug, Clone, Copy)]
pub struct VaSlope {
    bin_us: u64,
    // Closed bins: mean time (µs) and mean airspeed.
    t: [u64; MAX_BINS],
    v: [f32; MAX_BINS],
    len: usize,
    head: usize,
    // The open bin.
    open_start: u64,
    open_t_sum: u64,
    open_v_sum: f32,
    open_n: u32,
    newest_t: u64,
}

impl VaSlope {
    /// A differentiator with bins of `bin_s` seconds.
    pub fn new(bin_s: f32) -> Self {
        VaSlope {
            bin_us: ((bin_s.max(1e-3)) * 1e6) as u64,
            t: [0; MAX_BINS],
            v: [0.0; MAX_BINS],
            len: 0,
            head: 0,
            open_start: 0,
            open_t_sum: 0,
            open_v_sum: 0.0,
            open_n: 0,
            newest_t: 0,
        }
    }

    /// Adds a sample. Non-increasing times restart the history.
    pub fn push(&mut self, t_us: u64, va: f32) {
        if (self.len > 0 || self.open_n > 0) && t_us <= self.newest_t {
            self.reset();
        }
        if self.open_n > 0 && t_us >= self.open_start + self.bin_us {
            self.close_bin();
        }
        if self.open_n == 0 {
            self.open_start = t_us;
        }
        self.open_t_sum += t_us - self.open_start;
        self.open_v_sum += va;
        self.open_n += 1;
        self.newest_t = t_us;
    }

    fn close_bin(&mut self) {
        let n = self.open_n as u64;
        self.t[self.head] = self.open_start + self.open_t_sum / n;
        self.v[self.head] = self.open_v_sum / self.open_n as f32;
        self.head = (self.head + 1) % MAX_BINS;
        self.len = (self.len + 1).min(MAX_BINS);
        self.open_n = 0;
        self.open_t_sum = 0;
        self.open_v_sum = 0.0;
    }

    /// Clears the history.
    pub fn reset(&mut self) {
        self.len = 0;
        self.open_n = 0;
        self.open_t_sum = 0;
        self.open_v_sum = 0.0;
    }

    /// The fit over the last `bins` closed bins (≥ 2 needed), evaluated at the newest sample.
    pub fn estimate(&self, bins: usize) -> Option<VaEstimate> {
        let n = bins.clamp(2, MAX_BINS).min(self.len);
        if n < 2 {
            return None;
        }
        let idx = |k: usize| (self.head + MAX_BINS - 1 - k) % MAX_BINS;
        let t0 = self.newest_t;
        // Times relative to the newest sample keep f32 precision over long flights.
        let rel = |i: usize| -(t0.saturating_sub(self.t[i]) as f32) * 1e-6;
        let (mut st, mut sv) = (0.0f32, 0.0f32);
        for k in 0..n {
            st += rel(idx(k));
            sv += self.v[idx(k)];
        }
        let (mt, mv) = (st / n as f32, sv / n as f32);
        let (mut stt, mut stv) = (0.0f32, 0.0f32);
        for k in 0..n {
            let dt = rel(idx(k)) - mt;
            stt += dt * dt;
            stv += dt * (self.v[idx(k)] - mv);
        }
        if !(stt > 0.0) {
            return None;
        }
        let slope = stv / stt;
        Some(VaEstimate { va: mv - slope * mt, va_dot: slope, t_us: t0 })
    }
}
