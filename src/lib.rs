//! # wing-ahrs
//!
//! GPS-aided MEMS attitude estimation for small, highly dynamic fixed-wing UAVs:
//! a six-state "half" EKF (roll, pitch, yaw + three gyro biases) after the thesis
//! in `shared/seed`, with two measurement models — EKF1 (GPS-derived acceleration)
//! and EKF2 (airspeed) — that turn sensor data into a measured attitude so the
//! update is linear.
//!
//! The crate is the portable core: `no_std`, allocation-free, `forbid(unsafe_code)`,
//! f32 with `libm` transcendentals, so the firmware and the host replay produce
//! the same attitude from the same samples.
//!
//! ## Layers (data flows one way)
//! - [`fix`] — the GPS fix type every parser produces.
//! - [`gps`] — streaming UBX/NMEA receiver parser, encoders, receiver configuration.
//! - [`measure`] — measurement models (one file each) and the shared sin/cos solver.
//! - [`ekf`] — state, covariance, predict, scalar update.
//! - [`Ahrs`] — the facade: `on_imu`, `on_airspeed`, `on_gps`, read-outs.
//! - [`health`] — counters, flags, innovation records.
//! - [`drivers`] — embedded-hal 1.0 sensor drivers for real boards (no hardware access of their own).
//!
//! Conventions: NED navigation frame, FRD body frame, 3-2-1 Euler angles, SI units
//! and radians (docs/design.md, conventions).
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod ahrs;
pub mod config;
pub mod drivers;
pub mod ekf;
pub mod estimator;
pub mod fix;
pub mod gps;
pub mod health;
pub mod math;
pub mod measure;
pub mod mekf;
pub mod mounting;
pub mod rotation;

pub use ahrs::GpsOutcome;
pub use config::{
    Config, Filter, InFlightMounting, MeasNoise, Model, MountingConfig, QuatConfig, GRAVITY,
};
pub use estimator::{Ahrs, Sample};
pub use fix::{FixType, GpsFix};
pub use health::{AxisStatus, AxisUpdate, Flags, Health, UpdateRecord};
pub use mounting::{LevelCalibration, LevelError, MountingStatus};
pub use rotation::Euler;

/// The README's library example, compiled and run as a doctest (`cargo test`).
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeExample;
