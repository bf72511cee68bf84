//! Metrics checked against independently known answers: statistics of constructed
//! series, angle wrapping, NEES against a hand-computed quadratic form, χ² bounds
//! against tabulated quantiles, whiteness on white vs. correlated sequences.
use sim_harness::estimate::EstimateRow;
use sim_harness::log::{FlightLog, LogRow};
use sim_harness::metrics::*;

#[test]
fn stats_of_a_known_series() {
    let s = Stats::of(&[1.0, -1.0, 3.0, 1.0]);
    assert!((s.mean - 1.0).abs() < 1e-12);
    assert!((s.std - 2f64.sqrt()).abs() < 1e-12);
    assert!((s.rms - 3f64.sqrt()).abs() < 1e-12);
    assert_eq!(s.max_abs, 3.0);
}

#[test]
fn errors_are_wrapped_and_start_after_convergence_time() {
    let pi = std::f64::consts::PI;
    let mut log = FlightLog::default();
    let mut est = Vec::new();
    for k in 0..200 {
        let t = k as f64 * 0.1;
        log.rows.push(LogRow { t, truth: Some([0.0, 0.0, pi - 0.01]), ..Default::default() });
        // Yaw estimate across the ±π seam: true error +0.02 rad, not −2π + 0.02.
        let roll = if t < 5.0 { 1.0 } else { 0.01 };
        est.push(EstimateRow { t, att: [roll, -0.02, -pi + 0.01], ..Default::default() });
    }
    let c = compare(&log, &est, 5.0).unwrap();
    assert_eq!(c.against, Against::Truth);
    assert!((c.att[0].mean - 0.01).abs() < 1e-12, "samples before t_from must be excluded");
    assert!((c.att[1].rms - 0.02).abs() < 1e-12);
    assert!((c.att[2].mean - 0.02).abs() < 1e-9, "yaw error not wrapped: {}", c.att[2].mean);
    // Without truth, the ref_* columns are used and labelled as agreement.
    for r in &mut log.rows {
        r.reference = r.truth.take();
    }
    let c = compare(&log, &est, 5.0).unwrap();
    assert_eq!(c.against, Against::Reference);
    assert!(Against::Reference.label().contains("agreement"));
}

#[test]
fn nees_matches_the_quadratic_form() {
    // P = diag(4, 1, 9, 1e-4, 1e-4, 1e-4) with a correlation between states 0 and 3.
    let mut p = [[0.0f32; 6]; 6];
    for (i, v) in [4.0, 1.0, 9.0, 1e-4, 1e-4, 1e-4].iter().enumerate() {
        p[i][i] = *v;
    }
    p[0][3] = 0.01;
    p[3][0] = 0.01;
    let e = [2.0, 1.0, 3.0, 0.0, 0.01, 0.0];
    // Block [[4, .01], [.01, 1e-4]] inverse, e0 = 2, e3 = 0 → 4·(1e-4)/det.
    let det = 4.0 * 1e-4 - 0.01 * 0.01;
    let expect = 2.0 * 2.0 * 1e-4 / det + 1.0 + 1.0 + 0.01 * 0.01 / 1e-4;
    let got = nees(&e, &p).unwrap();
    assert!((got - expect).abs() < 1e-3 * expect, "{got} vs {expect}");
    assert!((nees_sub(&e, &p, &[1, 2]).unwrap() - 2.0).abs() < 1e-9);
    assert!(symmetric_pd(&p, 1e-6));
    p[1][1] = -1.0;
    assert!(nees(&e, &p).is_none());
    assert!(!symmetric_pd(&p, 1e-6));
}

#[test]
fn chi2_bounds_match_tables() {
    // χ²(100): 2.5 % = 74.222, 97.5 % = 129.561.  χ²(300): 253.912, 349.874.
    let (lo, hi) = chi2_mean_bounds(1, 100);
    assert!((lo * 100.0 - 74.222).abs() < 0.2 && (hi * 100.0 - 129.561).abs() < 0.2, "{lo} {hi}");
    let (lo, hi) = chi2_mean_bounds(6, 50);
    assert!((lo * 50.0 - 253.912).abs() < 0.3 && (hi * 50.0 - 349.874).abs() < 0.3, "{lo} {hi}");
}

/// A small deterministic PRNG (xorshift) + Box-Muller, so this test needs no crate.
fn normals(n: usize, mut s: u64) -> Vec<f64> {
    let mut u = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| (-2.0 * u().max(1e-300).ln()).sqrt() * (std::f64::consts::TAU * u()).cos())
        .collect()
}

#[test]
fn whiteness_separates_white_from_correlated() {
    let w = normals(2000, 7);
    let mk = |v: &[f64]| -> Vec<EstimateRow> {
        v.iter()
            .enumerate()
            .map(|(k, x)| EstimateRow {
                t: k as f64,
                innov: [Some(*x), None, None],
                innov_sd: [Some(1.0), None, None],
                ..Default::default()
            })
            .collect()
    };
    let white = innovation_stats(&mk(&w), 0.0, 10)[0].clone().unwrap();
    assert!(white.white_fraction >= 0.8, "{white:?}");
    assert!((white.nis_mean - 1.0).abs() < 0.1);
    // AR(1) with coefficient 0.8: ρ(1) ≈ 0.8.
    let mut ar = vec![0.0; w.len()];
    for k in 1..w.len() {
        ar[k] = 0.8 * ar[k - 1] + w[k];
    }
    let col = innovation_stats(&mk(&ar), 0.0, 10)[0].clone().unwrap();
    assert!((col.autocorr[0] - 0.8).abs() < 0.05, "{:?}", col.autocorr);
    assert!(col.white_fraction < 0.2);
    assert!(innovation_stats(&mk(&w), 0.0, 10)[1].is_none());
}

#[test]
fn consistency_of_true_chi2_samples_is_inside_bounds() {
    // 50 runs × 400 epochs of χ²(1) samples: the run-average is inside the 95 % bounds ~95 % of epochs.
    let series: Vec<Vec<Option<f64>>> =
        (0..50).map(|r| normals(400, 100 + r).into_iter().map(|x| Some(x * x)).collect()).collect();
    let c = consistency(&series, 1).unwrap();
    assert!(c.inside > 0.9 && c.inside < 0.99, "{c:?}");
    assert!((c.mean - 1.0).abs() < 0.05);
    // Scaled by 2 (variance under-estimated by half): mostly above.
    let bad: Vec<Vec<Option<f64>>> =
        series.iter().map(|s| s.iter().map(|v| v.map(|x| 2.0 * x)).collect()).collect();
    assert!(consistency(&bad, 1).unwrap().above > 0.9);
}
