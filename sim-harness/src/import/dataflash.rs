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

/// How an ArduPilot attitude message carries the board trim `AHRS_TRIM_X/Y/Z` (rad): its
/// attitude is of the "vehicle body", the IMU's axes turned by the trim. Our estimate is
/// the IMU's attitude (the IMU is not rotated on import), so the reference is turned back.
#[derive(Debug, Clone, Copy, PartialEq)]
enum TrimConvention {
    /// EKF2/EKF3 (`XKF1`, `NKF1`, and `ATT` when an EKF is the AHRS, `AHRS_EKF_TYPE` 2 or
    /// 3): the IMU's Euler angles minus the trim, angle by angle
    /// (`NavEKF3_core::getEulerAngles`) — not a rotation: inverted, the pitch trim keeps
    /// its sign.
    EulerMinus,
    /// DCM (`AHR2` beside an EKF, `ATT` otherwise): the IMU's attitude rotated by the
    /// trim's roll and pitch, `R_NB,vehicle = R_NB,IMU · R_NB(trim)ᵀ`.
    Rotation,
}

impl TrimConvention {
    /// The convention of reference message `name` in a log with these parameters.
    fn of(name: &str, params: &HashMap<String, f64>) -> Self {
        let ekf_ahrs = matches!(params.get("AHRS_EKF_TYPE"), Some(t) if *t == 2.0 || *t == 3.0);
        match name {
            "XKF1" | "NKF1" => TrimConvention::EulerMinus,
            "ATT" if ekf_ahrs => TrimConvention::EulerMinus,
            _ => TrimConvention::Rotation,
        }
    }

    /// The IMU's 3-2-1 Euler angles (rad) from a reference's, given the trim (rad).
    fn to_imu(self, trim: [f64; 3], e: [f64; 3]) -> [f64; 3] {
        use crate::sim::rotation::{mul_mm, r_bn};
        match self {
            TrimConvention::EulerMinus => {
                [e[0] + trim[0], e[1] + trim[1], crate::metrics::wrap(e[2] + trim[2])]
            }
            TrimConvention::Rotation => {
                // R_BN,IMU = R_BN(trim) · R_BN,vehicle.
                let r = mul_mm(&r_bn(trim[0], trim[1], 0.0), &r_bn(e[0], e[1], e[2]));
                [r[1][2].atan2(r[2][2]), (-r[0][2]).clamp(-1.0, 1.0).asin(), r[0][1].atan2(r[0][0])]
            }
        }
    }
}

/// The board trim `AHRS_TRIM_X/Y/Z`, rad (zero where the log has none).
fn board_trim(params: &HashMap<String, f64>) -> [f64; 3] {
    ["AHRS_TRIM_X", "AHRS_TRIM_Y", "AHRS_TRIM_Z"].map(|k| params.get(k).copied().unwrap_or(0.0))
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
            let trim = board_trim(&params);
            let conv = TrimConvention::of(REFERENCES[k].0, &params);
            s.attitude = std::mem::take(&mut refs[k]);
            s.notes.push(format!("reference: {}", REFERENCES[k].1));
            if trim != [0.0; 3] {
                for (_, e) in &mut s.attitude {
                    *e = conv.to_imu(trim, *e);
                }
                s.notes.push(format!(
                    "reference turned back from the vehicle body to the IMU's axes by the board trim AHRS_TRIM_X/Y/Z = {:.2}°/{:.2}°/{:.2}° ({}); the IMU is not rotated",
                    trim[0] / DEG,
                    trim[1] / DEG,
                    trim[2] / DEG,
                    match conv {
                        TrimConvention::EulerMinus => "the EKF's convention: Euler angles plus the trim",
                        TrimConvention::Rotation => "the DCM's convention: a rotation",
                    }
                ));
            }
        }
        None => s.notes.push("reference: none (no ATT, XKF1, NKF1 or AHR2 messages)".into()),
    }
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::attitude_error;
    use crate::sim::rotation::{mul_mm, r_bn};

    /// 3-2-1 Euler angles of an `R_BN`.
    fn euler(r: [[f64; 3]; 3]) -> [f64; 3] {
        [r[1][2].atan2(r[2][2]), (-r[0][2]).asin(), r[0][1].atan2(r[0][0])]
    }

    fn attitudes() -> Vec<[f64; 3]> {
        let mut v = Vec::new();
        for roll in [-179.0, -120.0, -30.0, 0.0, 45.0, 170.0f64] {
            for pitch in [-80.0, -20.0, 0.0, 35.0, 85.0f64] {
                for yaw in [-150.0, 10.0, 100.0f64] {
                    v.push([roll.to_radians(), pitch.to_radians(), yaw.to_radians()]);
                }
            }
        }
        v
    }

    /// The DCM convention, forward as ArduPilot's AHRS writes it (`R_NB,vehicle =
    /// R_NB,IMU · R_NB(trim)ᵀ`, i.e. `R_BN,vehicle = R_BN(trim)ᵀ · R_BN,IMU`), then undone:
    /// the IMU's attitude again, upright, inverted and near vertical.
    #[test]
    fn rotation_convention_undoes_the_ahrs_trim() {
        let trim = [0.02, 0.06, 0.0];
        let t = r_bn(trim[0], trim[1], 0.0);
        let tt = [0, 1, 2].map(|i| [0, 1, 2].map(|j| t[j][i]));
        for imu in attitudes() {
            let vehicle = euler(mul_mm(&tt, &r_bn(imu[0], imu[1], imu[2])));
            let back = TrimConvention::Rotation.to_imu(trim, vehicle);
            assert!(attitude_error(back, imu) < 1e-9, "{imu:?} → {vehicle:?} → {back:?}");
            // It is a rotation: the vehicle attitude is the trim's angle away.
            let a = attitude_error(vehicle, imu);
            assert!((a - (trim[0].hypot(trim[1]))).abs() < 1e-3, "{a}");
        }
    }

    /// The EKF convention (`euler − trim`, angle by angle) undone; and it is not a
    /// rotation: inverted, the pitch trim keeps its sign in Euler pitch.
    #[test]
    fn euler_convention_adds_the_trim_back() {
        let trim = [0.01, 0.06, 0.0];
        for imu in attitudes() {
            let reported = [imu[0] - trim[0], imu[1] - trim[1], imu[2] - trim[2]];
            let back = TrimConvention::EulerMinus.to_imu(trim, reported);
            assert!(attitude_error(back, imu) < 1e-12, "{imu:?} → {back:?}");
        }
        let mut params = HashMap::new();
        assert_eq!(TrimConvention::of("ATT", &params), TrimConvention::Rotation);
        assert_eq!(TrimConvention::of("XKF1", &params), TrimConvention::EulerMinus);
        params.insert("AHRS_EKF_TYPE".to_string(), 3.0);
        assert_eq!(TrimConvention::of("ATT", &params), TrimConvention::EulerMinus);
        assert_eq!(TrimConvention::of("AHR2", &params), TrimConvention::Rotation);
    }
}
