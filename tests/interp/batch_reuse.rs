//! A `PreparedBatch` re-prepared in place (`Material::prepare_batch_into`, what the batched
//! preview does for every 16 pixels) gives exactly what a fresh `prepare_batch` gives, also
//! when consecutive batches come from different materials (the slots' kernels then change
//! family); and the batched preview equals the scalar one.

use glam::Vec3;
use vstructc::interp::preview::{PreviewOptions, render_ball};
use vstructc::interp::*;
use vstructc::ir::{IrBuilder, RecipeId};
use vstructc_testkit::reference::{lambert, mul, ref10_ir};
use vstructc_testkit::verify::Rng;

const W: usize = 16;

fn random_batch(rng: &mut Rng) -> ShadingBatch<'static, W> {
    let n: [Vec3; W] = std::array::from_fn(|_| rng.sphere());
    ShadingBatch::new(
        n,
        std::array::from_fn(|_| rng.sphere()),
        std::array::from_fn(|k| {
            let v = rng.sphere();
            // Most views above the surface, some below (masked lanes).
            if v.dot(n[k]) < 0.0 && k % 4 != 0 {
                -v
            } else {
                v
            }
        }),
    )
}

#[test]
fn reused_batch_equals_fresh_batch() {
    let ref10 = Material::new(&ref10_ir()).expect("ref10 compiles");
    let mut b = IrBuilder::new();
    let l = lambert(&mut b, Vec3::new(0.7, 0.5, 0.3), "diffuse");
    let root = mul(&mut b, l, 0.8);
    let plain = Material::new(&b.finish("plain", RecipeId::Custom, root).expect("valid"))
        .expect("compiles");
    let mut rng = Rng::new(3);
    let mut scratch = Scratch::default();
    let mut reused = PreparedBatch::<W>::new_boxed();
    for round in 0..12 {
        let m = if round % 3 == 2 { &plain } else { &ref10 };
        let pts = random_batch(&mut rng);
        m.prepare_batch_into(&pts, &mut scratch, &mut reused);
        let fresh = m.prepare_batch(&pts);
        assert_eq!(reused.slot_count(), fresh.slot_count(), "round {round}");
        assert_eq!(reused.kernel_count(), fresh.kernel_count(), "round {round}");
        for _ in 0..8 {
            let ls: [Vec3; W] = std::array::from_fn(|_| rng.sphere());
            let (a, b) = (reused.eval(&ls), fresh.eval(&ls));
            for k in 0..W {
                assert_eq!(a[k], b[k], "round {round}, lane {k}");
            }
        }
    }
}

#[test]
fn batched_preview_equals_scalar_preview() {
    let m = Material::new(&ref10_ir()).expect("ref10 compiles");
    let opts = PreviewOptions {
        size: 48,
        parallel: false,
        ..PreviewOptions::default()
    };
    let scalar = render_ball(&m, &opts, &|_| {}).expect("valid preview options");
    let batched = render_ball(
        &m,
        &PreviewOptions {
            batched: true,
            ..opts.clone()
        },
        &|_| {},
    )
    .expect("valid preview options");
    for (k, (a, b)) in scalar.pixels.iter().zip(&batched.pixels).enumerate() {
        let tol = 1e-5 * a.max_element().max(1e-3);
        assert!(
            (*a - *b).abs().max_element() <= tol,
            "pixel {k}: {a} vs {b}"
        );
    }
}
