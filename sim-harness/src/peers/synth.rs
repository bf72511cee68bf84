//! Small kinematic flight logs with exact truth, for checking adapters: a static (or
//! unaccelerated) tilt, and level coordinated turns. Built from the forward model of
//! docs/design.md, conventions, `f_B = R_BN (a_N − g_N)`, not from the 6-DoF simulator, so a test of an
//! adapter does not depend on the simulator.

use super::{dcm_gps::r_nb, G};
use crate::log::{FlightLog, GpsSample, LogRow};
use rand::{rngs::StdRng, SeedableRng};
use rand_distr::{Distribution, Normal};

/// Sensor error model (defaults: thesis Table 5.1, 100 Hz IMU, 10 Hz GPS).
#[derive(Debug, Clone, Copy)]
pub struct Sensors {
    /// IMU rate, Hz.
    pub imu_hz: f64,
    /// GPS rate, Hz (must divide the IMU rate).
    pub gps_hz: f64,
    /// Accelerometer white noise, m/s² per sample.
    pub accel_noise: f64,
    /// Gyro white noise, rad/s per sample.
    pub gyro_noise: f64,
    /// Constant gyro bias, rad/s.
    pub gyro_bias: [f64; 3],
    /// GPS velocity noise, m/s.
    pub gps_vel_noise: f64,
}

impl Sensors {
    /// Noise-free, bias-free sensors at 100 Hz / 10 Hz.
    pub fn perfect() -> Self {
        Sensors {
            imu_hz: 100.0,
            gps_hz: 10.0,
            accel_noise: 0.0,
            gyro_noise: 0.0,
            gyro_bias: [0.0; 3],
            gps_vel_noise: 0.0,
        }
    }
    /// Thesis Table 5.1 sensors with a fixed turn-on bias of 1.5 °/s magnitude class.
    pub fn thesis() -> Self {
        let d = std::f64::consts::PI / 180.0;
        Sensors {
            accel_noise: 0.02,
            gyro_noise: 0.05 * d,
            gyro_bias: [1.5 * d, -d, 0.8 * d],
            gps_vel_noise: 0.01,
            ..Self::perfect()
        }
    }
}

/// Specific force (FRD) of a body at attitude (roll, pitch, yaw) with NED acceleration `a_n`.
pub fn specific_force(att: [f64; 3], a_n: [f64; 3]) -> [f64; 3] {
    let r = r_nb(att[0], att[1], att[2]);
    let v = [a_n[0], a_n[1], a_n[2] - G];
    // R_BN = R_NBᵀ
    core::array::from_fn(|j| r[0][j] * v[0] + r[1][j] * v[1] + r[2][j] * v[2])
}

struct Noise {
    rng: StdRng,
    n: Normal<f64>,
}
impl Noise {
    fn new(seed: u64) -> Self {
        Noise { rng: StdRng::seed_from_u64(seed), n: Normal::new(0.0, 1.0).expect("unit normal") }
    }
    fn v3(&mut self, s: f64) -> [f64; 3] {
        core::array::from_fn(|_| s * self.n.sample(&mut self.rng))
    }
}

/// Constant attitude for `seconds`, zero rates. With `speed` = 0 the body is at rest
/// (GPS velocity zero); otherwise it moves unaccelerated along its own x axis at
/// `speed` m/s, so the GPS course equals the yaw and there is no sideslip or α.
pub fn static_tilt(att: [f64; 3], speed: f64, seconds: f64, s: Sensors, seed: u64) -> FlightLog {
    let r = r_nb(att[0], att[1], att[2]);
    let vel = [speed * r[0][0], speed * r[1][0], speed * r[2][0]];
    let f = specific_force(att, [0.0; 3]);
    build(seconds, s, seed, |_| (att, [0.0; 3], f, vel))
}

/// Level coordinated turns at airspeed = ground speed `speed` (no wind), starting at
/// yaw `yaw0`: each segment holds bank `bank_deg` for `secs` seconds, banks change at
/// 30 °/s. Yaw rate g·tanφ/V, body rates p = φ̇, q = ψ̇ sφ, r = ψ̇ cφ (θ = 0).
pub fn coordinated_turns(
    speed: f64,
    yaw0: f64,
    segments: &[(f64, f64)],
    s: Sensors,
    seed: u64,
) -> FlightLog {
    const ROLL_RATE: f64 = 30.0 * std::f64::consts::PI / 180.0;
    // Bank profile φ(t), φ̇(t): hold each target after ramping to it.
    let mut knots = vec![(0.0, 0.0f64)]; // (t, φ) piecewise linear
    let (mut t, mut phi) = (0.0, 0.0);
    for &(secs, bank_deg) in segments {
        let target = bank_deg.to_radians();
        let ramp = (target - phi).abs() / ROLL_RATE;
        t += ramp;
        knots.push((t, target));
        t += secs;
        knots.push((t, target));
        phi = target;
    }
    let total = t;
    let bank = move |tq: f64| -> (f64, f64) {
        for w in knots.windows(2) {
            let ((t0, p0), (t1, p1)) = (w[0], w[1]);
            if tq <= t1 && t1 > t0 {
                return (p0 + (p1 - p0) * (tq - t0) / (t1 - t0), (p1 - p0) / (t1 - t0));
            }
        }
        (knots.last().map_or(0.0, |k| k.1), 0.0)
    };
    let sub = 20;
    let mut psi = yaw0;
    let mut t_prev = 0.0;
    build(total, s, seed, move |tq| {
        // Integrate ψ̇ = g tanφ / V from the previous sample to tq (midpoint rule, fine steps).
        let h = (tq - t_prev) / sub as f64;
        for k in 0..sub {
            let tm = t_prev + (k as f64 + 0.5) * h;
            psi += G * bank(tm).0.tan() / speed * h;
        }
        t_prev = tq;
        let (phi, phi_dot) = bank(tq);
        let psi_dot = G * phi.tan() / speed;
        let rates = [phi_dot, psi_dot * phi.sin(), psi_dot * phi.cos()];
        let a_n = [-speed * psi_dot * psi.sin(), speed * psi_dot * psi.cos(), 0.0];
        let att = [phi, 0.0, super::wrap(psi)];
        let vel = [speed * psi.cos(), speed * psi.sin(), 0.0];
        (att, rates, specific_force(att, a_n), vel)
    })
}

/// Samples `truth(t) -> (attitude, body rates, specific force, NED velocity)` into a log.
fn build(
    seconds: f64,
    s: Sensors,
    seed: u64,
    mut truth: impl FnMut(f64) -> ([f64; 3], [f64; 3], [f64; 3], [f64; 3]),
) -> FlightLog {
    let mut noise = Noise::new(seed);
    let n = (seconds * s.imu_hz).round() as usize;
    let every = (s.imu_hz / s.gps_hz).round().max(1.0) as usize;
    let rows = (0..=n)
        .map(|i| {
            let t = i as f64 / s.imu_hz;
            let (att, w, f, vel) = truth(t);
            let gn = noise.v3(s.gyro_noise);
            let an = noise.v3(s.accel_noise);
            let gps = (i % every == 0).then(|| {
                let vn = noise.v3(s.gps_vel_noise);
                GpsSample {
                    t,
                    vel: [vel[0] + vn[0], vel[1] + vn[1], vel[2] + vn[2]],
                    speed_acc: Some(s.gps_vel_noise),
                    lla: None,
                }
            });
            LogRow {
                t,
                gyro: core::array::from_fn(|k| w[k] + s.gyro_bias[k] + gn[k]),
                accel: core::array::from_fn(|k| f[k] + an[k]),
                gps,
                airspeed: Some(vel.iter().map(|v| v * v).sum::<f64>().sqrt()),
                baro_alt: None,
                truth: Some(att),
                truth_bias: Some(s.gyro_bias),
                reference: None,
                ..Default::default()
            }
        })
        .collect();
    FlightLog { rows }
}
