//! The process model (thesis eq 4.29–4.34, docs/design.md, process model): the analytic Jacobian F
//! against central finite differences of an independent f64 f, over a grid that
//! includes high bank and high pitch.

mod common;
use common::DEG;
use wing_ahrs::ekf::process::{derivative, jacobian};

/// Independent f64 implementation of f(x, ω) (docs/design.md, process model).
fn f64_f(x: [f64; 6], w: [f64; 3], inv_tau: f64) -> [f64; 6] {
    let (p, q, r) = (w[0] - x[3], w[1] - x[4], w[2] - x[5]);
    let (sf, cf) = x[0].sin_cos();
    let (st, ct) = x[1].sin_cos();
    [
        p + (q * sf + r * cf) * st / ct,
        q * cf - r * sf,
        (q * sf + r * cf) / ct,
        -x[3] * inv_tau,
        -x[4] * inv_tau,
        -x[5] * inv_tau,
    ]
}

fn grid() -> Vec<([f64; 6], [f64; 3])> {
    let mut v = Vec::new();
    for &roll in &[-170.0, -90.0, -60.0, 0.0, 30.0, 75.0, 120.0, 179.0] {
        for &pitch in &[-80.0, -45.0, 0.0, 10.0, 60.0, 84.0] {
            for &yaw in &[-150.0, 0.0, 95.0] {
                let x = [roll * DEG, pitch * DEG, yaw * DEG, 0.02, -0.03, 0.01];
                v.push((x, [0.7, -0.4, 1.1]));
                v.push((x, [-2.0, 1.5, -0.3]));
            }
        }
    }
    v
}

#[test]
fn jacobian_matches_central_differences() {
    let inv_tau = 1.0 / 382.0;
    let mut worst = 0.0f64;
    for (x, w) in grid() {
        let fa = jacobian(&x.map(|v| v as f32), w.map(|v| v as f32), inv_tau as f32, 0.0);
        for j in 0..6 {
            let h = 1e-6;
            let (mut xp, mut xm) = (x, x);
            xp[j] += h;
            xm[j] -= h;
            let (fp, fm) = (f64_f(xp, w, inv_tau), f64_f(xm, w, inv_tau));
            for i in 0..6 {
                let fd = (fp[i] - fm[i]) / (2.0 * h);
                let err = (fa[i][j] as f64 - fd).abs() / (1.0 + fd.abs());
                worst = worst.max(err);
                assert!(
                    err < 2e-5,
                    "F[{i}][{j}] = {} but finite difference {fd} at x={x:?} w={w:?}",
                    fa[i][j]
                );
            }
        }
    }
    println!("jacobian: worst relative error {worst:.2e} over {} points", grid().len());
}

#[test]
fn derivative_matches_independent_f() {
    for (x, w) in grid() {
        let fa = derivative(&x.map(|v| v as f32), w.map(|v| v as f32), 1.0 / 382.0, 0.0);
        let fr = f64_f(x, w, 1.0 / 382.0);
        for i in 0..6 {
            assert!(
                (fa[i] as f64 - fr[i]).abs() < 1e-4 * (1.0 + fr[i].abs()),
                "f[{i}] {} vs {}",
                fa[i],
                fr[i]
            );
        }
    }
}

#[test]
fn pitch_guard_keeps_kinematics_finite_at_90_degrees() {
    for &pitch in &[90.0f32, -90.0, 89.999, -89.999] {
        let x = [0.3, pitch * DEG as f32, 0.0, 0.0, 0.0, 0.0];
        let guard = (85.0f32 * DEG as f32).cos();
        let f = jacobian(&x, [1.0, 1.0, 1.0], 0.0, guard);
        let d = derivative(&x, [1.0, 1.0, 1.0], 0.0, guard);
        assert!(f.iter().flatten().all(|v| v.is_finite()) && d.iter().all(|v| v.is_finite()));
        // Unguarded it would blow up: the guard is what keeps it finite.
        let raw = derivative(&x, [1.0, 1.0, 1.0], 0.0, 0.0);
        assert!(raw[2].abs() > d[2].abs());
    }
}

/// The blockwise covariance propagation of `Ekf::predict` against the textbook dense
/// form in f64: `Φ = I + FΔt + (FΔt)²/2`, `P' = ΦPΦᵀ + G·Qc·Gᵀ·Δt`, `G = [[B, 0], [0, λI]]`.
#[test]
fn blockwise_predict_equals_dense_phi_p_phi_t_plus_qd() {
    use rand::{Rng, SeedableRng};
    use wing_ahrs::ekf::{Ekf, ProcessNoise, VarianceCaps};
    let mut rng = rand::rngs::StdRng::seed_from_u64(21);
    let noise = ProcessNoise {
        gyro_psd: 7.6e-9,
        bias_psd: 1.7e-11,
        lambda: 10.0,
        attitude_psd: 1e-8,
        inv_tau: 1.0 / 382.0,
    };
    let caps = VarianceCaps { attitude: 1.0, bias: 1.0 };
    let mut worst = 0.0f64;
    for _ in 0..2000 {
        let x: [f32; 6] = [
            rng.gen_range(-3.0..3.0),
            rng.gen_range(-1.3..1.3),
            rng.gen_range(-3.0..3.0),
            rng.gen_range(-0.05..0.05),
            rng.gen_range(-0.05..0.05),
            rng.gen_range(-0.05..0.05),
        ];
        let w: [f32; 3] =
            [rng.gen_range(-3.0..3.0), rng.gen_range(-3.0..3.0), rng.gen_range(-3.0..3.0)];
        let dt: f32 = rng.gen_range(0.002..0.05);
        // A random SPD P = L·Lᵀ with realistic scales.
        let scale = [1e-2, 1e-2, 3e-2, 1e-3, 1e-3, 1e-3];
        let mut l = [[0.0f64; 6]; 6];
        for i in 0..6 {
            for j in 0..=i {
                l[i][j] = rng.gen_range(-1.0..1.0) * scale[i] * if i == j { 2.0 } else { 0.5 };
            }
        }
        let mut p = [[0.0f32; 6]; 6];
        for i in 0..6 {
            for j in 0..6 {
                p[i][j] = (0..6).map(|k| l[i][k] * l[j][k]).sum::<f64>() as f32;
            }
        }
        for i in 0..6 {
            for j in 0..6 {
                p[i][j] = p[j][i]; // exact symmetry in f32
            }
        }
        let mut ekf = Ekf::new(x, [0.0; 6]);
        ekf.set_covariance(p);
        ekf.predict(dt, w, &noise, 0.0, caps);

        // Dense reference in f64 from the public Jacobian.
        let f = jacobian(&x, w, noise.inv_tau, 0.0);
        let d = dt as f64;
        let fd: Vec<Vec<f64>> =
            (0..6).map(|i| (0..6).map(|j| f[i][j] as f64 * d).collect()).collect();
        let mut phi = [[0.0f64; 6]; 6];
        for i in 0..6 {
            for j in 0..6 {
                let sq: f64 = (0..6).map(|k| fd[i][k] * fd[k][j]).sum();
                phi[i][j] = if i == j { 1.0 } else { 0.0 } + fd[i][j] + 0.5 * sq;
            }
        }
        let pf: Vec<Vec<f64>> = (0..6).map(|i| (0..6).map(|j| p[i][j] as f64).collect()).collect();
        let mut g = [[0.0f64; 6]; 6];
        for i in 0..3 {
            for j in 0..3 {
                g[i][j] = f[i][j + 3] as f64;
            }
            g[i + 3][i + 3] = noise.lambda as f64;
        }
        let qc = [
            noise.gyro_psd,
            noise.gyro_psd,
            noise.gyro_psd,
            noise.bias_psd,
            noise.bias_psd,
            noise.bias_psd,
        ]
        .map(|v| v as f64);
        let mut reference = [[0.0f64; 6]; 6];
        for i in 0..6 {
            for j in 0..6 {
                let mut v = 0.0;
                for a in 0..6 {
                    for b in 0..6 {
                        v += phi[i][a] * pf[a][b] * phi[j][b];
                    }
                }
                let q: f64 = (0..6).map(|k| g[i][k] * qc[k] * g[j][k]).sum::<f64>() * d
                    + if i == j && i < 3 { noise.attitude_psd as f64 * d } else { 0.0 };
                reference[i][j] = v + q;
            }
        }
        for i in 0..6 {
            for j in 0..6 {
                // f32 rounding, relative to the propagated variances (correlation-scaled).
                let tol = 1e-5 * (reference[i][i] * reference[j][j]).sqrt() + 1e-15;
                let err = (ekf.covariance()[i][j] as f64 - reference[i][j]).abs();
                worst = worst.max(err / tol);
                assert!(
                    err < tol,
                    "P'[{i}][{j}] = {} vs dense {} (x={x:?}, w={w:?}, dt={dt})",
                    ekf.covariance()[i][j],
                    reference[i][j]
                );
            }
        }
    }
    println!("blockwise vs dense predict: worst error {worst:.3} of tolerance");
}

/// The decimated predict carries sin/cos of roll and pitch from sample to sample (angle
/// addition with the step's increment) instead of recomputing them. Against the f64 model
/// at the state each step starts from: the Euler rates it returns agree through a tumble
/// that rolls through ±180° (wrap), pitches over the top (θ flip), and mixes small steps
/// with ones too large for the recurrence, with a measurement update every 10 steps — for
/// 20 s at 100 Hz.
#[test]
fn decimated_predict_rates_match_the_f64_model_through_wraps_and_flips() {
    use wing_ahrs::ekf::{Ekf, PendingCovariance, ProcessNoise, VarianceCaps};
    let noise = ProcessNoise {
        gyro_psd: 1e-7,
        bias_psd: 1e-10,
        lambda: 3.0,
        attitude_psd: 0.0,
        inv_tau: 0.0,
    };
    let caps = VarianceCaps { attitude: 1.0, bias: 1e-2 };
    let mut ekf = Ekf::new(
        [170.0 * DEG as f32, 20.0 * DEG as f32, 0.0, 0.01, -0.02, 0.005],
        [1e-4, 1e-4, 1e-4, 1e-6, 1e-6, 1e-6],
    );
    let mut pending = PendingCovariance::default();
    let (mut worst, mut flips, mut wraps, mut guarded_steps, mut updates) = (0.0f64, 0, 0, 0, 0);
    let wrap = |a: f32| {
        (a + std::f32::consts::PI).rem_euclid(2.0 * std::f32::consts::PI) - std::f32::consts::PI
    };
    for k in 0..2000 {
        let t = k as f64 * 0.01;
        // 8 s of rolling at 2 rad/s, then 12 s of looping at 1 rad/s (over the top every
        // π s); every fifth second a burst too large for the recurrence (0.06–0.08 rad/step).
        let burst = if (k / 100) % 5 == 4 { 6.0 } else { 0.0 };
        let gyro = if t < 8.0 {
            [(2.0 + burst) as f32, 0.2, 0.3]
        } else {
            [0.0, (1.0 + burst) as f32, 0.0]
        };
        let x0 = *ekf.state();
        let want = f64_f(x0.map(|v| v as f64), gyro.map(|v| v as f64), 0.0);
        let (rates, guarded) = ekf.predict_decimated(
            0.01,
            gyro,
            &noise,
            (85.0 * DEG as f32).cos(),
            caps,
            &mut pending,
            10,
        );
        let d_roll = ekf.state()[0] - x0[0];
        wraps += (d_roll.abs() > 3.0 && wrap(d_roll).abs() < 1.0) as u32;
        flips += (wrap(d_roll).abs() > 2.5) as u32;
        if guarded {
            // Within 5° of ±90° the filter guards cos θ (thesis eq 5.8) and the f64 model does
            // not: there the reference is the f32 model with fresh sincos (`euler_rates`).
            guarded_steps += 1;
            let (fresh, g) =
                wing_ahrs::ekf::process::euler_rates(&x0, gyro, (85.0 * DEG as f32).cos());
            assert!(g);
            for i in 0..3 {
                worst = worst.max(
                    (rates[i] as f64 - fresh[i] as f64).abs() / (fresh[i] as f64).abs().max(1.0),
                );
            }
            continue;
        }
        for i in 0..3 {
            let err = (rates[i] as f64 - want[i]).abs() / want[i].abs().max(1.0);
            worst = worst.max(err);
        }
        // A measurement update every 10 steps moves roll and pitch off the carried sin/cos:
        // by ~0.02 rad (rotated in on the next step) or, every 7th, by ~0.2 rad (recomputed).
        if k % 10 == 5 {
            let corr = if (k / 10) % 7 == 3 { 0.2 } else { 0.02 }
                * if (k / 10) % 2 == 0 { 1.0 } else { -1.0 };
            for axis in 0..2 {
                let z = ekf.state()[axis] + corr;
                assert!(ekf.update_axis(axis, z, 1e-6, f32::INFINITY).applied);
            }
            ekf.normalize_angles();
            updates += 1;
        }
    }
    println!("decimated predict vs f64 model: worst relative rate error {worst:.2e} ({wraps} roll wraps, {flips} pitch flips, {updates} updates, {guarded_steps} guarded steps against the f32 model)");
    assert!(
        wraps >= 3 && flips >= 2,
        "the tumble should wrap roll and flip pitch (wraps {wraps}, flips {flips})"
    );
    assert!(guarded_steps < 400, "most steps must be compared ({guarded_steps} guarded)");
    assert!(worst < 2e-5, "rates off by {worst:.2e}");
}

/// The staggered covariance propagation: with fixes every 10 samples (10 Hz GPS) P is
/// propagated half-way between them — every interval with N = 10, every second one with
/// N = 20 — and with fixes every 20 samples (5 Hz) half a block after each fix, never on an
/// update sample; with fixes every 2 or 25 samples (50 Hz, 4 Hz) the stagger must not
/// postpone it beyond the decimation factor.
#[test]
fn staggered_propagation_avoids_update_samples_and_is_never_postponed() {
    use wing_ahrs::ekf::{Ekf, PendingCovariance, ProcessNoise, VarianceCaps};
    let noise = ProcessNoise {
        gyro_psd: 1e-7,
        bias_psd: 1e-10,
        lambda: 3.0,
        attitude_psd: 0.0,
        inv_tau: 0.0,
    };
    let caps = VarianceCaps { attitude: 1.0, bias: 1e-2 };
    for every in [10u8, 20] {
        for fix_every in [10usize, 20, 7, 2, 25] {
            let mut ekf =
                Ekf::new([0.1, 0.05, 0.3, 0.0, 0.0, 0.0], [1e-4, 1e-4, 1e-4, 1e-6, 1e-6, 1e-6]);
            let mut pending = PendingCovariance::default();
            let (mut shared, mut propagations, mut max_pending, mut last) = (0, 0, 0, 0);
            let mut offsets = Vec::new();
            for k in 1..=1000 {
                let before = pending.samples();
                ekf.predict_decimated(
                    0.01,
                    [0.02, -0.01, 0.05],
                    &noise,
                    0.087,
                    caps,
                    &mut pending,
                    every,
                );
                let propagated = pending.samples() < before + 1;
                propagations += propagated as u32;
                max_pending = max_pending.max(pending.samples());
                if propagated && k > 3 * every as usize {
                    offsets.push(k - last);
                }
                if k % fix_every == 0 {
                    shared += (propagated && k > 3 * every as usize) as u32;
                    pending.stagger(every);
                    last = k;
                }
            }
            offsets.sort();
            offsets.dedup();
            println!("N = {every}, fixes every {fix_every} samples: {propagations} propagations, {shared} on update samples after start-up, ≤ {max_pending} pending, propagated {offsets:?} samples after a fix");
            assert!(max_pending < every as u32, "P left unpropagated for {max_pending} samples");
            assert!(
                propagations as usize >= 1000 / every as usize - 1,
                "{propagations} propagations in 1000 samples"
            );
            if fix_every == 10 || fix_every == 20 {
                assert_eq!(shared, 0, "propagation shared an interrupt with an update");
            }
            if fix_every == 10 {
                // Mid-way between fixes, once per ⌈N / interval⌉ intervals.
                assert_eq!(offsets, vec![5], "propagation not mid-interval");
                assert!(
                    propagations as usize <= 1000 / every as usize + 1,
                    "{propagations} propagations"
                );
            }
        }
    }
}
