//! Figures like thesis Figs 5.5–5.9 and 5.16, as PNG and SVG (plotters). Text is
//! drawn with DejaVu Sans embedded from the `dejavu` crate through plotters'
//! `ab_glyph` backend, so no system fonts are needed (headless CI).

use crate::estimate::EstimateRow;
use crate::log::FlightLog;
use crate::metrics::wrap;
use anyhow::{anyhow, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

const DEG: f64 = 180.0 / std::f64::consts::PI;
const AXES: [&str; 3] = ["roll", "pitch", "yaw"];
/// Width of the legend column right of each panel, px.
const LEGEND_W: u32 = 150;

/// One curve of a panel.
pub struct Series {
    /// Legend text.
    pub name: String,
    /// Colour.
    pub color: RGBColor,
    /// (t, value) points.
    pub points: Vec<(f64, f64)>,
}

/// One panel (a y axis) of a figure.
pub struct Panel {
    /// Y-axis label.
    pub ylabel: String,
    /// Curves.
    pub series: Vec<Series>,
}

fn register_fonts() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // Both fail only on a corrupt embedded font; text would then be missing, plots still drawn.
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            dejavu::sans::regular(),
        );
        let _ = plotters::style::register_font("sans-serif", FontStyle::Bold, dejavu::sans::bold());
    });
}

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    title: &str,
    panels: &[Panel],
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("drawing: {x:?}");
    root.fill(&WHITE).map_err(e)?;
    let root = root.titled(title, ("sans-serif", 20)).map_err(e)?;
    let areas = root.split_evenly((panels.len(), 1));
    for (area, p) in areas.iter().zip(panels) {
        // The legend gets its own column right of the plot, so it never covers the data.
        let (plot, legend) =
            area.split_horizontally(area.dim_in_pixel().0.saturating_sub(LEGEND_W));
        let pts = p
            .series
            .iter()
            .flat_map(|s| s.points.iter())
            .filter(|(t, v)| t.is_finite() && v.is_finite());
        let (mut t0, mut t1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for (t, v) in pts {
            t0 = t0.min(*t);
            t1 = t1.max(*t);
            y0 = y0.min(*v);
            y1 = y1.max(*v);
        }
        if t0 > t1 {
            continue;
        }
        if t1 - t0 < 1e-9 {
            t1 = t0 + 1.0;
        }
        let pad = ((y1 - y0) * 0.05).max(1e-6);
        let mut chart = ChartBuilder::on(&plot)
            .margin(6)
            // Room for the last x tick's label, which is centred on the plot's right edge.
            .margin_right(24)
            .x_label_area_size(28)
            .y_label_area_size(56)
            .build_cartesian_2d(t0..t1, (y0 - pad)..(y1 + pad))
            .map_err(e)?;
        chart
            .configure_mesh()
            .x_desc("t [s]")
            .y_desc(p.ylabel.as_str())
            .label_style(("sans-serif", 12))
            .light_line_style(WHITE.mix(0.0))
            .draw()
            .map_err(e)?;
        for s in &p.series {
            chart
                .draw_series(LineSeries::new(
                    s.points.iter().copied().filter(|(t, v)| t.is_finite() && v.is_finite()),
                    s.color.stroke_width(1),
                ))
                .map_err(e)?;
        }
        for (k, s) in p.series.iter().enumerate() {
            let y = 16 + 18 * k as i32;
            legend
                .draw(&PathElement::new(vec![(4, y), (24, y)], s.color.stroke_width(2)))
                .map_err(e)?;
            legend.draw(&Text::new(s.name.as_str(), (30, y - 7), ("sans-serif", 12))).map_err(e)?;
        }
    }
    root.present().map_err(e)?;
    Ok(())
}

/// Writes `<stem>.png` and `<stem>.svg` in `dir`; returns the PNG path.
pub fn write_figure(
    dir: &Path,
    stem: &str,
    title: &str,
    panels: &[Panel],
) -> Result<std::path::PathBuf> {
    register_fonts();
    std::fs::create_dir_all(dir)?;
    let h = 220 * panels.len() as u32 + 40;
    let png = dir.join(format!("{stem}.png"));
    draw(BitMapBackend::new(&png, (1000, h)).into_drawing_area(), title, panels)?;
    let svg = dir.join(format!("{stem}.svg"));
    draw(SVGBackend::new(&svg, (1000, h)).into_drawing_area(), title, panels)?;
    Ok(png)
}

/// Light blue for an estimate drawn under its truth.
const ESTIMATE: RGBColor = RGBColor(110, 150, 255);

/// Half-height of an error panel, deg: 1.5× the 99th percentile of |error| (at least 0.01°).
fn error_axis_limit(error: &[(f64, f64)]) -> f64 {
    let mut a: Vec<f64> = error.iter().map(|p| p.1.abs()).filter(|v| v.is_finite()).collect();
    a.sort_by(f64::total_cmp);
    let p99 = a.get(a.len().saturating_sub(1) * 99 / 100).copied().unwrap_or(0.0);
    (1.5 * p99).max(0.01)
}

/// Keeps at most ~`n` evenly spaced points (figures need not show every 10 ms sample).
fn thin<T: Clone>(v: &[T], n: usize) -> Vec<T> {
    let step = (v.len() / n.max(1)).max(1);
    v.iter().step_by(step).cloned().collect()
}

/// Writes the standard figure set for one replay: attitude vs truth/ref, error with
/// ±3σ, biases (vs true bias when known), innovations with ±σ. Returns the PNG paths.
pub fn standard_set(
    dir: &Path,
    stem: &str,
    title: &str,
    log: &FlightLog,
    est: &[EstimateRow],
) -> Result<Vec<std::path::PathBuf>> {
    let mut out = Vec::new();
    let est_t = thin(est, 4000);
    let truth_label =
        if log.rows.iter().any(|r| r.truth.is_some()) { "truth" } else { "ref (other estimator)" };
    let rows = thin(&log.rows, 4000);
    let reference = |r: &crate::log::LogRow| r.truth.or(r.reference);

    let att: Vec<Panel> = (0..3)
        .map(|i| Panel {
            ylabel: format!("{} [deg]", AXES[i]),
            // Truth last, so it is drawn over the (light) estimate and stays visible.
            series: vec![
                Series {
                    name: "estimate".into(),
                    color: ESTIMATE,
                    points: est_t.iter().map(|e| (e.t, e.att[i] * DEG)).collect(),
                },
                Series {
                    name: truth_label.into(),
                    color: BLACK,
                    points: rows
                        .iter()
                        .filter_map(|r| Some((r.t, reference(r)?[i] * DEG)))
                        .collect(),
                },
            ],
        })
        .collect();
    out.push(write_figure(dir, &format!("{stem}_attitude"), &format!("{title}: attitude"), &att)?);

    if log.rows.iter().any(|r| reference(r).is_some()) {
        let pairs: Vec<(f64, [f64; 3], [f64; 3])> = thin(
            &log.rows
                .iter()
                .zip(est)
                .filter_map(|(r, e)| Some((e.t, reference(r)?, [0, 1, 2].map(|i| e.sd[i]))))
                .collect::<Vec<_>>(),
            4000,
        );
        let ests: std::collections::HashMap<u64, &EstimateRow> =
            est.iter().map(|e| (e.t.to_bits(), e)).collect();
        let err: Vec<Panel> = (0..3)
            .map(|i| {
                let error: Vec<(f64, f64)> = pairs
                    .iter()
                    .filter_map(|(t, x, _)| {
                        Some((*t, wrap(ests.get(&t.to_bits())?.att[i] - x[i]) * DEG))
                    })
                    .collect();
                // The axis follows the error (its 99th percentile), not the start-up σ that
                // would squash a 0.04° error flat: curves beyond it are clipped to the edge.
                let lim = error_axis_limit(&error);
                let clip = |v: f64| v.clamp(-lim, lim);
                let mut series = vec![Series {
                    name: if truth_label == "truth" {
                        "error".into()
                    } else {
                        "difference to ref".into()
                    },
                    color: BLUE,
                    points: error.iter().map(|&(t, v)| (t, clip(v))).collect(),
                }];
                series.push(Series {
                    name: "+3σ (P)".into(),
                    color: RED,
                    points: pairs.iter().map(|(t, _, s)| (*t, clip(3.0 * s[i] * DEG))).collect(),
                });
                series.push(Series {
                    name: "−3σ (P)".into(),
                    color: RED,
                    points: pairs.iter().map(|(t, _, s)| (*t, clip(-3.0 * s[i] * DEG))).collect(),
                });
                Panel { ylabel: format!("{} err [deg]", AXES[i]), series }
            })
            .collect();
        out.push(write_figure(
            dir,
            &format!("{stem}_error"),
            &format!(
                "{title}: {} with ±3σ",
                if truth_label == "truth" { "error" } else { "difference to ref" }
            ),
            &err,
        )?);
    }

    let bias: Vec<Panel> = (0..3)
        .map(|i| {
            let mut series = vec![Series {
                name: "estimate".into(),
                color: BLUE,
                points: est_t.iter().map(|e| (e.t, e.bias[i] * DEG)).collect(),
            }];
            let tb: Vec<(f64, f64)> =
                rows.iter().filter_map(|r| Some((r.t, r.truth_bias?[i] * DEG))).collect();
            if !tb.is_empty() {
                series.insert(0, Series { name: "truth".into(), color: BLACK, points: tb });
            }
            Panel { ylabel: format!("b{} [deg/s]", ["p", "q", "r"][i]), series }
        })
        .collect();
    out.push(write_figure(dir, &format!("{stem}_bias"), &format!("{title}: gyro bias"), &bias)?);

    let upd: Vec<&EstimateRow> = est.iter().filter(|e| e.is_update()).collect();
    let innov: Vec<Panel> = (0..3)
        .map(|i| Panel {
            ylabel: format!("ν {} [deg]", AXES[i]),
            series: vec![
                Series {
                    name: "innovation".into(),
                    color: BLUE,
                    points: upd.iter().filter_map(|e| Some((e.t, e.innov[i]? * DEG))).collect(),
                },
                Series {
                    name: "+σ (√S)".into(),
                    color: RED,
                    points: upd.iter().filter_map(|e| Some((e.t, e.innov_sd[i]? * DEG))).collect(),
                },
                Series {
                    name: "−σ".into(),
                    color: RED,
                    points: upd.iter().filter_map(|e| Some((e.t, -e.innov_sd[i]? * DEG))).collect(),
                },
            ],
        })
        .collect();
    out.push(write_figure(
        dir,
        &format!("{stem}_innovations"),
        &format!("{title}: innovations"),
        &innov,
    )?);
    Ok(out)
}
