//! Small f64 3-vector / quaternion helpers for the simulator (hand-written: a
//! dozen functions, not worth a linear-algebra dependency).
//! Conventions (docs/design.md, conventions): NED / FRD, 3-2-1 Euler, quaternion scalar first,
//! `q` rotates body vectors into NED (`R_NB`).

/// 3-vector.
pub type V3 = [f64; 3];
/// 3×3 matrix, row major.
pub type M3 = [[f64; 3]; 3];

pub fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
pub fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
pub fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
pub fn cross(a: V3, b: V3) -> V3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
pub fn norm(a: V3) -> f64 {
    dot(a, a).sqrt()
}
/// `m · v`.
pub fn mul_mv(m: &M3, v: V3) -> V3 {
    [dot(m[0], v), dot(m[1], v), dot(m[2], v)]
}
/// `mᵀ · v`.
pub fn mul_mtv(m: &M3, v: V3) -> V3 {
    [
        m[0][0] * v[0] + m[1][0] * v[1] + m[2][0] * v[2],
        m[0][1] * v[0] + m[1][1] * v[1] + m[2][1] * v[2],
        m[0][2] * v[0] + m[1][2] * v[1] + m[2][2] * v[2],
    ]
}
/// `a · b`.
pub fn mul_mm(a: &M3, b: &M3) -> M3 {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
        }
    }
    c
}
pub const IDENTITY: M3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// `R_BN(φ, θ, ψ) = Rx(φ)·Ry(θ)·Rz(ψ)`: NED → body (docs/design.md, conventions; also the thesis' eq 4.3
/// misalignment matrix with θ1..3 = φ, θ, ψ).
pub fn r_bn(roll: f64, pitch: f64, yaw: f64) -> M3 {
    let (sf, cf) = roll.sin_cos();
    let (st, ct) = pitch.sin_cos();
    let (sp, cp) = yaw.sin_cos();
    [
        [ct * cp, ct * sp, -st],
        [sf * st * cp - cf * sp, sf * st * sp + cf * cp, sf * ct],
        [cf * st * cp + sf * sp, cf * st * sp - sf * cp, cf * ct],
    ]
}

/// Unit quaternion `[e0, e1, e2, e3]` (scalar first) from 3-2-1 Euler angles, rad.
pub fn quat_from_euler(roll: f64, pitch: f64, yaw: f64) -> [f64; 4] {
    let (sf, cf) = (roll / 2.0).sin_cos();
    let (st, ct) = (pitch / 2.0).sin_cos();
    let (sp, cp) = (yaw / 2.0).sin_cos();
    [
        cp * ct * cf + sp * st * sf,
        cp * ct * sf - sp * st * cf,
        cp * st * cf + sp * ct * sf,
        sp * ct * cf - cp * st * sf,
    ]
}

/// 3-2-1 Euler angles (roll, pitch, yaw), rad, yaw in (−π, π].
pub fn euler_from_quat(e: [f64; 4]) -> V3 {
    let [e0, e1, e2, e3] = e;
    let roll = (2.0 * (e0 * e1 + e2 * e3)).atan2(e0 * e0 + e3 * e3 - e1 * e1 - e2 * e2);
    let pitch = (2.0 * (e0 * e2 - e1 * e3)).clamp(-1.0, 1.0).asin();
    let yaw = (2.0 * (e0 * e3 + e1 * e2)).atan2(e0 * e0 + e1 * e1 - e2 * e2 - e3 * e3);
    [roll, pitch, yaw]
}

/// `R_NB` (body → NED) of a unit quaternion.
pub fn r_nb_quat(e: [f64; 4]) -> M3 {
    let [e0, e1, e2, e3] = e;
    [
        [
            e0 * e0 + e1 * e1 - e2 * e2 - e3 * e3,
            2.0 * (e1 * e2 - e3 * e0),
            2.0 * (e1 * e3 + e2 * e0),
        ],
        [
            2.0 * (e1 * e2 + e3 * e0),
            e0 * e0 - e1 * e1 + e2 * e2 - e3 * e3,
            2.0 * (e2 * e3 - e1 * e0),
        ],
        [
            2.0 * (e1 * e3 - e2 * e0),
            2.0 * (e2 * e3 + e1 * e0),
            e0 * e0 - e1 * e1 - e2 * e2 + e3 * e3,
        ],
    ]
}

/// `ė = ½ e ⊗ [0, ω]` for body rates ω (rad/s).
pub fn quat_rate(e: [f64; 4], w: V3) -> [f64; 4] {
    let [e0, e1, e2, e3] = e;
    let [p, q, r] = w;
    [
        0.5 * (-p * e1 - q * e2 - r * e3),
        0.5 * (p * e0 + r * e2 - q * e3),
        0.5 * (q * e0 - r * e1 + p * e3),
        0.5 * (r * e0 + q * e1 - p * e2),
    ]
}

/// Hamilton product `a ⊗ b`.
pub fn quat_mul(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]
}

/// Quaternion of a rotation vector (axis·angle, rad).
pub fn quat_from_rotvec(v: V3) -> [f64; 4] {
    let a = norm(v);
    if a < 1e-12 {
        return normalize_quat([1.0, 0.5 * v[0], 0.5 * v[1], 0.5 * v[2]]);
    }
    let (s, c) = (a / 2.0).sin_cos();
    let k = s / a;
    [c, v[0] * k, v[1] * k, v[2] * k]
}

pub fn normalize_quat(e: [f64; 4]) -> [f64; 4] {
    let n = (e[0] * e[0] + e[1] * e[1] + e[2] * e[2] + e[3] * e[3]).sqrt();
    [e[0] / n, e[1] / n, e[2] / n, e[3] / n]
}

/// Angle of the rotation between two unit quaternions, rad.
pub fn quat_angle_between(a: [f64; 4], b: [f64; 4]) -> f64 {
    let d = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]).abs().min(1.0);
    2.0 * d.acos()
}

/// Wraps an angle to (−π, π].
pub fn wrap_pi(a: f64) -> f64 {
    let mut x = a % (2.0 * std::f64::consts::PI);
    if x <= -std::f64::consts::PI {
        x += 2.0 * std::f64::consts::PI;
    } else if x > std::f64::consts::PI {
        x -= 2.0 * std::f64::consts::PI;
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quat_euler_round_trip_and_matrix_agree() {
        for &(r, p, y) in &[(0.3, -0.2, 2.9), (-1.2, 0.7, -0.4), (2.5, 1.3, 1.0)] {
            let q = quat_from_euler(r, p, y);
            let e = euler_from_quat(q);
            assert!(
                (e[0] - r).abs() < 1e-12 && (e[1] - p).abs() < 1e-12 && (e[2] - y).abs() < 1e-12
            );
            let a = r_nb_quat(q);
            let b = r_bn(r, p, y);
            for i in 0..3 {
                for j in 0..3 {
                    assert!((a[i][j] - b[j][i]).abs() < 1e-12, "R_NB = R_BNᵀ");
                }
            }
        }
    }
}
