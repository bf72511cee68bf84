//! # wing-ahrs
//!
//! GPS-aided MEMS attitude estimation for small, highly dynamic fixed-wing UAVs: a
//! six-state EKF (attitude + three gyro biases) that fuses the acceleration the GPS
//! velocity implies with the accelerometer, the course and the wind. The default is the
//! quaternion filter (`mekf`, valid at every attitude); the thesis' Euler-state filter
//! in `shared/seed` (`euler`: EKF1 from the GPS-derived acceleration, EKF2 from the
//! airspeed) stays selectable with [`Config::euler`] / [`Config::thesis`].
//!
//! The crate is the portable core: `no_std`, allocation-free, `forbid(unsafe_code)`,
//! f32 with `libm` transcendentals, so the firmware and the host replay produce
//! the same attitude from the same samples.
//!
//! ## The API (docs/api.md lists every item)
//! - [`Ahrs`] — the facade: [`Ahrs::step`], or its two halves [`Ahrs::predict`] and
//!   [`Ahrs::update`] (or one sensor at a time: `on_imu`, `on_airspeed`, `on_gps`), the
//!   attitude and the other read-outs; [`Sample`], [`GpsOutcome`].
//! - [`Config`] and its sub-configurations ([`config`]): the sensor figures and the
//!   choices a user makes; [`Config::validated`] checks the ranges the types cannot
//!   express, naming every field out of range ([`ConfigErrors`]), and returns the
//!   [`ValidConfig`] that [`Ahrs::new`] takes.
//! - [`GpsFix`], [`FixType`], and the streaming UBX/NMEA parser [`gps::GpsParser`], with
//!   receiver configuration messages in [`gps::config`].
//! - [`health`] — counters, flags, innovation records.
//! - [`mounting`] — board rotation: level calibration and its status.
//! - [`drivers`] — embedded-hal 1.0 sensor drivers for real boards (no hardware access of their own).
//!
//! Internally data flows one way: the GPS parser, the measurement models, the filter, the
//! facade. Those layers are not API; the tests, the harness and the boot-time benchmarks reach
//! them through the unstable `internals` feature (and the GPS encoders through `encode`).
//!
//! Conventions: NED navigation frame, FRD body frame, 3-2-1 Euler angles, SI units
//! and radians (docs/design.md, conventions).
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![deny(missing_docs)]
// Without the Euler filter its EKF and measurement models are unused; the linker drops them.
#![cfg_attr(not(feature = "euler"), allow(dead_code))]

/// Declares an item the integration tests, the harness, the fuzzer and the boot-time
/// benchmarks reach into, but that is not part of the API: `pub` and `#[doc(hidden)]` with
/// the unstable `internals` feature, `pub(crate)` without it (docs/api.md).
macro_rules! internal {
    ($(#[$m:meta])* pub $($item:tt)*) => {
        #[cfg(feature = "internals")]
        #[doc(hidden)]
        $(#[$m])* pub $($item)*
        #[cfg(not(feature = "internals"))]
        $(#[$m])* pub(crate) $($item)*
    };
}
pub(crate) use internal;

pub mod config;
pub mod drivers;
internal! { pub mod ekf; }
internal! { pub mod estimator; }
#[cfg(feature = "euler")]
internal! { pub mod euler; }
internal! { pub mod fix; }
pub mod gps;
pub mod health;
#[cfg(feature = "hil-record")]
pub mod hil_record;
internal! { pub mod math; }
internal! { pub mod measure; }
internal! { pub mod mekf; }
pub mod mounting;
internal! { pub mod rotation; }

pub use config::{
    Config, ConfigError, ConfigErrors, EulerConfig, Filter, InFlightMounting, MeasNoise, Model,
    MountingConfig, QuatConfig, ValidConfig, GRAVITY,
};
pub use estimator::{Ahrs, GpsOutcome, Sample};
pub use fix::{FixType, GpsFix};
pub use health::{AxisStatus, AxisUpdate, Flags, Health, UpdateRecord};
pub use mounting::{LevelCalibration, LevelError, MountingStatus};
pub use rotation::Euler;

/// The README's library example, compiled and run as a doctest (`cargo test`).
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeExample;
