//! MPU-6000 and ICM-42688-P drivers on a mocked SPI bus: the exact transactions of init and the
//! burst read, and the unit/axis conversion against the datasheet (PS-MPU-6000A
//! rev 3.4: 16.4 LSB/(°/s) at ±2000 °/s, 2048 LSB/g at ±16 g) and the board's
//! published sensor alignment (INAV MATEKF405SE CW270_DEG, ArduPilot ROTATION_YAW_180).

use embedded_hal_mock::eh1::delay::{CheckedDelay, NoopDelay, Transaction as DelayTx};
use embedded_hal_mock::eh1::spi::{Mock as SpiMock, Transaction as Tx};
use wing_ahrs::drivers::icm42688::Odr;
use wing_ahrs::drivers::mpu6000::{Dlpf, RawSample};
use wing_ahrs::drivers::{
    AxisMap, Icm42688, Icm42688Config, Icm42688Error, Mpu6000, Mpu6000Config, Mpu6000Error,
};

const G: f32 = 9.80665;

fn write(bytes: &[u8]) -> Vec<Tx<u8>> {
    vec![Tx::transaction_start(), Tx::write_vec(bytes.to_vec()), Tx::transaction_end()]
}

fn read(addr: u8, response: &[u8]) -> Vec<Tx<u8>> {
    vec![
        Tx::transaction_start(),
        Tx::write_vec(vec![addr | 0x80]),
        Tx::read_vec(response.to_vec()),
        Tx::transaction_end(),
    ]
}

/// Init up to and including the WHO_AM_I read, answering `id`.
fn reset_and_id(id: u8) -> Vec<Tx<u8>> {
    let mut t = Vec::new();
    t.extend(write(&[0x6B, 0x80])); // PWR_MGMT_1: DEVICE_RESET
    t.extend(write(&[0x68, 0x07])); // SIGNAL_PATH_RESET: gyro, accel, temp
    t.extend(write(&[0x6B, 0x03])); // PWR_MGMT_1: CLKSEL = PLL, Z gyro
    t.extend(write(&[0x6A, 0x10])); // USER_CTRL: I2C_IF_DIS
    t.extend(read(0x75, &[id])); // WHO_AM_I
    t
}

fn config_writes() -> Vec<Tx<u8>> {
    let mut t = Vec::new();
    t.extend(write(&[0x6C, 0x00])); // PWR_MGMT_2: all axes on
                                    // SMPLRT_DIV = 9 (1 kHz / 10 = 100 Hz), CONFIG DLPF_CFG = 3 (42 Hz gyro),
                                    // GYRO_CONFIG FS_SEL = 3 (±2000 °/s), ACCEL_CONFIG AFS_SEL = 3 (±16 g).
    t.extend(write(&[0x19, 9, 3, 0x18, 0x18]));
    t.extend(write(&[0x37, 0x10])); // INT_PIN_CFG: active-high push-pull pulse, any read clears
    t.extend(write(&[0x38, 0x01])); // INT_ENABLE: DATA_RDY_EN
    t
}

#[test]
fn mpu6000_init_issues_the_datasheet_reset_and_100hz_config_sequence() {
    let mut expect = reset_and_id(0x68);
    expect.extend(config_writes());
    expect.extend(read(0x19, &[9, 3, 0x18, 0x18])); // read-back of the config block
    let mut spi = SpiMock::new(&expect);
    // Both 100 ms waits of the register map's SPI reset sequence, in order.
    let mut delay = CheckedDelay::new(&[DelayTx::delay_ms(100), DelayTx::delay_ms(100)]);
    let cfg = Mpu6000Config::default();
    assert_eq!(cfg.sample_rate_hz(), 100.0);
    let mut imu = Mpu6000::new(spi.clone(), AxisMap::MATEK_F405_WING);
    imu.init(&mut delay, &cfg).expect("init");
    spi.done();
    delay.done();
}

#[test]
fn mpu6000_init_stops_at_a_wrong_who_am_i() {
    // 0x70 is an MPU-6500: a different register map, must not be configured as a 6000.
    let mut spi = SpiMock::new(&reset_and_id(0x70));
    let mut imu = Mpu6000::new(spi.clone(), AxisMap::IDENTITY);
    let r = imu.init(&mut NoopDelay::new(), &Mpu6000Config::default());
    assert_eq!(r, Err(Mpu6000Error::WrongId(0x70)));
    spi.done(); // no transaction after the failed WHO_AM_I
}

#[test]
fn mpu6000_init_reports_a_config_that_did_not_stick() {
    let mut expect = reset_and_id(0x68);
    expect.extend(config_writes());
    expect.extend(read(0x19, &[9, 3, 0x00, 0x18])); // gyro range write lost
    let mut spi = SpiMock::new(&expect);
    let mut imu = Mpu6000::new(spi.clone(), AxisMap::IDENTITY);
    let r = imu.init(&mut NoopDelay::new(), &Mpu6000Config::default());
    assert_eq!(
        r,
        Err(Mpu6000Error::ConfigMismatch { wrote: [9, 3, 0x18, 0x18], read: [9, 3, 0x00, 0x18] })
    );
    spi.done();
}

#[test]
fn mpu6000_other_rates_and_filters_reach_the_registers() {
    let cfg = Mpu6000Config { sample_rate_div: 4, dlpf: Dlpf::Hz98 };
    assert_eq!(cfg.sample_rate_hz(), 200.0);
    let mut expect = reset_and_id(0x68);
    expect.extend(write(&[0x6C, 0x00]));
    expect.extend(write(&[0x19, 4, 2, 0x18, 0x18]));
    expect.extend(write(&[0x37, 0x10]));
    expect.extend(write(&[0x38, 0x01]));
    expect.extend(read(0x19, &[4, 2, 0x18, 0x18]));
    let mut spi = SpiMock::new(&expect);
    let mut imu = Mpu6000::new(spi.clone(), AxisMap::IDENTITY);
    imu.init(&mut NoopDelay::new(), &cfg).unwrap();
    spi.done();
}

#[test]
fn mpu6000_burst_read_is_one_14_byte_transaction_from_accel_xout_h() {
    // accel (1, -2, 2048), temp -521 (35 °C per PS §6.3), gyro (1640, -1640, 32767)
    let bytes: Vec<u8> =
        [1i16, -2, 2048, -521, 1640, -1640, 32767].iter().flat_map(|v| v.to_be_bytes()).collect();
    let mut spi = SpiMock::new(&read(0x3B, &bytes));
    let mut imu = Mpu6000::new(spi.clone(), AxisMap::IDENTITY);
    let raw = imu.read_raw().unwrap();
    spi.done();
    assert_eq!(raw, RawSample { accel: [1, -2, 2048], temp: -521, gyro: [1640, -1640, 32767] });
    assert!(raw.saturated(), "gyro z at +32767 is clipped");
}

/// Counts → SI using the datasheet's numbers written out here, not the driver's constants.
#[test]
fn mpu6000_si_conversion_matches_datasheet_sensitivity() {
    // Sensor frame = body frame for this check; 1640 LSB = 100 °/s, 2048 LSB = 1 g.
    let bytes: Vec<u8> =
        [2048i16, -1024, 0, -521, 1640, -164, 0].iter().flat_map(|v| v.to_be_bytes()).collect();
    let mut spi = SpiMock::new(&read(0x3B, &bytes));
    let mut imu = Mpu6000::new(spi.clone(), AxisMap::IDENTITY);
    let s = imu.read().unwrap();
    spi.done();
    let deg = std::f64::consts::PI / 180.0;
    let close = |a: f32, b: f64| (a as f64 - b).abs() <= 1e-6 * b.abs().max(1.0);
    assert!(close(s.gyro[0], 100.0 * deg), "{}", s.gyro[0]);
    assert!(close(s.gyro[1], -10.0 * deg), "{}", s.gyro[1]);
    assert_eq!(s.gyro[2], 0.0);
    assert!(close(s.accel[0], 9.80665), "{}", s.accel[0]);
    assert!(close(s.accel[1], -0.5 * 9.80665), "{}", s.accel[1]);
    // PS §6.3: −521 LSB at 35 °C, 340 LSB/°C; RM §4.18: T = raw/340 + 36.53.
    assert!((s.temp_c - 35.0).abs() < 0.01, "{}", s.temp_c);
    assert!(!s.saturated);
    // Full scale: 32767 LSB ≈ 1998 °/s and ≈ 16 g.
    let raw = RawSample { accel: [32767, 0, 0], temp: 0, gyro: [32767, 0, 0] };
    let fs = wing_ahrs::drivers::mpu6000::to_sample(&raw, &AxisMap::IDENTITY);
    assert!(close(fs.gyro[0], 32767.0 / 16.4 * deg));
    assert!(close(fs.accel[0], 32767.0 / 2048.0 * 9.80665));
}

/// INAV: raw sensor → CW270_DEG alignment (x' = −y, y' = x, z' = z) in INAV's
/// x-forward, y-left, z-up body frame, then FLU → FRD.
fn inav_frd(s: [f32; 3]) -> [f32; 3] {
    let flu = [-s[1], s[0], s[2]];
    [flu[0], -flu[1], -flu[2]]
}

/// ArduPilot: the Invensense driver's fixed (y, x, −z), then the board's ROTATION_YAW_180.
fn ardupilot_frd(s: [f32; 3]) -> [f32; 3] {
    let v = [s[1], s[0], -s[2]];
    [-v[0], -v[1], v[2]]
}

#[test]
fn matek_axis_map_agrees_with_inav_and_ardupilot_target_definitions() {
    let map = AxisMap::MATEK_F405_WING;
    for v in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.3, -1.7, 9.1]] {
        assert_eq!(map.apply(v), inav_frd(v), "INAV for {v:?}");
        assert_eq!(map.apply(v), ardupilot_frd(v), "ArduPilot for {v:?}");
    }
    // Board level and still: the chip's Z (out of its top face) reads +1 g, and the
    // estimator must see specific force (0, 0, −g) in FRD (docs/design.md, conventions).
    let bytes: Vec<u8> = [0i16, 0, 2048, 0, 0, 0, 0].iter().flat_map(|v| v.to_be_bytes()).collect();
    let mut spi = SpiMock::new(&read(0x3B, &bytes));
    let mut imu = Mpu6000::new(spi.clone(), AxisMap::MATEK_F405_WING);
    let s = imu.read().unwrap();
    spi.done();
    assert_eq!(s.accel[0], 0.0);
    assert_eq!(s.accel[1], 0.0);
    assert!((s.accel[2] + G).abs() < 1e-5, "{:?}", s.accel);
}

#[test]
fn axis_maps_are_exactly_the_24_proper_rotations() {
    let mut accepted = 0;
    for p in [[0u8, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]] {
        for bits in 0..8u8 {
            let neg = [bits & 1 != 0, bits & 2 != 0, bits & 4 != 0];
            if let Some(m) = AxisMap::new(p, neg) {
                accepted += 1;
                let r = m.matrix();
                let det = r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1])
                    - r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0])
                    + r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]);
                assert_eq!(det, 1.0, "{p:?} {neg:?}");
                // apply() is the matrix product.
                let v = [0.25f32, -3.0, 7.5];
                let mv: Vec<f32> =
                    r.iter().map(|row| row.iter().zip(v).map(|(a, b)| a * b).sum()).collect();
                assert_eq!(m.apply(v).to_vec(), mv);
            }
        }
    }
    assert_eq!(accepted, 24);
    assert!(AxisMap::new([0, 0, 2], [false; 3]).is_none());
    assert!(AxisMap::new([0, 1, 3], [false; 3]).is_none());
    assert_eq!(AxisMap::new([1, 0, 2], [true, true, true]), Some(AxisMap::MATEK_F405_WING));
}

// ---- ICM-42688-P (DS-000347: WHO_AM_I 0x47, 16.4 LSB/(°/s), 2048 LSB/g, 132.48 LSB/°C + 25 °C) ----

fn icm_reset_and_id(id: u8) -> Vec<Tx<u8>> {
    let mut t = Vec::new();
    t.extend(write(&[0x76, 0x00])); // REG_BANK_SEL: bank 0
    t.extend(write(&[0x11, 0x01])); // DEVICE_CONFIG: SOFT_RESET_CONFIG
    t.extend(read(0x75, &[id])); // WHO_AM_I
    t
}

fn icm_config(gyro0: u8, accel0: u8, filt: u8) -> Vec<Tx<u8>> {
    let mut t = Vec::new();
    t.extend(write(&[0x4C, 0x33])); // INTF_CONFIG0: big endian, I2C off
    t.extend(write(&[0x4F, gyro0])); // GYRO_CONFIG0: FS ±2000 °/s | ODR
    t.extend(write(&[0x50, accel0])); // ACCEL_CONFIG0: FS ±16 g | ODR
    t.extend(write(&[0x52, filt])); // GYRO_ACCEL_CONFIG0: UI filter BW
    t.extend(write(&[0x14, 0x03])); // INT_CONFIG: INT1 pulsed, push-pull, active high
    t.extend(write(&[0x64, 0x00])); // INT_CONFIG1: INT_ASYNC_RESET cleared
    t.extend(write(&[0x65, 0x08])); // INT_SOURCE0: UI_DRDY_INT1_EN
    t.extend(write(&[0x4E, 0x0F])); // PWR_MGMT0: gyro + accel low noise
    t
}

#[test]
fn icm42688_init_issues_reset_id_and_100hz_config_sequence() {
    let mut expect = icm_reset_and_id(0x47);
    // ODR code 0b1000 = 100 Hz for both; filter index 4 in both nibbles.
    expect.extend(icm_config(0x08, 0x08, 0x44));
    expect.extend(read(0x4F, &[0x08, 0x08, 0x16, 0x44])); // read-back (0x51 is left at its reset value)
    let mut spi = SpiMock::new(&expect);
    let mut delay = CheckedDelay::new(&[DelayTx::delay_ms(1), DelayTx::delay_ms(50)]);
    let cfg = Icm42688Config::default();
    assert_eq!(cfg.odr.hz(), 100.0);
    let mut imu = Icm42688::new(spi.clone(), AxisMap::IDENTITY);
    imu.init(&mut delay, &cfg).expect("init");
    spi.done();
    delay.done();
}

#[test]
fn icm42688_rejects_an_mpu6000_and_a_config_that_did_not_stick() {
    let mut spi = SpiMock::new(&icm_reset_and_id(0x68));
    let mut imu = Icm42688::new(spi.clone(), AxisMap::IDENTITY);
    assert_eq!(
        imu.init(&mut NoopDelay::new(), &Icm42688Config::default()),
        Err(Icm42688Error::WrongId(0x68))
    );
    spi.done();

    let cfg = Icm42688Config { odr: Odr::Hz200, ui_filter_bw: 0 };
    let mut expect = icm_reset_and_id(0x47);
    expect.extend(icm_config(0x07, 0x07, 0x00));
    expect.extend(read(0x4F, &[0x07, 0x06, 0x16, 0x00])); // accel ODR write lost
    let mut spi = SpiMock::new(&expect);
    let mut imu = Icm42688::new(spi.clone(), AxisMap::IDENTITY);
    let r = imu.init(&mut NoopDelay::new(), &cfg);
    assert_eq!(
        r,
        Err(Icm42688Error::ConfigMismatch { wrote: [0x07, 0x07, 0x00], read: [0x07, 0x06, 0x00] })
    );
    spi.done();
}

#[test]
fn icm42688_burst_read_is_temp_accel_gyro_and_scales_per_datasheet() {
    // Register order from TEMP_DATA1 (0x1D): temp, accel XYZ, gyro XYZ.
    // temp 132 LSB ≈ 26 °C; accel (2048, 0, −1024) = (1, 0, −0.5) g; gyro (1640, 0, −164) = (100, 0, −10) °/s.
    let bytes: Vec<u8> =
        [132i16, 2048, 0, -1024, 1640, 0, -164].iter().flat_map(|v| v.to_be_bytes()).collect();
    let mut spi = SpiMock::new(&read(0x1D, &bytes));
    let mut imu = Icm42688::new(spi.clone(), AxisMap::IDENTITY);
    let s = imu.read().unwrap();
    spi.done();
    let deg = std::f64::consts::PI / 180.0;
    let close = |a: f32, b: f64| (a as f64 - b).abs() <= 1e-6 * b.abs().max(1.0);
    assert!(
        close(s.accel[0], 9.80665) && s.accel[1] == 0.0 && close(s.accel[2], -0.5 * 9.80665),
        "{:?}",
        s.accel
    );
    assert!(
        close(s.gyro[0], 100.0 * deg) && s.gyro[1] == 0.0 && close(s.gyro[2], -10.0 * deg),
        "{:?}",
        s.gyro
    );
    assert!((s.temp_c - (25.0 + 132.0 / 132.48)).abs() < 1e-4, "{}", s.temp_c);
}
