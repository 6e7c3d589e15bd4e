//! The fused scalar prepare of uniform materials (what `Material::prepare` runs for a
//! material with constant registers and the point's own frame, seen from above) computes
//! the general algorithm's bits (`Material::prepare_general_into`): the same surviving
//! lobes with the same records, weights, albedos and selection probabilities, the same
//! emission and transparency, hence the same `eval` and `sample`. Covered over materials
//! that use every batched family, every tint mode, `mix`, `mul`, emission and
//! transparency; with lobes dropped, with two-sided lobes, and with views below the
//! horizon, where the fused form hands the point to the general path.

use crate::uniform_materials;
use glam::Vec3;
use uniform_materials::{
    assorted_ir, coated_ir, negative_ir, point, shared_ir, stacked_ir, textured_ir,
};
use vstructc::interp::*;
use vstructc::ir::MaterialIr;
use vstructc_testkit::reference::ref10_ir;
use vstructc_testkit::verify::Rng;

fn cases() -> [(&'static str, MaterialIr); 6] {
    [
        ("ref10", ref10_ir()),
        ("assorted", assorted_ir()),
        ("coated", coated_ir()),
        ("stacked", stacked_ir()),
        // A leaf reached by two paths: its weight sums two terms.
        ("shared", shared_ir()),
        // Weights the fused form must clean (a negative one, a huge one).
        ("negative", negative_ir()),
    ]
}

/// Every option set the fused form must honour: the default, no dropping, a threshold high
/// enough to drop lobes, two-sided lobes, and no lobe packs.
fn option_sets() -> [PrepareOptions; 5] {
    let d = PrepareOptions::default();
    [
        d,
        PrepareOptions {
            drop_threshold: 0.0,
            ..d
        },
        PrepareOptions {
            drop_threshold: 0.05,
            ..d
        },
        PrepareOptions {
            sides: Sides::Both,
            ..d
        },
        PrepareOptions {
            pack_lobes: false,
            ..d
        },
    ]
}

/// Asserts two preparations hold the same bits (`{:?}` prints every float exactly, and
/// `-0.0` apart from `0.0`).
fn assert_same(fused: &Prepared, general: &Prepared, rng: &mut Rng, label: &str) {
    assert_eq!(
        format!("{:?}", fused.lobes()),
        format!("{:?}", general.lobes()),
        "{label}: lobes"
    );
    let bits = |v: Vec3| v.to_array().map(f32::to_bits);
    assert_eq!(bits(fused.emission()), bits(general.emission()), "{label}");
    assert_eq!(
        bits(fused.transparency()),
        bits(general.transparency()),
        "{label}"
    );
    assert_eq!(
        format!("{:?}", fused.albedo()),
        format!("{:?}", general.albedo()),
        "{label}: albedo"
    );
    assert_eq!(
        fused.view().to_array(),
        general.view().to_array(),
        "{label}"
    );
    for _ in 0..8 {
        let l = rng.sphere();
        let (a, b) = (fused.eval(l), general.eval(l));
        assert_eq!(bits(a.f_cos), bits(b.f_cos), "{label}: eval at {l}");
        assert_eq!(a.pdf.to_bits(), b.pdf.to_bits(), "{label}: pdf at {l}");
        let u = [rng.f32(), rng.f32(), rng.f32()];
        assert_eq!(
            format!("{:?}", fused.sample(u)),
            format!("{:?}", general.sample(u)),
            "{label}: sample at {u:?}"
        );
    }
}

#[test]
fn fused_prepare_equals_general_bit_for_bit() {
    tables::init_all();
    for (name, ir) in cases() {
        for (o, options) in option_sets().into_iter().enumerate() {
            let m = Material::with_options(&ir, options).expect("compiles");
            assert!(
                m.prepares_uniform(),
                "{name} qualifies for the fused prepare"
            );
            let mut rng = Rng::new(97);
            let mut scratch = Scratch::default();
            let (mut fused, mut general) = (Prepared::new(), Prepared::new());
            let mut dropped = 0;
            for i in 0..300 {
                let p = point(&mut rng, i);
                m.prepare_unpacked_into(&p, &mut scratch, &mut fused);
                m.prepare_general_into(&p, &mut scratch, &mut general);
                dropped += m.leaves().len() - fused.lobes().len();
                assert_same(
                    &fused,
                    &general,
                    &mut rng,
                    &format!("{name} options {o} point {i}"),
                );
                // `prepare_into` is the same preparation with `eval`'s lobe packs planned from
                // the records (their sums agree to rounding, tests/interp/packs.rs).
                m.prepare_into(&p, &mut scratch, &mut fused);
                assert_eq!(
                    format!("{:?}", fused.lobes()),
                    format!("{:?}", general.lobes()),
                    "{name} options {o} point {i}: packed"
                );
            }
            if options.drop_threshold >= 0.05 {
                assert!(dropped > 0, "{name}: the high threshold drops some lobes");
            }
        }
    }
}

/// A record left by another material's prepare (other families at every index) is
/// overwritten completely: preparing into a used `Prepared` equals preparing into a new one.
#[test]
fn fused_prepare_overwrites_a_used_record() {
    tables::init_all();
    let ms: Vec<Material> = cases()
        .iter()
        .map(|(_, ir)| Material::new(ir).expect("compiles"))
        .collect();
    let mut rng = Rng::new(5);
    let mut scratch = Scratch::default();
    let mut used = Prepared::new();
    for i in 0..200 {
        let p = point(&mut rng, i);
        for m in &ms {
            m.prepare_into(&p, &mut scratch, &mut used);
            let fresh = m.prepare(&p);
            assert_same(&used, &fresh, &mut rng, &format!("{} point {i}", m.name()));
        }
    }
}

/// Preparing the same material (or a clone) into the same `Prepared` again refreshes its
/// records and lobe packs in place, writing only their view-dependent fields (and the
/// packs' weight and probability terms); that gives the bits of a fresh prepare. Another
/// material in between, a view from below (the general path) and dropped lobes each make
/// the next prepare write them whole.
#[test]
fn packs_refreshed_in_place_equal_packs_filled_afresh() {
    tables::init_all();
    let cases = cases();
    // Other materials that keep every lobe (so their packs carry their own stamps).
    let keep_all = PrepareOptions {
        drop_threshold: 0.0,
        ..PrepareOptions::default()
    };
    let others: Vec<Material> = cases
        .iter()
        .map(|(_, ir)| Material::with_options(ir, keep_all).expect("compiles"))
        .collect();
    for (name, ir) in &cases {
        for (o, options) in option_sets().into_iter().enumerate() {
            if !options.pack_lobes {
                continue;
            }
            let m = Material::with_options(ir, options).expect("compiles");
            let clone = m.clone();
            let mut rng = Rng::new(31);
            let mut scratch = Scratch::default();
            let mut reused = Prepared::new();
            for i in 0..300 {
                let p = point(&mut rng, i);
                if i % 7 == 0 {
                    others[i / 7 % others.len()].prepare_into(&p, &mut scratch, &mut reused);
                }
                let by = if i % 4 == 0 { &clone } else { &m };
                by.prepare_into(&p, &mut scratch, &mut reused);
                let afresh = m.prepare(&p);
                assert_same(
                    &reused,
                    &afresh,
                    &mut rng,
                    &format!("{name} options {o} point {i}"),
                );
            }
        }
    }
}

/// `layer[Rgb](mul(coat, 2), add(lambert(ρ = 0.3), mul(lambert(ρ = 1), 0.06)))`, whose
/// leaves are the faint Lambert, the grey one and the coat, in that order. Under the coat
/// the faint Lambert's weighted albedo is about 0.055 at normal views and 0.036 at
/// grazing ones, so a drop threshold of 0.05 drops it at grazing views only (the others
/// stay above 0.07), and the grey Lambert's record then moves into its slot.
fn droppy_ir() -> MaterialIr {
    use vstructc::ir::{IrBuilder, RecipeId, TintMode};
    use vstructc_testkit::reference::{dielectric_r_of, lambert, mul};
    let mut b = IrBuilder::new();
    let (ax, ay, eta, one) = (
        b.prog.constf(0.2),
        b.prog.constf(0.2),
        b.prog.constf(1.5),
        b.prog.constf(1.0),
    );
    let coat = dielectric_r_of(&mut b, [ax, ay, eta], one, "coat");
    let coat = mul(&mut b, coat, 2.0);
    let faint = lambert(&mut b, Vec3::ONE, "faint");
    let faint = mul(&mut b, faint, 0.06);
    let grey = lambert(&mut b, Vec3::splat(0.3), "grey");
    let base = b.add(grey, faint);
    let root = b.layer(coat, base, TintMode::Rgb);
    b.finish("droppy", RecipeId::Custom, root)
        .expect("valid IR")
}

/// A dropped lobe moves the records after it down, so a record of one family may sit in
/// the slot of another leaf of that family with other constants: the next prepare into
/// the same `Prepared` must write its records whole, not only their view-dependent fields.
#[test]
fn records_moved_by_a_drop_are_written_whole_at_the_next_point() {
    tables::init_all();
    let options = PrepareOptions {
        drop_threshold: 0.05,
        ..PrepareOptions::default()
    };
    let m = Material::with_options(&droppy_ir(), options).expect("compiles");
    assert!(m.prepares_uniform());
    let mut rng = Rng::new(3);
    let mut scratch = Scratch::default();
    let mut reused = Prepared::new();
    let (mut kept, mut dropped) = (0, 0);
    for i in 0..200 {
        let f = Frame::new(rng.sphere(), rng.sphere());
        // Normal and grazing views in turn.
        let mu: f32 = if i % 2 == 0 { 0.95 } else { 0.1 };
        let v = f.z * mu + f.x * (1.0 - mu * mu).sqrt();
        let p = ShadingPoint::new(f.z, f.x, v);
        m.prepare_into(&p, &mut scratch, &mut reused);
        match reused.lobes().len() {
            3 => kept += 1,
            2 => dropped += 1,
            n => panic!("{n} lobes at point {i}"),
        }
        let afresh = m.prepare(&p);
        assert_same(&reused, &afresh, &mut rng, &format!("droppy point {i}"));
    }
    assert!(kept > 0 && dropped > 0, "kept {kept}, dropped {dropped}");
}

/// A material whose parameters come from an input is not uniform: the general path
/// prepares it, whatever its inputs.
#[test]
fn materials_with_inputs_are_not_fused() {
    tables::init_all();
    let m = Material::new(&textured_ir()).expect("compiles");
    assert!(!m.is_uniform() && !m.prepares_uniform());
    let mut rng = Rng::new(11);
    let mut scratch = Scratch::default();
    let (mut a, mut b) = (Prepared::new(), Prepared::new());
    for i in 0..50 {
        let inputs = [rng.f32(), rng.f32(), rng.f32()];
        let p = point(&mut rng, i).with_inputs(&inputs);
        m.prepare_unpacked_into(&p, &mut scratch, &mut a);
        m.prepare_general_into(&p, &mut scratch, &mut b);
        assert_same(&a, &b, &mut rng, &format!("textured point {i}"));
        if !a.lobes().is_empty() {
            assert_eq!(
                a.lobes()[0].albedo.reflect.to_array(),
                inputs,
                "the input reaches the lobe"
            );
        }
    }
}
