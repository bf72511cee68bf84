//! GPS receiver model (thesis eqs 4.14–4.15, §4.1.2): the true NED
//! velocity passed through the receiver's smoothing (a first-order lag, τ), plus
//! white noise per axis, sampled at the fix rate (epochs at k / rate s), each
//! fix delivered `latency_s` after its epoch at the first IMU sample at or after
//! that time, none during outages. The fix's position (when the caller gives the true
//! one) is the true WGS-84 position at the epoch plus a first-order Gauss–Markov error
//! per NED axis: a receiver's position error wanders over tens of seconds rather than
//! jumping from fix to fix, so differenced positions stay consistent with the velocity.

use super::gauss_markov;
use crate::log::GpsSample;
use crate::sim::geodetic;
use crate::sim::rotation::V3;
use anyhow::{ensure, Result};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
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
    /// Position error, first-order Gauss–Markov per axis: stationary 1-σ north/east and
    /// down, m (default 0 = the true position), and its correlation time, s (default 60).
    #[serde(default)]
    pub pos_error_ne_m: f64,
    #[serde(default)]
    pub pos_error_d_m: f64,
    #[serde(default = "default_pos_tau")]
    pub pos_error_tau_s: f64,
    /// What the receiver reports as its speed accuracy (`sAcc`): `"honest"` (default, the
    /// σ it adds), `"xK"` (K times that: u-blox receivers report 5–10× their velocity
    /// noise in flight), or `"none"` (NMEA, or a log without it).
    #[serde(default)]
    pub sacc: SaccReport,
}

/// How a simulated receiver reports its speed accuracy (`sAcc`).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub enum SaccReport {
    /// The RMS per-axis σ of the noise it adds.
    #[default]
    Honest,
    /// That σ times the factor (> 0).
    Scaled(f64),
    /// Nothing: the fix carries no accuracy.
    Absent,
}

impl SaccReport {
    /// The reported accuracy for a true per-axis σ `sigma`, m/s.
    pub fn report(self, sigma: f64) -> Option<f64> {
        match self {
            SaccReport::Honest => Some(sigma),
            SaccReport::Scaled(k) => Some(k * sigma),
            SaccReport::Absent => None,
        }
    }
}

impl TryFrom<String> for SaccReport {
    type Error = String;
    fn try_from(s: String) -> Result<Self, String> {
        s.parse()
    }
}

impl std::str::FromStr for SaccReport {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("sAcc report {s:?}: use honest, none or xK (K > 0, e.g. x10, x0.3)");
        match s {
            "honest" | "x1" => Ok(SaccReport::Honest),
            "none" | "absent" => Ok(SaccReport::Absent),
            _ => {
                let k: f64 = s.strip_prefix('x').and_then(|k| k.parse().ok()).ok_or_else(bad)?;
                (k.is_finite() && k > 0.0).then_some(SaccReport::Scaled(k)).ok_or_else(bad)
            }
        }
    }
}

impl From<SaccReport> for String {
    fn from(r: SaccReport) -> String {
        match r {
            SaccReport::Honest => "honest".into(),
            SaccReport::Scaled(k) => format!("x{k}"),
            SaccReport::Absent => "none".into(),
        }
    }
}

fn default_pos_tau() -> f64 {
    60.0
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
            ("pos_error_ne_m", self.pos_error_ne_m),
            ("pos_error_d_m", self.pos_error_d_m),
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
        ensure!(
            self.pos_error_tau_s.is_finite() && self.pos_error_tau_s > 0.0,
            "sensors.gps.pos_error_tau_s must be a finite number > 0, got {}",
            self.pos_error_tau_s
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
    /// Position error, NED m (None before the first epoch), and its own noise stream.
    pos_err: Option<V3>,
    pos_rng: ChaCha8Rng,
}

impl GpsModel {
    /// `outages`: half-open epoch intervals [start, end) s with no fix. `pos_rng` draws the
    /// position error only, so adding positions leaves the velocity noise of a seed alone.
    pub fn new(params: &GpsParams, outages: &[(f64, f64)], pos_rng: ChaCha8Rng) -> Self {
        GpsModel {
            params: params.clone(),
            outages: outages.to_vec(),
            filt: None,
            last_t: 0.0,
            next_epoch: 0,
            in_flight: VecDeque::new(),
            pos_err: None,
            pos_rng,
        }
    }

    /// Whether epoch `t` falls in an outage.
    pub fn in_outage(&self, t: f64) -> bool {
        self.outages.iter().any(|&(a, b)| t >= a && t < b)
    }

    /// Called at every internal simulation step with the true NED velocity (m/s)
    /// at time `t` (s): advances the smoothing and takes a fix (without position) when an
    /// epoch is due.
    pub fn on_step<R: Rng>(&mut self, t: f64, vel_ned: V3, rng: &mut R) {
        self.on_step_at(t, vel_ned, None::<fn() -> [f64; 3]>, rng);
    }

    /// [`Self::on_step`] with the true position: `lla` gives latitude, longitude (deg) and
    /// WGS-84 height (m) at `t`; it is called only when an epoch is due.
    pub fn on_step_at<R: Rng>(
        &mut self,
        t: f64,
        vel_ned: V3,
        lla: Option<impl FnOnce() -> [f64; 3]>,
        rng: &mut R,
    ) {
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
                // The receiver reports its accuracy as a u-blox does (`sAcc`), from the
                // RMS per-component σ of the noise it actually adds, as configured.
                let sigma =
                    ((2.0 * p.vel_noise_ne_m_s.powi(2) + p.vel_noise_d_m_s.powi(2)) / 3.0).sqrt();
                let speed_acc = p.sacc.report(sigma);
                let avail = t + p.latency_s;
                let lla = lla.map(|f| geodetic::offset(f(), self.position_error()));
                self.in_flight.push_back((avail, GpsSample { t, vel, speed_acc, lla }));
            }
        }
    }

    /// The position error at the next epoch, NED m: started from its stationary
    /// distribution, then one Gauss–Markov step of 1 / rate per epoch.
    fn position_error(&mut self) -> V3 {
        let p = &self.params;
        let sig = [p.pos_error_ne_m, p.pos_error_ne_m, p.pos_error_d_m];
        let rng = &mut self.pos_rng;
        let mut w = || rng.sample::<f64, _>(StandardNormal);
        let e = match self.pos_err {
            None => core::array::from_fn(|i| sig[i] * w()),
            Some(e) => core::array::from_fn(|i| {
                gauss_markov(e[i], sig[i], p.pos_error_tau_s, 1.0 / p.rate_hz, w())
            }),
        };
        self.pos_err = Some(e);
        e
    }

    /// The oldest fix delivered by time `t` (s), if any (one per IMU row).
    pub fn pop_available(&mut self, t: f64) -> Option<GpsSample> {
        match self.in_flight.front() {
            Some(&(avail, _)) if avail <= t + 1e-9 => self.in_flight.pop_front().map(|x| x.1),
            _ => None,
        }
    }
}
