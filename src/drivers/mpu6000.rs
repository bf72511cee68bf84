//! InvenSense MPU-6000 over SPI (embedded-hal 1.0 `SpiDevice`).
//!
//! Hand-written: the crates.io `mpu6000` crate targets embedded-hal 0.2; this one is
//! ~200 lines, allocation-free and needs no `unsafe`, so the core can carry it.
//!
//! Register numbers and sensitivities: MPU-6000/MPU-6050 Product Specification
//! PS-MPU-6000A-00 rev 3.4 (§6.1 gyro 16.4 LSB/(°/s) at FS_SEL=3, §6.2 accel
//! 2048 LSB/g at AFS_SEL=3, §6.3 temperature 340 LSB/°C) and Register Map
//! RM-MPU-6000A-00 rev 4.2 (§4.28 SPI reset sequence, §4.18 temperature offset 36.53 °C).
//!
//! SPI: mode 0 or 3, MSB first, ≤ 1 MHz for register writes, ≤ 20 MHz for reading
//! sensor registers. The bus clock belongs to the board; `init` must run at ≤ 1 MHz.

use embedded_hal::delay::DelayNs;
use embedded_hal::spi::{Operation, SpiDevice};

use super::axes::AxisMap;
pub use super::sample::{ImuSample, RawSample};
use crate::config::GRAVITY;

/// Register addresses (RM-MPU-6000A).
pub mod reg {
    /// Sample rate divider: rate = gyro output rate / (1 + SMPLRT_DIV).
    pub const SMPLRT_DIV: u8 = 0x19;
    /// FSYNC and DLPF_CFG.
    pub const CONFIG: u8 = 0x1A;
    /// Gyro full scale (FS_SEL in bits 4:3).
    pub const GYRO_CONFIG: u8 = 0x1B;
    /// Accel full scale (AFS_SEL in bits 4:3).
    pub const ACCEL_CONFIG: u8 = 0x1C;
    /// INT pin level, drive, latch and clear behaviour.
    pub const INT_PIN_CFG: u8 = 0x37;
    /// Interrupt enables (DATA_RDY_EN = bit 0).
    pub const INT_ENABLE: u8 = 0x38;
    /// First of 14 burst-read bytes: accel XYZ, temperature, gyro XYZ (big endian).
    pub const ACCEL_XOUT_H: u8 = 0x3B;
    /// Resets the analog and digital signal paths (required after DEVICE_RESET over SPI).
    pub const SIGNAL_PATH_RESET: u8 = 0x68;
    /// I2C_IF_DIS (bit 4) keeps the part in SPI mode.
    pub const USER_CTRL: u8 = 0x6A;
    /// DEVICE_RESET (bit 7), SLEEP, CLKSEL.
    pub const PWR_MGMT_1: u8 = 0x6B;
    /// Per-axis standby bits.
    pub const PWR_MGMT_2: u8 = 0x6C;
    /// Reads 0x68 on an MPU-6000.
    pub const WHO_AM_I: u8 = 0x75;
}

/// Expected WHO_AM_I value.
pub const WHO_AM_I_MPU6000: u8 = 0x68;
/// SPI read flag (address bit 7).
const READ: u8 = 0x80;
/// PWR_MGMT_1: DEVICE_RESET.
const DEVICE_RESET: u8 = 0x80;
/// SIGNAL_PATH_RESET: gyro, accel and temperature paths.
const RESET_ALL_PATHS: u8 = 0x07;
/// PWR_MGMT_1 CLKSEL = 3: PLL referenced to the Z gyro (datasheet recommends a gyro PLL over the 8 MHz RC).
const CLK_PLL_ZGYRO: u8 = 0x03;
/// USER_CTRL: disable the I2C slave interface so the part stays in SPI mode.
const I2C_IF_DIS: u8 = 0x10;
/// FS_SEL = 3: ±2000 °/s.
const GYRO_FS_2000DPS: u8 = 3 << 3;
/// AFS_SEL = 3: ±16 g.
const ACCEL_FS_16G: u8 = 3 << 3;
/// INT_PIN_CFG: active high, push-pull, 50 µs pulse, INT_RD_CLEAR (any read clears).
const INT_PULSE_ANY_READ_CLEARS: u8 = 0x10;
/// INT_ENABLE: DATA_RDY_EN.
const DATA_RDY_EN: u8 = 0x01;

/// Gyro sensitivity at FS_SEL = 3, LSB per °/s (PS-MPU-6000A §6.1).
pub const GYRO_LSB_PER_DPS: f32 = 16.4;
/// Accel sensitivity at AFS_SEL = 3, LSB per g (PS-MPU-6000A §6.2).
pub const ACCEL_LSB_PER_G: f32 = 2048.0;
/// Temperature sensitivity, LSB per °C (PS-MPU-6000A §6.3).
pub const TEMP_LSB_PER_C: f32 = 340.0;
/// Temperature at raw 0, °C (RM-MPU-6000A §4.18).
pub const TEMP_OFFSET_C: f32 = 36.53;

/// Gyro scale: rad/s per LSB.
pub const GYRO_RAD_S_PER_LSB: f32 = core::f32::consts::PI / 180.0 / GYRO_LSB_PER_DPS;
/// Accel scale: m/s² per LSB (standard gravity, the unit the datasheet's g means).
pub const ACCEL_M_S2_PER_LSB: f32 = GRAVITY / ACCEL_LSB_PER_G;

/// Digital low-pass filter (CONFIG.DLPF_CFG). Any setting other than `Off`
/// makes the gyro output rate 1 kHz, which SMPLRT_DIV divides.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum Dlpf {
    /// Accel 260 Hz / gyro 256 Hz (gyro output rate 8 kHz).
    Off = 0,
    /// Accel 184 Hz / gyro 188 Hz.
    Hz188 = 1,
    /// Accel 94 Hz / gyro 98 Hz.
    Hz98 = 2,
    /// Accel 44 Hz / gyro 42 Hz, ~4.9 ms delay: the anti-alias choice for 100 Hz sampling.
    Hz42 = 3,
    /// Accel 21 Hz / gyro 20 Hz.
    Hz20 = 4,
    /// Accel 10 Hz / gyro 10 Hz.
    Hz10 = 5,
    /// Accel 5 Hz / gyro 5 Hz.
    Hz5 = 6,
}

/// Sample-rate and filter configuration. Ranges are fixed at ±2000 °/s and ±16 g
/// (a fixed-wing in a hard turn or a hand launch must not clip).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Mpu6000Config {
    /// SMPLRT_DIV: output (and data-ready) rate = base rate / (1 + div).
    pub sample_rate_div: u8,
    /// Low-pass filter; sets the base rate (1 kHz, or 8 kHz when `Off`).
    pub dlpf: Dlpf,
}

impl Default for Mpu6000Config {
    /// 100 Hz data-ready with the 42 Hz DLPF (below Nyquist at 100 Hz).
    fn default() -> Self {
        Mpu6000Config { sample_rate_div: 9, dlpf: Dlpf::Hz42 }
    }
}

impl Mpu6000Config {
    /// Data-ready rate, Hz.
    pub fn sample_rate_hz(&self) -> f32 {
        let base = if self.dlpf == Dlpf::Off { 8000.0 } else { 1000.0 };
        base / (1.0 + self.sample_rate_div as f32)
    }

    /// Register values for SMPLRT_DIV, CONFIG, GYRO_CONFIG, ACCEL_CONFIG (consecutive addresses).
    fn block(&self) -> [u8; 4] {
        [self.sample_rate_div, self.dlpf as u8, GYRO_FS_2000DPS, ACCEL_FS_16G]
    }
}

/// Driver errors.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mpu6000Error<E> {
    /// The SPI device reported an error.
    Spi(E),
    /// WHO_AM_I did not read 0x68 (wrong chip, dead bus, or wrong SPI mode).
    WrongId(u8),
    /// The configuration read back differs from what was written (bus too fast for writes?).
    ConfigMismatch {
        /// SMPLRT_DIV..ACCEL_CONFIG as written.
        wrote: [u8; 4],
        /// The same registers as read back.
        read: [u8; 4],
    },
}

/// Decodes the 14 bytes starting at ACCEL_XOUT_H (big endian: accel, temperature, gyro).
pub fn parse_burst(b: &[u8; 14]) -> RawSample {
    let w = |i: usize| i16::from_be_bytes([b[i], b[i + 1]]);
    RawSample { accel: [w(0), w(2), w(4)], temp: w(6), gyro: [w(8), w(10), w(12)] }
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

/// MPU-6000 on an SPI device (the device owns chip select).
pub struct Mpu6000<SPI> {
    spi: SPI,
    axes: AxisMap,
}

impl<SPI: SpiDevice> Mpu6000<SPI> {
    /// Wraps the device; `axes` is the sensor's mounting on the board.
    pub fn new(spi: SPI, axes: AxisMap) -> Self {
        Mpu6000 { spi, axes }
    }

    /// Gives the SPI device back (e.g. to re-clock the bus after `init`).
    pub fn release(self) -> SPI {
        self.spi
    }

    /// Resets the chip (RM §4.28 SPI sequence: DEVICE_RESET, 100 ms, SIGNAL_PATH_RESET,
    /// 100 ms), checks WHO_AM_I, selects the gyro PLL, sets ±2000 °/s, ±16 g, the DLPF
    /// and sample rate, enables the data-ready pulse on INT, and reads the
    /// configuration back. Blocking (~200 ms); call before interrupts are enabled.
    pub fn init<D: DelayNs>(
        &mut self,
        delay: &mut D,
        cfg: &Mpu6000Config,
    ) -> Result<(), Mpu6000Error<SPI::Error>> {
        self.write(reg::PWR_MGMT_1, DEVICE_RESET)?;
        delay.delay_ms(100);
        self.write(reg::SIGNAL_PATH_RESET, RESET_ALL_PATHS)?;
        delay.delay_ms(100);
        self.write(reg::PWR_MGMT_1, CLK_PLL_ZGYRO)?;
        self.write(reg::USER_CTRL, I2C_IF_DIS)?;
        let id = self.read_reg(reg::WHO_AM_I)?;
        if id != WHO_AM_I_MPU6000 {
            return Err(Mpu6000Error::WrongId(id));
        }
        self.write(reg::PWR_MGMT_2, 0x00)?;
        let block = cfg.block();
        // SMPLRT_DIV..ACCEL_CONFIG are consecutive: one auto-incrementing burst write.
        let [b0, b1, b2, b3] = block;
        self.spi.write(&[reg::SMPLRT_DIV, b0, b1, b2, b3]).map_err(Mpu6000Error::Spi)?;
        self.write(reg::INT_PIN_CFG, INT_PULSE_ANY_READ_CLEARS)?;
        self.write(reg::INT_ENABLE, DATA_RDY_EN)?;
        let mut back = [0u8; 4];
        self.read_regs(reg::SMPLRT_DIV, &mut back)?;
        if back != block {
            return Err(Mpu6000Error::ConfigMismatch { wrote: block, read: back });
        }
        Ok(())
    }

    /// One 14-byte burst read (accel, temperature, gyro from the same sampling
    /// instant — RM §4.18), raw counts in the sensor frame. Clears the data-ready INT.
    pub fn read_raw(&mut self) -> Result<RawSample, Mpu6000Error<SPI::Error>> {
        let mut buf = [0u8; 14];
        self.read_regs(reg::ACCEL_XOUT_H, &mut buf)?;
        Ok(parse_burst(&buf))
    }

    /// Burst read converted to SI units in body FRD.
    pub fn read(&mut self) -> Result<ImuSample, Mpu6000Error<SPI::Error>> {
        let raw = self.read_raw()?;
        Ok(to_sample(&raw, &self.axes))
    }

    fn write(&mut self, reg: u8, val: u8) -> Result<(), Mpu6000Error<SPI::Error>> {
        self.spi.write(&[reg, val]).map_err(Mpu6000Error::Spi)
    }

    fn read_reg(&mut self, reg: u8) -> Result<u8, Mpu6000Error<SPI::Error>> {
        let mut b = [0u8; 1];
        self.read_regs(reg, &mut b)?;
        Ok(b[0])
    }

    fn read_regs(&mut self, reg: u8, buf: &mut [u8]) -> Result<(), Mpu6000Error<SPI::Error>> {
        self.spi
            .transaction(&mut [Operation::Write(&[reg | READ]), Operation::Read(buf)])
            .map_err(Mpu6000Error::Spi)
    }
}
