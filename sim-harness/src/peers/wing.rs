//! Our estimator, driven through the canonical replay call sequence (`replay::step`).

use super::setup::{SensorFigures, Setup, Tuning};
use super::{Estimator, YawSource};
use crate::log::LogRow;
use crate::replay;
use wing_ahrs::config::BiasModel;
use wing_ahrs::{Ahrs, Config, Filter, Model};

/// Table name of the default filter (the quaternion filter, `Config::default()`).
pub const NAME: &str = "wing-ahrs";
/// Table name of the Euler filter's EKF2 (airspeed), `Config::euler()` with `Model::Ekf2`.
pub const EULER_EKF2_NAME: &str = "wing-ahrs Euler EKF2";

/// wing-ahrs with a given configuration.
pub struct Wing {
    ahrs: Ahrs,
    name: &'static str,
}

impl Wing {
    /// The default: the quaternion filter (3-D GPS acceleration, the EKF1 idea).
    pub fn ekf1() -> Self {
        Wing { ahrs: Ahrs::try_new(Config::default()).expect("a valid configuration"), name: NAME }
    }
    /// The Euler filter's EKF2 (airspeed), recommended Euler defaults.
    pub fn ekf2() -> Self {
        Wing {
            ahrs: Ahrs::try_new(Config::euler().with_model(Model::Ekf2(Default::default())))
                .expect("a valid configuration"),
            name: EULER_EKF2_NAME,
        }
    }
    /// The quaternion filter set up for one log (matched: the spec's sensor figures).
    pub fn ekf1_with(setup: &Setup) -> Self {
        Wing {
            ahrs: Ahrs::try_new(matched(Config::default(), setup)).expect("a valid configuration"),
            name: NAME,
        }
    }
    /// The Euler filter's EKF2 set up for one log.
    pub fn ekf2_with(setup: &Setup) -> Self {
        let cfg = Config::euler().with_model(Model::Ekf2(Default::default()));
        Wing {
            ahrs: Ahrs::try_new(matched(cfg, setup)).expect("a valid configuration"),
            name: EULER_EKF2_NAME,
        }
    }
    /// Any configuration, with a table name.
    pub fn with_config(cfg: Config, name: &'static str) -> Self {
        Wing { ahrs: Ahrs::try_new(cfg).expect("a valid configuration"), name }
    }
    /// The wrapped estimator.
    pub fn ahrs(&self) -> &Ahrs {
        &self.ahrs
    }
}

impl Estimator for Wing {
    fn name(&self) -> &str {
        self.name
    }
    fn step(&mut self, row: &LogRow) {
        replay::step(&mut self.ahrs, row);
    }
    fn attitude(&self) -> [f64; 3] {
        let e = self.ahrs.attitude();
        [e.roll as f64, e.pitch as f64, e.yaw as f64]
    }
    fn estimates_bias(&self) -> bool {
        true
    }
    fn uses_gps(&self) -> bool {
        true
    }
    fn yaw_source(&self) -> YawSource {
        match self.ahrs.config().filter {
            wing_ahrs::Filter::Quaternion(_) => YawSource::GpsAcceleration,
            wing_ahrs::Filter::Euler(_) => YawSource::OwnGps,
        }
    }
}

/// `cfg` with the matched configuration's sensor figures (docs/peers.md); unchanged as shipped.
pub fn matched(mut cfg: Config, setup: &Setup) -> Config {
    if setup.tuning != Tuning::Matched {
        return cfg;
    }
    let f = &setup.figures;
    cfg.gyro_noise_density = f.gyro_noise_density as f32;
    cfg.bias_model = BiasModel::RandomWalk { density: f.gyro_bias_walk as f32 };
    cfg.init_sigma_bias = f.gyro_bias_init as f32;
    cfg.gps_latency = setup.latency as f32;
    if let Filter::Quaternion(q) = &mut cfg.filter {
        q.accel_noise_density = f.accel_noise_density as f32;
        q.airspeed_sigma = f.airspeed_noise as f32;
        q.unreported_vel_sigma = f.gnss_vel_noise as f32;
    }
    unobservable(cfg, f)
}

/// `cfg` told the IMU errors no state holds, from its datasheet figures `f`: the
/// accelerometer bias and the axes' misalignment (`QuatConfig::accel_bias_sigma`,
/// `mounting_sigma`). They change only the covariance the filter reports, never the
/// estimate: the matched configuration and the robustness suite tell them, since a filter
/// told a real part's 0.1 m/s² on a bias-free IMU reports several times its error
/// (docs/harness.md, "Receivers and starts").
pub fn unobservable(mut cfg: Config, f: &SensorFigures) -> Config {
    if let Filter::Quaternion(q) = &mut cfg.filter {
        q.accel_bias_sigma = f.accel_bias_sigma as f32;
        q.mounting_sigma = f.mounting_sigma as f32;
    }
    cfg
}
