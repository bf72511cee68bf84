//! The GPS fix: what a receiver parser produces and the estimator consumes.
//!
//! One type for both protocols (UBX, NMEA) so that everything downstream of the
//! parser — fix queue, estimator, telemetry — is protocol-agnostic.

/// Receiver fix quality, ordered from worst to best.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Default)]
pub enum FixType {
    /// No position/velocity solution: the fix must not be used.
    #[default]
    NoFix,
    /// Dead-reckoning only (receiver-internal): not used for attitude.
    DeadReckoning,
    /// 2-D fix: horizontal velocity usable, vertical velocity not trusted.
    Fix2D,
    /// 3-D fix.
    Fix3D,
    /// GNSS + dead reckoning combined (u-blox fixType 4).
    GnssDeadReckoning,
}

/// One GPS navigation solution (an epoch), as delivered by a receiver.
///
/// Velocities are NED, m/s. Times: `t_us` is the *local* clock (µs) at which the
/// fix became available to the board — the clock the IMU samples use — and
/// `itow_ms` the receiver's own epoch (GPS time of week, ms) when the protocol
/// gives one. The estimator differences velocities over the receiver epochs when
/// both fixes have them (exact 100 ms steps at 10 Hz), else over `t_us`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct GpsFix {
    /// Local arrival time, µs, same clock as `Ahrs::on_imu`.
    pub t_us: u64,
    /// GPS time of week of the epoch, ms (UBX `iTOW`; NMEA UTC time of day mapped to ms), if known.
    pub itow_ms: Option<u32>,
    /// Fix quality.
    pub fix_type: FixType,
    /// The receiver's own "fix OK" flag (UBX `gnssFixOK`; NMEA status `A` / quality > 0).
    pub fix_ok: bool,
    /// Horizontal ground velocity [north, east], m/s (NED).
    pub vel_ne: [f32; 2],
    /// Down velocity, m/s (NED, positive down), when the receiver measured it (UBX: yes;
    /// NMEA: no, `None`).
    pub vel_d: Option<f32>,
    /// Speed accuracy estimate, m/s 1-σ (UBX `sAcc`), if the protocol has it.
    pub speed_acc: Option<f32>,
    /// Satellites used in the solution.
    pub num_sats: u8,
    /// Latitude, 1e-7 deg (for logging and telemetry only).
    pub lat_e7: i32,
    /// Longitude, 1e-7 deg (for logging and telemetry only).
    pub lon_e7: i32,
    /// Height above mean sea level, mm (for logging and telemetry only).
    pub alt_msl_mm: i32,
}

impl GpsFix {
    /// Horizontal ground speed, m/s.
    pub fn ground_speed(&self) -> f32 {
        crate::math::hypot(self.vel_ne[0], self.vel_ne[1])
    }

    /// NED velocity, m/s, with an unmeasured down component taken as 0 (level flight): what
    /// the estimator differences, and what UBX and the telemetry send for a fix without vD.
    #[inline]
    pub fn vel_ned_or_level(&self) -> [f32; 3] {
        [self.vel_ne[0], self.vel_ne[1], self.vel_d.unwrap_or(0.0)]
    }

    /// Whether every measured velocity component is within `±lim` m/s (an unmeasured vD is
    /// not checked; NaN and ±Inf fail).
    #[inline]
    pub fn velocity_within(&self, lim: f32) -> bool {
        let v = self.vel_ne;
        libm::fabsf(v[0]) <= lim
            && libm::fabsf(v[1]) <= lim
            && self.vel_d.is_none_or(|d| libm::fabsf(d) <= lim)
    }

    /// Whether the fix is good enough to aid attitude: a 2-D or better solution
    /// that the receiver marks valid.
    pub fn usable(&self) -> bool {
        self.fix_ok && self.fix_type >= FixType::Fix2D && self.fix_type != FixType::DeadReckoning
    }
}

/// The fix acceptance both filters share: usable, velocity within `velocity_range` (m/s),
/// later than the last accepted fix, a speed accuracy (if reported) not negative. An
/// accepted fix is counted and clears `NO_GPS_YET` and `GPS_LOST`; a refused one is
/// counted in `gps_rejected` and never reaches the state.
#[inline(always)]
pub(crate) fn admit(
    fix: &GpsFix,
    velocity_range: f32,
    last_fix_t: &mut Option<u64>,
    flags: &mut crate::health::Flags,
    health: &mut crate::health::Health,
) -> bool {
    use crate::health::Flags;
    let in_order = last_fix_t.is_none_or(|t| fix.t_us > t);
    let vel_ok = fix.velocity_within(velocity_range);
    if !(fix.usable() && vel_ok && in_order && fix.speed_acc.is_none_or(|a| a >= 0.0)) {
        health.gps_rejected = health.gps_rejected.wrapping_add(1);
        return false;
    }
    *last_fix_t = Some(fix.t_us);
    flags.set(Flags::NO_GPS_YET, false);
    flags.set(Flags::GPS_LOST, false);
    health.gps_fixes = health.gps_fixes.wrapping_add(1);
    true
}
