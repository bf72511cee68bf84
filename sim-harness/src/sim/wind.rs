//! Wind: a steady NED wind that may vary with altitude (shear), discrete
//! 1 − cos gusts in NED, plus Dryden turbulence in body axes
//! (Beard & McLain §4.4, eq 4.14 and table 4.1):
//!
//! ```text
//! H_u(s) = σu √(2Va/Lu) / (s + Va/Lu)
//! H_v(s) = σv √(3Va/Lv) (s + Va/(√3 Lv)) / (s + Va/Lv)²      (H_w alike)
//! ```
//!
//! driven by unit-intensity white noise, so each gust component has variance σ².
//! The filters use the scenario's nominal airspeed (linear, time-invariant) and
//! are stepped with Euler–Maruyama at the simulator's internal step (≤ 2 ms,
//! ≪ L/Va), the gust held constant within each RK4 step.
//!
//! Shear: `w(h) = ned_m_s · (h / h_ref)^α + shear_m_s_per_m · (h − h_ref)` (power law
//! and/or a linear gradient, h the altitude in m, clamped to ≥ 1 m). A discrete gust
//! (MIL-F-8785C shape, in time) adds `A/2 · (1 − cos(2π (t − t0) / d))` for t in
//! [t0, t0 + d], A the peak NED vector.

use anyhow::{bail, Result};
use rand::Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

/// Wind section of a scenario.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WindSpec {
    /// Constant wind NED, m/s (the velocity of the air mass).
    #[serde(default)]
    pub ned_m_s: [f64; 3],
    /// `none`, `light` or `moderate` (Beard & McLain table 4.1, low altitude),
    /// or `custom` with the fields below.
    #[serde(default = "none")]
    pub turbulence: String,
    /// Custom gust intensities σu, σv, σw, m/s.
    #[serde(default)]
    pub sigma_m_s: Option<[f64; 3]>,
    /// Custom scale lengths Lu, Lv, Lw, m.
    #[serde(default)]
    pub length_m: Option<[f64; 3]>,
    /// Power-law shear exponent α (0 = none; 1/7 is the textbook neutral value).
    #[serde(default)]
    pub shear_exponent: f64,
    /// Linear shear: wind change per metre of altitude above `h_ref`, NED, (m/s)/m.
    #[serde(default)]
    pub shear_m_s_per_m: [f64; 3],
    /// Altitude `h_ref` where the wind equals `ned_m_s`, m (default: the initial altitude).
    #[serde(default)]
    pub shear_reference_altitude_m: Option<f64>,
    /// Discrete 1 − cos gusts.
    #[serde(default)]
    pub gust: Vec<Gust>,
}

/// One discrete 1 − cos gust (`[[wind.gust]]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Gust {
    /// Start, s.
    pub t_s: f64,
    /// Length, s.
    pub duration_s: f64,
    /// Peak gust velocity, NED, m/s.
    pub ned_m_s: [f64; 3],
}

impl Gust {
    /// Gust velocity at time `t` (s), NED m/s.
    pub fn at(&self, t: f64) -> [f64; 3] {
        let x = (t - self.t_s) / self.duration_s;
        if !(0.0..=1.0).contains(&x) {
            return [0.0; 3];
        }
        let k = 0.5 * (1.0 - (std::f64::consts::TAU * x).cos());
        self.ned_m_s.map(|a| a * k)
    }
}

fn none() -> String {
    "none".into()
}

impl Default for WindSpec {
    fn default() -> Self {
        WindSpec {
            ned_m_s: [0.0; 3],
            turbulence: none(),
            sigma_m_s: None,
            length_m: None,
            shear_exponent: 0.0,
            shear_m_s_per_m: [0.0; 3],
            shear_reference_altitude_m: None,
            gust: Vec::new(),
        }
    }
}

impl WindSpec {
    /// Steady wind plus discrete gusts at time `t` (s) and altitude `h` (m), NED m/s
    /// (the air-mass velocity without the Dryden part). `h0` is the initial altitude,
    /// the default shear reference.
    pub fn steady_at(&self, t: f64, h: f64, h0: f64) -> [f64; 3] {
        let h_ref = self.shear_reference_altitude_m.unwrap_or(h0).max(1.0);
        let k = if self.shear_exponent != 0.0 {
            (h.max(1.0) / h_ref).powf(self.shear_exponent)
        } else {
            1.0
        };
        let mut w: [f64; 3] =
            core::array::from_fn(|i| self.ned_m_s[i] * k + self.shear_m_s_per_m[i] * (h - h_ref));
        for g in &self.gust {
            let v = g.at(t);
            for i in 0..3 {
                w[i] += v[i];
            }
        }
        w
    }

    /// Checks the shear and gust fields (the turbulence is checked by [`Self::dryden_params`]).
    pub fn validate(&self) -> Result<()> {
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        if !finite(&self.ned_m_s) || !finite(&self.shear_m_s_per_m) {
            bail!("wind.ned_m_s and wind.shear_m_s_per_m must be finite");
        }
        if !(self.shear_exponent.is_finite() && (0.0..=1.0).contains(&self.shear_exponent)) {
            bail!("wind.shear_exponent must be in [0, 1], got {}", self.shear_exponent);
        }
        if let Some(h) = self.shear_reference_altitude_m {
            if !(h.is_finite() && h >= 1.0) {
                bail!("wind.shear_reference_altitude_m must be ≥ 1 m, got {h}");
            }
        }
        for g in &self.gust {
            if !(g.t_s.is_finite() && g.duration_s > 0.0 && finite(&g.ned_m_s)) {
                bail!("wind.gust needs a finite t_s, duration_s > 0 and a finite ned_m_s");
            }
        }
        Ok(())
    }

    /// (σ, L) per axis, or `None` without turbulence.
    pub fn dryden_params(&self) -> Result<Option<([f64; 3], [f64; 3])>> {
        Ok(match self.turbulence.as_str() {
            "none" => None,
            "light" => Some(([1.06, 1.06, 0.7], [200.0, 200.0, 50.0])),
            "moderate" => Some(([2.12, 2.12, 1.4], [200.0, 200.0, 50.0])),
            "custom" => match (self.sigma_m_s, self.length_m) {
                (Some(s), Some(l)) if s.iter().all(|v| *v >= 0.0) && l.iter().all(|v| *v > 0.0) => {
                    Some((s, l))
                }
                _ => bail!("wind.turbulence = \"custom\" needs sigma_m_s = [σu, σv, σw] ≥ 0 and length_m = [Lu, Lv, Lw] > 0"),
            },
            other => bail!("wind.turbulence must be none, light, moderate or custom, not {other:?}"),
        })
    }
}

/// Dryden gust generator (body axes).
#[derive(Debug, Clone)]
pub struct Dryden {
    sigma: [f64; 3],
    /// Va/L per axis, 1/s.
    a: [f64; 3],
    /// u: one state; v, w: two states each (controllable canonical form).
    xu: f64,
    xv: [f64; 2],
    xw: [f64; 2],
}

impl Dryden {
    /// Filters for nominal airspeed `va` (m/s). Starts from the stationary
    /// distribution's mean (zero gust) — a short transient, like switching it on.
    pub fn new(sigma: [f64; 3], length: [f64; 3], va: f64) -> Self {
        Dryden {
            sigma,
            a: [va / length[0], va / length[1], va / length[2]],
            xu: 0.0,
            xv: [0.0; 2],
            xw: [0.0; 2],
        }
    }

    /// Current gust, body axes, m/s.
    pub fn gust(&self) -> [f64; 3] {
        let second = |x: &[f64; 2], s: f64, a: f64| {
            let k = s * (3.0 * a).sqrt();
            k * (a / 3f64.sqrt() * x[0] + x[1])
        };
        [
            self.sigma[0] * (2.0 * self.a[0]).sqrt() * self.xu,
            second(&self.xv, self.sigma[1], self.a[1]),
            second(&self.xw, self.sigma[2], self.a[2]),
        ]
    }

    /// Advances the filters by `dt` seconds.
    pub fn step<R: Rng>(&mut self, dt: f64, rng: &mut R) {
        let sq = dt.sqrt();
        let n: [f64; 3] =
            [rng.sample(StandardNormal), rng.sample(StandardNormal), rng.sample(StandardNormal)];
        // x' = −a x + w (unit intensity): exact discretisation of the first-order filter.
        let e = (-self.a[0] * dt).exp();
        self.xu = e * self.xu + ((1.0 - e * e) / (2.0 * self.a[0])).sqrt() * n[0];
        let second = |x: &mut [f64; 2], a: f64, w: f64| {
            // x1' = x2, x2' = −a² x1 − 2a x2 + w
            let x1 = x[0] + dt * x[1];
            let x2 = x[1] + dt * (-a * a * x[0] - 2.0 * a * x[1]) + sq * w;
            *x = [x1, x2];
        };
        second(&mut self.xv, self.a[1], n[1]);
        second(&mut self.xw, self.a[2], n[2]);
    }
}
