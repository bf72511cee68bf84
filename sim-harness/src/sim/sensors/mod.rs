//! Sensor error models (thesis eqs 4.1–4.16, Table 5.1) and the two presets.
//!
//! Every parameter is in the scenario file (`[sensors]` with `preset = "thesis"` or
//! `"realistic"`, then `[sensors.imu]`, `[sensors.gps]`, `[sensors.airspeed]`,
//! `[sensors.baro]` overrides). Key names carry their units. Quantities marked "1-σ of a per-run
//! draw" are drawn once per run from the seed (turn-on biases, misalignments,
//! scale factors), so a Monte Carlo over seeds also varies them.

pub mod airspeed;
pub mod baro;
pub mod gps;
pub mod imu;
pub mod vibration;

use serde::{Deserialize, Serialize};

pub use airspeed::{AirspeedModel, AirspeedParams};
pub use baro::{BaroModel, BaroParams};
pub use gps::{GpsModel, GpsParams, SaccReport};
pub use imu::{ImuModel, ImuParams};
pub use vibration::{VibrationModel, VibrationSpec};

/// All sensor parameters of a run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorParams {
    pub imu: ImuParams,
    pub gps: GpsParams,
    pub airspeed: AirspeedParams,
    /// Barometer (default: none).
    #[serde(default)]
    pub baro: BaroParams,
}

impl SensorParams {
    /// Thesis Table 5.1: accel noise 0.02 m/s², gyro noise 0.05 °/s, turn-on bias
    /// 1.5 °/s (1-σ per axis), Gauss–Markov drift σ 211 °/h τ 382 s, GPS velocity
    /// noise 0.01 m/s at 10 Hz, airspeed noise 0.06 m/s; no misalignment, scale
    /// factor, quantization, latency or receiver lag. IMU 100 Hz; airspeed at the
    /// IMU rate (the thesis does not give one). GPS positions are exact (the thesis' receiver
    /// gives velocity only); no barometer.
    pub fn thesis() -> Self {
        SensorParams {
            imu: ImuParams {
                rate_hz: 100.0,
                gyro_noise_deg_s: 0.05,
                gyro_turn_on_bias_deg_s: 1.5,
                gyro_bias_gm_sigma_deg_h: 211.0,
                gyro_bias_gm_tau_s: 382.0,
                gyro_bias_rw_deg_s_per_sqrt_s: 0.0,
                gyro_scale_factor: 0.0,
                gyro_axis_misalignment_deg: 0.0,
                gyro_lsb_deg_s: 0.0,
                accel_noise_m_s2: 0.02,
                accel_turn_on_bias_m_s2: 0.0,
                accel_bias_gm_sigma_m_s2: 0.0,
                accel_bias_gm_tau_s: 0.0,
                accel_scale_factor: 0.0,
                accel_axis_misalignment_deg: 0.0,
                accel_lsb_m_s2: 0.0,
                package_misalignment_deg: 0.0,
                mounting_offset_deg: [0.0; 3],
                gyro_clip_deg_s: 0.0,
                accel_clip_m_s2: 0.0,
            },
            gps: GpsParams {
                rate_hz: 10.0,
                vel_noise_ne_m_s: 0.01,
                vel_noise_d_m_s: 0.01,
                latency_s: 0.0,
                smoothing_tau_s: 0.0,
                pos_error_ne_m: 0.0,
                pos_error_d_m: 0.0,
                pos_error_tau_s: 60.0,
                sacc: SaccReport::Honest,
            },
            airspeed: AirspeedParams {
                rate_hz: 100.0,
                noise_m_s: 0.06,
                bias_m_s: 0.0,
                lsb_m_s: 0.0,
            },
            baro: BaroParams::default(),
        }
    }

    /// A typical small-UAV sensor set: an ICM-42688-class MEMS IMU at 100 Hz
    /// (noise includes airframe vibration, ±500 °/s and ±16 g ranges, datasheet
    /// zero-rate offset ±0.5 °/s, cross-axis ≈ 0.2°, 0.5 % scale factor), a
    /// u-blox M8/M9 receiver at 5 Hz (0.05 m/s horizontal / 0.08 m/s vertical
    /// speed noise, 100 ms latency, 0.1 s smoothing; position error 1.0 m horizontal /
    /// 1.5 m vertical 1-σ wandering with τ 60 s), an MS4525-class pitot and an MS5611-class
    /// barometer at 20 Hz (0.1 m noise, 1 m drift with τ 300 s, 1 cm steps).
    pub fn realistic() -> Self {
        SensorParams {
            imu: ImuParams {
                rate_hz: 100.0,
                gyro_noise_deg_s: 0.1,
                gyro_turn_on_bias_deg_s: 0.3,
                gyro_bias_gm_sigma_deg_h: 36.0,
                gyro_bias_gm_tau_s: 300.0,
                gyro_bias_rw_deg_s_per_sqrt_s: 0.0,
                gyro_scale_factor: 0.005,
                gyro_axis_misalignment_deg: 0.2,
                gyro_lsb_deg_s: 1.0 / 65.5,
                accel_noise_m_s2: 0.1,
                accel_turn_on_bias_m_s2: 0.1,
                accel_bias_gm_sigma_m_s2: 0.005,
                accel_bias_gm_tau_s: 600.0,
                accel_scale_factor: 0.005,
                accel_axis_misalignment_deg: 0.2,
                accel_lsb_m_s2: 9.80665 / 2048.0,
                package_misalignment_deg: 0.3,
                mounting_offset_deg: [0.0; 3],
                gyro_clip_deg_s: 0.0,
                accel_clip_m_s2: 0.0,
            },
            gps: GpsParams {
                rate_hz: 5.0,
                vel_noise_ne_m_s: 0.05,
                vel_noise_d_m_s: 0.08,
                latency_s: 0.1,
                smoothing_tau_s: 0.1,
                pos_error_ne_m: 1.0,
                pos_error_d_m: 1.5,
                pos_error_tau_s: 60.0,
                sacc: SaccReport::Honest,
            },
            airspeed: AirspeedParams { rate_hz: 20.0, noise_m_s: 0.3, bias_m_s: 0.0, lsb_m_s: 0.0 },
            baro: BaroParams {
                rate_hz: 20.0,
                noise_m: 0.1,
                drift_sigma_m: 1.0,
                drift_tau_s: 300.0,
                lsb_m: 0.01,
            },
        }
    }

    /// Checks ranges; message names the key.
    pub fn validate(&self) -> anyhow::Result<()> {
        self.imu.validate()?;
        self.gps.validate(self.imu.rate_hz)?;
        self.airspeed.validate(self.imu.rate_hz)?;
        self.baro.validate(self.imu.rate_hz)
    }
}

/// Quantizes `x` to a multiple of `lsb` (no-op when `lsb` is 0).
pub(crate) fn quantize(x: f64, lsb: f64) -> f64 {
    if lsb > 0.0 {
        (x / lsb).round() * lsb
    } else {
        x
    }
}

/// First-order Gauss–Markov step (thesis eq 4.12), exact discretisation:
/// `b ← e^{−Δt/τ} b + σ √(1 − e^{−2Δt/τ}) w`, stationary standard deviation σ.
pub(crate) fn gauss_markov(b: f64, sigma: f64, tau: f64, dt: f64, w: f64) -> f64 {
    if sigma <= 0.0 || tau <= 0.0 {
        return b;
    }
    let phi = (-dt / tau).exp();
    phi * b + sigma * (1.0 - phi * phi).sqrt() * w
}
