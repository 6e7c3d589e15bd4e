//! Shared by the batched-evaluation tests: a batch's per-lane results against the scalar
//! path, at the tolerance of spec closures.md §1.5 (relative 1e-5, floor 1e-6).

use glam::Vec3;
use vstructc::interp::{Eval, Frame, Prepared};
use vstructc_testkit::verify::Rng;

/// `W` random frames and views; every fourth lane (`k % 4 == 0`) sees its surface from below
/// (one-sided lobes masked, two-sided ones flipped), the others from above.
#[allow(dead_code)] // not every test that includes this file uses every helper
pub fn random_frames_and_views<const W: usize>(rng: &mut Rng) -> ([Frame; W], [Vec3; W]) {
    let frames: [Frame; W] = std::array::from_fn(|_| Frame::new(rng.sphere(), rng.sphere()));
    let views = std::array::from_fn(|k| {
        let v = rng.sphere();
        let up = v.dot(frames[k].z) >= 0.0;
        if up == (k % 4 != 0) { v } else { -v }
    });
    (frames, views)
}

/// Asserts `batched[k]` equals `scalar[k].eval(ls[k])` for every lane; `label` names the case
/// in failure messages.
pub fn assert_lanes_match<const W: usize>(
    batched: &[Eval; W],
    scalar: &[Prepared],
    ls: &[Vec3; W],
    label: &str,
) {
    let tol = |x: f32| 1e-5 * x.abs().max(1e-6);
    for k in 0..W {
        let s = scalar[k].eval(ls[k]);
        let b = batched[k];
        assert!(
            (b.f_cos - s.f_cos).abs().max_element() <= tol(s.f_cos.max_element()),
            "{label} lane {k}: {} vs {}",
            b.f_cos,
            s.f_cos
        );
        assert!(
            (b.pdf - s.pdf).abs() <= tol(s.pdf),
            "{label} lane {k}: pdf {} vs {}",
            b.pdf,
            s.pdf
        );
    }
}
