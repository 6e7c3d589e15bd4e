//! Unit tests of `interp::vmath` (`src/interp/vmath.rs`).

use vstructc::interp::vmath::*;

fn rel(a: f32, b: f32) -> f32 {
    (a - b).abs() / b.abs().max(f32::MIN_POSITIVE)
}

#[test]
fn exp_matches_std() {
    for k in 0..=20_000 {
        let x = -87.0 + 175.0 * k as f32 / 20_000.0;
        assert!(
            rel(exp(x), x.exp()) < 4e-7,
            "exp({x}): {} vs {}",
            exp(x),
            x.exp()
        );
    }
    assert_eq!(exp(-100.0), 0.0);
    assert_eq!(exp(0.0), 1.0);
}

#[test]
fn log2_and_pow_match_std() {
    for k in 1..=20_000 {
        let x = (k as f32 / 20_000.0).powi(3) * 4.0;
        assert!(
            (log2(x) - x.log2()).abs() < 4e-7 * x.log2().abs().max(1.0),
            "log2({x})"
        );
        for y in [0.5, 1.0, 1.666_666_6, 3.0, 10.0] {
            let (a, b) = (pow_pos(x.min(1.0), y), x.min(1.0).powf(y));
            // Results below the normal range flush to 0.
            let ok = rel(a, b) < 2e-6 * (1.0 + y) || (b < 1e-37 && a < 1e-37);
            assert!(ok, "pow({x}, {y}): {a} vs {b}");
        }
    }
    assert_eq!(pow_pos(0.0, 2.0), 0.0);
    for k in -1000..=1000 {
        let x = k as f32 / 10.0;
        assert!(rel(exp2(x), x.exp2()) < 4e-7, "exp2({x})");
    }
}

#[test]
fn acos_matches_std() {
    for k in -20_000..=20_000 {
        let x = k as f32 / 20_000.0;
        assert!((acos(x) - x.acos()).abs() < 5e-7, "acos({x})");
    }
}
