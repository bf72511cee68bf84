//! Aid source of the Euler filter's EKF1: roll and pitch solved from the GPS-derived
//! acceleration and the accelerometer (thesis eq 4.45/4.48, or the robust forms), with
//! its noise from the sensors and, optionally, the fix shared by consecutive
//! differences carried as states (`ekf::fix_noise`).

use super::course::CourseYaw;
use super::update::IntervalNoise;
use super::{EulerAhrs, IntervalRefs};
use crate::config::{Ekf1Config, RotationHeading};
use crate::ekf::fix_noise::Coupling;

use crate::math::{sincos, Mat6, Vec3};
use crate::measure::gps_delta::GpsDelta;
use crate::measure::heading::{course, RollPitchTrig};
use crate::measure::interval::IntervalMean;
use crate::measure::{gps_accel, noise, RollPitch};

/// The heading that rotates the GPS acceleration into the heading frame.
#[derive(Debug, Clone, Copy)]
struct Heading {
    /// (sin ψ, cos ψ).
    sin_cos: (f32, f32),
    /// Its variance, rad²: the yaw measurement's R, or the predicted yaw's P.
    var: f32,
    /// The heading is the yaw measurement itself (their error is one, shared).
    shared: bool,
}

impl EulerAhrs {
    /// EKF1's roll and pitch measurement of interval `d`, its variances written into
    /// `noise` (and, with the fix-noise states, each axis' coupling to them).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn gps_accel_roll_pitch(
        &mut self,
        e1: &Ekf1Config,
        d: &GpsDelta,
        means: Option<IntervalMean>,
        refs: &IntervalRefs,
        trig: &RollPitchTrig,
        yaw: &CourseYaw,
        noise: &mut IntervalNoise,
        chol: &Mat6,
    ) -> RollPitch {
        let heading = self.rotation_heading(e1, refs, yaw, noise.var[2]);
        let r = gps_accel::heading_frame_specific_force_sc(d.accel_ned, heading.sin_cos);
        let rp = gps_accel::measure_near(e1.form, refs.accel, r, trig);
        if noise.sensors.is_some() {
            let pitch_sc = rp.pitch_sin_cos.unwrap_or((trig.st, trig.ct));
            self.gps_accel_noise(e1, d, means, refs.accel, r, pitch_sc, trig, heading, noise, chol);
        }
        rp
    }

    /// Before yaw is aligned the prediction is meaningless: the course. Without a usable
    /// course, the predicted yaw is the only heading there is.
    fn rotation_heading(
        &self,
        e1: &Ekf1Config,
        refs: &IntervalRefs,
        yaw: &CourseYaw,
        yaw_var: f32,
    ) -> Heading {
        let p_yaw = self.ekf.p[2][2];
        let (vel, att) = (refs.vel, refs.att);
        let (sin_cos, var, shared) = match (e1.rotation_heading, yaw.yaw_sc) {
            (RotationHeading::PredictedYaw, Some((_, y))) if !self.aligned[2] => {
                (y, yaw_var, !yaw.withhold)
            }
            (RotationHeading::Course, Some(_)) => (sincos(course(vel[0], vel[1])), yaw_var, false),
            (RotationHeading::CorrectedCourse, Some(_)) if yaw.withhold => {
                (sincos(att[2]), p_yaw, false)
            }
            (RotationHeading::CorrectedCourse, Some((_, y))) => (y, yaw_var, true),
            _ => (sincos(att[2]), p_yaw, false),
        };
        Heading { sin_cos, var, shared }
    }

    /// Roll and pitch variances from the sensors: white (floor and accelerometer), the
    /// rotation heading's error (white, or a state shared with the yaw measurement), and
    /// the GPS part as white or through the fix-noise states.
    #[allow(clippy::too_many_arguments)]
    fn gps_accel_noise(
        &mut self,
        e1: &Ekf1Config,
        d: &GpsDelta,
        means: Option<IntervalMean>,
        accel: Vec3,
        r: Vec3,
        pitch_sc: (f32, f32),
        trig: &RollPitchTrig,
        heading: Heading,
        noise: &mut IntervalNoise,
        chol: &Mat6,
    ) {
        let Some((v0, v1, floor)) = noise.sensors else {
            return;
        };
        let sq = |x: f32| x * x;
        let correlated = noise.correlated;
        let sem_sq = means.map_or([0.0; 3], |m| m.accel_sem_sq);
        let r_var = noise::differenced_accel_variance(v0 + v1, d.dt);
        let n = noise::ekf1_roll_pitch_noise(e1.form, accel, sem_sq, r, pitch_sc);
        let shared = correlated && heading.shared;
        if correlated {
            // C from the last update to now, linearised at the interval's mean attitude.
            let lin = crate::ekf::process::linearize_sc(
                (trig.sf, trig.cf),
                (trig.st, trig.ct),
                self.body_rates(),
                self.min_cos_pitch,
            );
            let shared_var = if shared { noise.var[2] } else { 0.0 };
            self.fix_noise.begin(&lin.a, &lin.b, self.noise.inv_tau, d.dt, v0, shared_var);
            if self.fix_noise.bound_cross(chol) {
                self.ekf.count_repair();
            }
        }
        for j in 0..2 {
            let white = sq(floor[j]) + n.accel_var[j];
            // (The white model predates the heading term and keeps its figures.)
            let hdg = if correlated { sq(n.heading_gain[j]) * heading.var } else { 0.0 };
            let gps = n.gain_sq[j] * r_var;
            noise.var[j] = white + hdg + gps;
            if correlated {
                let k = if shared { n.heading_gain[j] } else { 0.0 };
                noise.coupling[j] =
                    Some(Coupling { h: n.gain(j) / d.dt, fresh_var: v1, k, white_var: noise.var[j] });
                noise.var[j] = white + if shared { 0.0 } else { hdg };
            }
        }
        if shared {
            // The yaw measurement's whole variance is e's.
            noise.coupling[2] =
                Some(Coupling { k: 1.0, white_var: noise.var[2], ..Coupling::default() });
            noise.var[2] = 0.0;
        }
    }
}
