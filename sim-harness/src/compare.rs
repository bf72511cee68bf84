//! `sim-harness compare`: every estimator of [`crate::peers`] over the same flight logs,
//! side by side — roll/pitch/yaw RMS and max error against truth (simulated logs) or
//! agreement with the log's `ref_*` attitude (real logs), host cost per step, and SVG
//! figures overlaying the errors. Monte Carlo over simulator seeds with `--runs N`.

use crate::figures::{write_figure, Panel, Series as Curve};
use crate::log::{FlightLog, LogRow};
pub use crate::metrics::Against;
use crate::metrics::{wrap, Stats as AxisStats};
use crate::peers;
use crate::peers::setup::{SensorFigures, Setup, Tuning};
use anyhow::{bail, Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What `compare` runs with no items: every built-in scenario, the kinematic turns and the
/// real PX4 flights (skipped, saying so, when the shared data is absent).
pub fn default_items() -> Vec<String> {
    let mut v: Vec<String> = crate::sim::builtin_names().iter().map(|s| s.to_string()).collect();
    v.extend(["turns", "real_a", "real_b"].map(String::from));
    v
}

/// Arguments of `sim-harness compare`.
#[derive(clap::Args, Debug, Clone)]
pub struct CompareArgs {
    /// What `report` takes: built-in scenario names, scenario TOML files, flight logs
    /// (.csv, .ulg, .bin); also `turns` (kinematic coordinated turns, no simulator),
    /// `real_a`/`real_b` (the real PX4 flights of the shared data) and `jsbsim:NAME`
    /// (a JSBSim flight exported by `sim-harness jsbsim`). Default: every built-in
    /// scenario, turns, real_a, real_b.
    pub items: Vec<String>,
    /// More items, comma separated (appended to the positional ones).
    #[arg(long, value_delimiter = ',')]
    pub scenarios: Vec<String>,
    /// Monte Carlo runs per simulated scenario (different sensor-noise seeds).
    #[arg(long, default_value_t = 1)]
    pub runs: u32,
    /// First seed of the Monte Carlo runs.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Seconds at the start of each log left out of the statistics: the common settled time
    /// (start-up is reported on its own, as the time to converge).
    #[arg(long, default_value_t = DEFAULT_WARMUP)]
    pub warmup: f64,
    /// `matched`: ours, fusion-nav and EKF2 given the same sensor figures (the flight's
    /// sensor spec); `defaults`: every estimator as shipped (docs/peers.md).
    #[arg(long, value_enum, default_value_t = Tuning::Matched)]
    pub config: Tuning,
    /// Output directory for compare.md and the figures.
    #[arg(long, default_value = "target/compare")]
    pub out: PathBuf,
    /// Also write the headline table (ours, fusion-nav, PX4 EKF2: accuracy per flight
    /// class, host cost, and the M4F figures of `cargo xtask bench-peers` when its
    /// `target/bench-peers.txt` exists) as markdown to this file.
    #[arg(long)]
    pub headline: Option<PathBuf>,
    /// Write the tables into these markdown files between markers (repeatable): for the
    /// configuration CONFIG, `<!-- headline-CONFIG:begin -->` … `<!-- headline-CONFIG:end -->`
    /// (the headline), `ratio-CONFIG` (the per-flight 2× table of docs/peers.md) and
    /// `per-flight-CONFIG` (the full table); with `matched`, also `headline` (the README's
    /// block). A file with none of its blocks is an error.
    #[arg(long)]
    pub doc: Vec<PathBuf>,
}

impl CompareArgs {
    /// Defaults for a program (tests): `items`, one run, seed 1, 10 s warm-up.
    pub fn new(items: &[&str], out: &Path) -> Self {
        CompareArgs {
            items: items.iter().map(|s| s.to_string()).collect(),
            scenarios: Vec::new(),
            runs: 1,
            seed: 1,
            warmup: DEFAULT_WARMUP,
            config: Tuning::Matched,
            out: out.to_path_buf(),
            headline: None,
            doc: Vec::new(),
        }
    }
    /// The items to run, in order (the default set when none are given).
    pub fn all_items(&self) -> Vec<String> {
        let v: Vec<String> = self.items.iter().chain(&self.scenarios).cloned().collect();
        if v.is_empty() {
            default_items()
        } else {
            v
        }
    }
}

/// The common settled time, s: scoring starts here for every estimator.
pub const DEFAULT_WARMUP: f64 = 30.0;

/// Converged: tilt error within this, rad (1°) …
pub const CONVERGED_TILT: f64 = 1.0 * std::f64::consts::PI / 180.0;
/// … and staying there this long, s.
pub const CONVERGED_HOLD: f64 = 10.0;

/// Error (or agreement) samples of one estimator on one scenario, pooled over runs, rad.
#[derive(Debug, Clone, Default)]
pub struct Stats {
    err: [Vec<f64>; 3],
    /// Tilt error (angle between estimated and true down direction) and total attitude
    /// error (rotation angle between estimate and truth), rad, per sample.
    tilt: Vec<f64>,
    total: Vec<f64>,
    /// Total timed steps and nanoseconds.
    steps: u64,
    nanos: u128,
    /// Time to converge per run, s from the log's start (`None`: never); truth logs only.
    converge: Vec<Option<f64>>,
}

impl Stats {
    /// Per-axis statistics (roll, pitch, yaw), rad (the harness's `metrics::Stats`).
    pub fn axes(&self) -> [AxisStats; 3] {
        core::array::from_fn(|i| AxisStats::of(&self.err[i]))
    }
    /// RMS per axis (roll, pitch, yaw), rad.
    pub fn rms(&self) -> [f64; 3] {
        self.axes().map(|a| a.rms)
    }
    /// Max |error| per axis, rad.
    pub fn max(&self) -> [f64; 3] {
        self.axes().map(|a| a.max_abs)
    }
    /// Tilt and total attitude error statistics, rad.
    pub fn tilt_total(&self) -> [AxisStats; 2] {
        [AxisStats::of(&self.tilt), AxisStats::of(&self.total)]
    }
    /// Host cost per step, ns.
    pub fn ns_per_step(&self) -> f64 {
        self.nanos as f64 / self.steps.max(1) as f64
    }
    /// Roll/pitch RMS combined: √((φ² + θ²)/2), rad.
    pub fn rp_rms(&self) -> f64 {
        let r = self.rms();
        ((r[0] * r[0] + r[1] * r[1]) / 2.0).sqrt()
    }
    /// The slowest run's time to converge, s: `Some(None)` if a run never converged, `None`
    /// without truth.
    pub fn converge(&self) -> Option<Option<f64>> {
        if self.converge.is_empty() {
            return None;
        }
        Some(self.converge.iter().try_fold(0.0f64, |m, &c| c.map(|c| m.max(c))))
    }
    /// Sum of squared roll and pitch errors and their sample count (for pooled RMS).
    pub fn rp_sums(&self) -> ([f64; 2], usize) {
        let ss = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>();
        ([ss(&self.err[0]), ss(&self.err[1])], self.err[0].len())
    }
}

/// One row of the table.
#[derive(Debug, Clone)]
pub struct Row {
    /// Estimator name.
    pub name: String,
    /// Uses GPS.
    pub gps: bool,
    /// Estimates gyro bias in flight.
    pub bias: bool,
    /// Where its yaw comes from.
    pub yaw: peers::YawSource,
    /// Fed a GNSS position synthesised from the fixes' velocities (the log has none).
    pub synthetic_position: bool,
    /// Statistics.
    pub stats: Stats,
}

/// Which column of the headline table a flight belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum FlightClass {
    /// Our simulator (or the kinematic turns) without wind.
    StillAir,
    /// Our simulator with a steady wind or turbulence.
    Wind,
    /// Attitudes beyond normal flight (|roll| > 90° or |pitch| > 60° in the truth).
    Aerobatics,
    /// Flown by JSBSim's flight dynamics, our sensor models.
    Jsbsim,
    /// A real flight (agreement with the autopilot's attitude).
    Real,
}

impl FlightClass {
    /// Column label.
    pub fn label(self) -> &'static str {
        match self {
            FlightClass::StillAir => "still air",
            FlightClass::Wind => "wind",
            FlightClass::Aerobatics => "aerobatics",
            FlightClass::Jsbsim => "JSBSim",
            FlightClass::Real => "real",
        }
    }
    /// Every class, in column order.
    pub const ALL: [FlightClass; 5] = [
        FlightClass::StillAir,
        FlightClass::Wind,
        FlightClass::Aerobatics,
        FlightClass::Jsbsim,
        FlightClass::Real,
    ];
}

/// All rows of one scenario.
#[derive(Debug, Clone)]
pub struct ScenarioResult {
    /// Scenario name.
    pub name: String,
    /// Error or agreement.
    pub against: Against,
    /// Headline column.
    pub class: FlightClass,
    /// Runs pooled.
    pub runs: u32,
    /// The sensor spec the filters were given ([`Item::spec_label`]).
    pub spec: &'static str,
    /// One row per estimator, in [`peers::all`] order.
    pub rows: Vec<Row>,
}

/// An error series for the figures: (t, [roll, pitch, yaw] error in rad) per estimator.
pub type Series = Vec<(String, Vec<(f64, [f64; 3])>)>;

/// One item of the command line, resolved.
#[derive(Debug, Clone)]
pub struct Item {
    /// Table name.
    pub name: String,
    /// What it is.
    pub kind: ItemKind,
}

/// How an item's log is obtained.
#[derive(Debug, Clone)]
pub enum ItemKind {
    /// The kinematic coordinated turns (seeded).
    Turns,
    /// A simulator scenario (built-in name or TOML path; seeded).
    Simulated(Box<crate::sim::Scenario>),
    /// A log file (one run).
    Log(PathBuf),
    /// A real flight of the shared data by file name (skipped when absent).
    Real(&'static str),
}

impl Item {
    /// Resolves a command-line item, failing clearly for an unknown name or a missing file.
    pub fn resolve(item: &str) -> Result<Item> {
        let stem = |p: &str| {
            Path::new(p).file_stem().map_or(p.to_string(), |s| s.to_string_lossy().into_owned())
        };
        let kind = match item {
            "turns" => ItemKind::Turns,
            "real_a" => ItemKind::Real(crate::data::REAL_FLIGHTS[0]),
            "real_b" => ItemKind::Real(crate::data::REAL_FLIGHTS[1]),
            j if j.starts_with("jsbsim:") => {
                let name = &j["jsbsim:".len()..];
                let path = crate::jsbsim::log_path(name);
                if !path.exists() {
                    bail!("{j}: {} not found; generate it with `sim-harness jsbsim {name}` (needs python3 and the PyPI package jsbsim)", path.display());
                }
                return Ok(Item { name: j.to_string(), kind: ItemKind::Log(path) });
            }
            p if crate::import::is_log_path(p) => {
                if !Path::new(p).exists() {
                    bail!("flight log {p} not found");
                }
                ItemKind::Log(PathBuf::from(p))
            }
            other => ItemKind::Simulated(Box::new(
                crate::sim::load_scenario(other)
                    .with_context(|| format!("`{other}` is not a scenario name, TOML scenario or log file (built-in scenarios: {}, plus turns, real_a, real_b, jsbsim:NAME)", crate::sim::builtin_names().join(", ")))?,
            )),
        };
        Ok(Item { name: stem(item), kind })
    }

    /// Whether runs differ by seed (Monte Carlo); a log file is one run.
    pub fn seeded(&self) -> bool {
        matches!(self.kind, ItemKind::Turns | ItemKind::Simulated(_))
    }

    /// The item's log for `seed`, or `Ok(None)` (with a printed reason) when its data is absent.
    pub fn log(&self, seed: u64) -> Result<Option<(FlightLog, Against)>> {
        let from_file = |log: FlightLog| {
            let truth = log.rows.iter().any(|r| r.truth.is_some());
            (log, if truth { Against::Truth } else { Against::Reference })
        };
        match &self.kind {
            ItemKind::Turns => Ok(Some((turns_log(seed), Against::Truth))),
            ItemKind::Simulated(sc) => {
                let out = crate::sim::run(sc, seed)
                    .with_context(|| format!("simulating {}", self.name))?;
                Ok(Some((out.log, Against::Truth)))
            }
            ItemKind::Log(p) => Ok(Some(from_file(crate::import::load_any(p)?))),
            ItemKind::Real(file) => match crate::data::real_log(file) {
                Some(p) => Ok(Some(from_file(crate::csv::read_log(&p)?))),
                None => {
                    eprintln!("skip {}: real/{file} not found (set WING_AHRS_DATA or provide ../shared/data)", self.name);
                    Ok(None)
                }
            },
        }
    }

    /// The sensor spec the matched configuration hands every filter on this item: the
    /// simulator's sensor model of a simulated flight, thesis Table 5.1 for the kinematic turns
    /// and JSBSim flights (`sim-harness jsbsim`'s default), the `realistic` preset (a typical
    /// MEMS IMU and u-blox receiver) for a real log, whose sensors have no spec here.
    pub fn figures(&self) -> SensorFigures {
        match &self.kind {
            ItemKind::Simulated(sc) => SensorFigures::of(
                if sc.sensor_preset == "realistic" { "realistic" } else { "thesis" },
                &sc.sensors,
            ),
            ItemKind::Turns => SensorFigures::thesis(),
            ItemKind::Log(_) if self.name.starts_with("jsbsim:") => SensorFigures::thesis(),
            ItemKind::Log(_) | ItemKind::Real(_) => SensorFigures::realistic(),
        }
    }

    /// The configuration the navigation filters run in on this item: `requested`, except on
    /// a log compared against a reference (a real flight), whose sensors have no spec to
    /// match: there every filter runs as shipped (docs/peers.md: EKF2 handed the `realistic`
    /// preset's figures agreed up to 2.8× worse with the autopilot than as shipped).
    pub fn tuning(requested: Tuning, against: Against) -> Tuning {
        if against == Against::Reference {
            Tuning::Defaults
        } else {
            requested
        }
    }

    /// The spec named beside the flight in the tables.
    pub fn spec_label(&self, tuning: Tuning, against: Against) -> &'static str {
        match (Self::tuning(tuning, against), against) {
            (_, Against::Reference) => "no spec: as shipped",
            (Tuning::Defaults, _) => "as shipped",
            (Tuning::Matched, _) => self.figures().name,
        }
    }

    /// The headline column of this item, given one of its logs.
    pub fn class(&self, log: &FlightLog, against: Against) -> FlightClass {
        let aerobatic = log
            .rows
            .iter()
            .filter_map(|r| r.truth.or(r.reference))
            .any(|a| a[0].abs() > 90f64.to_radians() || a[1].abs() > 60f64.to_radians());
        if self.name.starts_with("jsbsim:") {
            FlightClass::Jsbsim
        } else if against == Against::Reference {
            FlightClass::Real
        } else if aerobatic {
            FlightClass::Aerobatics
        } else if let ItemKind::Simulated(sc) = &self.kind {
            let still = sc.wind.ned_m_s.iter().all(|w| *w == 0.0)
                && (sc.wind.turbulence.is_empty() || sc.wind.turbulence == "none");
            if still {
                FlightClass::StillAir
            } else {
                FlightClass::Wind
            }
        } else {
            FlightClass::StillAir
        }
    }
}

/// The kinematic coordinated turns of `turns` (bank 30°, −45°, 60° at 20 m/s).
fn turns_log(seed: u64) -> FlightLog {
    let segs = [
        (20.0, 0.0),
        (30.0, 30.0),
        (15.0, 0.0),
        (30.0, -45.0),
        (15.0, 0.0),
        (20.0, 60.0),
        (20.0, 0.0),
    ];
    peers::synth::coordinated_turns(20.0, 0.3, &segs, peers::synth::Sensors::thesis(), seed)
}

/// Loads one item's log for a seed (see [`Item`]), or `Ok(None)` when its data is absent.
pub fn scenario_log(name: &str, seed: u64) -> Result<Option<(FlightLog, Against)>> {
    Item::resolve(name)?.log(seed)
}

/// Timed passes per estimator and log (the fastest counts).
const TIMING_PASSES: usize = 15;

/// Median IMU period of a log, s (the nominal rate peers are built with).
pub fn nominal_dt(log: &FlightLog) -> f64 {
    let mut d: Vec<f64> =
        log.rows.windows(2).map(|w| w[1].t - w[0].t).filter(|d| *d > 0.0).collect();
    if d.is_empty() {
        return 0.01;
    }
    d.sort_by(f64::total_cmp);
    d[d.len() / 2]
}

fn target(row: &LogRow, against: Against) -> Option<[f64; 3]> {
    match against {
        Against::Truth => row.truth,
        Against::Reference => row.reference,
    }
}

/// Before the first timing of the process: every estimator steps `log` for ≥ 0.3 s, so the
/// first scenario's timings are not taken while the CPU clock is still ramping up (they
/// were ~10 % slower than the same scenario timed later).
fn warm_up_once(log: &FlightLog, setup: &Setup) {
    static DONE: std::sync::Once = std::sync::Once::new();
    DONE.call_once(|| {
        let start = Instant::now();
        while start.elapsed().as_secs_f64() < 0.3 {
            for mut est in peers::all_for(setup) {
                for row in &log.rows {
                    est.step(std::hint::black_box(row));
                }
                std::hint::black_box(est.attitude());
            }
        }
    });
}

/// Cost per estimator over `log`, ns: fresh instances, steps only (no read-out), each pass
/// timed as a whole, the fastest of [`TIMING_PASSES`] kept (the shared machine only ever adds
/// time). The estimators take turns pass by pass, so a change of load on the machine falls on
/// all of them alike instead of on whichever was being timed.
fn time_all(log: &FlightLog, setup: &Setup) -> Vec<u128> {
    let mut best: Vec<u128> = Vec::new();
    for _ in 0..TIMING_PASSES {
        // One fresh set per pass (construction is not timed).
        for (k, mut fresh) in peers::all_for(setup).into_iter().enumerate() {
            let start = Instant::now();
            for row in &log.rows {
                fresh.step(std::hint::black_box(row));
            }
            std::hint::black_box(fresh.attitude());
            let ns = start.elapsed().as_nanos();
            match best.get_mut(k) {
                Some(b) => *b = (*b).min(ns),
                None => best.push(ns),
            }
        }
    }
    best
}

/// The statistics window, s: from `from` on; for a real log against its reference, the
/// airborne part only (`real_logs::airborne`: 20 s after take-off to the landing), where
/// the log starts or ends on the ground.
fn window(log: &FlightLog, against: Against, from: f64) -> (f64, f64) {
    if against != Against::Reference {
        return (from, f64::INFINITY);
    }
    let (takeoff, landing) = crate::real_logs::airborne(log);
    (
        takeoff.map_or(from, |t| from.max(t + crate::real_logs::AFTER_TAKEOFF)),
        landing.unwrap_or(f64::INFINITY),
    )
}

/// The first time (s from `t0`) from which the tilt error stays ≤ [`CONVERGED_TILT`] for
/// [`CONVERGED_HOLD`] s, over `(t, tilt)` samples; `None` if it never does.
pub fn converged_at(t0: f64, tilt: &[(f64, f64)]) -> Option<f64> {
    let mut since = None;
    for &(t, e) in tilt {
        if e > CONVERGED_TILT {
            since = None;
            continue;
        }
        let s = *since.get_or_insert(t);
        if t - s >= CONVERGED_HOLD {
            return Some(s - t0);
        }
    }
    None
}

/// Runs every estimator over `log` in configuration `tuning` with the sensor figures
/// `figures`: accumulates errors after `warmup` s into `rows` and returns the error series.
/// Cost is timed in a second, output-free pass.
pub fn run_log(
    log: &FlightLog,
    against: Against,
    warmup: f64,
    tuning: Tuning,
    figures: SensorFigures,
    rows: &mut Vec<Row>,
) -> Series {
    let setup = Setup::for_log(log, nominal_dt(log), tuning, figures);
    warm_up_once(log, &setup);
    let t0 = log.rows.first().map_or(0.0, |r| r.t);
    let (from, to) = window(log, against, t0 + warmup);
    let mut series = Series::new();
    for (k, mut est) in peers::all_for(&setup).into_iter().enumerate() {
        if rows.len() <= k {
            rows.push(Row {
                name: est.name().to_string(),
                gps: est.uses_gps(),
                bias: est.estimates_bias(),
                yaw: est.yaw_source(),
                synthetic_position: false,
                stats: Stats::default(),
            });
        }
        let st = &mut rows[k].stats;
        let mut s = Vec::with_capacity(log.rows.len());
        let mut tilts = Vec::new();
        for row in &log.rows {
            est.step(row);
            let Some(want) = target(row, against) else { continue };
            let got = est.attitude();
            let e: [f64; 3] = core::array::from_fn(|i| wrap(got[i] - want[i]));
            if against == Against::Truth {
                tilts.push((row.t, crate::metrics::tilt_error(got, want)));
            }
            if row.t >= from && row.t <= to {
                for i in 0..3 {
                    st.err[i].push(e[i]);
                }
                st.tilt.push(crate::metrics::tilt_error(got, want));
                st.total.push(crate::metrics::attitude_error(got, want));
            }
            s.push((row.t - t0, e));
        }
        if against == Against::Truth {
            st.converge.push(converged_at(t0, &tilts));
        }
        rows[k].synthetic_position |= est.synthetic_position();
        series.push((est.name().to_string(), s));
    }
    for (k, nanos) in time_all(log, &setup).into_iter().enumerate() {
        rows[k].stats.nanos += nanos;
        rows[k].stats.steps += log.rows.len() as u64;
    }
    series
}

/// Runs the comparison, prints and writes the table and figures; returns the results.
pub fn run(args: &CompareArgs) -> Result<Vec<ScenarioResult>> {
    if args.runs == 0 {
        bail!("--runs must be at least 1");
    }
    let items: Vec<Item> =
        args.all_items().iter().map(|s| Item::resolve(s)).collect::<Result<_>>()?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let runs_of = |it: &Item| if it.seeded() { args.runs } else { 1 };
    let total: u64 = items.iter().map(|it| runs_of(it) as u64).sum();
    let bar = ProgressBar::new(total);
    bar.set_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} {msg} [{elapsed} / ~{eta}]")
            .expect("static template"),
    );
    let mut results = Vec::new();
    for item in &items {
        let mut rows = Vec::new();
        let (mut against, mut class) = (Against::Truth, FlightClass::StillAir);
        let mut done = 0;
        for r in 0..runs_of(item) {
            bar.set_message(format!("{} run {}", item.name, r + 1));
            let Some((log, a)) = item.log(args.seed + r as u64)? else {
                bar.inc(runs_of(item) as u64);
                break;
            };
            against = a;
            class = item.class(&log, a);
            let tuning = Item::tuning(args.config, a);
            let series = run_log(&log, a, args.warmup, tuning, item.figures(), &mut rows);
            if r == 0 {
                let stem = item.name.replace(':', "_");
                figure(&args.out, &stem, a, &series)
                    .with_context(|| format!("figure for {}", item.name))?;
            }
            done += 1;
            bar.inc(1);
        }
        if done > 0 {
            results.push(ScenarioResult {
                spec: item.spec_label(args.config, against),
                name: item.name.clone(),
                against,
                class,
                runs: done,
                rows,
            });
        }
    }
    bar.finish_and_clear();
    if results.is_empty() {
        bail!("nothing was compared: every item's data is absent");
    }
    let md = markdown(&results, args);
    println!("{md}");
    let path = args.out.join("compare.md");
    std::fs::write(&path, &md).with_context(|| format!("writing {}", path.display()))?;
    println!("wrote {} and {}/<scenario>_errors.{{png,svg}}", path.display(), args.out.display());
    let headline = crate::headline::markdown(&results, args);
    let ratio = crate::headline::ratio_table(&results, args);
    println!("{ratio}");
    if let Some(h) = &args.headline {
        std::fs::write(h, &headline).with_context(|| format!("writing {}", h.display()))?;
        println!("{headline}\nwrote the headline table to {}", h.display());
    }
    if !args.doc.is_empty() {
        let c = args.config.label();
        let mut blocks = vec![
            (format!("headline-{c}"), headline.clone()),
            (format!("ratio-{c}"), ratio),
            (format!("per-flight-{c}"), md),
        ];
        if args.config == Tuning::Matched {
            blocks.push(("headline".to_string(), headline));
        }
        for path in &args.doc {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("reading {}", path.display()))?;
            let (out, n) = crate::headline::replace_blocks(&text, &blocks);
            if n == 0 {
                bail!(
                    "{} has none of the blocks `--doc` writes for --config {c}: <!-- NAME:begin --> … <!-- NAME:end --> with NAME one of {}",
                    path.display(),
                    blocks.iter().map(|b| b.0.as_str()).collect::<Vec<_>>().join(", ")
                );
            }
            std::fs::write(path, out).with_context(|| format!("writing {}", path.display()))?;
            println!("wrote {n} block(s) into {}", path.display());
        }
    }
    Ok(results)
}

/// The command line that reproduces `args`.
pub fn command_line(args: &CompareArgs) -> String {
    format!(
        "sim-harness compare {} --runs {} --seed {} --warmup {} --config {}",
        args.all_items().join(" "),
        args.runs,
        args.seed,
        args.warmup,
        args.config.label()
    )
}

/// The row of a named estimator.
pub fn find<'a>(sc: &'a ScenarioResult, name: &str) -> Option<&'a Row> {
    sc.rows.iter().find(|r| r.name == name)
}

/// The markdown table plus the goal line per scenario.
pub fn markdown(results: &[ScenarioResult], args: &CompareArgs) -> String {
    let mut s = String::new();
    let config = match args.config {
        Tuning::Matched => "**matched**: ours, fusion-nav and PX4 EKF2 given the same sensor figures, the flight's spec in brackets (docs/peers.md lists each parameter); a real log has no spec, and there every filter runs as shipped; the attitude-only peers as shipped",
        Tuning::Defaults => "**defaults**: every estimator as shipped (docs/peers.md)",
    };
    let _ = writeln!(s, "Configuration {config}. Converged: tilt error ≤ 1° and staying so for {CONVERGED_HOLD} s, s from the log's start, the slowest run (`never`: not within the log; truth logs only).\n");
    let _ = writeln!(s, "Command: `{}`; statistics after {} s (the common settled time); angles in degrees; cost is host ns per IMU sample in this run (fastest of {TIMING_PASSES} passes), and its ratio to ours and to fusion-nav.", command_line(args), args.warmup);
    let _ = writeln!(s, "Tilt: angle between estimated and true down direction; total: rotation angle between estimated and true attitude. `*` yaw of a GPS-less peer: its own gyro-integrated yaw, aligned once to the first GPS course. `†` fed a GNSS position integrated from the fixes' velocities (the log has no `lat`/`lon`/`alt`). Real logs: agreement with the autopilot's `ref_*` attitude, not error, over the airborne part where a log starts or ends on the ground (20 s after take-off to the landing).\n");
    let _ = writeln!(s, "| scenario | estimator | GPS | bias est. | yaw source | roll RMS | roll max | pitch RMS | pitch max | yaw RMS | yaw max | tilt RMS | tilt max | total RMS | total max | converged | ns/sample | × ours | × fusion-nav |");
    let _ = writeln!(
        s,
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for sc in results {
        let ours = sc.rows.first().map_or(f64::NAN, |r| r.stats.ns_per_step());
        let fnav = find(sc, peers::fusion_nav::NAME).map_or(f64::NAN, |r| r.stats.ns_per_step());
        let label = match sc.against {
            Against::Truth => {
                let runs = if sc.runs == 1 { "" } else { "s" };
                format!("{} ({} run{runs}, {})", sc.name, sc.runs, sc.spec)
            }
            Against::Reference => format!("{} (agreement w/ ref, {})", sc.name, sc.spec),
        };
        for r in &sc.rows {
            let (rms, max) =
                (r.stats.rms().map(f64::to_degrees), r.stats.max().map(f64::to_degrees));
            let [tilt, total] = r.stats.tilt_total();
            let star = if r.yaw == peers::YawSource::GyroAlignedOnce { "*" } else { "" };
            let dagger = if r.synthetic_position { " †" } else { "" };
            let ns = r.stats.ns_per_step();
            let conv = match r.stats.converge() {
                None => "—".to_string(),
                Some(None) => "never".to_string(),
                Some(Some(c)) => format!("{c:.1}"),
            };
            let _ = writeln!(
                s,
                "| {label} | {}{dagger} | {} | {} | {} | {:.3} | {:.2} | {:.3} | {:.2} | {:.3}{star} | {:.2}{star} | {:.3} | {:.2} | {:.3}{star} | {:.2}{star} | {conv} | {ns:.0} | {:.2} | {:.3} |",
                r.name,
                if r.gps { "yes" } else { "no" },
                if r.bias { "yes" } else { "no" },
                r.yaw.label(),
                rms[0],
                max[0],
                rms[1],
                max[1],
                rms[2],
                max[2],
                tilt.rms.to_degrees(),
                tilt.max_abs.to_degrees(),
                total.rms.to_degrees(),
                total.max_abs.to_degrees(),
                ns / ours,
                ns / fnav,
            );
        }
    }
    let _ = writeln!(s, "\n{}", goal_lines(results));
    s
}

/// Host cost goal: ours ≤ this fraction of fusion-nav's cost per sample.
pub const COST_GOAL: f64 = 1.0 / 20.0;

/// Whether ours (the first row) meets the estimator issue's goal on one scenario: roll and
/// pitch RMS each ≤ the better of fusion-nav and PX4 EKF2 on that axis, at ≤ 1/20 of
/// fusion-nav's host cost per sample. `None` when a peer did not run.
pub fn goal_met(sc: &ScenarioResult) -> Option<bool> {
    let ours = sc.rows.first()?;
    let (f, e) = (find(sc, peers::fusion_nav::NAME)?, find(sc, peers::px4_ekf2::NAME)?);
    let (o, fr, er) = (ours.stats.rms(), f.stats.rms(), e.stats.rms());
    let accurate = (0..2).all(|i| o[i] <= fr[i].min(er[i]));
    Some(accurate && ours.stats.ns_per_step() <= COST_GOAL * f.stats.ns_per_step())
}

/// One pass/fail line per scenario for the goal of [`goal_met`].
pub fn goal_lines(results: &[ScenarioResult]) -> String {
    let mut s = String::from("Goal: our roll and pitch RMS ≤ the better of fusion-nav and PX4 EKF2, at ≤ 1/20 of fusion-nav's cost per sample:\n");
    for sc in results {
        let (Some(ours), Some(f), Some(e), Some(met)) = (
            sc.rows.first(),
            find(sc, peers::fusion_nav::NAME),
            find(sc, peers::px4_ekf2::NAME),
            goal_met(sc),
        ) else {
            continue;
        };
        let d = |r: &Row| r.stats.rms().map(f64::to_degrees);
        let (o, fr, er) = (d(ours), d(f), d(e));
        let better =
            |i: usize| if fr[i] <= er[i] { ("fusion-nav", fr[i]) } else { ("EKF2", er[i]) };
        let (br, bp) = (better(0), better(1));
        let ratio = ours.stats.ns_per_step() / f.stats.ns_per_step();
        let _ = writeln!(
            s,
            "- {}: **{}** — {} roll/pitch RMS {:.3}°/{:.3}° vs the better peer {:.3}° ({}) / {:.3}° ({}); cost {:.0} ns = 1/{:.0} of fusion-nav's {:.0} ns ({})",
            sc.name,
            if met { "PASS" } else { "FAIL" },
            ours.name,
            o[0],
            o[1],
            br.1,
            br.0,
            bp.1,
            bp.0,
            ours.stats.ns_per_step(),
            1.0 / ratio,
            f.stats.ns_per_step(),
            if ratio <= COST_GOAL { "≤ 1/20" } else { "over 1/20" }
        );
    }
    s
}

/// Overlay of every estimator's roll, pitch and yaw error over time (first run), PNG + SVG
/// through the harness's figure writer. Errors are clipped to the 99th percentile of all
/// estimators so one peer's start-up transient does not flatten the others.
pub fn figure(dir: &Path, scenario: &str, against: Against, series: &Series) -> Result<PathBuf> {
    use plotters::style::{Palette, Palette99};
    let what = if against == Against::Truth { "error" } else { "difference to ref_*" };
    let panels: Vec<Panel> = (0..3)
        .map(|axis| {
            let mut all: Vec<f64> = series
                .iter()
                .flat_map(|(_, s)| s.iter().map(|p| p.1[axis].to_degrees().abs()))
                .collect();
            all.sort_by(f64::total_cmp);
            let lim = all.get(all.len() * 99 / 100).copied().unwrap_or(1.0).max(0.5);
            Panel {
                ylabel: format!("{} {what} [deg]", ["roll", "pitch", "yaw"][axis]),
                series: series
                    .iter()
                    .enumerate()
                    .map(|(k, (name, s))| {
                        let (r, g, b) = Palette99::COLORS[k % Palette99::COLORS.len()];
                        let step = (s.len() / 1500).max(1);
                        Curve {
                            name: name.clone(),
                            color: plotters::style::RGBColor(r, g, b),
                            points: s
                                .iter()
                                .step_by(step)
                                .map(|p| (p.0, p.1[axis].to_degrees().clamp(-lim, lim)))
                                .collect(),
                        }
                    })
                    .collect(),
            }
        })
        .collect();
    write_figure(
        dir,
        &format!("{scenario}_errors"),
        &format!("{scenario}: attitude {what}, all estimators"),
        &panels,
    )
}
