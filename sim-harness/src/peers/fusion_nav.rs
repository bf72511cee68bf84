//! fusion-nav 0.1: a `no_std`, allocation-free 15-state error-state Kalman filter, fed as
//! its guide describes for a fixed-wing without a magnetometer: GNSS position and velocity
//! at each fix, its Gaussian-sum yaw estimator for heading (on by default), started in
//! flight from one IMU sample (`initialize_coarse`, the guide's entry point for "a restart
//! at altitude": our logs begin in the air).
//!
//! Inputs: IMU as delta angle / delta velocity (FRD, rad, m/s; the crate's own convention)
//! stamped on the same microsecond clock as EKF2; each fix at its epoch (`gps_t`), so the
//! filter's delayed-fusion history takes the latency; noise by PX4's rules as the crate
//! writes them: velocity σ = max(sAcc, 0.3) horizontally and 1.5× that vertically,
//! position σ = max(hAcc, 0.5) and max(vAcc, 0.75). Output: `state().attitude` (body FRD →
//! NED).
//!
//! Parameters changed from `Config::default()`, the same for every log (docs/peers.md):
//! - `init.sigma_gyro_bias` = 0.044 rad/s (2.5°/s, ArduPilot's fallback; default 0.01):
//!   the thesis sensors have a 1.5°/s turn-on bias, 2.6× the default prior, which would
//!   otherwise be read as attitude error in a start without a still window.

use super::gnss_feed::{micros, GnssFeed, H_ACC, V_ACC};
use super::{euler_of_quat, Estimator, StepClock, YawSource};
use crate::log::LogRow;
use fusion_nav::prelude::*;

/// PX4's velocity-noise floor as fusion-nav documents it (`EKF2_GPS_V_NOISE`), m/s.
const VEL_FLOOR: f32 = 0.3;
/// The position bounds of fusion-nav's quick start (PX4's `EKF2_GPS_P_NOISE` floor), m.
const POS_FLOOR_H: f32 = 0.5;
const POS_FLOOR_V: f32 = 0.75;

/// Table name.
pub const NAME: &str = "fusion-nav 0.1";

/// The fusion-nav peer.
pub struct FusionNav {
    eskf: Eskf,
    started: bool,
    clock: StepClock,
    feed: GnssFeed,
    synthetic_pos: bool,
}

/// The configuration used for every log.
pub fn config() -> Config {
    let mut c = Config::default();
    c.init.sigma_gyro_bias = RadiansPerSecond::from_rad_per_s(0.044);
    c
}

impl FusionNav {
    /// A filter for a log with nominal IMU period `dt`, s.
    ///
    /// # Panics
    /// If [`config`] is refused (it is a fixed, valid configuration).
    pub fn new(dt: f64) -> Self {
        FusionNav {
            eskf: Eskf::new(config()).expect("fusion-nav config is valid"),
            started: false,
            clock: StepClock::new(dt),
            feed: GnssFeed::new(),
            synthetic_pos: false,
        }
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
            SigmaBounds::at_least(VEL_FLOOR),
            SigmaBounds::at_least(1.5 * VEL_FLOOR),
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
