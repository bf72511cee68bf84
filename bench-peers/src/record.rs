//! The embedded flight: fixed 104-byte little-endian records written by `build.rs`.

static SAMPLES: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/samples.bin"));
const SIZE: usize = 104;

/// One IMU sample and the fix that arrived with it (each estimator reads what it uses).
#[allow(dead_code)]
pub struct Record {
    /// Sample time, µs.
    pub t_us: u64,
    /// Gyro, rad/s, and specific force, m/s², body FRD.
    pub gyro: [f32; 3],
    pub accel: [f32; 3],
    /// True airspeed, m/s (NaN: none this row).
    pub airspeed: f32,
    /// A fix arrived at this row.
    pub fix: bool,
    /// The fix's epoch, µs; NED velocity, m/s; speed accuracy, m/s; lat, lon (deg), alt (m).
    pub fix_t_us: u64,
    pub vel: [f32; 3],
    pub sacc: f32,
    pub lla: [f64; 3],
    /// Barometric altitude, m (NaN: none this row).
    pub baro_alt: f32,
    /// The simulator's true roll, pitch, yaw, rad (NaN: the log has none), for the
    /// agreement with truth only (`truth.rs`); no estimator is given it.
    pub truth: [f32; 3],
}

/// Size of the embedded flight, bytes (in flash, not the estimator's).
pub fn bytes() -> usize {
    SAMPLES.len()
}

/// Number of records.
pub fn count() -> usize {
    SAMPLES.len() / SIZE
}

/// Record `k` (< [`count`]).
pub fn get(k: usize) -> Record {
    let b = &SAMPLES[k * SIZE..(k + 1) * SIZE];
    let u64_at = |o: usize| u64::from_le_bytes(b[o..o + 8].try_into().unwrap_or([0; 8]));
    let f32_at = |o: usize| f32::from_le_bytes(b[o..o + 4].try_into().unwrap_or([0; 4]));
    let u32_at = |o: usize| u32::from_le_bytes(b[o..o + 4].try_into().unwrap_or([0; 4]));
    let f64_at = |o: usize| f64::from_le_bytes(b[o..o + 8].try_into().unwrap_or([0; 8]));
    let v3 = |o: usize| [f32_at(o), f32_at(o + 4), f32_at(o + 8)];
    Record {
        t_us: u64_at(0),
        gyro: v3(8),
        accel: v3(20),
        airspeed: f32_at(32),
        fix: u32_at(36) != 0,
        fix_t_us: u64_at(40),
        vel: v3(48),
        sacc: f32_at(60),
        lla: [f64_at(64), f64_at(72), f64_at(80)],
        baro_alt: f32_at(88),
        truth: v3(92),
    }
}
