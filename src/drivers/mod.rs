//! Sensor drivers for real flight boards, written against embedded-hal 1.0.
//!
//! They touch no hardware themselves: the board hands them an `SpiDevice` (bus +
//! chip select) and a `DelayNs`, so the same code is exercised on the host with
//! `embedded-hal-mock` and on the MCU with the HAL's peripherals.
//!
//! - [`axes`] — the sensor's mounting on a board: a signed axis permutation into body FRD.
//! - [`sample`] — raw counts and the SI sample every driver returns.
//! - [`mpu6000`] — InvenSense MPU-6000 6-axis IMU over SPI (Matek F405-Wing / F405-SE).
//! - [`icm42688`] — TDK InvenSense ICM-42688-P over SPI (newer F405 boards).

pub mod axes;
pub mod icm42688;
pub mod mpu6000;
pub mod sample;

pub use axes::AxisMap;
pub use icm42688::{Icm42688, Icm42688Config, Icm42688Error};
pub use mpu6000::{Mpu6000, Mpu6000Config, Mpu6000Error};
pub use sample::{ImuSample, RawSample};
