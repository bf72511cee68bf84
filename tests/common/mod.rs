//! Independent truth for the core tests: f64 kinematics, written from docs/design.md, conventions
//! without using the core's own rotation or model code.
#![allow(dead_code)]

pub mod heading;

use std::path::PathBuf;

use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

pub const G: f64 = 9.80665;
pub const DEG: f64 = std::f64::consts::PI / 180.0;

/// R_BN = Rx(φ)·Ry(θ)·Rz(ψ), f64.
pub fn r_bn(roll: f64, pitch: f64, yaw: f64) -> [[f64; 3]; 3] {
    let (sf, cf) = roll.sin_cos();
    let (st, ct) = pitch.sin_cos();
    let (sp, cp) = yaw.sin_cos();
    [
        [ct * cp, ct * sp, -st],
        [sf * st * cp - cf * sp, sf * st * sp + cf * cp, sf * ct],
        [cf * st * cp + sf * sp, cf * st * sp - sf * cp, cf * ct],
    ]
}

pub fn mat_vec(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    core::array::from_fn(|i| m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2])
}

pub fn mat_t_vec(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    core::array::from_fn(|i| m[0][i] * v[0] + m[1][i] * v[1] + m[2][i] * v[2])
}

/// Specific force f_B = R_BN (a_N − g_N).
pub fn specific_force(att: [f64; 3], a_ned: [f64; 3]) -> [f64; 3] {
    mat_vec(&r_bn(att[0], att[1], att[2]), [a_ned[0], a_ned[1], a_ned[2] - G])
}

pub fn wrap(a: f64) -> f64 {
    let mut w =
        (a + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI) - std::f64::consts::PI;
    if w <= -std::f64::consts::PI {
        w += 2.0 * std::f64::consts::PI;
    }
    w
}

/// Smooth 0→1 step over [0, 1] (C¹) and its derivative.
fn smoothstep(u: f64) -> (f64, f64) {
    let u = u.clamp(0.0, 1.0);
    (u * u * (3.0 - 2.0 * u), 6.0 * u * (1.0 - u))
}

/// A piecewise-smooth schedule: value(t) moving between waypoints (t_start, duration, target).
fn schedule(t: f64, start: f64, moves: &[(f64, f64, f64)]) -> (f64, f64) {
    let mut v = start;
    let mut vdot = 0.0;
    for &(t0, dur, target) in moves {
        if t >= t0 {
            let (s, ds) = smoothstep((t - t0) / dur);
            let from = v;
            v = from + (target - from) * s;
            vdot = if t < t0 + dur { (target - from) * ds / dur } else { 0.0 };
        }
    }
    (v, vdot)
}

/// One sample of the synthetic flight.
#[derive(Debug, Clone, Copy)]
pub struct Sample {
    pub t: f64,
    pub att: [f64; 3],
    pub rates: [f64; 3],
    pub vel: [f64; 3],
    pub accel_ned: [f64; 3],
    pub f_body: [f64; 3],
    pub airspeed: f64,
}

/// A coordinated-turn flight (β = 0, α = 0, no wind): bank φ(t) and flight-path
/// angle γ(t) follow smooth schedules, ψ̇ = g·tanφ/V, θ = γ. Truth is exact:
/// rates from the Euler-rate relation, acceleration from the analytic derivative
/// of v_N, specific force from the forward model.
pub struct Flight {
    pub speed: f64,
    pub roll_moves: Vec<(f64, f64, f64)>,
    pub gamma_moves: Vec<(f64, f64, f64)>,
    pub yaw0: f64,
}

impl Flight {
    /// Level entry, 30° right turn, reversal to −30°, a climb and a descent.
    pub fn coordinated_turns() -> Self {
        Flight {
            speed: 20.0,
            roll_moves: vec![
                (5.0, 2.0, 30.0 * DEG),
                (25.0, 2.0, -30.0 * DEG),
                (45.0, 2.0, 0.0),
                (60.0, 2.0, 45.0 * DEG),
                (75.0, 2.0, 0.0),
            ],
            gamma_moves: vec![(10.0, 3.0, 8.0 * DEG), (30.0, 3.0, -6.0 * DEG), (50.0, 3.0, 0.0)],
            yaw0: 20.0 * DEG,
        }
    }

    /// Samples at `rate` Hz for `duration` s (yaw integrated with 1 ms RK4 sub-steps).
    pub fn generate(&self, duration: f64, rate: f64) -> Vec<Sample> {
        let v = self.speed;
        let yaw_rate = |t: f64| {
            let (phi, _) = schedule(t, 0.0, &self.roll_moves);
            let (gam, _) = schedule(t, 0.0, &self.gamma_moves);
            G * phi.tan() / (v * gam.cos())
        };
        let n = (duration * rate).round() as usize;
        let dt_out = 1.0 / rate;
        let sub = 10;
        let h = dt_out / sub as f64;
        let mut yaw = self.yaw0;
        let mut out = Vec::with_capacity(n);
        for k in 0..n {
            let t = k as f64 * dt_out;
            if k > 0 {
                let mut tt = t - dt_out;
                for _ in 0..sub {
                    let k1 = yaw_rate(tt);
                    let k2 = yaw_rate(tt + h / 2.0);
                    let k4 = yaw_rate(tt + h);
                    yaw += h / 6.0 * (k1 + 4.0 * k2 + k4);
                    tt += h;
                }
            }
            let (phi, phidot) = schedule(t, 0.0, &self.roll_moves);
            let (gam, gamdot) = schedule(t, 0.0, &self.gamma_moves);
            let psidot = yaw_rate(t);
            let theta = gam;
            let thetadot = gamdot;
            let (sf, cf) = phi.sin_cos();
            let (st, ct) = theta.sin_cos();
            let rates = [
                phidot - psidot * st,
                thetadot * cf + psidot * sf * ct,
                -thetadot * sf + psidot * cf * ct,
            ];
            let (sg, cg) = gam.sin_cos();
            let (sp, cp) = yaw.sin_cos();
            let vel = [v * cg * cp, v * cg * sp, -v * sg];
            let accel_ned = [
                v * (-sg * gamdot * cp - cg * sp * psidot),
                v * (-sg * gamdot * sp + cg * cp * psidot),
                -v * cg * gamdot,
            ];
            let att = [phi, theta, wrap(yaw)];
            out.push(Sample {
                t,
                att,
                rates,
                vel,
                accel_ned,
                f_body: specific_force(att, accel_ned),
                airspeed: v,
            });
        }
        out
    }
}

/// Sensor errors for the synthetic flight (thesis Table 5.1 magnitudes).
pub struct Sensors {
    pub gyro_bias: [f64; 3],
    pub gyro_noise: f64,
    pub accel_noise: f64,
    pub gps_vel_noise: f64,
    pub airspeed_noise: f64,
    pub rng: StdRng,
}

impl Sensors {
    pub fn thesis(seed: u64) -> Self {
        Sensors {
            gyro_bias: [1.5 * DEG, -1.5 * DEG, 1.5 * DEG],
            gyro_noise: 0.05 * DEG,
            accel_noise: 0.02,
            gps_vel_noise: 0.01,
            airspeed_noise: 0.06,
            rng: StdRng::seed_from_u64(seed),
        }
    }

    pub fn gauss(&mut self) -> f64 {
        gauss(&mut self.rng)
    }

    pub fn gyro(&mut self, s: &Sample) -> [f32; 3] {
        core::array::from_fn(|i| {
            (s.rates[i] + self.gyro_bias[i] + self.gyro_noise * self.gauss()) as f32
        })
    }

    pub fn accel(&mut self, s: &Sample) -> [f32; 3] {
        core::array::from_fn(|i| (s.f_body[i] + self.accel_noise * self.gauss()) as f32)
    }

    pub fn gps_vel(&mut self, s: &Sample) -> [f32; 3] {
        core::array::from_fn(|i| (s.vel[i] + self.gps_vel_noise * self.gauss()) as f32)
    }

    pub fn airspeed(&mut self, s: &Sample) -> f32 {
        (s.airspeed + self.airspeed_noise * self.gauss()) as f32
    }
}

/// A 3-D fix at `t_us` with the measured NED velocity `vel` (vD included).
pub fn fix_at(t_us: u64, vel: [f32; 3]) -> wing_ahrs::GpsFix {
    wing_ahrs::GpsFix {
        t_us,
        fix_type: wing_ahrs::FixType::Fix3D,
        fix_ok: true,
        vel_ne: [vel[0], vel[1]],
        vel_d: Some(vel[2]),
        num_sats: 12,
        ..Default::default()
    }
}

/// Whether a symmetric 6×6 matrix is positive definite (Cholesky in f64).
pub fn is_pd(p: &[[f32; 6]; 6]) -> bool {
    let mut l = [[0.0f64; 6]; 6];
    for i in 0..6 {
        for j in 0..=i {
            let mut s = p[i][j] as f64;
            for k in 0..j {
                s -= l[i][k] * l[j][k];
            }
            if i == j {
                if !(s > 0.0) {
                    return false;
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    true
}

pub fn is_symmetric(p: &[[f32; 6]; 6]) -> bool {
    (0..6).all(|i| (0..6).all(|j| p[i][j] == p[j][i]))
}

/// The shared third-party data: `$WING_AHRS_DATA`, else `<crate>/../shared/data`, if present.
pub fn data_dir() -> Option<PathBuf> {
    let dir = std::env::var_os("WING_AHRS_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data"));
    dir.is_dir().then_some(dir)
}

/// Reports that `test` skips because `why` (data or a tool missing), or panics with that
/// reason when `WING_AHRS_REQUIRE_DATA` is set (as `cargo xtask test` does). The harness
/// has the same rule in `sim_harness::data::skip`; the core's tests cannot depend on it.
pub fn skip(test: &str, why: &str) {
    let required = std::env::var_os("WING_AHRS_REQUIRE_DATA").is_some();
    assert!(!required, "{test}: {why} (WING_AHRS_REQUIRE_DATA is set)");
    eprintln!("SKIP {test}: {why}");
}

/// A standard normal draw. Box-Muller: keeps the tests free of extra distribution crates.
pub fn gauss(rng: &mut StdRng) -> f64 {
    let u1: f64 = rng.gen_range(1e-12..1.0);
    let u2: f64 = rng.gen();
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}
