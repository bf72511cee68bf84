//! Markdown summaries: per-scenario accuracy side by side with the thesis' numbers
//! (docs/design.md, thesis reference numbers), and the EKF1 variant comparison.

use crate::metrics::{Against, Comparison, InnovationStats};
use std::fmt::Write;
use wing_ahrs::config::{AccelAlignment, Ekf1Config, Ekf1Form, RotationHeading};
use wing_ahrs::{Config, EulerConfig, MeasNoise, Model};

const DEG: f64 = 180.0 / std::f64::consts::PI;

/// Thesis reference (docs/design.md, thesis reference numbers) for a scenario/model: (label, [φ, θ, ψ] deg).
/// Std of the error, except the outage case (error at t = 79.99 s) and the real
/// flight (std of the difference to an Xsens MTi-G).
pub fn thesis_reference(scenario: &str, model: Model) -> Option<(&'static str, [f64; 3])> {
    match (scenario, model) {
        ("flight1", Model::Ekf1(_)) => Some(("Table 5.2 std", [0.135, 0.136, 0.759])),
        ("flight1", Model::Ekf2(_)) => Some(("Table 5.6 std", [0.704, 0.355, 0.751])),
        ("flight2", Model::Ekf2(_)) => Some(("Table 5.8 std", [1.753, 0.356, 1.810])),
        ("flight1_outage", Model::Ekf1(_)) => {
            Some(("Table 5.10 err @79.99 s", [0.557, -1.412, -3.081]))
        }
        (s, Model::Ekf1(_)) if s.starts_with("px4_") => {
            Some(("§5.4 std vs MTi-G", [2.083, 2.211, 8.273]))
        }
        _ => None,
    }
}

/// One line of the summary.
#[derive(Debug, Clone)]
pub struct Entry {
    /// Scenario or log name.
    pub name: String,
    /// Configuration label (model/variant).
    pub config: String,
    /// Model (for the thesis lookup).
    pub model: Model,
    /// The comparison (truth or ref).
    pub cmp: Comparison,
    /// Innovation statistics per axis.
    pub innov: [Option<InnovationStats>; 3],
    /// Error at the end of an outage (t, [φ, θ, ψ] rad), when the scenario has one.
    pub at: Option<(f64, [f64; 3])>,
}

/// The accuracy table (markdown), degrees.
pub fn accuracy_table(entries: &[Entry]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "| log / scenario | config | compared with | from t [s] | std φ/θ/ψ [°] | RMS φ/θ/ψ [°] | max φ/θ/ψ [°] | mean φ/θ/ψ [°] | tilt RMS / max [°] | total RMS / max [°] | wind RMS / max [m/s] | thesis φ/θ/ψ [°] |");
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|---|");
    for e in entries {
        let a = e.cmp.att.map(|x| x.scaled(DEG));
        let f3 = |v: [f64; 3]| format!("{:.3} / {:.3} / {:.3}", v[0], v[1], v[2]);
        let f2 = |x: &crate::metrics::Stats| format!("{:.3} / {:.3}", x.rms, x.max_abs);
        let thesis = thesis_reference(&e.name, e.model)
            .map_or("—".into(), |(l, v)| format!("{} ({l})", f3(v)));
        let against = match e.cmp.against {
            Against::Truth => "truth",
            Against::Reference => "ref_* (agreement)",
        };
        let wind = match &e.cmp.wind {
            Some(w) if w.horizontal.n > 0 => {
                let cov = if w.coverage < 0.995 {
                    format!(", {:.0} % of rows", 100.0 * w.coverage)
                } else {
                    String::new()
                };
                let m = w.horizontal_vs_mean.rms;
                format!(
                    "{} (from {:.0} s{cov}; vs its 60 s mean {m:.3})",
                    f2(&w.horizontal),
                    w.t_from
                )
            }
            Some(w) if w.t_from.is_infinite() => "— (no full turn)".into(),
            Some(_) => "— (no estimate)".into(),
            None => "—".into(),
        };
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.0} | {} | {} | {} | {} | {} | {} | {} | {} |",
            e.name,
            e.config,
            against,
            e.cmp.t_from,
            f3(a.map(|x| x.std)),
            f3(a.map(|x| x.rms)),
            f3(a.map(|x| x.max_abs)),
            f3(a.map(|x| x.mean)),
            f2(&e.cmp.tilt.scaled(DEG)),
            f2(&e.cmp.total.scaled(DEG)),
            wind,
            thesis
        );
        if let Some((t, err)) = e.at {
            let _ = writeln!(
                s,
                "| {} | {} | truth | at t = {t:.2} s | error {} | | | | | | | {} |",
                e.name,
                e.config,
                f3(err.map(|x| x * DEG)),
                thesis
            );
        }
    }
    s
}

/// Innovation table (markdown): mean/std in degrees, mean NIS, lag-1 autocorrelation,
/// fraction of lags 1..10 inside the white-noise band.
pub fn innovation_table(entries: &[Entry]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "| log / scenario | config | axis | n | ν mean [°] | ν std [°] | mean ν²/S | ρ(1) | white lags |");
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|");
    for e in entries {
        for (i, ax) in ["roll", "pitch", "yaw"].iter().enumerate() {
            if let Some(st) = &e.innov[i] {
                let _ = writeln!(
                    s,
                    "| {} | {} | {ax} | {} | {:.3} | {:.3} | {:.2} | {:.2} | {:.0} % |",
                    e.name,
                    e.config,
                    st.innov.n,
                    st.innov.mean * DEG,
                    st.innov.std * DEG,
                    st.nis_mean,
                    st.autocorr.first().copied().unwrap_or(0.0),
                    100.0 * st.white_fraction
                );
            }
        }
    }
    s
}

/// Applies `f` to the EKF1 options (none with EKF2).
fn set_ekf1(c: &mut Config, f: impl FnOnce(&mut Ekf1Config)) {
    if let Some(e1) = c.ekf1_mut() {
        f(e1);
    }
}

/// Applies `f` to the Euler filter's options.
fn set_euler(c: &mut Config, f: impl FnOnce(&mut EulerConfig)) {
    if let Some(e) = c.euler_mut() {
        f(e);
    }
}

/// Named configurations for the EKF1 variant comparison: the recommended Euler filter
/// (`Config::euler()`), the thesis' exact setting, and one-factor-at-a-time changes from
/// the first.
pub fn ekf1_variants() -> Vec<(String, Config)> {
    let d = Config::euler();
    let mut v = vec![("default".to_string(), d), ("thesis".to_string(), Config::thesis())];
    let mut push = |name: &str, f: &dyn Fn(&mut Config)| {
        let mut c = d;
        f(&mut c);
        if c != d {
            v.push((name.to_string(), c));
        }
    };
    push("form=ThesisExact", &|c| set_ekf1(c, |e| e.form = Ekf1Form::ThesisExact));
    push("form=RobustSingleAxis", &|c| set_ekf1(c, |e| e.form = Ekf1Form::RobustSingleAxis));
    push("form=RobustTwoAxis", &|c| set_ekf1(c, |e| e.form = Ekf1Form::RobustTwoAxis));
    push("align=Latest", &|c| set_ekf1(c, |e| e.accel_alignment = AccelAlignment::Latest));
    push("align=IntervalMean", &|c| {
        set_ekf1(c, |e| e.accel_alignment = AccelAlignment::IntervalMean)
    });
    push("heading=PredictedYaw", &|c| {
        set_ekf1(c, |e| e.rotation_heading = RotationHeading::PredictedYaw)
    });
    push("heading=Course", &|c| set_ekf1(c, |e| e.rotation_heading = RotationHeading::Course));
    push("heading=CorrectedCourse", &|c| {
        set_ekf1(c, |e| e.rotation_heading = RotationHeading::CorrectedCourse)
    });
    push("aoa_correction=off", &|c| set_euler(c, |e| e.heading_aoa_correction = false));
    push("aoa_correction=on", &|c| set_euler(c, |e| e.heading_aoa_correction = true));
    push("gates=off", &|c| set_euler(c, |e| e.gate_chi2 = [f32::INFINITY; 3]));
    push("R fixed 3° (previous default)", &|c| {
        set_euler(c, |e| e.meas_noise = MeasNoise::Fixed { sigma: [3.0f32.to_radians(); 3] });
        if let Some(e2) = c.ekf2_mut() {
            e2.rp_sigma = [3.0f32.to_radians(); 2];
        }
    });
    push("R fixed 1° (thesis eq 5.5)", &|c| {
        set_euler(c, |e| e.meas_noise = MeasNoise::Fixed { sigma: [1.0f32.to_radians(); 3] });
        if let Some(e2) = c.ekf2_mut() {
            e2.rp_sigma = [1.0f32.to_radians(); 2];
        }
    });
    push("R yaw floor 0.15° (NIS-consistent on flight1)", &|c| {
        set_euler(c, |e| {
            if let MeasNoise::FromSensors { floor, .. } = &mut e.meas_noise {
                floor[2] = 0.15f32.to_radians();
            }
        })
    });
    push("bias Gauss–Markov (thesis)", &|c| c.bias_model = Config::thesis().bias_model);
    push("λ = 10 (thesis)", &|c| set_euler(c, |e| e.bias_lambda = 10.0));
    push("white fix noise (differences as independent; before the fix-noise states)", &|c| {
        set_euler(c, |e| {
            if let MeasNoise::FromSensors { correlated_fix_noise, .. } = &mut e.meas_noise {
                *correlated_fix_noise = false;
            }
        })
    });
    push("covariance every sample (decimation 1)", &|c| c.covariance_decimation = 1);
    push("covariance every 10th sample throughout (previous default)", &|c| {
        c.covariance_decimation = 10
    });
    push("covariance every 20th sample from the start (no settling)", &|c| {
        let n = c.covariance_decimation;
        set_euler(c, |e| e.covariance_decimation_settling = n)
    });
    v
}

/// Variant comparison table: rows = variants, columns = RMS φ/θ/ψ per scenario.
/// `results[v][s]` is the comparison of variant v on scenario s.
pub fn variant_table(
    variants: &[String],
    scenarios: &[String],
    results: &[Vec<Option<Comparison>>],
) -> String {
    let mut s = String::new();
    let _ = write!(s, "| variant |");
    for sc in scenarios {
        let _ = write!(s, " {sc} RMS φ/θ/ψ [°] |");
    }
    let _ = write!(s, " mean of all RMS [°] |\n|---|");
    for _ in scenarios {
        s.push_str("---|");
    }
    s.push_str("---|\n");
    for (v, row) in variants.iter().zip(results) {
        let _ = write!(s, "| {v} |");
        let mut tot = Vec::new();
        for c in row {
            match c {
                Some(c) => {
                    let r = c.att.map(|x| x.rms * DEG);
                    tot.extend(r);
                    let _ = write!(s, " {:.3} / {:.3} / {:.3} |", r[0], r[1], r[2]);
                }
                None => s.push_str(" — |"),
            }
        }
        let m = if tot.is_empty() { f64::NAN } else { tot.iter().sum::<f64>() / tot.len() as f64 };
        let _ = writeln!(s, " {m:.3} |");
    }
    s
}
