//! HIL sensor-record decoder (QEMU board): the framed, checksummed records the host
//! streams on the sensor UART. Format: `docs/hil-protocol.md`.
//!
//! ```text
//! A5 5A | kind u8 | len u8 | payload[len] | crc16 LE (CRC-16/CCITT-FALSE over kind, len, payload)
//! ```
//! Hand-written: a 60-line byte state machine with a table-free CRC; no crate fits
//! this project-specific framing.

/// Largest payload accepted, bytes.
pub const MAX_PAYLOAD: usize = 48;
/// Record kinds.
pub const KIND_IMU: u8 = 1;
/// Telemetry configuration record.
pub const KIND_CONFIG: u8 = 2;
/// End of the flight: flush telemetry, report, exit.
pub const KIND_STOP: u8 = 3;
const IMU_LEN: usize = 41;
const CONFIG_LEN: usize = 5;

/// One IMU sample (with airspeed and the host's cumulative GPS-fix count).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuRecord {
    /// Sample time, µs (the IMU clock the estimator runs on).
    pub t_us: u64,
    /// Gyro, rad/s, body FRD.
    pub gyro: [f32; 3],
    /// Specific force, m/s², body FRD.
    pub accel: [f32; 3],
    /// True airspeed, m/s, if a sample came with this row.
    pub airspeed: Option<f32>,
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

/// Longest frame: sync (2) + kind + len + payload + crc (2).
const MAX_FRAME: usize = MAX_PAYLOAD + 6;

/// Streaming decoder: one byte at a time, no panics. After a failed frame its
/// bytes after the first sync byte are scanned again, so a truncated record
/// cannot swallow the valid record that follows it (bounded: ≤ 54 bytes re-fed).
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

/// CRC-16/CCITT-FALSE update (poly 0x1021, init 0xFFFF), bitwise: 8 shifts per byte.
pub fn crc16(mut crc: u16, b: u8) -> u16 {
    crc ^= (b as u16) << 8;
    for _ in 0..8 {
        crc = if crc & 0x8000 != 0 { (crc << 1) ^ 0x1021 } else { crc << 1 };
    }
    crc
}

fn f32_at(p: &[u8], i: usize) -> f32 {
    f32::from_le_bytes([p[i], p[i + 1], p[i + 2], p[i + 3]])
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
                if b == 0xA5 {
                    self.state = State::Sync2;
                } else {
                    self.raw_n = 0;
                }
            }
            State::Sync2 => {
                if b == 0x5A {
                    self.state = State::Kind;
                } else if b == 0xA5 {
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
                let expected = match self.kind {
                    KIND_IMU => IMU_LEN,
                    KIND_CONFIG => CONFIG_LEN,
                    KIND_STOP => 0,
                    _ => usize::MAX,
                };
                if self.len != expected {
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
                return Some(self.record());
            }
        }
        None
    }

    fn record(&self) -> Record {
        let p = &self.buf;
        match self.kind {
            KIND_IMU => {
                let mut t = [0u8; 8];
                t.copy_from_slice(&p[0..8]);
                let flags = p[40];
                Record::Imu(ImuRecord {
                    t_us: u64::from_le_bytes(t),
                    gyro: [f32_at(p, 8), f32_at(p, 12), f32_at(p, 16)],
                    accel: [f32_at(p, 20), f32_at(p, 24), f32_at(p, 28)],
                    airspeed: if flags & 1 != 0 { Some(f32_at(p, 32)) } else { None },
                    gps_count: u32::from_le_bytes([p[36], p[37], p[38], p[39]]),
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
}
