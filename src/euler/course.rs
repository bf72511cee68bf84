//! Aid source of the Euler filter: the yaw from the GPS course, optionally corrected
//! for the angle of attack in banked flight, withheld while the aircraft slips.

use super::{EulerAhrs, IntervalRefs};
use crate::health::Flags;
use crate::measure::gps_delta::GpsDelta;
use crate::measure::heading::{
    angle_of_attack_trig, sin_flight_path_angle, yaw_and_sin_cos_from_velocity, RollPitchTrig,
};
use crate::measure::interval::IntervalMean;

/// The yaw the course measures over one fix interval.
#[derive(Debug, Clone, Copy)]
pub(super) struct CourseYaw {
    /// The course-derived yaw (rad) and its (sin, cos), when the ground speed allows one.
    pub yaw_sc: Option<(f32, (f32, f32))>,
    /// (sin α, cos α) of the angle-of-attack correction, (0, 0) without one.
    pub alpha_sin_cos: (f32, f32),
    /// The course is not used as a measurement: slipping, with the yaw aligned.
    pub withhold: bool,
}

impl CourseYaw {
    /// The yaw measurement, rad: none when unobservable or withheld.
    pub fn measurement(&self) -> Option<f32> {
        if self.withhold {
            None
        } else {
            self.yaw_sc.map(|y| y.0)
        }
    }
}

impl EulerAhrs {
    /// Whether the aircraft slips: the interval-mean lateral specific force above its
    /// limit and above its own noise (real airframes vibrate: a 5 Hz GPS interval mean
    /// can carry ~0.5 m/s² of noise). Compared as squares: |ay| > max(limit, 3·sem) ⟺
    /// ay² > max(limit², 9·sem²).
    pub(super) fn slipping(&self, means: Option<IntervalMean>) -> bool {
        let ay_noise_sq = means.map_or(0.0, |m| 9.0 * m.accel_sem_sq[1]);
        let ay = means.map_or(self.accel[1], |m| m.accel[1]);
        let limit = self.euler.max_lateral_accel_yaw;
        ay * ay > limit * limit && ay * ay > ay_noise_sq
    }

    /// Control policy of the course: observable above `min_ground_speed_yaw`, withheld
    /// in a slip once the yaw is aligned (the course is then off by β, and the gyro
    /// carries the yaw). Sets the flags and counts the skips.
    pub(super) fn control_course(
        &mut self,
        d: &GpsDelta,
        refs: &IntervalRefs,
        trig: &RollPitchTrig,
        slipping: bool,
    ) -> CourseYaw {
        let vel = refs.vel;
        let yaw_ok = vel[0] * vel[0] + vel[1] * vel[1]
            >= self.cfg.min_ground_speed_yaw * self.cfg.min_ground_speed_yaw;
        self.flags.set(Flags::YAW_UNOBSERVABLE, !yaw_ok);
        let aoa = if self.euler.heading_aoa_correction {
            let sin_gamma = if d.vd_valid { sin_flight_path_angle(vel) } else { 0.0 };
            angle_of_attack_trig(trig, sin_gamma)
        } else {
            None
        };
        self.flags.set(Flags::SIDESLIP, slipping);
        // With its sin/cos: the yaw measurement is also the heading that rotates the GPS
        // acceleration.
        let yaw_sc = if yaw_ok {
            Some(yaw_and_sin_cos_from_velocity(vel[0], vel[1], trig, aoa.map(|a| a.sin_cos)))
        } else {
            None
        };
        let withhold = yaw_sc.is_some() && slipping && self.aligned[2];
        if !yaw_ok {
            self.health.yaw_skipped_low_speed = self.health.yaw_skipped_low_speed.wrapping_add(1);
        } else if withhold {
            self.health.yaw_skipped_sideslip = self.health.yaw_skipped_sideslip.wrapping_add(1);
        }
        CourseYaw { yaw_sc, alpha_sin_cos: aoa.map_or((0.0, 0.0), |a| a.sin_cos), withhold }
    }
}
