//! Aid source: the GPS-derived acceleration against the accelerometer, as a 3-D
//! vector in NED (EKF1 in the quaternion filter). Control policy and fusion.
//!
//! Between two fixes the receiver's velocity difference is the mean inertial
//! acceleration, `ā = (v₁ − v₀)/Δt`; the IMU gives the mean specific force in NED,
//! `f̄ = Σ R̂ f Δt / T` ([`super::dv_window`]). The two agree when the attitude is
//! right: `ā − g = R·f̄_body`. Both sides are ground-referenced, so a steady wind
//! does not bias it, and with the error `R = exp([δθ×])R̂` the residual is
//! `y = (ā − g) − f̄ ≈ −[f̄×]·δθ`: it observes the tilt always (gravity) and the
//! heading whenever the aircraft accelerates horizontally (turns, speed changes).

use super::dv_window::WindowMean;
use super::filter::{minus_skew, AttRow, Fused, Mekf};
use crate::config::{QuatConfig, GRAVITY};
use crate::measure::gps_delta::GpsDelta;

/// The residual, Jacobian and noise of one fix interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measurement {
    /// `y = (ā − g) − f̄`, NED, m/s².
    pub y: [f32; 3],
    /// `∂y/∂δθ` (`∂y/∂δb` = 0).
    pub h: [AttRow; 3],
    /// Noise variance per NED axis, (m/s²)², the GPS part included.
    pub r: [f32; 3],
    /// The GPS part of `r`, `(σ₀² + σ₁²)/Δt²` (m/s²)²: left out where the fix noise is a state.
    pub r_gps: f32,
}

/// Forms the measurement of fix interval `d` with the IMU window `w`.
/// `vel_var` = the two fixes' velocity variances (m/s)², `gyro_psd` (rad²/s) and
/// `lag` (s, the receiver latency) give the attitude noise accumulated since the window.
/// `att_var` = the attitude error variances (rad², NED axes) for the second-order term.
#[allow(clippy::too_many_arguments)]
pub fn measurement(
    d: &GpsDelta,
    w: &WindowMean,
    r_bn: &crate::math::Mat3,
    vel_var: [f32; 2],
    cfg: &QuatConfig,
    gyro_psd: f32,
    lag: f32,
    att_var: [f32; 3],
) -> Measurement {
    let f = w.f_ned;
    let a = d.accel_ned;
    let mut y = [a[0] - f[0], a[1] - f[1], a[2] - GRAVITY - f[2]];
    let h = minus_skew(f);
    // GPS: (σ₀² + σ₁²)/Δt² per axis. Accelerometer: white noise over the window, plus the
    // window's own scatter (vibration) rotated into NED. Attitude drift since the window:
    // |f|²·σ_g²·(lag + T/2). A floor for what no model covers (lever arm, timing).
    let gps = (vel_var[0] + vel_var[1]) / (d.dt * d.dt);
    let white = cfg.accel_noise_density * cfg.accel_noise_density / w.duration;
    let f2 = f[0] * f[0] + f[1] * f[1] + f[2] * f[2];
    let drift = f2 * gyro_psd * (lag + 0.5 * w.duration);
    let floor = cfg.accel_floor * cfg.accel_floor + cfg.accel_floor_rel * cfg.accel_floor_rel * f2;
    // The rotation's second-order term ½ δθ × (δθ × f): while one axis is uncertain (the
    // heading after alignment) and another is not yet small (the tilt), a tilt error
    // tilts f̄ and the first-order model would read GPS noise across it as heading.
    let [p0, p1, p2] = att_var;
    let second = f2 * (p0 * p1 + p0 * p2 + p1 * p2);
    let mut r = [0.0f32; 3];
    for i in 0..3 {
        let vib: f32 = (0..3).map(|j| r_bn[i][j] * r_bn[i][j] * w.sem_sq[j]).sum();
        r[i] = gps + white + vib + drift + floor + second;
    }
    if !d.vd_valid {
        // No measured vertical velocity: the down axis carries no information.
        y[2] = 0.0;
        r[2] = 1e6;
    }
    Measurement { y, h, r, r_gps: gps }
}

/// Whether the interval's horizontal specific force is significantly (3σ) more than
/// tilt error and noise could make: only then does the measurement see the heading.
pub fn sees_heading(m: &Measurement, w: &WindowMean, att_var: [f32; 3]) -> bool {
    let f = w.f_ned;
    let fh2 = f[0] * f[0] + f[1] * f[1];
    let tilt_var = crate::math::max(att_var[0], att_var[1]);
    let noise = GRAVITY * GRAVITY * tilt_var + 0.5 * (m.r[0] + m.r[1]);
    fh2 > 9.0 * noise
}

/// Fuses `m` with the χ² gate of the configuration. `fix_var` = the two fixes'
/// velocity variances when both receivers reported them: their noise is then a state
/// (`Mekf::fuse_with_fix_noise`), else white.
pub fn fuse(
    ekf: &mut Mekf,
    m: &Measurement,
    fix_var: Option<[f32; 2]>,
    dt: f32,
    cfg: &QuatConfig,
) -> Fused {
    match fix_var {
        Some([v0, v1]) => {
            let white = m.r.map(|r| r - m.r_gps);
            let vd = |v: f32| if m.r[2] >= 1e6 { [v, v, 0.0] } else { [v; 3] };
            ekf.fuse_with_fix_noise(m.y, &m.h, white, vd(v0), vd(v1), dt, cfg.gate_chi2)
        }
        None => {
            ekf.forget_fix_noise();
            ekf.fuse(m.y, &m.h, m.r, cfg.gate_chi2)
        }
    }
}
