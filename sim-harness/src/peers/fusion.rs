//! x-io Technologies' Fusion AHRS (Madgwick's revised complementary filter), crate
//! `fusion-ahrs` (wboayue; a maintained port of the C library, MIT), with its
//! external-heading input fed from the GPS course.
//!
//! Conventions (fusion-ahrs 1.0): gyro in **deg/s**, accelerometer in **g**; with
//! `Convention::Ned` a level, still sensor reads (0, 0, −1) g — exactly our FRD specific
//! force divided by g, so no sign flip. Angles come out in degrees. Settings are those
//! of the library's own `advanced` example (gain 0.5, 2000 °/s range, 10° acceleration
//! and heading rejection, 5 s recovery), with its gyro `Bias` (offset) corrector in
//! front, as the authors recommend; that corrector only adapts when the gyro reads
//! below 3 °/s for 3 s ("stationary").
//!
//! Heading: between GPS fixes the external heading is the last GPS course advanced by
//! Fusion's own yaw change since that fix (a fresh course only every 0.1 s would lag a
//! turn); below [`super::MIN_COURSE_SPEED`] no heading is given.

use super::{course, wrap, Estimator, StepClock, YawSource, G};
use crate::log::LogRow;
use fusion_ahrs::{Ahrs, AhrsSettings, Bias, BiasSettings, Convention, Vector};

/// Fusion adapter.
pub struct Fusion {
    f: Ahrs,
    bias: Bias,
    clock: StepClock,
    /// (course at the last fix, Fusion's yaw then), rad.
    heading_ref: Option<(f64, f64)>,
}

impl Fusion {
    /// A filter with nominal IMU period `dt`, s.
    pub fn new(dt: f64) -> Self {
        let rate = (1.0 / dt) as f32;
        let settings = AhrsSettings {
            sample_rate: rate,
            convention: Convention::Ned,
            gain: 0.5,
            gyroscope_range: 2000.0,
            acceleration_rejection: 10.0,
            magnetic_rejection: 10.0,
            rejection_timeout: 5.0,
        };
        Fusion {
            f: Ahrs::with_settings(settings),
            bias: Bias::with_settings(BiasSettings { sample_rate: rate, ..Default::default() }),
            clock: StepClock::new(dt),
            heading_ref: None,
        }
    }

    fn yaw(&self) -> f64 {
        (self.f.quaternion().to_euler().yaw as f64).to_radians()
    }
}

impl Estimator for Fusion {
    fn name(&self) -> &str {
        "Fusion (fusion-ahrs)"
    }
    fn step(&mut self, row: &LogRow) {
        self.f.set_sample_period(self.clock.dt(row.t) as f32);
        let d = |v: f64| v.to_degrees() as f32;
        let gyro = self.bias.update(Vector::new(d(row.gyro[0]), d(row.gyro[1]), d(row.gyro[2])));
        let a = row.accel;
        let accel = Vector::new((a[0] / G) as f32, (a[1] / G) as f32, (a[2] / G) as f32);
        if let Some(g) = row.gps {
            // A fix without a usable course drops the heading input until the next one.
            let chi = course(g.vel);
            if let (Some(chi), None) = (chi, self.heading_ref) {
                // First usable course: initialise the heading, as the library's
                // `set_heading` is meant for, instead of waiting out its rejection timeout.
                self.f.set_heading(chi.to_degrees() as f32);
            }
            self.heading_ref = chi.map(|chi| (chi, self.yaw()));
        }
        match self.heading_ref {
            Some((chi, yaw_then)) => {
                let heading = wrap(chi + wrap(self.yaw() - yaw_then));
                self.f.update_external_heading(gyro, accel, heading.to_degrees() as f32);
            }
            None => self.f.update_no_magnetometer(gyro, accel),
        }
    }
    fn attitude(&self) -> [f64; 3] {
        let e = self.f.quaternion().to_euler();
        [(e.roll as f64).to_radians(), (e.pitch as f64).to_radians(), (e.yaw as f64).to_radians()]
    }
    fn estimates_bias(&self) -> bool {
        false
    }
    fn uses_gps(&self) -> bool {
        true
    }
    fn yaw_source(&self) -> YawSource {
        YawSource::GpsCourseInput
    }
}
