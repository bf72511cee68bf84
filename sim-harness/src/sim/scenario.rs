//! Scenario files (TOML): airframe, initial condition, wind, sensors, GPS
//! outages and a maneuver script. See `sim-harness/scenarios/*.toml` for
//! commented examples. Key names carry units (`_deg`, `_m_s`, …): scenario
//! files are written by people; the simulator converts to SI radians on load.
//!
//! `base = "flight1"` (a built-in name or a path relative to the file) makes a
//! file a variant of another: tables merge key by key, the variant's values win,
//! arrays (e.g. `maneuver`) are replaced whole.
//!
//! `random:SEED` is a randomised flight (airframe, script, wind, sensors; [`super::random`]).
//! Names may carry modifiers: `flight2+wind=6@45,turb=light` is flight2 in a 6 m/s
//! wind from 045° with light turbulence (grammar and the `wind` group in
//! [`super::names`]; docs/scenarios.md).
//!
//! ```toml
//! name = "my_flight"            # required
//! description = "…"
//! duration_s = 100.0            # required
//! airframe = "aerosonde"        # aerosonde | easystar_scaled | zagi
//! airframe_scale = { mass = 1.1, inertia = 0.9, aero = 1.0, control = 1.0 }  # optional
//! integration_hz = 1000.0       # internal RK4 rate (≥ 100)
//! roll_error_max_deg = 30.0     # roll-loop design error: smaller = stiffer
//! gps_outages = [[60.0, 80.0]]  # epochs [start, end) s without fixes
//! [[vibration]]                 # see sensors::VibrationSpec: IMU-sensed vibration
//! start_s = 40.0
//! end_s = 60.0
//! accel_m_s2 = 3.0
//! repeat_every_s = 100.0        # optional: replay the script periodically
//! [initial]                     # trimmed, wings level
//! altitude_m = 140.0
//! airspeed_m_s = 25.0
//! heading_deg = 0.0             # also north_m, east_m
//! [wind]
//! ned_m_s = [0.0, 0.0, 0.0]     # steady wind (air-mass velocity)
//! turbulence = "none"           # none | light | moderate | custom (sigma_m_s, length_m)
//! shear_exponent = 0.0          # power-law shear (h / h_ref)^α; also shear_m_s_per_m = [n, e, d]
//! shear_reference_altitude_m = 100.0   # default: the initial altitude
//! [[wind.gust]]                 # discrete 1 − cos gust
//! t_s = 20.0
//! duration_s = 4.0
//! ned_m_s = [0.0, 3.0, 0.0]     # peak
//! [sensors]
//! preset = "thesis"             # thesis | realistic; then override any key:
//! [sensors.imu]                 # see sensors::ImuParams (rate_hz, gyro_noise_deg_s, …)
//! [sensors.gps]                 # see sensors::GpsParams (rate_hz, latency_s, …)
//! [sensors.airspeed]            # see sensors::AirspeedParams
//! [sensors.baro]                # see sensors::BaroParams (rate_hz 0 = none)
//! [[segment]]                   # kinematic script instead (see kinematic.rs):
//! figure = "loop"               # or duration_s with p/q/r_deg_s, load_factor, level
//! [[maneuver]]                  # see Maneuver: sticky commands from time t
//! t = 5.0
//! bank_deg = 25.0
//! climb_m_s = 2.0
//! ```

use super::aircraft::Airframe;
use super::autopilot::{Feedback, Lateral, Longitudinal, Targets};
use super::kinematic::{Segment, SegmentSpec};
use super::sensors::{SensorParams, VibrationSpec};
use super::wind::WindSpec;
use super::SensorSpec;
use anyhow::{anyhow, bail, ensure, Context, Result};
use serde::Deserialize;
use std::path::Path;

/// Built-in scenarios, compiled in so the binary works from any directory.
pub(crate) const BUILTIN: &[(&str, &str)] = &[
    ("flight1", include_str!("../../scenarios/flight1.toml")),
    ("flight2", include_str!("../../scenarios/flight2.toml")),
    ("aggressive", include_str!("../../scenarios/aggressive.toml")),
    ("level", include_str!("../../scenarios/level.toml")),
    ("flight1_outage", include_str!("../../scenarios/flight1_outage.toml")),
    ("coordinated_turn", include_str!("../../scenarios/coordinated_turn.toml")),
    ("aerobatics", include_str!("../../scenarios/aerobatics.toml")),
    ("aerobatics_realistic", include_str!("../../scenarios/aerobatics_realistic.toml")),
    ("aerobatics_wind5", include_str!("../../scenarios/aerobatics_wind5.toml")),
];

/// Initial condition: trimmed, wings level.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Initial {
    pub altitude_m: f64,
    pub airspeed_m_s: f64,
    #[serde(default)]
    pub heading_deg: f64,
    #[serde(default)]
    pub north_m: f64,
    #[serde(default)]
    pub east_m: f64,
}

/// Scales applied to the named airframe (`[airframe_scale]`, each default 1): a family
/// of airframes around the three presets, for Monte Carlo.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AirframeScale {
    /// Mass factor.
    #[serde(default = "one")]
    pub mass: f64,
    /// Factor on Jx, Jy, Jz, Jxz.
    #[serde(default = "one")]
    pub inertia: f64,
    /// Factor on the lift slope and the stability and damping derivatives
    /// (C_L_α, C_m_α, C_m_q, C_Y_β, C_ℓ_β, C_ℓ_p, C_n_β, C_n_r).
    #[serde(default = "one")]
    pub aero: f64,
    /// Factor on the control derivatives (C_L_δe, C_m_δe, C_ℓ_δa, C_n_δr, C_Y_δr).
    #[serde(default = "one")]
    pub control: f64,
}

fn one() -> f64 {
    1.0
}

impl AirframeScale {
    /// The scaled airframe; factors must be in [0.5, 2].
    pub fn apply(&self, a: &Airframe) -> Result<Airframe> {
        for (k, v) in [
            ("mass", self.mass),
            ("inertia", self.inertia),
            ("aero", self.aero),
            ("control", self.control),
        ] {
            ensure!(
                v.is_finite() && (0.5..=2.0).contains(&v),
                "airframe_scale.{k} must be in [0.5, 2], got {v}"
            );
        }
        let mut b = a.clone();
        b.mass *= self.mass;
        for j in [&mut b.Jx, &mut b.Jy, &mut b.Jz, &mut b.Jxz] {
            *j *= self.inertia;
        }
        for c in [
            &mut b.C_L_alpha,
            &mut b.C_m_alpha,
            &mut b.C_m_q,
            &mut b.C_Y_beta,
            &mut b.C_ell_beta,
            &mut b.C_ell_p,
            &mut b.C_n_beta,
            &mut b.C_n_r,
        ] {
            *c *= self.aero;
        }
        for c in [
            &mut b.C_L_delta_e,
            &mut b.C_m_delta_e,
            &mut b.C_ell_delta_a,
            &mut b.C_n_delta_r,
            &mut b.C_Y_delta_r,
        ] {
            *c *= self.control;
        }
        Ok(b)
    }
}

/// A square pulse pair: +amplitude for half the period, then −amplitude.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Doublet {
    pub amplitude_deg: f64,
    pub period_s: f64,
}

/// One script entry: from time `t` (s) on, the given commands hold until changed.
/// Doublets are one-shot and start at `t`.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Maneuver {
    pub t: f64,
    /// Lateral: hold a bank angle, or fly a course (one of the two).
    pub bank_deg: Option<f64>,
    pub course_deg: Option<f64>,
    /// Bank-command slew rate, °/s (default 45).
    pub bank_rate_deg_s: Option<f64>,
    /// Bank limit of the course loop, ° (default 35).
    pub bank_limit_deg: Option<f64>,
    /// Longitudinal: `altitude_m` (reached at |climb_m_s|, default 2 m/s), or a
    /// steady `climb_m_s` alone (positive up), or `pitch_deg`.
    pub altitude_m: Option<f64>,
    pub climb_m_s: Option<f64>,
    pub pitch_deg: Option<f64>,
    /// Airspeed, m/s, approached at `airspeed_rate_m_s2` (default 1).
    pub airspeed_m_s: Option<f64>,
    pub airspeed_rate_m_s2: Option<f64>,
    /// Sideslip the rudder holds, ° (crossed controls); `coordinated = false`
    /// opens the sideslip loop (rudder only from the offsets below).
    pub sideslip_deg: Option<f64>,
    pub coordinated: Option<bool>,
    /// Sticky open-loop surface offsets, °.
    pub rudder_deg: Option<f64>,
    pub aileron_deg: Option<f64>,
    pub elevator_deg: Option<f64>,
    pub rudder_doublet: Option<Doublet>,
    pub aileron_doublet: Option<Doublet>,
    pub elevator_doublet: Option<Doublet>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ScenarioFile {
    name: String,
    #[serde(default)]
    description: String,
    duration_s: f64,
    #[serde(default = "aerosonde")]
    airframe: String,
    #[serde(default)]
    airframe_scale: Option<AirframeScale>,
    #[serde(default = "default_integration_hz")]
    integration_hz: f64,
    #[serde(default = "default_roll_error")]
    roll_error_max_deg: f64,
    #[serde(default)]
    gps_outages: Vec<[f64; 2]>,
    #[serde(default)]
    vibration: Vec<VibrationSpec>,
    initial: Initial,
    #[serde(default)]
    wind: WindSpec,
    #[serde(default)]
    sensors: Option<toml::Table>,
    #[serde(default)]
    maneuver: Vec<Maneuver>,
    /// Kinematic script (aerobatics): replaces the 6-DoF airframe and autopilot.
    #[serde(default)]
    segment: Vec<SegmentSpec>,
    #[serde(default)]
    repeat_every_s: Option<f64>,
    /// The log starts here, s (default 0): the estimator is switched on in flight.
    #[serde(default)]
    log_start_s: f64,
}

fn aerosonde() -> String {
    "aerosonde".into()
}
fn default_integration_hz() -> f64 {
    1000.0
}
fn default_roll_error() -> f64 {
    30.0
}

/// A loaded scenario (see the module doc for the file format).
#[derive(Debug, Clone, PartialEq)]
pub struct Scenario {
    pub name: String,
    pub description: String,
    /// The first logged time, s: rows before it are flown but not logged (an estimator
    /// switched on in flight, e.g. after a power cycle in a turn).
    pub log_start: f64,
    /// s
    pub duration: f64,
    pub airframe: Airframe,
    /// Internal RK4 rate, Hz (rounded to a whole number of steps per IMU sample).
    pub integration_hz: f64,
    /// Roll-loop design error (smaller = stiffer roll loop), rad.
    pub roll_error_max: f64,
    pub initial: Initial,
    pub wind: WindSpec,
    /// Name of the sensor preset the parameters started from.
    pub sensor_preset: String,
    pub sensors: SensorParams,
    /// Half-open GPS epoch intervals [start, end) s without fixes.
    pub gps_outages: Vec<(f64, f64)>,
    /// Airframe vibration episodes (`[[vibration]]`), sensed by the IMU.
    pub vibration: Vec<VibrationSpec>,
    pub maneuvers: Vec<Maneuver>,
    /// Replay the maneuver script every this many seconds (long flights), s.
    pub repeat_every: Option<f64>,
    /// Kinematic script (non-empty: flown by [`super::kinematic`], not the 6-DoF model).
    pub segments: Vec<Segment>,
}

impl Scenario {
    /// Replaces all sensor parameters by a preset (the file's overrides are dropped;
    /// GPS outages are part of the scenario and stay).
    pub fn with_spec(mut self, spec: SensorSpec) -> Self {
        self.sensors = spec.params();
        self.sensor_preset = spec.name().into();
        self
    }

    /// Changes the duration, s (the script beyond it is not flown).
    pub fn with_duration(mut self, s: f64) -> Self {
        self.duration = s;
        self
    }

    /// Checks every value a run depends on.
    pub fn validate(&self) -> Result<()> {
        let n = &self.name;
        ensure!(
            self.duration.is_finite() && self.duration > 0.0 && self.duration <= 48.0 * 3600.0,
            "scenario {n}: duration_s must be in (0, 172800] s, got {}",
            self.duration
        );
        ensure!(
            self.log_start.is_finite() && self.log_start >= 0.0 && self.log_start < self.duration,
            "scenario {n}: log_start_s must be in [0, duration_s), got {}",
            self.log_start
        );
        ensure!(
            self.integration_hz.is_finite()
                && self.integration_hz >= 100.0
                && self.integration_hz <= 20000.0,
            "scenario {n}: integration_hz must be in [100, 20000], got {}",
            self.integration_hz
        );
        ensure!(
            self.initial.altitude_m.is_finite() && self.initial.altitude_m > 0.0,
            "scenario {n}: initial.altitude_m must be > 0"
        );
        ensure!(
            self.initial.airspeed_m_s.is_finite() && self.initial.airspeed_m_s > 0.0,
            "scenario {n}: initial.airspeed_m_s must be > 0"
        );
        self.sensors.validate().with_context(|| format!("scenario {n}"))?;
        self.wind.dryden_params().with_context(|| format!("scenario {n}"))?;
        self.wind.validate().with_context(|| format!("scenario {n}"))?;
        for v in &self.vibration {
            v.validate().with_context(|| format!("scenario {n}"))?;
        }
        for &(a, b) in &self.gps_outages {
            ensure!(
                a.is_finite() && b.is_finite() && a < b,
                "scenario {n}: gps_outages entry [{a}, {b}] must have start < end"
            );
        }
        if let Some(p) = self.repeat_every {
            let last_t = self.maneuvers.last().map_or(0.0, |m| m.t);
            ensure!(
                p.is_finite() && p > 0.0 && p > last_t && !self.maneuvers.is_empty(),
                "scenario {n}: repeat_every_s must be longer than the last maneuver time ({last_t} s) and the script not empty"
            );
        }
        let mut last = 0.0;
        for (i, m) in self.maneuvers.iter().enumerate() {
            ensure!(
                m.t.is_finite() && m.t >= last,
                "scenario {n}: maneuver #{} at t = {} s: times must start at ≥ 0 and not decrease",
                i + 1,
                m.t
            );
            last = m.t;
            ensure!(
                !(m.bank_deg.is_some() && m.course_deg.is_some()),
                "scenario {n}: maneuver at t = {} s sets both bank_deg and course_deg",
                m.t
            );
            ensure!(
                !(m.pitch_deg.is_some() && (m.altitude_m.is_some() || m.climb_m_s.is_some())),
                "scenario {n}: maneuver at t = {} s sets pitch_deg together with altitude_m/climb_m_s",
                m.t
            );
            for d in [m.rudder_doublet, m.aileron_doublet, m.elevator_doublet].into_iter().flatten()
            {
                ensure!(
                    d.period_s > 0.0,
                    "scenario {n}: doublet at t = {} s needs period_s > 0",
                    m.t
                );
            }
        }
        Ok(())
    }
}

/// Parses a built-in name, a TOML file path, or either with `+modifiers`
/// (see [`super::names`]).
pub fn load(name_or_path: &str) -> Result<Scenario> {
    if let Some(seed) = super::random::parse_name(name_or_path) {
        let text = super::random::scenario_toml(seed?);
        return parse(&text).with_context(|| format!("random scenario {name_or_path}:\n{text}"));
    }
    let split = super::names::split(name_or_path).filter(|_| !Path::new(name_or_path).exists());
    let Some((base, mods)) = split else {
        let (table, origin) = load_table(name_or_path, None, 0)?;
        return from_table(table).with_context(|| format!("in scenario {origin}"));
    };
    let (mut table, origin) = load_table(base, None, 0)?;
    let duration = table.get("duration_s").and_then(toml::Value::as_float).unwrap_or(0.0);
    let overlay = super::names::overlay(mods, duration)
        .with_context(|| format!("in scenario name {name_or_path:?}"))?;
    let preset_switch = overlay
        .get("sensors")
        .and_then(toml::Value::as_table)
        .is_some_and(|s| s.contains_key("preset"));
    if preset_switch {
        table.remove("sensors"); // a preset switch drops the base's overrides
    }
    merge(&mut table, overlay);
    table.insert("name".into(), name_or_path.into());
    from_table(table).with_context(|| format!("in scenario {name_or_path} (base {origin})"))
}

/// Parses scenario text (e.g. for tests); `base` is resolved against built-ins only.
pub fn parse(text: &str) -> Result<Scenario> {
    let table: toml::Table = text.parse().map_err(|e| anyhow!("{e}"))?;
    let table = resolve_base(table, None, 0)?;
    from_table(table)
}

fn load_table(
    name_or_path: &str,
    dir: Option<&Path>,
    depth: usize,
) -> Result<(toml::Table, String)> {
    ensure!(depth < 8, "scenario `base` chain too deep at {name_or_path:?} (a cycle?)");
    if let Some((_, text)) = BUILTIN.iter().find(|(n, _)| *n == name_or_path) {
        let t: toml::Table =
            text.parse().map_err(|e| anyhow!("built-in scenario {name_or_path}: {e}"))?;
        return Ok((resolve_base(t, None, depth + 1)?, format!("built-in {name_or_path}")));
    }
    let path = match dir {
        Some(d) => d.join(name_or_path),
        None => Path::new(name_or_path).to_path_buf(),
    };
    if !path.exists() {
        bail!(
            "unknown scenario {name_or_path:?}: not a built-in ({}) and no such file",
            super::builtin_names().join(", ")
        );
    }
    let text =
        std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    let t: toml::Table = text.parse().map_err(|e| anyhow!("{}: {e}", path.display()))?;
    let t = resolve_base(t, path.parent(), depth + 1)
        .with_context(|| format!("in {}", path.display()))?;
    Ok((t, path.display().to_string()))
}

fn resolve_base(mut t: toml::Table, dir: Option<&Path>, depth: usize) -> Result<toml::Table> {
    let Some(base) = t.remove("base") else {
        return Ok(t);
    };
    let base = base
        .as_str()
        .ok_or_else(|| anyhow!("`base` must be a string (a built-in name or a path)"))?;
    let (mut b, _) = load_table(base, dir, depth)?;
    merge(&mut b, t);
    Ok(b)
}

/// Deep merge: tables key by key, everything else replaced.
fn merge(dst: &mut toml::Table, src: toml::Table) {
    for (k, v) in src {
        match (dst.get_mut(&k), v) {
            (Some(toml::Value::Table(d)), toml::Value::Table(s)) => merge(d, s),
            (_, v) => {
                dst.insert(k, v);
            }
        }
    }
}

fn from_table(t: toml::Table) -> Result<Scenario> {
    let f: ScenarioFile =
        toml::Value::Table(t).try_into().map_err(|e: toml::de::Error| anyhow!("{e}"))?;
    let airframe = Airframe::by_name(&f.airframe).ok_or_else(|| {
        anyhow!(
            "airframe must be \"aerosonde\", \"easystar_scaled\" or \"zagi\", not {:?}",
            f.airframe
        )
    })?;
    let airframe = match f.airframe_scale {
        Some(k) => k.apply(&airframe)?,
        None => airframe,
    };
    let (sensor_preset, sensors) = resolve_sensors(f.sensors)?;
    ensure!(
        f.segment.is_empty() || (f.maneuver.is_empty() && f.repeat_every_s.is_none()),
        "a kinematic scenario ([[segment]]) takes no [[maneuver]] or repeat_every_s"
    );
    let segments = super::kinematic::expand(&f.segment, f.initial.airspeed_m_s)?;
    let sc = Scenario {
        name: f.name,
        description: f.description,
        log_start: f.log_start_s,
        duration: f.duration_s,
        airframe,
        integration_hz: f.integration_hz,
        roll_error_max: f.roll_error_max_deg.to_radians(),
        initial: f.initial,
        wind: f.wind,
        sensor_preset,
        sensors,
        gps_outages: f.gps_outages.iter().map(|a| (a[0], a[1])).collect(),
        vibration: f.vibration,
        maneuvers: f.maneuver,
        repeat_every: f.repeat_every_s,
        segments,
    };
    sc.validate()?;
    Ok(sc)
}

fn resolve_sensors(t: Option<toml::Table>) -> Result<(String, SensorParams)> {
    let mut t = t.unwrap_or_default();
    let preset = match t.remove("preset") {
        None => "thesis".to_string(),
        Some(toml::Value::String(s)) => s,
        Some(_) => bail!("sensors.preset must be a string: \"thesis\" or \"realistic\""),
    };
    let spec: SensorSpec = preset.parse()?;
    let mut base = match toml::Value::try_from(spec.params()).map_err(|e| anyhow!("{e}"))? {
        toml::Value::Table(b) => b,
        _ => unreachable!("SensorParams serialises to a table"),
    };
    merge(&mut base, t);
    let p: SensorParams = toml::Value::Table(base)
        .try_into()
        .map_err(|e: toml::de::Error| anyhow!("in [sensors]: {e}"))?;
    Ok((preset, p))
}

/// Plays the maneuver script: turns the sticky commands into rate-limited
/// autopilot targets at each step.
#[derive(Debug, Clone)]
pub struct Script {
    maneuvers: Vec<Maneuver>,
    next: usize,
    repeat: Option<f64>,
    /// Start time of the current script cycle, s.
    cycle_t0: f64,
    bank_target: f64,
    bank_ref: f64,
    bank_rate: f64,
    bank_limit: f64,
    course: Option<f64>,
    alt_target: Option<f64>,
    climb: Option<f64>,
    h_ref: f64,
    pitch: Option<f64>,
    va_target: f64,
    va_ref: f64,
    va_rate: f64,
    sideslip: f64,
    coordinated: bool,
    offsets: [f64; 3],
    doublets: Vec<(usize, f64, Doublet)>,
}

impl Script {
    pub fn new(sc: &Scenario) -> Self {
        Script {
            maneuvers: sc.maneuvers.clone(),
            next: 0,
            repeat: sc.repeat_every,
            cycle_t0: 0.0,
            bank_target: 0.0,
            bank_ref: 0.0,
            bank_rate: 45f64.to_radians(),
            bank_limit: 35f64.to_radians(),
            course: None,
            alt_target: Some(sc.initial.altitude_m),
            climb: None,
            h_ref: sc.initial.altitude_m,
            pitch: None,
            va_target: sc.initial.airspeed_m_s,
            va_ref: sc.initial.airspeed_m_s,
            va_rate: 1.0,
            sideslip: 0.0,
            coordinated: true,
            offsets: [0.0; 3],
            doublets: Vec::new(),
        }
    }

    fn apply(&mut self, m: &Maneuver, t0: f64, fb: &Feedback) {
        let r = |d: f64| d.to_radians();
        if let Some(b) = m.bank_deg {
            self.bank_target = r(b);
            self.course = None;
        }
        if let Some(c) = m.course_deg {
            self.course = Some(r(c));
        }
        if let Some(v) = m.bank_rate_deg_s {
            self.bank_rate = r(v);
        }
        if let Some(v) = m.bank_limit_deg {
            self.bank_limit = r(v);
        }
        if let Some(p) = m.pitch_deg {
            self.pitch = Some(r(p));
            self.alt_target = None;
            self.climb = None;
        }
        if m.altitude_m.is_some() || m.climb_m_s.is_some() {
            if self.pitch.take().is_some() {
                self.h_ref = fb.altitude;
            }
            self.alt_target = m.altitude_m;
            self.climb = m.climb_m_s;
        }
        if let Some(v) = m.airspeed_m_s {
            self.va_target = v;
        }
        if let Some(v) = m.airspeed_rate_m_s2 {
            self.va_rate = v;
        }
        if let Some(v) = m.sideslip_deg {
            self.sideslip = r(v);
        }
        if let Some(v) = m.coordinated {
            self.coordinated = v;
        }
        for (i, v) in [m.rudder_deg, m.aileron_deg, m.elevator_deg].into_iter().enumerate() {
            if let Some(v) = v {
                self.offsets[i] = r(v);
            }
        }
        for (i, d) in
            [m.rudder_doublet, m.aileron_doublet, m.elevator_doublet].into_iter().enumerate()
        {
            if let Some(d) = d {
                self.doublets.push((i, t0, d));
            }
        }
    }

    /// Targets at time `t` (s) for a step of `dt` (s).
    pub fn targets(&mut self, t: f64, dt: f64, fb: &Feedback) -> Targets {
        loop {
            if self.next == self.maneuvers.len() {
                match self.repeat {
                    Some(p) if t + 1e-9 >= self.cycle_t0 + p => {
                        self.cycle_t0 += p;
                        self.next = 0;
                    }
                    _ => break,
                }
            }
            let t0 = self.cycle_t0 + self.maneuvers[self.next].t;
            if t0 > t + 1e-9 {
                break;
            }
            let m = self.maneuvers[self.next].clone();
            self.apply(&m, t0, fb);
            self.next += 1;
        }
        let slew = |cur: f64, tgt: f64, rate: f64| cur + (tgt - cur).clamp(-rate * dt, rate * dt);
        self.bank_ref = slew(self.bank_ref, self.bank_target, self.bank_rate);
        self.va_ref = slew(self.va_ref, self.va_target, self.va_rate);
        let lateral = match self.course {
            Some(c) => {
                self.bank_ref = fb.roll;
                Lateral::Course(c)
            }
            None => Lateral::Bank(self.bank_ref),
        };
        let longitudinal = match self.pitch {
            Some(p) => Longitudinal::Pitch(p),
            None => {
                let hdot = match (self.alt_target, self.climb) {
                    (Some(h), c) => {
                        let rate = c.map_or(2.0, f64::abs);
                        (h - self.h_ref).clamp(-rate * dt, rate * dt) / dt
                    }
                    (None, Some(c)) => c,
                    (None, None) => 0.0,
                };
                self.h_ref += hdot * dt;
                Longitudinal::Altitude { h: self.h_ref, hdot }
            }
        };
        let mut off = self.offsets;
        self.doublets.retain(|&(_, t0, d)| t < t0 + d.period_s);
        for &(i, t0, d) in &self.doublets {
            if t >= t0 {
                let s = if t < t0 + d.period_s / 2.0 { 1.0 } else { -1.0 };
                off[i] += s * d.amplitude_deg.to_radians();
            }
        }
        Targets {
            lateral,
            longitudinal,
            airspeed: self.va_ref,
            sideslip: self.sideslip,
            coordinated: self.coordinated,
            rudder_offset: off[0],
            aileron_offset: off[1],
            elevator_offset: off[2],
            bank_limit: self.bank_limit,
        }
    }
}
