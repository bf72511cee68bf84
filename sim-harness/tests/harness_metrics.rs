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

mod attitude_metrics {
    //! Tilt and total attitude error against independent constructions: a known
    //! axis-angle rotation composed with truth (in body or NED axes) gives exactly that
    //! angle, at random attitudes including ±90° pitch and inverted.
    use rand::{Rng, SeedableRng};
    use sim_harness::estimate::EstimateRow;
    use sim_harness::log::{FlightLog, LogRow};
    use sim_harness::metrics::*;
    use sim_harness::sim::rotation as rot;

    fn unit<R: Rng>(rng: &mut R) -> [f64; 3] {
        loop {
            let v = [rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0)];
            let n = rot::norm(v);
            if n > 0.1 && n <= 1.0 {
                return rot::scale(v, 1.0 / n);
            }
        }
    }

    /// Random attitudes, with the hard ones always included.
    fn attitudes() -> Vec<[f64; 3]> {
        let d = f64::to_radians;
        // Pitch 1 µrad from ±90°: at exactly ±90° 3-2-1 Euler angles cannot carry the
        // rotation (roll and yaw merge), so no Euler-based metric can be checked there.
        let v90 = std::f64::consts::FRAC_PI_2 - 1e-6;
        let mut v = vec![
            [0.0, v90, 0.3],
            [1.0, -v90, -2.0],
            [d(180.0), 0.0, 1.0],
            [d(-179.0), d(89.9), d(179.0)],
            [0.0; 3],
        ];
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(13);
        for _ in 0..500 {
            let q = rot::quat_from_rotvec(rot::scale(
                unit(&mut rng),
                rng.gen_range(0.0..std::f64::consts::PI),
            ));
            v.push(rot::euler_from_quat(q));
        }
        v
    }

    #[test]
    fn total_error_is_the_angle_of_a_composed_rotation() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let mut worst = 0.0f64;
        for t in attitudes() {
            let qt = rot::quat_from_euler(t[0], t[1], t[2]);
            for theta in [1e-6, 1e-3, 0.05, 0.5, 2.0, 3.0] {
                let dq = rot::quat_from_rotvec(rot::scale(unit(&mut rng), theta));
                // Body-axis perturbation (R_est = R_true·ΔR) and NED-axis (ΔR·R_true).
                for q in [rot::quat_mul(qt, dq), rot::quat_mul(dq, qt)] {
                    let est = rot::euler_from_quat(q);
                    worst = worst.max((attitude_error(est, t) - theta).abs() / theta.max(1e-3));
                    assert!(tilt_error(est, t) <= attitude_error(est, t) + 1e-9, "tilt ≤ total");
                }
            }
        }
        println!("total attitude error vs composed angle: worst relative error {worst:.1e}");
        assert!(worst < 1e-6);
    }

    #[test]
    fn tilt_is_the_angle_of_a_horizontal_ned_rotation_and_ignores_yaw() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(6);
        let (mut worst, mut worst_yaw) = (0.0f64, 0.0f64);
        for t in attitudes() {
            let qt = rot::quat_from_euler(t[0], t[1], t[2]);
            for theta in [1e-4, 0.01, 0.3, 1.5, 3.0] {
                // A rotation about a horizontal NED axis moves the down direction by θ.
                let a = rng.gen_range(0.0..std::f64::consts::TAU);
                let dq = rot::quat_from_rotvec([theta * a.cos(), theta * a.sin(), 0.0]);
                let est = rot::euler_from_quat(rot::quat_mul(dq, qt));
                worst = worst.max((tilt_error(est, t) - theta).abs());
                // A rotation about NED down (a pure heading error) leaves tilt at 0.
                let dz = rot::quat_from_rotvec([0.0, 0.0, theta]);
                let est = rot::euler_from_quat(rot::quat_mul(dz, qt));
                worst_yaw = worst_yaw.max(tilt_error(est, t));
                // Absolute: the Euler round trip at ±90° pitch keeps ~1e-8 rad (asin near 1).
                let err = (attitude_error(est, t) - theta).abs();
                assert!(err < 1e-7, "{t:?} θ {theta}: total {err:e} off");
            }
        }
        println!("tilt vs horizontal-axis angle: worst {worst:.1e} rad; tilt under heading error ≤ {worst_yaw:.1e} rad");
        assert!(worst < 1e-7 && worst_yaw < 1e-7);
    }

    #[test]
    fn comparison_carries_tilt_total_and_wind_after_the_first_full_turn() {
        // Truth: a steady 10°/s turn (full turn at t = 36 s), 5 m/s wind; estimate:
        // yaw off by 0.1 rad (tilt 0), wind off by (0.3, −0.4) → 0.5 m/s.
        let (mut log, mut est) = (FlightLog::default(), Vec::new());
        for k in 0..600 {
            let t = k as f64 * 0.1;
            let truth = [0.3, 0.1, wrap((10.0 * t).to_radians())];
            log.rows.push(LogRow {
                t,
                truth: Some(truth),
                truth_wind: Some([5.0, 0.0, 0.0]),
                ..Default::default()
            });
            est.push(EstimateRow {
                t,
                att: [0.3, 0.1, wrap(truth[2] + 0.1)],
                wind: (t > 5.0).then_some(([5.3, -0.4, 0.0], [0.1, 0.1])),
                ..Default::default()
            });
        }
        let c = compare(&log, &est, 10.0).unwrap();
        assert!(c.tilt.max_abs < 1e-12, "a heading error is no tilt");
        assert!((c.total.rms - 0.1).abs() < 1e-9, "{}", c.total.rms);
        let t_turn = first_full_turn(&log).unwrap();
        assert!((t_turn - 36.0).abs() < 0.11, "{t_turn}");
        let w = c.wind.unwrap();
        assert_eq!(w.t_from, t_turn);
        assert!((w.horizontal.rms - 0.5).abs() < 1e-9 && w.coverage == 1.0);
        assert!((w.ne[1].mean + 0.4).abs() < 1e-9);
        // A steady wind is its own 60 s mean.
        assert!((w.horizontal_vs_mean.rms - 0.5).abs() < 1e-9);
        // No wind columns: no wind error.
        est.iter_mut().for_each(|e| e.wind = None);
        assert!(compare(&log, &est, 10.0).unwrap().wind.is_none());
    }

    #[test]
    fn wind_against_its_mean_leaves_out_the_gusts() {
        // Truth: 5 m/s north plus a 2 m/s, 6 s gust wave; the estimate holds the steady
        // 5 m/s. Against the instantaneous truth it is off by the gusts' RMS (√2 m/s); against
        // the centred 60 s mean (ten periods) by next to nothing, except at the ends where the
        // window is cut short.
        let (mut log, mut est) = (FlightLog::default(), Vec::new());
        for k in 0..3000 {
            let t = k as f64 * 0.1;
            let gust = 2.0 * (std::f64::consts::TAU * t / 6.0).sin();
            let truth = [0.0, 0.0, wrap((10.0 * t).to_radians())];
            log.rows.push(LogRow {
                t,
                truth: Some(truth),
                truth_wind: Some([5.0 + gust, 0.0, 0.0]),
                ..Default::default()
            });
            est.push(EstimateRow {
                t,
                att: truth,
                wind: Some(([5.0, 0.0, 0.0], [0.1, 0.1])),
                ..Default::default()
            });
        }
        let w = compare(&log, &est, 40.0).unwrap().wind.unwrap();
        assert!((w.horizontal.rms - 2f64.sqrt()).abs() < 0.01, "{}", w.horizontal.rms);
        assert!(w.horizontal_vs_mean.rms < 0.05, "{}", w.horizontal_vs_mean.rms);
    }
}
