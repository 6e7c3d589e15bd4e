//! The lane-parallel prepare of uniform materials (`Material::prepare_batch_eval_into`, what
//! the batched preview runs) equals the scalar path lane by lane (spec closures.md §1.5:
//! relative 1e-5): evaluation, directional albedo, emission and transparency, over materials
//! that use every kernel family, every tint mode, `mix`, `mul`, emission and transparency,
//! with lobes dropped in some lanes and not in others. Batches it does not cover (a view
//! below some lane's horizon, a material with inputs) go through the general path, which
//! keeps the per-lane records.

use crate::lanes;
use crate::uniform_materials;
use glam::Vec3;
use lanes::assert_lanes_match;
use uniform_materials::{assorted_ir, coated_ir, negative_ir, shared_ir, textured_ir};
use vstructc::interp::*;
use vstructc_testkit::reference::ref10_ir;
use vstructc_testkit::verify::Rng;

const W: usize = 16;

/// `W` random points seen from above (`below`: lane indices seen from below instead).
fn batch<const W: usize>(rng: &mut Rng, below: &[usize]) -> ShadingBatch<'static, W> {
    let frames: [Frame; W] = std::array::from_fn(|_| Frame::new(rng.sphere(), rng.sphere()));
    let vs = std::array::from_fn(|k| {
        let v = rng.sphere();
        let up = v.dot(frames[k].z) > 0.0;
        if up != below.contains(&k) { v } else { -v }
    });
    ShadingBatch::new(
        std::array::from_fn(|k| frames[k].z),
        std::array::from_fn(|k| frames[k].x),
        vs,
    )
}

/// Relative 1e-5 with a floor of 1e-6, per channel.
fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() <= 1e-5 * b.abs().max_element().max(1e-6)
}

/// Compares `pb` with the scalar preparation of each lane of `pts`: eval at random
/// directions, albedo, emission, transparency.
fn assert_batch_matches<const W: usize>(
    m: &Material,
    pts: &ShadingBatch<W>,
    pb: &PreparedBatch<W>,
    rng: &mut Rng,
    label: &str,
) {
    let scalar: Vec<Prepared> = (0..W).map(|k| m.prepare(&pts.lane(k))).collect();
    for (k, s) in scalar.iter().enumerate() {
        let (a, e, t) = (s.albedo().total(), s.emission(), s.transparency());
        assert!(
            close(pb.albedo(k), a),
            "{label} lane {k}: albedo {} vs {a}",
            pb.albedo(k)
        );
        assert!(close(pb.emission(k), e), "{label} lane {k}: emission");
        assert!(
            close(pb.transparency(k), t),
            "{label} lane {k}: transparency"
        );
    }
    for _ in 0..20 {
        let ls: [Vec3; W] = std::array::from_fn(|k| {
            let l = rng.sphere();
            if l.dot(pts.n[k]) < 0.0 && rng.f32() < 0.8 {
                -l
            } else {
                l
            }
        });
        assert_lanes_match(&pb.eval(&ls), &scalar, &ls, label);
    }
}

#[test]
fn lane_parallel_prepare_equals_scalar() {
    lane_parallel_prepare_equals_scalar_at::<W>();
    // One lane is the scalar preview's path for uniform materials; four, a narrow batch.
    lane_parallel_prepare_equals_scalar_at::<1>();
    lane_parallel_prepare_equals_scalar_at::<4>();
}

fn lane_parallel_prepare_equals_scalar_at<const W: usize>() {
    tables::init_all();
    let cases = [
        ("ref10", ref10_ir()),
        ("assorted", assorted_ir()),
        ("coated", coated_ir()),
        // A leaf reached by two paths: its weight sums two terms.
        ("shared", shared_ir()),
        // Weights that need cleaning (a negative one, an overflowing one).
        ("negative", negative_ir()),
    ];
    for (name, ir) in cases {
        let m = Material::new(&ir).expect("compiles");
        assert!(m.prepares_lanes(), "{name} qualifies");
        let mut rng = Rng::new(41);
        let mut scratch = Scratch::default();
        let mut pb = PreparedBatch::<W>::new_boxed();
        for round in 0..25 {
            let pts = batch::<W>(&mut rng, &[]);
            m.prepare_batch_eval_into(&pts, &mut scratch, &mut pb);
            assert!(pb.lane(0).is_none(), "{name}: the lane-parallel path ran");
            assert_eq!(
                pb.kernel_count(),
                pb.slot_count(),
                "{name}: every slot has a kernel"
            );
            assert_batch_matches(&m, &pts, &pb, &mut rng, &format!("{name} round {round}"));
        }
    }
}

/// With a high drop threshold a lobe survives in some lanes and not in others: its slot is
/// masked there, and the albedos and selection probabilities cover the survivors only.
#[test]
fn lane_parallel_prepare_drops_per_lane() {
    tables::init_all();
    let opts = PrepareOptions {
        drop_threshold: 0.04,
        ..PrepareOptions::default()
    };
    let m = Material::with_options(&ref10_ir(), opts).expect("compiles");
    let mut rng = Rng::new(43);
    let mut scratch = Scratch::default();
    let mut pb = PreparedBatch::<W>::new_boxed();
    let mut mixed_counts = 0;
    for round in 0..25 {
        let pts = batch::<W>(&mut rng, &[]);
        m.prepare_batch_eval_into(&pts, &mut scratch, &mut pb);
        assert!(pb.lane(0).is_none(), "the lane-parallel path ran");
        let counts: Vec<usize> = (0..W)
            .map(|k| m.prepare(&pts.lane(k)).lobes().len())
            .collect();
        if counts.iter().any(|&c| c != counts[0]) {
            mixed_counts += 1;
        }
        assert_batch_matches(&m, &pts, &pb, &mut rng, &format!("dropping round {round}"));
    }
    assert!(
        mixed_counts > 0,
        "some batch drops a lobe in some lanes only"
    );
}

/// A lane seen from below, or a material with inputs, takes the general path (the records are
/// kept); a batch reused across both paths gives what a fresh one gives.
#[test]
fn batches_outside_the_lane_parallel_path_fall_back() {
    tables::init_all();
    let m = Material::new(&ref10_ir()).expect("compiles");
    let mut rng = Rng::new(47);
    let mut scratch = Scratch::default();
    let mut pb = PreparedBatch::<W>::new_boxed();
    for round in 0..12 {
        let below: &[usize] = if round % 2 == 0 { &[] } else { &[5] };
        let pts = batch(&mut rng, below);
        m.prepare_batch_eval_into(&pts, &mut scratch, &mut pb);
        assert_eq!(
            pb.lane(0).is_some(),
            !below.is_empty(),
            "round {round}: path"
        );
        assert_batch_matches(&m, &pts, &pb, &mut rng, &format!("round {round}"));
    }
    // Parameters from an input: not uniform, so never lane-parallel.
    let m = Material::new(&textured_ir()).expect("compiles");
    let pts = batch::<W>(&mut rng, &[]);
    m.prepare_batch_eval_into(&pts, &mut scratch, &mut pb);
    assert!(
        pb.lane(0).is_some(),
        "a material with inputs keeps the records"
    );
    assert_batch_matches(&m, &pts, &pb, &mut rng, "textured");
}

/// The preview's three ways of shading a pixel agree to relative 1e-5 (§1.5): the general
/// prepare one pixel at a time, the scalar path of a uniform material (the lane-parallel
/// prepare at one lane), and the batched path. Materials with inputs take the general
/// prepare on the scalar path.
#[test]
fn preview_paths_agree() {
    use vstructc::interp::preview::{PreviewOptions, render_ball};
    tables::init_all();
    let cases = [ref10_ir(), assorted_ir(), coated_ir(), textured_ir()];
    for ir in cases {
        let m = Material::new(&ir).expect("compiles");
        let base = PreviewOptions {
            size: 48,
            parallel: false,
            ..PreviewOptions::default()
        };
        let general = render_ball(
            &m,
            &PreviewOptions {
                general_prepare: true,
                ..base.clone()
            },
            &|_| {},
        )
        .expect("valid preview options");
        let scalar = render_ball(&m, &base, &|_| {}).expect("valid preview options");
        let batched = render_ball(
            &m,
            &PreviewOptions {
                batched: true,
                ..base.clone()
            },
            &|_| {},
        )
        .expect("valid preview options");
        let lit = general
            .pixels
            .iter()
            .filter(|p| p.max_element() > 0.1)
            .count();
        assert!(lit > 100, "{}: the ball is lit ({lit} pixels)", ir.name);
        for (k, g) in general.pixels.iter().enumerate() {
            for (path, img) in [("scalar", &scalar), ("batched", &batched)] {
                let p = img.pixels[k];
                assert!(
                    (p - *g).abs().max_element() <= 1e-5 * g.max_element().max(1e-3),
                    "{} pixel {k}: {path} {p} vs general {g}",
                    ir.name
                );
            }
        }
    }
}

/// `W` lights: each below lane `k`'s surface (`below`) or above it.
fn lights<const W: usize>(rng: &mut Rng, pts: &ShadingBatch<W>, below: bool) -> [Vec3; W] {
    std::array::from_fn(|k| {
        let l = rng.sphere();
        if (l.dot(pts.n[k]) < 0.0) == below {
            l
        } else {
            -l
        }
    })
}

/// A kernel slot whose lanes all see the light from below adds nothing (every kernel family
/// reflects only), and narrow batches skip it: the batch still equals the scalar path, zero
/// from the front, and, for lobes flipped to face a view from below, the flipped response.
#[test]
fn lights_below_every_lane() {
    fn at<const W: usize>() {
        let mut rng = Rng::new(97);
        let mut scratch = Scratch::default();
        let mut pb = PreparedBatch::<W>::new_boxed();
        for ir in [ref10_ir(), assorted_ir(), coated_ir()] {
            let m = Material::new(&ir).expect("compiles");
            for round in 0..20 {
                let pts = batch::<W>(&mut rng, &[]);
                m.prepare_batch_eval_into(&pts, &mut scratch, &mut pb);
                let scalar: Vec<Prepared> = (0..W).map(|k| m.prepare(&pts.lane(k))).collect();
                let ls = lights(&mut rng, &pts, true);
                let label = format!("{} W = {W} round {round}", ir.name);
                assert_lanes_match(&pb.eval(&ls), &scalar, &ls, &label);
                assert!(
                    pb.eval(&ls)
                        .iter()
                        .all(|e| e.f_cos == Vec3::ZERO && e.pdf == 0.0)
                );
            }
            // Two-sided: views from below flip the lobes, and light from below then reflects.
            let opts = PrepareOptions {
                sides: Sides::Both,
                ..PrepareOptions::default()
            };
            let m = Material::with_options(&ir, opts).expect("compiles");
            let all: Vec<usize> = (0..W).collect();
            let mut lit = 0;
            for round in 0..20 {
                let pts = batch::<W>(&mut rng, &all);
                m.prepare_batch_eval_into(&pts, &mut scratch, &mut pb);
                let scalar: Vec<Prepared> = (0..W).map(|k| m.prepare(&pts.lane(k))).collect();
                let ls = lights(&mut rng, &pts, true);
                let e = pb.eval(&ls);
                lit += e.iter().filter(|e| e.f_cos.max_element() > 0.0).count();
                let label = format!("{} flipped W = {W} round {round}", ir.name);
                assert_lanes_match(&e, &scalar, &ls, &label);
            }
            assert!(lit > 10 * W, "{}: flipped lobes respond ({lit})", ir.name);
        }
    }
    tables::init_all();
    at::<1>();
    at::<16>();
}

/// `Material::prepare_batch_f_cos_into` (the batched preview's prepare: no selection
/// probabilities) gives the same `f·μ_i`, albedo, emission and transparency as
/// `prepare_batch_eval_into`, bit for bit, with every materials' lanes prepared
/// lane-parallel and with views below a lane's horizon (the general path, densities kept);
/// `eval`'s pdf is NaN exactly where the probabilities were left out.
#[test]
fn prepare_without_densities_keeps_f_cos_and_albedo() {
    fn at<const W: usize>() {
        tables::init_all();
        for (name, ir) in [
            ("ref10", ref10_ir()),
            ("assorted", assorted_ir()),
            ("coated", coated_ir()),
        ] {
            let m = Material::new(&ir).expect("compiles");
            let mut rng = Rng::new(43);
            let mut scratch = Scratch::default();
            let (mut full, mut lean) = (
                PreparedBatch::<W>::new_boxed(),
                PreparedBatch::<W>::new_boxed(),
            );
            for round in 0..20 {
                // Every other round a view below the horizon in lane 0 (the general path).
                let below: &[usize] = if round % 2 == 1 { &[0] } else { &[] };
                let pts = batch::<W>(&mut rng, below);
                m.prepare_batch_eval_into(&pts, &mut scratch, &mut full);
                m.prepare_batch_f_cos_into(&pts, &mut scratch, &mut lean);
                let label = format!("{name} W={W} round {round}");
                let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                for k in 0..W {
                    assert_eq!(
                        bits(lean.albedo(k)),
                        bits(full.albedo(k)),
                        "{label}: albedo"
                    );
                    assert_eq!(bits(lean.emission(k)), bits(full.emission(k)), "{label}");
                    assert_eq!(
                        bits(lean.transparency(k)),
                        bits(full.transparency(k)),
                        "{label}"
                    );
                }
                for _ in 0..10 {
                    let ls: [Vec3; W] = std::array::from_fn(|_| rng.sphere());
                    let (want, got) = (full.eval(&ls), lean.eval_f_cos(&ls));
                    let lean_pdf = lean.eval(&ls);
                    for k in 0..W {
                        assert_eq!(bits(got[k]), bits(want[k].f_cos), "{label} lane {k}");
                        assert_eq!(
                            lean_pdf[k].pdf.is_nan(),
                            below.is_empty(),
                            "{label} lane {k}: pdf NaN only after the lane-parallel path"
                        );
                    }
                }
            }
        }
    }
    at::<16>();
    at::<1>();
}
