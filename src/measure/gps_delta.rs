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
    /// Velocity of the newest fix, m/s.
    pub vel: Vec3,
    /// Velocity of the previous fix, m/s.
    pub prev_vel: Vec3,
    /// Whether both fixes had a measured down velocity.
    pub vd_valid: bool,
    /// Whether the newest fix had a measured down velocity.
    pub latest_vd_valid: bool,
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
    prev: Option<GpsFix>,
}

/// Flight-path angle γ = atan2(−vD, √(vN² + vE²)), rad.
pub fn flight_path_angle(v: Vec3) -> f32 {
    crate::math::atan2(-v[2], crate::math::hypot(v[0], v[1]))
}

impl GpsDifferencer {
    /// Forgets the previous fix: the next one only re-seeds.
    pub fn reset(&mut self) {
        self.prev = None;
    }

    /// Interval between two fixes, s.
    fn interval(prev: &GpsFix, fix: &GpsFix) -> f32 {
        match (prev.itow_ms, fix.itow_ms) {
            (Some(a), Some(b)) => (b.wrapping_add(WEEK_MS).wrapping_sub(a) % WEEK_MS) as f32 * 1e-3,
            _ => fix.t_us.wrapping_sub(prev.t_us) as i64 as f32 * 1e-6,
        }
    }

    /// Pushes a validated fix. Intervals outside `[min_dt, max_dt]` s do not difference:
    /// too short is ignored, too long re-seeds.
    pub fn push(&mut self, fix: &GpsFix, min_dt: f32, max_dt: f32) -> Push {
        let Some(prev) = self.prev else {
            self.prev = Some(*fix);
            return Push::Seeded;
        };
        let dt = Self::interval(&prev, fix);
        let local_dt = (fix.t_us as i64 - prev.t_us as i64) as f32 * 1e-6;
        if dt > max_dt || local_dt > max_dt {
            self.prev = Some(*fix);
            return Push::Seeded;
        }
        // Duplicate epoch, or local time not advancing (stale / out of order).
        if !(dt >= min_dt) || !(local_dt > 0.0) {
            return Push::TooSoon;
        }
        let v0 = prev.vel_ned;
        let v1 = fix.vel_ned;
        let vd_valid = prev.vd_valid && fix.vd_valid;
        let inv = 1.0 / dt;
        let accel_ned = [(v1[0] - v0[0]) * inv, (v1[1] - v0[1]) * inv, if vd_valid { (v1[2] - v0[2]) * inv } else { 0.0 }];
        let mean_vel = [0.5 * (v0[0] + v1[0]), 0.5 * (v0[1] + v1[1]), if vd_valid { 0.5 * (v0[2] + v1[2]) } else { 0.0 }];
        self.prev = Some(*fix);
        Push::Delta(GpsDelta { accel_ned, dt, mean_vel, vel: v1, prev_vel: v0, vd_valid, latest_vd_valid: fix.vd_valid })
    }
}
