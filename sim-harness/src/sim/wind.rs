//! Wind: a constant NED wind plus Dryden turbulence in body axes
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
}

fn none() -> String {
    "none".into()
}

impl Default for WindSpec {
    fn default() -> Self {
        WindSpec { ned_m_s: [0.0; 3], turbulence: none(), sigma_m_s: None, length_m: None }
    }
}

impl WindSpec {
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
