//! The receiver-and-start robustness suite (`sim-harness robust`, `report robust`).
//!
//! A world is drawn at random from what a user's flight varies: the flight (the 6-DoF
//! simulator's, or one flown by JSBSim on one of four airframes), the sensor grade, the
//! fix rate, the receiver latency, the wind, and when the estimator is switched on (at
//! the start, or in flight: wings level, or in a 25–35° bank). Each world is then flown
//! with every way a receiver reports its speed accuracy ([`SACC`]: honest, 3×, 10× and
//! 0.3× its noise, or not at all), the same noise for all, so the variants compare run
//! for run. A run is *lost* when the tilt error exceeds 5° from 20 s after the switch-on,
//! or the heading error 20° after the first full turn. Consistency: attitude NEES
//! (NED error, 3 dof) and the share of samples with an axis beyond 4σ, per group.

use crate::log::FlightLog;
use crate::metrics::{self, Stats};
use crate::montecarlo::{record_run, RunRecord};
use crate::sim::{self, sensors::SaccReport, SensorSpec};
use anyhow::{Context, Result};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use wing_ahrs::Config;

/// How the receiver reports its speed accuracy, as `sacc=` modifiers; the first is the
/// reference the others are compared with.
pub const SACC: [&str; 5] = ["honest", "x3", "x10", "x0.3", "none"];
/// Fix rates drawn, Hz.
pub const RATES: [f64; 6] = [1.0, 2.0, 4.0, 5.0, 10.0, 20.0];
/// Receiver latencies drawn, s.
pub const LATENCIES: [f64; 3] = [0.0, 0.06, 0.15];
/// Winds of the simulator's flights (JSBSim flights carry their own).
/// (Light turbulence: the simulator's autopilot flies coordinated_turn into the ground in
/// some moderate-turbulence seeds.)
pub const WINDS: [&str; 4] = ["", "wind=7@{d}", "wind=12@{d}", "wind=6@{d},turb=light"];
/// The simulator's flights drawn.
pub const SIM_BASES: [&str; 4] = ["flight1", "flight2", "aggressive", "coordinated_turn"];
/// JSBSim flights (`scripts/jsbsim_fly.py`): a C172 in a 7 m/s wind, the J-3 Cub, the
/// T-6 through aerobatics in a 6 m/s wind with light turbulence, and a C182 (rand4).
pub const JSBSIM_BASES: [&str; 4] = ["c172_wind7", "j3cub_turns", "t6_aerobatics_wind6", "rand4"];

/// When the estimator is switched on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Start {
    /// With the log (the simulator trims its flights level at t = 0).
    First,
    /// In flight, wings level (|roll| < 5°, |pitch| < 10°), from 30 s on.
    AirLevel,
    /// In flight, in a 25–35° bank (|pitch| < 15°), from 30 s on.
    AirBank,
}

impl Start {
    fn name(self) -> &'static str {
        match self {
            Start::First => "t0",
            Start::AirLevel => "air-level",
            Start::AirBank => "air-bank30",
        }
    }
}

/// One drawn world, flown with each of [`SACC`].
#[derive(Debug, Clone)]
pub struct World {
    /// `sim:NAME+mods` or `jsbsim:NAME`.
    pub base: String,
    pub spec: SensorSpec,
    pub rate_hz: f64,
    pub latency_s: f64,
    pub start: Start,
    /// Simulator wind modifiers (empty: still air, or the JSBSim flight's own wind).
    pub wind: String,
    pub seed: u64,
}

impl World {
    /// A short label: base, sensors, rate, latency, start.
    pub fn label(&self) -> String {
        let wind = if self.wind.is_empty() { String::new() } else { format!("+{}", self.wind) };
        format!(
            "{}{wind} {} {}Hz {:.0}ms {}",
            self.base,
            self.spec.name(),
            self.rate_hz,
            self.latency_s * 1e3,
            self.start.name()
        )
    }
}

/// `n` worlds drawn from `seed`, alternating simulator and JSBSim flights and cycling
/// the sensor grades, starts and rates so a short suite still covers each.
pub fn worlds(n: usize, seed: u64) -> Vec<World> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|k| {
            let jsb = k % 2 == 1;
            let base = if jsb {
                format!("jsbsim:{}", JSBSIM_BASES[(k / 2) % JSBSIM_BASES.len()])
            } else {
                format!("sim:{}", SIM_BASES[(k / 2) % SIM_BASES.len()])
            };
            let spec = if (k / 2) % 2 == 0 { SensorSpec::Thesis } else { SensorSpec::Realistic };
            let start = [Start::First, Start::AirLevel, Start::AirBank][k % 3];
            let rate_hz = RATES[(k + rng.gen_range(0..RATES.len())) % RATES.len()];
            let latency_s = LATENCIES[rng.gen_range(0..LATENCIES.len())];
            let wind = if jsb {
                String::new()
            } else {
                let d = rng.gen_range(0..8) * 45;
                WINDS[rng.gen_range(0..WINDS.len())].replace("{d}", &d.to_string())
            };
            World { base, spec, rate_hz, latency_s, start, wind, seed: seed + k as u64 }
        })
        .collect()
}

/// The flight log of `w` with the receiver reporting `sacc`, from its switch-on.
pub fn flight(w: &World, sacc: SaccReport) -> Result<FlightLog> {
    let full = if let Some(name) = w.base.strip_prefix("jsbsim:") {
        let truth = fly_jsbsim(name)?;
        let mut s = w.spec.params();
        s.gps.rate_hz = w.rate_hz;
        s.gps.latency_s = w.latency_s;
        s.gps.sacc = sacc;
        crate::jsbsim::export(&truth, &s, w.seed)?
    } else {
        let base = w.base.strip_prefix("sim:").unwrap_or(&w.base);
        let mut mods = format!(
            "spec={},gps={},lat={},sacc={}",
            w.spec.name(),
            w.rate_hz,
            w.latency_s,
            String::from(sacc)
        );
        if !w.wind.is_empty() {
            mods = format!("{mods},{}", w.wind);
        }
        let sc = sim::load_scenario(&format!("{base}+{mods}"))?;
        sim::run(&sc, w.seed)?.log
    };
    let t0 = switch_on(&full, w.start)
        .with_context(|| format!("{}: no time to switch on {}", w.base, w.start.name()))?;
    Ok(FlightLog { rows: full.rows.into_iter().filter(|r| r.t >= t0).collect() })
}

/// The JSBSim truth of flight `name`, flown once (`target/jsbsim/NAME.truth.csv`).
fn fly_jsbsim(name: &str) -> Result<std::path::PathBuf> {
    let truth = crate::jsbsim::log_path(name).with_extension("truth.csv");
    if !truth.exists() {
        std::fs::create_dir_all(truth.parent().unwrap_or(std::path::Path::new(".")))?;
        // Flown into a file of its own and moved in whole: another thread or process (a
        // test running beside this one) may be flying the same truth, and must never read
        // half of it.
        static FLIGHTS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let k = FLIGHTS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let part = truth.with_extension(format!("truth.{}.{k}.part", std::process::id()));
        crate::jsbsim::fly(name, &part)?;
        std::fs::rename(&part, &truth)
            .with_context(|| format!("moving {} to {}", part.display(), truth.display()))?;
    }
    Ok(truth)
}

/// When the estimator is switched on in `log`, s: the first row (from 30 s on for an
/// in-air start) whose true roll fits `start`.
fn switch_on(log: &FlightLog, start: Start) -> Option<f64> {
    let first = log.rows.first()?.t;
    let deg = f64::to_radians;
    let fits = |e: [f64; 3]| match start {
        Start::First => true,
        Start::AirLevel => e[0].abs() < deg(5.0) && e[1].abs() < deg(10.0),
        Start::AirBank => (deg(25.0)..=deg(35.0)).contains(&e[0].abs()) && e[1].abs() < deg(15.0),
    };
    if start == Start::First {
        return Some(first);
    }
    log.rows.iter().find(|r| r.t >= first + 30.0 && r.truth.is_some_and(fits)).map(|r| r.t)
}

/// `cfg` told the accelerometer bias and axis misalignment of `w`'s IMU, as a user reads
/// them off the datasheet (`QuatConfig::accel_bias_sigma`, `mounting_sigma`): thesis
/// Table 5.1's IMU has neither, the realistic one 0.1 m/s² and 0.36°. They move only the
/// covariance reported, never the estimate; the Euler filter has no such terms.
pub fn told(cfg: Config, w: &World) -> Config {
    let figures = crate::peers::setup::SensorFigures::of(w.spec.name(), &w.spec.params());
    crate::peers::wing::unobservable(cfg, &figures)
}

/// One run's figures.
#[derive(Debug, Clone)]
pub struct RunResult {
    pub world: usize,
    pub sacc: &'static str,
    /// Roll, pitch, yaw error RMS from switch-on + 20 s, rad.
    pub rms: [f64; 3],
    /// Largest tilt error from switch-on + 20 s, and heading error after the first full
    /// turn (NaN: no full turn), rad.
    pub tilt_max: f64,
    pub yaw_max: f64,
    /// The NED tilt error's RMS per horizontal axis, `√(mean(e_N² + e_E²)/2)`, over the
    /// sampled epochs from switch-on + 20 s, rad: the roll/pitch RMS without the Euler
    /// angles' singularity (through the vertical, roll and yaw differences grow without
    /// bound for a small rotation).
    pub tilt_rms: f64,
    /// Mean attitude NEES (3 dof) and the share of samples with an axis beyond 4σ.
    pub nees: f64,
    /// Mean NEES of each NED axis alone (1 dof): which axis the filter is wrong about.
    pub nees_axis: [f64; 3],
    pub beyond4: f64,
    /// Whether P or the state went non-finite, or P lost symmetry.
    pub broken: bool,
}

impl RunResult {
    /// Tilt > 5° after settling, or heading > 20° after the first full turn.
    pub fn lost(&self) -> bool {
        self.broken
            || self.tilt_max > 5f64.to_radians()
            || self.yaw_max > 20f64.to_radians()
            || !self.tilt_max.is_finite()
    }

    /// `√((roll² + pitch²)/2)` RMS, rad.
    pub fn roll_pitch(&self) -> f64 {
        ((self.rms[0].powi(2) + self.rms[1].powi(2)) / 2.0).sqrt()
    }

    /// The honest run of the same world in `res`.
    fn honest<'a>(&self, res: &'a [RunResult]) -> Option<&'a RunResult> {
        res.iter().find(|h| h.world == self.world && h.sacc == SACC[0])
    }
}

/// Flies world `k` with `sacc` and scores it. The filter is told its IMU's figures for the
/// errors no state holds ([`told`]).
pub fn run(k: usize, w: &World, sacc: &'static str, cfg: Config) -> Result<RunResult> {
    let r: SaccReport = sacc.parse().map_err(|e: String| anyhow::anyhow!(e))?;
    let log = flight(w, r)?;
    let t_from = log.rows.first().map_or(0.0, |r| r.t) + 20.0;
    let rec = record_run(w.seed, &log, told(cfg, w), t_from);
    let turn = metrics::first_full_turn(&log);
    Ok(score(k, sacc, &rec, turn))
}

fn score(world: usize, sacc: &'static str, rec: &RunRecord, turn: Option<f64>) -> RunResult {
    let (mut tilt_max, mut yaw_max) = (0.0f64, if turn.is_some() { 0.0 } else { f64::NAN });
    let mut tilt_sq = 0.0f64;
    for e in &rec.epochs {
        // EPOCH_COLUMNS: t, e_n, e_e, e_d (degrees).
        tilt_max = tilt_max.max(e[1].hypot(e[2]).to_radians());
        tilt_sq += (e[1].powi(2) + e[2].powi(2)) / 2.0;
        if turn.is_some_and(|t| e[0] >= t) {
            yaw_max = yaw_max.max(e[3].abs().to_radians());
        }
    }

    let n4 = (0..rec.nees_t.len())
        .filter(|&k| {
            rec.nees_axis.iter().any(|a| a.get(k).copied().flatten().is_some_and(|v| v > 16.0))
        })
        .count();
    RunResult {
        world,
        sacc,
        rms: rec.err.map(|s| s.rms),
        tilt_max,
        yaw_max,
        tilt_rms: (tilt_sq / rec.epochs.len().max(1) as f64).sqrt().to_radians(),
        nees: mean_of_sampled(&rec.nees3),
        nees_axis: [0, 1, 2].map(|i| mean_of_sampled(&rec.nees_axis[i])),
        beyond4: n4 as f64 / rec.nees_t.len().max(1) as f64,
        broken: rec.broken,
    }
}

/// The mean of the epochs that have a value (NEES is `None` where P was not invertible).
fn mean_of_sampled(v: &[Option<f64>]) -> f64 {
    let v: Vec<f64> = v.iter().flatten().copied().collect();
    Stats::of(&v).mean
}

/// The Euler filter's EKF1 (`Config::euler()`) on world `k` without a speed accuracy:
/// what the default must not fall behind when the receiver reports none (as `SACC_EULER`).
pub const SACC_EULER: &str = "none/euler";

/// Flies every world with every [`SACC`] variant, and the Euler EKF1 without a report,
/// in parallel.
pub fn run_all(worlds: &[World], cfg: Config) -> Result<Vec<RunResult>> {
    let all: Vec<usize> = (0..worlds.len()).collect();
    run_some(worlds, &all, cfg)
}

/// [`run_all`] for the worlds numbered `ks` only (a lost run of a draw flown again).
pub fn run_some(worlds: &[World], ks: &[usize], cfg: Config) -> Result<Vec<RunResult>> {
    // JSBSim flights first, one at a time: two runs must not fly the same truth at once.
    for &k in ks {
        if let Some(name) = worlds[k].base.strip_prefix("jsbsim:") {
            fly_jsbsim(name)?;
        }
    }
    let jobs: Vec<(usize, &'static str)> =
        ks.iter().flat_map(|&k| SACC.iter().chain([&SACC_EULER]).map(move |s| (k, *s))).collect();
    jobs.par_iter()
        .map(|&(k, s)| {
            let (sacc, cfg) = if s == SACC_EULER { ("none", Config::euler()) } else { (s, cfg) };
            let mut r = run(k, &worlds[k], sacc, cfg).with_context(|| worlds[k].label())?;
            r.sacc = s;
            Ok(r)
        })
        .collect()
}

/// The summary per receiver variant and sensor grade: runs, lost, roll/pitch RMS (mean
/// over runs), its worst ratio to the honest report of the same world, yaw RMS, NEES,
/// beyond 4σ. Markdown.
pub fn table(worlds: &[World], res: &[RunResult]) -> String {
    let mut s = String::from(
        "| sAcc reported | sensors | runs | lost | roll/pitch RMS [°] | worst ratio to honest | tilt RMS (NED) [°] | worst tilt ratio | yaw RMS [°] | NEES att (bounds) | beyond 4σ |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for spec in [SensorSpec::Thesis, SensorSpec::Realistic] {
        for sacc in SACC.iter().copied().chain([SACC_EULER]) {
            let runs: Vec<&RunResult> =
                res.iter().filter(|r| r.sacc == sacc && worlds[r.world].spec == spec).collect();
            if runs.is_empty() {
                continue;
            }
            let n = runs.len() as f64;
            let lost = runs.iter().filter(|r| r.lost()).count();
            let mean = |f: fn(&RunResult) -> f64| runs.iter().map(|r| f(r)).sum::<f64>() / n;
            let worst = |f: fn(&RunResult) -> f64| {
                runs.iter().filter_map(|r| Some(f(r) / f(r.honest(res)?))).fold(0.0f64, f64::max)
            };
            let (lo, hi) = metrics::chi2_mean_bounds(3, runs.len());
            s += &format!(
                "| {sacc} | {} | {} | {lost} | {:.3} | {:.2} | {:.3} | {:.2} | {:.3} | {:.2} ({lo:.2}–{hi:.2}) | {:.2} % |\n",
                spec.name(),
                runs.len(),
                mean(RunResult::roll_pitch).to_degrees(),
                worst(RunResult::roll_pitch),
                mean(|r| r.tilt_rms).to_degrees(),
                worst(|r| r.tilt_rms),
                mean(|r| r.rms[2]).to_degrees(),
                mean(|r| r.nees),
                mean(|r| r.beyond4) * 100.0
            );
        }
    }
    s
}

/// One line per run: world, variant, figures; lost runs marked.
pub fn details(worlds: &[World], res: &[RunResult]) -> String {
    let mut s = String::from(
        "| world | sAcc | roll / pitch / yaw RMS [°] | tilt RMS (NED) [°] | tilt max [°] | yaw max after a turn [°] | NEES att (N / E / D) | beyond 4σ | |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in res {
        let d = r.rms.map(f64::to_degrees);
        s += &format!(
            "| {} | {} | {:.3} / {:.3} / {:.3} | {:.3} | {:.2} | {:.2} | {:.2} ({:.1} / {:.1} / {:.1}) | {:.1} % | {} |\n",
            worlds[r.world].label(),
            r.sacc,
            d[0],
            d[1],
            d[2],
            r.tilt_rms.to_degrees(),
            r.tilt_max.to_degrees(),
            r.yaw_max.to_degrees(),
            r.nees,
            r.nees_axis[0],
            r.nees_axis[1],
            r.nees_axis[2],
            r.beyond4 * 100.0,
            if r.lost() { "**lost**" } else { "" }
        );
    }
    s
}

/// Markers of the generated block in a markdown file.
const BEGIN: &str = "<!-- robust:begin -->";
const END: &str = "<!-- robust:end -->";

/// Rewrites the block between [`BEGIN`] and [`END`] of the markdown file `path` with `body`.
pub fn write_doc(path: &std::path::Path, body: &str) -> Result<()> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let (Some(a), Some(b)) = (text.find(BEGIN), text.find(END)) else {
        anyhow::bail!("{} has no `{BEGIN}` … `{END}` block to rewrite", path.display());
    };
    anyhow::ensure!(a < b, "{}: `{END}` comes before `{BEGIN}`", path.display());
    let new = format!("{}{BEGIN}\n{body}{}", &text[..a], &text[b..]);
    std::fs::write(path, new).with_context(|| format!("cannot write {}", path.display()))
}
