//! [`Config::validate`]: the ranges the field types cannot express (docs/tuning.md gives
//! each field's meaning). Run once where a configuration is built (the CLI, the firmware's
//! boot), never per sample.

use super::{BiasModel, Config, EulerConfig, Filter, MeasNoise, Model, QuatConfig, ValidConfig};
use core::fmt;

/// A configuration field outside its allowed range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConfigError {
    /// The field as written in Rust, e.g. `"gps_latency"`, `"mounting.offsets[2]"`, or
    /// `"EulerConfig::gate_chi2[2]"`, `"QuatConfig::gate_chi2"`, `"Ekf2Config::window"`
    /// (a field of the options a `Filter` or `Model` variant holds).
    pub field: &'static str,
    /// What it must be, e.g. `"in [0, 0.5] s"`.
    pub allowed: &'static str,
    /// The value found (integers as f32).
    pub value: f32,
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.field == FILTER {
            // Not a number: the filter variant this build does not hold.
            return write!(f, "config field `{}` must be {}", self.field, self.allowed);
        }
        write!(f, "config field `{}` is {}; it must be {}", self.field, self.value, self.allowed)
    }
}

impl core::error::Error for ConfigError {}

const POSITIVE: &str = "> 0 and finite";
/// The field name of a filter the crate is built without.
const FILTER: &str = "filter";
const NON_NEGATIVE: &str = "≥ 0 and finite";
const POSITIVE_OR_INF: &str = "> 0 (∞ disables)";

/// Every configuration field out of range, found at once by [`Config::validate`] (in
/// the order checked; without allocation, the first [`ConfigErrors::CAPACITY`] are kept
/// and [`ConfigErrors::total`] counts them all).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConfigErrors {
    list: [ConfigError; ConfigErrors::CAPACITY],
    kept: u8,
    total: u16,
}

impl ConfigErrors {
    /// How many errors are kept.
    pub const CAPACITY: usize = 12;

    const NONE: ConfigErrors = ConfigErrors {
        list: [ConfigError { field: "", allowed: "", value: 0.0 }; ConfigErrors::CAPACITY],
        kept: 0,
        total: 0,
    };

    fn push(&mut self, e: ConfigError) {
        if (self.kept as usize) < Self::CAPACITY {
            self.list[self.kept as usize] = e;
            self.kept += 1;
        }
        self.total = self.total.saturating_add(1);
    }

    /// The errors kept, in the order checked.
    pub fn iter(&self) -> impl Iterator<Item = &ConfigError> {
        self.list[..self.kept as usize].iter()
    }

    /// The first field out of range.
    pub fn first(&self) -> &ConfigError {
        &self.list[0]
    }

    /// How many fields are out of range (kept or not).
    pub fn total(&self) -> usize {
        self.total as usize
    }
}

impl fmt::Display for ConfigErrors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let n = self.total();
        write!(f, "{n} configuration field{} out of range:", if n == 1 { "" } else { "s" })?;
        for e in self.iter() {
            write!(f, "\n  {e}")?;
        }
        if n > self.kept as usize {
            write!(f, "\n  … and {} more", n - self.kept as usize)?;
        }
        Ok(())
    }
}

impl core::error::Error for ConfigErrors {}

/// Collects every failing check.
struct Check(ConfigErrors);

impl Check {
    fn ok(&mut self, good: bool, field: &'static str, allowed: &'static str, value: f32) {
        if !good {
            self.0.push(ConfigError { field, allowed, value });
        }
    }
    /// Applies `check` to each axis of `v`, named by `names`.
    fn each(
        &mut self,
        names: [&'static str; 3],
        v: [f32; 3],
        check: fn(&mut Self, &'static str, f32),
    ) {
        for (name, x) in names.into_iter().zip(v) {
            check(self, name, x);
        }
    }

    fn positive(&mut self, field: &'static str, v: f32) {
        self.ok(v > 0.0 && v.is_finite(), field, POSITIVE, v);
    }
    fn non_negative(&mut self, field: &'static str, v: f32) {
        self.ok(v >= 0.0 && v.is_finite(), field, NON_NEGATIVE, v);
    }
    /// > 0, where +∞ switches the check or gate off (NaN fails).
    fn positive_or_inf(&mut self, field: &'static str, v: f32) {
        self.ok(v > 0.0, field, POSITIVE_OR_INF, v);
    }
    fn within(&mut self, field: &'static str, allowed: &'static str, v: f32, lo: f32, hi: f32) {
        self.ok(v >= lo && v <= hi, field, allowed, v);
    }
    fn at_least_one(&mut self, field: &'static str, v: f32) {
        self.ok(v >= 1.0, field, "≥ 1", v);
    }
}

const HALF_PI: f32 = crate::math::PI / 2.0;

impl Config {
    /// Checks every range the field types cannot express: noise densities, σ and gates
    /// positive (gates and limits documented as "`f32::INFINITY` disables" may be +∞),
    /// the latency in [0, 0.5] s, decimations ≥ 1, angles within their quadrant, and
    /// nothing NaN; of the filter's options, those `filter` holds. Returns the first
    /// offending field. `Config::default()`, `Config::euler()` and `Config::thesis()` pass.
    /// Not on the sample path: call it where the configuration is built.
    // Every error at once without an allocator (~0.5 KB); built once, never per sample.
    #[allow(clippy::result_large_err)]
    pub fn validate(&self) -> Result<(), ConfigErrors> {
        let mut c = Check(ConfigErrors::NONE);
        // Sensor noise and process model.
        c.positive("gyro_noise_density", self.gyro_noise_density);
        match self.bias_model {
            BiasModel::GaussMarkov { sigma, tau } => {
                c.positive("bias_model.sigma", sigma);
                c.positive("bias_model.tau", tau);
            }
            BiasModel::RandomWalk { density } => c.non_negative("bias_model.density", density),
        }
        // Initialisation.
        c.positive("init_sigma_attitude", self.init_sigma_attitude);
        c.positive("init_sigma_bias", self.init_sigma_bias);
        // Operational limits.
        c.non_negative("min_ground_speed_yaw", self.min_ground_speed_yaw);
        c.positive("gps_timeout", self.gps_timeout);
        c.positive("gps_max_interval", self.gps_max_interval);
        c.ok(
            self.gps_min_interval >= 0.0 && self.gps_min_interval < self.gps_max_interval,
            "gps_min_interval",
            "≥ 0 and < gps_max_interval",
            self.gps_min_interval,
        );
        c.positive("dt_max", self.dt_max);
        c.positive_or_inf("gyro_range", self.gyro_range);
        c.positive_or_inf("accel_range", self.accel_range);
        c.positive_or_inf("velocity_range", self.velocity_range);
        c.positive_or_inf("airspeed_range", self.airspeed_range);
        c.at_least_one("covariance_decimation", self.covariance_decimation as f32);
        c.positive_or_inf("gyro_clip", self.gyro_clip);
        c.positive_or_inf("accel_clip", self.accel_clip);
        for s in self.gyro_scale {
            c.within("gyro_scale", "each in [−0.1, 0.1]", s, -0.1, 0.1);
        }
        for b in self.accel_bias {
            c.within("accel_bias", "each in [−2, 2] m/s²", b, -2.0, 2.0);
        }
        c.within("gps_latency", "in [0, 0.5] s", self.gps_latency, 0.0, 0.5);
        match &self.filter {
            Filter::Quaternion(q) => check_quat(&mut c, q),
            Filter::Euler(e) => {
                #[cfg(not(feature = "euler"))]
                c.ok(
                    false,
                    FILTER,
                    "Filter::Quaternion (the crate is built without the `euler` feature)",
                    f32::NAN,
                );
                check_euler(&mut c, e)
            }
        }
        self.check_mounting(&mut c);
        if c.0.total == 0 {
            Ok(())
        } else {
            Err(c.0)
        }
    }

    /// This configuration as a [`ValidConfig`] (what [`crate::Ahrs::new`] takes), or every
    /// field out of range.
    // Every error at once without an allocator (~0.5 KB); built once, never per sample.
    #[allow(clippy::result_large_err)]
    pub fn validated(self) -> Result<ValidConfig, ConfigErrors> {
        self.validate().map(|()| ValidConfig(self))
    }

    fn check_mounting(&self, c: &mut Check) {
        let m = &self.mounting;
        let pi = crate::math::PI;
        let names = ["mounting.offsets[0]", "mounting.offsets[1]", "mounting.offsets[2]"];
        for (i, name) in names.into_iter().enumerate() {
            c.within(name, "in [−π, π] rad", m.offsets[i], -pi, pi);
        }
        c.positive("mounting.estimate_time", m.estimate_time);
        c.non_negative("mounting.estimate_min_speed", m.estimate_min_speed);
        c.positive("mounting.estimate_max_rate", m.estimate_max_rate);
        c.ok(
            m.estimate_max_bank > 0.0 && m.estimate_max_bank <= HALF_PI,
            "mounting.estimate_max_bank",
            "in (0, π/2] rad",
            m.estimate_max_bank,
        );
        c.within("mounting.expected_aoa", "in [−π/2, π/2] rad", m.expected_aoa, -HALF_PI, HALF_PI);
    }
}

fn check_euler(c: &mut Check, e: &EulerConfig) {
    c.non_negative("EulerConfig::bias_lambda", e.bias_lambda);
    c.non_negative("EulerConfig::attitude_process_noise", e.attitude_process_noise);
    match e.meas_noise {
        MeasNoise::Fixed { sigma } => {
            let names = [
                "EulerConfig::meas_noise.sigma[0]",
                "EulerConfig::meas_noise.sigma[1]",
                "EulerConfig::meas_noise.sigma[2]",
            ];
            c.each(names, sigma, Check::positive);
        }
        MeasNoise::FromSensors { vel_sigma, floor, correlated_fix_noise } => {
            c.positive("EulerConfig::meas_noise.vel_sigma", vel_sigma);
            // Only EKF1 carries the fix noise as states: with EKF2 the flag would be ignored.
            c.ok(
                !(correlated_fix_noise && matches!(e.model, Model::Ekf2(_))),
                "EulerConfig::meas_noise.correlated_fix_noise",
                "false with `Model::Ekf2` (only EKF1 carries the fix noise as states)",
                1.0,
            );
            let names = [
                "EulerConfig::meas_noise.floor[0]",
                "EulerConfig::meas_noise.floor[1]",
                "EulerConfig::meas_noise.floor[2]",
            ];
            c.each(names, floor, Check::non_negative);
        }
    }
    let names =
        ["EulerConfig::gate_chi2[0]", "EulerConfig::gate_chi2[1]", "EulerConfig::gate_chi2[2]"];
    c.each(names, e.gate_chi2, Check::positive_or_inf);
    c.at_least_one("EulerConfig::gate_max_consecutive", e.gate_max_consecutive as f32);
    c.positive_or_inf("EulerConfig::max_lateral_accel_yaw", e.max_lateral_accel_yaw);
    c.ok(
        e.gimbal_limit > 0.0 && e.gimbal_limit < HALF_PI,
        "EulerConfig::gimbal_limit",
        "in (0, π/2) rad",
        e.gimbal_limit,
    );
    c.at_least_one(
        "EulerConfig::covariance_decimation_settling",
        e.covariance_decimation_settling as f32,
    );
    // EKF1's options are enums: nothing to check.
    if let Model::Ekf2(e2) = &e.model {
        c.non_negative("Ekf2Config::window", e2.window);
        c.positive("Ekf2Config::va_bin", e2.va_bin);
        c.ok(
            (2..=16).contains(&e2.va_dot_window),
            "Ekf2Config::va_dot_window",
            "in 2..=16",
            e2.va_dot_window as f32,
        );
        c.non_negative("Ekf2Config::min_airspeed", e2.min_airspeed);
        c.non_negative("Ekf2Config::airborne_hold", e2.airborne_hold);
        c.non_negative("Ekf2Config::ground_speed_static", e2.ground_speed_static);
        c.positive_or_inf("Ekf2Config::max_lateral_accel", e2.max_lateral_accel);
        c.positive("Ekf2Config::rp_sigma[0]", e2.rp_sigma[0]);
        c.positive("Ekf2Config::rp_sigma[1]", e2.rp_sigma[1]);
    }
}

fn check_quat(c: &mut Check, q: &QuatConfig) {
    c.positive("QuatConfig::accel_noise_density", q.accel_noise_density);
    c.non_negative("QuatConfig::accel_floor", q.accel_floor);
    c.non_negative("QuatConfig::accel_floor_rel", q.accel_floor_rel);
    c.positive_or_inf("QuatConfig::gate_chi2", q.gate_chi2);
    c.positive_or_inf("QuatConfig::gate_chi2_heading", q.gate_chi2_heading);
    c.at_least_one("QuatConfig::gate_max_consecutive", q.gate_max_consecutive as f32);
    c.non_negative("QuatConfig::bias_plausible_sigmas", q.bias_plausible_sigmas);
    c.positive("QuatConfig::course_sigma", q.course_sigma);
    c.within("QuatConfig::course_max_bank", "in [0, π/2] rad", q.course_max_bank, 0.0, HALF_PI);
    c.positive_or_inf("QuatConfig::course_max_lateral", q.course_max_lateral);
    c.non_negative("QuatConfig::course_interval", q.course_interval);
    c.non_negative("QuatConfig::crab_wind", q.crab_wind);
    c.positive_or_inf("QuatConfig::wind_max_sigma", q.wind_max_sigma);
    c.positive("QuatConfig::unreported_vel_sigma", q.unreported_vel_sigma);
    c.non_negative("QuatConfig::wind_heading_memory", q.wind_heading_memory);
    c.non_negative("QuatConfig::wind_walk", q.wind_walk);
    c.non_negative("QuatConfig::airspeed_walk", q.airspeed_walk);
    c.positive("QuatConfig::wind_init_sigma", q.wind_init_sigma);
    c.positive("QuatConfig::flow_angle_sigma", q.flow_angle_sigma);
    c.positive("QuatConfig::airspeed_sigma", q.airspeed_sigma);
    c.positive_or_inf("QuatConfig::vibration_ratio", q.vibration_ratio);
    c.non_negative("QuatConfig::gyro_rate_noise", q.gyro_rate_noise);
    c.within("QuatConfig::gyro_scale_sigma", "in [0, 0.1]", q.gyro_scale_sigma, 0.0, 0.1);
    c.within(
        "QuatConfig::gyro_misalignment_sigma",
        "in [0, 0.1] rad",
        q.gyro_misalignment_sigma,
        0.0,
        0.1,
    );
    c.within("QuatConfig::latency_gain", "in [0, 1]", q.latency_gain, 0.0, 1.0);
    c.within("QuatConfig::latency_sigma", "in [0, 1] s", q.latency_sigma, 0.0, 1.0);
    c.within(
        "QuatConfig::course_align_max_bank",
        "in [0, π/2] rad",
        q.course_align_max_bank,
        0.0,
        HALF_PI,
    );
    c.non_negative("QuatConfig::accel_bias_sigma", q.accel_bias_sigma);
    c.within("QuatConfig::mounting_sigma", "in [0, π/2] rad", q.mounting_sigma, 0.0, HALF_PI);
    c.within("QuatConfig::heading_rate_sigma", "in [0, 1] rad/s", q.heading_rate_sigma, 0.0, 1.0);
    #[cfg(feature = "gyro-scale-states")]
    let (allowed, hi) = ("in [0, 0.1]", 0.1);
    #[cfg(not(feature = "gyro-scale-states"))]
    let (allowed, hi) = ("0 (the crate is built without the `gyro-scale-states` feature)", 0.0);
    c.within("QuatConfig::gyro_scale_state_sigma", allowed, q.gyro_scale_state_sigma, 0.0, hi);
    #[cfg(not(feature = "latency-consider"))]
    c.ok(
        !q.latency_consider,
        "QuatConfig::latency_consider",
        "false (the crate is built without the `latency-consider` feature)",
        1.0,
    );
}

#[cfg(test)]
mod tests {
    use super::super::{BiasModel, Config, Ekf2Config, EulerConfig, MeasNoise, Model, QuatConfig};

    #[test]
    #[cfg(feature = "euler")]
    fn the_shipped_configurations_validate() {
        for (name, c) in [
            ("default", Config::default()),
            ("euler", Config::euler()),
            ("thesis", Config::thesis()),
            ("euler EKF2", Config::euler().with_model(Model::Ekf2(Ekf2Config::default()))),
            ("thesis EKF2", Config::thesis().with_model(Model::Ekf2(Ekf2Config::THESIS))),
        ] {
            assert_eq!(c.validate(), Ok(()), "Config::{name}()");
        }
    }

    type Case = (&'static str, fn(&mut Config));
    type EulerCase = (&'static str, fn(&mut EulerConfig));
    type QuatCase = (&'static str, fn(&mut QuatConfig));

    /// EKF2 with the default options but one.
    fn ekf2(spoil: fn(&mut Ekf2Config)) -> Model {
        let mut e = Ekf2Config::default();
        spoil(&mut e);
        Model::Ekf2(e)
    }

    fn sensors(vel_sigma: f32, floor: [f32; 3]) -> MeasNoise {
        MeasNoise::FromSensors { vel_sigma, floor, correlated_fix_noise: true }
    }

    /// One out-of-range value per field, each named in the error.
    const CASES: &[Case] = &[
        ("gyro_noise_density", |c| c.gyro_noise_density = 0.0),
        ("bias_model.sigma", |c| c.bias_model = BiasModel::GaussMarkov { sigma: -1.0, tau: 1.0 }),
        ("bias_model.tau", |c| c.bias_model = BiasModel::GaussMarkov { sigma: 1.0, tau: 0.0 }),
        ("bias_model.density", |c| c.bias_model = BiasModel::RandomWalk { density: f32::NAN }),
        ("init_sigma_attitude", |c| c.init_sigma_attitude = 0.0),
        ("init_sigma_bias", |c| c.init_sigma_bias = f32::INFINITY),
        ("min_ground_speed_yaw", |c| c.min_ground_speed_yaw = -1.0),
        ("gps_timeout", |c| c.gps_timeout = 0.0),
        ("gps_max_interval", |c| c.gps_max_interval = f32::NAN),
        ("gps_min_interval", |c| c.gps_min_interval = -0.1),
        ("gps_min_interval", |c| c.gps_min_interval = c.gps_max_interval),
        ("dt_max", |c| c.dt_max = 0.0),
        ("gyro_range", |c| c.gyro_range = 0.0),
        ("accel_range", |c| c.accel_range = -1.0),
        ("velocity_range", |c| c.velocity_range = f32::NAN),
        ("airspeed_range", |c| c.airspeed_range = 0.0),
        ("covariance_decimation", |c| c.covariance_decimation = 0),
        ("gyro_clip", |c| c.gyro_clip = 0.0),
        ("gyro_scale", |c| c.gyro_scale = [0.0, f32::NAN, 0.0]),
        ("accel_clip", |c| c.accel_clip = f32::NAN),
        ("gps_latency", |c| c.gps_latency = 0.6),
        ("gps_latency", |c| c.gps_latency = -0.01),
        ("mounting.offsets[0]", |c| c.mounting.offsets[0] = 4.0),
        ("mounting.offsets[1]", |c| c.mounting.offsets[1] = f32::NAN),
        ("mounting.offsets[2]", |c| c.mounting.offsets[2] = -4.0),
        ("mounting.estimate_time", |c| c.mounting.estimate_time = 0.0),
        ("mounting.estimate_min_speed", |c| c.mounting.estimate_min_speed = -1.0),
        ("mounting.estimate_max_rate", |c| c.mounting.estimate_max_rate = 0.0),
        ("mounting.estimate_max_bank", |c| c.mounting.estimate_max_bank = 0.0),
        ("mounting.expected_aoa", |c| c.mounting.expected_aoa = 2.0),
    ];

    /// The same for the Euler filter's options.
    const EULER_CASES: &[EulerCase] = &[
        ("EulerConfig::bias_lambda", |e| e.bias_lambda = -1.0),
        ("EulerConfig::attitude_process_noise", |e| e.attitude_process_noise = f32::INFINITY),
        ("EulerConfig::meas_noise.sigma[0]", |e| {
            e.meas_noise = MeasNoise::Fixed { sigma: [0.0, 0.1, 0.1] }
        }),
        ("EulerConfig::meas_noise.sigma[1]", |e| {
            e.meas_noise = MeasNoise::Fixed { sigma: [0.1, -0.1, 0.1] }
        }),
        ("EulerConfig::meas_noise.sigma[2]", |e| {
            e.meas_noise = MeasNoise::Fixed { sigma: [0.1, 0.1, f32::NAN] }
        }),
        ("EulerConfig::meas_noise.vel_sigma", |e| e.meas_noise = sensors(0.0, [0.0; 3])),
        ("EulerConfig::meas_noise.floor[0]", |e| e.meas_noise = sensors(0.1, [-1.0, 0.0, 0.0])),
        ("EulerConfig::meas_noise.floor[1]", |e| e.meas_noise = sensors(0.1, [0.0, f32::NAN, 0.0])),
        ("EulerConfig::meas_noise.floor[2]", |e| e.meas_noise = sensors(0.1, [0.0, 0.0, -1.0])),
        ("EulerConfig::gate_chi2[0]", |e| e.gate_chi2[0] = 0.0),
        ("EulerConfig::gate_chi2[1]", |e| e.gate_chi2[1] = f32::NAN),
        ("EulerConfig::gate_chi2[2]", |e| e.gate_chi2[2] = -3.0),
        ("EulerConfig::gate_max_consecutive", |e| e.gate_max_consecutive = 0),
        ("EulerConfig::max_lateral_accel_yaw", |e| e.max_lateral_accel_yaw = 0.0),
        ("EulerConfig::gimbal_limit", |e| e.gimbal_limit = 1.6),
        ("EulerConfig::covariance_decimation_settling", |e| e.covariance_decimation_settling = 0),
        ("Ekf2Config::window", |e| *e = e.with_model(ekf2(|x| x.window = -0.5))),
        ("Ekf2Config::va_bin", |e| *e = e.with_model(ekf2(|x| x.va_bin = 0.0))),
        ("Ekf2Config::va_dot_window", |e| *e = e.with_model(ekf2(|x| x.va_dot_window = 1))),
        ("Ekf2Config::va_dot_window", |e| *e = e.with_model(ekf2(|x| x.va_dot_window = 17))),
        ("Ekf2Config::min_airspeed", |e| *e = e.with_model(ekf2(|x| x.min_airspeed = -1.0))),
        ("Ekf2Config::airborne_hold", |e| *e = e.with_model(ekf2(|x| x.airborne_hold = f32::NAN))),
        ("Ekf2Config::ground_speed_static", |e| {
            *e = e.with_model(ekf2(|x| x.ground_speed_static = -2.0))
        }),
        ("Ekf2Config::max_lateral_accel", |e| {
            *e = e.with_model(ekf2(|x| x.max_lateral_accel = 0.0))
        }),
        ("Ekf2Config::rp_sigma[0]", |e| *e = e.with_model(ekf2(|x| x.rp_sigma[0] = 0.0))),
        ("Ekf2Config::rp_sigma[1]", |e| *e = e.with_model(ekf2(|x| x.rp_sigma[1] = f32::NAN))),
    ];

    /// The same for the quaternion filter's options.
    const QUAT_CASES: &[QuatCase] = &[
        ("QuatConfig::accel_noise_density", |q| q.accel_noise_density = 0.0),
        ("QuatConfig::accel_floor", |q| q.accel_floor = -0.05),
        ("QuatConfig::accel_floor_rel", |q| q.accel_floor_rel = f32::NAN),
        ("QuatConfig::gate_chi2", |q| q.gate_chi2 = 0.0),
        ("QuatConfig::gate_chi2_heading", |q| q.gate_chi2_heading = -1.0),
        ("QuatConfig::gate_max_consecutive", |q| q.gate_max_consecutive = 0),
        ("QuatConfig::bias_plausible_sigmas", |q| q.bias_plausible_sigmas = f32::NAN),
        ("QuatConfig::course_sigma", |q| q.course_sigma = 0.0),
        ("QuatConfig::course_max_bank", |q| q.course_max_bank = 2.0),
        ("QuatConfig::course_max_lateral", |q| q.course_max_lateral = 0.0),
        ("QuatConfig::course_interval", |q| q.course_interval = -1.0),
        ("QuatConfig::crab_wind", |q| q.crab_wind = f32::NAN),
        ("QuatConfig::wind_max_sigma", |q| q.wind_max_sigma = 0.0),
        ("QuatConfig::unreported_vel_sigma", |q| q.unreported_vel_sigma = 0.0),
        ("QuatConfig::wind_heading_memory", |q| q.wind_heading_memory = -1.0),
        ("QuatConfig::wind_walk", |q| q.wind_walk = -0.03),
        ("QuatConfig::airspeed_walk", |q| q.airspeed_walk = f32::INFINITY),
        ("QuatConfig::wind_init_sigma", |q| q.wind_init_sigma = 0.0),
        ("QuatConfig::flow_angle_sigma", |q| q.flow_angle_sigma = 0.0),
        ("QuatConfig::airspeed_sigma", |q| q.airspeed_sigma = -1.0),
        ("QuatConfig::vibration_ratio", |q| q.vibration_ratio = 0.0),
        ("QuatConfig::gyro_rate_noise", |q| q.gyro_rate_noise = -0.1),
        ("QuatConfig::gyro_scale_sigma", |q| q.gyro_scale_sigma = 0.5),
        ("QuatConfig::gyro_misalignment_sigma", |q| q.gyro_misalignment_sigma = f32::NAN),
        ("QuatConfig::latency_gain", |q| q.latency_gain = 2.0),
        ("QuatConfig::latency_sigma", |q| q.latency_sigma = f32::NAN),
        ("QuatConfig::course_align_max_bank", |q| q.course_align_max_bank = f32::NAN),
        ("QuatConfig::accel_bias_sigma", |q| q.accel_bias_sigma = -0.1),
        ("QuatConfig::mounting_sigma", |q| q.mounting_sigma = f32::INFINITY),
        ("QuatConfig::heading_rate_sigma", |q| q.heading_rate_sigma = -0.01),
        ("QuatConfig::gyro_scale_state_sigma", |q| q.gyro_scale_state_sigma = 0.5),
    ];

    fn named(c: &Config, field: &str) {
        // The spoilt field first (a field others are checked against fails them too).
        let errors = c.validate().expect_err(field);
        let e = errors.first();
        assert_eq!(e.field, field, "{e}");
        let msg = format!("{errors}");
        assert!(msg.contains(field) && msg.contains(e.allowed), "{msg}");
        assert_eq!(c.validated().err().map(|e| e.first().field), Some(field));
    }

    /// Built without the `euler` feature (as the firmware is), the quaternion filter still
    /// validates and the Euler filter is refused by name, never built in its place.
    #[test]
    #[cfg(not(feature = "euler"))]
    fn without_the_euler_feature_the_euler_filter_is_refused() {
        assert_eq!(Config::default().validate(), Ok(()));
        for c in [Config::euler(), Config::thesis()] {
            let e = c.validate().unwrap_err();
            assert_eq!(e.first().field, "filter", "{e}");
            assert!(format!("{e}").contains("without the `euler` feature"), "{e}");
        }
    }

    #[test]
    #[cfg(not(feature = "latency-consider"))]
    fn without_the_latency_consider_feature_the_switch_is_refused() {
        let mut c = Config::default();
        c.quat_mut().unwrap().latency_consider = true;
        named(&c, "QuatConfig::latency_consider");
    }

    #[test]
    fn every_error_is_reported_at_once() {
        let mut c = Config { gyro_noise_density: -1.0, gps_latency: 2.0, ..Config::default() };
        c.quat_mut().unwrap().accel_noise_density = f32::NAN;
        let errors = c.validate().expect_err("three fields out of range");
        let fields: Vec<_> = errors.iter().map(|e| e.field).collect();
        assert_eq!(
            fields,
            ["gyro_noise_density", "gps_latency", "QuatConfig::accel_noise_density"],
            "{errors}"
        );
        let msg = format!("{errors}");
        assert!(msg.starts_with("3 configuration fields out of range"), "{msg}");
        // More than the kept errors: all counted, the rest summarised.
        let mut c = Config {
            gyro_scale: [1.0; 3],
            accel_bias: [9.0; 3],
            gps_latency: -1.0,
            gyro_noise_density: 0.0,
            init_sigma_bias: 0.0,
            ..Config::default()
        };
        c.mounting.offsets = [9.0; 3];
        c.mounting.expected_aoa = 9.0;
        let errors = c.validate().expect_err("thirteen");
        assert_eq!(errors.total(), 13, "{errors}");
        assert_eq!(errors.iter().count(), super::ConfigErrors::CAPACITY);
        assert!(format!("{errors}").ends_with("… and 1 more"), "{errors}");
    }

    #[test]
    #[cfg(feature = "euler")]
    fn ekf2_with_fix_noise_states_cannot_be_built() {
        // `with_model` turns the flag EKF2 would ignore off ...
        let c = Config::euler().with_model(Model::Ekf2(Ekf2Config::default()));
        assert_eq!(c.validate(), Ok(()));
        // ... and setting it by hand is refused.
        let mut c = c;
        c.euler_mut().unwrap().meas_noise = Config::DEFAULT_MEAS_NOISE;
        named(&c, "EulerConfig::meas_noise.correlated_fix_noise");
    }

    /// The Euler filter's shipped configurations, where the crate is built with it.
    fn euler_bases() -> Vec<Config> {
        if cfg!(feature = "euler") {
            vec![Config::euler(), Config::thesis()]
        } else {
            Vec::new()
        }
    }

    #[test]
    fn every_out_of_range_field_is_named() {
        for base in [Config::default()].into_iter().chain(euler_bases()) {
            for (field, spoil) in CASES {
                let mut c = base;
                spoil(&mut c);
                named(&c, field);
            }
        }
        for base in euler_bases() {
            for (field, spoil) in EULER_CASES {
                let mut c = base;
                spoil(c.euler_mut().unwrap());
                named(&c, field);
            }
        }
        for (field, spoil) in QUAT_CASES {
            let mut c = Config::default();
            spoil(c.quat_mut().unwrap());
            named(&c, field);
        }
    }

    #[test]
    fn infinity_disables_the_gates_and_limits() {
        let inf = f32::INFINITY;
        let mut c = Config { gyro_clip: inf, ..Config::default() };
        c.quat_mut().unwrap().gate_chi2 = inf;
        assert_eq!(c.validate(), Ok(()));
        if !cfg!(feature = "euler") {
            return;
        }
        let mut c = Config::euler().with_model(Model::Ekf2(Ekf2Config {
            max_lateral_accel: inf,
            ..Ekf2Config::default()
        }));
        let e = c.euler_mut().unwrap();
        e.gate_chi2 = [inf; 3];
        e.max_lateral_accel_yaw = inf;
        assert_eq!(c.validate(), Ok(()));
    }
}
