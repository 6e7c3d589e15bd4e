//! The batched SoA GGX dielectric lobe equals the scalar leaf (spec closures.md §1.5:
//! relative 1e-5).

use glam::Vec3;
use vstructc::interp::soa::{DielectricRBatch, Vec3x};
use vstructc::interp::verify::Rng;
use vstructc::interp::*;

const W: usize = 16;

fn empty_batch() -> DielectricRBatch<W> {
    DielectricRBatch {
        ax: [0.0; W],
        ay: [0.0; W],
        eta: [0.0; W],
        tint: Vec3x::zero(),
    }
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

#[test]
fn batch_equals_scalar() {
    let mut rng = Rng::new(11);
    for _ in 0..200 {
        let mut batch = empty_batch();
        let (mut v, mut l) = (Vec3x::<W>::zero(), Vec3x::<W>::zero());
        for k in 0..W {
            batch.ax[k] = 0.01 + 0.99 * rng.f32();
            batch.ay[k] = 0.01 + 0.99 * rng.f32();
            batch.eta[k] = 1.0 + 2.0 * rng.f32();
            batch
                .tint
                .set(k, Vec3::new(rng.f32(), rng.f32(), rng.f32()));
            let s = rng.sphere();
            v.set(k, Vec3::new(s.x, s.y, s.z.abs()));
            l.set(k, rng.sphere());
        }
        let out = batch.eval(&v, &l);
        for k in 0..W {
            let want = scalar_lane(&batch, k, &v, &l);
            let got = out.get(k);
            assert!(
                (got - want).abs().max_element() <= 1e-5 * want.max_element() + 1e-12,
                "lane {k}: {got} vs {want}"
            );
        }
    }
}

/// Lanes below the surface (either direction) give exactly 0, total internal reflection
/// (η < 1) and the narrowest widths the batch takes (1e-3) still equal the scalar leaf.
#[test]
fn batch_masked_lanes_tir_and_narrow_widths() {
    let mut rng = Rng::new(23);
    for round in 0..200 {
        let mut batch = empty_batch();
        let (mut v, mut l) = (Vec3x::<W>::zero(), Vec3x::<W>::zero());
        for k in 0..W {
            let narrow = k % 3 == 0;
            let a = |r: &mut Rng| {
                if narrow {
                    1e-3 + 0.02 * r.f32()
                } else {
                    1e-3 + r.f32()
                }
            };
            batch.ax[k] = a(&mut rng);
            batch.ay[k] = a(&mut rng);
            batch.eta[k] = 0.5 + 2.5 * rng.f32();
            batch
                .tint
                .set(k, Vec3::new(rng.f32(), rng.f32(), rng.f32()));
            let s = rng.sphere();
            // Lane 1 mod 4: V below; lane 2 mod 4: L anywhere (half below).
            let vz = if k % 4 == 1 { -s.z.abs() } else { s.z.abs() };
            v.set(k, Vec3::new(s.x, s.y, vz));
            let d = rng.sphere();
            l.set(
                k,
                if k % 4 == 2 {
                    d
                } else {
                    Vec3::new(d.x, d.y, d.z.abs())
                },
            );
        }
        let out = batch.eval(&v, &l);
        for k in 0..W {
            let got = out.get(k);
            if v.z[k] <= 0.0 || l.z[k] <= 0.0 {
                assert_eq!(got, Vec3::ZERO, "round {round} lane {k}: masked");
                continue;
            }
            let want = scalar_lane(&batch, k, &v, &l);
            assert!(
                (got - want).abs().max_element() <= 1e-5 * want.max_element() + 1e-12,
                "round {round} lane {k}: {got} vs {want}"
            );
        }
    }
}

/// Every vector extension the batch can run with gives the same bits (`interp::simd`): the
/// versions differ only in vector width, never in the per-lane operations.
#[test]
fn batch_levels_agree_bit_for_bit() {
    use vstructc::interp::simd::{Level, level};
    println!("widest level on this CPU: {}", level().name());
    let mut rng = Rng::new(23);
    for _ in 0..100 {
        let mut batch = empty_batch();
        let (mut v, mut l) = (Vec3x::<W>::zero(), Vec3x::<W>::zero());
        for k in 0..W {
            batch.ax[k] = 0.001 + rng.f32();
            batch.ay[k] = 0.001 + rng.f32();
            batch.eta[k] = 0.3 + 2.7 * rng.f32();
            batch.tint.set(k, Vec3::splat(rng.f32()));
            v.set(k, rng.sphere());
            l.set(k, rng.sphere());
        }
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
