//! fusion-nav 0.1: a `no_std`, allocation-free 15-state error-state Kalman filter, fed as
//! its guide describes for a fixed-wing without a magnetometer: GNSS position and velocity
//! at each fix, its Gaussian-sum yaw estimator for heading (on by default). Started as the
//! guide recommends: `initialize(window)` from the first 2 s (`init.min_duration`) where the
//! log starts on the ground (it then measures the gyro bias), `initialize_coarse` from one
//! sample where it starts in the air (the guide's entry point for "a restart at altitude":
//! no still window exists).
//!
//! Inputs: IMU as delta angle / delta velocity (FRD, rad, m/s; the crate's own convention)
//! stamped on the same microsecond clock as EKF2; each fix at its epoch (`gps_t`), so the
//! filter's delayed-fusion history takes the latency; noise by PX4's rules as the crate
//! writes them: velocity σ = max(sAcc, floor) horizontally and 1.5× that vertically (floor
//! 0.3 m/s, PX4's `EKF2_GPS_V_NOISE`; matched: the spec's GNSS velocity noise), position
//! σ = max(hAcc, 0.5) and max(vAcc, 0.75). Output: `state().attitude` (body FRD → NED).
//!
//! Configuration (docs/peers.md): `Config::default()` with `hold = None` (its README: "a car
//! or a fixed-wing sets `Config::hold = None`"); matched, also the spec's IMU noise, gyro
//! bias walk and turn-on σ.

use super::gnss_feed::{micros, GnssFeed, H_ACC, V_ACC};
use super::setup::{Setup, Tuning};
use super::{euler_of_quat, Estimator, StepClock, YawSource};
use crate::log::LogRow;
use fusion_nav::prelude::*;

/// PX4's velocity-noise floor as fusion-nav documents it (`EKF2_GPS_V_NOISE`), m/s.
const VEL_FLOOR: f32 = 0.3;
/// PX4's prediction step, s (`EKF2_PREDICT_US`), by which fusion-nav's docs convert.
const PX4_STEP_S: f64 = 0.01;
/// Where the log starts on the ground: the window's length, s (`init.min_duration`'s 2 s).
const WINDOW_S: f64 = 2.0;
/// The position bounds of fusion-nav's quick start (PX4's `EKF2_GPS_P_NOISE` floor), m.
const POS_FLOOR_H: f32 = 0.5;
const POS_FLOOR_V: f32 = 0.75;

/// Table name.
pub const NAME: &str = "fusion-nav 0.1";

/// The fusion-nav peer.
pub struct FusionNav {
    eskf: Eskf,
    started: bool,
    /// The still window being gathered (a log that starts on the ground), and its first time.
    window: Option<(StaticWindow, f64)>,
    vel_floor: f32,
    clock: StepClock,
    feed: GnssFeed,
    synthetic_pos: bool,
}

/// fusion-nav's smallest accelerometer-bias prior, m/s² (`init.sigma_accel_bias` must be
/// positive): what a spec without a turn-on accelerometer bias is handed.
const ACCEL_BIAS_FLOOR: f32 = 1e-3;

/// The configuration for `setup`: as shipped, or with the spec's sensor figures.
pub fn config(setup: &Setup) -> Config {
    // Its README's set-up for a fixed wing: no position hold while unaided (the hold assumes
    // the vehicle stays put, which one in flight does not).
    let mut c = Config { hold: None, ..Config::default() };
    if setup.tuning == Tuning::Matched {
        let f = &setup.figures;
        // The crate's own rule (`ImuNoise::default`'s docs): its white noise is PX4's per-step
        // σ at the 10 ms step read as a density, ten times the sensor's, for the model error
        // a datasheet figure leaves out. So it gets EKF2's matched figure, as EKF2 does.
        let per_step = 1.0 / PX4_STEP_S.sqrt();
        c.imu.gyro_white = (f.gyro_noise_density * per_step) as f32;
        c.imu.accel_white = (f.accel_noise_density * per_step) as f32;
        c.imu.gyro_bias_walk = f.gyro_bias_walk as f32;
        c.init.sigma_gyro_bias = RadiansPerSecond::from_rad_per_s(f.gyro_bias_init as f32);
        c.imu.accel_bias_walk = f.accel_bias_walk as f32;
        // Its configuration refuses a zero prior: 1 mm/s² stands for a spec's "none".
        c.init.sigma_accel_bias =
            MetersPerSecond2::from_m_per_s2((f.accel_bias_init as f32).max(ACCEL_BIAS_FLOOR));
    }
    c
}

impl FusionNav {
    /// As shipped, for a log starting in the air with nominal IMU period `dt`, s.
    pub fn new(dt: f64) -> Self {
        Self::with_setup(&Setup::nominal(dt))
    }

    /// A filter set up for one log.
    ///
    /// # Panics
    /// If [`config`] is refused (positive, finite figures always pass).
    pub fn with_setup(setup: &Setup) -> Self {
        let matched = setup.tuning == Tuning::Matched;
        FusionNav {
            eskf: Eskf::new(config(setup)).expect("fusion-nav config is valid"),
            started: false,
            window: (!setup.in_air_start).then(|| (StaticWindow::new(), f64::NAN)),
            vel_floor: if matched { setup.figures.gnss_vel_noise as f32 } else { VEL_FLOOR },
            clock: StepClock::new(setup.dt),
            feed: setup.gnss_feed(),
            synthetic_pos: false,
        }
    }
}

impl FusionNav {
    /// The wrapped filter (diagnostics, tests).
    pub fn eskf(&self) -> &Eskf {
        &self.eskf
    }
    /// Whether the filter has started (after the still window, on a ground start).
    pub fn started(&self) -> bool {
        self.started
    }
}

impl Estimator for FusionNav {
    fn name(&self) -> &str {
        NAME
    }
    fn step(&mut self, row: &LogRow) {
        let dt = self.clock.dt(row.t);
        let f = |v: [f64; 3]| v.map(|x| x as f32);
        let [gx, gy, gz] = f(row.gyro);
        let [ax, ay, az] = f(row.accel);
        let imu = ImuSample::from_rates(
            Timestamp::from_micros(micros(row.t)),
            AngularRate::body(gx, gy, gz),
            Acceleration::body(ax, ay, az),
            Seconds::from_secs(dt as f32),
        );
        if let Some((window, t0)) = &mut self.window {
            // Gather the start window; fixes arriving meanwhile precede the filter's clock.
            if t0.is_nan() {
                *t0 = row.t;
            }
            let _ = window.push(StaticSample { imu, ..StaticSample::default() });
            if row.t - *t0 >= WINDOW_S {
                self.started = self.eskf.initialize(window).is_ok();
                self.window = None;
            }
            return;
        }
        if !self.started {
            self.started = self.eskf.initialize_coarse(imu).is_ok();
        } else {
            let _ = self.eskf.predict(imu);
        }
        let Some(fix) = self.feed.fix(row) else { return };
        if !self.started {
            return;
        }
        self.synthetic_pos |= fix.synthetic;
        let time = Timestamp::from_micros(fix.time_us);
        let [vn, ve, vd] = f(fix.vel);
        let sacc = fix.sacc as f32;
        let vel_noise = VelocityNoise::clamped(
            sacc,
            1.5 * sacc,
            SigmaBounds::at_least(self.vel_floor),
            SigmaBounds::at_least(1.5 * self.vel_floor),
        );
        let pos_noise = PositionNoise::clamped(
            H_ACC as f32,
            V_ACC as f32,
            SigmaBounds::new(POS_FLOOR_H, 100.0),
            SigmaBounds::new(POS_FLOOR_V, 100.0),
        );
        let [lat, lon, alt] = fix.lla;
        let _ = self.eskf.fuse_gnss_geodetic(
            time,
            Geodetic::from_degrees(lat, lon, alt),
            pos_noise,
            Position::zero(),
        );
        let _ = self.eskf.fuse_gnss_velocity(
            time,
            Velocity::ned(vn, ve, vd),
            vel_noise,
            Position::zero(),
        );
    }
    fn attitude(&self) -> [f64; 3] {
        let q = self.eskf.state().attitude.body_to_ned();
        euler_of_quat(q.w as f64, q.x as f64, q.y as f64, q.z as f64)
    }
    fn estimates_bias(&self) -> bool {
        true
    }
    fn uses_gps(&self) -> bool {
        true
    }
    fn yaw_source(&self) -> YawSource {
        YawSource::YawEstimator
    }
    fn synthetic_position(&self) -> bool {
        self.synthetic_pos
    }
}
