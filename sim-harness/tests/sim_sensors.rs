//! Sensor models reproduce their specification (thesis Table 5.1, eqs 4.1–4.16)
//! within sampling tolerance, measured against the simulator's truth.
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use sim_harness::sim::sensors::{GpsModel, GpsParams, ImuModel, SensorParams};
use sim_harness::sim::wind::Dryden;
use sim_harness::sim::{self, rotation as rot, SensorSpec, SimOutput};

fn std_mean(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    ((v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt(), m)
}

fn fly(name: &str, spec: SensorSpec, seed: u64) -> SimOutput {
    sim::run(&sim::load_scenario(name).unwrap().with_spec(spec), seed).unwrap()
}

#[test]
fn thesis_spec_noise_matches_table_5_1() {
    let o = fly("flight1", SensorSpec::Thesis, 21);
    let p = SensorParams::thesis();
    let rows = &o.log.rows;
    for i in 0..3 {
        let g: Vec<f64> = rows
            .iter()
            .zip(&o.truth)
            .map(|(r, x)| r.gyro[i] - x.body_rates[i] - r.truth_bias.unwrap()[i])
            .collect();
        let a: Vec<f64> =
            rows.iter().zip(&o.truth).map(|(r, x)| r.accel[i] - x.specific_force[i]).collect();
        let (gs, gm) = std_mean(&g);
        let (as_, am) = std_mean(&a);
        println!(
            "axis {i}: gyro noise {:.4}°/s (spec {}), accel noise {:.4} m/s² (spec {})",
            gs.to_degrees(),
            p.imu.gyro_noise_deg_s,
            as_,
            p.imu.accel_noise_m_s2
        );
        // 10 001 samples: the σ estimate is good to ~0.7 % (1σ); 4 % is > 5σ.
        assert!((gs.to_degrees() / p.imu.gyro_noise_deg_s - 1.0).abs() < 0.04);
        assert!((as_ / p.imu.accel_noise_m_s2 - 1.0).abs() < 0.04);
        assert!(
            gm.abs() < 5.0 * gs / (g.len() as f64).sqrt()
                && am.abs() < 5.0 * as_ / (a.len() as f64).sqrt()
        );
    }
    // GPS: thesis fixes have zero latency, so the epoch is on the row grid.
    let mut e = vec![];
    for r in rows.iter().filter(|r| r.gps.is_some()) {
        let g = r.gps.unwrap();
        assert!((g.t - r.t).abs() < 1e-9, "thesis spec has no latency");
        let k = (g.t * 100.0).round() as usize;
        for i in 0..3 {
            e.push(g.vel[i] - o.truth[k].velocity_ned[i]);
        }
    }
    assert_eq!(e.len() / 3, 1001, "10 Hz over 100 s, epochs 0..=100 s");
    let (gs, _) = std_mean(&e);
    println!("gps velocity noise {gs:.4} m/s (spec 0.01)");
    assert!((gs / 0.01 - 1.0).abs() < 0.08);
    let va: Vec<f64> =
        rows.iter().zip(&o.truth).filter_map(|(r, x)| r.airspeed.map(|m| m - x.airspeed)).collect();
    assert_eq!(va.len(), rows.len(), "airspeed at the IMU rate");
    let (s, _) = std_mean(&va);
    println!("airspeed noise {s:.4} m/s (spec 0.06)");
    assert!((s / 0.06 - 1.0).abs() < 0.04);
}

#[test]
fn turn_on_bias_and_gauss_markov_drift_have_their_sigma_and_tau() {
    let mut p = SensorParams::thesis().imu;
    let d2r = std::f64::consts::PI / 180.0;
    // Turn-on bias: 1-σ 1.5 °/s per axis over 2000 turn-ons (6000 draws, σ good to 0.9 %).
    let mut b0 = vec![];
    for seed in 0..2000 {
        let m = ImuModel::new(&p, &mut ChaCha8Rng::seed_from_u64(seed));
        b0.extend(m.gyro_turn_on);
    }
    let (s, _) = std_mean(&b0);
    println!("turn-on bias σ {:.3}°/s (spec 1.5)", s / d2r);
    assert!((s / d2r / 1.5 - 1.0).abs() < 0.05);
    // Gauss–Markov: stationary σ 211 °/h and correlation e^{-1} after τ = 382 s.
    p.gyro_turn_on_bias_deg_s = 0.0;
    p.gyro_noise_deg_s = 0.0;
    p.rate_hz = 10.0;
    let (mut start, mut end) = (vec![], vec![]);
    for seed in 0..400 {
        let mut rng = ChaCha8Rng::seed_from_u64(10_000 + seed);
        let mut m = ImuModel::new(&p, &mut rng);
        start.extend(m.gyro_bias());
        for _ in 0..3820 {
            m.sample([0.0; 3], [0.0; 3], &mut rng);
        }
        end.extend(m.gyro_bias());
    }
    let (s0, _) = std_mean(&start);
    let (s1, _) = std_mean(&end);
    let corr =
        start.iter().zip(&end).map(|(a, b)| a * b).sum::<f64>() / (start.len() as f64 * s0 * s1);
    println!(
        "GM drift σ {:.1} → {:.1} °/h (spec 211), corr after τ {corr:.3} (e⁻¹ = 0.368)",
        s0 / d2r * 3600.0,
        s1 / d2r * 3600.0
    );
    assert!(
        (s0 / d2r * 3600.0 / 211.0 - 1.0).abs() < 0.08
            && (s1 / d2r * 3600.0 / 211.0 - 1.0).abs() < 0.08
    );
    assert!((corr - (-1f64).exp()).abs() < 0.12);
}

#[test]
fn realistic_spec_applies_misalignment_scale_bias_and_quantization() {
    let o = fly("flight1", SensorSpec::Realistic, 8);
    let p = SensorParams::realistic();
    let lsb = p.imu.gyro_lsb_deg_s.to_radians();
    let m = &o.imu;
    // Every sample is on the quantization grid.
    for r in &o.log.rows {
        for i in 0..3 {
            assert!(((r.gyro[i] / lsb) - (r.gyro[i] / lsb).round()).abs() < 1e-6);
            let q = r.accel[i] / p.imu.accel_lsb_m_s2;
            assert!((q - q.round()).abs() < 1e-6);
        }
    }
    // gyro = M·ω + b + noise: the residual is white noise of the spec'd σ (plus LSB²/12).
    let mut res = vec![];
    for (r, x) in o.log.rows.iter().zip(&o.truth) {
        let pred = rot::add(rot::mul_mv(&m.gyro_matrix, x.body_rates), r.truth_bias.unwrap());
        res.extend((0..3).map(|i| r.gyro[i] - pred[i]));
    }
    let (s, _) = std_mean(&res);
    let expect = (p.imu.gyro_noise_deg_s.to_radians().powi(2) + lsb * lsb / 12.0).sqrt();
    println!(
        "realistic gyro residual after M·ω + b: {:.4}°/s (expected {:.4})",
        s.to_degrees(),
        expect.to_degrees()
    );
    assert!((s / expect - 1.0).abs() < 0.04);
    // And M is not the identity: misalignment and scale are in the data.
    let off: f64 = (0..3)
        .flat_map(|i| (0..3).map(move |j| (i, j)))
        .map(|(i, j)| (m.gyro_matrix[i][j] - if i == j { 1.0 } else { 0.0 }).abs())
        .sum();
    assert!(off > 1e-3, "realistic gyro matrix should differ from I");
    // Draw statistics over many turn-ons: package angles σ 0.3°, gyro scale σ 0.5 %.
    let (mut ang, mut sc) = (vec![], vec![]);
    for seed in 0..1500 {
        let m = ImuModel::new(&p.imu, &mut ChaCha8Rng::seed_from_u64(seed));
        ang.extend(m.package_angles);
        sc.extend((0..3).map(|i| m.gyro_matrix[i][i] - 1.0));
    }
    let (sa, _) = std_mean(&ang);
    let (ss, _) = std_mean(&sc);
    println!(
        "package misalignment σ {:.3}° (spec 0.3), gyro scale-factor σ {:.4} (spec 0.005)",
        sa.to_degrees(),
        ss
    );
    assert!((sa.to_degrees() / 0.3 - 1.0).abs() < 0.06 && (ss / 0.005 - 1.0).abs() < 0.06);
    // GPS latency 0.1 s and 5 Hz: each fix arrives 0.1 s after its epoch.
    let fixes: Vec<_> = o.log.rows.iter().filter_map(|r| r.gps.map(|g| (r.t, g.t))).collect();
    assert_eq!(fixes.len(), 500, "5 Hz epochs 0..99.8 s delivered within 100 s");
    for (t_row, t_epoch) in fixes {
        assert!((t_row - t_epoch - 0.1).abs() < 1e-6, "latency");
    }
}

#[test]
fn gps_smoothing_lags_a_ramp_by_tau() {
    let p = GpsParams {
        rate_hz: 10.0,
        vel_noise_ne_m_s: 0.0,
        vel_noise_d_m_s: 0.0,
        latency_s: 0.0,
        smoothing_tau_s: 0.3,
        pos_error_ne_m: 0.0,
        pos_error_d_m: 0.0,
        pos_error_tau_s: 60.0,
        sacc: Default::default(),
    };
    let mut g = GpsModel::new(&p, &[], ChaCha8Rng::seed_from_u64(1));
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let a = 2.0; // m/s², north
    let mut last = None;
    for k in 0..=10_000 {
        let t = k as f64 * 1e-3;
        g.on_step(t, [a * t, 0.0, 0.0], &mut rng);
        if let Some(f) = g.pop_available(t) {
            last = Some(f);
        }
    }
    let f = last.unwrap();
    let lag = (a * f.t - f.vel[0]) / a;
    println!("receiver smoothing: a ramp is delayed by {lag:.4} s (τ = 0.3 s)");
    assert!((lag / 0.3 - 1.0).abs() < 0.01);
}

#[test]
fn outage_scenario_has_no_fix_in_60_to_80_s() {
    let o = fly("flight1_outage", SensorSpec::Thesis, 2);
    let epochs: Vec<f64> = o.log.rows.iter().filter_map(|r| r.gps.map(|g| g.t)).collect();
    assert!(epochs.iter().all(|&t| !(60.0..80.0).contains(&t)));
    assert!(
        epochs.iter().any(|&t| (59.0..60.0).contains(&t))
            && epochs.iter().any(|&t| (80.0..81.0).contains(&t))
    );
    assert_eq!(epochs.len(), 1001 - 200);
    // Same flight and noise as flight1 otherwise.
    let f1 = fly("flight1", SensorSpec::Thesis, 2);
    assert_eq!(f1.log.rows[7000].truth, o.log.rows[7000].truth);
}

#[test]
fn dryden_gusts_have_the_specified_sigma() {
    let mut d = Dryden::new([1.06, 1.06, 0.7], [200.0, 200.0, 50.0], 25.0);
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let mut v: [Vec<f64>; 3] = Default::default();
    for k in 0..2_000_000 {
        d.step(0.005, &mut rng);
        if k % 10 == 0 {
            let g = d.gust();
            for i in 0..3 {
                v[i].push(g[i]);
            }
        }
    }
    for (i, s) in [1.06, 1.06, 0.7].iter().enumerate() {
        let (m, _) = std_mean(&v[i]);
        println!("Dryden σ axis {i}: {m:.3} m/s (spec {s})");
        // 10 000 s ≈ 1250 correlation lengths (L/Va = 8 s): σ good to a few %.
        assert!((m / s - 1.0).abs() < 0.08);
    }
}
