//! The shared `a·sin x + b·cos x = c` solver (docs/design.md, sin/cos solver): roots satisfy the
//! equation, the one nearer the prediction is chosen, and edge cases are reported
//! instead of producing NaN.

use proptest::prelude::*;
use wing_ahrs::measure::solver::solve_sin_cos;

fn residual(a: f32, b: f32, c: f32, x: f32) -> f32 {
    a * x.sin() + b * x.cos() - c
}

#[test]
fn both_roots_solve_the_equation_and_nearest_is_chosen() {
    let (a, b) = (3.0f32, -4.0f32); // ρ = 5
    for &c in &[-4.9f32, -2.0, 0.0, 1.0, 4.99] {
        for &pred in &[-3.0f32, -1.0, 0.0, 1.0, 3.0] {
            let s = solve_sin_cos(a, b, c, pred, 1e-3).unwrap();
            assert!(!s.clamped);
            assert!(
                residual(a, b, c, s.x).abs() < 1e-4 && residual(a, b, c, s.other()).abs() < 1e-4
            );
            let d = |x: f32| wing_ahrs::math::wrap_pi(x - pred).abs();
            assert!(d(s.x) <= d(s.other()));
        }
    }
}

#[test]
fn c_beyond_radius_is_clamped_and_reported() {
    let s = solve_sin_cos(3.0, 4.0, 7.5, 0.0, 1e-3).unwrap();
    assert!(s.clamped);
    // Clamped to c = ρ: the single root x = atan2(a, b), where a sin x + b cos x = ρ.
    assert!((s.x - 3.0f32.atan2(4.0)).abs() < 1e-5 && (s.x - s.other()).abs() < 1e-5);
    let s = solve_sin_cos(3.0, 4.0, -7.5, 0.0, 1e-3).unwrap();
    assert!(s.clamped && residual(3.0, 4.0, -5.0, s.x).abs() < 1e-4);
}

#[test]
fn degenerate_radius_and_non_finite_inputs_give_no_measurement() {
    assert!(solve_sin_cos(0.0, 0.0, 0.0, 0.0, 1e-3).is_none());
    assert!(solve_sin_cos(1e-5, -1e-5, 0.0, 0.0, 1e-3).is_none());
    assert!(solve_sin_cos(f32::NAN, 1.0, 0.0, 0.0, 1e-3).is_none());
    assert!(solve_sin_cos(1.0, f32::INFINITY, 0.0, 0.0, 1e-3).is_none());
    assert!(solve_sin_cos(1.0, 1.0, f32::NAN, 0.0, 1e-3).is_none());
    assert!(solve_sin_cos(1.0, 1.0, 0.0, f32::NAN, 1e-3).is_none());
}

#[test]
fn tangent_case_gives_a_double_root() {
    // c = ρ exactly: both roots coincide.
    let s = solve_sin_cos(0.0, 2.0, 2.0, 0.5, 1e-3).unwrap();
    assert!(s.x.abs() < 1e-3 && s.other().abs() < 1e-3);
}

proptest! {
    #[test]
    fn recovers_any_angle_from_its_forward_value(x in -3.1f32..3.1, a in -20.0f32..20.0, b in -20.0f32..20.0) {
        prop_assume!((a * a + b * b).sqrt() > 0.5);
        let c = a * x.sin() + b * x.cos();
        // Predicting at the truth, the chosen root is the truth (unless both roots are
        // nearly equal, i.e. |c| ≈ ρ, where either is right).
        let s = solve_sin_cos(a, b, c, x, 1e-3).unwrap();
        let rho = (a * a + b * b).sqrt();
        let tol = if (c.abs() / rho) > 0.999 { 0.1 } else { 2e-3 };
        prop_assert!(wing_ahrs::math::wrap_pi(s.x - x).abs() < tol, "x={} got {} (other {})", x, s.x, s.other());
    }

    #[test]
    fn sin_cos_of_the_returned_root_matches_the_root(x in -3.1f32..3.1, a in -20.0f32..20.0, b in -20.0f32..20.0, dc in -0.5f32..0.5) {
        // Including |c| > ρ (clamped): the algebraic sine and cosine are those of the angle returned.
        prop_assume!((a * a + b * b).sqrt() > 0.5);
        let c = a * x.sin() + b * x.cos() + dc;
        let s = solve_sin_cos(a, b, c, 0.0, 1e-3).unwrap();
        let (sx, cx) = s.sin_cos;
        prop_assert!((sx - s.x.sin()).abs() < 2e-6 && (cx - s.x.cos()).abs() < 2e-6, "x={} sin_cos=({}, {})", s.x, sx, cx);
    }

    #[test]
    fn never_returns_nan(a in proptest::num::f32::ANY, b in proptest::num::f32::ANY, c in proptest::num::f32::ANY, p in proptest::num::f32::ANY) {
        if let Some(s) = solve_sin_cos(a, b, c, p, 1e-3) {
            prop_assert!(s.x.is_finite() && s.other().is_finite());
        }
    }
}
