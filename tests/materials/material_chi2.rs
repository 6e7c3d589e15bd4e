//! χ² sampling test of whole materials (spec closures.md §5.5): the reference 10-lobe
//! material of §6.2 and every recipe at its definition's defaults, sampled by
//! `Prepared::sample` (one-sample MIS over the lobes) against the mixture density of
//! `Prepared::eval`, with the spec's sizes: 5 cosine-distributed views per material (odd ones
//! from below), 10⁶ samples each, the Šidák correction over every run. A delta choice
//! (specular delta, transparency) has no density: it counts as a sample outside the pdf,
//! whose mass is then below one by that choice's probability. The per-sample consistency of
//! `sample` with `eval` and the mean weight against `albedo()` are in tests/interp/material.rs.
//! Run optimised, as the leaf suite: `cargo test --release` (and CI); ignored by a debug
//! `cargo test`.

use crate::common;

use glam::Vec3;
use vstructc::interp::{Material, ShadingPoint};
use vstructc::ir::MaterialIr;
use vstructc_testkit::reference::ref10_ir;
use vstructc_testkit::verify::{Chi2Config, Rng, chi2_test, sidak};

const VIEWS: usize = 5;

fn materials() -> Vec<(String, MaterialIr)> {
    let mut out = vec![("ref10".to_string(), ref10_ir())];
    for shader in common::RECIPES {
        out.push((shader.to_string(), common::recipe_at_defaults(shader)));
    }
    out
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "spec-sized statistical suite: runs with `cargo test --release`"
)]
fn chi2_every_material() {
    let materials = materials();
    let cfg = Chi2Config::default();
    let level = sidak(0.01, materials.len() * VIEWS);
    let mut failures = Vec::new();
    for (mi, (name, ir)) in materials.iter().enumerate() {
        let m = Material::new(ir).expect("compiles");
        let mut rng = Rng::new(500 + mi as u64);
        for vi in 0..VIEWS {
            let mut v = rng.cosine();
            if vi % 2 == 1 {
                v.z = -v.z;
            }
            let p = m.prepare(&ShadingPoint::new(Vec3::Z, Vec3::X, v));
            let out = chi2_test(
                |u| p.sample(u).filter(|s| !s.delta).map(|s| s.l),
                |l| f64::from(p.eval(l).pdf),
                &cfg,
                (mi * VIEWS + vi) as u64 + 9000,
            );
            if !out.passes(level, cfg.samples) {
                failures.push(format!(
                    "{name} (view {vi}: {v}): χ² {:.1} dof {} p {:.3e} (level {level:.2e}), \
                     zero-cell hits {}",
                    out.stat, out.dof, out.p_value, out.zero_cell_hits
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
