//! Fixed-wing flight simulator with sensor error models (the thesis' §5.1
//! environment, rebuilt): a nonlinear 6-DoF airframe (Aerosonde or Zagi, Beard &
//! McLain), constant wind + Dryden turbulence, a loop-closure autopilot flying a
//! TOML maneuver script, and IMU / GPS / airspeed models (thesis eqs 4.1–4.16,
//! Table 5.1). Output: a [`FlightLog`](crate::log::FlightLog) (the docs/formats.md CSV
//! contract) plus per-row truth extras. f64 throughout; a run is a pure function
//! of (scenario, seed).
//!
//! ```no_run
//! let sc = sim_harness::sim::load_scenario("flight1")?.with_spec(sim_harness::sim::SensorSpec::Realistic);
//! let out = sim_harness::sim::run(&sc, 42)?;
//! # anyhow::Ok(())
//! ```

pub mod aircraft;
pub mod autopilot;
pub mod dynamics;
pub mod geodetic;
pub mod kinematic;
pub mod names;
pub mod random;
pub mod rotation;
pub mod scenario;
pub mod sensors;
pub mod trim;
pub mod wind;

use crate::log::{FlightLog, LogRow};
use anyhow::{bail, Result};
use autopilot::{Autopilot, Feedback};
use dynamics::{rk4_step, State, WindInput};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rotation::V3;
use sensors::{AirspeedModel, BaroModel, GpsModel, ImuModel, SensorParams, VibrationModel};

pub use scenario::{Maneuver, Scenario};

/// Sensor presets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SensorSpec {
    /// Thesis Table 5.1 (see [`SensorParams::thesis`]).
    Thesis,
    /// Typical MEMS IMU + u-blox receiver (see [`SensorParams::realistic`]).
    Realistic,
}

impl SensorSpec {
    pub fn params(self) -> SensorParams {
        match self {
            SensorSpec::Thesis => SensorParams::thesis(),
            SensorSpec::Realistic => SensorParams::realistic(),
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            SensorSpec::Thesis => "thesis",
            SensorSpec::Realistic => "realistic",
        }
    }
}

impl std::str::FromStr for SensorSpec {
    type Err = anyhow::Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "thesis" => Ok(SensorSpec::Thesis),
            "realistic" => Ok(SensorSpec::Realistic),
            _ => bail!("unknown sensor spec {s:?}: use \"thesis\" or \"realistic\""),
        }
    }
}

/// Names of the built-in scenarios.
pub fn builtin_names() -> &'static [&'static str] {
    &[
        "flight1",
        "flight2",
        "aggressive",
        "level",
        "flight1_outage",
        "coordinated_turn",
        "aerobatics",
        "aerobatics_realistic",
        "aerobatics_wind5",
    ]
}

/// Loads a built-in scenario by name or a TOML scenario file by path.
pub fn load_scenario(name_or_path: &str) -> Result<Scenario> {
    scenario::load(name_or_path)
}

/// Truth beyond the log's attitude and gyro bias, one per log row.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TruthExtra {
    /// s (same as the row's `t`)
    pub t: f64,
    /// Position NED, m.
    pub position_ned: V3,
    /// Inertial velocity NED, m/s.
    pub velocity_ned: V3,
    /// True airspeed, m/s; angle of attack and sideslip, rad.
    pub airspeed: f64,
    pub alpha: f64,
    pub beta: f64,
    /// True body rates p, q, r, rad/s (FRD).
    pub body_rates: V3,
    /// True specific force, m/s² (FRD).
    pub specific_force: V3,
    /// Wind (steady + shear + discrete gusts + Dryden turbulence) NED, m/s.
    pub wind_ned: V3,
    /// True accelerometer bias, m/s².
    pub accel_bias: V3,
    /// Servo positions: elevator, aileron, rudder (rad), throttle (0–1).
    pub controls: [f64; 4],
}

/// A simulated flight.
#[derive(Debug, Clone)]
pub struct SimOutput {
    pub log: FlightLog,
    pub truth: Vec<TruthExtra>,
    /// The IMU as drawn at turn-on (misalignment, scale factors, turn-on biases).
    pub imu: ImuModel,
}

/// Independent random streams, so changing one model leaves the others' noise alone.
fn stream(seed: u64, id: u64) -> ChaCha8Rng {
    let mut r = ChaCha8Rng::seed_from_u64(seed);
    r.set_stream(id);
    r
}

/// Flies `scenario` with sensor noise from `seed`, keeping the whole log in memory
/// (≈ 350 bytes per row: use [`run_streaming`] for flights of hours).
pub fn run(scenario: &Scenario, seed: u64) -> Result<SimOutput> {
    let n = (scenario.duration * scenario.sensors.imu.rate_hz).round().max(0.0) as usize + 1;
    let mut log = FlightLog { rows: Vec::with_capacity(n.min(1 << 24)) };
    let mut truth = Vec::with_capacity(n.min(1 << 24));
    let imu = run_streaming(scenario, seed, |r, x| {
        log.rows.push(*r);
        truth.push(*x);
    })?;
    Ok(SimOutput { log, truth, imu })
}

/// Like [`run`], but hands each row and its truth to `sink` as it is produced
/// (constant memory). Returns the IMU as drawn at turn-on.
pub fn run_streaming(
    scenario: &Scenario,
    seed: u64,
    mut sink: impl FnMut(&LogRow, &TruthExtra),
) -> Result<ImuModel> {
    scenario.validate()?;
    // Rows before the log's start are flown, not logged (an estimator switched on in flight).
    let start = scenario.log_start - 1e-9;
    let mut sink = move |r: &LogRow, x: &TruthExtra| {
        if r.t >= start {
            sink(r, x)
        }
    };
    if !scenario.segments.is_empty() {
        return kinematic::run_streaming(scenario, seed, sink);
    }
    let sc = scenario;
    let af = &sc.airframe;
    let trim = trim::level_trim(af, sc.initial.airspeed_m_s)?;
    let mut rng_imu = stream(seed, 1);
    let mut rng_gps = stream(seed, 2);
    let mut rng_air = stream(seed, 3);
    let mut rng_wind = stream(seed, 4);
    let mut rng_baro = stream(seed, 5);
    let (mut vib, mut rng_vib) = (VibrationModel::new(&sc.vibration), stream(seed, 7));

    let psi0 = sc.initial.heading_deg.to_radians();
    let mut state = State::new(
        [sc.initial.north_m, sc.initial.east_m, -sc.initial.altitude_m],
        [0.0; 3],
        [0.0, trim.alpha, psi0],
    );
    // Air-relative trim velocity plus the steady wind, in body axes.
    let h0 = sc.initial.altitude_m;
    let steady_at = |t: f64, h: f64| sc.wind.steady_at(t, h, h0);
    let w_b = rotation::mul_mtv(&rotation::r_nb_quat(state.quat), steady_at(0.0, h0));
    state.vel_b = rotation::add([trim.va * trim.alpha.cos(), 0.0, trim.va * trim.alpha.sin()], w_b);

    let mut imu = ImuModel::new(&sc.sensors.imu, &mut rng_imu);
    let imu_draw = imu.clone();
    let mut gps = GpsModel::new(&sc.sensors.gps, &sc.gps_outages, stream(seed, 6));
    let mut baro = BaroModel::new(&sc.sensors.baro);
    let mut aspd = AirspeedModel::new(&sc.sensors.airspeed);
    let mut dryden = sc.wind.dryden_params()?.map(|(s, l)| wind::Dryden::new(s, l, trim.va));
    let mut ap = Autopilot::new(af, &trim, sc.roll_error_max);
    let mut script = scenario::Script::new(sc);

    let rate = sc.sensors.imu.rate_hz;
    let n_rows = (sc.duration * rate).round() as usize;
    let sub = ((sc.integration_hz / rate).round() as usize).max(1);
    let dt = 1.0 / (rate * sub as f64);
    let total = n_rows * sub;

    for i in 0..=total {
        let t = i as f64 * dt;
        let wind = WindInput {
            steady_ned: steady_at(t, -state.pos[2]),
            gust_body: dryden.as_ref().map_or([0.0; 3], |d| d.gust()),
        };
        let d0 = state.derive(af, &ap.out, &wind);
        let euler = state.euler();
        let v = d0.vel_ned;
        let fb = Feedback {
            roll: euler[0],
            pitch: euler[1],
            p: state.omega[0],
            q: state.omega[1],
            r: state.omega[2],
            course: v[1].atan2(v[0]),
            ground_speed: v[0].hypot(v[1]),
            altitude: -state.pos[2],
            va: d0.air.va,
            beta: d0.air.beta,
        };
        let tg = script.targets(t, dt, &fb);
        // Servo positions now (u0) and at the end of the step (u1).
        let u0 = ap.out;
        let u1 = ap.step(&tg, &fb, dt);
        let p_now = state.pos;
        gps.on_step_at(t, v, Some(|| geodetic::lla_of(p_now)), &mut rng_gps);
        if i % sub == 0 {
            let t_row = (i / sub) as f64 / rate;
            let d = d0;
            let bias = imu.gyro_bias();
            let accel_bias = imu.accel_bias();
            let (vw, vf) = vib.sample(t_row, &mut rng_vib);
            let (gyro, accel) = imu.sample(
                rotation::add(state.omega, vw),
                rotation::add(d.specific_force, vf),
                &mut rng_imu,
            );
            let row = LogRow {
                t: t_row,
                gyro,
                accel,
                gps: gps.pop_available(t_row),
                airspeed: aspd.sample(t_row, d.air.va, &mut rng_air),
                baro_alt: baro.sample(t_row, geodetic::lla_of(state.pos)[2], &mut rng_baro),
                truth: Some(euler),
                truth_bias: Some(bias),
                reference: None,
                truth_wind: Some(d.wind_ned),
            };
            let extra = TruthExtra {
                t: t_row,
                position_ned: state.pos,
                velocity_ned: d.vel_ned,
                airspeed: d.air.va,
                alpha: d.air.alpha,
                beta: d.air.beta,
                body_rates: state.omega,
                specific_force: d.specific_force,
                wind_ned: d.wind_ned,
                accel_bias,
                controls: [u0.elevator, u0.aileron, u0.rudder, u0.throttle],
            };
            sink(&row, &extra);
        }
        if i == total {
            break;
        }
        if let Some(d) = dryden.as_mut() {
            d.step(dt, &mut rng_wind);
        }
        // Shear: the wind at the end of the step at the altitude predicted to 2nd order,
        // so it matches the next step's start (the accelerometer truth stays continuous).
        let wind1 = WindInput {
            steady_ned: steady_at(t + dt, -(state.pos[2] + d0.vel_ned[2] * dt)),
            gust_body: dryden.as_ref().map_or([0.0; 3], |d| d.gust()),
        };
        state = rk4_step(af, &state, (&u0, &u1), (&wind, &wind1), dt);
        let ok = state.pos.iter().chain(&state.vel_b).chain(&state.omega).all(|x| x.is_finite());
        if !ok {
            bail!("scenario {}: the simulation diverged at t = {:.2} s", sc.name, t);
        }
        if state.pos[2] > 0.0 {
            bail!("scenario {}: the aircraft hit the ground at t = {:.2} s", sc.name, t);
        }
    }
    Ok(imu_draw)
}
