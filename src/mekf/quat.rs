//! Unit quaternions for the attitude (Hamilton, `[w, x, y, z]`, body FRD → NED):
//! `v_ned = R(q)·v_body`. Hand-written rather than a crate: four small functions,
//! f32 with the core's own sin/cos, and no generic-math code in the IMU interrupt.

use crate::math::{Mat3, Vec3};
use crate::rotation::Euler;

/// A rotation as a unit quaternion `[w, x, y, z]` (body → NED).
pub type Quat = [f32; 4];

/// The identity rotation.
pub const IDENTITY: Quat = [1.0, 0.0, 0.0, 0.0];

/// Hamilton product `a ⊗ b`.
#[inline]
pub fn mul(a: &Quat, b: &Quat) -> Quat {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]
}

/// The rotation by the rotation vector `v` (rad): `exp(v/2)`. A series to O(|v|⁴)
/// below 0.1 rad (an IMU step: no sincos on the hot path), exact above.
#[inline]
pub fn from_rotation_vector(v: Vec3) -> Quat {
    let a2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    let (c, s) = if a2 < 0.01 {
        // cos(a/2) and sin(a/2)/a to O(a⁴): errors < 3e-9.
        (1.0 - a2 * (1.0 / 8.0) + a2 * a2 * (1.0 / 384.0), 0.5 - a2 * (1.0 / 48.0))
    } else {
        let a = crate::math::sqrt(a2);
        let (sh, ch) = crate::math::sincos(0.5 * a);
        (ch, sh / a)
    };
    [c, s * v[0], s * v[1], s * v[2]]
}

/// `q` scaled back to unit norm. One Newton step of 1/√n (no √, no division): the
/// norm drifts by ~1e-7 per IMU step, so one step restores it to f32 precision.
#[inline]
pub fn renormalize(q: &Quat) -> Quat {
    let n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
    let k = 1.5 - 0.5 * n2;
    [q[0] * k, q[1] * k, q[2] * k, q[3] * k]
}

/// `q` scaled to unit norm exactly (after a large change: alignment, a reset).
pub fn normalize(q: &Quat) -> Quat {
    let n = crate::math::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if !(n > 1e-6) {
        return IDENTITY;
    }
    [q[0] / n, q[1] / n, q[2] / n, q[3] / n]
}

/// The direction cosine matrix `R(q)`, body → NED.
#[inline]
pub fn to_dcm(q: &Quat) -> Mat3 {
    let [w, x, y, z] = *q;
    let (xx, yy, zz) = (x * x, y * y, z * z);
    let (xy, xz, yz) = (x * y, x * z, y * z);
    let (wx, wy, wz) = (w * x, w * y, w * z);
    [
        [1.0 - 2.0 * (yy + zz), 2.0 * (xy - wz), 2.0 * (xz + wy)],
        [2.0 * (xy + wz), 1.0 - 2.0 * (xx + zz), 2.0 * (yz - wx)],
        [2.0 * (xz - wy), 2.0 * (yz + wx), 1.0 - 2.0 * (xx + yy)],
    ]
}

/// The quaternion of 3-2-1 Euler angles: `q = q_z(ψ) ⊗ q_y(θ) ⊗ q_x(φ)`.
pub fn from_euler(e: &Euler) -> Quat {
    let (sr, cr) = crate::math::sincos(0.5 * e.roll);
    let (sp, cp) = crate::math::sincos(0.5 * e.pitch);
    let (sy, cy) = crate::math::sincos(0.5 * e.yaw);
    [
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    ]
}

/// 3-2-1 Euler angles of `q` (output only: roll and yaw are undefined at ±90° pitch,
/// where this returns the pair with the same body x-axis).
pub fn to_euler(q: &Quat) -> Euler {
    let [w, x, y, z] = *q;
    let sp = (2.0 * (w * y - z * x)).clamp(-1.0, 1.0);
    if libm::fabsf(sp) > 0.999_999 {
        // Gimbal lock: only yaw ∓ roll is defined; report it as yaw with roll 0.
        let s = if sp > 0.0 { 1.0 } else { -1.0 };
        let half = crate::math::PI * 0.5;
        return Euler { roll: 0.0, pitch: s * half, yaw: -2.0 * s * crate::math::atan2(x, w) };
    }
    Euler {
        roll: crate::math::atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y)),
        pitch: crate::math::asin(sp),
        yaw: crate::math::atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z)),
    }
}

/// `R·v`.
#[inline]
pub fn rotate(r: &Mat3, v: Vec3) -> Vec3 {
    [
        r[0][0] * v[0] + r[0][1] * v[1] + r[0][2] * v[2],
        r[1][0] * v[0] + r[1][1] * v[1] + r[1][2] * v[2],
        r[2][0] * v[0] + r[2][1] * v[1] + r[2][2] * v[2],
    ]
}

/// `Rᵀ·v`.
#[inline]
#[cfg(any(test, feature = "internals"))]
pub fn rotate_back(r: &Mat3, v: Vec3) -> Vec3 {
    [
        r[0][0] * v[0] + r[1][0] * v[1] + r[2][0] * v[2],
        r[0][1] * v[0] + r[1][1] * v[1] + r[2][1] * v[2],
        r[0][2] * v[0] + r[1][2] * v[1] + r[2][2] * v[2],
    ]
}

/// `a × b`.
#[inline]
pub fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// The shortest rotation taking direction `u` to direction `v` (neither need be unit;
/// antiparallel vectors turn about an axis normal to `u`).
pub fn between(u: Vec3, v: Vec3) -> Quat {
    let nu = crate::math::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    let nv = crate::math::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if !(nu > 1e-6 && nv > 1e-6) {
        return IDENTITY;
    }
    let c = cross(u, v);
    let d = u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
    let w = nu * nv + d;
    if w < 1e-6 * nu * nv {
        // Antiparallel: half a turn about any axis normal to u.
        let a = if libm::fabsf(u[0]) < 0.9 * nu { [1.0, 0.0, 0.0] } else { [0.0, 1.0, 0.0] };
        let n = cross(u, a);
        return normalize(&[0.0, n[0], n[1], n[2]]);
    }
    normalize(&[w, c[0], c[1], c[2]])
}
