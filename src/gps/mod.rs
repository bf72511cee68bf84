//! GPS receiver input: a streaming parser for u-blox UBX and NMEA 0183, fed one
//! byte at a time from the UART RX interrupt, that emits [`GpsFix`]es.
//!
//! Hand-written rather than the `ublox` crate: that crate's no-alloc parser
//! re-scans and `memmove`s its buffer and checksums a whole frame on its last
//! byte (O(frame) in one interrupt, more after a bad checksum) and discards
//! non-UBX bytes, so NMEA interleaving would need a demultiplexer in front anyway;
//! the `nmea` crate costs ≈ 68 KiB of flash. Measured flash (thumbv7em-none-eabihf,
//! opt-level "s", fat LTO, a minimal no_std consumer of the fixes): `ublox` 0.4.5
//! for NAV-PVT + NAV-VELNED only: 6.1 KiB `.text` + 0.25 KiB buffer; this module
//! for UBX (PVT, VELNED, SOL, POSLLH) + NMEA (RMC, GGA, VTG) + epoch joining:
//! 9.1 KiB `.text` + 0.3 KiB `.rodata`.
//!
//! Cost (`cargo run --release --example gps_bench`; valgrind mode in its doc):
//! ≈ 78 x86-64 instructions per byte on a NAV-PVT stream, ≈ 92 on NMEA
//! RMC+VTG+GGA. Parser state: 680 bytes.
//!
//! Guarantees: no allocation, no unsafe, no panic on any input, bounded memory,
//! bounded work per byte (the longest paths: re-hunting ≤ 5 bytes of a rejected
//! UBX header or a failed frame's tail, decoding one ≤ 15-char NMEA field, one
//! ≤ 92-byte NAV payload, or building one fix). A fix is emitted only from frames
//! whose checksum matched, whose fields are in range and whose solution is usable
//! ([`GpsFix::usable`]); everything else is counted in [`Counters`].
//!
//! Time stamps: the caller passes the local time (µs, the IMU clock, monotonic)
//! with each byte; a fix's `t_us` is the time passed with the byte that completed
//! it (the last checksum byte of its final message; for an NMEA epoch completed
//! only by a newer one, see `gps/epoch.rs`, the time of its own last sentence). The
//! firmware may overwrite `t_us` with its own stamp; it should still pass a
//! monotonic time, which the UBX-over-NMEA rule below uses.
//!
//! Protocol interleaving: UBX frames and NMEA sentences may alternate on one
//! stream; a `0xB5` or `$` outside a frame starts one, any other byte outside a
//! frame is dropped (counted). When both protocols deliver fixes, UBX wins: NMEA
//! fixes are suppressed for [`NMEA_SUPPRESS_US`] after the last UBX fix so the
//! estimator does not receive each epoch twice (only the epoch at the switch can
//! arrive from both). See `gps/epoch.rs` for how messages of one epoch are joined and
//! why NMEA fixes carry no vertical velocity.
//!
//! Resynchronisation: after a damaged frame the next intact frame is decoded —
//! a rejected header and the tail of a frame with a bad checksum are hunted
//! through again, and the header of a decoded NAV message seen inside another
//! frame restarts framing there (see `gps/ubx.rs`); NMEA restarts at every `$`.

pub mod config;
#[cfg(feature = "encode")]
pub mod encode;
crate::internal! { pub mod epoch; }
crate::internal! { pub mod nmea; }
crate::internal! { pub mod ubx; }

use crate::fix::GpsFix;

/// After a UBX fix, NMEA fixes are ignored for this long, µs.
pub const NMEA_SUPPRESS_US: u64 = 2_000_000;
/// Largest |velocity component| accepted, m/s (u-blox's own limit is 500 m/s).
pub const MAX_SPEED: f32 = 600.0;
/// Largest plausible speed accuracy, m/s: a receiver reporting more has no velocity
/// solution worth using (and a shifted sAcc field in a corrupted frame reads as ≥ 65 m/s).
pub const MAX_SPEED_ACC: f32 = 50.0;

/// Telemetry counters (wrapping u32). "Frames" means UBX frames and NMEA sentences.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Counters {
    /// Frames with a good checksum (any message type).
    pub frames_ok: u32,
    /// Frames whose checksum did not match.
    pub checksum_failures: u32,
    /// Frames dropped for a length beyond the bound (or a wrong fixed length).
    pub oversize: u32,
    /// Frames cut short by the start of another frame or an impossible byte.
    pub truncated: u32,
    /// Good checksum, but RMC/GGA/VTG fields invalid or the wrong number of them, or UBX
    /// NAV fields that contradict each other (`consistent()` of NAV-PVT, -VELNED, -SOL, -POSLLH).
    pub malformed: u32,
    /// Bytes that were not part of a good frame (line ends between NMEA sentences excluded).
    pub bytes_dropped: u32,
    /// Fixes emitted.
    pub fixes: u32,
    /// Epochs whose values were out of range (not emitted).
    pub fixes_rejected: u32,
    /// Epochs without a usable solution (no fix, dead reckoning, receiver flag not OK; not emitted).
    pub fixes_unusable: u32,
    /// NMEA epochs dropped because UBX delivers fixes.
    pub nmea_suppressed: u32,
    /// UBX NAV-PVT frames decoded.
    pub nav_pvt: u32,
    /// UBX NAV-VELNED frames decoded.
    pub nav_velned: u32,
    /// UBX NAV-SOL frames decoded.
    pub nav_sol: u32,
    /// UBX NAV-POSLLH frames decoded.
    pub nav_posllh: u32,
    /// NMEA RMC sentences decoded.
    pub rmc: u32,
    /// NMEA GGA sentences decoded.
    pub gga: u32,
    /// NMEA VTG sentences decoded.
    pub vtg: u32,
}

fn inc(c: &mut u32) {
    *c = c.wrapping_add(1);
}

/// A decoded NAV message whose fields pass their redundancy check (see `consistent()` of
/// each), or none, counted in `malformed`.
fn consistent_or_count<T>(m: T, consistent: fn(&T) -> bool, malformed: &mut u32) -> Option<T> {
    if consistent(&m) {
        Some(m)
    } else {
        inc(malformed);
        None
    }
}

fn add(c: &mut u32, n: u16) {
    *c = c.wrapping_add(n as u32);
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    Hunt,
    Ubx,
    Nmea,
}

/// Streaming UBX + NMEA parser. One per UART.
#[derive(Debug, Clone)]
pub struct GpsParser {
    mode: Mode,
    ubx: ubx::Framer,
    nmea: nmea::Framer,
    legacy: epoch::UbxLegacy,
    nmea_epoch: epoch::NmeaEpoch,
    last_ubx_fix_us: Option<u64>,
    /// Nothing but RMC/GGA/VTG (and line ends) since the last RMC/GGA/VTG.
    nmea_adjacent: bool,
    /// The UBX framer's replay bytes must be hunted through again.
    replay: bool,
    /// Bytes of a good frame being hunted again (`ubx::Step::Frame::replay`): already
    /// counted with it, so not counted as dropped if they start nothing.
    recounted: u16,
    counters: Counters,
}

impl Default for GpsParser {
    fn default() -> Self {
        Self::new()
    }
}

crate::internal! {
/// Whether a fix's values are physically possible (finite, in range).
pub fn plausible(f: &GpsFix) -> bool {
    let speed_ok = |v: f32| v.is_finite() && libm::fabsf(v) <= MAX_SPEED;
    f.vel_ne.iter().all(|v| speed_ok(*v))
        && f.vel_d.is_none_or(speed_ok)
        && (-900_000_000..=900_000_000).contains(&f.lat_e7)
        && (-1_800_000_000..=1_800_000_000).contains(&f.lon_e7)
        && (-1_000_000..=100_000_000).contains(&f.alt_msl_mm)
        && f.speed_acc.is_none_or(|a| a.is_finite() && (0.0..=MAX_SPEED_ACC).contains(&a))
        && f.itow_ms.is_none_or(|t| t < 604_800_000)
}
}

impl GpsParser {
    /// A parser hunting for the first frame.
    pub const fn new() -> Self {
        Self {
            mode: Mode::Hunt,
            ubx: ubx::Framer::new(),
            nmea: nmea::Framer::new(),
            legacy: epoch::UbxLegacy::new(),
            nmea_epoch: epoch::NmeaEpoch::new(),
            last_ubx_fix_us: None,
            nmea_adjacent: false,
            replay: false,
            recounted: 0,
            counters: Counters {
                frames_ok: 0,
                checksum_failures: 0,
                oversize: 0,
                truncated: 0,
                malformed: 0,
                bytes_dropped: 0,
                fixes: 0,
                fixes_rejected: 0,
                fixes_unusable: 0,
                nmea_suppressed: 0,
                nav_pvt: 0,
                nav_velned: 0,
                nav_sol: 0,
                nav_posllh: 0,
                rmc: 0,
                gga: 0,
                vtg: 0,
            },
        }
    }

    /// Counters for telemetry.
    pub fn counters(&self) -> &Counters {
        &self.counters
    }

    /// Feed one received byte with its local arrival time (µs, IMU clock).
    /// Returns a fix when this byte completed one. Never panics.
    pub fn push(&mut self, byte: u8, t_us: u64) -> Option<GpsFix> {
        let out = self.step(byte, t_us);
        if self.replay {
            return self.replay(t_us).or(out);
        }
        out
    }

    /// Rare path: bytes of a rejected UBX header, or the last ≤ 5 bytes of a
    /// frame with a bad checksum, are hunted through again. Each replay is a
    /// window of the stream ending at the current byte that starts later than the
    /// one before, so the queue never holds more than 5 bytes; 8 leaves margin.
    fn replay(&mut self, t_us: u64) -> Option<GpsFix> {
        let mut queue = [0u8; 8];
        let (mut head, mut n) = (0usize, 0usize);
        let mut out = None;
        loop {
            if self.replay {
                self.replay = false;
                let mut nq = [0u8; 8];
                let mut k = 0;
                for &x in self.ubx.replay().iter().chain(queue[head..n].iter()) {
                    if let Some(slot) = nq.get_mut(k) {
                        *slot = x;
                        k += 1;
                    }
                }
                queue = nq;
                head = 0;
                n = k;
            }
            if head >= n {
                return out;
            }
            let b = queue[head];
            head += 1;
            if let Some(f) = self.step(b, t_us) {
                out = Some(f);
            }
        }
    }

    /// Feed a slice of bytes that arrived at `t_us`; `on_fix` gets each fix.
    pub fn push_slice(&mut self, bytes: &[u8], t_us: u64, mut on_fix: impl FnMut(GpsFix)) {
        for &b in bytes {
            if let Some(f) = self.push(b, t_us) {
                on_fix(f);
            }
        }
    }

    /// One byte through the state machine; sets `self.replay` when bytes must be re-hunted.
    fn step(&mut self, b: u8, t_us: u64) -> Option<GpsFix> {
        match self.mode {
            Mode::Hunt => {
                self.start_frame(b);
                None
            }
            Mode::Ubx => match self.ubx.push(b) {
                ubx::Step::More => None,
                ubx::Step::Frame { class, id, replay, .. } => {
                    self.mode = Mode::Hunt;
                    self.replay = replay;
                    self.recounted = if replay { self.ubx.replay().len() as u16 } else { 0 };
                    self.nmea_adjacent = false;
                    inc(&mut self.counters.frames_ok);
                    self.ubx_frame(class, id, t_us)
                }
                ubx::Step::Failed { why, bytes, replay } => {
                    self.dropped(bytes);
                    self.nmea_adjacent = false;
                    match why {
                        ubx::Fail::Checksum => inc(&mut self.counters.checksum_failures),
                        ubx::Fail::Oversize => inc(&mut self.counters.oversize),
                        ubx::Fail::Truncated => {
                            // The framer already continues with the frame that cut this one.
                            inc(&mut self.counters.truncated);
                            return None;
                        }
                        ubx::Fail::NotAFrame => {}
                    }
                    self.mode = Mode::Hunt;
                    self.replay = replay;
                    None
                }
            },
            Mode::Nmea => match self.nmea.push(b) {
                nmea::Step::More => None,
                nmea::Step::Done(kind) => {
                    self.mode = Mode::Hunt;
                    inc(&mut self.counters.frames_ok);
                    self.nmea_sentence(kind, t_us)
                }
                nmea::Step::Truncated => {
                    inc(&mut self.counters.truncated);
                    self.nmea_adjacent = false;
                    add(&mut self.counters.bytes_dropped, self.nmea.len());
                    self.mode = Mode::Hunt;
                    self.start_frame(b);
                    None
                }
                fail => {
                    self.nmea_adjacent = false;
                    let c = &mut self.counters;
                    match fail {
                        nmea::Step::Checksum => inc(&mut c.checksum_failures),
                        nmea::Step::Oversize => inc(&mut c.oversize),
                        _ => inc(&mut c.malformed),
                    }
                    add(&mut c.bytes_dropped, self.nmea.len());
                    self.mode = Mode::Hunt;
                    None
                }
            },
        }
    }

    /// A byte outside any frame: start one or drop it.
    fn start_frame(&mut self, b: u8) {
        match b {
            ubx::SYNC1 => {
                self.ubx.start();
                self.mode = Mode::Ubx;
            }
            b'$' => {
                self.nmea.start();
                self.mode = Mode::Nmea;
            }
            b'\r' | b'\n' => {}
            _ => {
                self.dropped(1);
                self.nmea_adjacent = false;
            }
        }
    }

    /// Counts `n` dropped bytes, less those of a good frame hunted again.
    fn dropped(&mut self, n: u16) {
        let again = n.min(self.recounted);
        self.recounted -= again;
        add(&mut self.counters.bytes_dropped, n - again);
    }

    fn ubx_frame(&mut self, class: u8, id: u8, t_us: u64) -> Option<GpsFix> {
        if class != ubx::CLASS_NAV {
            return None;
        }
        let p = self.ubx.payload();
        let c = &mut self.counters;
        let fix = match id {
            ubx::ID_PVT => {
                let m = consistent_or_count(
                    ubx::decode_pvt(p)?,
                    ubx::NavPvt::consistent,
                    &mut c.malformed,
                )?;
                inc(&mut c.nav_pvt);
                self.legacy.delivered(m.itow_ms);
                Some(epoch::from_pvt(&m, t_us))
            }
            ubx::ID_VELNED => {
                let m = consistent_or_count(
                    ubx::decode_velned(p)?,
                    ubx::NavVelned::consistent,
                    &mut c.malformed,
                )?;
                inc(&mut c.nav_velned);
                self.legacy.velned(m, t_us).unwrap_or_else(|_| {
                    inc(&mut c.malformed);
                    None
                })
            }
            ubx::ID_SOL => {
                let m = consistent_or_count(
                    ubx::decode_sol(p)?,
                    ubx::NavSol::consistent,
                    &mut c.malformed,
                )?;
                inc(&mut c.nav_sol);
                self.legacy.sol(m, t_us).unwrap_or_else(|_| {
                    inc(&mut c.malformed);
                    None
                })
            }
            ubx::ID_POSLLH => {
                let m = consistent_or_count(
                    ubx::decode_posllh(p)?,
                    ubx::NavPosllh::consistent,
                    &mut c.malformed,
                )?;
                inc(&mut c.nav_posllh);
                self.legacy.posllh(m);
                None
            }
            _ => None,
        }?;
        let out = self.vet(fix);
        if out.is_some() {
            self.last_ubx_fix_us = Some(t_us);
        }
        out
    }

    fn nmea_sentence(&mut self, kind: nmea::Kind, t_us: u64) -> Option<GpsFix> {
        let c = &mut self.counters;
        match kind {
            nmea::Kind::Rmc => inc(&mut c.rmc),
            nmea::Kind::Gga => inc(&mut c.gga),
            nmea::Kind::Vtg => inc(&mut c.vtg),
            nmea::Kind::Other => {
                self.nmea_adjacent = false;
                return None;
            }
        }
        let adjacent = core::mem::replace(&mut self.nmea_adjacent, true);
        let fix = self.nmea_epoch.add(self.nmea.sentence(), t_us, adjacent)?;
        if self.last_ubx_fix_us.is_some_and(|u| t_us.saturating_sub(u) < NMEA_SUPPRESS_US) {
            inc(&mut self.counters.nmea_suppressed);
            return None;
        }
        self.vet(fix)
    }

    /// Final gate: only plausible, usable fixes leave the parser.
    fn vet(&mut self, fix: GpsFix) -> Option<GpsFix> {
        if !plausible(&fix) {
            inc(&mut self.counters.fixes_rejected);
            return None;
        }
        if !fix.usable() {
            inc(&mut self.counters.fixes_unusable);
            return None;
        }
        inc(&mut self.counters.fixes);
        Some(fix)
    }
}

/// Feed `bytes` through a fresh parser and return how many fixes came out. A
/// self-contained loop for instruction-count benchmarks (QEMU, valgrind):
/// instructions per byte = instructions of this call / `bytes.len()`.
#[cfg(feature = "internals")]
#[doc(hidden)]
#[inline(never)]
pub fn count_fixes(bytes: &[u8]) -> u32 {
    let mut p = GpsParser::new();
    let mut n = 0u32;
    for (i, &b) in bytes.iter().enumerate() {
        if p.push(b, i as u64).is_some() {
            n = n.wrapping_add(1);
        }
    }
    n
}
