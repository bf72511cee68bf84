//! A built-in synthetic flight for HIL runs when no log is given (and until the
//! `sim` branch's simulator is merged): level flight, ±35° coordinated turns and a
//! climb at 22 m/s, 100 Hz IMU, 10 Hz GPS, with turn-on gyro bias and white noise.
//! Kinematics are exact for β = 0, α = 0 (nose along the velocity, so ψ = course,
//! θ = flight-path angle); gyro and accelerometer follow from the truth by central
//! differences at 1 kHz (docs/design.md, conventions).

use crate::log::{FlightLog, GpsSample, LogRow};
use wing_ahrs::GRAVITY;

const V: f64 = 22.0;
const DEG: f64 = std::f64::consts::PI / 180.0;

/// Commanded bank φ(t) and flight-path angle γ(t), smooth (cosine ramps).
fn command(t: f64) -> (f64, f64) {
    let ramp = |t: f64, t0: f64, t1: f64| -> f64 {
        if t <= t0 {
            0.0
        } else if t >= t1 {
            1.0
        } else {
            0.5 - 0.5 * ((t - t0) / (t1 - t0) * std::f64::consts::PI).cos()
        }
    };
    let bank = 35.0 * DEG * (ramp(t, 8.0, 11.0) - ramp(t, 25.0, 28.0))
        - 35.0 * DEG * (ramp(t, 34.0, 37.0) - ramp(t, 50.0, 53.0))
        + 20.0 * DEG * (ramp(t, 60.0, 62.0) - ramp(t, 75.0, 77.0));
    let gamma = 6.0 * DEG * (ramp(t, 56.0, 59.0) - ramp(t, 70.0, 73.0));
    (bank, gamma)
}

/// Deterministic Gaussian noise (xorshift + Box-Muller): no RNG crate needed for a demo.
struct Noise(u64);
impl Noise {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    fn gauss(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
    }
}

/// R_BN(φ, θ, ψ)·v (NED → body).
fn to_body(e: [f64; 3], v: [f64; 3]) -> [f64; 3] {
    let (sf, cf, st, ct, sp, cp) =
        (e[0].sin(), e[0].cos(), e[1].sin(), e[1].cos(), e[2].sin(), e[2].cos());
    let r = [
        [ct * cp, ct * sp, -st],
        [sf * st * cp - cf * sp, sf * st * sp + cf * cp, sf * ct],
        [cf * st * cp + sf * sp, cf * st * sp - sf * cp, cf * ct],
    ];
    [0, 1, 2].map(|i| r[i][0] * v[0] + r[i][1] * v[1] + r[i][2] * v[2])
}

/// The flight: `seconds` long, noise seeded by `seed`.
pub fn synthetic(seconds: f64, seed: u64) -> FlightLog {
    let fine = 1000usize; // Hz
    let n = (seconds * fine as f64) as usize + 2;
    // Truth at 1 kHz: Euler angles and NED velocity.
    let mut euler = Vec::with_capacity(n);
    let mut vel = Vec::with_capacity(n);
    let mut chi: f64 = 0.3;
    for k in 0..n {
        let t = k as f64 / fine as f64;
        let (phi, gamma) = command(t);
        euler.push([phi, gamma, chi]);
        vel.push([V * gamma.cos() * chi.cos(), V * gamma.cos() * chi.sin(), -V * gamma.sin()]);
        chi += GRAVITY as f64 * phi.tan() / V / fine as f64;
    }
    let mut noise = Noise(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
    let bias = [0.8 * DEG, -0.6 * DEG, 0.5 * DEG];
    let mut rows = Vec::new();
    let h = 1.0 / fine as f64;
    let mut k = 1;
    while k + 1 < n {
        let t = k as f64 * h;
        let e = euler[k];
        let d = |i: usize| {
            let mut x = euler[k + 1][i] - euler[k - 1][i];
            if i == 2 {
                x = (x + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI)
                    - std::f64::consts::PI;
            }
            x / (2.0 * h)
        };
        let (fd, td, pd) = (d(0), d(1), d(2));
        let (sf, cf, st, ct) = (e[0].sin(), e[0].cos(), e[1].sin(), e[1].cos());
        let rates = [fd - pd * st, td * cf + pd * sf * ct, -td * sf + pd * cf * ct];
        let acc_n = [0, 1, 2].map(|i| (vel[k + 1][i] - vel[k - 1][i]) / (2.0 * h));
        let f_b = to_body(e, [acc_n[0], acc_n[1], acc_n[2] - GRAVITY as f64]);
        let gyro = [0, 1, 2].map(|i| rates[i] + bias[i] + 0.05 * DEG * noise.gauss());
        let accel = [0, 1, 2].map(|i| f_b[i] + 0.02 * noise.gauss());
        let step = rows.len();
        let gps = (step % 10 == 5).then(|| GpsSample {
            t,
            vel: [0, 1, 2].map(|i| vel[k][i] + 0.01 * noise.gauss()),
            speed_acc: Some(0.01),
            lla: None,
        });
        let yaw = (e[2] + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI)
            - std::f64::consts::PI;
        rows.push(LogRow {
            t,
            gyro,
            accel,
            gps,
            airspeed: Some(V + 0.06 * noise.gauss()),
            baro_alt: None,
            truth: Some([e[0], e[1], yaw]),
            truth_bias: Some(bias),
            reference: None,
            ..Default::default()
        });
        k += fine / 100;
    }
    FlightLog { rows }
}

/// The µs time stamp of row `i` of [`synthetic`] (rows are 10 ms apart from t = 1 ms).
pub fn synthetic_row_us(i: usize) -> u64 {
    crate::replay::to_us(0.001 + i as f64 * 0.01)
}
