//! Monte Carlo over seeds: each run simulates a flight (the caller's closure), replays
//! it through the core and records NEES, NIS and errors. Runs in parallel on all
//! cores (rayon) with a progress bar (indicatif).

use crate::log::FlightLog;
use crate::metrics::{self, wrap, Consistency, Stats};
use anyhow::Result;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use wing_ahrs::Config;

const DEG: f64 = 180.0 / std::f64::consts::PI;

/// NEES is sampled every this many IMU rows (100 Hz → 10 Hz): neighbouring samples
/// are nearly identical, so more would only cost memory.
const NEES_EVERY: usize = 10;

/// What one run records.
#[derive(Debug, Clone, Default)]
pub struct RunRecord {
    /// Seed of the run.
    pub seed: u64,
    /// Full-state NEES (6 dof) per sampled epoch after `t_from`.
    pub nees6: Vec<Option<f64>>,
    /// Attitude-only NEES (3 dof) per sampled epoch.
    pub nees3: Vec<Option<f64>>,
    /// Per-axis attitude NEES (1 dof each: e²/Pᵢᵢ) per sampled epoch.
    pub nees_axis: [Vec<Option<f64>>; 3],
    /// Time of each sampled epoch, s.
    pub nees_t: Vec<f64>,
    /// NIS per axis per update (in update order).
    pub nis: [Vec<Option<f64>>; 3],
    /// Attitude error statistics after `t_from`, rad.
    pub err: [Stats; 3],
    /// Whether any state or P entry was non-finite, or P lost symmetry/PD.
    pub broken: bool,
    /// Per sampled epoch, the columns of [`EPOCH_COLUMNS`] (for `--epochs-csv`): where in
    /// which run the attitude error leaves its reported σ.
    pub epochs: Vec<[f64; EPOCH_COLUMNS.len()]>,
}

/// The columns of [`RunRecord::epochs`] after `seed` (errors and σ in degrees, NED axes).
pub const EPOCH_COLUMNS: [&str; 20] = [
    "t",
    "e_n",
    "e_e",
    "e_d",
    "sd_n",
    "sd_e",
    "sd_d",
    "roll",
    "pitch",
    "yaw_rate",
    "latency",
    "wind_err",
    "wind_sd",
    "wind_speed",
    "eb_x",
    "eb_y",
    "eb_z",
    "sdb_x",
    "sdb_y",
    "sdb_z",
];

/// Aggregated Monte Carlo result.
#[derive(Debug, Clone)]
pub struct McResult {
    /// Per-run records.
    pub runs: Vec<RunRecord>,
    /// 6-dof NEES consistency.
    pub nees6: Option<Consistency>,
    /// 3-dof (attitude) NEES consistency.
    pub nees3: Option<Consistency>,
    /// Per-axis NIS consistency (1 dof).
    pub nis: [Option<Consistency>; 3],
    /// Run-average of each axis' error RMS and std, rad.
    pub err_rms: [f64; 3],
    /// Mean over runs of the per-run error std, rad.
    pub err_std: [f64; 3],
    /// Largest |error| over all runs, rad.
    pub err_max: [f64; 3],
    /// Share of all runs' sampled epochs where an attitude axis (NED) is off by more than
    /// 4 of its reported σ, and the number of epochs; `None` without samples.
    pub beyond_4sigma: Option<(f64, usize)>,
}

/// One `--epochs-csv` row ([`EPOCH_COLUMNS`]): the NED attitude and bias errors `e` with
/// their σ from `p`, the truth's roll, pitch and heading rate, the latency, the wind error.
fn epoch_row(
    row: &crate::log::LogRow,
    tr: [f64; 3],
    e: &[f64; 6],
    p: &[[f32; 6]; 6],
    ahrs: &wing_ahrs::Ahrs,
) -> [f64; EPOCH_COLUMNS.len()] {
    let sd = |i: usize| (p[i][i] as f64).max(0.0).sqrt() * DEG;
    // The heading rate of the truth's attitude from the body rates (bias-free gyro).
    let (sf, cf) = tr[0].sin_cos();
    let g = row.gyro;
    let yaw_rate = (g[1] * sf + g[2] * cf) / tr[1].cos().max(1e-3) * DEG;
    let (w_err, w_sd) = match (ahrs.wind(), row.truth_wind) {
        (Some((w, s)), Some(tw)) => {
            ((w[0] as f64 - tw[0]).hypot(w[1] as f64 - tw[1]), (s[0] as f64).hypot(s[1] as f64))
        }
        _ => (f64::NAN, f64::NAN),
    };
    let w_speed = row.truth_wind.map_or(f64::NAN, |w| w[0].hypot(w[1]));
    [
        row.t,
        e[0] * DEG,
        e[1] * DEG,
        e[2] * DEG,
        sd(0),
        sd(1),
        sd(2),
        tr[0] * DEG,
        tr[1] * DEG,
        yaw_rate,
        ahrs.gps_latency() as f64,
        w_err,
        w_sd,
        w_speed,
        e[3] * DEG,
        e[4] * DEG,
        e[5] * DEG,
        sd(3),
        sd(4),
        sd(5),
    ]
}

/// One run: replays `log` and records consistency statistics from `t_from` on.
pub fn record_run(seed: u64, log: &FlightLog, cfg: Config, t_from: f64) -> RunRecord {
    let mut rec = RunRecord { seed, ..Default::default() };
    let mut errs: [Vec<f64>; 3] = Default::default();
    let mut seq = 0u32;
    let mut k = 0usize;
    crate::replay::run(log, cfg, |row, ahrs| {
        k += 1;
        // The quaternion filter's own error covariance (NED attitude error) where it has
        // one: no Euler singularity in the consistency check.
        let ned = ahrs.error_covariance();
        let p = ned.unwrap_or_else(|| ahrs.covariance());
        let x = ahrs.state();
        if !x.iter().all(|v| v.is_finite()) || !p.iter().flatten().all(|v| v.is_finite()) {
            rec.broken = true;
        }
        let upd = ahrs.last_update();
        let new_update = upd.seq != seq;
        seq = upd.seq;
        if row.t < t_from {
            return;
        }
        if new_update {
            for i in 0..3 {
                rec.nis[i].push(upd.axes[i].nis().map(|v| v as f64));
            }
        }
        let (Some(tr), Some(tb)) = (row.truth, row.truth_bias) else { return };
        for i in 0..3 {
            errs[i].push(wrap(x[i] as f64 - tr[i]));
        }
        if k.is_multiple_of(NEES_EVERY) {
            if !metrics::symmetric_pd(&p, 1e-4) {
                rec.broken = true;
            }
            let att = if ned.is_some() {
                rotation_error_ned([x[0], x[1], x[2]].map(f64::from), tr)
            } else {
                [wrap(x[0] as f64 - tr[0]), wrap(x[1] as f64 - tr[1]), wrap(x[2] as f64 - tr[2])]
            };
            let e = [
                att[0],
                att[1],
                att[2],
                x[3] as f64 - tb[0],
                x[4] as f64 - tb[1],
                x[5] as f64 - tb[2],
            ];
            rec.nees6.push(metrics::nees(&e, &p));
            rec.nees3.push(metrics::nees_sub(&e, &p, &[0, 1, 2]));
            for i in 0..3 {
                rec.nees_axis[i].push(metrics::nees_sub(&e, &p, &[i]));
            }
            rec.nees_t.push(row.t);
            rec.epochs.push(epoch_row(row, tr, &e, &p, ahrs));
        }
    });
    rec.err = [0, 1, 2].map(|i| Stats::of(&errs[i]));
    rec
}

/// Runs `runs` seeds (`seed0`, `seed0+1`, …) in parallel. `make_log(seed)` simulates a flight.
pub fn run<F>(
    runs: usize,
    seed0: u64,
    cfg: Config,
    t_from: f64,
    progress: bool,
    make_log: F,
) -> Result<McResult>
where
    F: Fn(u64) -> Result<FlightLog> + Sync,
{
    let pb = if progress { ProgressBar::new(runs as u64) } else { ProgressBar::hidden() };
    pb.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} runs ({eta} left)",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let recs: Vec<RunRecord> = (0..runs as u64)
        .into_par_iter()
        .map(|i| {
            let seed = seed0 + i;
            let log = make_log(seed)?;
            let r = record_run(seed, &log, cfg, t_from);
            pb.inc(1);
            Ok(r)
        })
        .collect::<Result<_>>()?;
    pb.finish_and_clear();
    Ok(aggregate(recs))
}

/// Aggregates run records into consistency and error figures.
pub fn aggregate(runs: Vec<RunRecord>) -> McResult {
    let col = |f: &dyn Fn(&RunRecord) -> Vec<Option<f64>>| runs.iter().map(f).collect::<Vec<_>>();
    let nees6 = metrics::consistency(&col(&|r| r.nees6.clone()), 6);
    let nees3 = metrics::consistency(&col(&|r| r.nees3.clone()), 3);
    let nis = [0, 1, 2].map(|i| metrics::consistency(&col(&|r| r.nis[i].clone()), 1));
    let n = runs.len().max(1) as f64;
    let err_rms = [0, 1, 2].map(|i| runs.iter().map(|r| r.err[i].rms).sum::<f64>() / n);
    let err_std = [0, 1, 2].map(|i| runs.iter().map(|r| r.err[i].std).sum::<f64>() / n);
    let err_max = [0, 1, 2].map(|i| runs.iter().map(|r| r.err[i].max_abs).fold(0.0, f64::max));
    let beyond_4sigma = beyond_4sigma(&runs);
    McResult { runs, nees6, nees3, nis, err_rms, err_std, err_max, beyond_4sigma }
}

/// The "≤ 1 % of samples beyond 4σ": per epoch, whether any axis' `e²/σ²` > 16.
fn beyond_4sigma(runs: &[RunRecord]) -> Option<(f64, usize)> {
    let (mut n, mut out) = (0usize, 0usize);
    for r in runs {
        for k in 0..r.nees_t.len() {
            let axes: Vec<f64> =
                r.nees_axis.iter().filter_map(|a| a.get(k).copied().flatten()).collect();
            if axes.len() == 3 {
                n += 1;
                out += usize::from(axes.iter().any(|&v| v > 16.0));
            }
        }
    }
    (n > 0).then(|| (out as f64 / n as f64, n))
}

/// A buffered CSV file, with the path in the error.
fn create(path: &std::path::Path) -> Result<std::io::BufWriter<std::fs::File>> {
    let f = std::fs::File::create(path)
        .map_err(|e| anyhow::anyhow!("cannot create {}: {e}", path.display()))?;
    Ok(std::io::BufWriter::new(f))
}

/// Writes the run-mean NEES per sampled epoch as CSV: `t, nees6, nees3, nees_roll,
/// nees_pitch, nees_yaw` (each a mean over runs; compare with the χ² bounds of
/// [`format`]) — where in a flight a filter is over- or under-confident.
pub fn write_nees_csv(path: &std::path::Path, res: &McResult) -> Result<()> {
    use std::io::Write;
    let Some(first) = res.runs.first() else { return Ok(()) };
    let mut w = create(path)?;
    writeln!(w, "t,nees6,nees3,nees_roll,nees_pitch,nees_yaw")?;
    let mean = |f: &dyn Fn(&RunRecord) -> Option<f64>| {
        let v: Vec<f64> = res.runs.iter().filter_map(f).collect();
        if v.is_empty() {
            f64::NAN
        } else {
            v.iter().sum::<f64>() / v.len() as f64
        }
    };
    for (k, t) in first.nees_t.iter().enumerate() {
        let at = |s: &Vec<Option<f64>>| s.get(k).copied().flatten();
        let c = [
            mean(&|r| at(&r.nees6)),
            mean(&|r| at(&r.nees3)),
            mean(&|r| at(&r.nees_axis[0])),
            mean(&|r| at(&r.nees_axis[1])),
            mean(&|r| at(&r.nees_axis[2])),
        ];
        writeln!(w, "{t},{},{},{},{},{}", c[0], c[1], c[2], c[3], c[4])?;
    }
    w.flush()?;
    Ok(())
}

/// Writes every run's sampled epochs as CSV: `seed` and [`EPOCH_COLUMNS`].
pub fn write_epochs_csv(path: &std::path::Path, res: &McResult) -> Result<()> {
    use std::io::Write;
    let mut w = create(path)?;
    writeln!(w, "seed,{}", EPOCH_COLUMNS.join(","))?;
    for r in &res.runs {
        for e in &r.epochs {
            write!(w, "{}", r.seed)?;
            for v in e {
                write!(w, ",{v}")?;
            }
            writeln!(w)?;
        }
    }
    w.flush()?;
    Ok(())
}

/// Human-readable summary (degrees in output).
pub fn format(res: &McResult) -> String {
    use std::fmt::Write;
    let d = DEG;
    let mut s = String::new();
    let line = |s: &mut String, name: &str, c: &Option<Consistency>| {
        if let Some(c) = c {
            let ok = if c.inside >= 0.90 {
                "consistent"
            } else if c.above > 0.5 {
                "OVER-confident (P/S too small)"
            } else if c.below > 0.5 {
                "UNDER-confident (P/S too large)"
            } else {
                "inconsistent"
            };
            let _ = writeln!(
                s,
                "  {name:<12} mean {:>8.3}  95% bounds [{:.3}, {:.3}] (χ²({}·{})/{})  inside {:>5.1}%  below {:>5.1}%  above {:>5.1}%  → {ok}",
                c.mean, c.bounds.0, c.bounds.1, c.dof, c.runs, c.runs, 100.0 * c.inside, 100.0 * c.below, 100.0 * c.above
            );
        } else {
            let _ = writeln!(s, "  {name:<11} (no samples)");
        }
    };
    let _ = writeln!(s, "Monte Carlo: {} runs", res.runs.len());
    line(&mut s, "NEES (6)", &res.nees6);
    line(&mut s, "NEES att (3)", &res.nees3);
    for (i, a) in ["NIS roll", "NIS pitch", "NIS yaw"].iter().enumerate() {
        line(&mut s, a, &res.nis[i]);
    }
    let _ = writeln!(s, "  error (deg)        roll     pitch    yaw");
    let _ = writeln!(
        s,
        "    mean RMS     {:>8.3} {:>8.3} {:>8.3}",
        res.err_rms[0] * d,
        res.err_rms[1] * d,
        res.err_rms[2] * d
    );
    let _ = writeln!(
        s,
        "    mean std     {:>8.3} {:>8.3} {:>8.3}",
        res.err_std[0] * d,
        res.err_std[1] * d,
        res.err_std[2] * d
    );
    let _ = writeln!(
        s,
        "    max |err|    {:>8.3} {:>8.3} {:>8.3}",
        res.err_max[0] * d,
        res.err_max[1] * d,
        res.err_max[2] * d
    );
    if let Some((f, n)) = res.beyond_4sigma {
        let _ = writeln!(
            s,
            "  attitude error beyond 4σ on an axis: {:.2}% of {n} samples (goal ≤ 1%)",
            100.0 * f
        );
    }
    let broken = res.runs.iter().filter(|r| r.broken).count();
    let _ = writeln!(s, "  runs with NaN / non-PD P: {broken}");
    s
}

/// Body → NED rotation matrix of 3-2-1 Euler angles (f64).
fn dcm(e: [f64; 3]) -> [[f64; 3]; 3] {
    let (sf, cf) = e[0].sin_cos();
    let (st, ct) = e[1].sin_cos();
    let (sp, cp) = e[2].sin_cos();
    [
        [ct * cp, sf * st * cp - cf * sp, cf * st * cp + sf * sp],
        [ct * sp, sf * st * sp + cf * cp, cf * st * sp - sf * cp],
        [-st, sf * ct, cf * ct],
    ]
}

/// The NED rotation error δθ (rad) with `R_true = exp([δθ×])·R_est`, i.e. the
/// rotation vector of `R_true·R_estᵀ`, negated to be "estimate − truth" like the
/// Euler errors: `R_est = exp([δθ×])·R_true`.
pub fn rotation_error_ned(est: [f64; 3], truth: [f64; 3]) -> [f64; 3] {
    let a = dcm(est);
    let b = dcm(truth);
    // E = R_est·R_trueᵀ.
    let mut m = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            m[i][j] = (0..3).map(|k| a[i][k] * b[j][k]).sum();
        }
    }
    let c = ((m[0][0] + m[1][1] + m[2][2] - 1.0) / 2.0).clamp(-1.0, 1.0);
    let ang = c.acos();
    let v = [m[2][1] - m[1][2], m[0][2] - m[2][0], m[1][0] - m[0][1]];
    let s = ang.sin();
    let k = if s.abs() < 1e-9 { 0.5 } else { ang / (2.0 * s) };
    [v[0] * k, v[1] * k, v[2] * k]
}
