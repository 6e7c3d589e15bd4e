//! Leaf API rules (spec closures.md §0, §2.4, §3): hemispheres and two-sidedness, classes,
//! delta lobes, pass-through leaves, frames.

use glam::Vec3;
use vstructc::interp::diffuse::{Lambert, OrenNayar, OrenNayarVariant};
use vstructc::interp::*;

fn lambert() -> Lobe {
    Lobe::Lambert(Lambert { rho: Vec3::ONE })
}

#[test]
fn one_sided_lobes_are_zero_from_below_two_sided_flip() {
    let v = Vec3::new(0.3, 0.2, 0.9).normalize();
    let l = Vec3::new(-0.4, 0.1, 0.8).normalize();
    let below = |w: Vec3| Vec3::new(w.x, -w.y, -w.z);
    let lobes = [
        lambert(),
        Lobe::OrenNayar(OrenNayar {
            rho: Vec3::ONE,
            sigma: 0.5,
            variant: OrenNayarVariant::Energy,
        }),
        Lobe::MicrofacetR(MicrofacetR {
            ggx: Ggx::new(0.2, 0.4),
            masking: Masking::HeightCorrelated,
            fresnel: Fresnel::One,
            comp: Compensation::None,
        }),
        Lobe::SheenLTC(SheenLTC { r: 0.4 }),
    ];
    for lobe in lobes {
        let front = lobe.prepare(v, Sides::Front).eval(l);
        assert!(front.f_cos.x > 0.0);
        // Seen from below, one-sided: inactive.
        let p = lobe.prepare(below(v), Sides::Front);
        assert!(p.is_inactive());
        assert_eq!(p.eval(below(l)).f_cos, Vec3::ZERO);
        assert!(p.sample([0.3, 0.6, 0.5]).is_none());
        // Two-sided: the flipped configuration gives the same value, samples come back below.
        let p = lobe.prepare(below(v), Sides::Both);
        assert!(p.is_flipped());
        let back = p.eval(below(l));
        assert!(
            (back.f_cos - front.f_cos).abs().max_element() < 1e-6
                && (back.pdf - front.pdf).abs() < 1e-5
        );
        let s = p.sample([0.3, 0.6, 0.5]).expect("sample");
        assert!(s.l.z < 0.0);
        // Reflection lobes are zero for light on the other side.
        assert_eq!(
            lobe.prepare(v, Sides::Front).eval(below(l)).f_cos,
            Vec3::ZERO
        );
    }
    // Grazing view: inactive.
    assert!(lambert().prepare(Vec3::X, Sides::Both).is_inactive());
}

#[test]
fn classes_follow_the_spec() {
    let gold = Fresnel::Conductor {
        eta: Vec3::splat(0.2),
        kappa: Vec3::splat(3.0),
    };
    let mf = |fresnel| {
        Lobe::MicrofacetR(MicrofacetR {
            ggx: Ggx::isotropic(0.3),
            masking: Masking::HeightCorrelated,
            fresnel,
            comp: Compensation::None,
        })
    };
    let diel = |mode| {
        Lobe::Dielectric(Dielectric::new(
            Ggx::isotropic(0.3),
            Masking::HeightCorrelated,
            1.5,
            mode,
        ))
    };
    assert_eq!(lambert().class(), LobeClass::Opaque);
    assert_eq!(mf(gold).class(), LobeClass::Opaque);
    assert_eq!(
        mf(Fresnel::Schlick {
            f0: Vec3::splat(0.04),
            f90: Vec3::ONE,
            q: 5.0
        })
        .class(),
        LobeClass::Layerable
    );
    assert_eq!(diel(DielectricMode::R).class(), LobeClass::Layerable);
    assert_eq!(diel(DielectricMode::T).class(), LobeClass::Opaque);
    assert_eq!(diel(DielectricMode::Rt).class(), LobeClass::Opaque);
    assert_eq!(
        Lobe::SheenCK(SheenCK {
            r: 0.3,
            masking: SheenMasking::MaterialX
        })
        .class(),
        LobeClass::Layerable
    );
    assert_eq!(
        Lobe::Emission(Emission {
            radiance: Vec3::ONE
        })
        .class(),
        LobeClass::PassThrough
    );
    assert_eq!(
        Lobe::Transparent(Transparent { tint: Vec3::ONE }).class(),
        LobeClass::PassThrough
    );
    assert!(
        Lobe::SubsurfaceProxy(Lambert { rho: Vec3::ONE })
            .prepare(Vec3::Z, Sides::Front)
            .is_subsurface()
    );
    assert_eq!(LobeKind::MicrofacetR.name(), "microfacet_r");
}

#[test]
fn delta_lobes_sample_mirror_and_refraction() {
    let v = Vec3::new(0.6, 0.0, 0.8);
    let m = Lobe::MicrofacetR(MicrofacetR {
        ggx: Ggx::isotropic(5e-4),
        masking: Masking::HeightCorrelated,
        fresnel: Fresnel::Dielectric { eta: 1.5 },
        comp: Compensation::None,
    })
    .prepare(v, Sides::Front);
    assert!(m.is_delta());
    assert_eq!(m.eval(Vec3::new(-0.6, 0.0, 0.8)).f_cos, Vec3::ZERO);
    let s = m.sample([0.1, 0.2, 0.3]).expect("delta sample");
    assert!(s.delta && (s.l - Vec3::new(-0.6, 0.0, 0.8)).length() < 1e-6);
    let f = fresnel::dielectric(0.8, 1.5);
    assert!((s.weight.x - f).abs() < 1e-6 && (m.albedo().reflect.x - f).abs() < 1e-6);
    let d = Lobe::Dielectric(Dielectric::new(
        Ggx::isotropic(0.0),
        Masking::HeightCorrelated,
        1.5,
        DielectricMode::Rt,
    ))
    .prepare(v, Sides::Front);
    let p_r = f / (f + (1.0 - f));
    let r = d.sample([0.0, 0.0, 0.5 * p_r]).expect("reflection");
    let t = d.sample([0.0, 0.0, 0.5 + 0.5 * p_r]).expect("refraction");
    assert!(r.delta && t.delta && r.l.z > 0.0 && t.l.z < 0.0);
    assert!((r.pdf - p_r).abs() < 1e-6 && (t.pdf - (1.0 - p_r)).abs() < 1e-6);
    // Snell: sinθ_t = sinθ_i / η.
    assert!((t.l.x + 0.6 / 1.5).abs() < 1e-6);
    assert!((t.weight.x * t.pdf - (1.0 - f) / 2.25).abs() < 1e-6);
    let a = d.albedo();
    assert!((a.reflect.x - f).abs() < 1e-6 && (a.transmit_energy.x - (1.0 - f)).abs() < 1e-6);
}

#[test]
fn pass_through_leaves() {
    let v = Vec3::new(0.0, 0.6, 0.8);
    let e = Lobe::Emission(Emission {
        radiance: Vec3::new(1.0, 2.0, 3.0),
    })
    .prepare(v, Sides::Front);
    assert_eq!(e.emission(), Vec3::new(1.0, 2.0, 3.0));
    assert_eq!(e.eval(v).f_cos, Vec3::ZERO);
    assert!(e.sample([0.5; 3]).is_none());
    let t = Lobe::Transparent(Transparent {
        tint: Vec3::splat(0.5),
    })
    .prepare(v, Sides::Front);
    assert_eq!(t.transparency(), Vec3::splat(0.5));
    let s = t.sample([0.5; 3]).expect("straight");
    assert!(s.delta && s.l == -v && s.weight == Vec3::splat(0.5));
    assert_eq!(t.albedo().transmit, Vec3::splat(0.5));
}

#[test]
fn frames_and_mappings() {
    let n = Vec3::new(0.0, 0.0, 2.0);
    let f = Frame::new(n, Vec3::new(1.0, 0.0, 0.5));
    assert!((f.x - Vec3::X).length() < 1e-6 && (f.y - Vec3::Y).length() < 1e-6);
    let w = Vec3::new(0.3, -0.4, 0.5);
    assert!((f.to_world(f.to_local(w)) - w).length() < 1e-6);
    // Degenerate tangent: still orthonormal.
    let g = Frame::new(Vec3::new(1.0, 1.0, 0.0), Vec3::new(2.0, 2.0, 0.0));
    assert!(g.x.dot(g.z).abs() < 1e-6 && (g.x.length() - 1.0).abs() < 1e-6);
    let r = f.rotated(std::f32::consts::FRAC_PI_2);
    assert!((r.x - Vec3::Y).length() < 1e-6);
    // Roughness/anisotropy mapping of spec §0.
    let (ax, ay) = ggx::roughness_to_alpha(0.5, 0.0);
    assert!((ax - 0.25).abs() < 1e-7 && (ay - 0.25).abs() < 1e-7);
    let (ax, ay) = ggx::roughness_to_alpha(0.5, 0.75);
    assert!((ax - 0.5).abs() < 1e-6 && (ay - 0.125).abs() < 1e-6);
    let (bx, by) = ggx::roughness_to_alpha(0.5, -0.75);
    assert_eq!((bx, by), (ay, ax));
    // mia highlight widths of spec §3.12.
    let alphas = MiaHighlight3 {
        glossiness: 0.5,
        anisotropy: 1.0,
        variant: WardVariant::Classic,
    }
    .alphas();
    for ((a, _), want) in alphas.iter().zip([0.333_333, 0.447_214, 0.577_350]) {
        assert!((a - want).abs() < 1e-5);
    }
    let alphas = MiaHighlight3 {
        glossiness: 1.0,
        anisotropy: 1.0,
        variant: WardVariant::Classic,
    }
    .alphas();
    for ((a, _), want) in alphas.iter().zip([0.0880, 0.1240, 0.1741]) {
        assert!((a - want).abs() < 1e-4);
    }
}
