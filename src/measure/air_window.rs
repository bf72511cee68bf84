//! Moving-window means for the windowed EKF2 measurement (docs/design.md, EKF2).
//!
//! The airspeed model assumes β = 0: the velocity turns with the body, so the
//! centripetal term is `Va·r`. On real airframes r oscillates (Dutch roll, adverse
//! yaw, turbulence) while the velocity does not follow: the neglected `v̇ = d(Va sβ)/dt`
//! reaches several m/s², i.e. tens of degrees of roll per single-sample measurement
//! (PX4 flight b: 33° std against the autopilot). Over a window W the neglected
//! terms average to `Δ(Va sβ)/W` and `Va·Δα/W` — bounded changes divided by W — while
//! the specific force, rates and airspeed average like the attitude they measure. So
//! the model is applied to means over the last W seconds (whole GPS intervals): mean
//! specific force, mean gyro, least-squares airspeed level and slope, mean GPS
//! velocity; the measured roll/pitch is that of the window's mean predicted attitude.
//! A ring of per-interval sums gives the moving window in O(1) per sample and fixed memory.

use crate::math::{wrap_pi, Vec3};

/// Most GPS intervals a window can span; a longer `window` is capped to it.
pub const MAX_INTERVALS: usize = 12;

/// Means over a window.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowMean {
    /// Mean specific force, m/s², body FRD.
    pub accel: Vec3,
    /// Largest |lateral specific force| among the window's per-interval means, m/s²: a
    /// slip that reverses within the window cancels in `accel[1]` but not here.
    pub lateral_max: f32,
    /// Mean raw gyro, rad/s, body FRD (subtract the bias estimate).
    pub gyro: Vec3,
    /// Mean predicted roll and pitch over the window, rad.
    pub att: [f32; 2],
    /// Least-squares airspeed at the window's mean airspeed-sample time, m/s.
    pub va: f32,
    /// Least-squares airspeed slope over the window, m/s² (0 with < 3 samples).
    pub va_dot: f32,
    /// Smallest and largest airspeed sample in the window, m/s.
    pub va_range: [f32; 2],
    /// Number of airspeed samples in the window.
    pub va_samples: u32,
    /// Mean GPS NED velocity over the window (its two end fixes averaged), m/s.
    pub vel: Vec3,
    /// Largest ground speed at the window's two end fixes, m/s.
    pub ground_speed_max: f32,
    /// Window length, s.
    pub duration: f32,
    /// GPS intervals in the window.
    pub intervals: usize,
}

/// Sums over one GPS interval. Airspeed times τ are seconds from the interval start.
#[derive(Debug, Clone, Copy)]
struct Interval {
    start_us: u64,
    vel_start: Vec3,
    n: u32,
    acc: Vec3,
    gyro: Vec3,
    att_ref: [f32; 2],
    att_off: [f32; 2],
    nv: u32,
    st: f32,
    stt: f32,
    sv: f32,
    stv: f32,
    va_min: f32,
    va_max: f32,
}

impl Interval {
    fn new(start_us: u64, vel_start: Vec3) -> Self {
        Interval {
            start_us,
            vel_start,
            n: 0,
            acc: [0.0; 3],
            gyro: [0.0; 3],
            att_ref: [0.0; 2],
            att_off: [0.0; 2],
            nv: 0,
            st: 0.0,
            stt: 0.0,
            sv: 0.0,
            stv: 0.0,
            va_min: f32::INFINITY,
            va_max: 0.0,
        }
    }
}

/// The open interval plus a ring of closed ones.
#[derive(Debug, Clone, Copy)]
pub struct AirWindow {
    open: Option<Interval>,
    ring: [Interval; MAX_INTERVALS],
    len: usize,
    head: usize,
}

impl Default for AirWindow {
    fn default() -> Self {
        AirWindow { open: None, ring: [Interval::new(0, [0.0; 3]); MAX_INTERVALS], len: 0, head: 0 }
    }
}

impl AirWindow {
    /// Forgets everything and opens a first interval at a GPS fix (time `t_us`, NED velocity `vel`).
    pub fn restart(&mut self, t_us: u64, vel: Vec3) {
        self.len = 0;
        self.open = Some(Interval::new(t_us, vel));
    }

    /// Adds an IMU sample: specific force, raw gyro and the predicted roll/pitch.
    pub fn push_imu(&mut self, accel: Vec3, gyro: Vec3, roll: f32, pitch: f32) {
        let Some(iv) = self.open.as_mut() else { return };
        if iv.n == 0 {
            iv.att_ref = [roll, pitch];
        }
        for i in 0..3 {
            iv.acc[i] += accel[i];
            iv.gyro[i] += gyro[i];
        }
        // Offsets from the first sample: a roll through ±180° cannot break the mean.
        iv.att_off[0] += wrap_pi(roll - iv.att_ref[0]);
        iv.att_off[1] += pitch - iv.att_ref[1];
        iv.n += 1;
    }

    /// Adds an airspeed sample (m/s) at `t_us`.
    pub fn push_airspeed(&mut self, t_us: u64, va: f32) {
        let Some(iv) = self.open.as_mut() else { return };
        let tau = t_us.saturating_sub(iv.start_us).min(u32::MAX as u64) as u32 as f32 * 1e-6;
        iv.nv += 1;
        iv.st += tau;
        iv.stt += tau * tau;
        iv.sv += va;
        iv.stv += tau * va;
        iv.va_min = iv.va_min.min(va);
        iv.va_max = iv.va_max.max(va);
    }

    /// Moves the stored predicted roll/pitch by an update's correction, so the window
    /// mean stays the corrected trajectory (else a correction would be applied again).
    pub fn shift_att(&mut self, d_roll: f32, d_pitch: f32) {
        let len = self.len;
        for j in 0..len {
            let iv = &mut self.ring[(self.head + j) % MAX_INTERVALS];
            iv.att_ref[0] = wrap_pi(iv.att_ref[0] + d_roll);
            iv.att_ref[1] += d_pitch;
        }
        if let Some(iv) = self.open.as_mut() {
            iv.att_ref[0] = wrap_pi(iv.att_ref[0] + d_roll);
            iv.att_ref[1] += d_pitch;
        }
    }

    /// Sample variance, across the newest `k` closed intervals, of the per-interval mean
    /// of `c_acc·accel + c_gyro·gyro` — how much a window-mean measurement built from that
    /// combination scatters within the window (0 for k < 2).
    pub fn spread(&self, k: usize, c_acc: Vec3, c_gyro: Vec3) -> f32 {
        let k = k.min(self.len);
        if k < 2 {
            return 0.0;
        }
        let (mut s1, mut s2, mut m) = (0.0f32, 0.0f32, 0u32);
        for j in 0..k {
            let iv = &self.ring[(self.head + self.len - 1 - j) % MAX_INTERVALS];
            if iv.n == 0 {
                continue;
            }
            let nf = iv.n as f32;
            let y = (0..3)
                .map(|i| c_acc[i] * iv.acc[i] / nf + c_gyro[i] * iv.gyro[i] / nf)
                .sum::<f32>();
            s1 += y;
            s2 += y * y;
            m += 1;
        }
        if m < 2 {
            return 0.0;
        }
        let mf = m as f32;
        ((s2 - s1 * s1 / mf) / (mf - 1.0)).max(0.0)
    }

    /// Closes the open interval at the fix (`t_us`, `vel`), opens the next one, and
    /// returns the means over the newest intervals that together span at least `min_s`
    /// (or all the ring holds, if fewer). `None` until the window spans `min_s` or with
    /// no IMU sample in it.
    pub fn close_interval(&mut self, t_us: u64, vel: Vec3, min_s: f32) -> Option<WindowMean> {
        let closed = self.open.replace(Interval::new(t_us, vel))?;
        self.push_closed(closed);
        let (k, start) = self.span_back(t_us, min_s);
        let duration = t_us.saturating_sub(start).min(u32::MAX as u64) as u32 as f32 * 1e-6;
        if !(duration >= min_s || self.len == MAX_INTERVALS) {
            return None;
        }
        let first = self.ring[(self.head + self.len - k) % MAX_INTERVALS];
        let r = first.att_ref;
        let (mut n, mut acc, mut gyro, mut off) = (0u32, [0.0f32; 3], [0.0f32; 3], [0.0f32; 2]);
        let mut lateral_max = 0.0f32;
        let (mut nv, mut st, mut stt, mut sv, mut stv, mut vmin, mut vmax) =
            (0u32, 0.0f32, 0.0f32, 0.0f32, 0.0f32, f32::INFINITY, 0.0f32);
        for j in 0..k {
            let iv = &self.ring[(self.head + self.len - k + j) % MAX_INTERVALS];
            let nf = iv.n as f32;
            n += iv.n;
            for i in 0..3 {
                acc[i] += iv.acc[i];
                gyro[i] += iv.gyro[i];
            }
            if iv.n > 0 {
                lateral_max = lateral_max.max(libm::fabsf(iv.acc[1] / nf));
                off[0] += iv.att_off[0] + nf * wrap_pi(iv.att_ref[0] - r[0]);
                off[1] += iv.att_off[1] + nf * (iv.att_ref[1] - r[1]);
            }
            // Shift the interval's τ origin to the window start: τ' = τ + d.
            let d = iv.start_us.saturating_sub(start) as f32 * 1e-6;
            let nvf = iv.nv as f32;
            nv += iv.nv;
            st += iv.st + nvf * d;
            stt += iv.stt + 2.0 * d * iv.st + nvf * d * d;
            sv += iv.sv;
            stv += iv.stv + d * iv.sv;
            vmin = vmin.min(iv.va_min);
            vmax = vmax.max(iv.va_max);
        }
        if n == 0 {
            return None;
        }
        let nf = n as f32;
        let (va, va_dot) = airspeed_fit(nv, st, stt, sv, stv);
        let v0 = first.vel_start;
        let gs = |v: Vec3| crate::math::hypot(v[0], v[1]);
        Some(WindowMean {
            accel: [acc[0] / nf, acc[1] / nf, acc[2] / nf],
            lateral_max,
            gyro: [gyro[0] / nf, gyro[1] / nf, gyro[2] / nf],
            att: [wrap_pi(r[0] + off[0] / nf), r[1] + off[1] / nf],
            va,
            va_dot,
            va_range: if nv == 0 { [0.0, 0.0] } else { [vmin, vmax] },
            va_samples: nv,
            vel: [0.5 * (v0[0] + vel[0]), 0.5 * (v0[1] + vel[1]), 0.5 * (v0[2] + vel[2])],
            ground_speed_max: gs(v0).max(gs(vel)),
            duration,
            intervals: k,
        })
    }

    /// Stores a closed interval as the ring's newest (the oldest goes when it is full).
        fn push_closed(&mut self, closed: Interval) {
        let slot = (self.head + self.len) % MAX_INTERVALS;
        self.ring[slot] = closed;
        if self.len < MAX_INTERVALS {
            self.len += 1;
        } else {
            self.head = (self.head + 1) % MAX_INTERVALS;
        }
    }

    /// The newest intervals back from `t_us` until their span reaches `min_s` (or the
    /// ring's oldest): how many, and the first one's start time.
        fn span_back(&self, t_us: u64, min_s: f32) -> (usize, u64) {
        let mut k = 0;
        let mut start = t_us;
        while k < self.len {
            start = self.ring[(self.head + self.len - 1 - k) % MAX_INTERVALS].start_us;
            k += 1;
            if t_us.saturating_sub(start) as f32 * 1e-6 >= min_s {
                break;
            }
        }
        (k, start)
    }
}

/// Least-squares airspeed level (the mean) and slope from `nv` samples' sums of τ, τ²,
/// v and τ·v; `(0, 0)` without samples, slope 0 with < 3 or no spread in time.
fn airspeed_fit(nv: u32, st: f32, stt: f32, sv: f32, stv: f32) -> (f32, f32) {
    if nv == 0 {
        return (0.0, 0.0);
    }
    let nvf = nv as f32;
    let (mt, mv) = (st / nvf, sv / nvf);
    let var_t = stt / nvf - mt * mt;
    let slope = if nv >= 3 && var_t > 1e-6 { (stv / nvf - mt * mv) / var_t } else { 0.0 };
    (mv, slope)
}
