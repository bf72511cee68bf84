//! Sensor drivers for real flight boards, written against embedded-hal 1.0.
//!
//! They touch no hardware themselves: the board hands them an `SpiDevice` (bus +
//! chip select) and a `DelayNs`, so the same code is exercised on the host with
//! `embedded-hal-mock` and on the MCU with the HAL's peripherals.
//!
//! - [`axes`] — the sensor's mounting on a board: a signed axis permutation into body FRD.
//! - [`mpu6000`] — InvenSense MPU-6000 6-axis IMU over SPI (Matek F405-Wing / F405-SE).

pub mod axes;
pub mod mpu6000;

pub use axes::AxisMap;
pub use mpu6000::{ImuSample, Mpu6000, Mpu6000Config, Mpu6000Error};
