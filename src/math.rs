//! Small fixed-size linear algebra and angle helpers.
//!
//! Hand-written rather than nalgebra: the covariance propagation exploits the
//! block structure of Φ (zero lower-left block, diagonal bias block) and the
//! updates are scalar, which a dense generic matrix type would not see (cost).

/// A 3-vector, f32.
pub type Vec3 = [f32; 3];
/// A 3×3 matrix, row-major.
pub type Mat3 = [[f32; 3]; 3];
/// A 6×6 matrix, row-major.
pub type Mat6 = [[f32; 6]; 6];

/// π as f32.
pub const PI: f32 = core::f32::consts::PI;

/// Wraps an angle to (−π, π].
#[inline]
pub fn wrap_pi(a: f32) -> f32 {
    if !a.is_finite() {
        return a;
    }
    let two_pi = 2.0 * PI;
    let mut w = a - two_pi * libm::floorf((a + PI) / two_pi);
    // floor-based wrap gives [−π, π); move −π to +π and absorb rounding.
    if w <= -PI {
        w += two_pi;
    }
    if w > PI {
        w -= two_pi;
    }
    w
}

/// Whether every component is finite.
#[inline]
pub fn all_finite(v: &[f32]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// Euclidean norm of a 3-vector.
#[inline]
pub fn norm3(v: Vec3) -> f32 {
    libm::sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
}

/// Matrix product of two 3×3 matrices.
#[inline]
pub fn mul3(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
        }
    }
    c
}

/// a · bᵀ for 3×3 matrices.
#[inline]
pub fn mul3_bt(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = a[i][0] * b[j][0] + a[i][1] * b[j][1] + a[i][2] * b[j][2];
        }
    }
    c
}

/// Matrix-vector product.
#[inline]
pub fn mul3v(a: &Mat3, v: Vec3) -> Vec3 {
    [
        a[0][0] * v[0] + a[0][1] * v[1] + a[0][2] * v[2],
        a[1][0] * v[0] + a[1][1] * v[1] + a[1][2] * v[2],
        a[2][0] * v[0] + a[2][1] * v[1] + a[2][2] * v[2],
    ]
}
