//! GPS position and barometric altitude in the flight-log CSV (docs/formats.md `lat`, `lon`,
//! `alt`, `baro_alt`): the simulator's forward model against its own truth, and a real
//! imported log's positions against its velocities.
use sim_harness::log::FlightLog;
use sim_harness::sim::{self, geodetic, SensorSpec};
use sim_harness::{data, import};

/// (epoch, NED position about the first fix, velocity) of every fix with a position.
fn fixes(log: &FlightLog) -> Vec<(f64, [f64; 3], [f64; 3])> {
    let mut origin = None;
    log.rows
        .iter()
        .filter_map(|r| r.gps)
        .filter_map(|g| {
            let lla = g.lla?;
            let o = *origin.get_or_insert(lla);
            Some((g.t, geodetic::ned_of(o, lla), g.vel))
        })
        .collect()
}

/// Differenced positions minus the trapezoid of the two fixes' velocities, m/s, per axis.
fn velocity_residuals(f: &[(f64, [f64; 3], [f64; 3])], max_gap: f64) -> Vec<[f64; 3]> {
    f.windows(2)
        .filter(|w| w[1].0 - w[0].0 <= max_gap)
        .map(|w| {
            let dt = w[1].0 - w[0].0;
            core::array::from_fn(|i| (w[1].1[i] - w[0].1[i]) / dt - 0.5 * (w[0].2[i] + w[1].2[i]))
        })
        .collect()
}

fn rms(v: impl Iterator<Item = f64>) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for x in v {
        s += x * x;
        n += 1;
    }
    (s / n.max(1) as f64).sqrt()
}

/// Thesis sensors (exact positions, 0.01 m/s velocity noise at 10 Hz): every fix's position,
/// taken back to NED about the simulator's origin, is the true position at its epoch, and the
/// positions differenced between fixes are the fixes' velocity.
#[test]
fn simulated_positions_are_the_truth_and_difference_to_the_velocity() {
    for name in ["flight1", "aerobatics"] {
        let sc = sim::load_scenario(name).unwrap().with_spec(SensorSpec::Thesis);
        let out = sim::run(&sc, 5).unwrap();
        let mut worst = 0.0_f64;
        for r in &out.log.rows {
            let Some(g) = r.gps else { continue };
            let x = out.truth.iter().find(|x| (x.t - g.t).abs() < 1e-9).expect("epoch row");
            let ned = geodetic::ned_of(geodetic::ORIGIN, g.lla.expect("position"));
            for i in 0..3 {
                worst = worst.max((ned[i] - x.position_ned[i]).abs());
            }
        }
        let res = velocity_residuals(&fixes(&out.log), 0.11);
        let axis = |i: usize| rms(res.iter().map(|r| r[i]));
        println!(
            "{name}: position vs truth max {worst:.2e} m; Δpos/Δt − v̄ RMS N/E/D {:.4}/{:.4}/{:.4} m/s over {} intervals",
            axis(0),
            axis(1),
            axis(2),
            res.len()
        );
        assert!(worst < 1e-6, "{name}: NED → WGS-84 → NED off by {worst} m");
        assert!(res.len() >= 999);
        // Velocity noise 0.01 m/s per fix: the mean of two is 0.007 m/s; the trapezoid adds
        // a little in the aerobatic figures (jerk over 0.1 s).
        for i in 0..3 {
            assert!(axis(i) < 0.02, "{name}: axis {i} RMS {}", axis(i));
        }
    }
}

/// Realistic sensors: the position error (fix minus truth) is the documented Gauss–Markov
/// process (σ 1.0 m N/E, 1.5 m D, τ 60 s, one step per 0.2 s epoch): its one-step
/// innovations e₊ − φe have σ√(1 − φ²). The barometer reads the true height plus its drift
/// and noise (0.1 m white at 20 Hz).
#[test]
fn realistic_position_error_and_baro_follow_their_models() {
    // 400 s: 2,000 fixes, so the σ estimates are good to ~2 %.
    let sc = sim::load_scenario("flight1+spec=realistic,dur=400").unwrap();
    let p = sc.sensors.clone();
    let out = sim::run(&sc, 9).unwrap();
    let mut err: Vec<[f64; 3]> = Vec::new();
    let mut baro: Vec<f64> = Vec::new();
    for (r, x) in out.log.rows.iter().zip(&out.truth) {
        if let Some(g) = r.gps {
            let t = out.truth.iter().find(|y| (y.t - g.t).abs() < 1e-9).unwrap();
            let ned = geodetic::ned_of(geodetic::ORIGIN, g.lla.unwrap());
            err.push(core::array::from_fn(|i| ned[i] - t.position_ned[i]));
        }
        if let Some(b) = r.baro_alt {
            baro.push(b - geodetic::lla_of(x.position_ned)[2]);
        }
    }
    let phi = (-1.0 / (p.gps.rate_hz * p.gps.pos_error_tau_s)).exp();
    let k = (1.0 - phi * phi).sqrt();
    let step = |i: usize| rms(err.windows(2).map(|w| w[1][i] - phi * w[0][i]));
    let (sn, se, sd) = (step(0), step(1), step(2));
    println!(
        "GPS position error innovations σ N/E/D {sn:.4}/{se:.4}/{sd:.4} m (model {:.4}/{:.4}); RMS error N {:.2} m",
        p.gps.pos_error_ne_m * k,
        p.gps.pos_error_d_m * k,
        rms(err.iter().map(|e| e[0]))
    );
    assert!(err.len() >= 2000);
    for (s, sigma) in
        [(sn, p.gps.pos_error_ne_m), (se, p.gps.pos_error_ne_m), (sd, p.gps.pos_error_d_m)]
    {
        assert!((s / (sigma * k) - 1.0).abs() < 0.1, "{s} vs {}", sigma * k);
    }
    // Baro: sample-to-sample differences are the white noise (drift moves 0.004 m per step).
    let d = rms(baro.windows(2).map(|w| w[1] - w[0])) / 2f64.sqrt();
    let bias = baro.iter().sum::<f64>() / baro.len() as f64;
    println!(
        "baro: {} samples, white σ {d:.3} m (model {}), mean offset {bias:.2} m",
        baro.len(),
        p.baro.noise_m
    );
    assert_eq!(baro.len() as f64, (sc.duration * p.baro.rate_hz).round() + 1.0);
    assert!((d / p.baro.noise_m - 1.0).abs() < 0.1, "{d}");
    assert!(bias.abs() < 4.0 * p.baro.drift_sigma_m);
}

/// A real PX4 ULog (shared data): every fix carries a finite position, and the positions
/// differenced between fixes match the fixes' own velocities (a receiver's position and
/// velocity are independent solutions: Doppler vs pseudorange). The log is 6.5 s on the
/// ground, so the residual is the position's fix-to-fix jitter (~0.1 m per 0.2 s fix), and
/// the end-to-end displacement matches the integrated velocity to the receiver's position
/// accuracy (measured: 1.9 / 1.0 / 3.3 m N/E/D over 6.2 s, a receiver still converging on
/// the ground; bound 5 m).
#[test]
fn imported_ulog_positions_follow_its_velocities() {
    const T: &str = "imported_ulog_positions_follow_its_velocities";
    let Some(ulg) = data::data_file("real/raw/sample_log_small.ulg") else {
        data::skip(T, "real/raw/sample_log_small.ulg not found (set WING_AHRS_DATA)");
        return;
    };
    let (log, sum) = import::import(&ulg).unwrap();
    assert_eq!(sum.gps_positions, sum.gps_fixes);
    assert!(sum.baro > 0, "vehicle_air_data baro");
    let f = fixes(&log);
    assert_eq!(f.len(), sum.gps_fixes);
    assert!(f.iter().all(|x| x.1.iter().chain(&x.2).all(|v| v.is_finite())));
    let res = velocity_residuals(&f, 0.5);
    let speed = rms(f.iter().map(|x| x.2[0].hypot(x.2[1])));
    let axis = |i: usize| rms(res.iter().map(|r| r[i]));
    println!(
        "sample_log_small: {} fixes, RMS ground speed {speed:.2} m/s; Δpos/Δt − v̄ RMS N/E/D {:.3}/{:.3}/{:.3} m/s",
        f.len(),
        axis(0),
        axis(1),
        axis(2)
    );
    assert!(res.len() >= 20);
    let (a, b) = (f[0], f[f.len() - 1]);
    let integral: [f64; 3] = core::array::from_fn(|i| {
        f.windows(2).map(|w| 0.5 * (w[0].2[i] + w[1].2[i]) * (w[1].0 - w[0].0)).sum()
    });
    let drift: [f64; 3] = core::array::from_fn(|i| b.1[i] - a.1[i] - integral[i]);
    println!("  over {:.1} s: displacement − ∫v = {drift:.2?} m", b.0 - a.0);
    for i in 0..3 {
        assert!(axis(i) < 1.0, "axis {i}: {}", axis(i));
        assert!(drift[i].abs() < 5.0, "axis {i}: {drift:?}");
    }
}
