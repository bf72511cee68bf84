//! Kinematic trajectory generator for flights the 6-DoF autopilot cannot fly
//! (loops, rolls, inverted, vertical). The script gives body rates (or a load factor,
//! or "hold level") and airspeed per segment; the attitude is a quaternion (valid at
//! every attitude), and everything the sensors see follows from it exactly:
//!
//! ```text
//! q̇ = ½ q ⊗ [0, ω]                           ω: the segment's body rates (FRD, rad/s)
//! v_N = R(q)·v_air,B(Va, α, β) + w_f          ground velocity, NED
//! a_N = R(q)·(ω × v_air,B + v̇_air,B) + ẇ_f    exact derivative of v_N
//! f_B = R(q)ᵀ·(a_N − g),  g = [0, 0, +9.80665]
//! ```
//!
//! `w_f` is the wind the airframe follows: the true wind (steady + shear + gusts +
//! Dryden) through a first-order lag of [`FOLLOW_TAU_S`] (the airframe's inertia), so
//! the wind's fast part shows up as airspeed, α and β changes, as on a real aircraft,
//! not as unbounded accelerations. The true air-relative velocity is `v_N − w_true`
//! (what the airspeed sensor and the `alpha`/`beta` truth report).
//!
//! Body rates move from one segment's command to the next with a smoothstep over
//! `ramp_s` (default 0.25 s), so the specific force stays continuous. The sensors are
//! the 6-DoF simulator's own models ([`super::sensors`]): presets, latency, rates and
//! noise all apply.
//!
//! Segment keys (`[[segment]]`): `duration_s`; rates `p_deg_s`, `q_deg_s`, `r_deg_s`;
//! or `load_factor` (sets q = (n − R₃₃)·g/Va: exact for α = 0) or `level = true`
//! (q keeps body x horizontal: a level turn at any bank); `coordinated` (default true: r = g·R₃₂/Va,
//! no side force, unless `r_deg_s` is given); `airspeed_m_s` (reached at the segment's end
//! along a smoothstep); `alpha_deg`, `beta_deg` (reached over the ramp); `ramp_s`.
//! Or a named figure (`figure = "loop"`, see [`Figure`]) that expands to segments.
//! After the last segment the aircraft flies straight on (zero rates).

use super::dynamics::G;
use super::rotation::{self as rot, V3};
use super::scenario::Scenario;
use super::sensors::{AirspeedModel, BaroModel, GpsModel, ImuModel, VibrationModel};
use super::{geodetic, stream, wind, TruthExtra};
use crate::log::LogRow;
use anyhow::{bail, ensure, Result};
use serde::Deserialize;

/// Time constant with which the kinematic airframe follows the wind, s.
pub const FOLLOW_TAU_S: f64 = 0.5;

/// Time constant of the `level` mode's return to zero pitch, s.
const LEVEL_TAU_S: f64 = 1.0;

/// One scripted segment (see the module doc), as written in the file.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SegmentSpec {
    /// A named figure instead of raw rates (see [`Figure`]).
    pub figure: Option<String>,
    pub duration_s: Option<f64>,
    pub p_deg_s: Option<f64>,
    pub q_deg_s: Option<f64>,
    pub r_deg_s: Option<f64>,
    pub load_factor: Option<f64>,
    pub level: Option<bool>,
    pub coordinated: Option<bool>,
    pub airspeed_m_s: Option<f64>,
    pub alpha_deg: Option<f64>,
    pub beta_deg: Option<f64>,
    pub ramp_s: Option<f64>,
    /// Figure parameters: pitch rate of loops, °/s (default 45).
    pub pitch_rate_deg_s: Option<f64>,
    /// Roll rate of rolls, °/s (default 120).
    pub roll_rate_deg_s: Option<f64>,
    /// Bank of `steep_turn`, ° (default 70).
    pub bank_deg: Option<f64>,
    /// Time held in knife-edge / inverted / vertical / the steep turn, s (default 5).
    pub hold_s: Option<f64>,
}

/// How q is set in a segment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Pitch {
    Rate(f64),
    LoadFactor(f64),
    Level,
}

/// An expanded segment (SI units).
#[derive(Debug, Clone, PartialEq)]
pub struct Segment {
    /// s
    pub duration: f64,
    /// Roll rate, rad/s.
    pub p: f64,
    pub pitch: Pitch,
    /// Yaw rate, rad/s; `None` = coordinated (r = g·R₃₂/Va).
    pub r: Option<f64>,
    /// Airspeed at the segment's end, m/s.
    pub airspeed: f64,
    /// α, β reached over the ramp, rad.
    pub alpha: f64,
    pub beta: f64,
    /// Rate blend time, s.
    pub ramp: f64,
    /// Label (the figure it belongs to, or "segment").
    pub label: String,
}

/// The named figures.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Figure {
    /// 360° inside loop at a constant pitch rate, slowing to 80 % at the top.
    Loop,
    /// Half loop up, half roll to upright at the top (heading reversed, higher).
    Immelmann,
    /// Half roll to inverted, half loop down (heading reversed, lower).
    SplitS,
    /// 360° roll about the body x axis.
    AxialRoll,
    /// 360° rotation about a body axis 30° above x: a barrel around the flight path.
    BarrelRoll,
    /// Roll to 90°, fly straight (knife-edge) for `hold_s`, roll back.
    KnifeEdge,
    /// Half roll, straight inverted for `hold_s`, half roll back.
    Inverted,
    /// 5/8 loop, half roll, 3/4 loop, half roll, 1/8 pull to level.
    CubanEight,
    /// Pull to 85° nose-up, hold `hold_s` (slowing), pull over to inverted level, half roll.
    Vertical,
    /// Roll to `bank_deg` (60–80°), hold a level coordinated turn for `hold_s`, roll out.
    SteepTurn,
    /// Straight and level for `hold_s`.
    Straight,
}

impl Figure {
    pub const ALL: [(&'static str, Figure); 11] = [
        ("loop", Figure::Loop),
        ("immelmann", Figure::Immelmann),
        ("split_s", Figure::SplitS),
        ("axial_roll", Figure::AxialRoll),
        ("barrel_roll", Figure::BarrelRoll),
        ("knife_edge", Figure::KnifeEdge),
        ("inverted", Figure::Inverted),
        ("cuban_eight", Figure::CubanEight),
        ("vertical", Figure::Vertical),
        ("steep_turn", Figure::SteepTurn),
        ("straight", Figure::Straight),
    ];

    pub fn by_name(s: &str) -> Option<Figure> {
        Self::ALL.iter().find(|(n, _)| *n == s).map(|x| x.1)
    }
}

/// Builds segments with a running airspeed.
struct Builder {
    va: f64,
    ramp: f64,
    out: Vec<Segment>,
    label: String,
}

impl Builder {
    fn push(&mut self, duration: f64, p: f64, pitch: Pitch, r: Option<f64>, va_end: f64) {
        self.out.push(Segment {
            duration,
            p,
            pitch,
            r,
            airspeed: va_end,
            alpha: 0.0,
            beta: 0.0,
            ramp: self.ramp,
            label: self.label.clone(),
        });
        self.va = va_end;
    }
    /// Pitch through `angle` rad at rate `q` rad/s (sign of the angle), airspeed to `va_end`.
    fn pull(&mut self, angle: f64, q: f64, va_end: f64) {
        let q = q.copysign(angle);
        self.push(angle / q, 0.0, Pitch::Rate(q), Some(0.0), va_end);
    }
    /// Roll through `angle` rad at rate `p` (no pitch or yaw rate: straight path).
    fn roll(&mut self, angle: f64, p: f64) {
        let p = p.copysign(angle);
        let va = self.va;
        self.push(angle / p, p, Pitch::Rate(0.0), Some(0.0), va);
    }
    fn straight(&mut self, t: f64, va_end: f64) {
        self.push(t, 0.0, Pitch::Rate(0.0), Some(0.0), va_end);
    }
}

fn figure_segments(b: &mut Builder, f: Figure, s: &SegmentSpec) -> Result<()> {
    use std::f64::consts::{FRAC_PI_2 as H, PI};
    let q = s.pitch_rate_deg_s.unwrap_or(45.0).to_radians();
    let p = s.roll_rate_deg_s.unwrap_or(120.0).to_radians();
    let hold = s.hold_s.unwrap_or(5.0);
    ensure!(q > 0.0 && p > 0.0 && hold >= 0.0, "figure rates must be > 0 and hold_s ≥ 0");
    let va = b.va;
    let top = 0.8 * va;
    match f {
        Figure::Loop => {
            b.pull(H, q, 0.9 * va);
            b.pull(H, q, top);
            b.pull(H, q, 0.9 * va);
            b.pull(H, q, va);
        }
        Figure::Immelmann => {
            b.pull(H, q, 0.9 * va);
            b.pull(H, q, top);
            b.roll(PI, p);
            b.straight(1.0, top);
        }
        Figure::SplitS => {
            b.roll(PI, p);
            b.pull(H, q, 1.1 * va);
            b.pull(H, q, 1.15 * va);
            b.straight(1.0, va);
        }
        Figure::AxialRoll => b.roll(2.0 * PI, p),
        Figure::BarrelRoll => {
            let w = p.min(90f64.to_radians());
            let d = 30f64.to_radians();
            let t = 2.0 * PI / w;
            b.push(t, w * d.cos(), Pitch::Rate(w * d.sin()), Some(0.0), va);
        }
        Figure::KnifeEdge => {
            b.roll(H, p);
            b.straight(hold, va);
            b.roll(-H, p);
        }
        Figure::Inverted => {
            b.roll(PI, p);
            b.straight(hold, va);
            b.roll(-PI, p);
        }
        Figure::CubanEight => {
            let e = PI / 4.0;
            b.pull(H, q, 0.9 * va);
            b.pull(H, q, top);
            b.pull(e, q, 0.9 * va);
            b.roll(PI, p);
            b.pull(e, q, va);
            b.pull(H, q, 0.9 * va);
            b.pull(H, q, top);
            b.pull(e, q, 0.9 * va);
            b.roll(PI, p);
            b.pull(e, q, va);
        }
        Figure::Vertical => {
            let up = 85f64.to_radians();
            b.pull(up, q, 0.9 * va);
            b.straight(hold, 0.6 * va);
            b.pull(PI - up, q, 0.7 * va);
            b.roll(PI, p);
            b.straight(1.0, va);
        }
        Figure::SteepTurn => {
            let bank = s.bank_deg.unwrap_or(70.0).to_radians();
            ensure!(bank.abs() < 85f64.to_radians(), "steep_turn bank_deg must be below 85°");
            let pr = p.min(60f64.to_radians()).copysign(bank);
            b.push(bank / pr, pr, Pitch::Level, None, va);
            b.push(hold, 0.0, Pitch::Level, None, va);
            b.push(bank / pr, -pr, Pitch::Level, None, va);
        }
        Figure::Straight => b.straight(hold, va),
    }
    Ok(())
}

/// Expands the file's segments (figures included) for an entry airspeed `va0`, m/s.
pub fn expand(specs: &[SegmentSpec], va0: f64) -> Result<Vec<Segment>> {
    let mut b = Builder { va: va0, ramp: 0.25, out: Vec::new(), label: String::new() };
    for (i, s) in specs.iter().enumerate() {
        let at = || format!("segment #{}", i + 1);
        b.ramp = s.ramp_s.unwrap_or(0.25);
        ensure!(b.ramp.is_finite() && b.ramp >= 0.0, "{}: ramp_s must be ≥ 0", at());
        if let Some(name) = &s.figure {
            let f = Figure::by_name(name).ok_or_else(|| {
                let known: Vec<&str> = Figure::ALL.iter().map(|x| x.0).collect();
                anyhow::anyhow!("{}: unknown figure {name:?} (known: {})", at(), known.join(", "))
            })?;
            ensure!(
                s.p_deg_s.is_none() && s.q_deg_s.is_none() && s.r_deg_s.is_none(),
                "{}: a figure takes no raw rates",
                at()
            );
            b.label = name.clone();
            figure_segments(&mut b, f, s).map_err(|e| anyhow::anyhow!("{}: {e}", at()))?;
            continue;
        }
        let d = s.duration_s.ok_or_else(|| anyhow::anyhow!("{}: needs duration_s", at()))?;
        ensure!(d.is_finite() && d > 0.0, "{}: duration_s must be > 0", at());
        let n_pitch = [s.q_deg_s.is_some(), s.load_factor.is_some(), s.level == Some(true)]
            .iter()
            .filter(|x| **x)
            .count();
        ensure!(n_pitch <= 1, "{}: give one of q_deg_s, load_factor, level", at());
        let pitch = match (s.q_deg_s, s.load_factor, s.level) {
            (Some(q), _, _) => Pitch::Rate(q.to_radians()),
            (_, Some(n), _) => Pitch::LoadFactor(n),
            (_, _, Some(true)) => Pitch::Level,
            _ => Pitch::Rate(0.0),
        };
        let r = match (s.r_deg_s, s.coordinated.unwrap_or(true)) {
            (Some(r), _) => Some(r.to_radians()),
            (None, true) => None,
            (None, false) => Some(0.0),
        };
        let va = s.airspeed_m_s.unwrap_or(b.va);
        ensure!(va.is_finite() && va > 1.0, "{}: airspeed_m_s must be > 1", at());
        b.label = "segment".into();
        b.push(d, s.p_deg_s.unwrap_or(0.0).to_radians(), pitch, r, va);
        let last = b.out.last_mut().expect("just pushed");
        last.alpha = s.alpha_deg.unwrap_or(0.0).to_radians();
        last.beta = s.beta_deg.unwrap_or(0.0).to_radians();
    }
    for s in &b.out {
        ensure!(s.airspeed > 1.0, "a figure slows the aircraft below 1 m/s");
    }
    Ok(b.out)
}

/// Plays the expanded script: commanded rates, airspeed, α, β at a time.
struct Player<'a> {
    segs: &'a [Segment],
    /// Start time of each segment, s.
    starts: Vec<f64>,
    va0: f64,
}

/// Commands at one instant (before the rate blend).
struct Cmd {
    w: V3,
    va: f64,
    va_dot: f64,
    alpha: f64,
    alpha_dot: f64,
    beta: f64,
    beta_dot: f64,
}

fn smoothstep(x: f64) -> (f64, f64) {
    let x = x.clamp(0.0, 1.0);
    (x * x * (3.0 - 2.0 * x), 6.0 * x * (1.0 - x))
}

impl<'a> Player<'a> {
    fn new(segs: &'a [Segment], va0: f64) -> Self {
        let mut starts = Vec::with_capacity(segs.len());
        let mut t = 0.0;
        for s in segs {
            starts.push(t);
            t += s.duration;
        }
        Player { segs, starts, va0 }
    }

    /// Index of the segment at `t` (`segs.len()` after the script).
    fn index(&self, t: f64) -> usize {
        let end = self.starts.last().zip(self.segs.last()).map_or(0.0, |(a, s)| a + s.duration);
        if t >= end {
            return self.segs.len();
        }
        self.starts.partition_point(|s| *s <= t).saturating_sub(1)
    }

    /// The raw command of segment `i` for attitude `q` and airspeed `va`.
    fn rates(&self, i: usize, q: [f64; 4], va: f64, alpha: f64) -> V3 {
        let Some(s) = self.segs.get(i) else { return [0.0; 3] };
        let r_nb = rot::r_nb_quat(q);
        let (r31, r32, r33) = (r_nb[2][0], r_nb[2][1], r_nb[2][2]);
        // Coordinated: no side force, f_y = r·Va·cos α − p·Va·sin α − g·R₃₂ = 0.
        let r = s.r.unwrap_or_else(|| (G * r32 / va + s.p * alpha.sin()) / alpha.cos());
        let qr = match s.pitch {
            Pitch::Rate(x) => x,
            Pitch::LoadFactor(n) => (n - r33) * G / va,
            // Body x stays horizontal: d(R₃₁)/dt = R₃₂·r − R₃₃·q, steered to −R₃₁/τ (τ 1 s)
            // so the pitch returns to 0 (a level turn at any bank below ~84°).
            Pitch::Level => (r32 * r + r31 / LEVEL_TAU_S) / r33.max(0.1),
        };
        [s.p, qr, r]
    }

    fn state_at(&self, i: usize) -> (f64, f64, f64) {
        // Airspeed, α, β at the start of segment i (= the end of i − 1).
        match i.checked_sub(1).and_then(|k| self.segs.get(k)) {
            Some(s) => (s.airspeed, s.alpha, s.beta),
            None => (self.va0, 0.0, 0.0),
        }
    }

    /// Commands at `t` for attitude `q`; `w_prev` is the blended rate at the
    /// segment's start.
    fn command(&self, t: f64, q: [f64; 4], w_start: &[V3]) -> Cmd {
        let i = self.index(t);
        let (va_a, al_a, be_a) = self.state_at(i);
        let (tau, s) = match self.segs.get(i) {
            Some(s) => (t - self.starts[i], s.clone()),
            None => {
                // After the script: straight on, the rates blended to zero over 0.25 s.
                let end =
                    self.starts.last().zip(self.segs.last()).map_or(0.0, |(a, s)| a + s.duration);
                let (k, _) = smoothstep((t - end) / 0.25);
                let w0 = w_start[i];
                return Cmd {
                    w: w0.map(|x| x * (1.0 - k)),
                    va: va_a,
                    va_dot: 0.0,
                    alpha: al_a,
                    alpha_dot: 0.0,
                    beta: be_a,
                    beta_dot: 0.0,
                };
            }
        };
        // Airspeed along a smoothstep over the segment: continuous V̇a (zero at both ends).
        let (kv, dkv) = smoothstep(tau / s.duration);
        let va = va_a + kv * (s.airspeed - va_a);
        let va_dot = dkv / s.duration * (s.airspeed - va_a);
        let (k, dk) = if s.ramp > 0.0 { smoothstep(tau / s.ramp) } else { (1.0, 0.0) };
        let dk = if s.ramp > 0.0 { dk / s.ramp } else { 0.0 };
        let alpha = al_a + k * (s.alpha - al_a);
        let beta = be_a + k * (s.beta - be_a);
        let raw = self.rates(i, q, va, alpha);
        let w0 = w_start[i];
        let w = core::array::from_fn(|j| w0[j] + k * (raw[j] - w0[j]));
        Cmd {
            w,
            va,
            va_dot,
            alpha,
            alpha_dot: dk * (s.alpha - al_a),
            beta,
            beta_dot: dk * (s.beta - be_a),
        }
    }
}

/// Air-relative velocity in body axes for (Va, α, β) and its time derivative.
fn air_body(c: &Cmd) -> (V3, V3) {
    let (sa, ca) = c.alpha.sin_cos();
    let (sb, cb) = c.beta.sin_cos();
    let u = [ca * cb, sb, sa * cb];
    let du_da = [-sa * cb, 0.0, ca * cb];
    let du_db = [-ca * sb, cb, -sa * sb];
    let v = rot::scale(u, c.va);
    let dv = rot::add(
        rot::scale(u, c.va_dot),
        rot::scale(rot::add(rot::scale(du_da, c.alpha_dot), rot::scale(du_db, c.beta_dot)), c.va),
    );
    (v, dv)
}

/// Flies a kinematic scenario (see [`super::run_streaming`]).
pub fn run_streaming(
    sc: &Scenario,
    seed: u64,
    mut sink: impl FnMut(&LogRow, &TruthExtra),
) -> Result<ImuModel> {
    let segs = &sc.segments;
    let va0 = sc.initial.airspeed_m_s;
    let player = Player::new(segs, va0);
    let mut rng_imu = stream(seed, 1);
    let mut rng_gps = stream(seed, 2);
    let mut rng_air = stream(seed, 3);
    let mut rng_wind = stream(seed, 4);
    let mut rng_baro = stream(seed, 5);
    let (mut vib, mut rng_vib) = (VibrationModel::new(&sc.vibration), stream(seed, 7));
    let mut imu = ImuModel::new(&sc.sensors.imu, &mut rng_imu);
    let imu_draw = imu.clone();
    let mut gps = GpsModel::new(&sc.sensors.gps, &sc.gps_outages, stream(seed, 6));
    let mut baro = BaroModel::new(&sc.sensors.baro);
    let mut aspd = AirspeedModel::new(&sc.sensors.airspeed);
    let mut dryden = sc.wind.dryden_params()?.map(|(s, l)| wind::Dryden::new(s, l, va0));
    let h0 = sc.initial.altitude_m;

    let mut q = rot::quat_from_euler(0.0, 0.0, sc.initial.heading_deg.to_radians());
    let mut pos = [sc.initial.north_m, sc.initial.east_m, -h0];
    let true_wind = |t: f64, pos: V3, q: [f64; 4], d: &Option<wind::Dryden>| {
        let gust_b = d.as_ref().map_or([0.0; 3], |d| d.gust());
        rot::add(sc.wind.steady_at(t, -pos[2], h0), rot::mul_mv(&rot::r_nb_quat(q), gust_b))
    };
    let mut w_f = true_wind(0.0, pos, q, &dryden);

    let rate = sc.sensors.imu.rate_hz;
    let n_rows = (sc.duration * rate).round() as usize;
    let sub = ((sc.integration_hz / rate).round() as usize).max(1);
    let dt = 1.0 / (rate * sub as f64);
    let total = n_rows * sub;
    // Blended rate at each segment's start: the next segment's entry is kept at the
    // latest rate while the current one runs (so RK4 stages across a boundary see it).
    let mut w_start: Vec<V3> = vec![[0.0; 3]; segs.len() + 1];

    for i in 0..=total {
        let t = i as f64 * dt;
        let idx = player.index(t);
        let c = player.command(t, q, &w_start);
        if idx < segs.len() {
            w_start[idx + 1] = c.w;
        }
        let r_nb = rot::r_nb_quat(q);
        let (v_air_b, dv_air_b) = air_body(&c);
        let w_true = true_wind(t, pos, q, &dryden);
        let w_dot = rot::scale(rot::sub(w_true, w_f), 1.0 / FOLLOW_TAU_S);
        let v_n = rot::add(rot::mul_mv(&r_nb, v_air_b), w_f);
        let a_b = rot::add(rot::cross(c.w, v_air_b), dv_air_b);
        let a_n = rot::add(rot::mul_mv(&r_nb, a_b), w_dot);
        let f_b = rot::mul_mtv(&r_nb, rot::sub(a_n, [0.0, 0.0, G]));
        let p_now = pos;
        gps.on_step_at(t, v_n, Some(|| geodetic::lla_of(p_now)), &mut rng_gps);
        if i % sub == 0 {
            let t_row = (i / sub) as f64 / rate;
            let air =
                super::aircraft::AirData::from_body(rot::mul_mtv(&r_nb, rot::sub(v_n, w_true)));
            let bias = imu.gyro_bias();
            let accel_bias = imu.accel_bias();
            let (vw, vf) = vib.sample(t_row, &mut rng_vib);
            let (gyro, accel) = imu.sample(rot::add(c.w, vw), rot::add(f_b, vf), &mut rng_imu);
            let row = LogRow {
                t: t_row,
                gyro,
                accel,
                gps: gps.pop_available(t_row),
                airspeed: aspd.sample(t_row, air.va, &mut rng_air),
                baro_alt: baro.sample(t_row, geodetic::lla_of(pos)[2], &mut rng_baro),
                truth: Some(rot::euler_from_quat(q)),
                truth_bias: Some(bias),
                reference: None,
                truth_wind: Some(w_true),
            };
            let extra = TruthExtra {
                t: t_row,
                position_ned: pos,
                velocity_ned: v_n,
                airspeed: air.va,
                alpha: air.alpha,
                beta: air.beta,
                body_rates: c.w,
                specific_force: f_b,
                wind_ned: w_true,
                accel_bias,
                controls: [0.0; 4],
            };
            sink(&row, &extra);
        }
        if i == total {
            break;
        }
        // RK4 on the attitude (the rates depend on it through load factor / coordination).
        let f = |tt: f64, qq: [f64; 4]| rot::quat_rate(qq, player.command(tt, qq, &w_start).w);
        let add = |a: [f64; 4], k: [f64; 4], h: f64| core::array::from_fn(|j| a[j] + h * k[j]);
        let k1 = f(t, q);
        let k2 = f(t + dt / 2.0, add(q, k1, dt / 2.0));
        let k3 = f(t + dt / 2.0, add(q, k2, dt / 2.0));
        let k4 = f(t + dt, add(q, k3, dt));
        let q1 = rot::normalize_quat(core::array::from_fn(|j| {
            q[j] + dt / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])
        }));
        // The followed wind: the exact first-order lag response to the true wind moving
        // linearly from this step's start to its end (end at the predicted position).
        if let Some(d) = dryden.as_mut() {
            d.step(dt, &mut rng_wind);
        }
        let w1 = true_wind(t + dt, rot::add(pos, rot::scale(v_n, dt)), q1, &dryden);
        let e = (-dt / FOLLOW_TAU_S).exp();
        let lin = FOLLOW_TAU_S / dt * (1.0 - e);
        w_f =
            core::array::from_fn(|j| w1[j] + e * (w_f[j] - w_true[j]) - (w1[j] - w_true[j]) * lin);
        // Position: trapezoid of the ground velocity (end value from the new state).
        let c1 = player.command(t + dt, q1, &w_start);
        let v1 = rot::add(rot::mul_mv(&rot::r_nb_quat(q1), air_body(&c1).0), w_f);
        pos = rot::add(pos, rot::scale(rot::add(v_n, v1), 0.5 * dt));
        q = q1;
        if !q.iter().chain(&pos).all(|x| x.is_finite()) {
            bail!("scenario {}: the kinematic trajectory diverged at t = {t:.2} s", sc.name);
        }
        if pos[2] > 0.0 {
            bail!("scenario {}: the trajectory hit the ground at t = {t:.2} s", sc.name);
        }
    }
    Ok(imu_draw)
}
