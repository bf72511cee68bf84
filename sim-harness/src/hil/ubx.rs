//! GpsFix → UBX NAV-PVT bytes for the HIL GPS UART.
//! INTERIM: replaced by the core's `wing_ahrs::gps::encode` once branch `gps` is merged.

use wing_ahrs::{FixType, GpsFix};

/// UBX Fletcher-8 checksum over class..payload.
pub fn checksum(bytes: &[u8]) -> (u8, u8) {
    let (mut a, mut b) = (0u8, 0u8);
    for &x in bytes {
        a = a.wrapping_add(x);
        b = b.wrapping_add(a);
    }
    (a, b)
}

/// A NAV-PVT frame (92-byte payload) for `fix`: velocities rounded to mm/s.
pub fn nav_pvt(fix: &GpsFix) -> Vec<u8> {
    let mut p = [0u8; 92];
    let put = |p: &mut [u8; 92], o: usize, v: &[u8]| p[o..o + v.len()].copy_from_slice(v);
    put(&mut p, 0, &fix.itow_ms.unwrap_or(0).to_le_bytes());
    put(&mut p, 4, &2026u16.to_le_bytes());
    p[11] = 0x07; // validDate | validTime | fullyResolved
    p[20] = match fix.fix_type {
        FixType::NoFix => 0,
        FixType::DeadReckoning => 1,
        FixType::Fix2D => 2,
        FixType::Fix3D => 3,
        FixType::GnssDeadReckoning => 4,
    };
    p[21] = fix.fix_ok as u8;
    p[23] = fix.num_sats;
    put(&mut p, 24, &fix.lon_e7.to_le_bytes());
    put(&mut p, 28, &fix.lat_e7.to_le_bytes());
    put(&mut p, 32, &fix.alt_msl_mm.to_le_bytes());
    put(&mut p, 36, &fix.alt_msl_mm.to_le_bytes());
    let mm = |v: f32| (v as f64 * 1000.0).round() as i32;
    for i in 0..3 {
        put(&mut p, 48 + 4 * i, &mm(fix.vel_ned[i]).to_le_bytes());
    }
    let gs = fix.ground_speed() as f64;
    put(&mut p, 60, &((gs * 1000.0).round() as i32).to_le_bytes());
    put(&mut p, 68, &((fix.speed_acc.unwrap_or(0.05) as f64 * 1000.0).round() as u32).to_le_bytes());
    let mut f = vec![0xB5, 0x62, 0x01, 0x07, 92, 0];
    f.extend_from_slice(&p);
    let (a, b) = checksum(&f[2..]);
    f.push(a);
    f.push(b);
    f
}

/// What a NAV-PVT parser makes of [`nav_pvt`]`(fix)`: the same conversions as the
/// firmware's decoder (i32 mm/s as f32 × 1e-3), stamped with `t_us`.
pub fn decoded(fix: &GpsFix, t_us: u64) -> GpsFix {
    let mm = |v: f32| (v as f64 * 1000.0).round() as i32;
    GpsFix {
        t_us,
        vel_ned: [mm(fix.vel_ned[0]) as f32 * 1e-3, mm(fix.vel_ned[1]) as f32 * 1e-3, mm(fix.vel_ned[2]) as f32 * 1e-3],
        speed_acc: Some((fix.speed_acc.unwrap_or(0.05) as f64 * 1000.0).round() as u32 as f32 * 1e-3),
        alt_msl_mm: fix.alt_msl_mm,
        ..*fix
    }
}
