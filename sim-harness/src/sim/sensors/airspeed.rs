//! Airspeed sensor (thesis eq 5.1): true airspeed plus white noise, an optional
//! constant bias and quantization, at its own rate.

use super::quantize;
use anyhow::{ensure, Result};
use rand::Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

/// Airspeed-sensor parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AirspeedParams {
    /// Sample rate, Hz (≤ the IMU rate; 0 = no airspeed sensor).
    pub rate_hz: f64,
    /// White noise, 1-σ, m/s.
    pub noise_m_s: f64,
    /// Constant bias, m/s.
    pub bias_m_s: f64,
    /// Quantization step, m/s (0 = none).
    pub lsb_m_s: f64,
}

impl AirspeedParams {
    pub fn validate(&self, imu_rate: f64) -> Result<()> {
        ensure!(
            self.rate_hz.is_finite() && self.rate_hz >= 0.0 && self.rate_hz <= imu_rate,
            "sensors.airspeed.rate_hz must be in [0, imu rate = {imu_rate}] Hz, got {}",
            self.rate_hz
        );
        ensure!(
            self.noise_m_s.is_finite() && self.noise_m_s >= 0.0,
            "sensors.airspeed.noise_m_s must be ≥ 0"
        );
        ensure!(self.bias_m_s.is_finite(), "sensors.airspeed.bias_m_s must be finite");
        ensure!(
            self.lsb_m_s.is_finite() && self.lsb_m_s >= 0.0,
            "sensors.airspeed.lsb_m_s must be ≥ 0"
        );
        Ok(())
    }
}

/// The sensor and its sample schedule.
#[derive(Debug, Clone)]
pub struct AirspeedModel {
    params: AirspeedParams,
    next: u64,
}

impl AirspeedModel {
    pub fn new(params: &AirspeedParams) -> Self {
        AirspeedModel { params: params.clone(), next: 0 }
    }

    /// A reading at IMU sample time `t` (s) when one is due, from true airspeed `va` (m/s).
    pub fn sample<R: Rng>(&mut self, t: f64, va: f64, rng: &mut R) -> Option<f64> {
        if self.params.rate_hz <= 0.0 || t + 1e-9 < self.next as f64 / self.params.rate_hz {
            return None;
        }
        self.next += 1;
        let p = &self.params;
        let m = va + p.bias_m_s + p.noise_m_s * rng.sample::<f64, _>(StandardNormal);
        Some(quantize(m, p.lsb_m_s).max(0.0))
    }
}
