//! UBX framing (sync, header checks, running Fletcher-8 checksum) and decoding of
//! the NAV messages that carry a velocity solution.
//!
//! Work per byte is constant: the checksum is updated byte by byte and only the
//! payload of a decoded message (≤ 92 bytes) is stored; other payloads are
//! checksummed and skipped without being stored.

/// First UBX sync character (`µ`).
pub const SYNC1: u8 = 0xB5;
/// Second UBX sync character (`b`).
pub const SYNC2: u8 = 0x62;
/// Class of the navigation results messages.
pub const CLASS_NAV: u8 = 0x01;
/// NAV-POSLLH message id (payload 28 bytes).
pub const ID_POSLLH: u8 = 0x02;
/// NAV-SOL message id (payload 52 bytes).
pub const ID_SOL: u8 = 0x06;
/// NAV-PVT message id (payload 92 bytes).
pub const ID_PVT: u8 = 0x07;
/// NAV-VELNED message id (payload 36 bytes).
pub const ID_VELNED: u8 = 0x12;
/// Payload length of NAV-PVT (protocol ≥ 15; the older 84-byte form is not decoded).
pub const LEN_PVT: u16 = 92;
/// Payload length of NAV-VELNED.
pub const LEN_VELNED: u16 = 36;
/// Payload length of NAV-SOL.
pub const LEN_SOL: u16 = 52;
/// Payload length of NAV-POSLLH.
pub const LEN_POSLLH: u16 = 28;
/// Longest payload framed for messages that are not decoded (checksummed, not
/// stored). 4 KiB covers every message of an M8/F9 (RXM-SFRBX/RAWX, MON-SPAN,
/// NAV-SAT with 100+ satellites). A corrupted length can swallow up to this many
/// bytes, but decoded NAV frames inside them are still found by their header
/// signature (below), so only NMEA and undecoded frames are lost there.
pub const MAX_SKIP_LEN: u16 = 4096;

/// The UBX message classes a u-blox receiver emits; any other class byte after the
/// sync characters is garbage and restarts the hunt at once.
const KNOWN_CLASSES: [u8; 15] =
    [0x01, 0x02, 0x04, 0x05, 0x06, 0x09, 0x0A, 0x0B, 0x0D, 0x10, 0x13, 0x21, 0x27, 0x28, 0x29];

/// Headers (sync, class, id, length) of the decoded messages. A frame shortened
/// by lost bytes (or a false header in garbage) would swallow the next frame's
/// header into its payload; seeing one of these 48-bit patterns end inside a
/// payload restarts framing there instead, so the framer resynchronises within
/// one frame. The chance that real payload
/// data contains one is ≈ 2⁻⁴⁸ per byte.
const SIGNATURES: [(u64, u8, u16); 4] = [
    (sig(ID_PVT, LEN_PVT), ID_PVT, LEN_PVT),
    (sig(ID_VELNED, LEN_VELNED), ID_VELNED, LEN_VELNED),
    (sig(ID_SOL, LEN_SOL), ID_SOL, LEN_SOL),
    (sig(ID_POSLLH, LEN_POSLLH), ID_POSLLH, LEN_POSLLH),
];

const fn sig(id: u8, len: u16) -> u64 {
    ((SYNC1 as u64) << 40)
        | ((SYNC2 as u64) << 32)
        | ((CLASS_NAV as u64) << 24)
        | ((id as u64) << 16)
        | (((len & 0xFF) as u64) << 8)
        | ((len >> 8) as u64)
}

/// Expected payload length of a decoded message, `None` for messages only skipped.
pub fn decoded_len(class: u8, id: u8) -> Option<u16> {
    if class != CLASS_NAV {
        return None;
    }
    match id {
        ID_PVT => Some(LEN_PVT),
        ID_VELNED => Some(LEN_VELNED),
        ID_SOL => Some(LEN_SOL),
        ID_POSLLH => Some(LEN_POSLLH),
        _ => None,
    }
}

/// UBX Fletcher-8 checksum over class, id, length and payload (u-blox spec §"UBX checksum").
pub fn checksum(bytes: &[u8]) -> (u8, u8) {
    let (mut a, mut b) = (0u8, 0u8);
    for &x in bytes {
        a = a.wrapping_add(x);
        b = b.wrapping_add(a);
    }
    (a, b)
}

/// Wrap `payload` in a UBX frame (sync, class, id, length, Fletcher checksum).
pub fn frame(class: u8, id: u8, payload: &[u8], out: &mut [u8]) -> Option<usize> {
    let n = payload.len();
    let len = u16::try_from(n).ok()?;
    let frame = out.get_mut(..n + 8)?;
    frame[0] = SYNC1;
    frame[1] = SYNC2;
    frame[2] = class;
    frame[3] = id;
    frame[4..6].copy_from_slice(&len.to_le_bytes());
    frame[6..6 + n].copy_from_slice(payload);
    let (a, b) = checksum(&frame[2..6 + n]);
    frame[6 + n] = a;
    frame[7 + n] = b;
    Some(n + 8)
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum State {
    Sync2,
    Class,
    Id,
    Len1,
    Len2,
    Payload,
    CkA,
    CkB,
}

/// Why a frame was dropped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fail {
    /// Bad checksum.
    Checksum,
    /// Length above the bound, or not the fixed length of a decoded message.
    Oversize,
    /// Header rejected (second sync char or class byte): not a frame.
    NotAFrame,
    /// A new frame header appeared inside this frame: it was cut short.
    Truncated,
}

/// Result of one byte fed to the framer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Step {
    /// Frame in progress.
    More,
    /// A frame with a good checksum ended with this byte; `len` is its payload length.
    Frame {
        /// Class byte.
        class: u8,
        /// Message id.
        id: u8,
        /// Payload length, bytes.
        len: u16,
        /// The frame's last bytes begin a decoded message's header (`µ`, `µb`, `µb` + class
        /// …): they may also be the start of the next frame, which a frame cut short whose
        /// checksum collided there (odds 2⁻¹⁶) would swallow. Hunt them ([`Framer::replay`])
        /// again; harmless if they were only payload and checksum.
        replay: bool,
    },
    /// The frame failed; `bytes` were lost with it. With `replay`, the bytes of
    /// [`Framer::replay`] (ending with this byte) must be hunted through again; with `Fail::Truncated` the framer
    /// has already started the frame that cut this one short and stays active.
    Failed {
        /// Why.
        why: Fail,
        /// Bytes lost with the failed frame (replayed bytes excluded).
        bytes: u16,
        /// Whether the header bytes must be re-scanned.
        replay: bool,
    },
}

/// Byte-at-a-time UBX framer. Start it with [`Framer::start`] on a `0xB5`.
#[derive(Debug, Clone)]
pub struct Framer {
    state: State,
    class: u8,
    id: u8,
    len: u16,
    idx: u16,
    ck_a: u8,
    ck_b: u8,
    rx_a: u8,
    hdr: [u8; 6],
    hdr_len: u8,
    hist: u64,
    rbuf: [u8; 6],
    rlen: u8,
    store: bool,
    nbytes: u16,
    buf: [u8; LEN_PVT as usize],
}

impl Default for Framer {
    fn default() -> Self {
        Self::new()
    }
}

impl Framer {
    /// A framer waiting for [`Framer::start`].
    pub const fn new() -> Self {
        Self {
            state: State::Sync2,
            class: 0,
            id: 0,
            len: 0,
            idx: 0,
            ck_a: 0,
            ck_b: 0,
            rx_a: 0,
            hdr: [0; 6],
            hdr_len: 0,
            hist: 0,
            rbuf: [0; 6],
            rlen: 0,
            store: false,
            nbytes: 0,
            buf: [0; LEN_PVT as usize],
        }
    }

    /// Begin a frame: the caller has just seen `SYNC1`.
    pub fn start(&mut self) {
        self.state = State::Sync2;
        self.hdr[0] = SYNC1;
        self.hdr_len = 1;
        self.ck_a = 0;
        self.ck_b = 0;
        self.nbytes = 1;
        self.hist = SYNC1 as u64;
    }

    /// Header bytes of the current frame received so far (sync chars included).
    #[cfg(any(test, feature = "internals"))]
    pub fn header(&self) -> &[u8] {
        &self.hdr[..self.hdr_len as usize]
    }

    /// Stored payload of the last frame (valid after [`Step::Frame`] of a decoded message).
    pub fn payload(&self) -> &[u8] {
        let n = (self.len as usize).min(self.buf.len());
        &self.buf[..n]
    }

    fn fletcher(&mut self, b: u8) {
        self.ck_a = self.ck_a.wrapping_add(b);
        self.ck_b = self.ck_b.wrapping_add(self.ck_a);
    }

    fn header_byte(&mut self, b: u8) {
        if (self.hdr_len as usize) < self.hdr.len() {
            self.hdr[self.hdr_len as usize] = b;
            self.hdr_len += 1;
        }
    }

    fn fail_header(&mut self, why: Fail) -> Step {
        let n = self.hdr_len as usize;
        self.rlen = (n - 1) as u8;
        self.rbuf[..n - 1].copy_from_slice(&self.hdr[1..n]);
        Step::Failed { why, bytes: 1, replay: true }
    }

    /// Bytes to hunt through again after a [`Step::Failed`] with `replay`.
    pub fn replay(&self) -> &[u8] {
        &self.rbuf[..self.rlen as usize]
    }

    /// Begin the payload of a frame with a complete, accepted header.
    fn begin_payload(&mut self) {
        self.idx = 0;
        self.store = decoded_len(self.class, self.id).is_some();
        self.state = if self.len == 0 { State::CkA } else { State::Payload };
    }

    /// A decoded message's header seen inside a frame: restart there.
    fn restart_at_signature(&mut self) -> bool {
        for &(s, id, len) in &SIGNATURES {
            if self.hist == s {
                self.class = CLASS_NAV;
                self.id = id;
                self.len = len;
                self.hdr = [SYNC1, SYNC2, CLASS_NAV, id, (len & 0xFF) as u8, (len >> 8) as u8];
                self.hdr_len = 6;
                let (a, b) = checksum(&self.hdr[2..]);
                self.ck_a = a;
                self.ck_b = b;
                self.begin_payload();
                return true;
            }
        }
        false
    }

    /// Feed one byte of the frame.
    pub fn push(&mut self, b: u8) -> Step {
        self.nbytes = self.nbytes.saturating_add(1);
        // History of this frame's bytes, header included: a header split between
        // a false header (garbage `µb…`) and its payload is still recognised.
        self.roll(b);
        match self.state {
            State::Sync2 | State::Class | State::Id | State::Len1 | State::Len2 => {
                self.header_step(b)
            }
            State::Payload => {
                if self.restart_at_signature() {
                    return self.cut_short();
                }
                self.payload_byte(b);
                Step::More
            }
            State::CkA => {
                if self.restart_at_signature() {
                    return self.cut_short();
                }
                self.rx_a = b;
                self.state = State::CkB;
                Step::More
            }
            State::CkB => self.checksum_end(b),
        }
    }

    /// One header byte (second sync char, class, id, length): the checks a header must
    /// pass before its payload is read.
    #[inline(always)]
    fn header_step(&mut self, b: u8) -> Step {
        self.header_byte(b);
        match self.state {
            State::Sync2 => {
                if b != SYNC2 {
                    return self.fail_header(Fail::NotAFrame);
                }
                self.state = State::Class;
            }
            State::Class => {
                if !KNOWN_CLASSES.contains(&b) {
                    return self.fail_header(Fail::NotAFrame);
                }
                self.class = b;
                self.fletcher(b);
                self.state = State::Id;
            }
            State::Id => {
                self.id = b;
                self.fletcher(b);
                self.state = State::Len1;
            }
            State::Len1 => {
                self.len = b as u16;
                self.fletcher(b);
                self.state = State::Len2;
            }
            _ => {
                self.len |= (b as u16) << 8;
                self.fletcher(b);
                let ok = match decoded_len(self.class, self.id) {
                    Some(l) => self.len == l,
                    None => self.len <= MAX_SKIP_LEN,
                };
                if !ok {
                    return self.fail_header(Fail::Oversize);
                }
                self.begin_payload();
            }
        }
        Step::More
    }

    /// One payload byte: stored if the message is decoded, summed either way.
    #[inline(always)]
    fn payload_byte(&mut self, b: u8) {
        if self.store {
            if let Some(slot) = self.buf.get_mut(self.idx as usize) {
                *slot = b;
            }
        }
        self.fletcher(b);
        self.idx += 1;
        if self.idx == self.len {
            self.state = State::CkA;
        }
    }

    /// The second checksum byte: the frame ends, good or failed.
    #[inline(always)]
    fn checksum_end(&mut self, b: u8) -> Step {
        let ok = self.rx_a == self.ck_a && b == self.ck_b;
        // A whole decoded-message header ends here: with a good checksum this "frame" is
        // one cut short whose checksum collided with the next header's bytes.
        if self.restart_at_signature() {
            return self.cut_short();
        }
        self.state = State::Sync2;
        if ok {
            let k = self.header_prefix_len();
            self.keep_tail(k);
            return Step::Frame { class: self.class, id: self.id, len: self.len, replay: k > 0 };
        }
        // A frame shortened by lost bytes ends inside the next frame's
        // header: hunt through its last ≤ 5 bytes again (a partial
        // header; a complete one was caught by the signature check).
        let k = (self.nbytes.saturating_sub(1) as usize).min(5);
        self.keep_tail(k);
        Step::Failed { why: Fail::Checksum, bytes: self.nbytes - k as u16, replay: true }
    }

    /// The last `k` bytes seen become [`Framer::replay`]'s.
    #[inline(always)]
    fn keep_tail(&mut self, k: usize) {
        for i in 0..k {
            self.rbuf[i] = (self.hist >> (8 * (k - 1 - i))) as u8;
        }
        self.rlen = k as u8;
    }

    /// The longest tail (≤ 5 bytes) of the bytes seen that begins a decoded message's
    /// header (see `Step::Frame::replay`).
    fn header_prefix_len(&self) -> usize {
        (1..=5usize)
            .rev()
            .find(|&k| {
                let mask = (1u64 << (8 * k)) - 1;
                SIGNATURES.iter().any(|&(s, _, _)| self.hist & mask == s >> (8 * (6 - k)))
            })
            .unwrap_or(0)
    }

    fn roll(&mut self, b: u8) {
        self.hist = ((self.hist << 8) | b as u64) & 0xFFFF_FFFF_FFFF;
    }

    /// The frame was cut short by a new header inside it; the framer already
    /// continues with the new frame (the caller stays in UBX mode).
    fn cut_short(&mut self) -> Step {
        let lost = self.nbytes.saturating_sub(6);
        self.nbytes = 6;
        Step::Failed { why: Fail::Truncated, bytes: lost, replay: false }
    }
}

fn u16le(p: &[u8], o: usize) -> u16 {
    u16::from_le_bytes([p[o], p[o + 1]])
}
fn u32le(p: &[u8], o: usize) -> u32 {
    u32::from_le_bytes([p[o], p[o + 1], p[o + 2], p[o + 3]])
}
fn i32le(p: &[u8], o: usize) -> i32 {
    u32le(p, o) as i32
}

/// NAV-PVT fields used for a fix.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct NavPvt {
    /// GPS time of week, ms.
    pub itow_ms: u32,
    /// fixType (0 none, 1 DR, 2 2-D, 3 3-D, 4 GNSS+DR, 5 time only).
    pub fix_type: u8,
    /// flags (bit 0 gnssFixOK).
    pub flags: u8,
    /// flags3 (bit 0 invalidLlh).
    pub flags3: u8,
    /// Satellites used.
    pub num_sv: u8,
    /// Longitude, 1e-7 deg.
    pub lon_e7: i32,
    /// Latitude, 1e-7 deg.
    pub lat_e7: i32,
    /// Height above MSL, mm.
    pub h_msl_mm: i32,
    /// NED velocity, mm/s.
    pub vel_mm_s: [i32; 3],
    /// Speed accuracy, mm/s.
    pub s_acc_mm_s: u32,
    /// 2-D ground speed, mm/s (`gSpeed`: the receiver's own |vN, vE|).
    pub g_speed_mm_s: i32,
    /// Date/time (year, month, day, hour, min, sec) as sent; not used for the fix.
    pub year: u16,
}

impl NavPvt {
    /// Whether `gSpeed` equals |vN, vE| (to 2 % + 50 mm/s): a redundancy check. A
    /// corrupted frame that still passes the 16-bit Fletcher checksum (odds 2⁻¹⁶, e.g.
    /// a byte inserted inside the payload) shifts the velocity fields against it.
    pub fn consistent(&self) -> bool {
        let h = crate::math::hypot(self.vel_mm_s[0] as f32, self.vel_mm_s[1] as f32);
        libm::fabsf(self.g_speed_mm_s as f32 - h) <= 50.0 + 0.02 * h
    }
}

/// Decode a NAV-PVT payload (exactly [`LEN_PVT`] bytes).
pub fn decode_pvt(p: &[u8]) -> Option<NavPvt> {
    if p.len() != LEN_PVT as usize {
        return None;
    }
    Some(NavPvt {
        itow_ms: u32le(p, 0),
        year: u16le(p, 4),
        fix_type: p[20],
        flags: p[21],
        num_sv: p[23],
        lon_e7: i32le(p, 24),
        lat_e7: i32le(p, 28),
        h_msl_mm: i32le(p, 36),
        vel_mm_s: [i32le(p, 48), i32le(p, 52), i32le(p, 56)],
        s_acc_mm_s: u32le(p, 68),
        g_speed_mm_s: i32le(p, 60),
        flags3: p[78],
    })
}

/// NAV-VELNED fields.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct NavVelned {
    /// GPS time of week, ms.
    pub itow_ms: u32,
    /// NED velocity, cm/s.
    pub vel_cm_s: [i32; 3],
    /// Speed accuracy, cm/s.
    pub s_acc_cm_s: u32,
    /// 3-D speed |v|, cm/s (`speed`, the receiver's own).
    pub speed_cm_s: u32,
    /// 2-D ground speed |vN, vE|, cm/s (`gSpeed`, the receiver's own).
    pub g_speed_cm_s: u32,
}

impl NavVelned {
    /// Whether `speed` and `gSpeed` equal |v| and |vN, vE| (to 2 % + 5 cm/s): the redundancy
    /// check of [`NavPvt::consistent`] for the legacy message (a checksum-colliding byte
    /// insertion shifts the velocity fields against them).
    pub fn consistent(&self) -> bool {
        let [n, e, d] = self.vel_cm_s.map(|v| v as f32);
        let h = crate::math::hypot(n, e);
        let s = crate::math::hypot(h, d);
        let near = |reported: u32, v: f32| libm::fabsf(reported as f32 - v) <= 5.0 + 0.02 * v;
        near(self.g_speed_cm_s, h) && near(self.speed_cm_s, s)
    }
}

/// Decode a NAV-VELNED payload.
pub fn decode_velned(p: &[u8]) -> Option<NavVelned> {
    if p.len() != LEN_VELNED as usize {
        return None;
    }
    Some(NavVelned {
        itow_ms: u32le(p, 0),
        vel_cm_s: [i32le(p, 4), i32le(p, 8), i32le(p, 12)],
        s_acc_cm_s: u32le(p, 28),
        speed_cm_s: u32le(p, 16),
        g_speed_cm_s: u32le(p, 20),
    })
}

/// NAV-SOL fields (fix status part).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct NavSol {
    /// GPS time of week, ms.
    pub itow_ms: u32,
    /// gpsFix (same coding as NAV-PVT fixType).
    pub gps_fix: u8,
    /// flags (bit 0 gpsFixOK).
    pub flags: u8,
    /// Satellites used.
    pub num_sv: u8,
    /// Speed accuracy, cm/s (the same estimate NAV-VELNED carries: the legacy epoch
    /// checks one against the other).
    pub s_acc_cm_s: u32,
}

impl NavSol {
    /// Whether the status fields agree with each other: a defined `gpsFix` (0–5), no
    /// gpsFixOK without a fix, the satellites a position fix needs (2-D ≥ 3, 3-D ≥ 4) and
    /// no more than a u-blox 8 has channels (72). NAV-SOL has no redundant velocity, so this
    /// is what catches a checksum-colliding byte insertion (odds 2⁻¹⁶) shifting `reserved1`
    /// or `pDOP` into `numSV`, or the week into `gpsFix`. One case stays invisible: a byte
    /// inserted exactly at `numSV` that is itself a possible count — the satellite count is
    /// then wrong (nothing else; the estimator does not use it).
    pub fn consistent(&self) -> bool {
        let min_sv = match self.gps_fix {
            2 => 3,
            3 | 4 => 4,
            0..=5 => 0,
            _ => return false,
        };
        let fix_ok = self.flags & 0x01 != 0;
        (min_sv..=MAX_SV).contains(&self.num_sv) && !(fix_ok && self.gps_fix == 0)
    }
}

/// Most satellites a NAV-SOL can have used: a u-blox 8's channel count.
const MAX_SV: u8 = 72;

/// Decode a NAV-SOL payload.
pub fn decode_sol(p: &[u8]) -> Option<NavSol> {
    if p.len() != LEN_SOL as usize {
        return None;
    }
    Some(NavSol {
        itow_ms: u32le(p, 0),
        gps_fix: p[10],
        flags: p[11],
        num_sv: p[47],
        s_acc_cm_s: u32le(p, 40),
    })
}

/// NAV-POSLLH fields.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct NavPosllh {
    /// GPS time of week, ms.
    pub itow_ms: u32,
    /// Longitude, 1e-7 deg.
    pub lon_e7: i32,
    /// Latitude, 1e-7 deg.
    pub lat_e7: i32,
    /// Height above MSL, mm.
    pub h_msl_mm: i32,
    /// Height above the ellipsoid, mm.
    pub height_mm: i32,
}

impl NavPosllh {
    /// Whether the ellipsoidal and the MSL height differ by no more than the geoid can
    /// (undulation −106…+85 m; 150 m allowed): the redundancy that catches a
    /// checksum-colliding byte insertion shifting the position fields.
    pub fn consistent(&self) -> bool {
        (self.height_mm as i64 - self.h_msl_mm as i64).abs() <= 150_000
    }
}

/// Decode a NAV-POSLLH payload.
pub fn decode_posllh(p: &[u8]) -> Option<NavPosllh> {
    if p.len() != LEN_POSLLH as usize {
        return None;
    }
    Some(NavPosllh {
        itow_ms: u32le(p, 0),
        lon_e7: i32le(p, 4),
        lat_e7: i32le(p, 8),
        h_msl_mm: i32le(p, 16),
        height_mm: i32le(p, 12),
    })
}
