//! Airframe vibration (engine, propeller) as the IMU senses it: band-limited noise added
//! to the true specific force and body rates before the IMU error model (so scale factor,
//! quantization and clipping apply to it). Each axis is a narrow-band process
//! `a(t) cos 2πf t + b(t) sin 2πf t` with a, b independent unit first-order
//! Gauss–Markov processes of correlation time 1/(π B): RMS = the amplitude, power in a
//! band of width ≈ B around f. Active from `start_s` to `end_s` (scenario `[[vibration]]`).

use super::gauss_markov;
use crate::sim::rotation::V3;
use anyhow::{ensure, Result};
use rand::Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

/// One vibration episode.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VibrationSpec {
    /// On from this time, s.
    pub start_s: f64,
    /// Off from this time, s.
    pub end_s: f64,
    /// RMS specific force per axis, m/s².
    #[serde(default)]
    pub accel_m_s2: f64,
    /// RMS angular rate per axis, °/s.
    #[serde(default)]
    pub gyro_deg_s: f64,
    /// Centre frequency, Hz (aliased by the IMU's sample rate like a real one).
    #[serde(default = "default_freq")]
    pub freq_hz: f64,
    /// Bandwidth, Hz (> 0).
    #[serde(default = "default_bw")]
    pub bandwidth_hz: f64,
}

fn default_freq() -> f64 {
    37.0
}
fn default_bw() -> f64 {
    5.0
}

impl VibrationSpec {
    pub fn validate(&self) -> Result<()> {
        ensure!(
            self.start_s.is_finite() && self.end_s.is_finite() && self.start_s < self.end_s,
            "vibration: start_s < end_s required, got [{}, {}]",
            self.start_s,
            self.end_s
        );
        for (k, v) in [
            ("accel_m_s2", self.accel_m_s2),
            ("gyro_deg_s", self.gyro_deg_s),
            ("freq_hz", self.freq_hz),
        ] {
            ensure!(
                v.is_finite() && v >= 0.0,
                "vibration.{k} must be a finite number ≥ 0, got {v}"
            );
        }
        ensure!(
            self.bandwidth_hz.is_finite() && self.bandwidth_hz > 0.0,
            "vibration.bandwidth_hz must be > 0, got {}",
            self.bandwidth_hz
        );
        Ok(())
    }
}

/// The episodes and their quadrature states (6 axes × a, b).
#[derive(Debug, Clone)]
pub struct VibrationModel {
    specs: Vec<VibrationSpec>,
    state: Vec<[[f64; 2]; 6]>,
    last_t: Option<f64>,
}

impl VibrationModel {
    pub fn new(specs: &[VibrationSpec]) -> Self {
        VibrationModel {
            specs: specs.to_vec(),
            state: vec![[[0.0; 2]; 6]; specs.len()],
            last_t: None,
        }
    }

    /// The vibration at IMU sample time `t` (s): (body rates rad/s, specific force m/s²)
    /// to add to the truth. Draws only while an episode is on.
    pub fn sample<R: Rng>(&mut self, t: f64, rng: &mut R) -> (V3, V3) {
        let dt = self.last_t.map_or(0.0, |l| t - l);
        self.last_t = Some(t);
        let (mut w, mut f) = ([0.0; 3], [0.0; 3]);
        for (s, st) in self.specs.iter().zip(&mut self.state) {
            if !(t >= s.start_s && t < s.end_s) {
                continue;
            }
            let tau = 1.0 / (std::f64::consts::PI * s.bandwidth_hz);
            let (sn, cs) = (2.0 * std::f64::consts::PI * s.freq_hz * t).sin_cos();
            for (axis, ab) in st.iter_mut().enumerate() {
                for x in ab.iter_mut() {
                    let n: f64 = rng.sample(StandardNormal);
                    // First sample of an episode: from the stationary distribution.
                    *x = if dt > 0.0 && *x != 0.0 { gauss_markov(*x, 1.0, tau, dt, n) } else { n };
                }
                let v = ab[0] * cs + ab[1] * sn;
                if axis < 3 {
                    w[axis] += s.gyro_deg_s.to_radians() * v;
                } else {
                    f[axis - 3] += s.accel_m_s2 * v;
                }
            }
        }
        (w, f)
    }
}
