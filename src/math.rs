//! Small fixed-size types, angle helpers and f32-only elementary functions.
//!
//! No nalgebra: the covariance propagation exploits the block structure of Φ
//! (zero lower-left block, diagonal bias block, e₂ third column of Φa) and the
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
    // Fast path: almost every call is already in range (this runs several times per IMU
    // sample). One mask and one compare; ±π itself and NaN take the slow path.
    if libm::fabsf(a) < PI {
        return a;
    }
    if a == PI {
        return a;
    }
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

/// `a.max(b)` to the bit as libm's `fmaxf` gives it (`a < b ? b : a`, and the other
/// operand when one is NaN), but inline: `f32::max` is a call to `fmaxf` on the M4F
/// (ARMv7E-M has no `vmaxnm`), ~12 instructions with the call, and the GPS-update path
/// takes ~25. Written so that a constant `b` leaves one compare (`a` NaN: `b`).
#[inline(always)]
pub fn max(a: f32, b: f32) -> f32 {
    if a >= b || b.is_nan() {
        a
    } else {
        b
    }
}

/// `a.min(b)` to the bit as libm's `fminf` gives it (`a < b ? a : b`, and the other
/// operand when one is NaN), inline (see [`max`]).
#[inline(always)]
pub fn min(a: f32, b: f32) -> f32 {
    if a < b || b.is_nan() {
        a
    } else {
        b
    }
}

/// Euclidean norm of a 3-vector.
#[inline]
pub fn norm3(v: Vec3) -> f32 {
    sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
}

// --- f32-only elementary functions -------------------------------------------------
//
// libm's `sinf`/`cosf`/`sincosf`/`hypotf`/`asinf` evaluate in f64, which the Cortex-M4F
// FPU cannot do: ~1,200 instructions per `sinf` in software (measured under QEMU). These
// stay in f32 (Cody-Waite reduction, cephes minimax polynomials, ≤ 2 ulp on |x| ≤ 8192),
// are pure IEEE f32 arithmetic and so round identically on host and MCU.

const FRAC_2_PI: f32 = core::f32::consts::FRAC_2_PI;
/// 1.5·2²³: adding it rounds an |f32| < 2²² to an integer (round to nearest even).
const ROUND_SHIFTER: f32 = 12_582_912.0;
// π/2 split in three parts so that k·PIO2_1 and k·PIO2_2 are exact for the reduction
// (cephes' π/4 split, doubled).
const PIO2_1: f32 = 2.0 * 0.785_156_25;
const PIO2_2: f32 = 2.0 * 2.418_756_5e-4;
const PIO2_3: f32 = 2.0 * 3.774_895e-8;

/// `(sin x, cos x)`, f32 only. Non-finite input gives NaN; beyond ±8192 rad the
/// argument is first wrapped to (−π, π] in f32 (no angle the filter forms comes near:
/// libm's f64 `sincosf` here would put a 776-byte frame on the interrupt stack).
#[inline(always)]
pub fn sincos(x: f32) -> (f32, f32) {
    let mut x = x;
    if !(libm::fabsf(x) <= 8192.0) {
        if !x.is_finite() {
            return (f32::NAN, f32::NAN);
        }
        x = wrap_pi(x);
    }
    // Quadrant: x = k·π/2 + z, |z| ≤ π/4, k = round(x·2/π) by the 1.5·2²³ shifter — f32
    // addition rounds to the nearest integer and k's low bits land in the mantissa, so the
    // quadrant needs no float→int conversion (|x·2/π| ≤ 5216 < 2²²).
    let shifted = x * FRAC_2_PI + ROUND_SHIFTER;
    let k = shifted - ROUND_SHIFTER;
    let q = shifted.to_bits() & 3;
    let z = ((x - k * PIO2_1) - k * PIO2_2) - k * PIO2_3;
    let zz = z * z;
    let s = z + z * zz * (-1.666_665_5e-1 + zz * (8.332_161e-3 + zz * -1.951_529_6e-4));
    let c =
        1.0 - 0.5 * zz + zz * zz * (4.166_664_6e-2 + zz * (-1.388_731_6e-3 + zz * 2.443_315_7e-5));
    // (sin, cos) = (s, c), (c, −s), (−s, −c), (−c, s) for q = 0…3: a select and two sign-bit
    // flips, not a jump (a roll crossing ±45° changes quadrant; a mispredicted branch here
    // cost the host more than the polynomials).
    let (sn, cs) = if q & 1 == 0 { (s, c) } else { (c, s) };
    let sin_sign = (q & 2) << 30;
    let cos_sign = ((q + 1) & 2) << 30;
    (f32::from_bits(sn.to_bits() ^ sin_sign), f32::from_bits(cs.to_bits() ^ cos_sign))
}

/// sin x, f32 only (see [`sincos`]).
#[inline]
pub fn sin(x: f32) -> f32 {
    sincos(x).0
}

/// cos x, f32 only (see [`sincos`]).
#[inline]
pub fn cos(x: f32) -> f32 {
    sincos(x).1
}

/// √(a² + b²) in f32. No overflow guard: every caller's arguments are bounded
/// (accelerations, velocities, unit-scale coefficients ≪ 1e19).
#[inline]
pub fn hypot(a: f32, b: f32) -> f32 {
    sqrt(a * a + b * b)
}

/// asin s for |s| ≤ 1, via [`atan2`].
#[inline]
pub fn asin(s: f32) -> f32 {
    atan2(s, sqrt((1.0 - s * s).max(0.0)))
}

const FRAC_PI_2: f32 = core::f32::consts::FRAC_PI_2;
const FRAC_PI_4: f32 = core::f32::consts::FRAC_PI_4;
/// tan(π/8): beyond it the argument is reduced by π/4.
const TAN_PI_8: f32 = 0.414_213_57;

/// atan2(y, x) in (−π, π], f32 only: one division and a degree-9 odd polynomial
/// (cephes `atanf` coefficients on |z| ≤ tan π/8). Max error 2.6e-7 rad against f64
/// (`tests/math_f32.rs` prints it); libm's `atan2f` is correctly rounded but costs more
/// on the M4F (special-case ladder, a second reduction). Inputs that make the quotient
/// NaN — (0, 0), both infinite, NaN — go to libm, so IEEE special values are unchanged
/// except atan2(−0, x < 0) = +π (the (−π, π] convention of [`wrap_pi`]). Finite inputs
/// need |x| + |y| < 3.4e38 (the reduction adds them; no physical input comes near).
#[inline]
pub fn atan2(y: f32, x: f32) -> f32 {
    let (ax, ay) = (libm::fabsf(x), libm::fabsf(y));
    let (lo, hi) = if ay <= ax { (ay, ax) } else { (ax, ay) };
    // θ = atan(lo/hi) ∈ [0, π/4]; above tan π/8 use atan t = π/4 + atan((t−1)/(t+1)).
    let (z, base) =
        if lo > TAN_PI_8 * hi { ((lo - hi) / (lo + hi), FRAC_PI_4) } else { (lo / hi, 0.0) };
    let zz = z * z;
    let p = (((8.053_744_5e-2 * zz - 1.387_768_6e-1) * zz + 1.997_771_1e-1) * zz - 3.333_294_9e-1)
        * zz
        * z
        + z;
    let mut t = base + p;
    // One check for every special case: 0/0, ∞/∞ and NaN all give NaN here (cheaper on
    // the M4F than classifying the inputs first).
    if t.is_nan() {
        return libm::atan2f(y, x);
    }
    if ay > ax {
        t = FRAC_PI_2 - t;
    }
    if x < 0.0 {
        t = PI - t;
    }
    if y < 0.0 {
        -t
    } else {
        t
    }
}

/// √x in f32, correctly rounded (IEEE 754), from the `fpu-sqrt` crate: the M4F FPU's
/// `VSQRT.F32` on the firmware (about 10 instructions with its moves, against libm's 57 in
/// software), `libm::sqrtf` on the host (one `sqrtss`). Both round correctly, so the host
/// replay and the firmware agree to the bit.
#[inline(always)]
pub fn sqrt(x: f32) -> f32 {
    fpu_sqrt::sqrt(x)
}

/// Whether every component satisfies `|c| ≤ lim` (false for NaN and ±Inf: no separate
/// finiteness check). `&`, not `&&`: no branch per component on the IMU path.
#[inline(always)]
pub fn within(v: &Vec3, lim: f32) -> bool {
    (libm::fabsf(v[0]) <= lim) & (libm::fabsf(v[1]) <= lim) & (libm::fabsf(v[2]) <= lim)
}
