//! GPS velocity differencing (thesis eq 4.16): the mean NED acceleration over the
//! interval between two fixes, plus the flight-path angle γ and its rate (eq 4.64–4.66).

use crate::fix::GpsFix;
use crate::math::Vec3;

const WEEK_MS: u32 = 604_800_000;

/// What one new fix yields when differenced against the previous one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GpsDelta {
    /// Mean NED acceleration over the interval, m/s².
    pub accel_ned: Vec3,
    /// Interval length, s.
    pub dt: f32,
    /// Mean NED velocity over the interval, m/s.
    pub mean_vel: Vec3,
    /// Velocity of the newest fix, m/s (vD 0 when the fix has none).
    pub vel: Vec3,
    /// Velocity of the previous fix, m/s (vD 0 when the fix has none).
    pub prev_vel: Vec3,
    /// Whether both fixes had a measured down velocity.
    pub vd_valid: bool,
    /// Whether the newest fix had a measured down velocity.
    pub latest_vd_valid: bool,
    /// The receivers' speed accuracy (m/s, 1-σ) of the previous and the newest fix, if reported.
    pub speed_acc: [Option<f32>; 2],
}

impl GpsDelta {
    /// Flight-path angle of the newest fix, rad (0 when its vD is unknown). Computed on
    /// demand: only the airspeed model uses it (two atan2 per update saved in EKF1).
    pub fn gamma(&self) -> f32 {
        if self.latest_vd_valid {
            flight_path_angle(self.vel)
        } else {
            0.0
        }
    }

    /// γ̇ over the interval, rad/s (0 when vD is unknown in either fix).
    pub fn gamma_dot(&self) -> f32 {
        if self.vd_valid {
            (flight_path_angle(self.vel) - flight_path_angle(self.prev_vel)) / self.dt
        } else {
            0.0
        }
    }
}

/// Outcome of pushing a fix into the differencer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Push {
    /// First fix, or a fix after a gap: stored, nothing to difference yet.
    Seeded,
    /// Interval shorter than the minimum (a duplicate epoch): ignored.
    TooSoon,
    /// A new difference.
    Delta(GpsDelta),
}

/// Differences consecutive fixes. Uses receiver epochs (`itow_ms`) when both fixes
/// have them, else local arrival times.
#[derive(Debug, Clone, Copy, Default)]
pub struct GpsDifferencer {
    prev: Option<Epoch>,
}

/// What differencing keeps of a fix (a few words, not the whole fix: cheap to copy).
#[derive(Debug, Clone, Copy)]
struct Epoch {
    t_us: u64,
    itow_ms: Option<u32>,
    /// NED velocity, m/s; vD 0 when the fix has none.
    vel: Vec3,
    /// A measured vD from a 3-D fix (a 2-D fix's vD is not used).
    vd_valid: bool,
    speed_acc: Option<f32>,
}

impl Epoch {
    fn of(fix: &GpsFix) -> Self {
        Epoch {
            t_us: fix.t_us,
            itow_ms: fix.itow_ms,
            vel: fix.vel_ned_or_level(),
            vd_valid: fix.vel_d.is_some() && fix.fix_type >= crate::fix::FixType::Fix3D,
            speed_acc: fix.speed_acc,
        }
    }
}

/// Flight-path angle γ = atan2(−vD, √(vN² + vE²)), rad.
pub fn flight_path_angle(v: Vec3) -> f32 {
    crate::math::atan2(-v[2], crate::math::hypot(v[0], v[1]))
}

/// `t1 − t0` in seconds from µs times, via i32 (saturated at ±35 min, far beyond any
/// differencing interval): i32 → f32 is one instruction on the M4F, i64 → f32 a library call.
fn local_seconds(t0: u64, t1: u64) -> f32 {
    let d = (t1.wrapping_sub(t0) as i64).clamp(i32::MIN as i64, i32::MAX as i64) as i32;
    d as f32 * 1e-6
}

impl GpsDifferencer {
    /// Forgets the previous fix: the next one only re-seeds.
    pub fn reset(&mut self) {
        self.prev = None;
    }

    /// Interval between two fixes, s.
    fn interval(prev: &Epoch, fix: &Epoch) -> f32 {
        match (prev.itow_ms, fix.itow_ms) {
            (Some(a), Some(b)) => (b.wrapping_add(WEEK_MS).wrapping_sub(a) % WEEK_MS) as f32 * 1e-3,
            _ => local_seconds(prev.t_us, fix.t_us),
        }
    }

    /// Pushes a validated fix. Intervals outside `[min_dt, max_dt]` s do not difference:
    /// too short is ignored, too long re-seeds. The vD of a fix below 3-D is not used.
    pub fn push(&mut self, fix: &GpsFix, min_dt: f32, max_dt: f32) -> Push {
        let cur = Epoch::of(fix);
        let Some(prev) = self.prev else {
            self.prev = Some(cur);
            return Push::Seeded;
        };
        let dt = Self::interval(&prev, &cur);
        let local_dt = local_seconds(prev.t_us, cur.t_us);
        if dt > max_dt || local_dt > max_dt {
            self.prev = Some(cur);
            return Push::Seeded;
        }
        // Duplicate epoch, or local time not advancing (stale / out of order).
        if !(dt >= min_dt) || !(local_dt > 0.0) {
            return Push::TooSoon;
        }
        let v0 = prev.vel;
        let v1 = cur.vel;
        let vd_valid = prev.vd_valid && cur.vd_valid;
        let inv = 1.0 / dt;
        let accel_ned = [
            (v1[0] - v0[0]) * inv,
            (v1[1] - v0[1]) * inv,
            if vd_valid { (v1[2] - v0[2]) * inv } else { 0.0 },
        ];
        let mean_vel = [
            0.5 * (v0[0] + v1[0]),
            0.5 * (v0[1] + v1[1]),
            if vd_valid { 0.5 * (v0[2] + v1[2]) } else { 0.0 },
        ];
        self.prev = Some(cur);
        Push::Delta(GpsDelta {
            accel_ned,
            dt,
            mean_vel,
            vel: v1,
            prev_vel: v0,
            vd_valid,
            latest_vd_valid: cur.vd_valid,
            speed_acc: [prev.speed_acc, cur.speed_acc],
        })
    }
}
