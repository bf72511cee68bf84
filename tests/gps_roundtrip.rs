//! Encode a simulated flight's fixes to UBX and NMEA, parse them back, compare
//! within each protocol's quantisation.

mod gps_common;
use gps_common::*;
use wing_ahrs::gps::{config, ubx, GpsParser};
use wing_ahrs::GpsFix;

/// Parse frames sent back to back at 115200 Bd (87 µs per byte); returns each
/// fix with the index of the frame during which it came out. Checks that `t_us`
/// is the arrival time of the last byte of frame `i` (complete epoch) or of frame
/// `i - 1` (epoch flushed by a newer one; NMEA ends at its checksum, before CR LF).
fn parse_stream(frames: &[Vec<u8>]) -> (GpsParser, Vec<(GpsFix, usize)>) {
    let mut p = GpsParser::new();
    let mut out = Vec::new();
    let mut t = 0u64;
    let mut ends = Vec::new();
    for (i, fr) in frames.iter().enumerate() {
        for &b in fr {
            t += 87;
            if let Some(f) = p.push(b, t) {
                // (an NMEA sentence completes at its checksum, before CR LF)
                let prev_end = |e: u64| f.t_us <= e && e - f.t_us <= 2 * 87;
                assert!(f.t_us == t || (i > 0 && prev_end(ends[i - 1])), "t_us {} at {t}", f.t_us);
                out.push((f, i));
            }
        }
        ends.push(t);
    }
    (p, out)
}

#[test]
fn nav_pvt_round_trip_is_exact_to_the_millimetre() {
    let sent = flight(600, 345_600_000, 473_977_420, 85_455_940);
    let frames: Vec<_> = sent.iter().map(pvt).collect();
    let (p, got) = parse_stream(&frames);
    assert_eq!(got.len(), sent.len());
    assert_eq!(p.counters().nav_pvt as usize, sent.len());
    for (k, ((g, i), s)) in got.iter().zip(&sent).enumerate() {
        // A NAV-PVT frame is a whole epoch: its fix comes out during that frame, not later.
        assert_eq!(*i, k, "fix {k} came out during frame {i}");
        assert_eq!(g.itow_ms, s.itow_ms);
        let (gd, sd) = (g.vel_d.expect("NAV-PVT carries vD"), s.vel_d.unwrap());
        for (a, b) in [(g.vel_ne[0], s.vel_ne[0]), (g.vel_ne[1], s.vel_ne[1]), (gd, sd)] {
            assert!((a - b).abs() <= 0.0005 + 1e-5, "{g:?} vs {s:?}");
        }
        assert!((g.speed_acc.unwrap() - s.speed_acc.unwrap()).abs() <= 0.0005 + 1e-5);
        assert!(g.fix_ok);
        assert_eq!(
            (g.fix_type, g.num_sats, g.lat_e7, g.lon_e7, g.alt_msl_mm),
            (s.fix_type, s.num_sats, s.lat_e7, s.lon_e7, s.alt_msl_mm)
        );
    }
}

#[test]
fn legacy_velned_sol_posllh_join_by_itow() {
    let sent = flight(300, 100_000, -338_688_000, 1_512_093_000);
    let frames: Vec<_> = sent.iter().map(legacy).collect();
    let (p, got) = parse_stream(&frames);
    assert_eq!(got.len(), sent.len());
    let c = p.counters();
    assert_eq!((c.nav_velned, c.nav_sol, c.nav_posllh), (300, 300, 300));
    for ((g, _), s) in got.iter().zip(&sent) {
        assert_eq!(g.itow_ms, s.itow_ms);
        let (gd, sd) = (g.vel_d.expect("NAV-VELNED carries vD"), s.vel_d.unwrap());
        for (a, b) in [(g.vel_ne[0], s.vel_ne[0]), (g.vel_ne[1], s.vel_ne[1]), (gd, sd)] {
            assert!((a - b).abs() <= 0.005 + 1e-5, "{g:?} vs {s:?}");
        }
        assert_eq!(
            (g.num_sats, g.lat_e7, g.lon_e7, g.alt_msl_mm),
            (s.num_sats, s.lat_e7, s.lon_e7, s.alt_msl_mm)
        );
    }
    // NAV-PVT and the legacy set of the same epoch: one fix per epoch, not two.
    let both: Vec<_> = sent.iter().map(|f| [pvt(f), legacy(f)].concat()).collect();
    let (_, got) = parse_stream(&both);
    assert_eq!(got.len(), sent.len());
}

fn nmea_round_trip(vtg_first: bool) {
    // UTC 11:59:30.00 onwards, over noon; both hemispheres.
    for (lat, lon) in [(473_977_420, 85_455_940), (-338_688_000, -1_512_093_000)] {
        let sent = flight(400, 43_170_000, lat, lon);
        let frames: Vec<Vec<u8>> = sent.iter().flat_map(|f| nmea(f, vtg_first)).collect();
        let (p, got) = parse_stream(&frames);
        let c = p.counters();
        assert_eq!((c.rmc, c.vtg, c.gga, c.checksum_failures, c.malformed), (400, 400, 400, 0, 0));
        assert_eq!(got.len(), sent.len(), "one fix per epoch");
        for (k, ((g, i), s)) in got.iter().zip(&sent).enumerate() {
            assert_eq!(*i, 3 * k + 2, "emitted on the epoch's last sentence (GGA)");
            assert_eq!(g.itow_ms, s.itow_ms);
            // Speed 1e-3 kn, course 0.01°: ≤ 0.26 mm/s + 30 m/s · 0.005° ≈ 3 mm/s.
            for j in 0..2 {
                assert!((g.vel_ne[j] - s.vel_ne[j]).abs() < 0.004, "{g:?} vs {s:?}");
            }
            assert!(g.vel_d.is_none() && g.speed_acc.is_none(), "NMEA has no vD, no sAcc");
            assert!((g.lat_e7 - s.lat_e7).abs() <= 1 && (g.lon_e7 - s.lon_e7).abs() <= 1);
            assert!((g.alt_msl_mm - s.alt_msl_mm).abs() <= 5);
            assert_eq!((g.num_sats, g.fix_type, g.fix_ok), (s.num_sats, s.fix_type, true));
        }
    }
}

#[test]
fn nmea_rmc_vtg_gga_round_trip_ublox_order() {
    nmea_round_trip(false);
}

#[test]
fn nmea_vtg_rmc_gga_round_trip_vtg_first_order() {
    nmea_round_trip(true);
}

#[test]
fn rmc_only_stream_emits_each_epoch_when_the_next_begins() {
    let sent = flight(50, 43_170_000, 473_977_420, 85_455_940);
    let frames: Vec<Vec<u8>> = sent.iter().map(|f| nmea(f, false).remove(0)).collect();
    let (_, got) = parse_stream(&frames);
    assert_eq!(got.len(), sent.len() - 1, "the last epoch waits for a newer time");
    for ((g, i), (k, s)) in got.iter().zip(sent.iter().enumerate()) {
        assert_eq!(*i, k + 1);
        assert_eq!(g.itow_ms, s.itow_ms);
        assert_eq!(g.fix_type, wing_ahrs::FixType::Fix2D, "no GGA: no altitude, 2-D");
    }
}

#[test]
fn ubx_wins_over_nmea_on_a_mixed_stream() {
    let sent = flight(100, 43_170_000, 473_977_420, 85_455_940);
    let mut frames = Vec::new();
    for (k, f) in sent.iter().enumerate() {
        frames.extend(nmea(f, false));
        if k >= 50 {
            frames.push(pvt(f));
        }
    }
    let (p, got) = parse_stream(&frames);
    // Epochs 0..=50 from NMEA (epoch 50's sentences precede its first NAV-PVT:
    // the one epoch delivered twice, at the switch), 50.. from UBX only.
    assert_eq!(got.len(), 101);
    assert!(got[..51].iter().all(|(g, _)| g.vel_d.is_none()), "NMEA: no vD");
    assert!(got[51..].iter().all(|(g, _)| g.vel_d.is_some()), "UBX: vD");
    assert_eq!(p.counters().nmea_suppressed, 49, "NMEA epochs after the first UBX fix");
}

#[test]
fn unusable_and_out_of_range_fixes_are_counted_not_emitted() {
    let mut fs = flight(4, 1000, 0, 0);
    fs[0].fix_ok = false;
    fs[1].fix_type = wing_ahrs::FixType::NoFix;
    fs[2].vel_ne[0] = 900.0; // faster than any receiver reports
    let frames: Vec<_> = fs.iter().map(pvt).collect();
    let (p, got) = parse_stream(&frames);
    assert_eq!(got.len(), 1);
    assert_eq!(got[0].0.itow_ms, fs[3].itow_ms);
    assert_eq!((p.counters().fixes_unusable, p.counters().fixes_rejected), (2, 1));
}

/// Receiver configuration frames checked field by field against the u-blox
/// M8 protocol spec (UBX-13003221) and the F9 interface description.
#[test]
fn receiver_configuration_frames_match_the_spec() {
    fn frames(mut b: &[u8]) -> Vec<(u8, u8, Vec<u8>)> {
        let mut v = Vec::new();
        while !b.is_empty() {
            assert_eq!(&b[..2], &[0xB5, 0x62]);
            let len = u16::from_le_bytes([b[4], b[5]]) as usize;
            let (a, c) = ubx::checksum(&b[2..6 + len]);
            assert_eq!((b[6 + len], b[7 + len]), (a, c), "Fletcher checksum");
            v.push((b[2], b[3], b[6..6 + len].to_vec()));
            b = &b[8 + len..];
        }
        v
    }
    let mut buf = [0u8; config::CONFIG_MAX];
    let n = config::m8_10hz_nav_pvt(115_200, &mut buf).unwrap();
    let f = frames(&buf[..n]);
    assert_eq!(f.len(), 3);
    // CFG-RATE (0x06 0x08), 6 bytes: measRate 100 ms, navRate 1, timeRef 1 (GPS).
    assert_eq!((f[0].0, f[0].1), (0x06, 0x08));
    assert_eq!(f[0].2, [100, 0, 1, 0, 1, 0]);
    // CFG-MSG (0x06 0x01), 8 bytes: NAV-PVT (01 07), rate 1 on UART1 (2nd port) only.
    assert_eq!((f[1].0, f[1].1), (0x06, 0x01));
    assert_eq!(f[1].2, [0x01, 0x07, 0, 1, 0, 0, 0, 0]);
    // CFG-PRT (0x06 0x00), 20 bytes: port 1, mode 8N1 (0x8C0), baud, in UBX|NMEA, out UBX.
    assert_eq!((f[2].0, f[2].1, f[2].2.len()), (0x06, 0x00, 20));
    let p = &f[2].2;
    assert_eq!(p[0], 1);
    assert_eq!(u32::from_le_bytes(p[4..8].try_into().unwrap()), 0x8C0);
    assert_eq!(u32::from_le_bytes(p[8..12].try_into().unwrap()), 115_200);
    assert_eq!(u16::from_le_bytes([p[12], p[13]]), 0x0003);
    assert_eq!(u16::from_le_bytes([p[14], p[15]]), 0x0001);
    // Known-good bytes of the M8 CFG-RATE 10 Hz command (as published by u-center).
    assert_eq!(
        &buf[..14],
        &[0xB5, 0x62, 0x06, 0x08, 0x06, 0x00, 0x64, 0x00, 0x01, 0x00, 0x01, 0x00, 0x7A, 0x12]
    );

    let n = config::valset_10hz_nav_pvt(230_400, &mut buf).unwrap();
    let f = frames(&buf[..n]);
    assert_eq!(f.len(), 1);
    assert_eq!((f[0].0, f[0].1), (0x06, 0x8A));
    let p = &f[0].2;
    assert_eq!(&p[..4], &[0, 1, 0, 0], "version 0, RAM layer, reserved");
    // Walk key/value pairs; the value size is coded in key bits 28..30.
    let mut kv = std::collections::HashMap::new();
    let mut o = 4;
    while o < p.len() {
        let key = u32::from_le_bytes(p[o..o + 4].try_into().unwrap());
        let size = match (key >> 28) & 7 {
            1 | 2 => 1,
            3 => 2,
            4 => 4,
            5 => 8,
            s => panic!("bad size code {s} in key {key:#x}"),
        };
        let mut v = [0u8; 8];
        v[..size].copy_from_slice(&p[o + 4..o + 4 + size]);
        kv.insert(key, u64::from_le_bytes(v));
        o += 4 + size;
    }
    assert_eq!(o, p.len());
    assert_eq!(kv[&0x3021_0001], 100, "CFG-RATE-MEAS");
    assert_eq!(kv[&0x3021_0002], 1, "CFG-RATE-NAV");
    assert_eq!(kv[&0x2091_0007], 1, "CFG-MSGOUT-UBX_NAV_PVT_UART1");
    assert_eq!(kv[&0x1074_0001], 1, "CFG-UART1OUTPROT-UBX");
    assert_eq!(kv[&0x1074_0002], 0, "CFG-UART1OUTPROT-NMEA");
    assert_eq!(kv[&0x4052_0001], 230_400, "CFG-UART1-BAUDRATE");
    // The parser frames its own configuration output as good UBX (class CFG, skipped).
    let mut parser = GpsParser::new();
    parser.push_slice(&buf[..n], 0, |_| panic!("no fix in config"));
    assert_eq!((parser.counters().frames_ok, parser.counters().bytes_dropped), (1, 0));
}

/// The NMEA course → velocity trigonometry against f64 at every millidegree.
#[test]
fn course_sin_cos_match_f64_everywhere() {
    let mut worst = 0.0f64;
    for c in 0..=360_000u32 {
        let (s, co) = wing_ahrs::gps::epoch::sin_cos_mdeg(c);
        let a = (c as f64 * 1e-3).to_radians();
        worst = worst.max((s as f64 - a.sin()).abs()).max((co as f64 - a.cos()).abs());
    }
    assert!(worst < 2e-7, "worst error {worst}");
}
