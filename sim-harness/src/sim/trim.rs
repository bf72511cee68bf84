//! Wings-level, constant-altitude trim: the angle of attack, elevator and
//! throttle that zero the body accelerations and pitching moment at a given
//! airspeed (Beard & McLain §5.3, solved here by Newton on three equations).

use super::aircraft::{forces_moments, AirData, Airframe, Controls};
use super::dynamics::G;
use anyhow::{bail, Result};

/// A trimmed straight-and-level condition.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Trim {
    /// m/s
    pub va: f64,
    /// rad (= pitch, level flight)
    pub alpha: f64,
    pub controls: Controls,
}

fn residual(af: &Airframe, va: f64, x: [f64; 3]) -> [f64; 3] {
    let [alpha, de, dt] = x;
    let air = AirData { va, alpha, beta: 0.0 };
    let u = Controls { elevator: de, aileron: 0.0, rudder: 0.0, throttle: dt };
    let (f, m) = forces_moments(af, &air, [0.0; 3], &u);
    // θ = α: gravity in body axes is g·[−sin α, 0, cos α].
    [
        f[0] / af.mass - G * alpha.sin(),
        f[2] / af.mass + G * alpha.cos(),
        m[1] / (0.5 * super::aircraft::RHO * va * va * af.S * af.c),
    ]
}

/// Solves the trim at airspeed `va` (m/s).
pub fn level_trim(af: &Airframe, va: f64) -> Result<Trim> {
    let mut x = [0.05, 0.0, 0.5];
    for _ in 0..50 {
        let r = residual(af, va, x);
        if r.iter().all(|v| v.abs() < 1e-10) {
            break;
        }
        let mut j = [[0.0; 3]; 3];
        for k in 0..3 {
            let mut xp = x;
            let h = 1e-6;
            xp[k] += h;
            let rp = residual(af, va, xp);
            for i in 0..3 {
                j[i][k] = (rp[i] - r[i]) / h;
            }
        }
        let dx = solve3(j, [-r[0], -r[1], -r[2]]);
        for k in 0..3 {
            x[k] += dx[k];
        }
    }
    let r = residual(af, va, x);
    if r.iter().any(|v| v.is_nan() || v.abs() >= 1e-6) {
        bail!("no level trim for the {} at {va} m/s (residual {r:?})", af.name);
    }
    let [alpha, de, dt] = x;
    if !(0.0..=1.0).contains(&dt) || de.abs() > af.max_elevator || alpha.abs() > 0.3 {
        bail!(
            "the {} cannot fly level at {va} m/s (trim α {:.1}°, elevator {:.1}°, throttle {:.2})",
            af.name,
            alpha.to_degrees(),
            de.to_degrees(),
            dt
        );
    }
    Ok(Trim {
        va,
        alpha,
        controls: Controls { elevator: de, aileron: 0.0, rudder: 0.0, throttle: dt },
    })
}

/// Cramer's rule for a 3×3 system.
fn solve3(a: [[f64; 3]; 3], b: [f64; 3]) -> [f64; 3] {
    let det = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(a);
    let mut x = [0.0; 3];
    for k in 0..3 {
        let mut m = a;
        for i in 0..3 {
            m[i][k] = b[i];
        }
        x[k] = det(m) / d;
    }
    x
}
