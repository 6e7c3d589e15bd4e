//! Unit tests of `ir::program` (`src/ir/program.rs`).

use vstructc::glam::Vec3;
use vstructc::ir::program::*;

fn ctx() -> RunContext<'static> {
    RunContext {
        inputs: &[],
        mu_o: &[],
        globals: Globals::default(),
    }
}

#[test]
fn constants_fold_and_share() {
    let mut b = ProgramBuilder::new();
    let x = b.constf(2.0);
    let y = b.constf(3.0);
    let s = b.add(x, y);
    assert_eq!(b.constant(s), Some(Vec3::splat(5.0)));
    let again = b.constf(5.0);
    assert_eq!(s, again, "equal constants share a register");
}

#[test]
fn cse_shares_commutative_ops() {
    let mut b = ProgramBuilder::new();
    let i0 = b.input(0);
    let i1 = b.input(1);
    let a = b.mul(i0, i1);
    let c = b.mul(i1, i0);
    assert_eq!(a, c);
    let d = b.sub(i0, i1);
    let e = b.sub(i1, i0);
    assert_ne!(d, e, "sub is not commutative");
}

#[test]
fn identities() {
    let mut b = ProgramBuilder::new();
    let i0 = b.input(0);
    let one = b.constf(1.0);
    let zero = b.constf(0.0);
    assert_eq!(b.mul(i0, one), i0);
    assert_eq!(b.mul(i0, zero), zero);
    assert_eq!(b.add(zero, i0), i0);
    let i1 = b.input(1);
    assert_eq!(b.lerp(i0, i1, zero), i0);
    assert_eq!(b.lerp(i0, i1, one), i1);
    assert_eq!(b.select(one, i0, i1), i0);
    assert_eq!(b.select(zero, i0, i1), i1);
}

#[test]
fn div_by_zero_is_zero_and_inputs_are_not_folded() {
    let mut b = ProgramBuilder::new();
    let i0 = b.input(0);
    let z = b.constf(0.0);
    let d = b.div(i0, z);
    let p = b.finish();
    let regs = p.run(&RunContext {
        inputs: &[Vec3::splat(3.0)],
        ..ctx()
    });
    assert_eq!(regs[d.index()], Vec3::ZERO);
}

#[test]
fn fresnel_points_of_the_spec() {
    assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
    assert!((fresnel_dielectric(0.5, 1.5) - 0.0891867).abs() < 1e-6);
    assert!((fresnel_dielectric(0.1, 1.5) - 0.571593).abs() < 1e-5);
    assert_eq!(fresnel_dielectric(0.5, 1.0 / 1.5), 1.0);
    let gold = [
        (0.183, 3.424, 0.944221),
        (0.421, 2.346, 0.776152),
        (1.373, 1.770, 0.373348),
    ];
    for (n, k, f0) in gold {
        assert!((fresnel_conductor(1.0, n, k) - f0).abs() < 1e-5);
    }
    let mut b = ProgramBuilder::new();
    let f0 = b.constf(0.2);
    let f90 = b.constf(1.0);
    let q = b.constf(5.0);
    for (mu, want) in [(1.0, 0.2), (0.5, 0.225), (0.0, 1.0)] {
        let m = b.constf(mu);
        let r = b.schlick(m, f0, f90, q);
        assert!((b.constant(r).unwrap().x - want).abs() < 1e-6);
    }
}

#[test]
fn fresnel_average_fit() {
    assert!((fresnel_avg_dielectric(1.5) - 0.093101).abs() < 2e-4);
    assert!((fresnel_avg_dielectric(2.0) - 0.160684).abs() < 2e-4);
}

#[test]
fn rebuild_drops_dead_ops() {
    let mut b = ProgramBuilder::new();
    let i0 = b.input(0);
    let i1 = b.input(1);
    let _dead = b.mul(i0, i1);
    let live = b.add(i0, i1);
    let p = b.finish();
    let (q, map) = p.rebuild(&[live]);
    assert_eq!(q.len(), 3);
    assert!(map.contains_key(&live));
}

#[test]
fn value_noise_is_in_range_and_continuous() {
    for i in 0..100 {
        let p = Vec3::new(i as f32 * 0.37, i as f32 * 0.11, 0.5);
        let n = value_noise(p);
        assert!((0.0..=1.0).contains(&n));
        let m = value_noise(p + Vec3::splat(1e-4));
        assert!((n - m).abs() < 1e-2);
    }
}
