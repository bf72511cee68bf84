//! Accuracy and consistency metrics: error statistics against truth (or agreement
//! against another estimator's `ref_*` attitude), innovation statistics and
//! whiteness, NEES/NIS and their χ² bounds. f64 throughout; angles wrapped.

use crate::estimate::EstimateRow;
use crate::log::FlightLog;

/// Wraps an angle to (−π, π].
pub fn wrap(a: f64) -> f64 {
    let w =
        a - std::f64::consts::TAU * ((a + std::f64::consts::PI) / std::f64::consts::TAU).floor();
    if w <= -std::f64::consts::PI {
        w + std::f64::consts::TAU
    } else {
        w
    }
}

/// mean / std / RMS / max|·| of a series.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Stats {
    /// Mean.
    pub mean: f64,
    /// Standard deviation (population).
    pub std: f64,
    /// Root mean square.
    pub rms: f64,
    /// Largest absolute value.
    pub max_abs: f64,
    /// Number of samples.
    pub n: usize,
}

impl Stats {
    /// Statistics of `xs` (all zeros when empty).
    pub fn of(xs: &[f64]) -> Stats {
        let n = xs.len();
        if n == 0 {
            return Stats::default();
        }
        let nf = n as f64;
        let mean = xs.iter().sum::<f64>() / nf;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / nf;
        let rms = (xs.iter().map(|x| x * x).sum::<f64>() / nf).sqrt();
        let max_abs = xs.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        Stats { mean, std: var.sqrt(), rms, max_abs, n }
    }

    /// The same statistics scaled (e.g. rad → deg).
    pub fn scaled(&self, k: f64) -> Stats {
        Stats {
            mean: self.mean * k,
            std: self.std * k,
            rms: self.rms * k,
            max_abs: self.max_abs * k,
            n: self.n,
        }
    }
}

/// What the attitude was compared against.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Against {
    /// Simulated truth: differences are errors.
    Truth,
    /// Another estimator (`ref_*`): differences are agreement, not error.
    Reference,
}

impl Against {
    /// Human label.
    pub fn label(self) -> &'static str {
        match self {
            Against::Truth => "error vs truth",
            Against::Reference => "agreement vs ref_* (another estimator, not truth)",
        }
    }
}

/// Per-axis comparison of an estimate with truth or reference, from `t_from` on.
#[derive(Debug, Clone, PartialEq)]
pub struct Comparison {
    /// Truth or reference.
    pub against: Against,
    /// Convergence time: samples before it are excluded, s.
    pub t_from: f64,
    /// Roll, pitch, yaw difference statistics, rad (estimate − truth/reference, wrapped).
    pub att: [Stats; 3],
    /// Bias error statistics, rad/s (only against truth with `true_b*`).
    pub bias: Option<[Stats; 3]>,
    /// Rows whose truth/reference has a non-finite cell: skipped, counted.
    pub skipped_nonfinite: usize,
    /// Tilt error (angle between estimated and true body-down direction), rad.
    pub tilt: Stats,
    /// Total attitude error (rotation angle of R_estᵀ·R_true), rad.
    pub total: Stats,
    /// Wind error, when the estimate has wind and the log `true_wind_*`.
    pub wind: Option<WindError>,
}

/// Wind-estimate error statistics (estimate − truth), m/s, from `t_from`, counted only
/// after the aircraft's heading has turned through 360° (wind is unobservable before).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindError {
    /// Start of the statistics: max(t_from, end of the first full turn), s.
    pub t_from: f64,
    /// North and east error.
    pub ne: [Stats; 2],
    /// Horizontal error magnitude |ŵ_NE − w_NE|.
    pub horizontal: Stats,
    /// Horizontal error against the truth's centred [`WIND_MEAN_WINDOW`] mean: the wind an
    /// estimator of the steady wind tracks, without the gusts no such estimate can follow.
    pub horizontal_vs_mean: Stats,
    /// Fraction of rows from `t_from` with a wind estimate.
    pub coverage: f64,
}

/// `R_BN` (NED → body) of 3-2-1 Euler angles, rad.
fn dcm(e: [f64; 3]) -> [[f64; 3]; 3] {
    crate::sim::rotation::r_bn(e[0], e[1], e[2])
}

/// Tilt error between two attitudes (3-2-1 Euler, rad): the angle between the NED
/// down direction seen in the two body frames (the third columns of R_BN, i.e. the third
/// rows of R_NB), rad in [0, π]. Independent of yaw; well defined at ±90° pitch.
pub fn tilt_error(est: [f64; 3], truth: [f64; 3]) -> f64 {
    let (a, b) = (dcm(est), dcm(truth));
    let u = [a[0][2], a[1][2], a[2][2]];
    let v = [b[0][2], b[1][2], b[2][2]];
    let c = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
    let s = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
    s.atan2(u[0] * v[0] + u[1] * v[1] + u[2] * v[2])
}

/// Total attitude error (3-2-1 Euler, rad): the rotation angle of R_estᵀ·R_true, rad in
/// [0, π], from the relative quaternion (accurate near 0, unlike acos of the trace).
pub fn attitude_error(est: [f64; 3], truth: [f64; 3]) -> f64 {
    use crate::sim::rotation as rot;
    let a = rot::quat_from_euler(est[0], est[1], est[2]);
    let b = rot::quat_from_euler(truth[0], truth[1], truth[2]);
    let d = rot::quat_mul([a[0], -a[1], -a[2], -a[3]], b);
    2.0 * rot::norm([d[1], d[2], d[3]]).atan2(d[0].abs())
}

/// Time at which the true heading has first turned through a full 360° (unwrapped yaw
/// from the first row), s; `None` when it never does.
pub fn first_full_turn(log: &FlightLog) -> Option<f64> {
    let mut prev: Option<f64> = None;
    let (mut turned, mut lo, mut hi) = (0.0f64, 0.0f64, 0.0f64);
    for r in &log.rows {
        let Some(e) = r.truth else { continue };
        if let Some(p) = prev {
            turned += wrap(e[2] - p);
            lo = lo.min(turned);
            hi = hi.max(turned);
            if hi - lo >= std::f64::consts::TAU {
                return Some(r.t);
            }
        }
        prev = Some(e[2]);
    }
    None
}

/// Width of the centred moving mean of the true wind that [`WindError::horizontal_vs_mean`]
/// compares with, s: several correlation times of light/moderate Dryden turbulence.
pub const WIND_MEAN_WINDOW: f64 = 60.0;

/// The horizontal true wind of each row averaged over the rows within ±`window`/2 s
/// (fewer at the ends); `None` where the row has no truth.
fn centred_mean_wind(log: &FlightLog, window: f64) -> Vec<Option<[f64; 2]>> {
    let rows: Vec<(f64, [f64; 2])> =
        log.rows.iter().filter_map(|r| r.truth_wind.map(|w| (r.t, [w[0], w[1]]))).collect();
    let mut sum = vec![[0.0f64; 2]; rows.len() + 1];
    for (i, (_, w)) in rows.iter().enumerate() {
        sum[i + 1] = [sum[i][0] + w[0], sum[i][1] + w[1]];
    }
    let (mut lo, mut hi) = (0usize, 0usize);
    let mut means = Vec::with_capacity(rows.len());
    for &(t, _) in &rows {
        while rows[lo].0 < t - window / 2.0 {
            lo += 1;
        }
        while hi < rows.len() && rows[hi].0 <= t + window / 2.0 {
            hi += 1;
        }
        let k = (hi - lo) as f64;
        means.push([(sum[hi][0] - sum[lo][0]) / k, (sum[hi][1] - sum[lo][1]) / k]);
    }
    let mut it = means.into_iter();
    log.rows.iter().map(|r| r.truth_wind.and_then(|_| it.next())).collect()
}

/// Wind error of `est` against the log's `true_wind_*` (see [`WindError`]).
pub fn wind_error(log: &FlightLog, est: &[EstimateRow], t_from: f64) -> Option<WindError> {
    if !log.rows.iter().any(|r| r.truth_wind.is_some()) || !est.iter().any(|e| e.wind.is_some()) {
        return None;
    }
    let t0 = first_full_turn(log).map_or(f64::INFINITY, |t| t.max(t_from));
    let mean = centred_mean_wind(log, WIND_MEAN_WINDOW);
    let (mut n, mut e, mut h, mut hm, mut rows) = (vec![], vec![], vec![], vec![], 0usize);
    for ((r, x), m) in log.rows.iter().zip(est).zip(&mean).filter(|((r, _), _)| r.t >= t0) {
        let (Some(w), Some(m)) = (r.truth_wind, m) else { continue };
        rows += 1;
        if let Some((we, _)) = x.wind {
            n.push(we[0] - w[0]);
            e.push(we[1] - w[1]);
            h.push((we[0] - w[0]).hypot(we[1] - w[1]));
            hm.push((we[0] - m[0]).hypot(we[1] - m[1]));
        }
    }
    Some(WindError {
        t_from: t0,
        ne: [Stats::of(&n), Stats::of(&e)],
        horizontal: Stats::of(&h),
        horizontal_vs_mean: Stats::of(&hm),
        coverage: if rows == 0 { 0.0 } else { h.len() as f64 / rows as f64 },
    })
}

/// Per-row attitude differences (estimate − truth/ref, wrapped) as (t, [φ, θ, ψ]).
/// Rows are paired by index: `est` must come from replaying `log`.
pub fn differences(log: &FlightLog, est: &[EstimateRow], against: Against) -> Vec<(f64, [f64; 3])> {
    log.rows
        .iter()
        .zip(est)
        .filter_map(|(r, e)| {
            let truth = target(r, against)?;
            if !truth.iter().all(|v| v.is_finite()) {
                return None; // counted by compare_with
            }
            Some((e.t, [0, 1, 2].map(|i| wrap(e.att[i] - truth[i]))))
        })
        .collect()
}

fn target(r: &crate::log::LogRow, against: Against) -> Option<[f64; 3]> {
    match against {
        Against::Truth => r.truth,
        Against::Reference => r.reference,
    }
}

/// Compares against truth when the log has it, else against `ref_*`; `None` when neither.
pub fn compare(log: &FlightLog, est: &[EstimateRow], t_from: f64) -> Option<Comparison> {
    let against = if log.rows.iter().any(|r| r.truth.is_some()) {
        Against::Truth
    } else if log.rows.iter().any(|r| r.reference.is_some()) {
        Against::Reference
    } else {
        return None;
    };
    Some(compare_with(log, est, t_from, against))
}

/// Compares against the given source.
pub fn compare_with(
    log: &FlightLog,
    est: &[EstimateRow],
    t_from: f64,
    against: Against,
) -> Comparison {
    let d = differences(log, est, against);
    let att = [0, 1, 2].map(|i| {
        Stats::of(&d.iter().filter(|(t, _)| *t >= t_from).map(|(_, e)| e[i]).collect::<Vec<_>>())
    });
    let bias =
        (against == Against::Truth && log.rows.iter().any(|r| r.truth_bias.is_some())).then(|| {
            [0, 1, 2].map(|i| {
                Stats::of(
                    &log.rows
                        .iter()
                        .zip(est)
                        .filter(|(_, e)| e.t >= t_from)
                        .filter_map(|(r, e)| Some(e.bias[i] - r.truth_bias?[i]))
                        .collect::<Vec<_>>(),
                )
            })
        });
    let (mut tilt, mut total) = (vec![], vec![]);
    for (r, e) in log.rows.iter().zip(est).filter(|(_, e)| e.t >= t_from) {
        if let Some(x) = target(r, against).filter(|v| v.iter().all(|x| x.is_finite())) {
            tilt.push(tilt_error(e.att, x));
            total.push(attitude_error(e.att, x));
        }
    }
    let skipped_nonfinite = log
        .rows
        .iter()
        .filter(|r| target(r, against).is_some_and(|v| !v.iter().all(|x| x.is_finite())))
        .count();
    let wind = (against == Against::Truth).then(|| wind_error(log, est, t_from)).flatten();
    Comparison {
        against,
        t_from,
        att,
        bias,
        tilt: Stats::of(&tilt),
        total: Stats::of(&total),
        wind,
        skipped_nonfinite,
    }
}

/// Error at the first row at or after `t` (e.g. the end of a GPS outage), rad.
pub fn error_at(log: &FlightLog, est: &[EstimateRow], t: f64) -> Option<[f64; 3]> {
    differences(log, est, Against::Truth).into_iter().find(|(ti, _)| *ti >= t).map(|(_, e)| e)
}

/// Innovation statistics of one axis.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct InnovationStats {
    /// Innovation statistics, rad.
    pub innov: Stats,
    /// Mean normalised innovation squared ν²/S (≈ 1 when R and P are right).
    pub nis_mean: f64,
    /// Autocorrelation of ν/√S at lags 1..=`lags`.
    pub autocorr: Vec<f64>,
    /// Fraction of those lags inside the 95 % white-noise band ±1.96/√N.
    pub white_fraction: f64,
}

/// Innovation statistics per axis over update rows from `t_from` on (gated rows included:
/// the gate's decision is part of the health signal). `None` for an axis never measured.
pub fn innovation_stats(
    est: &[EstimateRow],
    t_from: f64,
    lags: usize,
) -> [Option<InnovationStats>; 3] {
    [0, 1, 2].map(|i| {
        let pairs: Vec<(f64, f64)> = est
            .iter()
            .filter(|e| e.t >= t_from)
            .filter_map(|e| Some((e.innov[i]?, e.innov_sd[i]?)))
            .collect();
        if pairs.len() < 3 {
            return None;
        }
        let nu: Vec<f64> = pairs.iter().map(|p| p.0).collect();
        let z: Vec<f64> = pairs.iter().map(|(v, s)| v / s).collect();
        let nis_mean = z.iter().map(|x| x * x).sum::<f64>() / z.len() as f64;
        let ac: Vec<f64> = (1..=lags.min(z.len() - 1)).map(|l| autocorrelation(&z, l)).collect();
        let band = 1.96 / (z.len() as f64).sqrt();
        let white_fraction = if ac.is_empty() {
            1.0
        } else {
            ac.iter().filter(|r| r.abs() <= band).count() as f64 / ac.len() as f64
        };
        Some(InnovationStats { innov: Stats::of(&nu), nis_mean, autocorr: ac, white_fraction })
    })
}

/// Sample autocorrelation of `x` at `lag`.
pub fn autocorrelation(x: &[f64], lag: usize) -> f64 {
    let n = x.len();
    if lag >= n {
        return 0.0;
    }
    let m = x.iter().sum::<f64>() / n as f64;
    let den: f64 = x.iter().map(|v| (v - m).powi(2)).sum();
    if den == 0.0 {
        return 0.0;
    }
    (0..n - lag).map(|k| (x[k] - m) * (x[k + lag] - m)).sum::<f64>() / den
}

/// NEES `eᵀ P⁻¹ e` of a 6-state error (angles wrapped by the caller) with the filter's P,
/// by Cholesky in f64. `None` if P is not positive definite.
pub fn nees(e: &[f64; 6], p: &[[f32; 6]; 6]) -> Option<f64> {
    nees_sub(e, p, &[0, 1, 2, 3, 4, 5])
}

/// NEES over the sub-state `idx` (e.g. `[0, 1, 2]`: attitude only, 3 dof).
pub fn nees_sub(e: &[f64; 6], p: &[[f32; 6]; 6], idx: &[usize]) -> Option<f64> {
    let n = idx.len();
    let mut l = [[0.0f64; 6]; 6];
    for i in 0..n {
        for j in 0..=i {
            let (a, b) = (idx[i], idx[j]);
            let mut s = 0.5 * (p[a][b] as f64 + p[b][a] as f64);
            for k in 0..j {
                s -= l[i][k] * l[j][k];
            }
            if i == j {
                if !(s > 0.0) {
                    return None;
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    // Solve L y = e; NEES = |y|².
    let mut y = [0.0f64; 6];
    for i in 0..n {
        let mut s = e[idx[i]];
        for k in 0..i {
            s -= l[i][k] * y[k];
        }
        y[i] = s / l[i][i];
    }
    Some(y[..n].iter().map(|v| v * v).sum())
}

/// Whether P is symmetric (to `rel_tol` of its diagonal scale) and positive definite.
pub fn symmetric_pd(p: &[[f32; 6]; 6], rel_tol: f64) -> bool {
    for i in 0..6 {
        for j in 0..6 {
            let (a, b) = (p[i][j] as f64, p[j][i] as f64);
            let scale = (p[i][i] as f64 * p[j][j] as f64).sqrt().max(1e-30);
            if !a.is_finite() || (a - b).abs() > rel_tol * scale {
                return false;
            }
        }
    }
    nees(&[0.0; 6], p).is_some()
}

/// Standard normal quantile for the 95 % two-sided bounds.
const Z_975: f64 = 1.959_963_985;

/// Two-sided 95 % bounds of the *average* of `runs` independent χ²(`dof`) variables:
/// χ²(dof·runs) quantiles 2.5 %/97.5 % divided by `runs` (Wilson–Hilferty
/// approximation; relative error < 1 % for dof·runs ≥ 10).
pub fn chi2_mean_bounds(dof: usize, runs: usize) -> (f64, f64) {
    let k = (dof * runs) as f64;
    let q = |z: f64| {
        let a = 2.0 / (9.0 * k);
        k * (1.0 - a + z * a.sqrt()).powi(3)
    };
    (q(-Z_975) / runs as f64, q(Z_975) / runs as f64)
}

/// A Monte-Carlo consistency result for one quantity (NEES or one axis' NIS).
#[derive(Debug, Clone, PartialEq)]
pub struct Consistency {
    /// Degrees of freedom of one sample.
    pub dof: usize,
    /// Number of runs averaged.
    pub runs: usize,
    /// 95 % bounds of the run-average.
    pub bounds: (f64, f64),
    /// Mean over epochs of the run-averaged statistic.
    pub mean: f64,
    /// Fraction of epochs whose run-average lies inside the bounds (≈ 0.95 when consistent).
    pub inside: f64,
    /// Fraction of epochs above the upper bound (over-confident filter).
    pub above: f64,
    /// Fraction of epochs below the lower bound (under-confident filter).
    pub below: f64,
    /// Number of epochs.
    pub epochs: usize,
}

/// Run-averages a statistic over `series[run][epoch]` (runs must share the epoch grid;
/// `None` samples are skipped) and checks it against the χ² bounds.
pub fn consistency(series: &[Vec<Option<f64>>], dof: usize) -> Option<Consistency> {
    let runs = series.len();
    let epochs = series.iter().map(Vec::len).min()?;
    let mut avg = Vec::with_capacity(epochs);
    for k in 0..epochs {
        let v: Vec<f64> = series.iter().filter_map(|s| s[k]).collect();
        if v.len() == runs {
            avg.push(v.iter().sum::<f64>() / runs as f64);
        }
    }
    if avg.is_empty() || runs == 0 {
        return None;
    }
    let bounds = chi2_mean_bounds(dof, runs);
    let n = avg.len() as f64;
    Some(Consistency {
        dof,
        runs,
        bounds,
        mean: avg.iter().sum::<f64>() / n,
        inside: avg.iter().filter(|v| **v >= bounds.0 && **v <= bounds.1).count() as f64 / n,
        above: avg.iter().filter(|v| **v > bounds.1).count() as f64 / n,
        below: avg.iter().filter(|v| **v < bounds.0).count() as f64 / n,
        epochs: avg.len(),
    })
}
