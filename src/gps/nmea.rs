//! NMEA 0183 framing (`$…*hh`, XOR checksum required) and incremental field
//! decoding of RMC, GGA and VTG from any talker.
//!
//! Fields are decoded as each `,` arrives into a scratch record, so the work per
//! byte is bounded by the longest field ([`MAX_FIELD`] chars); the record is only
//! handed on after the checksum matched, so a corrupt sentence never reaches an
//! epoch. Numbers are parsed as scaled integers (no float parsing, no rounding
//! surprises); floats appear only when the velocity vector is formed.

/// Longest sentence body accepted between `$` and `*` (the standard allows 80).
pub const MAX_BODY: u8 = 120;
/// Longest field decoded; longer fields in RMC/GGA/VTG make the sentence malformed.
pub const MAX_FIELD: usize = 15;

/// Sentence types decoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Kind {
    /// Not (yet) recognised: framed and checksummed only.
    #[default]
    Other,
    /// Recommended minimum data.
    Rmc,
    /// Fix data.
    Gga,
    /// Course and speed over ground.
    Vtg,
}

/// Decoded fields of one RMC/GGA/VTG sentence. Angles and speeds stay in the
/// sentence's units as scaled integers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Sentence {
    /// Which sentence.
    pub kind: Kind,
    /// UTC time of day, ms (RMC, GGA).
    pub time_ms: Option<u32>,
    /// RMC status: `A` valid, `V` warning.
    pub status: u8,
    /// Latitude, 1e-7 deg, signed (north positive).
    pub lat_e7: Option<i32>,
    /// Longitude, 1e-7 deg, signed (east positive).
    pub lon_e7: Option<i32>,
    /// Speed over ground, 1e-3 knots (RMC, VTG `N`).
    pub sog_mkn: Option<u32>,
    /// Speed over ground, 1e-3 km/h (VTG `K`).
    pub sog_mkmh: Option<u32>,
    /// Course over ground (true), 1e-3 deg.
    pub cog_mdeg: Option<u32>,
    /// GGA fix quality (0 invalid, 1 GPS, 2 DGPS, 4/5 RTK, 6 estimated…).
    pub quality: Option<u8>,
    /// GGA satellites used.
    pub sats: Option<u8>,
    /// GGA altitude above MSL, mm.
    pub alt_mm: Option<i32>,
    /// FAA mode indicator (NMEA ≥ 2.3; `A` autonomous, `D` differential, `E` estimated, `N` none…), 0 if absent.
    pub mode: u8,
}

impl Sentence {
    /// No fields.
    pub const EMPTY: Self = Self {
        kind: Kind::Other,
        time_ms: None,
        status: 0,
        lat_e7: None,
        lon_e7: None,
        sog_mkn: None,
        sog_mkmh: None,
        cog_mdeg: None,
        quality: None,
        sats: None,
        alt_mm: None,
        mode: 0,
    };
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum State {
    Body,
    Ck1,
    Ck2,
}

/// Result of one byte fed to the framer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Step {
    /// Sentence in progress.
    More,
    /// A sentence with a good checksum ended; `Kind::Other` for types not decoded.
    Done(Kind),
    /// Good checksum but RMC/GGA/VTG fields out of range or the wrong count.
    Malformed,
    /// Bad checksum.
    Checksum,
    /// Body longer than [`MAX_BODY`].
    Oversize,
    /// A byte that cannot be in a sentence (non-printable, `$`, non-hex checksum)
    /// ended it early; the caller re-hunts from this byte.
    Truncated,
}

/// Byte-at-a-time NMEA framer and field decoder. Start it with [`Framer::start`] on `$`.
#[derive(Debug, Clone)]
pub struct Framer {
    state: State,
    len: u8,
    xor: u8,
    rx_ck: u8,
    field_idx: u8,
    field: [u8; MAX_FIELD],
    flen: u8,
    overflow: bool,
    bad: bool,
    hemi_pending: i64,
    s: Sentence,
}

impl Default for Framer {
    fn default() -> Self {
        Self::new()
    }
}

fn hex(b: u8) -> Option<u8> {
    match b {
        b'0'..=b'9' => Some(b - b'0'),
        b'A'..=b'F' => Some(b - b'A' + 10),
        b'a'..=b'f' => Some(b - b'a' + 10),
        _ => None,
    }
}

/// Parse a non-negative decimal `ddd.ddd` into value × 10^`dec` (extra digits
/// truncated). `None` for an empty field, a sign, two dots or any other char.
pub fn parse_fixed(f: &[u8], dec: u32) -> Option<i64> {
    if f.is_empty() {
        return None;
    }
    let mut v: i64 = 0;
    let mut frac: Option<u32> = None;
    let mut digits = 0;
    for &c in f {
        match c {
            b'0'..=b'9' => {
                digits += 1;
                match frac {
                    None => v = v.checked_mul(10)?.checked_add((c - b'0') as i64)?,
                    Some(n) if n < dec => {
                        v = v.checked_mul(10)?.checked_add((c - b'0') as i64)?;
                        frac = Some(n + 1);
                    }
                    Some(_) => {}
                }
            }
            b'.' if frac.is_none() => frac = Some(0),
            _ => return None,
        }
    }
    if digits == 0 {
        return None;
    }
    let have = frac.unwrap_or(0);
    for _ in have..dec {
        v = v.checked_mul(10)?;
    }
    Some(v)
}

/// `hhmmss[.sss]` → ms of the UTC day, with range checks.
fn parse_time(f: &[u8]) -> Option<u32> {
    if f.len() < 6 || f[..6].iter().any(|c| !c.is_ascii_digit()) {
        return None;
    }
    let v = parse_fixed(f, 3)?;
    let (hh, mm, ms) = (v / 10_000_000, (v / 100_000) % 100, v % 100_000);
    (hh < 24 && mm < 60 && ms < 61_000).then(|| (hh * 3_600_000 + mm * 60_000 + ms) as u32)
}

/// `(d)ddmm.mmmm` → 1e-7 deg magnitude, with range checks.
fn parse_angle(f: &[u8], max_deg: i64) -> Option<i64> {
    let dot = f.iter().position(|&c| c == b'.').unwrap_or(f.len());
    if dot < 3 {
        return None;
    }
    let v = parse_fixed(f, 7)?; // ddmm × 1e7
    let deg = v / 1_000_000_000;
    let min_e7 = v % 1_000_000_000;
    if min_e7 >= 600_000_000 {
        return None;
    }
    let e7 = deg * 10_000_000 + (min_e7 + 30) / 60;
    (e7 <= max_deg * 10_000_000).then_some(e7)
}

/// Signed decimal (altitude) → value × 10^dec.
fn parse_signed(f: &[u8], dec: u32) -> Option<i64> {
    match f.first() {
        Some(b'-') => parse_fixed(&f[1..], dec).map(|v| -v),
        _ => parse_fixed(f, dec),
    }
}

impl Framer {
    /// A framer waiting for [`Framer::start`].
    pub const fn new() -> Self {
        Self {
            state: State::Body,
            len: 0,
            xor: 0,
            rx_ck: 0,
            field_idx: 0,
            field: [0; MAX_FIELD],
            flen: 0,
            overflow: false,
            bad: false,
            hemi_pending: 0,
            s: Sentence::EMPTY,
        }
    }

    /// Begin a sentence: the caller has just seen `$`.
    pub fn start(&mut self) {
        self.state = State::Body;
        self.len = 0;
        self.xor = 0;
        self.field_idx = 0;
        self.flen = 0;
        self.overflow = false;
        self.bad = false;
        self.hemi_pending = 0;
        self.s = Sentence::default();
    }

    /// Characters received since `$` (for drop accounting).
    pub fn len(&self) -> u16 {
        self.len as u16 + 1
    }

    /// Whether nothing but `$` was received.
    #[cfg(any(test, feature = "internals"))]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The decoded sentence (valid after [`Step::Done`] of RMC/GGA/VTG).
    pub fn sentence(&self) -> &Sentence {
        &self.s
    }

    /// Feed one byte of the sentence.
    pub fn push(&mut self, b: u8) -> Step {
        match self.state {
            State::Body => {
                if b == b'*' {
                    self.end_field();
                    self.state = State::Ck1;
                    return Step::More;
                }
                if !(0x20..0x7F).contains(&b) || b == b'$' {
                    return Step::Truncated;
                }
                if self.len >= MAX_BODY {
                    return Step::Oversize;
                }
                self.len += 1;
                self.xor ^= b;
                if b == b',' {
                    self.end_field();
                } else if (self.flen as usize) < MAX_FIELD {
                    self.field[self.flen as usize] = b;
                    self.flen += 1;
                } else {
                    self.overflow = true;
                }
                Step::More
            }
            State::Ck1 => match hex(b) {
                Some(h) => {
                    self.rx_ck = h << 4;
                    self.state = State::Ck2;
                    self.len = self.len.saturating_add(1);
                    Step::More
                }
                None => Step::Truncated,
            },
            State::Ck2 => match hex(b) {
                Some(h) => {
                    self.len = self.len.saturating_add(1);
                    self.state = State::Body;
                    if self.rx_ck | h != self.xor {
                        return Step::Checksum;
                    }
                    if self.s.kind == Kind::Other {
                        return Step::Done(Kind::Other);
                    }
                    let n = self.field_idx;
                    let count_ok = match self.s.kind {
                        Kind::Rmc => (12..=14).contains(&n),
                        Kind::Gga => n == 15,
                        Kind::Vtg => (9..=10).contains(&n),
                        Kind::Other => true,
                    };
                    if self.bad || !count_ok {
                        Step::Malformed
                    } else {
                        Step::Done(self.s.kind)
                    }
                }
                None => Step::Truncated,
            },
        }
    }

    /// A field ended (`,` or `*`): decode it for the sentence type. Bounded by MAX_FIELD.
    fn end_field(&mut self) {
        let idx = self.field_idx;
        self.field_idx = self.field_idx.saturating_add(1);
        let n = self.flen as usize;
        self.flen = 0;
        if idx == 0 {
            self.s.kind = if n == 5 && !self.overflow {
                match &self.field[2..5] {
                    b"RMC" => Kind::Rmc,
                    b"GGA" => Kind::Gga,
                    b"VTG" => Kind::Vtg,
                    _ => Kind::Other,
                }
            } else {
                Kind::Other
            };
            return;
        }
        if self.s.kind == Kind::Other {
            return;
        }
        if self.overflow {
            self.bad = true;
            self.overflow = false;
            return;
        }
        let mut f = [0u8; MAX_FIELD];
        f[..n].copy_from_slice(&self.field[..n]);
        let f = &f[..n];
        if !self.field(idx, f) {
            self.bad = true;
        }
    }

    /// Decode field `idx` of the current sentence; false when present but invalid.
    fn field(&mut self, idx: u8, f: &[u8]) -> bool {
        let empty = f.is_empty();
        match (self.s.kind, idx) {
            (Kind::Rmc, 3) | (Kind::Gga, 2) => return self.angle_value(f, 90),
            (Kind::Rmc, 5) | (Kind::Gga, 4) => return self.angle_value(f, 180),
            (Kind::Rmc, 4) | (Kind::Gga, 3) => return self.hemisphere(f, b'N', b'S', true),
            (Kind::Rmc, 6) | (Kind::Gga, 5) => return self.hemisphere(f, b'E', b'W', false),
            _ => {}
        }
        let s = &mut self.s;
        match (s.kind, idx) {
            (Kind::Rmc, 1) | (Kind::Gga, 1) => {
                s.time_ms = parse_time(f);
                empty || s.time_ms.is_some()
            }
            (Kind::Rmc, 2) => {
                s.status = f.first().copied().unwrap_or(0);
                matches!(s.status, b'A' | b'V' | 0) && f.len() <= 1
            }
            (Kind::Rmc, 7) | (Kind::Vtg, 5) => {
                s.sog_mkn = parse_fixed(f, 3).and_then(|v| u32::try_from(v).ok());
                empty || s.sog_mkn.is_some()
            }
            (Kind::Vtg, 7) => {
                s.sog_mkmh = parse_fixed(f, 3).and_then(|v| u32::try_from(v).ok());
                empty || s.sog_mkmh.is_some()
            }
            (Kind::Rmc, 8) | (Kind::Vtg, 1) => {
                s.cog_mdeg =
                    parse_fixed(f, 3).and_then(|v| u32::try_from(v).ok()).filter(|&c| c <= 360_000);
                empty || s.cog_mdeg.is_some()
            }
            (Kind::Rmc, 12) | (Kind::Vtg, 9) => {
                s.mode = f.first().copied().unwrap_or(0);
                f.len() <= 1
            }
            (Kind::Gga, 6) => {
                s.quality =
                    parse_fixed(f, 0).and_then(|v| u8::try_from(v).ok()).filter(|&q| q <= 9);
                !empty && s.quality.is_some()
            }
            (Kind::Gga, 7) => {
                s.sats = parse_fixed(f, 0).and_then(|v| u8::try_from(v).ok());
                empty || s.sats.is_some()
            }
            (Kind::Gga, 9) => {
                s.alt_mm = parse_signed(f, 3)
                    .filter(|&a| (-1_000_000..=100_000_000).contains(&a))
                    .map(|a| a as i32);
                empty || s.alt_mm.is_some()
            }
            (Kind::Vtg, 2) => f == b"T" || empty,
            (Kind::Vtg, 6) => f == b"N" || empty,
            (Kind::Vtg, 8) => f == b"K" || empty,
            _ => true,
        }
    }

    /// Latitude/longitude magnitude, held until its hemisphere field arrives.
    fn angle_value(&mut self, f: &[u8], max_deg: i64) -> bool {
        if f.is_empty() {
            self.hemi_pending = -1;
            return true;
        }
        match parse_angle(f, max_deg) {
            Some(v) => {
                self.hemi_pending = v;
                true
            }
            None => false,
        }
    }

    fn hemisphere(&mut self, f: &[u8], pos: u8, neg: u8, lat: bool) -> bool {
        let v = self.hemi_pending;
        self.hemi_pending = 0;
        if v < 0 {
            return f.is_empty(); // no value: no hemisphere either
        }
        let sign = match f {
            [c] if *c == pos => 1,
            [c] if *c == neg => -1,
            _ => return false,
        };
        let val = Some((sign * v) as i32);
        if lat {
            self.s.lat_e7 = val;
        } else {
            self.s.lon_e7 = val;
        }
        true
    }
}
