//! The random shading configurations the interpreter and leaf benches evaluate.

use vstructc::glam::Vec3;
use vstructc::interp::Frame;
use vstructc_testkit::verify::Rng;

/// How many (frame, V, L) triples a bench pass evaluates.
pub const PAIRS: usize = 4096;

/// [`PAIRS`] random (frame, V, L) triples from `seed`, in world space, V and L on the
/// frame's upper side.
pub fn pairs(seed: u64) -> Vec<(Frame, Vec3, Vec3)> {
    let mut rng = Rng::new(seed);
    (0..PAIRS)
        .map(|_| {
            let n = rng.sphere();
            let f = Frame::new(n, rng.sphere());
            let side = |d: Vec3| if d.dot(n) < 0.0 { -d } else { d };
            (f, side(rng.sphere()), side(rng.sphere()))
        })
        .collect()
}
