//! Health counters, status flags and the per-update record: the filter's
//! health signal (thesis §3.2.7), read by telemetry and the harness.

/// Monotonic event counters (wrapping u32). Everything the estimator rejected,
/// clamped or skipped is counted here, never silently dropped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Health {
    /// IMU samples accepted (predict steps run).
    pub imu_samples: u32,
    /// IMU samples rejected: non-finite or out of range.
    pub imu_rejected: u32,
    /// IMU samples whose time did not advance (repeated or backwards timestamp).
    pub dt_nonpositive: u32,
    /// IMU steps longer than `dt_max`, clamped.
    pub dt_clamped: u32,
    /// GPS fixes accepted.
    pub gps_fixes: u32,
    /// GPS fixes rejected: not usable, non-finite, out of range, duplicate or out of order.
    pub gps_rejected: u32,
    /// Times the velocity differencer was re-seeded (start, gaps, after outages).
    pub gps_reseeds: u32,
    /// Transitions into "GPS lost".
    pub gps_outages: u32,
    /// Airspeed samples rejected.
    pub airspeed_rejected: u32,
    /// Measurement updates run (each may update 0–3 axes).
    pub updates: u32,
    /// Innovations rejected by the χ² gate, per axis (roll, pitch, yaw).
    pub gate_rejections: [u32; 3],
    /// Recoveries after `gate_max_consecutive` rejections. Euler filter: forced
    /// acceptances per axis (roll, pitch, yaw). Quaternion filter: `[0]` tilt aligned again,
    /// `[2]` heading (and wind) let go first, or after `course_doubt_after` doubting course
    /// updates; `[1]` gyro biases beyond `bias_plausible_sigmas` reset and the attitude
    /// aligned again.
    pub gate_resets: [u32; 3],
    /// Yaw updates skipped because the ground speed was too low.
    pub yaw_skipped_low_speed: u32,
    /// Yaw updates skipped because the lateral specific force showed sideslip.
    pub yaw_skipped_sideslip: u32,
    /// Solver calls whose |c| exceeded the radius and was clamped.
    pub solver_clamped: u32,
    /// Measurements not formed because the problem was degenerate.
    pub solver_degenerate: u32,
    /// Predict steps run with |θ| beyond the gimbal limit.
    pub gimbal_steps: u32,
    /// Covariance diagonal entries floored or non-finite covariance repaired.
    pub covariance_repairs: u32,
    /// IMU samples accepted with an axis at ≥ 99 % of `gyro_clip`/`accel_clip`
    /// (integrated anyway, flagged with `Flags::IMU_CLIPPED`).
    pub imu_clipped: u32,
    /// GPS intervals whose accelerometer scatter exceeded `QuatConfig::vibration_ratio` ×
    /// the noise spec (quaternion filter; flagged with `Flags::VIBRATION`).
    pub vibration: u32,
}

/// Status flags, a set of the named constants below (for telemetry: [`Flags::bits`]).
/// `Debug` names the set flags: `Flags(ALIGNED | SIDESLIP)`.
#[derive(Clone, Copy, PartialEq, Eq, Default, Hash)]
pub struct Flags(u16);

impl Flags {
    /// No usable GPS fix for longer than `gps_timeout`.
    pub const GPS_LOST: Flags = Flags(1 << 0);
    /// Ground speed below the yaw threshold: yaw is not being measured.
    pub const YAW_UNOBSERVABLE: Flags = Flags(1 << 1);
    /// |θ| beyond the gimbal limit: Euler kinematics are guarded.
    pub const NEAR_GIMBAL_LOCK: Flags = Flags(1 << 2);
    /// The state has been initialised from a measurement (or x(0|0) = 0 by config).
    pub const ALIGNED: Flags = Flags(1 << 3);
    /// No GPS fix has ever arrived.
    pub const NO_GPS_YET: Flags = Flags(1 << 4);
    /// Uncoordinated flight (lateral specific force beyond the limit): yaw not measured.
    pub const SIDESLIP: Flags = Flags(1 << 5);
    /// An IMU sample since the previous GPS fix was clipped (at the sensor's full scale).
    pub const IMU_CLIPPED: Flags = Flags(1 << 6);
    /// The last closed GPS interval's accelerometer scatter was beyond
    /// `QuatConfig::vibration_ratio` × the noise spec (quaternion filter).
    pub const VIBRATION: Flags = Flags(1 << 7);
    /// The attitude is doubtful (quaternion filter): the GPS acceleration has failed its
    /// gate persistently, or the attitude was re-aligned after such a run, and too few
    /// updates have passed since to vouch for it. An autopilot should not trust it.
    pub const UNRELIABLE: Flags = Flags(1 << 8);

    /// Every flag with its name, in bit order.
    pub const ALL: [(Flags, &'static str); 9] = [
        (Flags::GPS_LOST, "GPS_LOST"),
        (Flags::YAW_UNOBSERVABLE, "YAW_UNOBSERVABLE"),
        (Flags::NEAR_GIMBAL_LOCK, "NEAR_GIMBAL_LOCK"),
        (Flags::ALIGNED, "ALIGNED"),
        (Flags::NO_GPS_YET, "NO_GPS_YET"),
        (Flags::SIDESLIP, "SIDESLIP"),
        (Flags::IMU_CLIPPED, "IMU_CLIPPED"),
        (Flags::VIBRATION, "VIBRATION"),
        (Flags::UNRELIABLE, "UNRELIABLE"),
    ];

    /// The set's bits, as the estimate CSV and the firmware's telemetry carry them
    /// (docs/formats.md).
    pub const fn bits(self) -> u16 {
        self.0
    }

    /// The set with these bits; bits that name no flag are dropped.
    pub const fn from_bits_truncate(bits: u16) -> Self {
        let mut all = 0;
        let mut i = 0;
        while i < Self::ALL.len() {
            all |= Self::ALL[i].0 .0;
            i += 1;
        }
        Flags(bits & all)
    }

    /// Whether every flag of `f` is set.
    pub const fn has(self, f: Flags) -> bool {
        self.0 & f.0 == f.0
    }

    pub(crate) fn set(&mut self, f: Flags, on: bool) {
        if on {
            self.0 |= f.0;
        } else {
            self.0 &= !f.0;
        }
    }
}

impl core::ops::BitOr for Flags {
    type Output = Flags;
    fn bitor(self, rhs: Flags) -> Flags {
        Flags(self.0 | rhs.0)
    }
}

impl core::fmt::Debug for Flags {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("Flags(")?;
        let mut first = true;
        for (flag, name) in Self::ALL {
            if self.has(flag) {
                if !first {
                    f.write_str(" | ")?;
                }
                f.write_str(name)?;
                first = false;
            }
        }
        f.write_str(if first { "empty)" } else { ")" })
    }
}

/// What happened to one axis in an update.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AxisStatus {
    /// Innovation accepted and applied.
    Accepted,
    /// Rejected by the χ² gate.
    Gated,
    /// Accepted after too many consecutive gate rejections; axis variance was reset.
    ForcedAfterGate,
    /// First measurement of this axis: the state was initialised from it.
    Initialised,
    /// No measurement for this axis (low speed for yaw, degenerate geometry, no airspeed…).
    #[default]
    NotMeasured,
}

/// One axis of an update: the measurement, its innovation and innovation variance.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AxisUpdate {
    /// Measured angle z, rad.
    pub z: f32,
    /// Innovation ν = z − x̂ (wrapped to (−π, π]), rad.
    pub innovation: f32,
    /// Innovation variance S = P + R, rad².
    pub variance: f32,
    /// What the gate decided.
    pub status: AxisStatus,
}

impl AxisUpdate {
    /// Normalised innovation squared ν²/S (for NIS), if the axis was measured.
    pub fn nis(&self) -> Option<f32> {
        match self.status {
            AxisStatus::NotMeasured | AxisStatus::Initialised => None,
            _ => Some(self.innovation * self.innovation / self.variance),
        }
    }
}

/// The record of the latest measurement update (roll, pitch, yaw).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct UpdateRecord {
    /// Local time of the update, µs.
    pub t_us: u64,
    /// Update sequence number (1 for the first update); changes when a new update ran.
    pub seq: u32,
    /// Euler filter: roll, pitch, yaw. Quaternion filter: the N, E, D components of the
    /// GPS-acceleration residual (m/s², variance (m/s²)²).
    pub axes: [AxisUpdate; 3],
    /// Quaternion filter: the course (heading) update of this fix, rad.
    pub course: AxisUpdate,
    /// (sin α, cos α) of the angle of attack used for the heading correction ((0, 0) when
    /// disabled). The angle is computed on request ([`UpdateRecord::alpha`]): the update in
    /// the interrupt needs only its sine and cosine.
    pub alpha_sin_cos: (f32, f32),
}

impl UpdateRecord {
    /// Angle of attack used for the heading correction, rad (0 when disabled).
    pub fn alpha(&self) -> f32 {
        crate::math::atan2(self.alpha_sin_cos.0, self.alpha_sin_cos.1)
    }
}

#[cfg(test)]
mod tests {
    use super::Flags;

    #[test]
    fn debug_names_the_set_flags() {
        assert_eq!(format!("{:?}", Flags::ALIGNED | Flags::SIDESLIP), "Flags(ALIGNED | SIDESLIP)");
        assert_eq!(format!("{:?}", Flags::default()), "Flags(empty)");
        assert_eq!(Flags::from_bits_truncate(0xffff).bits(), 0x1ff);
        assert!(!(Flags::ALIGNED).has(Flags::ALIGNED | Flags::SIDESLIP));
    }
}
