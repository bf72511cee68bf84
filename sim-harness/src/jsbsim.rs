//! Flights from JSBSim, a flight-dynamics model we did not write: `scripts/jsbsim_fly.py`
//! flies an airframe JSBSim ships through scripted turns, aerobatic figures (T-6 Texan II:
//! loop, axial roll, 75° turns, Immelmann, inverted, split-S, Cuban eight) or a seeded random
//! plan (`randN`: airframe, wind, turbulence, bank and height schedule) and writes its truth
//! (attitude, body rates, specific force, NED velocity, position, airspeed, wind); [`export`]
//! passes that truth through this harness's own sensor models (`sim::sensors`, the
//! scenario presets) into a flight log that `report` and `compare` read as `jsbsim:NAME`.
//! The logs are generated into `target/jsbsim/` (never committed).

use crate::log::{FlightLog, LogRow};
use crate::sim::sensors::{AirspeedModel, BaroModel, GpsModel, ImuModel, SensorParams};
use anyhow::{bail, Context, Result};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The named flights `scripts/jsbsim_fly.py` knows (besides `randN`).
pub const FLIGHTS: [&str; 5] =
    ["c172_turns", "c172_wind7", "j3cub_turns", "t6_aerobatics", "t6_aerobatics_wind6"];

/// Whether `name` is a flight the script flies: a named one, or `randN` with N ≥ 1.
pub fn is_flight(name: &str) -> bool {
    FLIGHTS.contains(&name)
        || name
            .strip_prefix("rand")
            .and_then(|n| n.parse::<u32>().ok())
            .is_some_and(|n| n >= 1 && !name[4..].starts_with('0'))
}

/// Arguments of `sim-harness jsbsim`.
#[derive(clap::Args, Debug, Clone)]
pub struct JsbsimArgs {
    /// Flights to generate: c172_turns, c172_wind7, j3cub_turns, t6_aerobatics,
    /// t6_aerobatics_wind6, or randN (a seeded random flight, N ≥ 1). Default: the named ones.
    pub flights: Vec<String>,
    /// Sensor-noise seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Sensor preset: `thesis` (Table 5.1) or `realistic`.
    #[arg(long, default_value = "thesis")]
    pub spec: String,
}

/// Where the flight log of JSBSim flight `name` is written and read.
pub fn log_path(name: &str) -> PathBuf {
    dir().join(format!("{name}.csv"))
}

fn dir() -> PathBuf {
    std::env::var_os("WING_AHRS_JSBSIM_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("target/jsbsim"))
}

/// The script, found from the harness crate's source tree.
fn script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scripts/jsbsim_fly.py")
}

/// `sim-harness jsbsim`: flies each flight in JSBSim and exports it through our sensors.
pub fn run(args: &JsbsimArgs) -> Result<()> {
    let sensors = match args.spec.as_str() {
        "thesis" => SensorParams::thesis(),
        "realistic" => SensorParams::realistic(),
        s => bail!("--spec {s:?}: use thesis or realistic"),
    };
    let flights: Vec<String> = if args.flights.is_empty() {
        FLIGHTS.map(String::from).to_vec()
    } else {
        args.flights.clone()
    };
    std::fs::create_dir_all(dir()).with_context(|| format!("creating {}", dir().display()))?;
    for f in &flights {
        let truth = dir().join(format!("{f}.truth.csv"));
        fly(f, &truth)?;
        let log = export(&truth, &sensors, args.seed)?;
        crate::csv::write_log_file(&log_path(f), &log)?;
        println!("jsbsim:{f}: {} rows → {}", log.rows.len(), log_path(f).display());
    }
    Ok(())
}

/// Flies `name` in JSBSim (`scripts/jsbsim_fly.py`) and writes its truth CSV to `truth`.
pub fn fly(name: &str, truth: &Path) -> Result<()> {
    if !is_flight(name) {
        bail!("unknown JSBSim flight `{name}` (known: {}, randN)", FLIGHTS.join(", "));
    }
    let st = Command::new("python3")
        .arg(script())
        .arg(name)
        .arg(truth)
        .status()
        .context("running python3 scripts/jsbsim_fly.py (needs the PyPI package jsbsim)")?;
    if !st.success() {
        bail!("scripts/jsbsim_fly.py {name} failed (is `jsbsim` installed? python3 -m pip install jsbsim)");
    }
    Ok(())
}

/// One row of JSBSim truth (units and frames as in the script's docstring).
struct Truth {
    t: f64,
    att: [f64; 3],
    rates: [f64; 3],
    f_b: [f64; 3],
    vel: [f64; 3],
    lla: [f64; 3],
    va: f64,
    wind: [f64; 3],
}

fn read_truth(path: &Path) -> Result<Vec<Truth>> {
    let mut rdr =
        csv::Reader::from_path(path).with_context(|| format!("opening {}", path.display()))?;
    let mut out = Vec::new();
    for (k, rec) in rdr.records().enumerate() {
        let rec = rec.with_context(|| format!("{}: row {}", path.display(), k + 2))?;
        let v: Vec<f64> = rec
            .iter()
            .map(|c| c.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .with_context(|| format!("{}: row {}: not a number", path.display(), k + 2))?;
        if v.len() != 20 {
            bail!("{}: row {} has {} columns, expected 20", path.display(), k + 2, v.len());
        }
        let a = |i: usize| [v[i], v[i + 1], v[i + 2]];
        out.push(Truth {
            t: v[0],
            att: a(1),
            rates: a(4),
            f_b: a(7),
            vel: a(10),
            lla: a(13),
            va: v[16],
            wind: a(17),
        });
    }
    if out.len() < 2 {
        bail!("{}: no truth rows", path.display());
    }
    Ok(out)
}

/// Our sensor models applied to JSBSim's truth at its 100 Hz rows: the IMU (noise, turn-on
/// and Gauss–Markov biases, etc.), the GPS receiver (velocity noise, smoothing, rate,
/// latency; the fix's position is JSBSim's at the epoch plus the receiver's position error),
/// the airspeed sensor and the barometer (on JSBSim's WGS-84 height). Independent seeded
/// streams per sensor, numbered as in the simulator.
pub fn export(truth_csv: &Path, sensors: &SensorParams, seed: u64) -> Result<FlightLog> {
    let truth = read_truth(truth_csv)?;
    let stream = |id: u64| {
        let mut r = ChaCha8Rng::seed_from_u64(seed);
        r.set_stream(id);
        r
    };
    let (mut rng_imu, mut rng_gps, mut rng_air) = (stream(1), stream(2), stream(3));
    let mut imu = ImuModel::new(&sensors.imu, &mut rng_imu);
    let mut gps = GpsModel::new(&sensors.gps, &[], stream(6));
    let mut aspd = AirspeedModel::new(&sensors.airspeed);
    let (mut baro, mut rng_baro) = (BaroModel::new(&sensors.baro), stream(5));
    let mut rows = Vec::with_capacity(truth.len());
    for (k, x) in truth.iter().enumerate() {
        gps.on_step_at(x.t, x.vel, Some(|| x.lla), &mut rng_gps);
        let bias = imu.gyro_bias();
        // JSBSim's row k holds the state at t_k and the rates and forces that move it to
        // t_k+1 (its attitude and velocity differences match them forward, not backward);
        // an IMU sample at t_k reads the interval before it, so row k takes row k−1's.
        let step = &truth[k.saturating_sub(1)];
        let (gyro, accel) = imu.sample(step.rates, step.f_b, &mut rng_imu);
        rows.push(LogRow {
            t: x.t,
            gyro,
            accel,
            gps: gps.pop_available(x.t),
            airspeed: aspd.sample(x.t, x.va, &mut rng_air),
            baro_alt: baro.sample(x.t, x.lla[2], &mut rng_baro),
            truth: Some(x.att),
            truth_bias: Some(bias),
            reference: None,
            truth_wind: Some(x.wind),
        });
    }
    Ok(FlightLog { rows })
}

#[cfg(test)]
mod tests {
    use super::is_flight;

    #[test]
    fn knows_the_named_and_the_random_flights_only() {
        for f in ["c172_turns", "t6_aerobatics_wind6", "rand1", "rand42"] {
            assert!(is_flight(f), "{f}");
        }
        for f in ["rand", "rand0", "rand01", "rand-1", "randx", "c172", "t6_aerobatics "] {
            assert!(!is_flight(f), "{f}");
        }
    }
}
