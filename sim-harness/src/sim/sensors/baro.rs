//! Barometric altimeter: the true height plus a first-order Gauss–Markov drift (weather
//! and temperature move a baro's zero by metres over minutes), white noise and
//! quantization, at its own rate. Written as `baro_alt` (datum: the WGS-84 height the
//! drift starts from, so it reads close to the GPS `alt`).

use super::{gauss_markov, quantize};
use anyhow::{ensure, Result};
use rand::Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

/// Barometer parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BaroParams {
    /// Sample rate, Hz (≤ the IMU rate; 0 = no barometer).
    pub rate_hz: f64,
    /// White noise, 1-σ, m.
    pub noise_m: f64,
    /// Drift: stationary 1-σ, m, and correlation time, s (σ 0 = none).
    pub drift_sigma_m: f64,
    pub drift_tau_s: f64,
    /// Quantization step, m (0 = none).
    pub lsb_m: f64,
}

impl Default for BaroParams {
    /// No barometer.
    fn default() -> Self {
        BaroParams {
            rate_hz: 0.0,
            noise_m: 0.0,
            drift_sigma_m: 0.0,
            drift_tau_s: 300.0,
            lsb_m: 0.0,
        }
    }
}

impl BaroParams {
    pub fn validate(&self, imu_rate: f64) -> Result<()> {
        ensure!(
            self.rate_hz.is_finite() && self.rate_hz >= 0.0 && self.rate_hz <= imu_rate,
            "sensors.baro.rate_hz must be in [0, imu rate = {imu_rate}] Hz, got {}",
            self.rate_hz
        );
        for (k, v) in [
            ("noise_m", self.noise_m),
            ("drift_sigma_m", self.drift_sigma_m),
            ("lsb_m", self.lsb_m),
        ] {
            ensure!(
                v.is_finite() && v >= 0.0,
                "sensors.baro.{k} must be a finite number ≥ 0, got {v}"
            );
        }
        ensure!(
            self.drift_tau_s.is_finite() && self.drift_tau_s > 0.0,
            "sensors.baro.drift_tau_s must be > 0, got {}",
            self.drift_tau_s
        );
        Ok(())
    }
}

/// The sensor, its drift state and sample schedule.
#[derive(Debug, Clone)]
pub struct BaroModel {
    params: BaroParams,
    next: u64,
    drift: Option<f64>,
}

impl BaroModel {
    pub fn new(params: &BaroParams) -> Self {
        BaroModel { params: params.clone(), next: 0, drift: None }
    }

    /// A reading at IMU sample time `t` (s) when one is due, from the true height `h` (m).
    pub fn sample<R: Rng>(&mut self, t: f64, h: f64, rng: &mut R) -> Option<f64> {
        let p = &self.params;
        if p.rate_hz <= 0.0 || t + 1e-9 < self.next as f64 / p.rate_hz {
            return None;
        }
        self.next += 1;
        let mut w = || rng.sample::<f64, _>(StandardNormal);
        let d = match self.drift {
            None => p.drift_sigma_m * w(),
            Some(d) => gauss_markov(d, p.drift_sigma_m, p.drift_tau_s, 1.0 / p.rate_hz, w()),
        };
        self.drift = Some(d);
        Some(quantize(h + d + p.noise_m * w(), p.lsb_m))
    }
}
