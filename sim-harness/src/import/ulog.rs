//! PX4 ULog reader (the `px4-ulog` crate, PX4's own Rust parser; columnar full parse).
//!
//! Topics: `sensor_combined` (PX4's selected IMU, gyro and accel in body FRD),
//! `vehicle_gps_position` (the selected/blended receiver; `sensor_gps` when it is absent),
//! `airspeed` (else `airspeed_validated`), `vehicle_air_data` (baro altitude; else
//! `sensor_baro`'s pressure through the standard atmosphere is not attempted),
//! `vehicle_attitude` (the autopilot's EKF2 quaternion). Mapping and units: docs/import.md.

use super::{ImuSample, RawFix, Streams};
use anyhow::{anyhow, bail, Context, Result};
use px4_ulog::full_parser::{read_file, SomeVec};
use std::collections::HashMap;
use std::path::Path;

type Fields = HashMap<String, SomeVec>;

/// A column as f64, whatever its stored type.
fn col(f: &Fields, name: &str) -> Option<Vec<f64>> {
    Some(match f.get(name)? {
        SomeVec::Int8(v) => v.iter().map(|&x| x as f64).collect(),
        SomeVec::UInt8(v) => v.iter().map(|&x| x as f64).collect(),
        SomeVec::Int16(v) => v.iter().map(|&x| x as f64).collect(),
        SomeVec::UInt16(v) => v.iter().map(|&x| x as f64).collect(),
        SomeVec::Int32(v) => v.iter().map(|&x| x as f64).collect(),
        SomeVec::UInt32(v) => v.iter().map(|&x| x as f64).collect(),
        SomeVec::Int64(v) => v.iter().map(|&x| x as f64).collect(),
        SomeVec::Float(v) => v.iter().map(|&x| x as f64).collect(),
        SomeVec::Double(v) => v.clone(),
        SomeVec::Bool(v) => v.iter().map(|&x| x as u8 as f64).collect(),
        SomeVec::UInt64(v) => v.iter().map(|&x| x as f64).collect(),
        SomeVec::Char(_) => return None,
    })
}

/// A µs timestamp column (kept integral: f64 would round past 2⁵³ µs).
fn col_us(f: &Fields, name: &str) -> Option<Vec<u64>> {
    match f.get(name)? {
        SomeVec::UInt64(v) => Some(v.clone()),
        _ => col(f, name).map(|v| v.iter().map(|&x| x.max(0.0) as u64).collect()),
    }
}

fn need(f: &Fields, topic: &str, name: &str) -> Result<Vec<f64>> {
    col(f, name).ok_or_else(|| anyhow!("topic `{topic}` has no field `{name}`"))
}

/// Instance 0 of a topic (the primary), noting how many instances the log has.
fn instance<'a>(
    msgs: &'a HashMap<String, HashMap<px4_ulog::full_parser::MultiId, Fields>>,
    topic: &str,
    notes: &mut Vec<String>,
) -> Option<&'a Fields> {
    let inst = msgs.get(topic)?;
    let mut ids: Vec<u8> = inst.keys().map(|k| k.value()).collect();
    ids.sort_unstable();
    if ids.len() > 1 {
        notes.push(format!("`{topic}`: {} instances {ids:?}, instance {} used", ids.len(), ids[0]));
    }
    inst.iter().find(|(k, _)| k.value() == ids[0]).map(|(_, v)| v)
}

/// Reads a ULog file into streams.
pub fn read(path: &Path) -> Result<Streams> {
    let p = path.to_str().with_context(|| format!("{}: path is not UTF-8", path.display()))?;
    // The crate can panic on a schema it does not expect; a host tool reports, not aborts.
    let parsed = std::panic::catch_unwind(|| read_file(p))
        .map_err(|_| anyhow!("{}: the ULog parser failed on this file", path.display()))?
        .with_context(|| format!("{}: not a readable ULog file", path.display()))?;
    let mut s = Streams::default();
    s.notes.push(format!("PX4 ULog ({:?})", parsed.completeness));
    let msgs = &parsed.messages;

    let imu = instance(msgs, "sensor_combined", &mut s.notes)
        .with_context(|| format!("{}: no `sensor_combined` topic (IMU)", path.display()))?;
    let t = col_us(imu, "timestamp").context("sensor_combined: no timestamp")?;
    let g: Vec<Vec<f64>> = (0..3)
        .map(|i| need(imu, "sensor_combined", &format!("gyro_rad[{i}]")))
        .collect::<Result<_>>()?;
    let a: Vec<Vec<f64>> = (0..3)
        .map(|i| need(imu, "sensor_combined", &format!("accelerometer_m_s2[{i}]")))
        .collect::<Result<_>>()?;
    s.imu = (0..t.len())
        .map(|k| ImuSample {
            t_us: t[k],
            gyro: [g[0][k], g[1][k], g[2][k]],
            accel: [a[0][k], a[1][k], a[2][k]],
        })
        .collect();
    s.notes.push("IMU: `sensor_combined` (PX4's primary IMU), gyro time stamps".into());

    let gps_topic =
        ["vehicle_gps_position", "sensor_gps"].into_iter().find(|t| msgs.contains_key(*t));
    if let Some(topic) = gps_topic {
        let f = instance(msgs, topic, &mut s.notes).expect("present");
        s.gps = read_gps(f, topic)?;
        s.notes.push(format!("GPS: `{topic}`"));
    } else {
        s.notes.push("GPS: none in the log".into());
    }

    for topic in ["airspeed", "airspeed_validated"] {
        let Some(f) = instance(msgs, topic, &mut s.notes) else { continue };
        let (Some(t), Some(v)) = (col_us(f, "timestamp"), col(f, "true_airspeed_m_s")) else {
            continue;
        };
        s.airspeed = t.into_iter().zip(v).collect();
        s.notes.push(format!("airspeed: `{topic}.true_airspeed_m_s`"));
        break;
    }

    if let Some(f) = instance(msgs, "vehicle_air_data", &mut s.notes) {
        let t = col_us(f, "timestamp_sample").or_else(|| col_us(f, "timestamp"));
        if let (Some(t), Some(h)) = (t, col(f, "baro_alt_meter")) {
            s.baro = t.into_iter().zip(h).collect();
            s.notes.push("baro: `vehicle_air_data.baro_alt_meter`".into());
        }
    }

    if let Some(f) = instance(msgs, "vehicle_attitude", &mut s.notes) {
        let t = col_us(f, "timestamp_sample").or_else(|| col_us(f, "timestamp"));
        let q: Option<Vec<Vec<f64>>> = (0..4).map(|i| col(f, &format!("q[{i}]"))).collect();
        if let (Some(t), Some(q)) = (t, q) {
            s.attitude = (0..t.len())
                .map(|k| (t[k], quat_to_euler([q[0][k], q[1][k], q[2][k], q[3][k]])))
                .collect();
            s.notes.push("reference: `vehicle_attitude.q` (PX4 EKF2's estimate, not truth)".into());
        }
    }
    if s.imu.is_empty() {
        bail!("{}: `sensor_combined` has no samples", path.display());
    }
    Ok(s)
}

fn read_gps(f: &Fields, topic: &str) -> Result<Vec<RawFix>> {
    let t = col_us(f, "timestamp").with_context(|| format!("{topic}: no timestamp"))?;
    let epoch = col_us(f, "timestamp_sample");
    let v: Vec<Vec<f64>> = ["vel_n_m_s", "vel_e_m_s", "vel_d_m_s"]
        .iter()
        .map(|n| need(f, topic, n))
        .collect::<Result<_>>()?;
    let fix = need(f, topic, "fix_type")?;
    let valid = col(f, "vel_ned_valid");
    let sacc = col(f, "s_variance_m_s"); // despite the name, a 1-σ speed accuracy in m/s
    let pos = read_position(f);
    Ok((0..t.len())
        .map(|k| {
            let vel_ok = valid.as_ref().is_none_or(|v| v[k] != 0.0);
            RawFix {
                arrival_us: t[k],
                epoch_us: epoch.as_ref().map(|e| e[k]).filter(|&e| e > 0 && e <= t[k]),
                vel: [v[0][k], v[1][k], v[2][k]],
                speed_acc: sacc.as_ref().map(|s| s[k]),
                // No NED velocity: not usable for attitude, whatever the fix type.
                fix_type: if vel_ok { fix[k].clamp(0.0, 255.0) as u8 } else { 0 },
                pos: pos.as_ref().map(|p| [p[0][k], p[1][k], p[2][k]]),
            }
        })
        .collect())
}

/// Fix positions: newer PX4 logs degrees and metres, older 1e-7 deg and mm. The height is
/// the ellipsoid's where logged (WGS-84, as the CSV wants), else above mean sea level.
fn read_position(f: &Fields) -> Option<[Vec<f64>; 3]> {
    let scaled = |v: Vec<f64>, k: f64| v.iter().map(|x| x * k).collect::<Vec<f64>>();
    if let (Some(a), Some(b)) = (col(f, "latitude_deg"), col(f, "longitude_deg")) {
        let h = col(f, "altitude_ellipsoid_m").or_else(|| col(f, "altitude_msl_m"))?;
        return Some([a, b, h]);
    }
    let (a, b) = (col(f, "lat")?, col(f, "lon")?);
    let h = col(f, "alt_ellipsoid").or_else(|| col(f, "alt"))?;
    Some([scaled(a, 1e-7), scaled(b, 1e-7), scaled(h, 1e-3)])
}

/// PX4 quaternion (w, x, y, z; body FRD → NED) → 3-2-1 Euler (roll, pitch, yaw), rad.
pub fn quat_to_euler(q: [f64; 4]) -> [f64; 3] {
    let [w, x, y, z] = q;
    let n = (w * w + x * x + y * y + z * z).sqrt();
    let (w, x, y, z) = (w / n, x / n, y / n, z / n);
    let roll = (2.0 * (w * x + y * z)).atan2(1.0 - 2.0 * (x * x + y * y));
    let pitch = (2.0 * (w * y - z * x)).clamp(-1.0, 1.0).asin();
    let yaw = (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z));
    [roll, pitch, yaw]
}

#[cfg(test)]
mod tests {
    use super::quat_to_euler;

    /// Against the 3-2-1 composition q = qz(ψ)·qy(θ)·qx(φ) built from half angles.
    #[test]
    fn quaternion_to_euler_inverts_the_321_composition() {
        for &(r, p, y) in &[(0.3, -0.2, 2.5), (-1.0, 0.7, -3.0), (0.0, 0.0, 0.0)] {
            let (cr, sr) = ((r / 2.0_f64).cos(), (r / 2.0_f64).sin());
            let (cp, sp) = ((p / 2.0_f64).cos(), (p / 2.0_f64).sin());
            let (cy, sy) = ((y / 2.0_f64).cos(), (y / 2.0_f64).sin());
            let q = [
                cr * cp * cy + sr * sp * sy,
                sr * cp * cy - cr * sp * sy,
                cr * sp * cy + sr * cp * sy,
                cr * cp * sy - sr * sp * cy,
            ];
            let e = quat_to_euler(q);
            for (a, b) in e.iter().zip([r, p, y]) {
                assert!((a - b).abs() < 1e-12, "{e:?} vs {:?}", (r, p, y));
            }
        }
    }
}
