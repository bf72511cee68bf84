//! Encoders: a [`GpsFix`] to UBX NAV messages and NMEA RMC/GGA/VTG sentences,
//! written into a caller-provided buffer (no_std, no alloc). Used by the tests and
//! by the hardware-in-the-loop simulator, which plays the receiver's part.
//!
//! Every function returns the number of bytes written, or `None` when `out` is
//! too small (nothing meaningful is left in `out` then).
//!
//! Behind the `encode` feature: the core on a flight controller never sends a fix.

use super::ubx::{self, CLASS_NAV};
use crate::fix::{FixType, GpsFix};

/// Bytes of a whole NAV-PVT frame.
pub const NAV_PVT_FRAME: usize = ubx::LEN_PVT as usize + 8;
/// Longest NMEA sentence these encoders write (with CR LF).
pub const NMEA_MAX: usize = 96;

pub use super::ubx::frame as ubx_frame;

fn fix_type_code(t: FixType) -> u8 {
    match t {
        FixType::NoFix => 0,
        FixType::DeadReckoning => 1,
        FixType::Fix2D => 2,
        FixType::Fix3D => 3,
        FixType::GnssDeadReckoning => 4,
    }
}

fn round_i32(x: f32) -> i32 {
    let r = libm::roundf(x);
    if r.is_finite() {
        r.clamp(i32::MIN as f32, i32::MAX as f32) as i32
    } else {
        0
    }
}

fn put(p: &mut [u8], o: usize, v: &[u8]) {
    p[o..o + v.len()].copy_from_slice(v);
}

/// Course over ground, degrees in [0, 360).
fn course_deg(f: &GpsFix) -> f32 {
    let c = libm::atan2f(f.vel_ne[1], f.vel_ne[0]).to_degrees();
    if c < 0.0 {
        c + 360.0
    } else {
        c
    }
}

/// NAV-PVT (92-byte payload) of `fix`: iTOW, fix type, gnssFixOK, numSV, position,
/// NED velocity (mm/s; vD 0 when the fix has none), ground speed, heading of motion,
/// sAcc. Date/time fields are zero and flagged invalid.
pub fn nav_pvt(fix: &GpsFix, out: &mut [u8]) -> Option<usize> {
    let mut p = [0u8; ubx::LEN_PVT as usize];
    let v = fix.vel_ned_or_level().map(|c| round_i32(c * 1000.0));
    put(&mut p, 0, &fix.itow_ms.unwrap_or(0).to_le_bytes());
    p[20] = fix_type_code(fix.fix_type);
    p[21] = fix.fix_ok as u8;
    p[23] = fix.num_sats;
    put(&mut p, 24, &fix.lon_e7.to_le_bytes());
    put(&mut p, 28, &fix.lat_e7.to_le_bytes());
    put(&mut p, 32, &fix.alt_msl_mm.to_le_bytes()); // height above ellipsoid: geoid 0
    put(&mut p, 36, &fix.alt_msl_mm.to_le_bytes());
    put(&mut p, 40, &1500u32.to_le_bytes()); // hAcc mm
    put(&mut p, 44, &2500u32.to_le_bytes()); // vAcc mm
    put(&mut p, 48, &v[0].to_le_bytes());
    put(&mut p, 52, &v[1].to_le_bytes());
    put(&mut p, 56, &v[2].to_le_bytes());
    put(&mut p, 60, &round_i32(fix.ground_speed() * 1000.0).to_le_bytes());
    put(&mut p, 64, &round_i32(course_deg(fix) * 1e5).to_le_bytes());
    let sacc = round_i32(fix.speed_acc.unwrap_or(0.5) * 1000.0).max(0) as u32;
    put(&mut p, 68, &sacc.to_le_bytes());
    put(&mut p, 72, &500_000u32.to_le_bytes()); // headAcc 5 deg
    put(&mut p, 76, &150u16.to_le_bytes()); // pDOP 1.5
    ubx_frame(CLASS_NAV, ubx::ID_PVT, &p, out)
}

/// NAV-VELNED (cm/s; vD 0 when the fix has none) of `fix`.
pub fn nav_velned(fix: &GpsFix, out: &mut [u8]) -> Option<usize> {
    let mut p = [0u8; ubx::LEN_VELNED as usize];
    let v_ned = fix.vel_ned_or_level();
    let v = v_ned.map(|c| round_i32(c * 100.0));
    put(&mut p, 0, &fix.itow_ms.unwrap_or(0).to_le_bytes());
    put(&mut p, 4, &v[0].to_le_bytes());
    put(&mut p, 8, &v[1].to_le_bytes());
    put(&mut p, 12, &v[2].to_le_bytes());
    let (g, d) = (fix.ground_speed(), v_ned[2]);
    let speed = libm::sqrtf(g * g + d * d);
    put(&mut p, 16, &(round_i32(speed * 100.0) as u32).to_le_bytes());
    put(&mut p, 20, &(round_i32(fix.ground_speed() * 100.0) as u32).to_le_bytes());
    put(&mut p, 24, &round_i32(course_deg(fix) * 1e5).to_le_bytes());
    put(&mut p, 28, &speed_acc_cm_s(fix).to_le_bytes());
    put(&mut p, 32, &500_000u32.to_le_bytes());
    ubx_frame(CLASS_NAV, ubx::ID_VELNED, &p, out)
}

/// NAV-SOL of `fix` (fix status, satellites and the speed accuracy of [`nav_velned`];
/// ECEF fields zero).
pub fn nav_sol(fix: &GpsFix, out: &mut [u8]) -> Option<usize> {
    let mut p = [0u8; ubx::LEN_SOL as usize];
    put(&mut p, 0, &fix.itow_ms.unwrap_or(0).to_le_bytes());
    put(&mut p, 40, &speed_acc_cm_s(fix).to_le_bytes());
    p[10] = fix_type_code(fix.fix_type);
    p[11] = fix.fix_ok as u8 | 0x0C; // gpsFixOK, WKNSET, TOWSET
    p[47] = fix.num_sats;
    ubx_frame(CLASS_NAV, ubx::ID_SOL, &p, out)
}

/// The speed accuracy NAV-VELNED and NAV-SOL carry, cm/s (0.5 m/s when the fix has none).
fn speed_acc_cm_s(fix: &GpsFix) -> u32 {
    round_i32(fix.speed_acc.unwrap_or(0.5) * 100.0).max(0) as u32
}

/// Geoid separation written into NAV-POSLLH's ellipsoidal height, mm.
const GEOID_SEPARATION_MM: i32 = 48_000;

/// NAV-POSLLH of `fix`.
pub fn nav_posllh(fix: &GpsFix, out: &mut [u8]) -> Option<usize> {
    let mut p = [0u8; ubx::LEN_POSLLH as usize];
    put(&mut p, 0, &fix.itow_ms.unwrap_or(0).to_le_bytes());
    put(&mut p, 4, &fix.lon_e7.to_le_bytes());
    put(&mut p, 8, &fix.lat_e7.to_le_bytes());
    // Height above the ellipsoid: MSL plus a fixed 48 m geoid separation (Zurich, where the
    // simulated flights start; a real receiver's differs, the decoder allows ±150 m).
    put(&mut p, 12, &fix.alt_msl_mm.saturating_add(GEOID_SEPARATION_MM).to_le_bytes());
    put(&mut p, 16, &fix.alt_msl_mm.to_le_bytes());
    ubx_frame(CLASS_NAV, ubx::ID_POSLLH, &p, out)
}

/// Writes ASCII into a slice, tracking overflow.
struct Text<'a> {
    out: &'a mut [u8],
    n: usize,
    ok: bool,
}

impl Text<'_> {
    fn byte(&mut self, b: u8) {
        match self.out.get_mut(self.n) {
            Some(s) => {
                *s = b;
                self.n += 1;
            }
            None => self.ok = false,
        }
    }
    fn str(&mut self, s: &[u8]) {
        for &b in s {
            self.byte(b);
        }
    }
    /// Unsigned integer, at least `width` digits.
    fn uint(&mut self, mut v: u64, width: usize) {
        let mut d = [0u8; 20];
        let mut k = 0;
        while v > 0 || k < width.max(1) {
            d[k] = b'0' + (v % 10) as u8;
            v /= 10;
            k += 1;
            if k == d.len() {
                break;
            }
        }
        for i in (0..k).rev() {
            self.byte(d[i]);
        }
    }
    /// `value / 10^dec` with exactly `dec` decimals (value already scaled), `int_w` integer digits minimum.
    fn fixed(&mut self, value: i64, dec: u32, int_w: usize) {
        if value < 0 {
            self.byte(b'-');
        }
        let v = value.unsigned_abs();
        let s = 10u64.pow(dec);
        self.uint(v / s, int_w);
        if dec > 0 {
            self.byte(b'.');
            self.uint(v % s, dec as usize);
        }
    }
}

fn scaled(x: f32, scale: f32) -> i64 {
    let r = libm::roundf(x * scale);
    if r.is_finite() {
        r as i64
    } else {
        0
    }
}

/// `$` + body + `*hh\r\n` around what `body` writes.
fn sentence(out: &mut [u8], body: impl FnOnce(&mut Text)) -> Option<usize> {
    let mut t = Text { out, n: 0, ok: true };
    t.byte(b'$');
    body(&mut t);
    if !t.ok {
        return None;
    }
    let ck = t.out[1..t.n].iter().fold(0u8, |a, &b| a ^ b);
    const HEX: &[u8; 16] = b"0123456789ABCDEF";
    t.byte(b'*');
    t.byte(HEX[(ck >> 4) as usize]);
    t.byte(HEX[(ck & 15) as usize]);
    t.str(b"\r\n");
    t.ok.then_some(t.n)
}

/// UTC time of day `hhmmss.ss` from `itow_ms` (taken modulo one day: the
/// simulator passes UTC ms of day, as the parser reports for NMEA).
fn time(t: &mut Text, fix: &GpsFix) {
    let ms = fix.itow_ms.unwrap_or(0) % 86_400_000;
    t.uint((ms / 3_600_000) as u64, 2);
    t.uint((ms / 60_000 % 60) as u64, 2);
    t.uint((ms / 1000 % 60) as u64, 2);
    t.byte(b'.');
    t.uint((ms % 1000 / 10) as u64, 2);
}

/// `ddmm.mmmmmm,N` (6 decimals of minutes: exact for 1e-7 deg).
fn angle(t: &mut Text, e7: i32, deg_w: usize, pos: u8, neg: u8) {
    let a = e7.unsigned_abs() as u64;
    t.uint(a / 10_000_000, deg_w);
    let min_e6 = (a % 10_000_000) * 6; // minutes × 1e6
    t.uint(min_e6 / 1_000_000, 2);
    t.byte(b'.');
    t.uint(min_e6 % 1_000_000, 6);
    t.byte(b',');
    t.byte(if e7 < 0 { neg } else { pos });
}

fn valid(fix: &GpsFix) -> bool {
    fix.usable()
}

/// `$GPRMC`: time, status, position, speed (knots, 3 decimals), course (deg, 2
/// decimals), date `ddmmyy`, mode `A`/`N`.
pub fn nmea_rmc(fix: &GpsFix, date_ddmmyy: u32, out: &mut [u8]) -> Option<usize> {
    sentence(out, |t| {
        t.str(b"GPRMC,");
        time(t, fix);
        t.str(if valid(fix) { b",A," } else { b",V," });
        angle(t, fix.lat_e7, 2, b'N', b'S');
        t.byte(b',');
        angle(t, fix.lon_e7, 3, b'E', b'W');
        t.byte(b',');
        t.fixed(scaled(fix.ground_speed(), 3600.0 / 1852.0 * 1000.0), 3, 1);
        t.byte(b',');
        t.fixed(scaled(course_deg(fix), 100.0) % 36_000, 2, 1);
        t.byte(b',');
        t.uint(date_ddmmyy as u64 % 1_000_000, 6);
        t.str(b",,,");
        t.byte(if valid(fix) { b'A' } else { b'N' });
    })
}

/// `$GPGGA`: time, position, quality (1 fix, 6 dead reckoning, 0 none), satellites,
/// HDOP 1.0, altitude MSL (m, 2 decimals), geoid separation 0.
pub fn nmea_gga(fix: &GpsFix, out: &mut [u8]) -> Option<usize> {
    sentence(out, |t| {
        t.str(b"GPGGA,");
        time(t, fix);
        t.byte(b',');
        angle(t, fix.lat_e7, 2, b'N', b'S');
        t.byte(b',');
        angle(t, fix.lon_e7, 3, b'E', b'W');
        t.byte(b',');
        let q = match fix.fix_type {
            _ if !fix.fix_ok => 0,
            FixType::NoFix => 0,
            FixType::DeadReckoning => 6,
            _ => 1,
        };
        t.uint(q, 1);
        t.byte(b',');
        t.uint(fix.num_sats as u64, 2);
        t.str(b",1.0,");
        t.fixed((fix.alt_msl_mm as i64 + if fix.alt_msl_mm < 0 { -5 } else { 5 }) / 10, 2, 1);
        t.str(b",M,0.0,M,,");
    })
}

/// `$GPVTG`: course true (deg), speed knots and km/h, mode.
pub fn nmea_vtg(fix: &GpsFix, out: &mut [u8]) -> Option<usize> {
    sentence(out, |t| {
        t.str(b"GPVTG,");
        t.fixed(scaled(course_deg(fix), 100.0) % 36_000, 2, 1);
        t.str(b",T,,M,");
        t.fixed(scaled(fix.ground_speed(), 3600.0 / 1852.0 * 1000.0), 3, 1);
        t.str(b",N,");
        t.fixed(scaled(fix.ground_speed(), 3600.0), 3, 1);
        t.str(b",K,");
        t.byte(if valid(fix) { b'A' } else { b'N' });
    })
}
