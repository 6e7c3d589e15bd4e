//! The scalar entry points come in a baseline, an AVX2 and an AVX-512 version
//! (`vstructc::interp::simd`); `prepare_into`, `prepare_unpacked_into`, `eval` and
//! `eval_f_cos` run the AVX2 one where the CPU has it. Every version must compute the same
//! bits: the same prepared lobes, emission and transparency, and the same `eval`, for
//! uniform materials (the fused prepare, with and without lobe packs) and for a material
//! with inputs (the general prepare), from above and below the surface and at grazing views.

use crate::uniform_materials;
use glam::Vec3;
use uniform_materials::{assorted_ir, coated_ir, point, shared_ir, stacked_ir, textured_ir};
use vstructc::interp::simd::{Level, level};
use vstructc::interp::*;
use vstructc_testkit::reference::ref10_ir;
use vstructc_testkit::verify::Rng;

/// The levels this CPU can run, narrowest first.
fn levels() -> Vec<Level> {
    [Level::Baseline, Level::Avx2, Level::Avx512]
        .into_iter()
        .filter(|&l| l <= level())
        .collect()
}

fn bits(v: Vec3) -> [u32; 3] {
    v.to_array().map(f32::to_bits)
}

/// What a preparation holds, exactly (`{:?}` prints every float exactly).
fn fingerprint(p: &Prepared) -> String {
    format!(
        "{:?} {:?} {:?} {:?}",
        p.lobes(),
        bits(p.emission()),
        bits(p.transparency()),
        p.packed_lobe_count()
    )
}

#[test]
fn every_scalar_version_computes_the_same_bits() {
    tables::init_all();
    let levels = levels();
    if levels.len() == 1 {
        crate::common::not_run(
            "this CPU has no AVX2: only the baseline version runs, no other version to compare",
        );
    }
    let irs = [
        ref10_ir(),
        assorted_ir(),
        coated_ir(),
        stacked_ir(),
        shared_ir(),
        textured_ir(),
    ];
    let mut scratch = Scratch::default();
    for ir in &irs {
        for pack_lobes in [true, false] {
            let options = PrepareOptions {
                pack_lobes,
                ..PrepareOptions::default()
            };
            let m = Material::with_options(ir, options).expect("compiles");
            let mut rng = Rng::new(23);
            let mut base = Prepared::new();
            let mut other = Prepared::new();
            for i in 0..200 {
                let p = point(&mut rng, i);
                let ls: Vec<Vec3> = (0..4).map(|_| rng.sphere()).collect();
                let label = format!("{} packs {pack_lobes} point {i}", m.name());
                m.prepare_into_at(Level::Baseline, &p, &mut scratch, &mut base);
                for &at in &levels[1..] {
                    m.prepare_into_at(at, &p, &mut scratch, &mut other);
                    assert_eq!(fingerprint(&other), fingerprint(&base), "{label} at {at:?}");
                    m.prepare_unpacked_into_at(at, &p, &mut scratch, &mut other);
                    assert_eq!(
                        format!("{:?}", other.lobes()),
                        format!("{:?}", base.lobes()),
                        "{label}: unpacked at {at:?}"
                    );
                }
                for &l in &ls {
                    let e = base.eval_at(Level::Baseline, l);
                    let f = base.eval_f_cos_at(Level::Baseline, l);
                    for &at in &levels[1..] {
                        let (ea, fa) = (base.eval_at(at, l), base.eval_f_cos_at(at, l));
                        assert_eq!(bits(ea.f_cos), bits(e.f_cos), "{label}: eval at {at:?}");
                        assert_eq!(ea.pdf.to_bits(), e.pdf.to_bits(), "{label}: pdf {at:?}");
                        assert_eq!(bits(fa), bits(f), "{label}: f_cos at {at:?}");
                    }
                    // The default entry point is one of the versions.
                    assert_eq!(bits(base.eval(l).f_cos), bits(e.f_cos), "{label}: eval");
                }
            }
        }
    }
}
