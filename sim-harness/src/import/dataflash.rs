//! ArduPilot DataFlash (`.bin`) reader (the `ardupilot-binlog` crate: schemas from the
//! log's own FMT messages, so any firmware version reads).
//!
//! Messages: `IMU` (instance 0: `I` = 0, or the unnumbered `IMU` of older logs with
//! `IMU2`/`IMU3`), `GPS` + `GPA` (instance 0), `ARSP` (instance 0), `BARO` (instance 0),
//! `ATT` (the AHRS attitude the autopilot flew on; where a log has none, EKF3's `XKF1`
//! core 0, else EKF2's `NKF1` core 0, else the secondary AHRS `AHR2`). Mapping and units:
//! docs/import.md.

use super::{ImuSample, RawFix, Streams};
use anyhow::{bail, Context, Result};
use ardupilot_binlog::{Entry, Reader};
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

const DEG: f64 = std::f64::consts::PI / 180.0;

/// (message, instance) from the name and the `I` field: `IMU2` → ("IMU", 1).
fn msg_instance(e: &Entry) -> (&str, u8) {
    let name = e.name.as_str();
    let inst = e.get_i64("I").map(|i| i.clamp(0, 255) as u8);
    for base in ["IMU", "GPS", "GPA", "ARSP", "BARO"] {
        if let Some(rest) = name.strip_prefix(base) {
            if rest.is_empty() {
                return (base, inst.unwrap_or(0));
            }
            if let Ok(n) = rest.parse::<u8>() {
                return (base, n.saturating_sub(1));
            }
        }
    }
    (name, inst.unwrap_or(0))
}

/// Reference attitude messages, most preferred first, with what each one is.
const REFERENCES: [(&str, &str); 4] = [
    ("ATT", "`ATT` Roll/Pitch/Yaw (the autopilot's AHRS, not truth)"),
    ("XKF1", "`XKF1` core 0 Roll/Pitch/Yaw (EKF3, the log has no `ATT`; not truth)"),
    ("NKF1", "`NKF1` core 0 Roll/Pitch/Yaw (EKF2, the log has no `ATT`; not truth)"),
    ("AHR2", "`AHR2` Roll/Pitch/Yaw (the secondary AHRS, the log has no `ATT`; not truth)"),
];

fn f(e: &Entry, field: &str) -> Option<f64> {
    e.get_f64(field)
}

/// ArduPilot's board-level trim `AHRS_TRIM_X`/`_Y` (rad), reported, not applied. Its AHRS
/// (and so the `ATT` reference) rotates its output by it, but on the real aerobatic logs
/// tried (docs/real-logs.md) the trim stands in for an accelerometer offset: rotating the
/// IMU by it matches `ATT` upright and doubles the difference inverted.
fn board_trim_note(params: &HashMap<String, f64>) -> Option<String> {
    let x = params.get("AHRS_TRIM_X").copied().unwrap_or(0.0);
    let y = params.get("AHRS_TRIM_Y").copied().unwrap_or(0.0);
    (x != 0.0 || y != 0.0).then(|| {
        format!(
            "autopilot's board trim AHRS_TRIM_X/Y = {:.2}°/{:.2}°: its reference attitude includes it; the IMU is not rotated by it",
            x / DEG,
            y / DEG
        )
    })
}

/// Reads a DataFlash log into streams.
pub fn read(path: &Path) -> Result<Streams> {
    let file = std::fs::File::open(path)
        .with_context(|| format!("cannot open DataFlash log {}", path.display()))?;
    let reader = Reader::new(std::io::BufReader::new(file));
    let mut s = Streams::default();
    let mut imu_inst: BTreeMap<u8, usize> = BTreeMap::new();
    let mut gpa: HashMap<u64, f64> = HashMap::new();
    let mut gps: Vec<RawFix> = Vec::new();
    let mut params: HashMap<String, f64> = HashMap::new();
    let mut version = None;
    let mut bad = 0usize;
    // Reference attitude candidates, in order of preference (see `REFERENCES`).
    let mut refs: [Vec<(u64, [f64; 3])>; 4] = Default::default();
    for r in reader {
        let e = match r {
            Ok(e) => e,
            Err(_) => {
                bad += 1;
                continue;
            }
        };
        // Parameters, with or without a time stamp (older logs write `PARM` without one).
        if e.name == "PARM" {
            if let (Some(n), Some(v)) = (e.get_str("Name"), f(&e, "Value")) {
                params.insert(n.to_string(), v);
            }
            continue;
        }
        // ArduPilot ≤ 3.2 logged GPS with the time of week as `TimeMS` and the boot time as
        // `T` (ms): its arrival time is `T`, on the IMU's clock.
        let boot_t = (e.name == "GPS" && f(&e, "TimeUS").is_none())
            .then(|| f(&e, "T"))
            .flatten()
            .filter(|ms| *ms >= 0.0)
            .map(|ms| (ms * 1e3) as u64);
        // The firmware string: old logs write `MSG` without a time stamp.
        if version.is_none() && (e.name == "VER" || e.name == "MSG") {
            if let Some(m) = e.get_str("Message").or_else(|| e.get_str("FWS")) {
                if m.starts_with("Ardu") || m.starts_with("APM:") {
                    version = Some(m.to_string());
                }
            }
        }
        let Some(t) = boot_t.or(e.timestamp_usec) else {
            continue;
        };
        let (name, inst) = msg_instance(&e);
        match name {
            "IMU" => {
                *imu_inst.entry(inst).or_default() += 1;
                if inst != 0 {
                    continue;
                }
                let v = |k: &str| f(&e, k).unwrap_or(f64::NAN);
                s.imu.push(ImuSample {
                    t_us: t,
                    gyro: [v("GyrX"), v("GyrY"), v("GyrZ")],
                    accel: [v("AccX"), v("AccY"), v("AccZ")],
                });
            }
            "GPS" if inst == 0 => {
                let v = |k: &str| f(&e, k).unwrap_or(f64::NAN);
                let (spd, crs) = (v("Spd"), v("GCrs") * DEG);
                let pos = match (f(&e, "Lat"), f(&e, "Lng"), f(&e, "Alt")) {
                    (Some(a), Some(b), Some(c)) => Some([a * 1e-7, b * 1e-7, c]),
                    _ => None,
                };
                gps.push(RawFix {
                    arrival_us: t,
                    epoch_us: None,
                    vel: [spd * crs.cos(), spd * crs.sin(), v("VZ")],
                    speed_acc: None,
                    fix_type: f(&e, "Status").unwrap_or(0.0).clamp(0.0, 255.0) as u8,
                    pos,
                });
            }
            "GPA" if inst == 0 => {
                if let Some(a) = f(&e, "SAcc") {
                    gpa.insert(t, a);
                }
            }
            "BARO" if inst == 0 => {
                if let Some(h) = f(&e, "Alt") {
                    s.baro.push((t, h));
                }
            }
            "ARSP" if inst == 0 => {
                if let Some(v) = f(&e, "Airspeed") {
                    s.airspeed.push((t, v));
                }
            }
            "ATT" | "XKF1" | "NKF1" | "AHR2" => {
                // EKF messages carry one core each (`C`); core 0 is the first IMU's.
                if e.get_i64("C").unwrap_or(0) != 0 {
                    continue;
                }
                let k = REFERENCES.iter().position(|(m, _)| *m == name).unwrap_or(0);
                if let (Some(r), Some(p), Some(y)) = (f(&e, "Roll"), f(&e, "Pitch"), f(&e, "Yaw")) {
                    let y = crate::metrics::wrap(y * DEG);
                    refs[k].push((t, [r * DEG, p * DEG, y]));
                }
            }
            _ => {}
        }
    }
    // GPA (accuracies) is written with the same time stamp as its GPS message.
    for g in &mut gps {
        g.speed_acc = gpa.get(&g.arrival_us).copied();
    }
    s.gps = gps;
    s.notes.push(format!(
        "ArduPilot DataFlash{}{}",
        version.map_or(String::new(), |v| format!(" ({v})")),
        if bad > 0 { format!(", {bad} unreadable messages skipped") } else { String::new() }
    ));
    if imu_inst.is_empty() {
        bail!("{}: no IMU messages (the log was recorded without IMU logging)", path.display());
    }
    s.notes.push(format!(
        "IMU: instance 0 of {} ({})",
        imu_inst.len(),
        imu_inst.iter().map(|(i, n)| format!("#{i}: {n}")).collect::<Vec<_>>().join(", ")
    ));
    s.notes.push(
        "GPS: `GPS` instance 0, velocity from Spd/GCrs/VZ, no epoch in the log (arrival time)"
            .into(),
    );
    if let Some(note) = board_trim_note(&params) {
        s.notes.push(note);
    }
    for k in ["GPS_DELAY_MS", "GPS1_DELAY_MS", "GPS_DELAY_MS1"] {
        if let Some(v) = params.get(k) {
            s.notes.push(format!("autopilot's assumed GPS lag: {k} = {v} ms"));
        }
    }
    if !s.baro.is_empty() {
        s.notes.push(
            "baro: `BARO` instance 0 `Alt` (relative to the autopilot's ground level)".into(),
        );
    }
    match refs.iter().position(|r| !r.is_empty()) {
        Some(k) => {
            s.attitude = std::mem::take(&mut refs[k]);
            s.notes.push(format!("reference: {}", REFERENCES[k].1));
        }
        None => s.notes.push("reference: none (no ATT, XKF1, NKF1 or AHR2 messages)".into()),
    }
    Ok(s)
}
