//! Corrupted streams (proptest): random bit flips, inserted and deleted bytes,
//! truncated frames and garbage between frames. Properties:
//! - never a panic;
//! - no fix that differs from what was sent: every fix equals the clean decode of
//!   the same epoch (UBX: all fields; NMEA: time, velocity, position, and altitude
//!   and satellites when the epoch's GGA arrived) — UBX frames whose damage the 16-bit
//!   checksum cannot see (2⁻¹⁶) included, through the NAV fields' redundancy; the one
//!   field without any, NAV-SOL's satellite count, is exempt where the damage reached it;
//! - resynchronisation within one frame: every frame left intact still yields its
//!   epoch, whatever happened to the frame before it.

mod gps_common;
use gps_common::*;
use proptest::prelude::*;
use std::collections::HashMap;
use wing_ahrs::gps::GpsParser;
use wing_ahrs::{FixType, GpsFix};

#[derive(Debug, Clone)]
enum Damage {
    None,
    Flip(usize, u8),
    Delete(usize),
    Insert(usize, u8),
    /// Keep only the first 1..len-1 bytes.
    Truncate(usize),
}

fn damage() -> impl Strategy<Value = Damage> {
    prop_oneof![
        5 => Just(Damage::None),
        1 => (any::<usize>(), 0u8..8).prop_map(|(p, b)| Damage::Flip(p, b)),
        1 => any::<usize>().prop_map(Damage::Delete),
        1 => (any::<usize>(), any::<u8>()).prop_map(|(p, b)| Damage::Insert(p, b)),
        1 => any::<usize>().prop_map(Damage::Truncate),
    ]
}

/// Whether `d` can put an arbitrary byte into NAV-SOL's `numSV` (frame offset 6 + 47) of
/// `frame` while leaving every checked field before it intact: a byte inserted exactly
/// there, or the frame cut within pDOP…numSV (offsets 50–53) so that the bytes after the
/// cut fill it. Should the checksum then collide (2⁻¹⁶), that byte *is* the satellite
/// count, and no check can tell it from a real one (`NavSol::consistent`; every other field
/// of the fix is checked).
fn exposes_num_sv(frame: &[u8], d: &Damage) -> bool {
    let n = frame.len();
    let sol = n == 60 && frame[2] == 0x01 && frame[3] == 0x06;
    sol && match *d {
        Damage::Insert(p, _) => 1 + p % (n - 1) == 53,
        Damage::Truncate(p) => (50..=53).contains(&(1 + p % (n - 1))),
        _ => false,
    }
}

/// Apply `d`; returns the bytes and whether the frame is still intact.
fn apply(frame: &[u8], d: &Damage) -> (Vec<u8>, bool) {
    let mut f = frame.to_vec();
    let n = f.len();
    match *d {
        Damage::None => return (f, true),
        Damage::Flip(p, b) => f[p % n] ^= 1 << b,
        Damage::Delete(p) => {
            f.remove(p % n);
        }
        Damage::Insert(p, b) => f.insert(1 + p % (n - 1), b), // strictly inside
        Damage::Truncate(p) => f.truncate(1 + p % (n - 1)),
    }
    (f, false)
}

/// Garbage that cannot itself start a frame (no `µ`, no `$`): with it, every
/// intact frame must decode. Arbitrary garbage is tested without that claim.
fn quiet_garbage() -> impl Strategy<Value = Vec<u8>> {
    prop::collection::vec(
        any::<u8>().prop_filter("no frame start", |b| *b != 0xB5 && *b != b'$'),
        0..24,
    )
}

/// Frames of a stream and the epoch (index into `fixes`) each belongs to.
struct Stream {
    frames: Vec<Vec<u8>>,
    epoch_of: Vec<usize>,
}

fn build(fixes: &[GpsFix], kind: u8) -> Stream {
    let mut frames = Vec::new();
    let mut epoch_of = Vec::new();
    let mut gsv =
        b"$GPGSV,3,1,11,03,03,111,00,04,15,270,00,06,01,010,00,13,06,292,00*74\r\n".to_vec();
    gsv.truncate(gsv.len()); // an undecoded sentence with a valid checksum
    let ack = [0xB5, 0x62, 0x05, 0x01, 0x02, 0x00, 0x06, 0x8A, 0x98, 0xC1]; // ACK-ACK
    for (k, f) in fixes.iter().enumerate() {
        let mut push = |fr: Vec<u8>| {
            frames.push(fr);
            epoch_of.push(k);
        };
        match kind {
            0 => push(pvt(f)),
            1 => nmea(f, k % 2 == 0).into_iter().for_each(&mut push),
            2 => {
                // UBX with unrelated traffic: an undecoded NMEA sentence and UBX ACK.
                push(gsv.clone());
                push(pvt(f));
                push(ack.to_vec());
            }
            _ => {
                let b = legacy(f);
                // POSLLH (36), SOL (60), VELNED (44) as separate frames
                push(b[..36].to_vec());
                push(b[36..96].to_vec());
                push(b[96..].to_vec());
            }
        }
    }
    Stream { frames, epoch_of }
}

fn decode(bytes: &[u8]) -> Vec<GpsFix> {
    let mut p = GpsParser::new();
    let mut out = Vec::new();
    p.push_slice(bytes, 0, |f| out.push(f));
    out
}

/// Same epoch content, as far as the fix carries it (t_us aside); the satellite count
/// only unless `any_sats`.
fn same_but(got: &GpsFix, want: &GpsFix, any_sats: bool) -> bool {
    let want = &GpsFix { num_sats: if any_sats { got.num_sats } else { want.num_sats }, ..*want };
    let core = got.itow_ms == want.itow_ms
        && got.vel_ne == want.vel_ne
        && got.vel_d == want.vel_d
        && got.speed_acc == want.speed_acc
        && got.fix_ok == want.fix_ok;
    // UBX legacy without POSLLH: position all zero ("unknown").
    let unknown_pos = (got.lat_e7, got.lon_e7, got.alt_msl_mm) == (0, 0, 0);
    let pos = (got.lat_e7, got.lon_e7) == (want.lat_e7, want.lon_e7) || unknown_pos;
    // NMEA without GGA: 2-D, altitude and satellites 0.
    let no_gga = got.fix_type == FixType::Fix2D
        && got.vel_d.is_none()
        && got.alt_msl_mm == 0
        && got.num_sats == 0;
    let extra = got.alt_msl_mm == want.alt_msl_mm && got.num_sats == want.num_sats
        || no_gga
        || unknown_pos && got.num_sats == want.num_sats;
    let kind_ok = got.fix_type == want.fix_type
        || (got.fix_type == FixType::Fix2D
            && want.fix_type == FixType::Fix3D
            && got.vel_d.is_none());
    core && pos && extra && kind_ok
}

fn check(
    kind: u8,
    n: usize,
    damages: &[Damage],
    garbage: &[Vec<u8>],
    resync: bool,
) -> Result<(), TestCaseError> {
    let fixes = flight(n, 43_170_000, 473_977_420, 85_455_940);
    let s = build(&fixes, kind);
    let clean: Vec<u8> = s.frames.concat();
    let reference: HashMap<u32, GpsFix> =
        decode(&clean).into_iter().map(|f| (f.itow_ms.unwrap(), f)).collect();
    prop_assert_eq!(reference.len(), n, "clean stream decodes every epoch");

    let mut bytes = Vec::new();
    let mut intact_epoch = vec![true; n];
    let mut any_sats = vec![false; n];
    for (i, fr) in s.frames.iter().enumerate() {
        bytes.extend_from_slice(&garbage[i % garbage.len()]);
        let d = &damages[i % damages.len()];
        any_sats[s.epoch_of[i]] |= exposes_num_sv(fr, d);
        let (b, intact) = apply(fr, d);
        if !intact {
            intact_epoch[s.epoch_of[i]] = false;
        }
        bytes.extend_from_slice(&b);
    }
    let mut p = GpsParser::new();
    let mut got = Vec::new();
    for (t, &b) in bytes.iter().enumerate() {
        if let Some(f) = p.push(b, t as u64) {
            got.push(f);
        }
    }
    for f in &got {
        let itow = f.itow_ms.unwrap();
        let want = reference.get(&itow);
        let k = fixes.iter().position(|x| x.itow_ms == Some(itow));
        let any = k.is_some_and(|k| any_sats[k]);
        prop_assert!(
            want.is_some_and(|w| same_but(f, w, any)),
            "fix not sent: {:?}\nsent: {:?}",
            f,
            want
        );
    }
    let mut seen: Vec<u32> = got.iter().map(|f| f.itow_ms.unwrap()).collect();
    seen.sort();
    seen.dedup();
    prop_assert_eq!(seen.len(), got.len(), "an epoch emitted twice");
    if resync {
        for (k, f) in fixes.iter().enumerate() {
            if intact_epoch[k] {
                prop_assert!(
                    seen.contains(&f.itow_ms.unwrap()),
                    "intact epoch {} lost; counters {:?}",
                    k,
                    p.counters()
                );
            }
        }
    }
    Ok(())
}

proptest! {
    // 256 cases by default; PROPTEST_CASES=N for a longer run.
    // (`quiet_garbage` filters ~1 % of its bytes: long runs need more local rejects than the default 65,536.)
    #![proptest_config(ProptestConfig { cases: std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(256), max_local_rejects: u32::MAX, ..ProptestConfig::default() })]

    #[test]
    fn corrupted_nav_pvt_stream(d in prop::collection::vec(damage(), 1..12), g in prop::collection::vec(quiet_garbage(), 1..6)) {
        check(0, 24, &d, &g, true)?;
    }

    #[test]
    fn corrupted_nmea_stream(d in prop::collection::vec(damage(), 1..20), g in prop::collection::vec(quiet_garbage(), 1..6)) {
        check(1, 16, &d, &g, true)?;
    }

    #[test]
    fn corrupted_mixed_ubx_and_nmea_traffic(d in prop::collection::vec(damage(), 1..20), g in prop::collection::vec(quiet_garbage(), 1..6)) {
        check(2, 16, &d, &g, true)?;
    }

    #[test]
    fn corrupted_legacy_ubx_stream(d in prop::collection::vec(damage(), 1..20), g in prop::collection::vec(quiet_garbage(), 1..6)) {
        check(3, 16, &d, &g, true)?;
    }

    /// Garbage may contain frame starts: no resync claim, but still no wrong fix.
    #[test]
    fn arbitrary_garbage_never_yields_a_wrong_fix(kind in 0u8..4, d in prop::collection::vec(damage(), 1..12), g in prop::collection::vec(prop::collection::vec(any::<u8>(), 0..40), 1..6)) {
        check(kind, 16, &d, &g, false)?;
    }

    /// Pure noise: no panic, and nothing implausible ever comes out.
    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..4096)) {
        for f in decode(&bytes) {
            prop_assert!(f.usable() && wing_ahrs::gps::plausible(&f));
        }
    }
}

/// A deterministic worst case for resync: a NAV-PVT frame cut after k bytes for
/// every k, followed by an intact one, which must always decode.
#[test]
fn every_truncation_point_resyncs_on_the_next_frame() {
    let fixes = flight(2, 100_000, 0, 0);
    let (a, b) = (pvt(&fixes[0]), pvt(&fixes[1]));
    for k in 1..a.len() {
        let bytes = [&a[..k], &b[..]].concat();
        let got = decode(&bytes);
        assert_eq!(got.len(), 1, "cut at {k}");
        assert_eq!(got[0].itow_ms, fixes[1].itow_ms);
    }
    // And every single-byte deletion.
    for k in 0..a.len() {
        let mut c = a.clone();
        c.remove(k);
        let got = decode(&[c, b.clone()].concat());
        assert_eq!(got.len(), 1, "deleted byte {k}");
        assert_eq!(got[0].itow_ms, fixes[1].itow_ms);
    }
}

/// A corrupted NAV-PVT that still passes the Fletcher checksum (the 2⁻¹⁶ case a
/// proptest run found: one byte inserted inside the payload): re-framed with a valid
/// checksum at every insertion point, the shifted fields must never come out as a fix
/// that differs from the one sent. The gSpeed/velocity redundancy and the speed-accuracy
/// range catch the shifts that reach the fields a fix carries.
#[test]
fn checksum_colliding_byte_insertion_never_yields_a_wrong_fix() {
    let fixes = flight(3, 100_000, 473_977_420, 85_455_940);
    let f = fixes[2];
    let clean = pvt(&f);
    let payload = &clean[6..clean.len() - 2];
    let want = decode(&clean)[0];
    let mut rejected = 0;
    for at in 1..payload.len() {
        for byte in [0x00u8, 0x01, 0x55, 0x80, 0xFF] {
            // Insert, drop the last payload byte (the length field is unchanged), re-checksum.
            let mut p = payload.to_vec();
            p.insert(at, byte);
            p.truncate(payload.len());
            let mut buf = [0u8; 128];
            let n = wing_ahrs::gps::encode::ubx_frame(0x01, 0x07, &p, &mut buf).unwrap();
            match decode(&buf[..n]).first() {
                Some(got) => {
                    let fields = |g: &GpsFix| {
                        (
                            g.itow_ms,
                            g.vel_ne,
                            g.vel_d,
                            g.speed_acc,
                            g.lat_e7,
                            g.lon_e7,
                            g.alt_msl_mm,
                            g.num_sats,
                            g.fix_type,
                            g.fix_ok,
                        )
                    };
                    assert_eq!(
                        fields(got),
                        fields(&want),
                        "insertion of {byte:#04x} at payload offset {at} gave a wrong fix"
                    );
                }
                None => rejected += 1,
            }
        }
    }
    println!(
        "{rejected} of {} checksum-valid shifted frames rejected; the rest decode to the fix sent",
        5 * (payload.len() - 1)
    );
    assert!(rejected > 0);
}

/// The same for the legacy epoch (NAV-POSLLH, NAV-SOL, NAV-VELNED): each message in turn
/// gets a byte inserted at every payload offset, re-framed with a valid checksum (the case a
/// proptest run found: a byte inserted inside NAV-SOL shifted `reserved1` into `numSV`),
/// next to the other two intact. No shifted field may come out in a fix: the redundancy
/// checks (VELNED speed and gSpeed against the velocity, POSLLH ellipsoidal against MSL
/// height, SOL fix type against flags and satellites) reject what would — except the one
/// case no check can see: a byte inserted exactly at NAV-SOL's `numSV` that is itself a
/// possible count (here 12) gives that count, and nothing else differs.
#[test]
fn checksum_colliding_byte_insertion_in_legacy_messages_never_yields_a_wrong_fix() {
    use wing_ahrs::gps::ubx::{ID_POSLLH, ID_SOL, ID_VELNED};
    let fixes = flight(3, 100_000, 473_977_420, 85_455_940);
    let clean = legacy(&fixes[2]);
    // Split the three frames (POSLLH 36, SOL 60, VELNED 44 bytes).
    let frames = [&clean[..36], &clean[36..96], &clean[96..]];
    let want = decode(&clean)[0];
    let fields = |g: &GpsFix| {
        (
            g.itow_ms,
            g.vel_ne,
            g.vel_d,
            g.speed_acc,
            g.lat_e7,
            g.lon_e7,
            g.alt_msl_mm,
            g.num_sats,
            g.fix_type,
            g.fix_ok,
        )
    };
    let (mut shifted, mut rejected, mut invisible) = (0, 0, 0);
    for (k, id) in [ID_POSLLH, ID_SOL, ID_VELNED].into_iter().enumerate() {
        let payload = &frames[k][6..frames[k].len() - 2];
        for at in 1..payload.len() {
            for byte in [0x00u8, 0x01, 0x0C, 0x55, 0x80, 0xFF] {
                let mut p = payload.to_vec();
                p.insert(at, byte);
                p.truncate(payload.len());
                if p == payload {
                    continue; // the insertion changed nothing
                }
                shifted += 1;
                let mut buf = [0u8; 128];
                let n = wing_ahrs::gps::encode::ubx_frame(0x01, id, &p, &mut buf).unwrap();
                let mut bytes = Vec::new();
                for (j, f) in frames.iter().enumerate() {
                    bytes.extend_from_slice(if j == k { &buf[..n] } else { f });
                }
                match decode(&bytes).first() {
                    // Position lost with its POSLLH: reported as unknown (0 / 0 / 0), allowed.
                    Some(got) if (got.lat_e7, got.lon_e7, got.alt_msl_mm) == (0, 0, 0) => {
                        assert_eq!((got.itow_ms, got.vel_ne, got.vel_d, got.speed_acc, got.num_sats, got.fix_type, got.fix_ok), (want.itow_ms, want.vel_ne, want.vel_d, want.speed_acc, want.num_sats, want.fix_type, want.fix_ok), "message {id:#04x}: insertion of {byte:#04x} at payload offset {at}");
                    }
                    Some(got) if id == ID_SOL && at == 47 => {
                        invisible += 1;
                        assert_eq!(fields(&GpsFix { num_sats: want.num_sats, ..*got }), fields(&want), "insertion of {byte:#04x} at numSV");
                        assert_eq!(got.num_sats, byte);
                    }
                    Some(got) => assert_eq!(fields(got), fields(&want), "message {id:#04x}: insertion of {byte:#04x} at payload offset {at} gave a wrong fix"),
                    None => rejected += 1,
                }
            }
        }
    }
    println!("{rejected} of {shifted} checksum-valid shifted legacy messages rejected (no fix); {invisible} gave a wrong satellite count only (a possible count inserted at numSV); the rest decode to the fix sent");
    assert!(rejected > 0 && invisible == 1);
}
