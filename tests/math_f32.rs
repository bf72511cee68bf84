//! The core's f32-only sin/cos/hypot/asin/atan2/√ (src/math.rs) against f64 references:
//! accurate to a couple of f32 ulps everywhere the estimator uses them.

use wing_ahrs::math::{asin, atan2, hypot, max, min, sincos, sqrt};

#[test]
fn sincos_is_within_two_ulp_of_f64_over_the_flight_range_and_beyond() {
    let mut worst = 0.0f64;
    let n = 2_000_000;
    for k in 0..=n {
        let x = -40.0 + 80.0 * k as f64 / n as f64;
        let xf = x as f32;
        let (s, c) = sincos(xf);
        let (es, ec) = (xf as f64).sin_cos();
        worst = worst.max((s as f64 - es).abs()).max((c as f64 - ec).abs());
    }
    println!("sincos: worst absolute error {worst:.3e} on [-40, 40]");
    // |sin|,|cos| ≤ 1: 2 ulp at 1.0 is 1.2e-7.
    assert!(worst < 1.2e-7, "worst {worst:e}");
}

#[test]
fn sincos_handles_special_values() {
    assert_eq!(sincos(0.0), (0.0, 1.0));
    let (s, c) = sincos(f32::NAN);
    assert!(s.is_nan() && c.is_nan());
    let (s, c) = sincos(f32::INFINITY);
    assert!(s.is_nan() && c.is_nan());
    // Beyond ±8192 rad the argument is wrapped in f32 (no libm f64 path on the interrupt
    // stack): a point on the unit circle, exact only to the wrap's f32 rounding
    // (no angle the filter forms is that large).
    for x in [8193.0f32, -1e6, 3.0e38] {
        let (s, c) = sincos(x);
        assert!(((s * s + c * c) - 1.0).abs() < 1e-6, "x = {x}: ({s}, {c})");
    }
    let (s, c) = sincos(8200.0);
    assert!((s as f64 - 8200f64.sin()).abs() < 1e-3 && (c as f64 - 8200f64.cos()).abs() < 1e-3);
    for k in 0..16 {
        // Octant boundaries.
        let x = k as f32 * std::f32::consts::FRAC_PI_4;
        let (s, c) = sincos(x);
        assert!(
            (s as f64 - (x as f64).sin()).abs() < 1.2e-7
                && (c as f64 - (x as f64).cos()).abs() < 1.2e-7,
            "x = {x}"
        );
    }
}

#[test]
fn hypot_and_asin_match_f64() {
    for &(a, b) in &[(3.0f32, 4.0f32), (1e-3, 2e-3), (-250.0, 480.0), (9.80665, 0.0)] {
        let r = (a as f64).hypot(b as f64);
        assert!(((hypot(a, b) as f64) - r).abs() <= 2.0 * f32::EPSILON as f64 * r);
    }
    for k in -1000..=1000 {
        let s = k as f32 / 1000.0;
        assert!((asin(s) as f64 - (s as f64).asin()).abs() < 3e-7, "asin({s})");
    }
}

#[test]
fn atan2_is_within_3e7_of_f64_on_every_direction_and_scale() {
    // Every direction (fine grid of angles, incl. the octant and π/8 reduction boundaries)
    // at radii from 1e-6 to 1e6, plus an x/y grid straddling the axes.
    let mut worst = (0.0f64, 0.0f32, 0.0f32);
    let mut check = |y: f32, x: f32| {
        let e = (atan2(y, x) as f64 - (y as f64).atan2(x as f64)).abs();
        // On the negative x axis both π and −π are the same angle; ours returns π for y = −0.
        let e = e.min((e - 2.0 * std::f64::consts::PI).abs());
        if e > worst.0 {
            worst = (e, y, x);
        }
    };
    let n = 400_000;
    for &r in &[1e-6f64, 1e-2, 1.0, 37.0, 1e6] {
        for k in 0..n {
            let a = -std::f64::consts::PI + 2.0 * std::f64::consts::PI * k as f64 / n as f64;
            check((r * a.sin()) as f32, (r * a.cos()) as f32);
        }
    }
    for i in -300..=300 {
        for j in -300..=300 {
            check(i as f32 * 0.013, j as f32 * 0.017);
        }
    }
    println!(
        "atan2: worst absolute error {:.3e} rad at (y, x) = ({:e}, {:e})",
        worst.0, worst.1, worst.2
    );
    assert!(worst.0 < 3e-7, "worst {worst:?}");
}

#[test]
fn atan2_special_values_match_ieee_where_the_estimator_can_see_them() {
    assert_eq!(atan2(0.0, 1.0), 0.0);
    assert_eq!(atan2(0.0, 0.0), 0.0);
    assert_eq!(atan2(1.0, 0.0), std::f32::consts::FRAC_PI_2);
    assert_eq!(atan2(-1.0, 0.0), -std::f32::consts::FRAC_PI_2);
    assert_eq!(atan2(0.0, -1.0), std::f32::consts::PI);
    assert_eq!(atan2(1.0, 1.0), std::f32::consts::FRAC_PI_4);
    assert!(atan2(f32::NAN, 1.0).is_nan() && atan2(1.0, f32::NAN).is_nan());
    // Infinities go to libm's atan2f.
    assert!((atan2(f32::INFINITY, 1.0) - std::f32::consts::FRAC_PI_2).abs() < 1e-6);
    assert!((atan2(1.0, f32::NEG_INFINITY) - std::f32::consts::PI).abs() < 1e-6);
}

#[test]
fn sqrt_is_the_correctly_rounded_root_in_every_binade() {
    // The host replay and the firmware agree to the bit only if both round correctly
    // (the f64 root rounded to f32 is the correctly rounded f32 root: 53 ≥ 2·24 + 2).
    // 4,096 mantissas in each of the 254 normal binades, subnormals and the special inputs.
    let mut n = 0u64;
    for e in 0u32..255 {
        for m in 0..4096u32 {
            let x = f32::from_bits((e << 23) | (m << 11) | (m & 0x7ff));
            let want = (x as f64).sqrt() as f32;
            assert_eq!(sqrt(x).to_bits(), want.to_bits(), "sqrt({x:e})");
            n += 1;
        }
    }
    println!("sqrt: correctly rounded on all {n} inputs");
    assert_eq!(sqrt(0.0), 0.0);
    assert_eq!(sqrt(4.0), 2.0);
    assert!(sqrt(-1.0).is_nan() && sqrt(f32::NAN).is_nan());
    assert_eq!(sqrt(f32::INFINITY), f32::INFINITY);
}

/// The inline max/min give libm's `fmaxf`/`fminf` (what `f32::max`/`min` call on the M4F)
/// to the bit, signed zeros and NaN operands included: the filter's estimates do not move.
#[test]
fn max_and_min_are_fmaxf_and_fminf_to_the_bit() {
    let v = [
        0.0f32,
        -0.0,
        1.0,
        -1.0,
        1e-6,
        1e-40,
        -1e-40,
        f32::MAX,
        f32::MIN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
    ];
    for &a in &v {
        for &b in &v {
            let same = |x: f32, y: f32| x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan());
            assert!(same(max(a, b), libm::fmaxf(a, b)), "max({a}, {b})");
            assert!(same(min(a, b), libm::fminf(a, b)), "min({a}, {b})");
        }
    }
}
