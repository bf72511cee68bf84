//! InertialNav text exports: the whitespace-separated `IMU.txt`, `GPSraw.txt`, `NTUN.txt`
//! and `ATT.txt` that Paul Riseborough's InertialNav test harness reads, as written by its
//! `scripts/LoadPX4StackData.m` from PX4 sdlog2 logs (the shared data's `real/raw/*.zip`:
//! the 2014 PX4 fixed-wing flights a and b). A `.zip` of them or a directory holding them.
//! Hand-written: the format is four numeric tables, one line per sample; no crate reads it.
//!
//! Columns (docs/import.md): IMU `t_ms t_ms gx gy gz ax ay az` (rad/s, m/s², FRD); GPSraw
//! `t_ms lat lon alt vN vE vD` (deg, m, m/s; 3-D fixes only, the exporter dropped the
//! rest); NTUN column 8 the equivalent airspeed (m/s; all zero when the log had none) and
//! column 9 the barometric height (m); ATT `t_ms t_ms roll pitch yaw` (deg), the PX4
//! onboard attitude (sdlog2 `ATT`).

use super::{ImuSample, RawFix, Streams};
use anyhow::{bail, Context, Result};
use std::io::Read;
use std::path::Path;

/// The files an export must hold.
const REQUIRED: [&str; 2] = ["IMU.txt", "GPSraw.txt"];

/// Every file InertialNav's exporter writes (the ones read and the ones not).
pub const FILES: [&str; 10] = [
    "IMU.txt",
    "GPSraw.txt",
    "NTUN.txt",
    "ATT.txt",
    "GPS.txt",
    "MAG.txt",
    "GPOSonboard.txt",
    "timing.txt",
    "FLOW.txt",
    "DIST.txt",
];

/// Whether `path` is an InertialNav export: a directory with `IMU.txt`, or a `.zip`.
pub fn is_export(path: &Path) -> bool {
    if path.is_dir() {
        return path.join("IMU.txt").is_file();
    }
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("zip"))
}

/// Reads an export into streams.
pub fn read(path: &Path) -> Result<Streams> {
    let mut files = Files::open(path)?;
    for f in REQUIRED {
        if !files.has(f) {
            bail!("{}: not an InertialNav export (no {f})", path.display());
        }
    }
    let mut s = Streams::default();
    s.notes.push(format!(
        "InertialNav text export ({}): IMU.txt, GPSraw.txt, NTUN.txt airspeed and baro, ATT.txt as the reference",
        if path.is_dir() { "directory" } else { "zip" }
    ));
    let ms = |v: f64| -> Result<u64> {
        if v.is_finite() && v >= 0.0 {
            Ok((v * 1e3).round() as u64)
        } else {
            bail!("time {v} ms is not a non-negative number")
        }
    };
    for (i, r) in table(&mut files, "IMU.txt", 8)?.unwrap_or_default().iter().enumerate() {
        let t_us = ms(r[1]).with_context(|| format!("IMU.txt line {}", i + 1))?;
        s.imu.push(ImuSample { t_us, gyro: [r[2], r[3], r[4]], accel: [r[5], r[6], r[7]] });
    }
    for (i, r) in table(&mut files, "GPSraw.txt", 7)?.unwrap_or_default().iter().enumerate() {
        let arrival_us = ms(r[0]).with_context(|| format!("GPSraw.txt line {}", i + 1))?;
        s.gps.push(RawFix {
            arrival_us,
            epoch_us: None,
            vel: [r[4], r[5], r[6]],
            speed_acc: None,
            fix_type: 3,
            pos: Some([r[1], r[2], r[3]]),
        });
    }
    if let Some(rows) = table(&mut files, "NTUN.txt", 9)? {
        // The exporter writes zeros when the log had no airspeed topic.
        let has_airspeed = rows.iter().any(|r| r[7] != 0.0);
        for r in &rows {
            let t = ms(r[1])?;
            if has_airspeed {
                s.airspeed.push((t, r[7]));
            }
            s.baro.push((t, r[8]));
        }
        if !has_airspeed {
            s.notes.push("NTUN.txt: airspeed all zero (no airspeed sensor in the log)".into());
        }
    }
    if let Some(rows) = table(&mut files, "ATT.txt", 5)? {
        for r in rows {
            s.attitude.push((ms(r[1])?, [r[2].to_radians(), r[3].to_radians(), r[4].to_radians()]));
        }
    }
    Ok(s)
}

/// The export's files: a directory or the members of a zip.
enum Files {
    Dir(std::path::PathBuf),
    Zip(zip::ZipArchive<std::fs::File>, std::path::PathBuf),
}

impl Files {
    fn open(path: &Path) -> Result<Files> {
        if path.is_dir() {
            return Ok(Files::Dir(path.to_path_buf()));
        }
        let f =
            std::fs::File::open(path).with_context(|| format!("cannot open {}", path.display()))?;
        let z = zip::ZipArchive::new(f)
            .with_context(|| format!("{}: not a zip archive", path.display()))?;
        Ok(Files::Zip(z, path.to_path_buf()))
    }

    /// The index of the zip member `name`, in the archive's root or a folder inside it.
    fn member(z: &zip::ZipArchive<std::fs::File>, name: &str) -> Option<usize> {
        (0..z.len()).find(|&i| {
            z.name_for_index(i)
                .is_some_and(|n| n.is_ok_and(|n| n == name || n.ends_with(&format!("/{name}"))))
        })
    }

    /// Whether the export holds `name` (nothing is read).
    fn has(&self, name: &str) -> bool {
        match self {
            Files::Dir(d) => d.join(name).is_file(),
            Files::Zip(z, _) => Self::member(z, name).is_some(),
        }
    }

    /// A member's text, `None` when absent.
    fn get(&mut self, name: &str) -> Result<Option<String>> {
        match self {
            Files::Dir(d) => {
                let p = d.join(name);
                if !p.is_file() {
                    return Ok(None);
                }
                let text = std::fs::read_to_string(&p)
                    .with_context(|| format!("cannot read {}", p.display()))?;
                Ok(Some(text))
            }
            Files::Zip(z, path) => {
                let Some(idx) = Self::member(z, name) else { return Ok(None) };
                let mut text = String::new();
                z.by_index(idx)
                    .with_context(|| format!("{}: member {name}", path.display()))?
                    .read_to_string(&mut text)
                    .with_context(|| format!("{}: member {name} is not text", path.display()))?;
                Ok(Some(text))
            }
        }
    }
}

/// A numeric table, each non-empty line with at least `cols` numbers; `None` when the
/// export has no such file.
fn table(files: &mut Files, name: &str, cols: usize) -> Result<Option<Vec<Vec<f64>>>> {
    let Some(text) = files.get(name)? else { return Ok(None) };
    let mut rows = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let r: Vec<f64> = line
            .split_whitespace()
            .map(str::parse)
            .collect::<Result<_, _>>()
            .with_context(|| format!("{name} line {}: not numbers", i + 1))?;
        if r.len() < cols {
            bail!("{name} line {}: {} columns, at least {cols} expected", i + 1, r.len());
        }
        rows.push(r);
    }
    Ok(Some(rows))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir_with(files: &[(&str, &str)]) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("inav-{}-{}", std::process::id(), files.len()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        for (n, t) in files {
            std::fs::write(d.join(n), t).unwrap();
        }
        d
    }

    #[test]
    fn columns_map_to_streams() {
        let d = dir_with(&[
            ("IMU.txt", " 0 0 0.1 0.2 0.3 1 2 -9\n 10 10 0.1 0.2 0.3 1 2 -9\n"),
            ("GPSraw.txt", " 5 47.3 8.0 400 1.5 -2.5 0.5\n"),
            ("NTUN.txt", " 5 5 0 0 0 0 0 12.5 420 0\n"),
            ("ATT.txt", " 10 10 -3 6 90 0 0\n"),
        ]);
        assert!(is_export(&d));
        let s = read(&d).unwrap();
        assert_eq!(s.imu.len(), 2);
        assert_eq!(s.imu[1].t_us, 10_000);
        assert_eq!(s.imu[0].gyro, [0.1, 0.2, 0.3]);
        assert_eq!(s.imu[0].accel, [1.0, 2.0, -9.0]);
        assert_eq!(s.gps[0].arrival_us, 5_000);
        assert_eq!(s.gps[0].vel, [1.5, -2.5, 0.5]);
        assert_eq!(s.gps[0].pos, Some([47.3, 8.0, 400.0]));
        assert_eq!(s.airspeed, vec![(5_000, 12.5)]);
        assert_eq!(s.baro, vec![(5_000, 420.0)]);
        let a = s.attitude[0].1;
        assert!(
            (a[0] + 3f64.to_radians()).abs() < 1e-12 && (a[2] - 90f64.to_radians()).abs() < 1e-12
        );
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn bad_exports_are_errors() {
        let d = dir_with(&[("IMU.txt", " 0 0 0.1 0.2\n")]);
        assert!(read(&d).unwrap_err().to_string().contains("GPSraw.txt"));
        std::fs::write(d.join("GPSraw.txt"), "").unwrap();
        let e = format!("{:#}", read(&d).unwrap_err());
        assert!(e.contains("IMU.txt line 1") && e.contains("8 expected"), "{e}");
        std::fs::write(d.join("IMU.txt"), " 0 0 x 0 0 0 0 0\n").unwrap();
        assert!(format!("{:#}", read(&d).unwrap_err()).contains("not numbers"));
        let _ = std::fs::remove_dir_all(&d);
    }
}
