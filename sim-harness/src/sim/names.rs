//! Scenario names beyond the built-in files: the `BASE+key=value,…` modifier
//! grammar and the group names that expand to suites.
//!
//! ```text
//! flight2+wind=6@45,turb=light     6 m/s from 045° (blowing towards 225°), light Dryden
//! flight1+wind=10@270,shear=0.05   10 m/s from the west, +0.05 (m/s)/m with altitude
//! aggressive+wind=3,gust=3         3 m/s from the north, a train of 3 m/s 1 − cos gusts
//! ```
//!
//! Keys (each at most once, applied on top of the base scenario):
//! - `wind=S[@D]`: steady horizontal wind of S m/s from D° (meteorological: the
//!   direction it blows from, clockwise from north; default 0).
//! - `turb=none|light|moderate`: Dryden turbulence (Beard & McLain table 4.1).
//! - `shear=G`: linear shear, the wind speed grows by G (m/s)/m of altitude above the
//!   initial altitude, along the steady wind (needs `wind`).
//! - `gust=A`: 1 − cos gusts of peak A m/s, 4 s long, every 15 s from t = 10 s,
//!   cycling crosswind (90° right of the wind, or from the west without one), upward,
//!   and along the wind.
//! - `spec=thesis|realistic`: sensor preset (drops the base file's sensor overrides).
//! - `gps=HZ`: the receiver's fix rate; `lat=S`: its latency, s.
//! - `sacc=honest|xK|none`: what it reports as its speed accuracy: the σ it adds, K
//!   times that (`x10`: as pessimistic as u-blox receivers in flight), or nothing (NMEA).
//! - `airframe=aerosonde|easystar_scaled|zagi`, `dur=S` (duration, s).
//! - `start=S`: the log starts at S s (the estimator is switched on in flight).
//!
//! Groups (where a list of scenarios is taken, e.g. `report`): see [`groups`]:
//! `wind` (the wind suite) and `random` (`random:1` … `random:20`, see [`super::random`]).

use anyhow::{anyhow, bail, ensure, Result};

/// The 6-DoF flights the wind suite covers (each a built-in).
pub const WIND_BASES: [&str; 4] = ["flight1", "flight2", "aggressive", "coordinated_turn"];

/// The wind conditions of the suite, as modifier strings: 3, 6 and 10 m/s from eight
/// directions between them, steady, light and moderate turbulence, and one with shear
/// and gusts.
pub const WIND_CONDITIONS: [&str; 8] = [
    "wind=3@45",
    "wind=3@225,turb=light",
    "wind=6@90",
    "wind=6@270,turb=light",
    "wind=6@0,turb=moderate",
    "wind=10@135",
    "wind=10@315,turb=moderate",
    "wind=6@180,shear=0.05,gust=3",
];

/// Members of the `random` group: `random:1` … `random:N`.
pub const RANDOM_GROUP: u64 = 20;

/// Group names and what they expand to.
pub fn groups() -> Vec<(&'static str, Vec<String>)> {
    let wind = WIND_BASES
        .iter()
        .flat_map(|b| WIND_CONDITIONS.iter().map(move |c| format!("{b}+{c}")))
        .collect();
    let random = (1..=RANDOM_GROUP).map(|s| format!("random:{s}")).collect();
    vec![("wind", wind), ("random", random)]
}

/// A group's members, or the name itself when it is not a group.
pub fn expand(name: &str) -> Vec<String> {
    match groups().into_iter().find(|(g, _)| *g == name) {
        Some((_, v)) => v,
        None => vec![name.to_string()],
    }
}

/// Splits `BASE+mods` (None when there is no `+`).
pub fn split(name: &str) -> Option<(&str, &str)> {
    name.split_once('+')
}

fn num(key: &str, s: &str) -> Result<f64> {
    let v: f64 = s.trim().parse().map_err(|_| anyhow!("`{key}`: {s:?} is not a number"))?;
    ensure!(v.is_finite(), "`{key}`: {s:?} is not finite");
    Ok(v)
}

fn table() -> toml::Table {
    toml::Table::new()
}

fn sub<'a>(t: &'a mut toml::Table, k: &str) -> &'a mut toml::Table {
    t.entry(k.to_string())
        .or_insert_with(|| toml::Value::Table(table()))
        .as_table_mut()
        .expect("created as a table")
}

fn arr(v: [f64; 3]) -> toml::Value {
    toml::Value::Array(v.iter().map(|x| toml::Value::Float(*x)).collect())
}

/// The TOML overlay for the modifier string `mods` on a base of `duration` s.
pub fn overlay(mods: &str, duration: f64) -> Result<toml::Table> {
    let mut t = table();
    let mut seen: Vec<&str> = Vec::new();
    let (mut wind, mut shear, mut gust) = (None, None, None);
    let mut dur = duration;
    for item in mods.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let (k, v) =
            item.split_once('=').ok_or_else(|| anyhow!("modifier {item:?}: expected key=value"))?;
        ensure!(!seen.contains(&k), "modifier `{k}` given twice");
        seen.push(k);
        match k {
            "wind" => {
                let (s, d) = v.split_once('@').unwrap_or((v, "0"));
                let (s, d) = (num(k, s)?, num(k, d)?.to_radians());
                ensure!((0.0..=40.0).contains(&s), "`wind`: speed must be in [0, 40] m/s");
                wind = Some((s, d));
            }
            "turb" => {
                ensure!(
                    ["none", "light", "moderate"].contains(&v),
                    "`turb` must be none, light or moderate, not {v:?}"
                );
                sub(&mut t, "wind").insert("turbulence".into(), v.into());
            }
            "shear" => shear = Some(num(k, v)?),
            "gust" => gust = Some(num(k, v)?),
            "spec" => {
                ensure!(
                    ["thesis", "realistic"].contains(&v),
                    "`spec` must be thesis or realistic, not {v:?}"
                );
                sub(&mut t, "sensors").insert("preset".into(), v.into());
            }
            "gps" => {
                let hz = num(k, v)?;
                ensure!((0.1..=100.0).contains(&hz), "`gps`: fix rate must be in [0.1, 100] Hz");
                sub(sub(&mut t, "sensors"), "gps").insert("rate_hz".into(), hz.into());
            }
            "lat" => {
                let s = num(k, v)?;
                ensure!((0.0..=2.0).contains(&s), "`lat`: latency must be in [0, 2] s");
                sub(sub(&mut t, "sensors"), "gps").insert("latency_s".into(), s.into());
            }
            "sacc" => {
                let r: super::sensors::SaccReport = v.parse().map_err(|e: String| anyhow!(e))?;
                sub(sub(&mut t, "sensors"), "gps").insert("sacc".into(), String::from(r).into());
            }
            "airframe" => {
                t.insert("airframe".into(), v.into());
            }
            "start" => {
                let s = num(k, v)?;
                ensure!(s >= 0.0, "`start`: the log's start must be ≥ 0 s");
                t.insert("log_start_s".into(), s.into());
            }
            "dur" => {
                dur = num(k, v)?;
                t.insert("duration_s".into(), dur.into());
            }
            _ => bail!(
                "unknown modifier `{k}` (known: wind=S@D, turb=, shear=, gust=, spec=, gps=, \
                 lat=, sacc=, start=, airframe=, dur=)"
            ),
        }
    }
    // Unit vector the wind blows towards (NED), and its crosswind (90° right of it).
    let (s, d) = wind.unwrap_or((0.0, 0.0));
    let to = [-d.cos(), -d.sin(), 0.0];
    if wind.is_some() {
        sub(&mut t, "wind").insert("ned_m_s".into(), arr(to.map(|x| x * s)));
    }
    if let Some(g) = shear {
        ensure!(wind.is_some_and(|w| w.0 > 0.0), "`shear` needs a `wind` with a speed > 0");
        sub(&mut t, "wind").insert("shear_m_s_per_m".into(), arr(to.map(|x| x * g)));
    }
    if let Some(a) = gust {
        let cross = if wind.is_some() { [-to[1], to[0], 0.0] } else { [0.0, 1.0, 0.0] };
        let dirs = [cross, [0.0, 0.0, -1.0], if wind.is_some() { to } else { [1.0, 0.0, 0.0] }];
        let mut list = Vec::new();
        let mut k = 0;
        while 10.0 + 15.0 * k as f64 + 4.0 <= dur {
            let mut g = table();
            g.insert("t_s".into(), (10.0 + 15.0 * k as f64).into());
            g.insert("duration_s".into(), 4.0.into());
            g.insert("ned_m_s".into(), arr(dirs[k % 3].map(|x| x * a)));
            list.push(toml::Value::Table(g));
            k += 1;
        }
        sub(&mut t, "wind").insert("gust".into(), toml::Value::Array(list));
    }
    Ok(t)
}
