//! Measurement model 1 (EKF1): roll and pitch from the accelerometer and the
//! GPS-derived acceleration (thesis eq 4.37–4.50, docs/design.md, EKF1).
//!
//! `r = Rz(ψ)·(a_N − g_N)` (eq 4.40) and `A = Rx(φ)·Ry(θ)·r` (eq 4.39):
//! `Ax = rx cθ − rz sθ`, `Ay = rθ sφ + ry cφ`, `Az = rθ cφ − ry sφ`,
//! `rθ = rx sθ + rz cθ`. Each row is `a·sin x + b·cos x = c`.

use super::heading::RollPitchTrig;
use super::solver::solve_sin_cos_near;
use super::RollPitch;
use crate::config::{Ekf1Form, GRAVITY};
use crate::math::Vec3;

/// Specific-force radius below which a row is degenerate (free fall), m/s².
const MIN_RADIUS: f32 = 0.5;

/// `r` of eq 4.40: the GPS acceleration minus gravity, rotated into the heading frame.
#[cfg(any(test, feature = "internals"))]
pub fn heading_frame_specific_force(accel_ned: Vec3, heading: f32) -> Vec3 {
    heading_frame_specific_force_sc(accel_ned, crate::math::sincos(heading))
}

/// [`heading_frame_specific_force`] with the heading given as `(sin ψ, cos ψ)`.
#[inline]
pub fn heading_frame_specific_force_sc(accel_ned: Vec3, (s, c): (f32, f32)) -> Vec3 {
    [
        accel_ned[0] * c + accel_ned[1] * s,
        -accel_ned[0] * s + accel_ned[1] * c,
        accel_ned[2] - GRAVITY,
    ]
}

/// The forward model: the specific force an accelerometer at roll φ, pitch θ
/// reads for heading-frame vector `r` (eq 4.39).
#[cfg(any(test, feature = "internals"))]
pub fn forward(r: Vec3, roll: f32, pitch: f32) -> Vec3 {
    let (sf, cf) = crate::math::sincos(roll);
    let (st, ct) = crate::math::sincos(pitch);
    let r_theta = r[0] * st + r[2] * ct;
    [r[0] * ct - r[2] * st, r_theta * sf + r[1] * cf, r_theta * cf - r[1] * sf]
}

/// Thesis eq 4.45: `θm = arctan((−rx rz − Ax√(rx² + rz² − Ax²)) / (Ax² − rz²))`.
/// `None` where the denominator vanishes; a negative discriminant is clamped to 0.
pub fn pitch_thesis(accel: Vec3, r: Vec3) -> (Option<f32>, bool) {
    let ax = accel[0];
    let disc = r[0] * r[0] + r[2] * r[2] - ax * ax;
    let clamped = disc < 0.0;
    let den = ax * ax - r[2] * r[2];
    if libm::fabsf(den) < 1e-6 {
        return (None, clamped);
    }
    let num = -r[0] * r[2] - ax * crate::math::sqrt(disc.max(0.0));
    (Some(libm::atanf(num / den)), clamped)
}

/// Thesis eq 4.48: `φm = arctan((rθ ry + Ay√(ry² + rθ² − Ay²)) / (Ay² − rθ²))`.
pub fn roll_thesis(accel: Vec3, r: Vec3, pitch: f32) -> (Option<f32>, bool) {
    let ay = accel[1];
    let (st, ct) = crate::math::sincos(pitch);
    let r_theta = r[0] * st + r[2] * ct;
    let disc = r[1] * r[1] + r_theta * r_theta - ay * ay;
    let clamped = disc < 0.0;
    let den = ay * ay - r_theta * r_theta;
    if libm::fabsf(den) < 1e-6 {
        return (None, clamped);
    }
    let num = r_theta * r[1] + ay * crate::math::sqrt(disc.max(0.0));
    (Some(libm::atanf(num / den)), clamped)
}

/// Measures roll and pitch from body specific force `accel` (m/s², FRD) and the
/// heading-frame vector `r` (see [`heading_frame_specific_force`]).
/// `pred` = predicted (roll, pitch), used to pick the solver root.
#[cfg(any(test, feature = "internals"))]
pub fn measure(form: Ekf1Form, accel: Vec3, r: Vec3, pred: (f32, f32)) -> RollPitch {
    measure_near(form, accel, r, &RollPitchTrig::new(pred.0, pred.1))
}

/// [`measure`] with the predicted roll and pitch given by their sines and cosines
/// (the update computes them once for every model).
pub fn measure_near(form: Ekf1Form, accel: Vec3, r: Vec3, pred: &RollPitchTrig) -> RollPitch {
    let mut out = RollPitch::default();
    // Pitch (with its sine and cosine: the robust solver yields them without trigonometry).
    let pitch = match form {
        Ekf1Form::ThesisExact => {
            let (p, c) = pitch_thesis(accel, r);
            out.clamped += c as u8;
            p.map(|p| (p, crate::math::sincos(p)))
        }
        _ => solve_sin_cos_near(-r[2], r[0], accel[0], (pred.st, pred.ct), MIN_RADIUS).map(|s| {
            out.clamped += s.clamped as u8;
            (s.x, s.sin_cos)
        }),
    };
    let Some((theta, (st, ct))) = pitch else {
        out.degenerate = true;
        return out;
    };
    out.pitch = Some(theta);
    out.pitch_sin_cos = Some((st, ct));
    // Roll.
    let r_theta = r[0] * st + r[2] * ct;
    out.roll = match form {
        Ekf1Form::ThesisExact => {
            let (p, c) = roll_thesis(accel, r, theta);
            out.clamped += c as u8;
            p
        }
        Ekf1Form::RobustSingleAxis => {
            solve_sin_cos_near(r_theta, r[1], accel[1], (pred.sf, pred.cf), MIN_RADIUS).map(|s| {
                out.clamped += s.clamped as u8;
                s.x
            })
        }
        Ekf1Form::RobustTwoAxis => {
            let min2 = MIN_RADIUS * MIN_RADIUS;
            if accel[1] * accel[1] + accel[2] * accel[2] > min2
                && r[1] * r[1] + r_theta * r_theta > min2
            {
                // atan2(Ay, Az) − atan2(ry, rθ) as one atan2 of the complex quotient.
                Some(crate::math::atan2(
                    accel[1] * r_theta - accel[2] * r[1],
                    accel[2] * r_theta + accel[1] * r[1],
                ))
            } else {
                None
            }
        }
    };
    out.degenerate = out.roll.is_none();
    out
}
