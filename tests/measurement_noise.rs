//! The per-update measurement variances (`measure::noise`) against Monte Carlo: noisy
//! GPS velocities and accelerometer means are pushed through the real measurement
//! models (EKF1 roll/pitch, course), and the empirical variance of the measured angle
//! must match the first-order prediction. Truth comes from the forward model.

use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use wing_ahrs::config::Ekf1Form;
use wing_ahrs::measure::accel_roll_pitch::{forward, heading_frame_specific_force, measure};
use wing_ahrs::measure::heading::course;
use wing_ahrs::measure::noise::{
    course_variance, differenced_accel_variance, ekf1_roll_pitch_variance,
};

const DEG: f32 = core::f32::consts::PI / 180.0;

/// Box–Muller standard normal (f64 for the statistics, rounded to f32 at use).
fn gauss(rng: &mut StdRng) -> f64 {
    let u1: f64 = rng.gen_range(f64::MIN_POSITIVE..1.0);
    let u2: f64 = rng.gen();
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

fn wrap(a: f64) -> f64 {
    (a + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI) - std::f64::consts::PI
}

/// (roll, pitch, heading, NED acceleration) cases: level, coordinated turns, climbs,
/// an accelerating dive.
fn cases() -> Vec<(f32, f32, f32, [f32; 3])> {
    let g = 9.80665f32;
    let mut v = Vec::new();
    for &(roll_deg, pitch_deg) in
        &[(0.0f32, 0.0f32), (30.0, 2.0), (-45.0, 5.0), (60.0, -3.0), (10.0, 15.0), (-20.0, -12.0)]
    {
        let roll = roll_deg * DEG;
        let psi = 0.7f32;
        // Coordinated turn: horizontal centripetal acceleration g·tanφ to the right of the heading.
        let a_lat = g * libm::tanf(roll);
        let a_n = [-a_lat * libm::sinf(psi) + 0.5, a_lat * libm::cosf(psi) - 0.3, -0.4];
        v.push((roll, pitch_deg * DEG, psi, a_n));
    }
    v
}

#[test]
fn ekf1_roll_pitch_variance_matches_monte_carlo() {
    let mut rng = StdRng::seed_from_u64(7);
    // GPS-dominated (u-blox-like), then accelerometer-dominated (vibration).
    for (sigma_v, sigma_f) in [(0.05f32, 0.15f32), (0.002, 1.5)] {
        let dt = 0.1f32;
        let n_imu = 10.0f32;
        let sem = sigma_f / libm::sqrtf(n_imu);
        let r_var = differenced_accel_variance(2.0 * sigma_v * sigma_v, dt);
        for form in [Ekf1Form::RobustTwoAxis, Ekf1Form::RobustSingleAxis] {
            for (roll, pitch, psi, a_n) in cases() {
                let r_true = heading_frame_specific_force(a_n, psi);
                let accel_true = forward(r_true, roll, pitch);
                let (want_r, want_p) =
                    ekf1_roll_pitch_variance(form, accel_true, [sem; 3], r_true, pitch, r_var);
                let n = 20_000;
                let (mut s_r, mut s_p) = (0.0f64, 0.0f64);
                for _ in 0..n {
                    let dv: [f32; 3] = core::array::from_fn(|_| {
                        (std::f64::consts::SQRT_2 * gauss(&mut rng)) as f32 * sigma_v / dt
                    });
                    let a_meas = [a_n[0] + dv[0], a_n[1] + dv[1], a_n[2] + dv[2]];
                    let f: [f32; 3] =
                        core::array::from_fn(|k| accel_true[k] + sem * gauss(&mut rng) as f32);
                    let rp =
                        measure(form, f, heading_frame_specific_force(a_meas, psi), (roll, pitch));
                    s_r += wrap((rp.roll.unwrap() - roll) as f64).powi(2);
                    s_p += wrap((rp.pitch.unwrap() - pitch) as f64).powi(2);
                }
                let (got_r, got_p) = (s_r / n as f64, s_p / n as f64);
                // 20,000 samples: the variance estimate's own 1-σ is ~1 %; first-order
                // propagation is good to a few % at these noise levels.
                for (name, got, want) in
                    [("roll", got_r, want_r as f64), ("pitch", got_p, want_p as f64)]
                {
                    let ratio = got / want;
                    println!("{form:?} φ={:5.1}° θ={:5.1}° {name}: MC σ {:.3}° model σ {:.3}° ratio {ratio:.3}", roll / DEG, pitch / DEG, got.sqrt().to_degrees(), want.sqrt().to_degrees());
                    assert!((0.9..1.1).contains(&ratio), "{form:?} {name} at φ={roll}, θ={pitch}: MC variance {got:e} vs model {want:e}");
                }
            }
        }
    }
}

#[test]
fn course_variance_matches_monte_carlo() {
    let mut rng = StdRng::seed_from_u64(11);
    let sigma = 0.3f32;
    for &(vn, ve) in &[(20.0f32, 0.0f32), (-8.0, 9.0), (3.0, -4.0)] {
        let want = course_variance(sigma * sigma, [vn, ve, 0.0]) as f64;
        let chi = course(vn, ve) as f64;
        let n = 20_000;
        let s: f64 = (0..n)
            .map(|_| {
                let c = course(
                    vn + sigma * gauss(&mut rng) as f32,
                    ve + sigma * gauss(&mut rng) as f32,
                ) as f64;
                wrap(c - chi).powi(2)
            })
            .sum::<f64>()
            / n as f64;
        let ratio = s / want;
        println!(
            "course at ({vn}, {ve}) m/s: MC σ {:.3}° model σ {:.3}° ratio {ratio:.3}",
            s.sqrt().to_degrees(),
            want.sqrt().to_degrees()
        );
        assert!(
            (0.9..1.1).contains(&ratio),
            "course variance at ({vn}, {ve}): MC {s:e} vs model {want:e}"
        );
    }
}
