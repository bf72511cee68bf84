//! GPS receiver input for the RX interrupt: bytes → fixes.
//!
//! INTERIM: a minimal UBX NAV-PVT framer until the core's streaming UBX/NMEA parser
//! (`wing_ahrs::gps::GpsParser`, branch `gps`) is merged; the firmware then calls
//! that instead (same `push(byte) -> Option<GpsFix>` shape). Decoding follows the
//! same field conversions (mm/s × 1e-3 in f32) so the host reference matches.
use wing_ahrs::{FixType, GpsFix};

const SYNC1: u8 = 0xB5;
const SYNC2: u8 = 0x62;
const LEN_PVT: usize = 92;

/// Parser error counters.
#[derive(Clone, Copy, Debug, Default)]
pub struct Counters {
    /// Frames with a bad checksum.
    pub checksum_failures: u32,
    /// Frames with an impossible length.
    pub oversize: u32,
    /// Bytes outside good frames.
    pub bytes_dropped: u32,
    /// Fixes emitted.
    pub fixes: u32,
}

/// Streaming UBX framer (NAV-PVT only).
pub struct GpsParser {
    state: u8,
    class: u8,
    id: u8,
    len: usize,
    n: usize,
    ck_a: u8,
    ck_b: u8,
    rx_a: u8,
    buf: [u8; LEN_PVT],
    counters: Counters,
}

fn u32le(p: &[u8], o: usize) -> u32 {
    u32::from_le_bytes([p[o], p[o + 1], p[o + 2], p[o + 3]])
}

impl GpsParser {
    /// A parser hunting for sync.
    pub const fn new() -> Self {
        GpsParser {
            state: 0,
            class: 0,
            id: 0,
            len: 0,
            n: 0,
            ck_a: 0,
            ck_b: 0,
            rx_a: 0,
            buf: [0; LEN_PVT],
            counters: Counters { checksum_failures: 0, oversize: 0, bytes_dropped: 0, fixes: 0 },
        }
    }

    /// Error/fix counters.
    pub fn counters(&self) -> &Counters {
        &self.counters
    }

    fn ck(&mut self, b: u8) {
        self.ck_a = self.ck_a.wrapping_add(b);
        self.ck_b = self.ck_b.wrapping_add(self.ck_a);
    }

    /// One byte; a fix when it completed a good NAV-PVT with a usable solution.
    /// `t_us` stamps the fix (the firmware restamps it when the IMU task consumes it).
    pub fn push(&mut self, b: u8, t_us: u64) -> Option<GpsFix> {
        match self.state {
            0 => {
                if b == SYNC1 {
                    self.state = 1;
                } else {
                    self.counters.bytes_dropped += 1;
                }
            }
            1 => self.state = if b == SYNC2 { 2 } else { 0 },
            2 => {
                self.class = b;
                self.ck_a = 0;
                self.ck_b = 0;
                self.ck(b);
                self.state = 3;
            }
            3 => {
                self.id = b;
                self.ck(b);
                self.state = 4;
            }
            4 => {
                self.len = b as usize;
                self.ck(b);
                self.state = 5;
            }
            5 => {
                self.len |= (b as usize) << 8;
                self.ck(b);
                self.n = 0;
                if self.len > 1024 {
                    self.counters.oversize += 1;
                    self.state = 0;
                } else {
                    self.state = if self.len == 0 { 7 } else { 6 };
                }
            }
            6 => {
                if self.n < LEN_PVT {
                    self.buf[self.n] = b;
                }
                self.n += 1;
                self.ck(b);
                if self.n == self.len {
                    self.state = 7;
                }
            }
            7 => {
                self.rx_a = b;
                self.state = 8;
            }
            _ => {
                self.state = 0;
                if self.rx_a != self.ck_a || b != self.ck_b {
                    self.counters.checksum_failures += 1;
                    return None;
                }
                if self.class == 0x01 && self.id == 0x07 && self.len == LEN_PVT {
                    return self.pvt(t_us);
                }
            }
        }
        None
    }

    fn pvt(&mut self, t_us: u64) -> Option<GpsFix> {
        let p = &self.buf;
        let i = |o: usize| u32le(p, o) as i32;
        let fix_type = match p[20] {
            1 => FixType::DeadReckoning,
            2 => FixType::Fix2D,
            3 => FixType::Fix3D,
            4 => FixType::GnssDeadReckoning,
            _ => FixType::NoFix,
        };
        let fix = GpsFix {
            t_us,
            itow_ms: Some(u32le(p, 0)),
            fix_type,
            fix_ok: p[21] & 1 != 0 && p[78] & 1 == 0,
            vel_ned: [i(48) as f32 * 1e-3, i(52) as f32 * 1e-3, i(56) as f32 * 1e-3],
            vd_valid: true,
            speed_acc: Some(u32le(p, 68) as f32 * 1e-3),
            num_sats: p[23],
            lon_e7: i(24),
            lat_e7: i(28),
            alt_msl_mm: i(36),
        };
        if !fix.usable() {
            return None;
        }
        self.counters.fixes += 1;
        Some(fix)
    }
}
