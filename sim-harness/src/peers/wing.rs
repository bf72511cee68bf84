//! Our estimator, driven through the canonical replay call sequence (`replay::step`).

use super::{Estimator, YawSource};
use crate::log::LogRow;
use crate::replay;
use wing_ahrs::{Ahrs, Config, Model};

/// wing-ahrs with a given configuration.
pub struct Wing {
    ahrs: Ahrs,
    name: &'static str,
}

impl Wing {
    /// The default: the quaternion filter (3-D GPS acceleration, the EKF1 idea).
    pub fn ekf1() -> Self {
        Wing { ahrs: Ahrs::new(Config::default()), name: "wing-ahrs EKF1" }
    }
    /// The Euler filter's EKF2 (airspeed), recommended Euler defaults.
    pub fn ekf2() -> Self {
        Wing {
            ahrs: Ahrs::new(Config::euler().with_model(Model::Ekf2(Default::default()))),
            name: "wing-ahrs EKF2",
        }
    }
    /// Any configuration, with a table name.
    pub fn with_config(cfg: Config, name: &'static str) -> Self {
        Wing { ahrs: Ahrs::new(cfg), name }
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
