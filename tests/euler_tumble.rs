//! The Euler-state filter (`Config::euler()`) through an aerobatic sequence with exact
//! truth: loops, rolls, inverted flight and vertical lines through ±90° pitch, where its
//! state is singular. It may be inaccurate there (it is, by design), but every output must
//! stay finite, P symmetric positive definite, the gyro bias bounded, and the filter must
//! be back on the truth after the figures. (On real F3A flights it once collapsed P to 0,
//! ran the bias to 10⁵ rad/s and returned NaN: docs/real-logs.md, CHANGELOG session 15.)
//! Also the repair mechanisms themselves, on the filter core.

mod common;
use common::*;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use wing_ahrs::ekf::{Ekf, VarianceCaps};
use wing_ahrs::{Ahrs, Config, Flags};

/// Body rates (rad/s) of the sequence at `t` s: straight and level, then figures, then
/// straight and level again from `t = 150` s.
fn rates(t: f64) -> [f64; 3] {
    let loop_q = 2.0 * std::f64::consts::PI / 6.0; // a loop in 6 s
    let roll_p = 2.0 * std::f64::consts::PI / 3.0; // a roll in 3 s
    let quarter = 0.5 * std::f64::consts::PI / loop_q; // a quarter loop, s
    match t {
        t if t < 40.0 => [0.0; 3],
        // Two inside loops.
        t if t < 52.0 => [0.0, loop_q, 0.0],
        t if t < 56.0 => [0.0; 3],
        // Two rolls.
        t if t < 62.0 => [roll_p, 0.0, 0.0],
        t if t < 66.0 => [0.0; 3],
        // Half roll to inverted, 4 s inverted, half roll back.
        t if t < 67.5 => [roll_p, 0.0, 0.0],
        t if t < 71.5 => [0.0; 3],
        t if t < 73.0 => [roll_p, 0.0, 0.0],
        t if t < 76.0 => [0.0; 3],
        // Vertical line: pull to 90°, 3 s up with a roll on it, push over the top into an
        // outside quarter loop, 3 s down, pull out.
        t if t < 76.0 + quarter => [0.0, loop_q, 0.0],
        t if t < 79.0 + quarter => [roll_p, 0.0, 0.0],
        t if t < 79.0 + 3.0 * quarter => [0.0, loop_q, 0.0],
        t if t < 82.0 + 3.0 * quarter => [0.0; 3],
        t if t < 82.0 + 4.0 * quarter => [0.0, loop_q, 0.0],
        t if t < 86.0 + 4.0 * quarter => [0.0; 3],
        // A loop with a roll at its top (pitch and roll rates together, closing), then a
        // second vertical line, down.
        t if t < 86.0 + 6.0 * quarter => [0.0, loop_q, 0.0],
        t if t < 89.0 + 6.0 * quarter => [roll_p, 0.0, 0.0],
        t if t < 92.0 + 4.0 * quarter => [0.0, loop_q, 0.0],
        t if t < 96.0 + 4.0 * quarter => [0.0; 3],
        t if t < 96.0 + 7.0 * quarter => [0.0, loop_q, 0.0],
        t if t < 99.0 + 7.0 * quarter => [0.0; 3],
        t if t < 99.0 + 8.0 * quarter => [0.0, loop_q, 0.0],
        t if t < 104.0 + 8.0 * quarter => [0.0; 3],
        // Three more loops and a slow roll: a second round through the singularity.
        t if t < 122.0 + 8.0 * quarter => [0.0, loop_q, 0.0],
        t if t < 128.0 + 8.0 * quarter => [0.5 * roll_p, 0.0, 0.0],
        _ => [0.0; 3],
    }
}

/// C_NB (body → NED) advanced by body rates `w` over `dt` (exact for constant rates:
/// Rodrigues), re-orthonormalised.
fn advance(c: &mut [[f64; 3]; 3], w: [f64; 3], dt: f64) {
    let th = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt() * dt;
    if th == 0.0 {
        return;
    }
    let k = [w[0] * dt / th, w[1] * dt / th, w[2] * dt / th];
    let (s, co) = th.sin_cos();
    let kx = [[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]];
    let mut r = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let kk: f64 = (0..3).map(|m| kx[i][m] * kx[m][j]).sum();
            r[i][j] = if i == j { 1.0 } else { 0.0 } + s * kx[i][j] + (1.0 - co) * kk;
        }
    }
    let mut n = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            n[i][j] = (0..3).map(|m| c[i][m] * r[m][j]).sum();
        }
    }
    *c = n;
}

/// Roll, pitch, yaw of C_NB (3-2-1).
fn euler(c: &[[f64; 3]; 3]) -> [f64; 3] {
    [c[2][1].atan2(c[2][2]), (-c[2][0]).clamp(-1.0, 1.0).asin(), c[1][0].atan2(c[0][0])]
}

/// Angle of the rotation between two attitudes given as (roll, pitch, yaw), rad: defined at
/// every attitude, unlike the Euler angles' differences.
fn angle_between(a: [f64; 3], b: [f64; 3]) -> f64 {
    let ra = r_bn(a[0], a[1], a[2]);
    let rb = r_bn(b[0], b[1], b[2]);
    let tr: f64 = (0..3).map(|i| (0..3).map(|k| ra[i][k] * rb[i][k]).sum::<f64>()).sum();
    ((tr - 1.0) / 2.0).clamp(-1.0, 1.0).acos()
}

/// Tilt: the angle between the true and the estimated down axis, rad.
fn tilt_between(a: [f64; 3], b: [f64; 3]) -> f64 {
    let ra = r_bn(a[0], a[1], a[2]);
    let rb = r_bn(b[0], b[1], b[2]);
    let d: f64 = (0..3).map(|i| ra[i][2] * rb[i][2]).sum();
    d.clamp(-1.0, 1.0).acos()
}

#[test]
fn the_euler_filter_stays_finite_positive_definite_and_bounded_through_aerobatics_and_recovers() {
    const IMU_HZ: f64 = 50.0; // as the F3A logs
    const GPS_EVERY: u64 = 10; // 5 Hz fixes, reporting their speed accuracy
    const V: f64 = 25.0;
    const END: f64 = 220.0;
    let bias = [1.0 * DEG, -0.8 * DEG, 0.6 * DEG];
    let speed_acc = 0.05f32;
    let mut rng = StdRng::seed_from_u64(15);
    let mut gauss = move || -> f64 {
        // Box–Muller.
        let u: f64 = rng.gen_range(1e-12..1.0);
        let v: f64 = rng.gen_range(0.0..1.0);
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
    };
    let cfg = Config::euler();
    let bias_limit = (10.0 * cfg.init_sigma_bias) as f64;
    let mut ahrs = Ahrs::try_new(cfg).expect("a valid configuration");
    let yaw0: f64 = 30.0 * DEG;
    let (s, c) = yaw0.sin_cos();
    let mut cnb = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]];
    let dt = 1.0 / IMU_HZ;
    let mut worst_tilt_end = 0.0f64;
    let mut worst_total_end = 0.0f64;
    let mut repairs_in_figures = 0;
    let mut gimbal = 0;
    for k in 0..(END * IMU_HZ) as u64 {
        let t = k as f64 * dt;
        let w = rates(t);
        // Truth at t: specific force f_B = ω × v_B − C_BN g_N with v_B = [V, 0, 0] (no
        // α, β, constant speed), so the NED acceleration is C_NB (ω × v_B).
        let wxv = [0.0, w[2] * V, -w[1] * V];
        let g_b = [G * cnb[2][0], G * cnb[2][1], G * cnb[2][2]];
        let f = [wxv[0] - g_b[0], wxv[1] - g_b[1], wxv[2] - g_b[2]];
        let gyro = [
            (w[0] + bias[0] + 0.02 * DEG * gauss()) as f32,
            (w[1] + bias[1] + 0.02 * DEG * gauss()) as f32,
            (w[2] + bias[2] + 0.02 * DEG * gauss()) as f32,
        ];
        let accel = [
            (f[0] + 0.02 * gauss()) as f32,
            (f[1] + 0.02 * gauss()) as f32,
            (f[2] + 0.02 * gauss()) as f32,
        ];
        let t_us = (k * 20_000) + 1_000_000;
        assert!(ahrs.on_imu(t_us, gyro, accel));
        if k % GPS_EVERY == 0 {
            let v_n: [f32; 3] =
                core::array::from_fn(|i| (cnb[i][0] * V + speed_acc as f64 * gauss()) as f32);
            let mut fix = fix_at(t_us, v_n);
            fix.speed_acc = Some(speed_acc);
            ahrs.on_gps(&fix);
        }
        let truth = euler(&cnb);
        let x = ahrs.state();
        let p = ahrs.covariance();
        assert!(x.iter().all(|v| v.is_finite()), "t = {t:.2}: state {x:?}");
        assert!(p.iter().flatten().all(|v| v.is_finite()), "t = {t:.2}: P {p:?}");
        assert!(is_symmetric(&p), "t = {t:.2}: P not symmetric");
        assert!(is_pd(&p), "t = {t:.2}: P not positive definite: {p:?}");
        for (i, &v) in p.iter().enumerate().map(|(i, r)| (i, &r[i])) {
            assert!(v >= 1e-12, "t = {t:.2}: variance {i} collapsed to {v}");
        }
        for b in &x[3..6] {
            assert!((*b as f64).abs() <= bias_limit, "t = {t:.2}: bias {:?}", &x[3..6]);
        }
        if ahrs.flags().has(Flags::NEAR_GIMBAL_LOCK) {
            gimbal += 1;
        }
        if (40.0..150.0).contains(&t) {
            repairs_in_figures = ahrs.health().covariance_repairs;
        }
        // Back on the truth within 40 s of straight flight after the last figure.
        if t > 190.0 {
            let est = [x[0] as f64, x[1] as f64, x[2] as f64];
            worst_tilt_end = worst_tilt_end.max(tilt_between(truth, est));
            worst_total_end = worst_total_end.max(angle_between(truth, est));
        }
        advance(&mut cnb, w, dt);
    }
    let h = ahrs.health();
    println!(
        "gimbal steps {gimbal}, repairs {} (in the figures {repairs_in_figures}), gate resets {:?}, \
         tilt after {:.3}°, total after {:.3}°, bias {:?}",
        h.covariance_repairs,
        h.gate_resets,
        worst_tilt_end / DEG,
        worst_total_end / DEG,
        ahrs.gyro_bias()
    );
    // The sequence did go through the singularity.
    assert!(gimbal > 50, "only {gimbal} samples near ±90° pitch");
    assert!(ahrs.flags().has(Flags::ALIGNED));
    assert!(worst_tilt_end < 1.0 * DEG, "tilt after the figures {}°", worst_tilt_end / DEG);
    assert!(worst_total_end < 3.0 * DEG, "attitude after the figures {}°", worst_total_end / DEG);
    for (b, e) in ahrs.gyro_bias().iter().zip(bias) {
        assert!((*b as f64 - e).abs() < 0.3 * DEG, "bias {:?} vs {bias:?}", ahrs.gyro_bias());
    }
}

fn caps() -> VarianceCaps {
    VarianceCaps { attitude: 1.0, bias: 1e-2 }
}

#[test]
fn an_indefinite_covariance_is_repaired_to_positive_definite_and_counted() {
    let mut ekf = Ekf::new([0.1, 0.2, 0.3, 0.0, 0.0, 0.0], [1e-3, 1e-3, 1e-3, 1e-6, 1e-6, 1e-6]);
    // Roll–yaw "correlation" 3: what the sequential updates left on the F3A logs.
    let mut p = *ekf.covariance();
    p[0][2] = 3e-3;
    p[2][0] = 3e-3;
    p[1][4] = -2e-5;
    p[4][1] = -2e-5;
    ekf.set_covariance(p);
    assert!(!is_pd(ekf.covariance()));
    let repairs = ekf.repairs();
    let l = ekf.ensure_positive_definite();
    assert!(is_pd(ekf.covariance()) && is_symmetric(ekf.covariance()));
    assert_eq!(ekf.repairs(), repairs.wrapping_add(1));
    // The variances are kept, the factor is P's.
    for i in 0..6 {
        assert_eq!(ekf.covariance()[i][i], p[i][i]);
        for j in 0..6 {
            let llt: f32 = (0..6).map(|k| l[i][k] * l[j][k]).sum();
            assert!((llt - ekf.covariance()[i][j]).abs() <= 1e-6 * p[i][i].max(p[j][j]));
        }
    }
    // A positive definite P is left exactly as it is.
    let before = *ekf.covariance();
    ekf.ensure_positive_definite();
    assert_eq!(*ekf.covariance(), before);
    assert_eq!(ekf.repairs(), repairs.wrapping_add(1));
}

#[test]
fn a_diverged_bias_re_seeds_the_filter_and_is_counted() {
    let limit = 0.35;
    for bad in [0.5, -3.0e5, f32::NAN, f32::INFINITY] {
        let mut ekf = Ekf::new([0.1, -0.2, 0.3, 0.01, bad, 0.0], [1e-4; 6]);
        let (repairs, resets) = (ekf.repairs(), ekf.resets());
        assert!(ekf.check_state(caps(), limit));
        assert_eq!(ekf.resets(), resets + 1);
        assert_eq!(ekf.repairs(), repairs + 1);
        let x = ekf.state();
        assert_eq!(&x[..3], &[0.1, -0.2, 0.3], "the finite attitude is kept");
        assert_eq!(&x[3..], &[0.0; 3], "the bias restarts at 0");
        assert!(is_pd(ekf.covariance()));
        assert_eq!(ekf.covariance()[4][4], caps().bias);
    }
    let mut ekf = Ekf::new([0.1, -0.2, 0.3, 0.01, -0.3, 0.0], [1e-4; 6]);
    assert!(!ekf.check_state(caps(), limit), "a bias within the limit is an estimate");
    assert_eq!(ekf.resets(), 0);
}

#[test]
fn the_over_the_top_reflection_carries_the_covariance_with_it() {
    let x = [0.3, 1.5, -0.4, 0.001, 0.002, 0.003];
    let mut p = [[0.0f32; 6]; 6];
    for i in 0..6 {
        p[i][i] = if i < 3 { 1e-3 } else { 1e-6 };
    }
    // Pitch correlated with roll and with the pitch-rate bias.
    p[0][1] = 4e-4;
    p[1][0] = 4e-4;
    p[1][4] = -2e-5;
    p[4][1] = -2e-5;
    let mut ekf = Ekf::new(x, [0.0; 6]);
    ekf.set_covariance(p);
    let flips = ekf.flips();
    // Pitch 0.2 rad over the top: θ' = π − θ, the pitch error changes sign.
    let mut over = ekf;
    over.update_axis(1, 1.5 + 0.2, 1e-4, f32::INFINITY);
    let q = *over.covariance();
    over.normalize_angles();
    assert_eq!(over.flips(), flips + 1);
    let x2 = over.state();
    assert!(x2[1] < 0.5 * std::f32::consts::PI, "pitch {} reflected", x2[1]);
    let r = over.covariance();
    for i in 0..6 {
        for j in 0..6 {
            let sign = if (i == 1) != (j == 1) { -1.0 } else { 1.0 };
            assert_eq!(r[i][j], sign * q[i][j], "P[{i}][{j}]");
        }
    }
    assert!(is_pd(r));
}
