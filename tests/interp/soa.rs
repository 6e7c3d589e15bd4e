//! The batched SoA GGX dielectric lobe equals the scalar leaf (spec closures.md §1.5:
//! relative 1e-5).

use glam::Vec3;
use vstructc::interp::soa::{DielectricRBatch, Vec3x};
use vstructc::interp::*;
use vstructc_testkit::verify::Rng;

const W: usize = 16;

/// One lane's parameters and directions.
struct Lane {
    ax: f32,
    ay: f32,
    eta: f32,
    tint: Vec3,
    v: Vec3,
    l: Vec3,
}

/// A batch with its views and lights, lane `k` drawn by `lane(rng, k)`.
fn random_batch(
    rng: &mut Rng,
    mut lane: impl FnMut(&mut Rng, usize) -> Lane,
) -> (DielectricRBatch<W>, Vec3x<W>, Vec3x<W>) {
    let mut batch = DielectricRBatch {
        ax: [0.0; W],
        ay: [0.0; W],
        eta: [0.0; W],
        tint: Vec3x::zero(),
    };
    let (mut v, mut l) = (Vec3x::<W>::zero(), Vec3x::<W>::zero());
    for k in 0..W {
        let x = lane(rng, k);
        batch.ax[k] = x.ax;
        batch.ay[k] = x.ay;
        batch.eta[k] = x.eta;
        batch.tint.set(k, x.tint);
        v.set(k, x.v);
        l.set(k, x.l);
    }
    (batch, v, l)
}

/// Lane `k` of `batch` evaluated by the scalar leaf: the reference.
fn scalar_lane(batch: &DielectricRBatch<W>, k: usize, v: &Vec3x<W>, l: &Vec3x<W>) -> Vec3 {
    let lobe = Lobe::Dielectric(Dielectric {
        tint_r: batch.tint.get(k),
        ..Dielectric::new(
            Ggx::new(batch.ax[k], batch.ay[k]),
            Masking::HeightCorrelated,
            batch.eta[k],
            DielectricMode::R,
        )
    });
    lobe.prepare(v.get(k), Sides::Front).eval(l.get(k)).f_cos
}

/// Asserts lane `k` of `out` equals the scalar leaf to relative 1e-5.
fn assert_lane_matches(
    batch: &DielectricRBatch<W>,
    out: &Vec3x<W>,
    (v, l): (&Vec3x<W>, &Vec3x<W>),
    k: usize,
    label: &str,
) {
    let want = scalar_lane(batch, k, v, l);
    let got = out.get(k);
    assert!(
        (got - want).abs().max_element() <= 1e-5 * want.max_element() + 1e-12,
        "{label} lane {k}: {got} vs {want}"
    );
}

fn random_tint(rng: &mut Rng) -> Vec3 {
    Vec3::new(rng.f32(), rng.f32(), rng.f32())
}

#[test]
fn batch_equals_scalar() {
    let mut rng = Rng::new(11);
    for round in 0..200 {
        let (batch, v, l) = random_batch(&mut rng, |rng, _| {
            let (ax, ay) = (0.01 + 0.99 * rng.f32(), 0.01 + 0.99 * rng.f32());
            let eta = 1.0 + 2.0 * rng.f32();
            let tint = random_tint(rng);
            let s = rng.sphere();
            let v = Vec3::new(s.x, s.y, s.z.abs());
            let l = rng.sphere();
            Lane {
                ax,
                ay,
                eta,
                tint,
                v,
                l,
            }
        });
        let out = batch.eval(&v, &l);
        for k in 0..W {
            assert_lane_matches(&batch, &out, (&v, &l), k, &format!("round {round}"));
        }
    }
}

/// Lanes below the surface (either direction) give exactly 0, total internal reflection
/// (η < 1) and the narrowest widths the batch takes (1e-3) still equal the scalar leaf.
#[test]
fn batch_masked_lanes_tir_and_narrow_widths() {
    let mut rng = Rng::new(23);
    for round in 0..200 {
        let (batch, v, l) = random_batch(&mut rng, |rng, k| {
            let narrow = k % 3 == 0;
            let mut a = || {
                if narrow {
                    1e-3 + 0.02 * rng.f32()
                } else {
                    1e-3 + rng.f32()
                }
            };
            let (ax, ay) = (a(), a());
            let eta = 0.5 + 2.5 * rng.f32();
            let tint = random_tint(rng);
            let s = rng.sphere();
            // Lane 1 mod 4: V below; lane 2 mod 4: L anywhere (half below).
            let vz = if k % 4 == 1 { -s.z.abs() } else { s.z.abs() };
            let d = rng.sphere();
            let l = if k % 4 == 2 {
                d
            } else {
                Vec3::new(d.x, d.y, d.z.abs())
            };
            let v = Vec3::new(s.x, s.y, vz);
            Lane {
                ax,
                ay,
                eta,
                tint,
                v,
                l,
            }
        });
        let out = batch.eval(&v, &l);
        for k in 0..W {
            if v.z[k] <= 0.0 || l.z[k] <= 0.0 {
                assert_eq!(out.get(k), Vec3::ZERO, "round {round} lane {k}: masked");
                continue;
            }
            assert_lane_matches(&batch, &out, (&v, &l), k, &format!("round {round}"));
        }
    }
}

/// Every vector extension the batch can run with gives the same bits (`interp::simd`): the
/// versions differ only in vector width, never in the per-lane operations.
#[test]
fn batch_levels_agree_bit_for_bit() {
    use vstructc::interp::simd::{Level, level};
    if level() == Level::Baseline {
        crate::common::not_run(
            "this CPU has no AVX2: only the baseline version runs, no other version to compare",
        );
    }
    let mut rng = Rng::new(23);
    for _ in 0..100 {
        let (batch, v, l) = random_batch(&mut rng, |rng, _| {
            let (ax, ay) = (0.001 + rng.f32(), 0.001 + rng.f32());
            let eta = 0.3 + 2.7 * rng.f32();
            let tint = Vec3::splat(rng.f32());
            let (v, l) = (rng.sphere(), rng.sphere());
            Lane {
                ax,
                ay,
                eta,
                tint,
                v,
                l,
            }
        });
        let view = batch.view(&v);
        let base = view.eval_at(Level::Baseline, &l);
        for at in [Level::Avx2, Level::Avx512] {
            let got = view.eval_at(at, &l);
            for k in 0..W {
                assert_eq!(
                    got.get(k).to_array().map(f32::to_bits),
                    base.get(k).to_array().map(f32::to_bits),
                    "lane {k} at {}",
                    at.name()
                );
            }
        }
    }
}
