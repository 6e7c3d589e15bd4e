//! The batched evaluation of the reference material `ref10` equals the scalar path lane by
//! lane (spec closures.md §1.5: relative 1e-5), with every slot on its SoA kernel. ref10's
//! leaf weights and probabilities differ between lanes (the layers' albedo scaling depends
//! on V), so this also checks the weights the kernels fold into their constants; lanes
//! whose view is below the surface (one-sided lobes masked, dielectrics flipped) are mixed
//! in.

use crate::lanes;
use glam::Vec3;
use lanes::{assert_lanes_match, random_frames_and_views};
use vstructc::interp::*;
use vstructc_testkit::reference::ref10_ir;
use vstructc_testkit::verify::Rng;

const W: usize = 16;

#[test]
fn ref10_batch_equals_scalar() {
    tables::init_all();
    let m = Material::new(&ref10_ir()).expect("ref10 compiles");
    let mut rng = Rng::new(17);
    let mut scratch = Scratch::default();
    let mut reused = PreparedBatch::<W>::new_boxed();
    let mut masked = 0;
    for round in 0..30 {
        // Every fourth lane sees the surface from below.
        let (frames, vs) = random_frames_and_views::<W>(&mut rng);
        let pts = ShadingBatch::<W>::new(
            std::array::from_fn(|k| frames[k].z),
            std::array::from_fn(|k| frames[k].x),
            vs,
        );
        // Alternate a fresh batch and one re-prepared in place (kernels refilled).
        let fresh;
        let pb: &PreparedBatch<W> = if round % 2 == 0 {
            fresh = m.prepare_batch(&pts);
            &fresh
        } else {
            m.prepare_batch_into(&pts, &mut scratch, &mut reused);
            &reused
        };
        assert_eq!(
            pb.kernel_count(),
            pb.slot_count(),
            "every ref10 slot has a kernel"
        );
        // A view below the surface drops the one-sided lobes in that lane (the two-sided
        // dielectrics flip instead): those slots run with the lane masked.
        masked += (0..W)
            .filter(|&k| pb.lane(k).expect("a full batch").lobes().len() < 10)
            .count();
        let scalar: Vec<Prepared> = (0..W).map(|k| m.prepare(&pts.lane(k))).collect();
        for _ in 0..20 {
            let ls: [Vec3; W] = std::array::from_fn(|k| {
                let l = rng.sphere();
                if l.dot(frames[k].z) < 0.0 && rng.f32() < 0.8 {
                    -l
                } else {
                    l
                }
            });
            assert_lanes_match(&pb.eval(&ls), &scalar, &ls, &format!("round {round}"));
        }
    }
    assert!(masked > 0, "some slots have masked lanes");
}

/// The whole ref10 batch gives the same bits at every vector extension (`interp::simd`).
#[test]
fn ref10_batch_levels_agree_bit_for_bit() {
    use vstructc::interp::simd::Level;
    tables::init_all();
    let m = Material::new(&ref10_ir()).expect("ref10 compiles");
    let mut rng = Rng::new(29);
    for _ in 0..10 {
        let (frames, vs) = random_frames_and_views::<W>(&mut rng);
        let pts = ShadingBatch::<W>::new(
            std::array::from_fn(|k| frames[k].z),
            std::array::from_fn(|k| frames[k].x),
            vs,
        );
        let pb = m.prepare_batch(&pts);
        for _ in 0..10 {
            let ls: [Vec3; W] = std::array::from_fn(|_| rng.sphere());
            let bits =
                |e: &[Eval; W]| e.map(|e| (e.f_cos.to_array().map(f32::to_bits), e.pdf.to_bits()));
            let base = bits(&pb.eval_at(Level::Baseline, &ls));
            assert_eq!(bits(&pb.eval_at(Level::Avx2, &ls)), base, "avx2");
            assert_eq!(bits(&pb.eval_at(Level::Avx512, &ls)), base, "avx512");
        }
    }
}

/// `PreparedBatch::eval_f_cos` (the kernels without their densities, as the batched preview
/// runs them) gives `eval`'s `f_cos` bit for bit, at every vector extension, for batches
/// prepared lane-parallel and for batches with views below the surface (general prepare,
/// flipped dielectrics).
#[test]
fn ref10_batch_f_cos_alone_equals_eval() {
    use vstructc::interp::simd::Level;
    tables::init_all();
    let m = Material::new(&ref10_ir()).expect("ref10 compiles");
    let mut rng = Rng::new(31);
    let mut scratch = Scratch::default();
    let mut pb = PreparedBatch::<W>::new_boxed();
    for round in 0..20 {
        let (frames, mut vs) = random_frames_and_views::<W>(&mut rng);
        if round % 2 == 0 {
            // Every view above its surface: the lane-parallel prepare.
            for (v, f) in vs.iter_mut().zip(&frames) {
                if v.dot(f.z) <= 0.0 {
                    *v = -*v;
                }
            }
        }
        let pts = ShadingBatch::<W>::new(
            std::array::from_fn(|k| frames[k].z),
            std::array::from_fn(|k| frames[k].x),
            vs,
        );
        m.prepare_batch_eval_into(&pts, &mut scratch, &mut pb);
        for _ in 0..10 {
            let ls: [Vec3; W] = std::array::from_fn(|_| rng.sphere());
            for level in [Level::Baseline, Level::Avx2, Level::Avx512] {
                let want = pb
                    .eval_at(level, &ls)
                    .map(|e| e.f_cos.to_array().map(f32::to_bits));
                let got = pb
                    .eval_f_cos_at(level, &ls)
                    .map(|f| f.to_array().map(f32::to_bits));
                assert_eq!(got, want, "round {round}, {level:?}");
            }
        }
    }
}
