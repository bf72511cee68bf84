//! IMU error model (thesis eqs 4.1–4.13):
//!
//! ```text
//! ω_m = Q_g[(I + S_g)(I + N_g) R_p ω + b0_g + b_gm,g + b_rw,g + ε_g]
//! A_m = Q_a[(I + S_a)(I + N_a) R_p A + b0_a + b_gm,a + ε_a]
//! ```
//!
//! `R_p`: package misalignment, the eq 4.3 rotation of three small angles shared
//! by both triads. `N`: sensor-to-sensor misalignment, six independent small
//! off-diagonal terms per triad — the thesis writes it as a second eq 4.3
//! rotation, but a rotation cannot express non-orthogonal axes, which is what
//! the term is for. `S`: diagonal scale-factor error. `b0`: turn-on bias, a
//! random constant (eq 4.11). `b_gm`: first-order Gauss–Markov drift (eq 4.12),
//! started from its stationary distribution. `b_rw`: optional random walk
//! (eq 4.13). `ε`: white noise per sample. `Q`: quantization to the LSB.
//! Each sample is the instantaneous value at the sample time (no anti-alias filter).

use super::{gauss_markov, quantize};
use crate::sim::rotation::{self as rot, M3, V3};
use anyhow::{ensure, Result};
use rand::Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

/// IMU parameters (keys carry units; "σ" = 1-σ of a per-run draw where noted).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImuParams {
    /// Sample rate, Hz.
    pub rate_hz: f64,
    /// White noise per sample, 1-σ, °/s.
    pub gyro_noise_deg_s: f64,
    /// Turn-on bias, 1-σ per axis of a per-run draw, °/s.
    pub gyro_turn_on_bias_deg_s: f64,
    /// Gauss–Markov bias drift: stationary σ, °/h, and correlation time, s.
    pub gyro_bias_gm_sigma_deg_h: f64,
    pub gyro_bias_gm_tau_s: f64,
    /// Bias random walk, °/s/√s (0 = off).
    pub gyro_bias_rw_deg_s_per_sqrt_s: f64,
    /// Scale-factor error, 1-σ per axis of a per-run draw (0.01 = 1 %).
    pub gyro_scale_factor: f64,
    /// Sensor-to-sensor (non-orthogonality) misalignment, 1-σ per term, °.
    pub gyro_axis_misalignment_deg: f64,
    /// Quantization step, °/s (0 = none).
    pub gyro_lsb_deg_s: f64,
    /// White noise per sample, 1-σ, m/s².
    pub accel_noise_m_s2: f64,
    /// Turn-on bias, 1-σ per axis of a per-run draw, m/s².
    pub accel_turn_on_bias_m_s2: f64,
    /// Gauss–Markov bias drift: stationary σ, m/s², and correlation time, s.
    pub accel_bias_gm_sigma_m_s2: f64,
    pub accel_bias_gm_tau_s: f64,
    /// Scale-factor error, 1-σ per axis of a per-run draw.
    pub accel_scale_factor: f64,
    /// Sensor-to-sensor misalignment, 1-σ per term, °.
    pub accel_axis_misalignment_deg: f64,
    /// Quantization step, m/s² (0 = none).
    pub accel_lsb_m_s2: f64,
    /// Package misalignment (IMU case vs body axes), 1-σ per angle of a per-run draw, °.
    pub package_misalignment_deg: f64,
    /// A constant board mounting offset added to the drawn package angles: roll, pitch,
    /// yaw of the board in the airframe, ° (default 0; |each| ≤ 30).
    #[serde(default)]
    pub mounting_offset_deg: [f64; 3],
    /// Gyro full scale, °/s: every axis saturates at ±this (default 0 = no clipping).
    #[serde(default)]
    pub gyro_clip_deg_s: f64,
    /// Accelerometer full scale, m/s², as `gyro_clip_deg_s` (default 0 = no clipping).
    #[serde(default)]
    pub accel_clip_m_s2: f64,
}

impl ImuParams {
    pub fn validate(&self) -> Result<()> {
        ensure!(
            self.rate_hz.is_finite() && (10.0..=2000.0).contains(&self.rate_hz),
            "sensors.imu.rate_hz must be in [10, 2000] Hz, got {}",
            self.rate_hz
        );
        let nonneg = [
            ("gyro_noise_deg_s", self.gyro_noise_deg_s),
            ("gyro_turn_on_bias_deg_s", self.gyro_turn_on_bias_deg_s),
            ("gyro_bias_gm_sigma_deg_h", self.gyro_bias_gm_sigma_deg_h),
            ("gyro_bias_gm_tau_s", self.gyro_bias_gm_tau_s),
            ("gyro_bias_rw_deg_s_per_sqrt_s", self.gyro_bias_rw_deg_s_per_sqrt_s),
            ("gyro_scale_factor", self.gyro_scale_factor),
            ("gyro_axis_misalignment_deg", self.gyro_axis_misalignment_deg),
            ("gyro_lsb_deg_s", self.gyro_lsb_deg_s),
            ("accel_noise_m_s2", self.accel_noise_m_s2),
            ("accel_turn_on_bias_m_s2", self.accel_turn_on_bias_m_s2),
            ("accel_bias_gm_sigma_m_s2", self.accel_bias_gm_sigma_m_s2),
            ("accel_bias_gm_tau_s", self.accel_bias_gm_tau_s),
            ("accel_scale_factor", self.accel_scale_factor),
            ("accel_axis_misalignment_deg", self.accel_axis_misalignment_deg),
            ("accel_lsb_m_s2", self.accel_lsb_m_s2),
            ("package_misalignment_deg", self.package_misalignment_deg),
            ("gyro_clip_deg_s", self.gyro_clip_deg_s),
            ("accel_clip_m_s2", self.accel_clip_m_s2),
        ];
        for (k, v) in nonneg {
            ensure!(
                v.is_finite() && v >= 0.0,
                "sensors.imu.{k} must be a finite number ≥ 0, got {v}"
            );
        }
        ensure!(
            (self.gyro_bias_gm_sigma_deg_h == 0.0) || self.gyro_bias_gm_tau_s > 0.0,
            "sensors.imu.gyro_bias_gm_tau_s must be > 0 when gyro_bias_gm_sigma_deg_h is set"
        );
        ensure!(
            (self.accel_bias_gm_sigma_m_s2 == 0.0) || self.accel_bias_gm_tau_s > 0.0,
            "sensors.imu.accel_bias_gm_tau_s must be > 0 when accel_bias_gm_sigma_m_s2 is set"
        );
        ensure!(
            self.mounting_offset_deg.iter().all(|a| a.is_finite() && a.abs() <= 30.0),
            "sensors.imu.mounting_offset_deg must be three finite angles within ±30°, got {:?}",
            self.mounting_offset_deg
        );
        Ok(())
    }
}

/// One IMU with its per-run draws and its bias states.
#[derive(Debug, Clone)]
pub struct ImuModel {
    pub params: ImuParams,
    /// Full gyro input matrix `(I + S_g)(I + N_g) R_p` (drawn at turn-on).
    pub gyro_matrix: M3,
    /// Full accel input matrix `(I + S_a)(I + N_a) R_p`.
    pub accel_matrix: M3,
    /// Package misalignment angles, rad (eq 4.3 θ1..θ3): the draw plus `mounting_offset_deg`.
    pub package_angles: V3,
    /// Turn-on biases, rad/s and m/s².
    pub gyro_turn_on: V3,
    pub accel_turn_on: V3,
    gyro_gm: V3,
    gyro_rw: V3,
    accel_gm: V3,
}

/// Saturates `x` at ±`full_scale` (no-op when 0).
fn clip(x: f64, full_scale: f64) -> f64 {
    if full_scale > 0.0 {
        x.clamp(-full_scale, full_scale)
    } else {
        x
    }
}

fn normal3<R: Rng>(rng: &mut R, sigma: f64) -> V3 {
    [
        sigma * rng.sample::<f64, _>(StandardNormal),
        sigma * rng.sample::<f64, _>(StandardNormal),
        sigma * rng.sample::<f64, _>(StandardNormal),
    ]
}

fn input_matrix<R: Rng>(rng: &mut R, scale_sigma: f64, axis_sigma: f64, rp: &M3) -> M3 {
    let s = normal3(rng, scale_sigma);
    let mut n = rot::IDENTITY;
    for (i, row) in n.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            if i != j {
                *v = axis_sigma * rng.sample::<f64, _>(StandardNormal);
            }
        }
    }
    let sn: M3 = core::array::from_fn(|i| core::array::from_fn(|j| (1.0 + s[i]) * n[i][j]));
    rot::mul_mm(&sn, rp)
}

impl ImuModel {
    /// Draws the per-run errors from `rng`.
    pub fn new<R: Rng>(params: &ImuParams, rng: &mut R) -> Self {
        let d2r = std::f64::consts::PI / 180.0;
        let drawn = normal3(rng, params.package_misalignment_deg * d2r);
        let package_angles = rot::add(drawn, params.mounting_offset_deg.map(|a| a * d2r));
        let rp = rot::r_bn(package_angles[0], package_angles[1], package_angles[2]);
        let gyro_matrix = input_matrix(
            rng,
            params.gyro_scale_factor,
            params.gyro_axis_misalignment_deg * d2r,
            &rp,
        );
        let accel_matrix = input_matrix(
            rng,
            params.accel_scale_factor,
            params.accel_axis_misalignment_deg * d2r,
            &rp,
        );
        let gyro_turn_on = normal3(rng, params.gyro_turn_on_bias_deg_s * d2r);
        let accel_turn_on = normal3(rng, params.accel_turn_on_bias_m_s2);
        let gyro_gm = normal3(rng, params.gyro_bias_gm_sigma_deg_h * d2r / 3600.0);
        let accel_gm = normal3(rng, params.accel_bias_gm_sigma_m_s2);
        ImuModel {
            params: params.clone(),
            gyro_matrix,
            accel_matrix,
            package_angles,
            gyro_turn_on,
            accel_turn_on,
            gyro_gm,
            gyro_rw: [0.0; 3],
            accel_gm,
        }
    }

    /// Total additive gyro bias now, rad/s (the `true_b*` columns).
    pub fn gyro_bias(&self) -> V3 {
        rot::add(rot::add(self.gyro_turn_on, self.gyro_gm), self.gyro_rw)
    }

    /// Total additive accelerometer bias now, m/s².
    pub fn accel_bias(&self) -> V3 {
        rot::add(self.accel_turn_on, self.accel_gm)
    }

    /// Measures true body rates `omega` (rad/s) and specific force `f` (m/s²),
    /// then advances the bias processes by one sample period.
    /// Returns (gyro rad/s, accel m/s²), both FRD.
    pub fn sample<R: Rng>(&mut self, omega: V3, f: V3, rng: &mut R) -> (V3, V3) {
        let p = &self.params;
        let d2r = std::f64::consts::PI / 180.0;
        let gn = normal3(rng, p.gyro_noise_deg_s * d2r);
        let an = normal3(rng, p.accel_noise_m_s2);
        let g = rot::add(rot::add(rot::mul_mv(&self.gyro_matrix, omega), self.gyro_bias()), gn);
        let a = rot::add(rot::add(rot::mul_mv(&self.accel_matrix, f), self.accel_bias()), an);
        let gq = g.map(|x| clip(quantize(x, p.gyro_lsb_deg_s * d2r), p.gyro_clip_deg_s * d2r));
        let aq = a.map(|x| clip(quantize(x, p.accel_lsb_m_s2), p.accel_clip_m_s2));
        self.advance(rng);
        (gq, aq)
    }

    fn advance<R: Rng>(&mut self, rng: &mut R) {
        let p = &self.params;
        let dt = 1.0 / p.rate_hz;
        let d2r = std::f64::consts::PI / 180.0;
        let gs = p.gyro_bias_gm_sigma_deg_h * d2r / 3600.0;
        let w = normal3(rng, 1.0);
        for (b, w) in self.gyro_gm.iter_mut().zip(w) {
            *b = gauss_markov(*b, gs, p.gyro_bias_gm_tau_s, dt, w);
        }
        if p.gyro_bias_rw_deg_s_per_sqrt_s > 0.0 {
            let w = normal3(rng, p.gyro_bias_rw_deg_s_per_sqrt_s * d2r * dt.sqrt());
            self.gyro_rw = rot::add(self.gyro_rw, w);
        }
        if p.accel_bias_gm_sigma_m_s2 > 0.0 {
            let w = normal3(rng, 1.0);
            for (b, w) in self.accel_gm.iter_mut().zip(w) {
                *b = gauss_markov(*b, p.accel_bias_gm_sigma_m_s2, p.accel_bias_gm_tau_s, dt, w);
            }
        }
    }
}
