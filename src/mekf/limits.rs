//! The configuration's thresholds in the form the hot paths compare with.

use super::vibration;
use crate::config::{Config, QuatConfig};

/// Configuration thresholds in the form the hot paths compare with, computed once in
/// [`super::QuatAhrs::new`]: f32 ↔ u64 conversions and sines are library calls on the M4F.
#[derive(Debug, Clone, Copy)]
pub(super) struct Limits {
    /// `gps_timeout`, µs.
    pub(super) gps_timeout_us: u64,
    /// `wind_heading_memory`, µs.
    pub(super) wind_memory_us: u64,
    /// `course_interval`, µs.
    pub(super) course_interval_us: u64,
    /// sin `course_max_bank`, and sin of the wider bank allowed while aligning.
    pub(super) sin_bank: f32,
    pub(super) sin_align_bank: f32,
    /// [`vibration::limit`] of the configuration.
    pub(super) vib: f32,
    /// The largest plausible |gyro bias|², (rad/s)² (`bias_plausible_sigmas` ×
    /// `init_sigma_bias`, squared; infinite when off).
    pub(super) bias2: f32,
}

impl Limits {
    pub(super) fn new(cfg: &Config, q: &QuatConfig) -> Self {
        let us = |s: f32| (s.max(0.0) * 1e6) as u64;
        Limits {
            gps_timeout_us: us(cfg.gps_timeout),
            wind_memory_us: us(q.wind_heading_memory),
            course_interval_us: us(q.course_interval),
            sin_bank: crate::math::sin(q.course_max_bank),
            sin_align_bank: crate::math::sin(q.course_max_bank.max(q.course_align_max_bank)),
            vib: vibration::limit(q.vibration_ratio, q.accel_noise_density),
            bias2: if q.bias_plausible_sigmas > 0.0 {
                let b = q.bias_plausible_sigmas * cfg.init_sigma_bias;
                b * b
            } else {
                f32::INFINITY
            },
        }
    }
}
