//! Shared by the GPS tests: a simulated flight's fixes and stream builders.
#![allow(dead_code)]

use wing_ahrs::gps::encode;
use wing_ahrs::{FixType, GpsFix};

/// 10 Hz fixes of a turning, climbing fixed-wing flight: 22–30 m/s, turns up to
/// ±25 °/s through all headings (both hemispheres of lat/lon), climbs and descents
/// of ±4 m/s. `itow_ms` starts at `t0_ms` (use a time of day for NMEA).
pub fn flight(n: usize, t0_ms: u32, lat0_e7: i32, lon0_e7: i32) -> Vec<GpsFix> {
    let (mut chi, mut n_m, mut e_m, mut h) = (0.3f64, 0.0f64, 0.0f64, 120.0f64);
    (0..n)
        .map(|k| {
            let t = k as f64 * 0.1;
            let v = 26.0 + 4.0 * (t * 0.21).sin();
            let turn = 25f64.to_radians() * (t * 0.13).sin();
            let vd = -4.0 * (t * 0.17).cos();
            chi += turn * 0.1;
            let (vn, ve) = (v * chi.cos(), v * chi.sin());
            n_m += vn * 0.1;
            e_m += ve * 0.1;
            h -= vd * 0.1;
            let lat = lat0_e7 as f64 + n_m / 111_320.0 * 1e7;
            let lon = lon0_e7 as f64
                + e_m / (111_320.0 * (lat0_e7 as f64 * 1e-7).to_radians().cos()) * 1e7;
            GpsFix {
                t_us: 0,
                itow_ms: Some(t0_ms + 100 * k as u32),
                fix_type: FixType::Fix3D,
                fix_ok: true,
                vel_ne: [vn as f32, ve as f32],
                vel_d: Some(vd as f32),
                speed_acc: Some(0.3 + 0.1 * (k % 5) as f32),
                num_sats: 8 + (k % 9) as u8,
                lat_e7: lat.round() as i32,
                lon_e7: lon.round() as i32,
                alt_msl_mm: (h * 1000.0).round() as i32,
            }
        })
        .collect()
}

/// One NAV-PVT frame.
pub fn pvt(f: &GpsFix) -> Vec<u8> {
    let mut b = [0u8; 128];
    let n = encode::nav_pvt(f, &mut b).unwrap();
    b[..n].to_vec()
}

/// POSLLH, SOL, VELNED frames (u-blox id order).
pub fn legacy(f: &GpsFix) -> Vec<u8> {
    let mut out = Vec::new();
    let mut b = [0u8; 128];
    let n = encode::nav_posllh(f, &mut b).unwrap();
    out.extend_from_slice(&b[..n]);
    let n = encode::nav_sol(f, &mut b).unwrap();
    out.extend_from_slice(&b[..n]);
    let n = encode::nav_velned(f, &mut b).unwrap();
    out.extend_from_slice(&b[..n]);
    out
}

/// RMC, VTG, GGA sentences (u-blox order), or VTG first (`vtg_first`, AeroRust order).
pub fn nmea(f: &GpsFix, vtg_first: bool) -> Vec<Vec<u8>> {
    let mut b = [0u8; encode::NMEA_MAX];
    let s = |r: Option<usize>, b: &[u8]| b[..r.unwrap()].to_vec();
    let rmc = {
        let r = encode::nmea_rmc(f, 170423, &mut b);
        s(r, &b)
    };
    let vtg = {
        let r = encode::nmea_vtg(f, &mut b);
        s(r, &b)
    };
    let gga = {
        let r = encode::nmea_gga(f, &mut b);
        s(r, &b)
    };
    if vtg_first {
        vec![vtg, rmc, gga]
    } else {
        vec![rmc, vtg, gga]
    }
}
