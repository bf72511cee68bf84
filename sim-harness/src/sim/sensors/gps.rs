//! GPS velocity receiver model (thesis eqs 4.14–4.15, §4.1.2): the true NED
//! velocity passed through the receiver's smoothing (a first-order lag, τ), plus
//! white noise per axis, sampled at the fix rate (epochs at k / rate s), each
//! fix delivered `latency_s` after its epoch at the first IMU sample at or after
//! that time, none during outages.

use crate::log::GpsSample;
use crate::sim::rotation::V3;
use anyhow::{ensure, Result};
use rand::Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};
use std::collections::VecDeque;

/// GPS parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GpsParams {
    /// Fix rate, Hz (1–10 typical; ≤ the IMU rate).
    pub rate_hz: f64,
    /// White velocity noise, 1-σ, north/east and down, m/s.
    pub vel_noise_ne_m_s: f64,
    pub vel_noise_d_m_s: f64,
    /// Delay from a fix's epoch to its delivery, s.
    pub latency_s: f64,
    /// Receiver smoothing time constant (first-order lag on velocity), s (0 = none).
    pub smoothing_tau_s: f64,
}

impl GpsParams {
    pub fn validate(&self, imu_rate: f64) -> Result<()> {
        ensure!(
            self.rate_hz.is_finite() && self.rate_hz >= 0.1 && self.rate_hz <= imu_rate,
            "sensors.gps.rate_hz must be in [0.1, imu rate = {imu_rate}] Hz, got {}",
            self.rate_hz
        );
        for (k, v) in [
            ("vel_noise_ne_m_s", self.vel_noise_ne_m_s),
            ("vel_noise_d_m_s", self.vel_noise_d_m_s),
            ("latency_s", self.latency_s),
            ("smoothing_tau_s", self.smoothing_tau_s),
        ] {
            ensure!(
                v.is_finite() && v >= 0.0,
                "sensors.gps.{k} must be a finite number ≥ 0, got {v}"
            );
        }
        ensure!(
            self.latency_s <= 2.0,
            "sensors.gps.latency_s must be ≤ 2 s, got {}",
            self.latency_s
        );
        Ok(())
    }
}

/// The receiver: smoothing state, epoch counter and the fixes in flight.
#[derive(Debug, Clone)]
pub struct GpsModel {
    params: GpsParams,
    outages: Vec<(f64, f64)>,
    filt: Option<V3>,
    last_t: f64,
    next_epoch: u64,
    in_flight: VecDeque<(f64, GpsSample)>,
}

impl GpsModel {
    /// `outages`: half-open epoch intervals [start, end) s with no fix.
    pub fn new(params: &GpsParams, outages: &[(f64, f64)]) -> Self {
        GpsModel {
            params: params.clone(),
            outages: outages.to_vec(),
            filt: None,
            last_t: 0.0,
            next_epoch: 0,
            in_flight: VecDeque::new(),
        }
    }

    /// Whether epoch `t` falls in an outage.
    pub fn in_outage(&self, t: f64) -> bool {
        self.outages.iter().any(|&(a, b)| t >= a && t < b)
    }

    /// Called at every internal simulation step with the true NED velocity (m/s)
    /// at time `t` (s): advances the smoothing and takes a fix when an epoch is due.
    pub fn on_step<R: Rng>(&mut self, t: f64, vel_ned: V3, rng: &mut R) {
        let f = match self.filt {
            None => vel_ned,
            Some(f) if self.params.smoothing_tau_s > 0.0 => {
                let k = 1.0 - (-(t - self.last_t) / self.params.smoothing_tau_s).exp();
                [
                    f[0] + k * (vel_ned[0] - f[0]),
                    f[1] + k * (vel_ned[1] - f[1]),
                    f[2] + k * (vel_ned[2] - f[2]),
                ]
            }
            Some(_) => vel_ned,
        };
        self.filt = Some(f);
        self.last_t = t;
        let epoch = self.next_epoch as f64 / self.params.rate_hz;
        if t + 1e-9 >= epoch {
            self.next_epoch += 1;
            if !self.in_outage(epoch) {
                let p = &self.params;
                let n = |s: f64, rng: &mut R| s * rng.sample::<f64, _>(StandardNormal);
                let vel = [
                    f[0] + n(p.vel_noise_ne_m_s, rng),
                    f[1] + n(p.vel_noise_ne_m_s, rng),
                    f[2] + n(p.vel_noise_d_m_s, rng),
                ];
                // The receiver reports its accuracy as a u-blox does (`sAcc`): here the
                // RMS per-component σ of the noise it actually adds.
                let speed_acc =
                    ((2.0 * p.vel_noise_ne_m_s.powi(2) + p.vel_noise_d_m_s.powi(2)) / 3.0).sqrt();
                self.in_flight.push_back((
                    t + p.latency_s,
                    GpsSample { t, vel, speed_acc: Some(speed_acc), lla: None },
                ));
            }
        }
    }

    /// The oldest fix delivered by time `t` (s), if any (one per IMU row).
    pub fn pop_available(&mut self, t: f64) -> Option<GpsSample> {
        match self.in_flight.front() {
            Some(&(avail, _)) if avail <= t + 1e-9 => self.in_flight.pop_front().map(|x| x.1),
            _ => None,
        }
    }
}
