//! Other attitude estimators run on the same flight logs as ours (issue 6).
//!
//! Each adapter feeds one peer exactly as its authors document it (units, axis and
//! accelerometer sign conventions are stated per file and checked by
//! `tests/peers_static_tilt.rs`) and reports roll, pitch, yaw in our convention:
//! NED / FRD, 3-2-1 Euler, radians.

pub mod ahrs_madgwick;
pub mod ahrs_mahony;
pub mod dcm_gps;
pub mod dcmimu;
pub mod fusion;
pub mod fusion_nav;
pub mod gnss_feed;
pub mod px4_ekf2;
pub mod px4_ekf2_feed;
pub mod setup;
pub mod synth;
pub mod vqf;
pub mod wing;

use crate::log::LogRow;

/// Standard gravity, m/s² (docs/design.md, conventions).
pub const G: f64 = 9.80665;

/// Where an estimator's yaw comes from (the comparison table says which).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum YawSource {
    /// Integrated gyro only; aligned once to the first GPS course (see [`HeadingAlign`]).
    GyroAlignedOnce,
    /// GPS course fed to the peer's external-heading input.
    GpsCourseInput,
    /// The estimator's own GPS-aided yaw.
    OwnGps,
    /// A Gaussian-sum yaw estimator on GNSS velocity (fusion-nav, PX4's EKF-GSF): observes
    /// heading from horizontal acceleration, none in straight flight.
    YawEstimator,
    /// wing-ahrs' quaternion filter: heading from the 3-D GPS acceleration, and from the
    /// course only in coordinated flight (a straight slip leaves it on the gyro).
    GpsAcceleration,
}

impl YawSource {
    /// Short label for tables.
    pub fn label(self) -> &'static str {
        match self {
            YawSource::GyroAlignedOnce => "gyro (aligned once)*",
            YawSource::GpsCourseInput => "GPS course input",
            YawSource::OwnGps => "own, GPS-aided",
            YawSource::YawEstimator => "own GSF on GNSS vel.",
            YawSource::GpsAcceleration => "GPS accel. + coordinated course",
        }
    }
}

/// One attitude estimator driven row by row from a flight log.
pub trait Estimator {
    /// Name for tables and figures.
    fn name(&self) -> &str;
    /// Feeds one log row (IMU sample plus whatever else arrived with it).
    fn step(&mut self, row: &LogRow);
    /// Current roll, pitch, yaw, rad (NED/FRD, 3-2-1).
    fn attitude(&self) -> [f64; 3];
    /// Whether it estimates gyro bias in flight (not only at rest).
    fn estimates_bias(&self) -> bool;
    /// Whether it uses GPS (default: no — most peers are IMU-only).
    fn uses_gps(&self) -> bool {
        false
    }
    /// Where its yaw comes from (default: its own gyro yaw, aligned once to the course).
    fn yaw_source(&self) -> YawSource {
        YawSource::GyroAlignedOnce
    }
    /// Whether the GNSS position it was fed was synthesised from the fixes' velocities
    /// (the log has no `lat`/`lon`/`alt`; see [`gnss_feed`]).
    fn synthetic_position(&self) -> bool {
        false
    }
}

/// Builds every estimator of the comparison, as shipped, for a log that starts in the air
/// with nominal IMU period `dt`, s.
pub fn all(dt: f64) -> Vec<Box<dyn Estimator>> {
    all_for(&setup::Setup::nominal(dt))
}

/// Builds every estimator of the comparison for one log and configuration. The navigation
/// filters (ours, fusion-nav, EKF2) take the configuration; the attitude-only peers run as
/// shipped in both.
pub fn all_for(setup: &setup::Setup) -> Vec<Box<dyn Estimator>> {
    let dt = setup.dt;
    vec![
        Box::new(wing::Wing::ekf1_with(setup)),
        Box::new(wing::Wing::ekf2_with(setup)),
        Box::new(fusion_nav::FusionNav::with_setup(setup)),
        Box::new(px4_ekf2::Px4Ekf2::with_setup(setup)),
        Box::new(dcm_gps::DcmGps::new(dt)),
        Box::new(GyroCalibrated::new(dcm_gps::DcmGps::new(dt), "DCM+GPS, gyros cal. (ours, P&B)")),
        Box::new(fusion::Fusion::new(dt)),
        Box::new(HeadingAlign::new(vqf::Vqf::new(dt))),
        Box::new(HeadingAlign::new(dcmimu::DcmImu::new(dt))),
        Box::new(HeadingAlign::new(ahrs_mahony::Mahony::new(dt))),
        Box::new(HeadingAlign::new(ahrs_madgwick::Madgwick::new(dt))),
    ]
}

/// Time step from the row clock; the first row (or a non-positive step) uses the nominal period.
#[derive(Debug, Clone, Copy)]
pub struct StepClock {
    nominal: f64,
    last: Option<f64>,
}

impl StepClock {
    /// A clock with nominal period `nominal`, s.
    pub fn new(nominal: f64) -> Self {
        StepClock { nominal, last: None }
    }
    /// The step ending at `t`, s (clamped to 10 × nominal so a gap does not explode an integrator).
    pub fn dt(&mut self, t: f64) -> f64 {
        let dt = match self.last {
            Some(l) if t > l => (t - l).min(10.0 * self.nominal),
            _ => self.nominal,
        };
        self.last = Some(t);
        dt
    }
}

/// The accelerometer as the "gravity reaction points up" peers expect it: they take the
/// reading of a level, still sensor to be +g along the axis that points away from the
/// Earth. Our specific force is FRD with level & still = (0, 0, −g), so we hand them −f_B:
/// their reference axis then points down, i.e. their Earth frame is NED and, with the
/// gyro in FRD unchanged, their quaternion is the usual FRD→NED rotation.
pub fn gravity_up(f_b: [f64; 3]) -> [f64; 3] {
    [-f_b[0], -f_b[1], -f_b[2]]
}

/// Roll, pitch, yaw (3-2-1) of a unit quaternion (w, x, y, z) that rotates body vectors into the Earth frame.
pub fn euler_of_quat(w: f64, x: f64, y: f64, z: f64) -> [f64; 3] {
    let roll = (2.0 * (w * x + y * z)).atan2(1.0 - 2.0 * (x * x + y * y));
    let pitch = (2.0 * (w * y - z * x)).clamp(-1.0, 1.0).asin();
    let yaw = (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z));
    [roll, pitch, yaw]
}

pub use crate::metrics::wrap;

/// Below this ground speed the GPS course is not used, m/s (same as our core's default).
pub const MIN_COURSE_SPEED: f64 = 3.0;

/// GPS course over ground of a NED velocity, rad, if fast enough to be meaningful.
pub fn course(vel: [f64; 3]) -> Option<f64> {
    (vel[0].hypot(vel[1]) >= MIN_COURSE_SPEED).then(|| vel[1].atan2(vel[0]))
}

/// Gives a GPS-less peer a fair yaw: its own gyro-integrated yaw, shifted once by the
/// offset to the first usable GPS course (a one-time heading initialisation, as a user
/// without a magnetometer would do). Roll and pitch are untouched.
pub struct HeadingAlign<E> {
    inner: E,
    offset: Option<f64>,
}

impl<E: Estimator> HeadingAlign<E> {
    /// Wraps `inner`.
    pub fn new(inner: E) -> Self {
        HeadingAlign { inner, offset: None }
    }
}

impl<E: Estimator> Estimator for HeadingAlign<E> {
    fn name(&self) -> &str {
        self.inner.name()
    }
    fn step(&mut self, row: &LogRow) {
        self.inner.step(row);
        if self.offset.is_none() {
            if let Some(chi) = row.gps.and_then(|g| course(g.vel)) {
                self.offset = Some(wrap(chi - self.inner.attitude()[2]));
            }
        }
    }
    fn attitude(&self) -> [f64; 3] {
        let [r, p, y] = self.inner.attitude();
        [r, p, wrap(y + self.offset.unwrap_or(0.0))]
    }
    fn estimates_bias(&self) -> bool {
        self.inner.estimates_bias()
    }
    fn uses_gps(&self) -> bool {
        false
    }
    fn yaw_source(&self) -> YawSource {
        YawSource::GyroAlignedOnce
    }
}

/// A peer whose gyros were calibrated on the ground before take-off, as ArduPilot does at
/// boot: the log's true turn-on bias (`true_b*` of the first row, simulated logs only) is
/// subtracted from every gyro sample — a perfect ground calibration, the baseline's best
/// case. Without truth in the log it passes the gyro through unchanged.
pub struct GyroCalibrated<E> {
    inner: E,
    name: &'static str,
    bias: Option<[f64; 3]>,
}

impl<E: Estimator> GyroCalibrated<E> {
    /// Wraps `inner` under a new table name.
    pub fn new(inner: E, name: &'static str) -> Self {
        GyroCalibrated { inner, name, bias: None }
    }
}

impl<E: Estimator> Estimator for GyroCalibrated<E> {
    fn name(&self) -> &str {
        self.name
    }
    fn step(&mut self, row: &LogRow) {
        let b = *self.bias.get_or_insert(row.truth_bias.unwrap_or([0.0; 3]));
        let mut r = *row;
        r.gyro = core::array::from_fn(|i| row.gyro[i] - b[i]);
        self.inner.step(&r);
    }
    fn attitude(&self) -> [f64; 3] {
        self.inner.attitude()
    }
    fn estimates_bias(&self) -> bool {
        self.inner.estimates_bias()
    }
    fn uses_gps(&self) -> bool {
        self.inner.uses_gps()
    }
    fn yaw_source(&self) -> YawSource {
        self.inner.yaw_source()
    }
}
