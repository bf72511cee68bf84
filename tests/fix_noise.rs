//! The fix-noise states (`ekf::fix_noise`) against independent truth:
//! - the sequential updates equal a dense Kalman filter on the explicitly augmented state
//!   (x, q, the fresh fix noises, the heading error), over two GPS epochs with a Φ between;
//! - the EKF1 noise sensitivities (`measure::noise::ekf1_roll_pitch_noise`) equal finite
//!   differences of the real measurement model, and the roll and pitch directions are
//!   orthogonal (what lets q carry one independent state per axis).

use wing_ahrs::config::Ekf1Form;
use wing_ahrs::ekf::fix_noise::{Coupling, FixNoise};
use wing_ahrs::ekf::Ekf;
use wing_ahrs::measure::accel_roll_pitch::{forward, heading_frame_specific_force, measure};
use wing_ahrs::measure::noise::ekf1_roll_pitch_noise;

type M = Vec<Vec<f64>>;

/// Dense Kalman scalar update: x += K ν, P −= P hᵀ h P / (h P hᵀ + r).
fn dense_update(x: &mut [f64], p: &mut M, h: &[f64], z: f64, r: f64) {
    let n = x.len();
    let ph: Vec<f64> = (0..n).map(|i| (0..n).map(|j| p[i][j] * h[j]).sum()).collect();
    let s: f64 = (0..n).map(|i| h[i] * ph[i]).sum::<f64>() + r;
    let nu = z - (0..n).map(|i| h[i] * x[i]).sum::<f64>();
    for i in 0..n {
        x[i] += ph[i] / s * nu;
        for j in 0..n {
            p[i][j] -= ph[i] * ph[j] / s;
        }
    }
}

/// A deterministic SPD 6×6 (A·Aᵀ + d·I from a fixed pseudo-random A).
fn spd6(seed: u32) -> [[f32; 6]; 6] {
    let mut v = seed;
    let mut rnd = || {
        v = v.wrapping_mul(1664525).wrapping_add(1013904223);
        (v >> 8) as f64 / (1u64 << 24) as f64 - 0.5
    };
    let a: Vec<Vec<f64>> = (0..6).map(|_| (0..6).map(|_| rnd() * 0.02).collect()).collect();
    let mut p = [[0.0f32; 6]; 6];
    for i in 0..6 {
        for j in 0..6 {
            p[i][j] = ((0..6).map(|k| a[i][k] * a[j][k]).sum::<f64>()
                + if i == j { 1e-5 } else { 0.0 }) as f32;
        }
    }
    p
}

#[test]
fn sequential_updates_equal_the_dense_augmented_filter() {
    // Dense state: x(0..6), q_φ(6), q_θ(7), then per epoch: n_φ, n_θ, e.
    let prev_var = 0.01f64.powi(2);
    let fresh = [0.012f64.powi(2), 0.009f64.powi(2)];
    let heading_var = 0.035f64.powi(2);
    let p0 = spd6(7);
    let mut ekf = Ekf::new([0.01, -0.02, 0.5, 0.001, -0.002, 0.0005], [0.0; 6]);
    ekf.set_covariance(p0);
    let mut fx = FixNoise::default();
    let n = 6 + 2 + 2 * 3;
    let mut x = vec![0.0f64; n];
    let mut p: M = vec![vec![0.0; n]; n];
    for i in 0..6 {
        x[i] = ekf.state()[i] as f64;
        for j in 0..6 {
            p[i][j] = p0[i][j] as f64;
        }
    }
    p[6][6] = prev_var;
    p[7][7] = prev_var;
    // Epoch-specific couplings: (h_φ, k_φ), (h_θ, k_θ), white r per axis, measurements.
    let epochs = [
        ([0.5f32, 0.45], [0.3f32, -0.6], [2e-6f32, 3e-6, 0.0], [0.02f32, -0.01, 0.49]),
        ([0.55, 0.4], [-0.2, 0.7], [1e-6, 4e-6, 0.0], [0.0, -0.03, 0.52]),
    ];
    let (a, b) = (
        [[0.01f32, 0.02, 0.0], [-0.03, 0.0, 0.0], [0.02, 0.01, 0.0]],
        [[-1.0f32, -0.1, -0.05], [0.0, -0.98, 0.2], [0.0, -0.2, -1.01]],
    );
    let dt = 0.1f32;
    let mut q_idx = [6usize, 7];
    for (ep, (h, k, r, z)) in epochs.iter().enumerate() {
        let base = 8 + 3 * ep;
        let (nr, np, e) = (base, base + 1, base + 2);
        if ep > 0 {
            // Φ = I + F·Δt on x (extra states static): P_dense ← Φ P Φᵀ, and the filter's P the same.
            let mut phi = vec![vec![0.0f64; n]; n];
            for i in 0..n {
                phi[i][i] = 1.0;
            }
            for i in 0..3 {
                for j in 0..3 {
                    phi[i][j] += (a[i][j] * dt) as f64;
                    phi[i][j + 3] += (b[i][j] * dt) as f64;
                }
            }
            let tmp: M = (0..n)
                .map(|i| (0..n).map(|j| (0..n).map(|l| phi[i][l] * p[l][j]).sum()).collect())
                .collect();
            p = (0..n)
                .map(|i| (0..n).map(|j| (0..n).map(|l| tmp[i][l] * phi[j][l]).sum()).collect())
                .collect();
            ekf.set_covariance(core::array::from_fn(|i| core::array::from_fn(|j| p[i][j] as f32)));
        }
        fx.begin(&a, &b, 0.0, dt, prev_var as f32, heading_var as f32);
        p[nr][nr] = fresh[0];
        p[np][np] = fresh[1];
        p[e][e] = heading_var;
        // Yaw first (as the filter does), then roll, pitch.
        let mut hy = vec![0.0; n];
        hy[2] = 1.0;
        hy[e] = 1.0;
        dense_update(&mut x, &mut p, &hy, z[2] as f64, r[2] as f64);
        fx.update_axis(
            &mut ekf,
            2,
            z[2],
            r[2],
            Coupling { k: 1.0, ..Coupling::default() },
            f32::INFINITY,
        );
        for ax in 0..2 {
            let fresh_idx = if ax == 0 { nr } else { np };
            let mut hv = vec![0.0; n];
            hv[ax] = 1.0;
            hv[q_idx[ax]] = -(h[ax] as f64);
            hv[fresh_idx] = h[ax] as f64;
            hv[e] = k[ax] as f64;
            dense_update(&mut x, &mut p, &hv, z[ax] as f64, r[ax] as f64);
            let c = Coupling { h: h[ax], fresh_var: fresh[ax] as f32, k: k[ax], white_var: 0.0 };
            assert!(fx.update_axis(&mut ekf, ax, z[ax], r[ax], c, f32::INFINITY).applied);
        }
        q_idx = [nr, np];
        for i in 0..6 {
            assert!(
                (ekf.state()[i] as f64 - x[i]).abs() < 1e-5,
                "epoch {ep}: x[{i}] {} vs dense {}",
                ekf.state()[i],
                x[i]
            );
            for j in 0..6 {
                let tol = 1e-4 * p[i][i].max(p[j][j]).max(1e-9);
                assert!(
                    (ekf.covariance()[i][j] as f64 - p[i][j]).abs() < tol,
                    "epoch {ep}: P[{i}][{j}] {} vs dense {}",
                    ekf.covariance()[i][j],
                    p[i][j]
                );
            }
        }
    }
}

/// Measured (roll, pitch) of the real model for heading-frame vector r.
fn rp(accel: [f32; 3], r: [f32; 3], pred: (f32, f32)) -> (f32, f32) {
    let m = measure(Ekf1Form::RobustTwoAxis, accel, r, pred);
    (m.roll.unwrap(), m.pitch.unwrap())
}

#[test]
fn noise_sensitivities_match_finite_differences_of_the_model() {
    let deg = core::f32::consts::PI / 180.0;
    let mut cosines = Vec::new();
    for &(roll, pitch, heading, a_ned) in &[
        (0.0f32, 0.05f32, 0.8f32, [0.0f32, 0.0, 0.0]),
        (30.0 * deg, 0.04, 1.2, [-3.9, 4.1, 0.0]),
        (-45.0 * deg, 0.08, -2.0, [8.0, 5.0, -0.5]),
        (10.0 * deg, 15.0 * deg, 0.3, [1.0, 0.5, -1.5]),
    ] {
        let r = heading_frame_specific_force(a_ned, heading);
        let accel = forward(r, roll, pitch);
        let (st, ct) = (pitch.sin(), pitch.cos());
        let n = ekf1_roll_pitch_noise(Ekf1Form::RobustTwoAxis, accel, [0.0; 3], r, (st, ct));
        let eps = 1e-2f32;
        // Gradients of the measured roll and pitch in r (central differences).
        let mut grad = [[0.0f32; 3]; 2];
        for c in 0..3 {
            let (mut rp_, mut rm) = (r, r);
            rp_[c] += eps;
            rm[c] -= eps;
            let (a1, b1) = rp(accel, rp_, (roll, pitch));
            let (a0, b0) = rp(accel, rm, (roll, pitch));
            grad[0][c] = (a1 - a0) / (2.0 * eps);
            grad[1][c] = (b1 - b0) / (2.0 * eps);
        }
        for ax in 0..2 {
            let g2: f32 = grad[ax].iter().map(|v| v * v).sum();
            assert!(
                (g2 - n.gain_sq[ax]).abs() < 0.02 * n.gain_sq[ax],
                "axis {ax}: |∇|² {g2} vs gain² {}",
                n.gain_sq[ax]
            );
            assert!(
                (n.gain(ax).abs() - g2.sqrt()).abs() < 0.01 * g2.sqrt(),
                "axis {ax}: gain {} vs |∇| {}",
                n.gain(ax),
                g2.sqrt()
            );
        }
        // Roll and pitch respond to orthogonal directions of the GPS acceleration error.
        let dot: f32 = (0..3).map(|c| grad[0][c] * grad[1][c]).sum();
        let cos = dot / (n.gain_sq[0] * n.gain_sq[1]).sqrt();
        println!(
            "roll {:.0}°, pitch {:.0}°, |a| {:.1} m/s²: roll/pitch gradient cosine {cos:.3}",
            roll / deg,
            pitch / deg,
            a_ned.iter().map(|v| v * v).sum::<f32>().sqrt()
        );
        cosines.push(cos);
        // Heading sensitivity: rotate the GPS acceleration by a slightly wrong heading.
        let dh = 1e-3f32;
        let (r1, r0) = (
            heading_frame_specific_force(a_ned, heading + dh),
            heading_frame_specific_force(a_ned, heading - dh),
        );
        let (p1, t1) = rp(accel, r1, (roll, pitch));
        let (p0, t0) = rp(accel, r0, (roll, pitch));
        let fd = [(p1 - p0) / (2.0 * dh), (t1 - t0) / (2.0 * dh)];
        for ax in 0..2 {
            assert!(
                (fd[ax] - n.heading_gain[ax]).abs() < 0.01 + 0.02 * fd[ax].abs(),
                "axis {ax}: ∂z/∂ψ {} vs heading gain {}",
                fd[ax],
                n.heading_gain[ax]
            );
        }
    }
    // Straight flight: exactly orthogonal (what lets q carry one independent state per
    // axis); in turns with a forward acceleration the neglected correlation stays small.
    assert!(cosines[0].abs() < 1e-3, "straight flight: cosine {}", cosines[0]);
    assert!(cosines.iter().all(|c| c.abs() < 0.3), "cosines {cosines:?}");
}
