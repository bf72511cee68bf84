//! The quaternion filter against independent truth: its rotation algebra against f64
//! Euler matrices, its measurement Jacobians against finite differences of the forward
//! models, and the whole filter through a tumble over every attitude (inverted and
//! vertical included) against the integrated truth.

use rand::{Rng, SeedableRng};
use wing_ahrs::mekf::dv_window::WindowMean;
use wing_ahrs::mekf::{course, gps_accel, quat};
use wing_ahrs::{Ahrs, Config, Euler, FixType, GpsFix, QuatConfig, GRAVITY};

type M3 = [[f64; 3]; 3];

/// Body → NED of 3-2-1 Euler angles, f64 (written out independently of the core).
fn dcm(roll: f64, pitch: f64, yaw: f64) -> M3 {
    let (sf, cf) = roll.sin_cos();
    let (st, ct) = pitch.sin_cos();
    let (sp, cp) = yaw.sin_cos();
    [
        [ct * cp, sf * st * cp - cf * sp, cf * st * cp + sf * sp],
        [ct * sp, sf * st * sp + cf * cp, cf * st * sp - sf * cp],
        [-st, sf * ct, cf * ct],
    ]
}

fn mul(a: &M3, b: &M3) -> M3 {
    core::array::from_fn(|i| core::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

fn transpose(a: &M3) -> M3 {
    core::array::from_fn(|i| core::array::from_fn(|j| a[j][i]))
}

/// Rodrigues: exp([v×]), f64.
fn exp_so3(v: [f64; 3]) -> M3 {
    let a = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let k = if a < 1e-12 { [0.0; 3] } else { [v[0] / a, v[1] / a, v[2] / a] };
    let kx = [[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]];
    let kx2 = mul(&kx, &kx);
    core::array::from_fn(|i| {
        core::array::from_fn(|j| {
            (i == j) as u8 as f64 + a.sin() * kx[i][j] + (1.0 - a.cos()) * kx2[i][j]
        })
    })
}

/// Rotation angle between two rotations, rad (atan2 of the skew and trace parts:
/// accurate for small angles, where acos of the trace is not).
fn angle_between(a: &M3, b: &M3) -> f64 {
    let m = mul(a, &transpose(b));
    let v = [m[2][1] - m[1][2], m[0][2] - m[2][0], m[1][0] - m[0][1]];
    let s = 0.5 * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    s.atan2((m[0][0] + m[1][1] + m[2][2] - 1.0) / 2.0)
}

fn to_f64(r: &[[f32; 3]; 3]) -> M3 {
    core::array::from_fn(|i| core::array::from_fn(|j| r[i][j] as f64))
}

/// Uniform random attitudes with a share exactly at ±90° pitch and inverted.
fn random_attitudes(n: usize, seed: u64) -> Vec<(f64, f64, f64)> {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let pi = std::f64::consts::PI;
    (0..n)
        .map(|k| {
            let roll = rng.gen_range(-pi..pi);
            let yaw = rng.gen_range(-pi..pi);
            let pitch = match k % 10 {
                0 => pi / 2.0,
                1 => -pi / 2.0,
                2 => 0.0,
                _ => (rng.gen_range(-1.0f64..1.0)).asin(),
            };
            let roll = if k % 10 == 2 { pi } else { roll }; // inverted
            (roll, pitch, yaw)
        })
        .collect()
}

#[test]
fn quaternion_dcm_matches_the_euler_matrix_at_every_attitude() {
    for (roll, pitch, yaw) in random_attitudes(2000, 1) {
        let e = Euler { roll: roll as f32, pitch: pitch as f32, yaw: yaw as f32 };
        let q = quat::from_euler(&e);
        let n = q.iter().map(|v| v * v).sum::<f32>();
        assert!((n - 1.0).abs() < 1e-6, "norm {n}");
        let r = to_f64(&quat::to_dcm(&q));
        let err = angle_between(&r, &dcm(roll, pitch, yaw));
        assert!(err < 2e-6, "{roll} {pitch} {yaw}: {err}");
        // Back to Euler: the same rotation (angles themselves are not unique at ±90°).
        let b = quat::to_euler(&q);
        let rb = dcm(b.roll as f64, b.pitch as f64, b.yaw as f64);
        let tol = if pitch.abs() > 1.5 { 2e-3 } else { 2e-6 / pitch.cos() };
        assert!(angle_between(&rb, &r) < tol, "{roll} {pitch} {yaw}");
    }
}

#[test]
fn rotation_vector_and_product_match_rodrigues() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(2);
    for k in 0..2000 {
        // Both branches: the series below 0.1 rad and the exact form above.
        let scale = if k % 2 == 0 { 0.09 } else { 3.0 };
        let v: [f64; 3] = core::array::from_fn(|_| rng.gen_range(-1.0..1.0) * scale / 1.8);
        let q = quat::from_rotation_vector(v.map(|x| x as f32));
        let r = to_f64(&quat::to_dcm(&q));
        assert!(angle_between(&r, &exp_so3(v)) < 3e-6, "{v:?}");
        // q ⊗ p is R(q)·R(p).
        let (a, b, c) = random_attitudes(1, k)[0];
        let p = quat::from_euler(&Euler { roll: a as f32, pitch: b as f32, yaw: c as f32 });
        let rp = to_f64(&quat::to_dcm(&quat::mul(&q, &p)));
        assert!(angle_between(&rp, &mul(&exp_so3(v), &dcm(a, b, c))) < 5e-6);
    }
}

/// The GPS-acceleration residual of truth `r_true` as the filter would form it at `r_est`.
fn gps_accel_residual(r_est: &M3, r_true: &M3, f_body: [f64; 3]) -> [f64; 3] {
    let mv = |m: &M3, v: [f64; 3]| -> [f64; 3] {
        core::array::from_fn(|i| (0..3).map(|k| m[i][k] * v[k]).sum())
    };
    let z = mv(r_true, f_body); // ā − g, the truth's NED specific force
    let h = mv(r_est, f_body);
    [z[0] - h[0], z[1] - h[1], z[2] - h[2]]
}

#[test]
fn gps_accel_jacobian_matches_finite_differences() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(3);
    let cfg = QuatConfig::default();
    for (roll, pitch, yaw) in random_attitudes(500, 4) {
        let r_est = dcm(roll, pitch, yaw);
        let f_body: [f64; 3] = core::array::from_fn(|_| rng.gen_range(-20.0..20.0));
        let f_ned: [f64; 3] =
            core::array::from_fn(|i| (0..3).map(|k| r_est[i][k] * f_body[k]).sum());
        let w = WindowMean {
            f_ned: f_ned.map(|v| v as f32),
            f_body: f_body.map(|v| v as f32),
            sem_sq: [0.0; 3],
            noise_sq: [0.0; 3],
            duration: 0.1,
        };
        let d = wing_ahrs::measure::gps_delta::GpsDelta {
            accel_ned: [f_ned[0] as f32, f_ned[1] as f32, (f_ned[2] + GRAVITY as f64) as f32],
            dt: 0.1,
            mean_vel: [20.0, 0.0, 0.0],
            vel: [20.0, 0.0, 0.0],
            prev_vel: [20.0, 0.0, 0.0],
            vd_valid: true,
            latest_vd_valid: true,
            speed_acc: [Some(0.1); 2],
        };
        let m = gps_accel::measurement(
            &d,
            &w,
            &quat::to_dcm(&quat::from_euler(&Euler {
                roll: roll as f32,
                pitch: pitch as f32,
                yaw: yaw as f32,
            })),
            [0.01, 0.01],
            &cfg,
            0.0,
            0.0,
            [0.0; 3],
        );
        // At the truth the residual is zero (to f32 rounding of ~20 m/s² values).
        assert!(m.y.iter().all(|v| v.abs() < 1e-4), "{:?}", m.y);
        for axis in 0..3 {
            let eps = 1e-4;
            let mut dth = [0.0; 3];
            dth[axis] = eps;
            let yp = gps_accel_residual(&r_est, &mul(&exp_so3(dth), &r_est), f_body);
            dth[axis] = -eps;
            let ym = gps_accel_residual(&r_est, &mul(&exp_so3(dth), &r_est), f_body);
            for i in 0..3 {
                let fd = (yp[i] - ym[i]) / (2.0 * eps);
                let h = m.h[i][axis] as f64;
                assert!(
                    (fd - h).abs() < 1e-4 * (1.0 + fd.abs()),
                    "axis {axis} row {i}: {fd} vs {h}"
                );
            }
        }
    }
}

#[test]
fn heading_jacobian_matches_finite_differences() {
    for (roll, pitch, yaw) in random_attitudes(500, 5) {
        if pitch.abs() > 1.4 {
            continue; // the heading of a vertical body axis is undefined
        }
        let r = dcm(roll, pitch, yaw);
        let rf: [[f32; 3]; 3] = core::array::from_fn(|i| core::array::from_fn(|j| r[i][j] as f32));
        let (psi, h) = course::heading(&rf);
        let head = |m: &M3| m[1][0].atan2(m[0][0]);
        assert!(
            ((psi as f64 - head(&r) + 3.0 * std::f64::consts::PI) % std::f64::consts::TAU
                - std::f64::consts::PI)
                .abs()
                < 1e-5
        );
        for axis in 0..3 {
            let eps = 1e-5;
            let mut d = [0.0; 3];
            d[axis] = eps;
            let p = head(&mul(&exp_so3(d), &r));
            d[axis] = -eps;
            let m = head(&mul(&exp_so3(d), &r));
            let fd = (p - m) / (2.0 * eps);
            assert!(
                (fd - h[axis] as f64).abs() < 1e-3 * (1.0 + fd.abs()),
                "{roll} {pitch} {yaw} axis {axis}: {fd} vs {}",
                h[axis]
            );
        }
    }
}

/// Body rates of a tumble that visits every attitude: sums of sinusoids up to 3 rad/s.
fn tumble_rates(t: f64) -> [f64; 3] {
    if t < 5.0 {
        return [0.0; 3];
    }
    [
        2.0 * (0.7 * t).sin() + 1.0 * (2.3 * t).sin(),
        1.5 * (0.5 * t + 1.0).sin() + 0.8 * (1.7 * t).cos(),
        1.0 * (0.3 * t).cos() + 0.5 * (3.1 * t).sin(),
    ]
}

#[test]
fn a_tumble_through_every_attitude_keeps_the_filter_on_truth_with_p_positive_definite() {
    let mut ahrs = Ahrs::try_new(Config::default()).expect("a valid configuration");
    let dt = 0.01;
    let mut r = dcm(0.0, 0.0, 0.0);
    let mut rng = rand::rngs::StdRng::seed_from_u64(6);
    let bias = [0.01, -0.02, 0.015];
    let (mut worst_tilt, mut worst_total, mut min_pitch, mut max_pitch, mut inverted) =
        (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0usize);
    // Flown like an aircraft: the velocity along the body x-axis at 20 m/s (α = β = 0),
    // so the acceleration is V·R·(ω × e₁) and the course is the heading when upright.
    let speed = 20.0f64;
    for k in 0..12_000 {
        let t = k as f64 * dt;
        // Truth: R ← R·exp([ω dt×]).
        let w = tumble_rates(t);
        r = mul(&r, &exp_so3([w[0] * dt, w[1] * dt, w[2] * dt]));
        let g = 9.80665;
        let v = [speed * r[0][0], speed * r[1][0], speed * r[2][0]];
        // f = V·(ω × e₁) − Rᵀg, body.
        let f = [-r[2][0] * g, speed * w[2] - r[2][1] * g, -speed * w[1] - r[2][2] * g];
        let noise = |rng: &mut rand::rngs::StdRng, s: f64| rng.gen_range(-s..s);
        let gyro: [f32; 3] =
            core::array::from_fn(|i| (w[i] + bias[i] + noise(&mut rng, 1e-3)) as f32);
        let accel: [f32; 3] = core::array::from_fn(|i| (f[i] + noise(&mut rng, 0.02)) as f32);
        let t_us = (k as u64 + 1) * 10_000;
        assert!(ahrs.on_imu(t_us, gyro, accel));
        if k % 10 == 9 {
            let vel: [f32; 3] = core::array::from_fn(|i| (v[i] + noise(&mut rng, 0.01)) as f32);
            ahrs.on_gps(&GpsFix {
                t_us,
                fix_type: FixType::Fix3D,
                fix_ok: true,
                vel_ne: [vel[0], vel[1]],
                vel_d: Some(vel[2]),
                speed_acc: Some(0.01),
                num_sats: 12,
                ..GpsFix::default()
            });
        }
        let p = ahrs.error_covariance().expect("quaternion filter");
        assert!(p.iter().flatten().all(|v| v.is_finite()));
        for i in 0..6 {
            assert!(p[i][i] > 0.0);
            for j in 0..6 {
                assert!((p[i][j] - p[j][i]).abs() <= 1e-6 * (p[i][i] * p[j][j]).sqrt());
                assert!(p[i][j] * p[i][j] <= p[i][i] * p[j][j] * 1.0001);
            }
        }
        let e = ahrs.attitude();
        let re = dcm(e.roll as f64, e.pitch as f64, e.yaw as f64);
        let pitch = (-r[2][0]).asin();
        min_pitch = min_pitch.min(pitch);
        max_pitch = max_pitch.max(pitch);
        inverted += (r[2][2] < -0.9) as usize;
        if std::env::var("TUMBLE_TRACE").is_ok() && k % 50 == 0 {
            let tilt = (0..3).map(|i| re[2][i] * r[2][i]).sum::<f64>().clamp(-1.0, 1.0).acos();
            eprintln!(
                "{t:.1} pitch {:.1} inv {} tilt {:.2} total {:.2} {:?} resets {:?} gated {:?}",
                pitch * 57.3,
                r[2][2] < 0.0,
                tilt * 57.3,
                angle_between(&re, &r) * 57.3,
                ahrs.flags(),
                ahrs.health().gate_resets,
                ahrs.health().gate_rejections
            );
        }
        if t > 10.0 {
            // Tilt: the angle between estimated and true body-down in NED.
            let dot = (0..3).map(|i| re[2][i] * r[2][i]).sum::<f64>().clamp(-1.0, 1.0);
            worst_tilt = worst_tilt.max(dot.acos());
            worst_total = worst_total.max(angle_between(&re, &r));
        }
    }
    let deg = 180.0 / std::f64::consts::PI;
    println!(
        "tumble: pitch {:.0}..{:.0}°, {} samples inverted, worst tilt {:.3}°, worst total {:.3}°",
        min_pitch * deg,
        max_pitch * deg,
        inverted,
        worst_tilt * deg,
        worst_total * deg
    );
    assert!(max_pitch * deg > 85.0 && min_pitch * deg < -85.0, "the tumble must pass ±90°");
    assert!(inverted > 500, "the tumble must fly inverted");
    assert!(worst_tilt * deg < 1.0, "tilt error {:.3}°", worst_tilt * deg);
    assert!(worst_total * deg < 2.0, "total error {:.3}°", worst_total * deg);
}
