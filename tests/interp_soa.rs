//! The batched SoA GGX dielectric lobe equals the scalar leaf (spec closures.md §1.5:
//! relative 1e-5).

use glam::Vec3;
use vstructc::interp::soa::{DielectricRBatch, Vec3x};
use vstructc::interp::verify::Rng;
use vstructc::interp::*;

#[test]
fn batch_equals_scalar() {
    const W: usize = 16;
    let mut rng = Rng::new(11);
    for _ in 0..200 {
        let mut batch = DielectricRBatch::<W> {
            ax: [0.0; W],
            ay: [0.0; W],
            eta: [0.0; W],
            tint: Vec3x::zero(),
        };
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
            let lobe = Lobe::Dielectric(Dielectric {
                tint_r: batch.tint.get(k),
                ..Dielectric::new(
                    Ggx::new(batch.ax[k], batch.ay[k]),
                    Masking::HeightCorrelated,
                    batch.eta[k],
                    DielectricMode::R,
                )
            });
            let want = lobe.prepare(v.get(k), Sides::Front).eval(l.get(k)).f_cos;
            let got = out.get(k);
            assert!(
                (got - want).abs().max_element() <= 1e-5 * want.max_element() + 1e-12,
                "lane {k}: {got} vs {want}"
            );
        }
    }
}
