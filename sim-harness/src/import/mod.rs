//! Autopilot logs → the flight-log rows of docs/formats.md: PX4 ULog (`.ulg`), ArduPilot
//! DataFlash (`.bin`) and InertialNav's text exports of PX4 sdlog2 logs (`.zip` or a folder). Each format reader fills [`Streams`] (raw samples on the log's
//! own µs clock); [`assemble`] puts them on IMU rows. [`load_any`] is the one entry point
//! for csv, ulg and bin alike. Topic/field → column mappings: docs/import.md.

mod assemble;
pub mod dataflash;
pub mod inertialnav;
pub mod ulog;

pub use assemble::assemble;

use crate::log::FlightLog;
use anyhow::{bail, Context, Result};
use std::path::Path;

/// One IMU sample, body FRD.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuSample {
    /// Sample time, µs on the log's clock.
    pub t_us: u64,
    /// Angular rate, rad/s.
    pub gyro: [f64; 3],
    /// Specific force, m/s².
    pub accel: [f64; 3],
}

/// One GPS solution as the autopilot logged it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RawFix {
    /// When the autopilot received it, µs on the log's clock.
    pub arrival_us: u64,
    /// The fix's own epoch on the same clock, when the log has it (PX4 `timestamp_sample`).
    pub epoch_us: Option<u64>,
    /// NED velocity, m/s.
    pub vel: [f64; 3],
    /// Speed accuracy, m/s 1-σ.
    pub speed_acc: Option<f64>,
    /// Fix type in the common numbering (0–1 none, 2 2-D, 3 3-D, ≥ 4 DGPS/RTK).
    pub fix_type: u8,
    /// Latitude, longitude (deg) and height (m): above the WGS-84 ellipsoid where the log
    /// has it (PX4 `altitude_ellipsoid_m`), else above mean sea level (see docs/import.md).
    pub pos: Option<[f64; 3]>,
}

/// Everything a format reader extracted, before it is put on IMU rows.
#[derive(Debug, Clone, Default)]
pub struct Streams {
    /// IMU samples (any order; [`assemble`] sorts them).
    pub imu: Vec<ImuSample>,
    /// GPS solutions.
    pub gps: Vec<RawFix>,
    /// Airspeed (µs, m/s).
    pub airspeed: Vec<(u64, f64)>,
    /// Barometric altitude (µs, m; the autopilot's datum).
    pub baro: Vec<(u64, f64)>,
    /// The autopilot's own attitude (µs, [roll, pitch, yaw] rad, 3-2-1 Euler, NED/FRD).
    pub attitude: Vec<(u64, [f64; 3])>,
    /// What the reader chose and why (IMU instance, topic names, units), for the user.
    pub notes: Vec<String>,
}

/// What [`assemble`] did with the streams.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ImportSummary {
    /// Format and what the reader chose.
    pub notes: Vec<String>,
    /// IMU rows written.
    pub imu_rows: usize,
    /// IMU samples dropped: non-finite values.
    pub imu_nonfinite: usize,
    /// IMU samples dropped: a timestamp equal to the previous one.
    pub imu_duplicate_t: usize,
    /// GPS fixes placed on rows.
    pub gps_fixes: usize,
    /// Fixes dropped: below a 3-D fix or non-finite velocity.
    pub gps_no_3d: usize,
    /// Fixes dropped: a repeated epoch, or a later fix arriving on the same IMU row.
    pub gps_repeated: usize,
    /// Fixes outside the IMU's time span.
    pub gps_outside: usize,
    /// Fix rows that carry a position (`lat`, `lon`, `alt`).
    pub gps_positions: usize,
    /// Airspeed samples placed on rows.
    pub airspeed: usize,
    /// Barometric altitudes placed on rows.
    pub baro: usize,
    /// Rows with a reference attitude.
    pub reference_rows: usize,
    /// Mean IMU rate, Hz, and the smallest/largest interval, s.
    pub imu_rate_hz: f64,
    /// Smallest and largest IMU interval, s.
    pub imu_dt_range: [f64; 2],
    /// Median arrival − epoch of the fixes that carry an epoch, s.
    pub logged_gps_latency: Option<f64>,
    /// The log's first IMU time, µs (row t = (µs − this) / 10⁶).
    pub t0_us: u64,
}

impl ImportSummary {
    /// A few lines for the terminal.
    pub fn describe(&self) -> String {
        let mut s = String::new();
        for n in &self.notes {
            s.push_str("  ");
            s.push_str(n);
            s.push('\n');
        }
        s.push_str(&format!(
            "  IMU {} rows, {:.1} Hz mean, interval {:.4}–{:.4} s (dropped {} non-finite, {} repeated time)\n",
            self.imu_rows, self.imu_rate_hz, self.imu_dt_range[0], self.imu_dt_range[1], self.imu_nonfinite, self.imu_duplicate_t
        ));
        s.push_str(&format!(
            "  GPS {} fixes (dropped {} below 3-D, {} repeated or on the same row, {} outside the IMU span)",
            self.gps_fixes, self.gps_no_3d, self.gps_repeated, self.gps_outside
        ));
        s.push_str(&format!(", {} with position", self.gps_positions));
        if let Some(l) = self.logged_gps_latency {
            s.push_str(&format!("; logged arrival − epoch median {:.3} s", l));
        }
        s.push_str(&format!(
            "\n  airspeed {} samples, baro {} samples, reference attitude on {} rows",
            self.airspeed, self.baro, self.reference_rows
        ));
        s
    }
}

/// Which reader a path needs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Flight-log CSV (docs/formats.md).
    Csv,
    /// PX4 ULog.
    ULog,
    /// ArduPilot DataFlash binary.
    DataFlash,
    /// InertialNav text export (`IMU.txt`, `GPSraw.txt`, …), zipped or a directory.
    InertialNav,
}

/// The format from the file's first bytes (ULog magic, DataFlash header), else the extension.
pub fn detect(path: &Path) -> Result<Format> {
    use std::io::Read;
    if inertialnav::is_export(path) {
        return Ok(Format::InertialNav);
    }
    if path.is_dir() {
        bail!("{}: a folder, but not an InertialNav export (no IMU.txt)", path.display());
    }
    let mut head = [0u8; 8];
    let n = std::fs::File::open(path)
        .and_then(|mut f| f.read(&mut head))
        .with_context(|| format!("cannot open {}", path.display()))?;
    if n >= 7 && &head[..7] == b"ULog\x01\x12\x35" {
        return Ok(Format::ULog);
    }
    // DataFlash: every message starts A3 95, the first is a FMT (type 128).
    if n >= 3 && head[..3] == [0xA3, 0x95, 0x80] {
        return Ok(Format::DataFlash);
    }
    let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
    match ext.as_deref() {
        Some("csv") | None => Ok(Format::Csv),
        Some("ulg") => bail!("{}: not a ULog file (no ULog header)", path.display()),
        Some("bin") => bail!("{}: not a DataFlash log (no A3 95 FMT header)", path.display()),
        Some(_) => Ok(Format::Csv),
    }
}

/// Reads an autopilot log into streams (`.ulg` or `.bin`).
pub fn read_streams(path: &Path) -> Result<Streams> {
    match detect(path)? {
        Format::ULog => ulog::read(path),
        Format::DataFlash => dataflash::read(path),
        Format::InertialNav => inertialnav::read(path),
        Format::Csv => bail!("{}: a CSV flight log, not an autopilot log", path.display()),
    }
}

/// Imports an autopilot log: rows plus what was done.
pub fn import(path: &Path) -> Result<(FlightLog, ImportSummary)> {
    let s = read_streams(path)?;
    assemble(s).with_context(|| format!("importing {}", path.display()))
}

/// Any flight log the harness accepts: a docs/formats.md CSV, a PX4 `.ulg`, an ArduPilot
/// `.bin` or an InertialNav export (`.zip`).
pub fn load_any(path: &Path) -> Result<FlightLog> {
    match detect(path)? {
        Format::Csv => crate::csv::read_log(path),
        _ => Ok(import(path)?.0),
    }
}

/// Whether a report/compare item names a log file (rather than a scenario).
pub fn is_log_path(item: &str) -> bool {
    let p = Path::new(item);
    p.extension().is_some_and(|e| {
        let e = e.to_string_lossy().to_ascii_lowercase();
        e == "csv" || e == "ulg" || e == "bin" || e == "zip"
    }) || item.to_ascii_lowercase().ends_with(".csv.gz")
        || inertialnav::is_export(p)
}
