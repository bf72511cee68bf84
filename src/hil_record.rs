//! The HIL sensor-record codec: the framed, checksummed records `sim-harness hil` streams
//! to the QEMU firmware on the sensor UART (format: `docs/hil-protocol.md`). The one
//! definition of the format: the firmware decodes with [`Decoder`], the harness encodes
//! with [`encode`] (feature `encode`) and decodes its own records again for the host
//! reference.
//!
//! ```text
//! A5 5A | kind u8 | len u8 | payload[len] | crc16 LE (CRC-16/CCITT-FALSE over kind, len, payload)
//! ```
//! Hand-written: a byte state machine with a table-free CRC; no crate fits this
//! project-specific framing. Behind the `hil-record` feature (the firmware turns it on).

use crate::estimator::Sample;

/// First and second sync byte.
pub const SYNC: [u8; 2] = [0xA5, 0x5A];
/// Largest payload accepted, bytes.
pub const MAX_PAYLOAD: usize = 48;
/// Longest frame: sync (2) + kind + len + payload + crc (2).
pub const MAX_FRAME: usize = MAX_PAYLOAD + 6;
/// IMU sample record.
pub const KIND_IMU: u8 = 1;
/// Telemetry configuration record.
pub const KIND_CONFIG: u8 = 2;
/// End of the flight: flush telemetry, report, exit.
pub const KIND_STOP: u8 = 3;
/// Payload length of an IMU record, bytes.
pub const IMU_LEN: usize = 41;
/// Payload length of a configuration record, bytes.
pub const CONFIG_LEN: usize = 5;

/// Byte offsets in the IMU payload (all fields little-endian).
mod imu_at {
    /// `t_us` u64.
    pub const T_US: usize = 0;
    /// Gyro f32 × 3.
    pub const GYRO: usize = 8;
    /// Specific force f32 × 3.
    pub const ACCEL: usize = 20;
    /// Airspeed f32 (valid when bit 0 of `FLAGS` is set).
    pub const AIRSPEED: usize = 32;
    /// Cumulative GPS-fix count u32.
    pub const GPS_COUNT: usize = 36;
    /// Flags u8: bit 0, airspeed present.
    pub const FLAGS: usize = 40;
}

/// One IMU sample (with its airspeed) and the host's cumulative GPS-fix count.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuRecord {
    /// The sample as the estimator takes it ([`crate::Ahrs::predict`]): `t_us` is the
    /// IMU clock the estimator runs on.
    pub sample: Sample,
    /// GPS fixes the host has sent so far, this row's included: the firmware hands the
    /// estimator exactly this many fixes before/at this sample (determinism across UARTs).
    pub gps_count: u32,
}

/// Telemetry configuration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TelemetryConfig {
    /// ATTITUDE rate, Hz (0: off).
    pub attitude_hz: u16,
    /// HIGHRES_IMU (raw IMU for bench recordings) rate, Hz (0: off).
    pub raw_imu_hz: u16,
    /// Per-sample estimate output (ATTITUDE + DEBUG_VECT every sample) for HIL comparison.
    pub per_sample: bool,
}

/// A decoded record.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Record {
    /// IMU sample.
    Imu(ImuRecord),
    /// Telemetry configuration.
    Config(TelemetryConfig),
    /// End of flight.
    Stop,
}

/// CRC-16/CCITT-FALSE update (poly 0x1021, init 0xFFFF), bitwise: 8 shifts per byte.
pub fn crc16(mut crc: u16, b: u8) -> u16 {
    crc ^= (b as u16) << 8;
    for _ in 0..8 {
        crc = if crc & 0x8000 != 0 { (crc << 1) ^ 0x1021 } else { crc << 1 };
    }
    crc
}

/// CRC-16/CCITT-FALSE of `bytes` (check value of `"123456789"`: 0x29B1).
pub fn crc16_of(bytes: &[u8]) -> u16 {
    bytes.iter().fold(0xFFFF, |c, &b| crc16(c, b))
}

/// The payload length a record kind must have (`None`: unknown kind).
fn payload_len(kind: u8) -> Option<usize> {
    match kind {
        KIND_IMU => Some(IMU_LEN),
        KIND_CONFIG => Some(CONFIG_LEN),
        KIND_STOP => Some(0),
        _ => None,
    }
}

fn f32_at(p: &[u8], i: usize) -> f32 {
    f32::from_le_bytes([p[i], p[i + 1], p[i + 2], p[i + 3]])
}

fn vec3_at(p: &[u8], i: usize) -> [f32; 3] {
    [f32_at(p, i), f32_at(p, i + 4), f32_at(p, i + 8)]
}

/// The record of a checked payload of `kind` (its length is the kind's; the rest of `p`
/// is not read). A whole array, so the constant offsets need no bounds checks.
fn decode_payload(kind: u8, p: &[u8; MAX_PAYLOAD]) -> Record {
    match kind {
        KIND_IMU => {
            let mut t = [0u8; 8];
            t.copy_from_slice(&p[imu_at::T_US..imu_at::T_US + 8]);
            let g = imu_at::GPS_COUNT;
            Record::Imu(ImuRecord {
                sample: Sample {
                    t_us: u64::from_le_bytes(t),
                    gyro: vec3_at(p, imu_at::GYRO),
                    accel: vec3_at(p, imu_at::ACCEL),
                    airspeed: if p[imu_at::FLAGS] & 1 != 0 {
                        Some(f32_at(p, imu_at::AIRSPEED))
                    } else {
                        None
                    },
                },
                gps_count: u32::from_le_bytes([p[g], p[g + 1], p[g + 2], p[g + 3]]),
            })
        }
        KIND_CONFIG => Record::Config(TelemetryConfig {
            attitude_hz: u16::from_le_bytes([p[0], p[1]]),
            raw_imu_hz: u16::from_le_bytes([p[2], p[3]]),
            per_sample: p[4] & 1 != 0,
        }),
        _ => Record::Stop,
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    Sync1,
    Sync2,
    Kind,
    Len,
    Payload,
    Crc0,
    Crc1,
}

/// Streaming decoder: one byte at a time, no panics. After a failed frame its
/// bytes after the first sync byte are scanned again, so a truncated record
/// cannot swallow the valid record that follows it (bounded: ≤ 54 bytes re-fed).
#[derive(Clone, Debug)]
pub struct Decoder {
    raw: [u8; MAX_FRAME],
    raw_n: usize,
    state: State,
    kind: u8,
    len: usize,
    n: usize,
    crc: u16,
    crc_lo: u8,
    buf: [u8; MAX_PAYLOAD],
    failed: bool,
    /// Frames dropped: bad checksum, bad length or unknown kind.
    pub errors: u32,
}

impl Default for Decoder {
    fn default() -> Self {
        Self::new()
    }
}

impl Decoder {
    /// A decoder hunting for sync.
    pub const fn new() -> Self {
        Decoder {
            raw: [0; MAX_FRAME],
            raw_n: 0,
            state: State::Sync1,
            kind: 0,
            len: 0,
            n: 0,
            crc: 0xFFFF,
            crc_lo: 0,
            buf: [0; MAX_PAYLOAD],
            failed: false,
            errors: 0,
        }
    }

    fn fail(&mut self) {
        self.errors = self.errors.wrapping_add(1);
        self.state = State::Sync1;
        self.failed = true;
    }

    /// Feeds one byte; returns a record when this byte (or a re-scan it caused)
    /// completed a valid one.
    pub fn push(&mut self, b: u8) -> Option<Record> {
        // Work queue: bytes still to feed. A failed frame's bytes after its first
        // sync byte go back to its front; the queue never outgrows one frame + 1.
        let mut q = [0u8; MAX_FRAME + 1];
        q[0] = b;
        let (mut head, mut len) = (0usize, 1usize);
        let mut out = None;
        while head < len {
            let x = q[head];
            head += 1;
            if let Some(r) = self.step(x) {
                out = Some(r);
            }
            if self.failed {
                self.failed = false;
                let replay = self.raw_n.saturating_sub(1);
                self.raw_n = 0;
                let rest = len - head;
                let mut nq = [0u8; MAX_FRAME + 1];
                let k = replay.min(nq.len());
                nq[..k].copy_from_slice(&self.raw[1..1 + k]);
                let m = rest.min(nq.len() - k);
                nq[k..k + m].copy_from_slice(&q[head..head + m]);
                q = nq;
                head = 0;
                len = k + m;
            }
        }
        out
    }

    fn step(&mut self, b: u8) -> Option<Record> {
        if self.state == State::Sync1 {
            self.raw_n = 0;
        }
        if self.raw_n < MAX_FRAME {
            self.raw[self.raw_n] = b;
            self.raw_n += 1;
        }
        match self.state {
            State::Sync1 => {
                if b == SYNC[0] {
                    self.state = State::Sync2;
                } else {
                    self.raw_n = 0;
                }
            }
            State::Sync2 => {
                if b == SYNC[1] {
                    self.state = State::Kind;
                } else if b == SYNC[0] {
                    self.raw[0] = b;
                    self.raw_n = 1;
                } else {
                    self.state = State::Sync1;
                    self.raw_n = 0;
                }
            }
            State::Kind => {
                self.kind = b;
                self.crc = crc16(0xFFFF, b);
                self.state = State::Len;
            }
            State::Len => {
                self.len = b as usize;
                self.n = 0;
                self.crc = crc16(self.crc, b);
                if payload_len(self.kind) != Some(self.len) {
                    self.fail();
                } else {
                    self.state = if self.len == 0 { State::Crc0 } else { State::Payload };
                }
            }
            State::Payload => {
                self.buf[self.n] = b;
                self.n += 1;
                self.crc = crc16(self.crc, b);
                if self.n == self.len {
                    self.state = State::Crc0;
                }
            }
            State::Crc0 => {
                self.crc_lo = b;
                self.state = State::Crc1;
            }
            State::Crc1 => {
                self.state = State::Sync1;
                if u16::from_le_bytes([self.crc_lo, b]) != self.crc {
                    self.fail();
                    return None;
                }
                self.raw_n = 0;
                return Some(decode_payload(self.kind, &self.buf));
            }
        }
        None
    }
}

/// The record of one whole frame (`bytes` holds nothing else): `None` if it is not a
/// valid frame.
pub fn decode_frame(bytes: &[u8]) -> Option<Record> {
    let mut d = Decoder::new();
    let mut out = None;
    for &b in bytes {
        if let Some(r) = d.push(b) {
            out = Some(r);
        }
    }
    out
}

#[cfg(feature = "encode")]
mod enc {
    use super::*;

    fn put(p: &mut [u8], o: usize, v: &[u8]) {
        p[o..o + v.len()].copy_from_slice(v);
    }

    /// Writes `rec` as a whole frame into `out`; returns the frame's length, or `None`
    /// when `out` is too small ([`MAX_FRAME`] always suffices).
    pub fn encode(rec: &Record, out: &mut [u8]) -> Option<usize> {
        let mut p = [0u8; MAX_PAYLOAD];
        let kind = match rec {
            Record::Imu(r) => {
                let s = &r.sample;
                put(&mut p, imu_at::T_US, &s.t_us.to_le_bytes());
                for (i, v) in s.gyro.iter().enumerate() {
                    put(&mut p, imu_at::GYRO + 4 * i, &v.to_le_bytes());
                }
                for (i, v) in s.accel.iter().enumerate() {
                    put(&mut p, imu_at::ACCEL + 4 * i, &v.to_le_bytes());
                }
                put(&mut p, imu_at::AIRSPEED, &s.airspeed.unwrap_or(0.0).to_le_bytes());
                put(&mut p, imu_at::GPS_COUNT, &r.gps_count.to_le_bytes());
                p[imu_at::FLAGS] = s.airspeed.is_some() as u8;
                KIND_IMU
            }
            Record::Config(c) => {
                put(&mut p, 0, &c.attitude_hz.to_le_bytes());
                put(&mut p, 2, &c.raw_imu_hz.to_le_bytes());
                p[4] = c.per_sample as u8;
                KIND_CONFIG
            }
            Record::Stop => KIND_STOP,
        };
        let len = payload_len(kind)?;
        let n = len + 6;
        let f = out.get_mut(..n)?;
        f[..2].copy_from_slice(&SYNC);
        f[2] = kind;
        f[3] = len as u8;
        f[4..4 + len].copy_from_slice(&p[..len]);
        let crc = crc16_of(&f[2..4 + len]);
        f[4 + len..].copy_from_slice(&crc.to_le_bytes());
        Some(n)
    }
}

#[cfg(feature = "encode")]
pub use enc::encode;

#[cfg(all(test, feature = "encode"))]
mod tests {
    use super::*;

    fn imu(airspeed: Option<f32>) -> Record {
        Record::Imu(ImuRecord {
            sample: Sample {
                t_us: 0x0102_0304_0506_0708,
                gyro: [1.0, -2.5, f32::MIN_POSITIVE],
                accel: [4.0, f32::NAN, -9.81],
                airspeed,
            },
            gps_count: 0xDEAD_BEEF,
        })
    }

    fn round_trip(rec: &Record) -> (usize, Record) {
        let mut f = [0u8; MAX_FRAME];
        let n = encode(rec, &mut f).expect("fits");
        (n, decode_frame(&f[..n]).expect("decodes"))
    }

    /// Bit patterns, so a NaN compares as itself.
    fn bits(r: &Record) -> [u64; 9] {
        let Record::Imu(r) = r else { panic!("not IMU") };
        let s = &r.sample;
        let b = |x: f32| x.to_bits() as u64;
        [
            s.t_us,
            b(s.gyro[0]),
            b(s.gyro[1]),
            b(s.gyro[2]),
            b(s.accel[0]),
            b(s.accel[1]),
            b(s.accel[2]),
            s.airspeed.map_or(u64::MAX, b),
            r.gps_count as u64,
        ]
    }

    #[test]
    fn crc_matches_the_standard_check_value() {
        assert_eq!(crc16_of(b"123456789"), 0x29B1);
    }

    #[test]
    fn every_record_round_trips() {
        for a in [None, Some(23.5)] {
            let (n, back) = round_trip(&imu(a));
            assert_eq!(n, IMU_LEN + 6);
            assert_eq!(bits(&back), bits(&imu(a)));
        }
        let c =
            Record::Config(TelemetryConfig { attitude_hz: 50, raw_imu_hz: 0, per_sample: true });
        assert_eq!(round_trip(&c), (CONFIG_LEN + 6, c));
        assert_eq!(round_trip(&Record::Stop), (6, Record::Stop));
    }

    #[test]
    fn imu_record_layout() {
        let mut f = [0u8; MAX_FRAME];
        let n = encode(&imu(Some(20.0)), &mut f).unwrap();
        assert_eq!(&f[..4], &[0xA5, 0x5A, 1, 41]);
        assert_eq!(&f[4..12], &0x0102_0304_0506_0708u64.to_le_bytes());
        assert_eq!(&f[4 + 32..4 + 36], &20.0f32.to_le_bytes());
        assert_eq!(&f[4 + 36..4 + 40], &0xDEAD_BEEFu32.to_le_bytes());
        assert_eq!(f[4 + 40], 1);
        assert_eq!(u16::from_le_bytes([f[n - 2], f[n - 1]]), crc16_of(&f[2..n - 2]));
    }

    #[test]
    fn a_bad_frame_is_counted_and_the_next_one_still_decodes() {
        let mut f = [0u8; MAX_FRAME];
        let n = encode(&imu(None), &mut f).unwrap();
        let mut d = Decoder::new();
        // Truncated: the record after it must not be swallowed.
        for &b in &f[..7] {
            assert_eq!(d.push(b), None);
        }
        let mut got = None;
        for &b in &f[..n] {
            got = d.push(b).or(got);
        }
        assert_eq!(bits(&got.expect("decoded")), bits(&imu(None)));
        assert_eq!(d.errors, 1);
        let mut bad = f;
        bad[n - 1] ^= 0xFF;
        assert_eq!(decode_frame(&bad[..n]), None);
        assert_eq!(encode(&imu(None), &mut [0u8; 10]), None);
    }
}
