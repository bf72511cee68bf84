//! The attitude error that no state holds: the accelerometer's bias and the IMU's
//! mounting. Both are constant in body axes, so the filter, which cannot tell a tilted
//! accelerometer from a tilted aircraft, settles on an attitude off by them; its own P
//! knows nothing of that. They are added to the covariance the filter reports (a
//! "consider" term), not to the P it updates with: they bias the estimate, they are not
//! noise in the innovations, so the gates and gains stay as they are.

use crate::config::{QuatConfig, GRAVITY};
use crate::math::Mat3;

/// The variance these errors add about each body axis, rad²: the mounting σ on all
/// three, plus the tilt a horizontal accelerometer bias stands for in 1 g flight,
/// `σ_b/g`, about x and y.
pub fn body_variance(q: &QuatConfig) -> [f32; 3] {
    let m = q.mounting_sigma * q.mounting_sigma;
    let b = q.accel_bias_sigma / GRAVITY;
    [m + b * b, m + b * b, m]
}

/// `p += R·diag(d)·Rᵀ` on the attitude block of a NED error covariance `p` (`r` body →
/// NED); nothing when `d` is zero.
pub fn add_to_ned(p: &mut [[f32; 6]; 6], r: &Mat3, d: [f32; 3]) {
    if d == [0.0; 3] {
        return;
    }
    for i in 0..3 {
        for k in i..3 {
            let v: f32 = (0..3).map(|l| r[i][l] * r[k][l] * d[l]).sum();
            p[i][k] += v;
            if k != i {
                p[k][i] += v;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rz(a: f32) -> Mat3 {
        let (s, c) = (libm::sinf(a), libm::cosf(a));
        [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
    }

    #[test]
    fn a_bias_tilts_about_the_horizontal_body_axes_only() {
        let q = QuatConfig { accel_bias_sigma: 0.1, mounting_sigma: 0.0, ..Default::default() };
        let d = body_variance(&q);
        let tilt = 0.1 / GRAVITY;
        assert!((d[0] - tilt * tilt).abs() < 1e-9 && (d[1] - d[0]).abs() < 1e-12);
        assert_eq!(d[2], 0.0);
    }

    #[test]
    fn the_body_term_turns_with_the_aircraft() {
        // A body-x variance only: at heading 90° it lies along east.
        let mut p = [[0.0f32; 6]; 6];
        add_to_ned(&mut p, &rz(core::f32::consts::FRAC_PI_2), [4e-4, 0.0, 0.0]);
        assert!(p[0][0].abs() < 1e-9, "north {}", p[0][0]);
        assert!((p[1][1] - 4e-4).abs() < 1e-9, "east {}", p[1][1]);
        assert!(p[0][1].abs() < 1e-9 && p[2][2] == 0.0);
        // At 45° it is split, and correlated, between north and east.
        let mut p = [[0.0f32; 6]; 6];
        add_to_ned(&mut p, &rz(core::f32::consts::FRAC_PI_4), [4e-4, 0.0, 0.0]);
        assert!((p[0][0] - 2e-4).abs() < 1e-8 && (p[0][1] - 2e-4).abs() < 1e-8);
        assert_eq!(p[0][1], p[1][0]);
    }
}
