//! TDK InvenSense ICM-42688-P over SPI (embedded-hal 1.0 `SpiDevice`) — the IMU of
//! newer F405 flight controllers. Not wired into a board yet (the `f405` board is the
//! MPU-6000 Matek F405-Wing); ready for an ICM-42688-P board's module.
//!
//! Hand-written for the same reasons as [`super::mpu6000`]: the crates.io `icm426xx`
//! crate is async-first with its own init policy; this is a few hundred lines,
//! blocking, allocation-free and `unsafe`-free.
//!
//! Source: ICM-42688-P datasheet DS-000347 (user bank 0 register map; gyro
//! 16.4 LSB/(°/s) at ±2000 °/s, accel 2048 LSB/g at ±16 g, temperature
//! T = raw/132.48 + 25 °C; ODR code 8 = 100 Hz; INT_CONFIG1.INT_ASYNC_RESET must be
//! cleared for the INT pins to work). SPI mode 0 or 3, ≤ 24 MHz.

use embedded_hal::delay::DelayNs;
use embedded_hal::spi::{Operation, SpiDevice};

use super::axes::AxisMap;
pub use super::sample::{ImuSample, RawSample};
use crate::config::GRAVITY;

/// User bank 0 register addresses.
pub mod reg {
    /// SOFT_RESET_CONFIG (bit 0).
    pub const DEVICE_CONFIG: u8 = 0x11;
    /// INT1 mode, drive, polarity.
    pub const INT_CONFIG: u8 = 0x14;
    /// First of 14 burst-read bytes: temperature, accel XYZ, gyro XYZ (big endian).
    pub const TEMP_DATA1: u8 = 0x1D;
    /// Interface: data endianness, I²C disable.
    pub const INTF_CONFIG0: u8 = 0x4C;
    /// Gyro and accel power modes.
    pub const PWR_MGMT0: u8 = 0x4E;
    /// GYRO_FS_SEL (7:5), GYRO_ODR (3:0).
    pub const GYRO_CONFIG0: u8 = 0x4F;
    /// ACCEL_FS_SEL (7:5), ACCEL_ODR (3:0).
    pub const ACCEL_CONFIG0: u8 = 0x50;
    /// ACCEL_UI_FILT_BW (7:4), GYRO_UI_FILT_BW (3:0).
    pub const GYRO_ACCEL_CONFIG0: u8 = 0x52;
    /// INT_TPULSE_DURATION, INT_ASYNC_RESET.
    pub const INT_CONFIG1: u8 = 0x64;
    /// Interrupt sources routed to INT1 (UI_DRDY_INT1_EN = bit 3).
    pub const INT_SOURCE0: u8 = 0x65;
    /// Reads 0x47 on an ICM-42688-P.
    pub const WHO_AM_I: u8 = 0x75;
    /// Register bank select.
    pub const REG_BANK_SEL: u8 = 0x76;
}

/// Expected WHO_AM_I value.
pub const WHO_AM_I_ICM42688P: u8 = 0x47;
const READ: u8 = 0x80;
const SOFT_RESET: u8 = 0x01;
/// Big-endian sensor data and FIFO count (reset value 0x30) + UI_SIFS_CFG = 11: I²C off.
const INTF_SPI_ONLY_BIG_ENDIAN: u8 = 0x33;
/// GYRO_FS_SEL = 000 (±2000 °/s) | ODR code.
const GYRO_FS_2000DPS: u8 = 0x00;
/// ACCEL_FS_SEL = 000 (±16 g) | ODR code.
const ACCEL_FS_16G: u8 = 0x00;
/// INT1: pulsed, push-pull, active high.
const INT1_PULSE_PUSH_PULL_HIGH: u8 = 0x03;
/// INT_CONFIG1: 100 µs pulses, INT_ASYNC_RESET cleared (required for INT operation).
const INT_CONFIG1_OPERATE: u8 = 0x00;
/// INT_SOURCE0: UI data ready → INT1.
const UI_DRDY_INT1_EN: u8 = 0x08;
/// PWR_MGMT0: gyro and accel in low-noise mode.
const GYRO_ACCEL_LOW_NOISE: u8 = 0x0F;

/// Gyro sensitivity at ±2000 °/s, LSB per °/s (DS-000347 table 1).
pub const GYRO_LSB_PER_DPS: f32 = 16.4;
/// Accel sensitivity at ±16 g, LSB per g (DS-000347 table 2).
pub const ACCEL_LSB_PER_G: f32 = 2048.0;
/// Temperature sensitivity, LSB per °C.
pub const TEMP_LSB_PER_C: f32 = 132.48;
/// Temperature at raw 0, °C.
pub const TEMP_OFFSET_C: f32 = 25.0;
/// Gyro scale: rad/s per LSB.
pub const GYRO_RAD_S_PER_LSB: f32 = core::f32::consts::PI / 180.0 / GYRO_LSB_PER_DPS;
/// Accel scale: m/s² per LSB.
pub const ACCEL_M_S2_PER_LSB: f32 = GRAVITY / ACCEL_LSB_PER_G;

/// Output data rate (the same code for gyro and accel).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum Odr {
    /// 1 kHz.
    Hz1000 = 0x06,
    /// 200 Hz.
    Hz200 = 0x07,
    /// 100 Hz: the estimator's rate.
    Hz100 = 0x08,
    /// 50 Hz.
    Hz50 = 0x09,
}

impl Odr {
    /// Rate, Hz.
    pub fn hz(self) -> f32 {
        match self {
            Odr::Hz1000 => 1000.0,
            Odr::Hz200 => 200.0,
            Odr::Hz100 => 100.0,
            Odr::Hz50 => 50.0,
        }
    }
}

/// Configuration. Ranges are fixed at ±2000 °/s and ±16 g.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Icm42688Config {
    /// Output (and data-ready) rate of both sensors.
    pub odr: Odr,
    /// UI low-pass filter bandwidth index for both sensors (GYRO_ACCEL_CONFIG0 nibbles):
    /// 0 = ODR/2, n = 1..7 → max(400 Hz, ODR) / {4, 5, 8, 10, 16, 20, 40}.
    pub ui_filter_bw: u8,
}

impl Default for Icm42688Config {
    /// 100 Hz with the UI filter at max(400, 100)/10 = 40 Hz (anti-alias below 50 Hz Nyquist).
    fn default() -> Self {
        Icm42688Config { odr: Odr::Hz100, ui_filter_bw: 4 }
    }
}

impl Icm42688Config {
    fn gyro_config0(&self) -> u8 {
        GYRO_FS_2000DPS | self.odr as u8
    }
    fn accel_config0(&self) -> u8 {
        ACCEL_FS_16G | self.odr as u8
    }
    fn filter(&self) -> u8 {
        let bw = self.ui_filter_bw & 0x0F;
        (bw << 4) | bw
    }
}

/// Driver errors.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Icm42688Error<E> {
    /// The SPI device reported an error.
    Spi(E),
    /// WHO_AM_I did not read 0x47.
    WrongId(u8),
    /// GYRO_CONFIG0, ACCEL_CONFIG0, GYRO_ACCEL_CONFIG0 read back differ from what was written.
    ConfigMismatch {
        /// As written.
        wrote: [u8; 3],
        /// As read back.
        read: [u8; 3],
    },
}

/// Decodes the 14 bytes starting at TEMP_DATA1 (big endian: temperature, accel, gyro).
pub fn parse_burst(b: &[u8; 14]) -> RawSample {
    let w = |i: usize| i16::from_be_bytes([b[i], b[i + 1]]);
    RawSample { temp: w(0), accel: [w(2), w(4), w(6)], gyro: [w(8), w(10), w(12)] }
}

/// Scales raw counts to SI (±2000 °/s, ±16 g) and rotates them into body FRD.
pub fn to_sample(raw: &RawSample, axes: &AxisMap) -> ImuSample {
    raw.to_si(
        axes,
        GYRO_RAD_S_PER_LSB,
        ACCEL_M_S2_PER_LSB,
        raw.temp as f32 / TEMP_LSB_PER_C + TEMP_OFFSET_C,
    )
}

/// ICM-42688-P on an SPI device (the device owns chip select).
pub struct Icm42688<SPI> {
    spi: SPI,
    axes: AxisMap,
}

impl<SPI: SpiDevice> Icm42688<SPI> {
    /// Wraps the device; `axes` is the sensor's mounting on the board.
    pub fn new(spi: SPI, axes: AxisMap) -> Self {
        Icm42688 { spi, axes }
    }

    /// Gives the SPI device back.
    pub fn release(self) -> SPI {
        self.spi
    }

    /// Soft reset (1 ms), WHO_AM_I, SPI-only interface, ±2000 °/s and ±16 g at the
    /// configured ODR, UI filter, data-ready pulse on INT1, sensors on in low-noise
    /// mode (then 50 ms: the datasheet forbids register writes for 200 µs and the gyro
    /// needs ~45 ms to start), configuration read back.
    pub fn init<D: DelayNs>(
        &mut self,
        delay: &mut D,
        cfg: &Icm42688Config,
    ) -> Result<(), Icm42688Error<SPI::Error>> {
        self.write(reg::REG_BANK_SEL, 0)?;
        self.write(reg::DEVICE_CONFIG, SOFT_RESET)?;
        delay.delay_ms(1);
        let id = self.read_regs::<1>(reg::WHO_AM_I)?[0];
        if id != WHO_AM_I_ICM42688P {
            return Err(Icm42688Error::WrongId(id));
        }
        self.write(reg::INTF_CONFIG0, INTF_SPI_ONLY_BIG_ENDIAN)?;
        let wrote = [cfg.gyro_config0(), cfg.accel_config0(), cfg.filter()];
        self.write(reg::GYRO_CONFIG0, wrote[0])?;
        self.write(reg::ACCEL_CONFIG0, wrote[1])?;
        self.write(reg::GYRO_ACCEL_CONFIG0, wrote[2])?;
        self.write(reg::INT_CONFIG, INT1_PULSE_PUSH_PULL_HIGH)?;
        self.write(reg::INT_CONFIG1, INT_CONFIG1_OPERATE)?;
        self.write(reg::INT_SOURCE0, UI_DRDY_INT1_EN)?;
        self.write(reg::PWR_MGMT0, GYRO_ACCEL_LOW_NOISE)?;
        delay.delay_ms(50);
        // GYRO_CONFIG0, ACCEL_CONFIG0, GYRO_CONFIG1 (not ours), GYRO_ACCEL_CONFIG0.
        let back = self.read_regs::<4>(reg::GYRO_CONFIG0)?;
        let read = [back[0], back[1], back[3]];
        if read != wrote {
            return Err(Icm42688Error::ConfigMismatch { wrote, read });
        }
        Ok(())
    }

    /// One 14-byte burst read, raw counts in the sensor frame.
    pub fn read_raw(&mut self) -> Result<RawSample, Icm42688Error<SPI::Error>> {
        Ok(parse_burst(&self.read_regs::<14>(reg::TEMP_DATA1)?))
    }

    /// Burst read converted to SI units in body FRD.
    pub fn read(&mut self) -> Result<ImuSample, Icm42688Error<SPI::Error>> {
        let raw = self.read_raw()?;
        Ok(to_sample(&raw, &self.axes))
    }

    fn write(&mut self, reg: u8, val: u8) -> Result<(), Icm42688Error<SPI::Error>> {
        self.spi.write(&[reg, val]).map_err(Icm42688Error::Spi)
    }

    fn read_regs<const N: usize>(&mut self, reg: u8) -> Result<[u8; N], Icm42688Error<SPI::Error>> {
        let mut buf = [0u8; N];
        self.spi
            .transaction(&mut [Operation::Write(&[reg | READ]), Operation::Read(&mut buf)])
            .map_err(Icm42688Error::Spi)?;
        Ok(buf)
    }
}
