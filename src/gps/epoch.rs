//! Turning decoded messages into one [`GpsFix`] per receiver epoch.
//!
//! - UBX NAV-PVT is a complete epoch by itself.
//! - UBX NAV-VELNED + NAV-SOL (+ NAV-POSLLH) are joined by equal `iTOW`; the fix is
//!   emitted as soon as VELNED and SOL of one `iTOW` are both in (u-blox sends NAV
//!   messages in id order, so POSLLH (0x02) has arrived by then). An epoch already
//!   emitted (e.g. from NAV-PVT) is not emitted again.
//! - NMEA RMC and GGA are joined by equal UTC time. VTG carries no time: it joins
//!   the open epoch if it directly follows that epoch's RMC (u-blox order RMC,
//!   VTG, GGA); otherwise it waits for the RMC/GGA directly after it (AeroRust
//!   order VTG, RMC, GGA — a VTG right after a GGA is taken to open the next epoch). "Directly" means no other
//!   frame, failed frame or dropped byte in between, so a lost sentence cannot
//!   make a VTG join the wrong epoch; and an epoch with an RMC takes its velocity
//!   from the RMC only, VTG is the fallback. The fix is emitted when RMC and GGA of
//!   one time are both in; an epoch that never completes (a receiver sending RMC
//!   only, or a lost GGA) is emitted when a sentence of a newer time arrives,
//!   stamped with the arrival time of its own last sentence. Without GGA the fix
//!   is 2-D with no satellite count or altitude (0).
//! - A UBX VELNED + SOL epoch whose POSLLH was lost reports position 0 / 0 / 0
//!   (position is for logging only; "all zero" reads as unknown).
//! - NMEA has no vertical velocity: fixes from NMEA have `vel_d = None`. Differencing
//!   0.1 m GGA altitudes at 10 Hz would give a vD with ≈ 1 m/s quantisation noise —
//!   worse than the estimator's own "no vertical acceleration, γ = 0" fallback that
//!   `vel_d = None` selects.
//! - NMEA `itow_ms` is the UTC time of day in ms (it wraps at midnight).

use super::nmea::{Kind, Sentence};
use super::ubx::{NavPosllh, NavPvt, NavSol, NavVelned};
use crate::fix::{FixType, GpsFix};

/// Speed below which a missing NMEA course is accepted as "standing still"
/// (receivers blank the course when they cannot resolve it), m/s.
pub const STILL_SPEED: f32 = 0.5;

const KNOT: f32 = 1852.0 / 3600.0;

/// Sine and cosine of an angle in millidegrees (an NMEA course): exact integer
/// reduction to [0°, 45°] and Taylor polynomials there (error < 3e-8).
/// Hand-written because libm's `sinf`/`cosf` reduce the argument in f64, which the
/// Cortex-M4F emulates in software (≈ 4 KiB of flash and slow in the UART ISR).
pub fn sin_cos_mdeg(mdeg: u32) -> (f32, f32) {
    let c = mdeg % 360_000;
    let (q, r) = (c / 90_000, c % 90_000);
    let (swap, r) = if r > 45_000 { (true, 90_000 - r) } else { (false, r) };
    let x = r as f32 * (core::f32::consts::PI / 180_000.0);
    let x2 = x * x;
    let s = x * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0 * (1.0 - x2 / 72.0))));
    let co = 1.0 - x2 / 2.0 * (1.0 - x2 / 12.0 * (1.0 - x2 / 30.0 * (1.0 - x2 / 56.0)));
    let (s, co) = if swap { (co, s) } else { (s, co) };
    match q {
        0 => (s, co),
        1 => (co, -s),
        2 => (-s, -co),
        _ => (-co, s),
    }
}

/// u-blox fixType / gpsFix → [`FixType`].
pub fn ubx_fix_type(t: u8) -> FixType {
    match t {
        1 => FixType::DeadReckoning,
        2 => FixType::Fix2D,
        3 => FixType::Fix3D,
        4 => FixType::GnssDeadReckoning,
        _ => FixType::NoFix, // 0 none, 5 time only
    }
}

/// A complete fix from NAV-PVT.
pub fn from_pvt(p: &NavPvt, t_us: u64) -> GpsFix {
    GpsFix {
        t_us,
        itow_ms: Some(p.itow_ms),
        fix_type: ubx_fix_type(p.fix_type),
        fix_ok: p.flags & 0x01 != 0 && p.flags3 & 0x01 == 0,
        vel_ne: [p.vel_mm_s[0] as f32 * 1e-3, p.vel_mm_s[1] as f32 * 1e-3],
        vel_d: Some(p.vel_mm_s[2] as f32 * 1e-3),
        speed_acc: Some(p.s_acc_mm_s as f32 * 1e-3),
        num_sats: p.num_sv,
        lat_e7: p.lat_e7,
        lon_e7: p.lon_e7,
        alt_msl_mm: p.h_msl_mm,
    }
}

/// Joins NAV-VELNED, NAV-SOL and NAV-POSLLH of one `iTOW`.
#[derive(Debug, Clone)]
pub struct UbxLegacy {
    itow: Option<u32>,
    velned: Option<NavVelned>,
    sol: Option<NavSol>,
    pos: Option<NavPosllh>,
    emitted: bool,
}

/// A legacy epoch whose NAV-SOL and NAV-VELNED disagree (dropped, no fix).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Inconsistent;

impl Default for UbxLegacy {
    fn default() -> Self {
        Self::new()
    }
}

impl UbxLegacy {
    /// Nothing collected.
    pub const fn new() -> Self {
        Self { itow: None, velned: None, sol: None, pos: None, emitted: false }
    }

    fn epoch(&mut self, itow: u32) {
        if self.itow != Some(itow) {
            *self = Self { itow: Some(itow), ..Self::new() };
        }
    }

    /// Mark the epoch `itow` as delivered by another message (NAV-PVT).
    pub fn delivered(&mut self, itow: u32) {
        self.epoch(itow);
        self.emitted = true;
    }

    /// Add NAV-VELNED; returns the fix when the epoch became complete, or
    /// [`Inconsistent`] when it completed with a NAV-SOL it contradicts.
    pub fn velned(&mut self, m: NavVelned, t_us: u64) -> Result<Option<GpsFix>, Inconsistent> {
        self.epoch(m.itow_ms);
        self.velned = Some(m);
        self.complete(t_us)
    }

    /// Add NAV-SOL; as [`UbxLegacy::velned`].
    pub fn sol(&mut self, m: NavSol, t_us: u64) -> Result<Option<GpsFix>, Inconsistent> {
        self.epoch(m.itow_ms);
        self.sol = Some(m);
        self.complete(t_us)
    }

    /// Add NAV-POSLLH (position for logging; never completes an epoch by itself).
    pub fn posllh(&mut self, m: NavPosllh) {
        self.epoch(m.itow_ms);
        self.pos = Some(m);
    }

    fn complete(&mut self, t_us: u64) -> Result<Option<GpsFix>, Inconsistent> {
        let (Some(v), Some(s)) = (self.velned, self.sol) else { return Ok(None) };
        if self.emitted {
            return Ok(None);
        }
        self.emitted = true;
        // Both carry the receiver's speed accuracy (equal in the u-blox captures): a
        // checksum-colliding byte insertion (2⁻¹⁶) shifting either one's fields shows here.
        if s.s_acc_cm_s.abs_diff(v.s_acc_cm_s) > 1 {
            return Err(Inconsistent);
        }
        let p = self.pos.unwrap_or_default();
        Ok(Some(GpsFix {
            t_us,
            itow_ms: Some(v.itow_ms),
            fix_type: ubx_fix_type(s.gps_fix),
            fix_ok: s.flags & 0x01 != 0,
            vel_ne: [v.vel_cm_s[0] as f32 * 1e-2, v.vel_cm_s[1] as f32 * 1e-2],
            vel_d: Some(v.vel_cm_s[2] as f32 * 1e-2),
            speed_acc: Some(v.s_acc_cm_s as f32 * 1e-2),
            num_sats: s.num_sv,
            lat_e7: p.lat_e7,
            lon_e7: p.lon_e7,
            alt_msl_mm: p.h_msl_mm,
        }))
    }
}

/// What an NMEA epoch has collected.
#[derive(Debug, Clone, Copy)]
struct Collected {
    time_ms: Option<u32>,
    rmc: Option<Sentence>,
    gga: Option<Sentence>,
    vtg: Option<Sentence>,
    emitted: bool,
    t_us: u64,
}

impl Collected {
    const EMPTY: Self =
        Self { time_ms: None, rmc: None, gga: None, vtg: None, emitted: false, t_us: 0 };
}

/// Joins RMC, GGA and VTG of one UTC epoch.
#[derive(Debug, Clone)]
pub struct NmeaEpoch {
    cur: Collected,
    pending_vtg: Option<(Sentence, u64)>,
    last: Kind,
}

/// An NMEA epoch's outcome: a fix (possibly not usable) or nothing yet.
pub type NmeaOut = Option<GpsFix>;

impl Default for NmeaEpoch {
    fn default() -> Self {
        Self::new()
    }
}

impl NmeaEpoch {
    /// Nothing collected.
    pub const fn new() -> Self {
        Self { cur: Collected::EMPTY, pending_vtg: None, last: Kind::Other }
    }

    /// Add one decoded RMC/GGA/VTG sentence that ended at local time `t_us`.
    /// `adjacent`: nothing (no other frame, no failed frame, no dropped byte) came
    /// between the previous RMC/GGA/VTG and this one. May return the fix of an
    /// epoch that just completed, or of the previous epoch flushed by a newer time.
    pub fn add(&mut self, s: &Sentence, t_us: u64, adjacent: bool) -> NmeaOut {
        match s.kind {
            Kind::Vtg => {
                // Only "RMC, VTG" is unambiguous: a VTG right after a GGA may open
                // the next epoch (order VTG, RMC, GGA), so it waits for the next one.
                let after_rmc = adjacent && self.last == Kind::Rmc;
                self.last = Kind::Vtg;
                let joins = after_rmc && !self.cur.emitted && self.cur.vtg.is_none();
                if joins {
                    self.cur.vtg = Some(*s);
                    self.cur.t_us = t_us;
                    self.pending_vtg = None;
                } else {
                    self.pending_vtg = Some((*s, t_us));
                }
                None
            }
            Kind::Rmc | Kind::Gga => {
                // A VTG waiting for its epoch belongs to this sentence only if
                // nothing came between them.
                let vtg = self.pending_vtg.take().filter(|_| adjacent).map(|(v, _)| v);
                self.last = s.kind;
                let time = s.time_ms?;
                let mut flushed = None;
                if self.cur.time_ms != Some(time) {
                    if !self.cur.emitted {
                        flushed = build(&self.cur);
                    }
                    self.cur = Collected { time_ms: Some(time), ..Collected::EMPTY };
                }
                if self.cur.vtg.is_none() {
                    self.cur.vtg = vtg;
                }
                if s.kind == Kind::Rmc {
                    self.cur.rmc = Some(*s);
                } else {
                    self.cur.gga = Some(*s);
                }
                self.cur.t_us = t_us;
                if flushed.is_some() {
                    return flushed;
                }
                if self.cur.rmc.is_some() && self.cur.gga.is_some() && !self.cur.emitted {
                    self.cur.emitted = true;
                    return build(&self.cur);
                }
                None
            }
            Kind::Other => None,
        }
    }
}

/// Build the fix of a collected epoch; `None` when it has no velocity at all.
fn build(c: &Collected) -> Option<GpsFix> {
    let time = c.time_ms?;
    if c.rmc.is_none() && c.vtg.is_none() {
        return None;
    }
    let rmc = c.rmc.unwrap_or(Sentence::EMPTY);
    let vtg = c.vtg.unwrap_or(Sentence::EMPTY);
    let gga = c.gga.unwrap_or(Sentence::EMPTY);
    // Velocity from RMC when the epoch has one, else from VTG (knots, else km/h):
    // never mixed, so a VTG joined to the wrong epoch cannot alter an RMC epoch.
    let (speed, course) = if c.rmc.is_some() {
        (rmc.sog_mkn.map(|k| k as f32 * 1e-3 * KNOT), rmc.cog_mdeg)
    } else {
        let kn = vtg.sog_mkn.map(|k| k as f32 * 1e-3 * KNOT);
        (kn.or(vtg.sog_mkmh.map(|k| k as f32 * 1e-3 / 3.6)), vtg.cog_mdeg)
    };
    let mut vel_ok = true;
    let vel = match (speed, course) {
        (Some(s), Some(c)) => {
            let (sin, cos) = sin_cos_mdeg(c);
            [s * cos, s * sin]
        }
        (Some(s), None) if s < STILL_SPEED => [0.0; 2],
        _ => {
            vel_ok = false;
            [0.0; 2]
        }
    };
    let mode = if rmc.mode != 0 { rmc.mode } else { vtg.mode };
    let rmc_ok = c.rmc.is_none_or(|r| r.status == b'A');
    let gga_ok = c.gga.is_none_or(|g| !matches!(g.quality, Some(0) | Some(6) | None));
    let mode_ok = !matches!(mode, b'N' | b'E');
    let fix_type = if !vel_ok || !rmc_ok || !gga_ok || mode == b'N' {
        FixType::NoFix
    } else if mode == b'E' || gga.quality == Some(6) {
        FixType::DeadReckoning
    } else if gga.alt_mm.is_some() {
        FixType::Fix3D
    } else {
        FixType::Fix2D
    };
    Some(GpsFix {
        t_us: c.t_us,
        itow_ms: Some(time),
        fix_type,
        fix_ok: vel_ok && rmc_ok && gga_ok && mode_ok,
        vel_ne: vel,
        vel_d: None,
        speed_acc: None,
        num_sats: gga.sats.unwrap_or(0),
        lat_e7: rmc.lat_e7.or(gga.lat_e7).unwrap_or(0),
        lon_e7: rmc.lon_e7.or(gga.lon_e7).unwrap_or(0),
        alt_msl_mm: gga.alt_mm.unwrap_or(0),
    })
}
