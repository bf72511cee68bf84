//! Real receiver captures (`shared/data/gnss/`) through the streaming parser.
//!
//! Truth is an independent framer written here: a whole-buffer scan that checks
//! UBX frames (sync, length within the file, Fletcher checksum) and NMEA
//! sentences (`$…*hh` with XOR checksum) and counts them by type. The parser,
//! fed one byte at a time, must decode exactly as many NAV-PVT / NAV-VELNED /
//! NAV-SOL / NAV-POSLLH / RMC / GGA / VTG and see no checksum failure.

mod common;

use std::collections::HashMap;
use std::path::PathBuf;
use wing_ahrs::gps::GpsParser;
use wing_ahrs::GpsFix;

/// The GNSS captures, or None after `common::skip` (a failure under WING_AHRS_REQUIRE_DATA).
fn data_dir(test: &str) -> Option<PathBuf> {
    let gnss = common::data_dir().map(|d| d.join("gnss")).filter(|g| g.is_dir());
    if gnss.is_none() {
        common::skip(test, "no GNSS captures in $WING_AHRS_DATA or ../shared/data (gnss/)");
    }
    gnss
}

#[derive(Debug, Default, PartialEq, Eq, Clone, Copy)]
struct Counts {
    pvt: u32,
    velned: u32,
    sol: u32,
    posllh: u32,
    rmc: u32,
    gga: u32,
    vtg: u32,
}

/// Frames the independent framer found: the parser counts only their sum (`frames_ok`).
#[derive(Debug, Default)]
struct Frames {
    ubx: u32,
    nmea: u32,
}

/// Independent framer: whole-buffer look-ahead, no state machine.
fn reference_count(data: &[u8]) -> (Counts, Frames) {
    let mut c = Counts::default();
    let mut frames = Frames::default();
    let mut i = 0;
    while i < data.len() {
        if data[i] == 0xB5 && data.get(i + 1) == Some(&0x62) && i + 6 <= data.len() {
            let len = u16::from_le_bytes([data[i + 4], data[i + 5]]) as usize;
            let end = i + 6 + len + 2;
            if end <= data.len() {
                let (mut a, mut b) = (0u8, 0u8);
                for &x in &data[i + 2..i + 6 + len] {
                    a = a.wrapping_add(x);
                    b = b.wrapping_add(a);
                }
                if a == data[end - 2] && b == data[end - 1] {
                    frames.ubx += 1;
                    match (data[i + 2], data[i + 3]) {
                        (1, 7) => c.pvt += 1,
                        (1, 0x12) => c.velned += 1,
                        (1, 6) => c.sol += 1,
                        (1, 2) => c.posllh += 1,
                        _ => {}
                    }
                    i = end;
                    continue;
                }
            }
        }
        if data[i] == b'$' {
            if let Some(star) = data[i..].iter().take(130).position(|&x| x == b'*') {
                let body = &data[i + 1..i + star];
                let ck = data
                    .get(i + star + 1..i + star + 3)
                    .and_then(|h| u8::from_str_radix(std::str::from_utf8(h).ok()?, 16).ok());
                let printable = body.iter().all(|&x| (0x20..0x7f).contains(&x) && x != b'$');
                if printable && ck == Some(body.iter().fold(0, |a, &x| a ^ x)) {
                    frames.nmea += 1;
                    let addr = body.split(|&x| x == b',').next().unwrap_or(b"");
                    if addr.len() == 5 {
                        match &addr[2..] {
                            b"RMC" => c.rmc += 1,
                            b"GGA" => c.gga += 1,
                            b"VTG" => c.vtg += 1,
                            _ => {}
                        }
                    }
                    i += star + 3;
                    continue;
                }
            }
        }
        i += 1;
    }
    (c, frames)
}

fn parse(data: &[u8]) -> (GpsParser, Vec<GpsFix>) {
    let mut p = GpsParser::new();
    let mut fixes = Vec::new();
    for (k, &b) in data.iter().enumerate() {
        if let Some(f) = p.push(b, k as u64) {
            fixes.push(f);
        }
    }
    (p, fixes)
}

#[test]
fn every_capture_decodes_exactly_the_independently_framed_messages() {
    let Some(dir) = data_dir("every_capture_decodes_exactly_the_independently_framed_messages")
    else {
        return;
    };
    let mut files: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).collect();
    files.sort();
    assert!(!files.is_empty());
    for path in files {
        let data = std::fs::read(&path).unwrap();
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        let (want, framed) = reference_count(&data);
        let (p, fixes) = parse(&data);
        let c = *p.counters();
        let got = Counts {
            pvt: c.nav_pvt,
            velned: c.nav_velned,
            sol: c.nav_sol,
            posllh: c.nav_posllh,
            rmc: c.rmc,
            gga: c.gga,
            vtg: c.vtg,
        };
        println!(
            "{name}: PVT {} VELNED {} SOL {} POSLLH {} RMC {} GGA {} VTG {} | frames ok {} (ref {} UBX + {} NMEA) | fixes {} unusable {} rejected {} | dropped bytes {}",
            c.nav_pvt, c.nav_velned, c.nav_sol, c.nav_posllh, c.rmc, c.gga, c.vtg, c.frames_ok,
            framed.ubx, framed.nmea, fixes.len(), c.fixes_unusable, c.fixes_rejected, c.bytes_dropped
        );
        assert_eq!(got, want, "{name}: decoded counts differ from the independent framer");
        assert_eq!(c.frames_ok, framed.ubx + framed.nmea, "{name}: frames ok");
        assert_eq!(c.checksum_failures, 0, "{name}: checksum failures on a clean capture");
        assert_eq!(c.malformed, 0, "{name}: malformed RMC/GGA/VTG");
        assert_eq!(c.fixes as usize, fixes.len());
        for f in &fixes {
            assert!(f.usable() && wing_ahrs::gps::plausible(f), "{name}: {f:?}");
            assert!(f.lat_e7 != 0 && f.lon_e7 != 0, "{name}: fix without position {f:?}");
        }
    }
}

/// Stationary captures: every fix is slow (< 2 m/s) and all fixes of a file lie
/// within a few hundred metres of each other.
#[test]
fn stationary_captures_give_plausible_still_fixes() {
    let Some(dir) = data_dir("stationary_captures_give_plausible_still_fixes") else { return };
    for name in [
        "pygpsdata-MIXED.log",
        "gpsd_ublox-neo-m8n.log",
        "gpsd_ublox-zed-f9p-hp.log",
        "gpsd_ublox-zed-f9p-nmea.log",
        "gpsd_ublox-8.log",
    ] {
        let data = std::fs::read(dir.join(name)).unwrap();
        let (_, fixes) = parse(&data);
        assert!(!fixes.is_empty(), "{name}: no fixes");
        let f0 = fixes[0];
        for f in &fixes {
            let vd = f.vel_d.unwrap_or(0.0); // the NMEA capture has no vD
            assert!(f.ground_speed() < 2.0 && vd.abs() < 2.0, "{name}: moving {f:?}");
            let dlat = (f.lat_e7 - f0.lat_e7).abs() as f64 * 1e-7 * 111e3;
            let dlon = (f.lon_e7 - f0.lon_e7).abs() as f64
                * 1e-7
                * 111e3
                * (f0.lat_e7 as f64 * 1e-7).to_radians().cos();
            assert!(dlat < 300.0 && dlon < 300.0, "{name}: position jumps {dlat} m / {dlon} m");
            assert!(f.num_sats >= 4, "{name}: {f:?}");
        }
        println!(
            "{name}: {} still fixes, first at lat {:.5} lon {:.5}",
            fixes.len(),
            f0.lat_e7 as f64 * 1e-7,
            f0.lon_e7 as f64 * 1e-7
        );
    }
}

/// The moving AeroRust log: every fix's speed and course equal its RMC fields and
/// the VTG sent just before that RMC; altitude is its GGA's.
#[test]
fn aerorust_fix_speeds_match_rmc_and_vtg_fields() {
    let Some(dir) = data_dir("aerorust_fix_speeds_match_rmc_and_vtg_fields") else { return };
    let text = std::fs::read(dir.join("aerorust_nmea1.log")).unwrap();
    let text = String::from_utf8_lossy(&text);
    // time (ms of day) → (RMC knots, RMC course, VTG (knots, km/h), GGA altitude m)
    type Truth = (f64, f64, Option<(f64, f64)>, Option<f64>);
    let mut truth: HashMap<u32, Truth> = HashMap::new();
    let mut last_vtg = None;
    let tod = |s: &str| -> u32 {
        let v: f64 = s.parse().unwrap();
        let hh = (v / 10000.0).floor();
        let mm = ((v - hh * 10000.0) / 100.0).floor();
        let ss = v - hh * 10000.0 - mm * 100.0;
        ((hh * 3600.0 + mm * 60.0 + ss) * 1000.0).round() as u32
    };
    for line in text.lines() {
        let body = line.trim().split('*').next().unwrap_or("");
        let f: Vec<&str> = body.split(',').collect();
        if f[0].ends_with("VTG") {
            last_vtg = f[5].parse::<f64>().ok().zip(f[7].parse::<f64>().ok());
        } else if f[0].ends_with("RMC") && f[2] == "A" {
            let t = tod(f[1]);
            let e = truth.entry(t).or_insert((0.0, 0.0, None, None));
            e.0 = f[7].parse().unwrap();
            e.1 = f[8].parse().unwrap_or(f64::NAN);
            e.2 = last_vtg.take();
        } else if f[0].ends_with("GGA") && !f[1].is_empty() {
            truth.entry(tod(f[1])).or_insert((0.0, 0.0, None, None)).3 = f[9].parse().ok();
        }
    }
    let (_, fixes) = parse(text.as_bytes());
    assert!(fixes.len() > 100, "only {} fixes", fixes.len());
    let (mut max_speed, mut min_alt, mut max_alt) = (0.0f32, f32::MAX, f32::MIN);
    for f in &fixes {
        let t = f.itow_ms.unwrap();
        let (kn, course, vtg, alt) = truth[&t];
        let speed = f.ground_speed() as f64;
        if course.is_nan() {
            // No course: documented as "standing still" below STILL_SPEED.
            assert!(
                kn * 1852.0 / 3600.0 < wing_ahrs::gps::epoch::STILL_SPEED as f64 && speed == 0.0,
                "t {t}"
            );
            continue;
        }
        assert!(
            (speed - kn * 1852.0 / 3600.0).abs() < 1e-3 * (1.0 + speed),
            "t {t}: {speed} vs RMC {kn} kn"
        );
        if let Some((vkn, vkmh)) = vtg {
            assert!(
                (speed - vkn * 1852.0 / 3600.0).abs() < 1e-3 * (1.0 + speed),
                "t {t}: VTG {vkn} kn"
            );
            assert!((speed - vkmh / 3.6).abs() < 0.06, "t {t}: VTG {vkmh} km/h");
        }
        if speed > 1.0 {
            let c = (f.vel_ne[1] as f64).atan2(f.vel_ne[0] as f64).to_degrees().rem_euclid(360.0);
            let d = (c - course + 540.0).rem_euclid(360.0) - 180.0;
            assert!(d.abs() < 0.01, "t {t}: course {c} vs RMC {course}");
        }
        assert_eq!(f.vel_d, None, "NMEA has no vertical velocity");
        if let Some(a) = alt {
            assert_eq!(f.alt_msl_mm as f64, (a * 1000.0).round(), "t {t}");
        }
        max_speed = max_speed.max(f.ground_speed());
        min_alt = min_alt.min(f.alt_msl_mm as f32 * 1e-3);
        max_alt = max_alt.max(f.alt_msl_mm as f32 * 1e-3);
    }
    println!(
        "aerorust: {} fixes, max speed {max_speed:.1} m/s, altitude {min_alt:.0}..{max_alt:.0} m",
        fixes.len()
    );
    // The README's description of the flight: 78.5 m/s → 0, 2188 m → 108 m.
    assert!((70.0..90.0).contains(&max_speed), "max speed {max_speed}");
    assert!(max_alt > 2000.0 && min_alt < 200.0);
}

/// Second opinion from another implementation: pyubx2 (PyPI, reads UBX and NMEA)
/// counts the same NAV-PVT / VELNED / SOL / POSLLH / RMC / GGA / VTG per capture.
/// Skips, saying so, when python3 or pyubx2 is not installed (fails under WING_AHRS_REQUIRE_DATA).
#[test]
fn pyubx2_counts_the_same_messages() {
    let Some(dir) = data_dir("pyubx2_counts_the_same_messages") else { return };
    const SCRIPT: &str = r#"
import sys
from collections import Counter
from pyubx2 import UBXReader, UBX_PROTOCOL, NMEA_PROTOCOL, ERR_IGNORE
for path in sys.argv[1:]:
    c = Counter()
    with open(path, 'rb') as f:
        for raw, msg in UBXReader(f, protfilter=UBX_PROTOCOL | NMEA_PROTOCOL, quitonerror=ERR_IGNORE):
            if msg is not None:
                c[msg.identity] += 1
    n = [c['NAV-PVT'], c['NAV-VELNED'], c['NAV-SOL'], c['NAV-POSLLH']]
    n += [sum(v for k, v in c.items() if len(k) == 5 and k.endswith(t)) for t in ('RMC', 'GGA', 'VTG')]
    print(' '.join(map(str, n)))
"#;
    let mut files: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).collect();
    files.sort();
    let out = std::process::Command::new("python3").arg("-c").arg(SCRIPT).args(&files).output();
    let out = match out {
        Ok(o) if o.status.success() => String::from_utf8(o.stdout).unwrap(),
        Ok(o) => {
            let err = String::from_utf8_lossy(&o.stderr);
            let why = format!("pyubx2 not usable ({})", err.lines().last().unwrap_or(""));
            common::skip("pyubx2_counts_the_same_messages", &why);
            return;
        }
        Err(e) => {
            common::skip("pyubx2_counts_the_same_messages", &format!("python3 not found ({e})"));
            return;
        }
    };
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), files.len());
    for (path, line) in files.iter().zip(lines) {
        let want: Vec<u32> = line.split_whitespace().map(|x| x.parse().unwrap()).collect();
        let (p, _) = parse(&std::fs::read(path).unwrap());
        let c = p.counters();
        let got = vec![c.nav_pvt, c.nav_velned, c.nav_sol, c.nav_posllh, c.rmc, c.gga, c.vtg];
        println!("{}: pyubx2 {want:?}", path.display());
        assert_eq!(got, want, "{}: differs from pyubx2", path.display());
    }
}

/// The legacy epoch's redundancy checks (NAV-SOL against NAV-VELNED speed accuracy, the
/// VELNED speeds against its velocity, POSLLH heights, SOL status) on a real u-blox 8:
/// with the NAV-PVT frames cut out of the mixed capture, its NAV-VELNED + NAV-SOL epochs
/// still decode — none rejected — with the velocity and speed accuracy NAV-PVT gave
/// for the same epoch (cm/s against mm/s: within 0.5 cm/s).
#[test]
fn legacy_epochs_of_a_real_receiver_pass_the_redundancy_checks() {
    let Some(dir) = data_dir("legacy_epochs_of_a_real_receiver_pass_the_redundancy_checks") else {
        return;
    };
    let data = std::fs::read(dir.join("pygpsdata-MIXED.log")).unwrap();
    // Cut every NAV-PVT frame (class 0x01, id 0x07, 92-byte payload, 100 bytes framed).
    let (mut legacy, mut i) = (Vec::new(), 0);
    while i < data.len() {
        if data[i..].starts_with(&[0xB5, 0x62, 0x01, 0x07, 92, 0]) {
            i += 100;
        } else {
            legacy.push(data[i]);
            i += 1;
        }
    }
    let (_, with_pvt) = parse(&data);
    let (p, got) = parse(&legacy);
    let c = p.counters();
    println!("pygpsdata-MIXED.log without NAV-PVT: {} fixes from NAV-VELNED {} / NAV-SOL {}; malformed {}", got.len(), c.nav_velned, c.nav_sol, c.malformed);
    assert_eq!(c.malformed, 0);
    assert!(got.len() >= 9, "{} legacy fixes", got.len());
    let by_itow: HashMap<u32, GpsFix> = with_pvt.iter().map(|f| (f.itow_ms.unwrap(), *f)).collect();
    for f in &got {
        let pvt = by_itow[&f.itow_ms.unwrap()];
        let (vd, pvt_vd) =
            (f.vel_d.expect("NAV-VELNED has vD"), pvt.vel_d.expect("NAV-PVT has vD"));
        for (a, b) in [(f.vel_ne[0], pvt.vel_ne[0]), (f.vel_ne[1], pvt.vel_ne[1]), (vd, pvt_vd)] {
            assert!((a - b).abs() <= 0.005 + 1e-6, "{f:?} vs {pvt:?}");
        }
        assert!((f.speed_acc.unwrap() - pvt.speed_acc.unwrap()).abs() <= 0.005 + 1e-6);
        assert!(f.num_sats >= 4);
    }
}

/// The learnt GPS velocity noise (`mekf::vel_noise`) on real receivers at rest, where the
/// truth is known: the velocity is zero, so its scatter about the mean is the noise. The
/// residual of the GPS acceleration at rest is the acceleration the fixes show (the IMU
/// would read g exactly); the learner starts from the receiver's own `sAcc`, 5–10× too
/// pessimistic, and must find the noise seen, not the report.
#[test]
fn learnt_velocity_noise_matches_real_receivers_at_rest() {
    use wing_ahrs::mekf::vel_noise::VelNoise;
    let Some(dir) = data_dir("learnt_velocity_noise_matches_real_receivers_at_rest") else {
        return;
    };
    for name in ["pygpsdata-MIXED.log", "gpsd_ublox-zed-f9p-hp.log", "gpsd_ublox-neo-m8n.log"] {
        let data = std::fs::read(dir.join(name)).unwrap();
        let (_, fixes) = parse(&data);
        let fixes: Vec<&GpsFix> = fixes.iter().filter(|f| f.itow_ms.is_some()).collect();
        let vel = |f: &GpsFix| [f.vel_ne[0], f.vel_ne[1], f.vel_d.unwrap_or(0.0)];
        let vertical = fixes.iter().all(|f| f.vel_d.is_some());
        let axes = if vertical { 3 } else { 2 };
        // The noise seen: per-axis scatter about the mean, pooled over the axes (RMS).
        let n = fixes.len() as f64;
        let mut var = 0.0;
        for i in 0..axes {
            let m = fixes.iter().map(|f| vel(f)[i] as f64).sum::<f64>() / n;
            var += fixes.iter().map(|f| (vel(f)[i] as f64 - m).powi(2)).sum::<f64>() / n;
        }
        let seen = (var / axes as f64).sqrt();
        let mut vn = VelNoise::default();
        let mut reported = Vec::new();
        for w in fixes.windows(2) {
            let dt = (w[1].itow_ms.unwrap().wrapping_sub(w[0].itow_ms.unwrap())) as f32 * 1e-3;
            if !(dt > 0.0 && dt <= 2.0) {
                vn.restart();
                continue;
            }
            let (v0, v1) = (vel(w[0]), vel(w[1]));
            if let Some(a) = w[1].speed_acc {
                vn.reference(a);
                reported.push(a as f64);
            } else {
                vn.reference(0.3);
            }
            let y = [0, 1, 2].map(|i| (v1[i] - v0[i]) / dt);
            vn.observe(y, [0.0; 3], [0.0; 3], dt, vertical);
        }
        let learnt = vn.sigma().unwrap() as f64;
        reported.sort_by(f64::total_cmp);
        let median = reported.get(reported.len() / 2).copied().unwrap_or(f64::NAN);
        println!(
            "{name}: {} fixes, noise seen σ {seen:.4} m/s per axis, reported sAcc median {median:.3}, learnt σ {learnt:.4}",
            fixes.len()
        );
        // Closer to the noise seen than the report by at least half, in the log: a report
        // 5–10× off leaves the learnt σ within about 2× (a receiver's own smoothing makes its
        // fix-to-fix noise smaller than its scatter, which the learner sees as it should).
        let off = |x: f64| (x / seen).ln().abs();
        assert!(
            off(learnt) < 0.5 * off(median),
            "{name}: learnt {learnt}, seen {seen}, reported {median}"
        );
        assert!((0.4..1.5).contains(&(learnt / seen)), "{name}: learnt {learnt} vs seen {seen}");
    }
}

/// Before alignment (`VelNoise::observe_lengths`): fixes with white velocity noise σ on a
/// body at rest in a steady turn (the IMU's length constant), each receiver reporting 10×,
/// 0.1× or 1× σ. The lengths differ by the noise of the two fixes along f; the learnt σ
/// must come to the noise, not the report, within the scatter of 200 one-axis samples.
#[test]
fn the_lengths_learn_the_noise_whatever_the_report() {
    use rand::SeedableRng;
    use wing_ahrs::mekf::vel_noise::VelNoise;
    let (sigma, dt) = (0.03f64, 0.1f64);
    for (seed, report) in [(1u64, 10.0 * sigma), (2, 0.1 * sigma), (3, sigma)] {
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        let mut vn = VelNoise::default();
        // The specific force's direction: a 35° bank; the fixes' noise projected on it.
        let f_hat = [0.0, -0.574, -0.819];
        let mut fix = || [0; 3].map(|_| common::gauss(&mut rng) * sigma);
        let mut prev = fix();
        for _ in 0..200 {
            let next = fix();
            let along: f64 = (0..3).map(|i| (next[i] - prev[i]) * f_hat[i]).sum();
            vn.reference(report as f32);
            vn.observe_lengths((along / dt) as f32, dt as f32);
            prev = next;
        }
        let learnt = vn.sigma().unwrap() as f64;
        assert!(
            (learnt / sigma - 1.0).abs() < 0.2,
            "report {report}: learnt {learnt}, noise {sigma}"
        );
    }
}
