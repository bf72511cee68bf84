//! GPS latency measured from a log: how long after the motion it describes a fix reaches
//! its row. The acceleration from differencing consecutive fixes is compared with the
//! accelerometer's, averaged over the same interval shifted back by a candidate latency
//! L; the L with the highest correlation is the estimate.
//!
//! With an attitude (`ref_*`, else simulated truth) the body specific force is rotated to
//! NED and the three components are correlated; without one, the magnitudes
//! |a_gps − g| and |f| are (rotation-free, weaker).

use crate::log::FlightLog;

const G: f64 = 9.80665;

/// What was correlated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// NED components, body force rotated by the log's reference attitude.
    Reference,
    /// NED components, rotated by the simulated truth attitude.
    Truth,
    /// Magnitudes only (no attitude in the log).
    Magnitude,
}

/// A latency estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// Arrival minus effective epoch, s.
    pub latency_s: f64,
    /// Correlation at the estimate.
    pub corr: f64,
    /// Correlation with no latency (for comparison).
    pub corr_at_zero: f64,
    /// Fix pairs used.
    pub pairs: usize,
    /// Attitude source.
    pub method: Method,
}

/// Search step, s.
const STEP: f64 = 0.005;

/// Cumulative trapezoid integral of each channel over the rows' times.
struct Integral {
    t: Vec<f64>,
    f: Vec<[f64; 4]>,
}

impl Integral {
    fn at(&self, t: f64) -> Option<[f64; 4]> {
        if !(t >= self.t[0] && t <= self.t[self.t.len() - 1]) {
            return None;
        }
        let i = self.t.partition_point(|&x| x <= t).max(1) - 1;
        let j = (i + 1).min(self.t.len() - 1);
        let dt = self.t[j] - self.t[i];
        let w = if dt > 0.0 { (t - self.t[i]) / dt } else { 0.0 };
        Some(core::array::from_fn(|k| self.f[i][k] + w * (self.f[j][k] - self.f[i][k])))
    }
    fn mean(&self, a: f64, b: f64) -> Option<[f64; 4]> {
        let (fa, fb) = (self.at(a)?, self.at(b)?);
        Some(core::array::from_fn(|k| (fb[k] - fa[k]) / (b - a)))
    }
}

/// Body → NED for 3-2-1 Euler angles.
fn to_ned(att: [f64; 3], v: [f64; 3]) -> [f64; 3] {
    let (sr, cr) = att[0].sin_cos();
    let (sp, cp) = att[1].sin_cos();
    let (sy, cy) = att[2].sin_cos();
    [
        cp * cy * v[0] + (sr * sp * cy - cr * sy) * v[1] + (cr * sp * cy + sr * sy) * v[2],
        cp * sy * v[0] + (sr * sp * sy + cr * cy) * v[1] + (cr * sp * sy - sr * cy) * v[2],
        -sp * v[0] + sr * cp * v[1] + cr * cp * v[2],
    ]
}

fn pearson(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in x.iter().zip(y) {
        sxy += (a - mx) * (b - my);
        sxx += (a - mx) * (a - mx);
        syy += (b - my) * (b - my);
    }
    if sxx > 0.0 && syy > 0.0 {
        sxy / (sxx * syy).sqrt()
    } else {
        0.0
    }
}

/// Estimates the latency in [0, `max_s`]. `None` when the log has fewer than 20 usable
/// fix pairs or the best correlation is below 0.3 (nothing to align).
pub fn estimate(log: &FlightLog, max_s: f64) -> Option<Estimate> {
    let rows = &log.rows;
    if rows.len() < 2 {
        return None;
    }
    let n_ref = rows.iter().filter(|r| r.reference.is_some()).count();
    let n_truth = rows.iter().filter(|r| r.truth.is_some()).count();
    let method = if n_ref * 10 >= rows.len() * 9 {
        Method::Reference
    } else if n_truth * 10 >= rows.len() * 9 {
        Method::Truth
    } else {
        Method::Magnitude
    };
    // Specific force per row: NED (3) + magnitude; rows without an attitude hold the last.
    let mut last_att = [0.0; 3];
    let mut t = Vec::with_capacity(rows.len());
    let mut f = Vec::with_capacity(rows.len());
    let mut acc = [0.0; 4];
    let mut prev: Option<(f64, [f64; 4])> = None;
    for r in rows {
        let att = match method {
            Method::Reference => r.reference,
            Method::Truth => r.truth,
            Method::Magnitude => None,
        };
        if let Some(a) = att {
            last_att = a;
        }
        let n = to_ned(last_att, r.accel);
        let m = r.accel.iter().map(|v| v * v).sum::<f64>().sqrt();
        let cur = [n[0], n[1], n[2], m];
        if let Some((tp, fp)) = prev {
            let dt = r.t - tp;
            if !(dt >= 0.0) {
                return None;
            }
            for k in 0..4 {
                acc[k] += 0.5 * (fp[k] + cur[k]) * dt;
            }
        }
        t.push(r.t);
        f.push(acc);
        prev = Some((r.t, cur));
    }
    let integ = Integral { t, f };
    let fixes: Vec<(f64, [f64; 3])> =
        rows.iter().filter_map(|r| r.gps.map(|g| (r.t, g.vel))).collect();
    let pairs: Vec<(f64, f64, [f64; 3])> = fixes
        .windows(2)
        .filter_map(|w| {
            let dt = w[1].0 - w[0].0;
            (0.04..=1.1)
                .contains(&dt)
                .then(|| (w[0].0, w[1].0, core::array::from_fn(|k| (w[1].1[k] - w[0].1[k]) / dt)))
        })
        .collect();
    let corr_at = |l: f64| -> (f64, usize) {
        let (mut x, mut y) = (Vec::new(), Vec::new());
        let mut used = 0;
        for &(a, b, ag) in &pairs {
            let Some(fm) = integ.mean(a - l, b - l) else { continue };
            used += 1;
            match method {
                Method::Magnitude => {
                    x.push((ag[0] * ag[0] + ag[1] * ag[1] + (ag[2] - G) * (ag[2] - G)).sqrt());
                    y.push(fm[3]);
                }
                _ => {
                    // a = f + g (NED, g down); each component de-meaned on its own below.
                    let ai = [fm[0], fm[1], fm[2] + G];
                    for k in 0..3 {
                        x.push(ag[k]);
                        y.push(ai[k]);
                    }
                }
            }
        }
        if method != Method::Magnitude {
            // Pearson per component would need three sums; de-meaning each component and
            // pooling gives one correlation over all three.
            for k in 0..3 {
                for v in [&mut x, &mut y] {
                    let idx: Vec<usize> = (k..v.len()).step_by(3).collect();
                    let m = idx.iter().map(|&i| v[i]).sum::<f64>() / idx.len().max(1) as f64;
                    for i in idx {
                        v[i] -= m;
                    }
                }
            }
        }
        (if used >= 20 { pearson(&x, &y) } else { f64::NAN }, used)
    };
    let steps = (max_s / STEP).round() as usize;
    let cs: Vec<(f64, usize)> = (0..=steps).map(|i| corr_at(i as f64 * STEP)).collect();
    let (best, &(c, used)) = cs
        .iter()
        .enumerate()
        .filter(|(_, c)| c.0.is_finite())
        .max_by(|a, b| a.1 .0.total_cmp(&b.1 .0))?;
    if c < 0.3 {
        return None;
    }
    // Parabola through the peak and its neighbours.
    let mut l = best as f64 * STEP;
    if best > 0 && best < steps {
        let (a, b, d) = (cs[best - 1].0, c, cs[best + 1].0);
        let den = a - 2.0 * b + d;
        if den < 0.0 && a.is_finite() && d.is_finite() {
            l += 0.5 * (a - d) / den * STEP;
        }
    }
    Some(Estimate { latency_s: l, corr: c, corr_at_zero: cs[0].0, pairs: used, method })
}

#[cfg(test)]
mod tests {
    use super::to_ned;

    #[test]
    fn rotation_matches_known_cases() {
        // 90° yaw: body x → east. 90° roll: body y → down.
        let e = to_ned([0.0, 0.0, std::f64::consts::FRAC_PI_2], [1.0, 0.0, 0.0]);
        assert!((e[1] - 1.0).abs() < 1e-12 && e[0].abs() < 1e-12);
        let d = to_ned([std::f64::consts::FRAC_PI_2, 0.0, 0.0], [0.0, 1.0, 0.0]);
        assert!((d[2] - 1.0).abs() < 1e-12);
    }
}

/// The largest latency searched and applied, s (the core caps its delay line at ~0.3 s).
pub const MAX_S: f64 = 0.5;

/// How the replay chooses `gps_latency`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Choice {
    /// Measured from the data ([`estimate`]).
    Auto,
    /// The log's own arrival − epoch (`t` − `gps_t`), median over the fixes.
    Log,
    /// A given value, s.
    Seconds(f64),
}

impl std::str::FromStr for Choice {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "auto" => Ok(Choice::Auto),
            "log" => Ok(Choice::Log),
            _ => match s.parse::<f64>() {
                Ok(v) if (0.0..=MAX_S).contains(&v) => Ok(Choice::Seconds(v)),
                Ok(v) => Err(format!("must be auto, log or seconds in [0, {MAX_S}], got {v}")),
                Err(_) => Err(format!("must be auto, log or a number of seconds, got {s:?}")),
            },
        }
    }
}

/// Median of the log's `t − gps_t` over its fixes, s (0 when it has none).
pub fn logged(log: &FlightLog) -> f64 {
    let mut d: Vec<f64> = log.rows.iter().filter_map(|r| r.gps.map(|g| r.t - g.t)).collect();
    if d.is_empty() {
        return 0.0;
    }
    d.sort_by(f64::total_cmp);
    d[d.len() / 2].clamp(0.0, MAX_S)
}

/// The latency to configure, s, and a line saying where it came from.
pub fn resolve(log: &FlightLog, c: Choice) -> anyhow::Result<(f64, String)> {
    Ok(match c {
        Choice::Seconds(v) => (v, format!("gps latency {v:.3} s (given)")),
        Choice::Log => {
            let v = logged(log);
            (v, format!("gps latency {v:.3} s (the log's median t − gps_t)"))
        }
        Choice::Auto => match estimate(log, MAX_S) {
            Some(e) => (
                e.latency_s,
                format!(
                    "gps latency {:.3} s (measured: GPS vs accelerometer acceleration, {:?}, correlation {:.2} vs {:.2} at 0, {} fix pairs)",
                    e.latency_s, e.method, e.corr, e.corr_at_zero, e.pairs
                ),
            ),
            None => anyhow::bail!(
                "--gps-latency auto: cannot measure the latency from this log (fewer than 20 fix pairs or no correlation ≥ 0.3 between GPS and accelerometer acceleration); give it in seconds"
            ),
        },
    })
}
