//! White furnace (spec closures.md §5.3) by deterministic quadrature, and golden albedo
//! values (§5.4). Quadrature maps are written in the test (f64), so they check the leaves'
//! eval against the tables and closed forms independently of the leaves' own samplers.
//!
//! Layered rows of §5.3 (`layer[...](dielectric R, lambert)`, sheen over Lambert, the recipes)
//! need the closure algebra and belong to the interpreter's material tests.

use crate::common::leaves_ref;

use glam::{DVec3, Vec3};
use leaves_ref::*;
use vstructc::interp::diffuse::{Lambert, OrenNayar, OrenNayarVariant, eon_e_hat};
use vstructc::interp::microfacet::{dielectric_albedos, e1};
use vstructc::interp::sheen::sheen_ltc_albedo;
use vstructc::interp::tables::{self, TableId};
use vstructc::interp::*;

const MUS: [f32; 5] = [0.05, 0.2, 0.5, 0.8, 1.0];
const N: usize = 512;

fn view(mu: f32) -> Vec3 {
    Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu)
}

fn cosine_albedo(p: &PreparedLobe) -> f64 {
    cosine_quadrature(N, |l, pdf| f64::from(p.eval(l).f_cos.x) / pdf)
}

#[test]
fn furnace_lambert_is_one() {
    for mu in MUS {
        let p = Lobe::Lambert(Lambert { rho: Vec3::ONE }).prepare(view(mu), Sides::Front);
        let e = cosine_albedo(&p);
        assert!((e - 1.0).abs() < 1e-6, "μ {mu}: {e}");
        assert_eq!(p.albedo().reflect, Vec3::ONE);
    }
}

/// Translucent sends all of a white ρ through the surface (spec §3.2) and the subsurface
/// proxy is a white Lambert (§3.16): both integrate to 1, on their own sides, and say so.
#[test]
fn furnace_translucent_and_subsurface_proxy_are_one() {
    let white = Lambert { rho: Vec3::ONE };
    // The lower hemisphere, by mirroring the cosine grid's directions.
    let below = |l: Vec3| Vec3::new(l.x, l.y, -l.z);
    for mu in MUS {
        let p = Lobe::Translucent(white).prepare(view(mu), Sides::Front);
        let e = cosine_quadrature(N, |l, pdf| f64::from(p.eval(below(l)).f_cos.x) / pdf);
        assert!((e - 1.0).abs() < 1e-6, "translucent μ {mu}: {e}");
        assert_eq!(
            cosine_albedo(&p),
            0.0,
            "translucent reflects nothing, μ {mu}"
        );
        assert_eq!(p.albedo().transmit, Vec3::ONE);
        assert_eq!(p.albedo().reflect, Vec3::ZERO);
        let p = Lobe::SubsurfaceProxy(white).prepare(view(mu), Sides::Front);
        let e = cosine_albedo(&p);
        assert!((e - 1.0).abs() < 1e-6, "subsurface proxy μ {mu}: {e}");
        assert_eq!(p.albedo().reflect, Vec3::ONE);
    }
}

#[test]
fn furnace_eon_is_one() {
    for sigma in [0.25f32, 0.5, 1.0] {
        for variant in [OrenNayarVariant::Energy, OrenNayarVariant::EnergyFast] {
            for mu in MUS {
                let lobe = Lobe::OrenNayar(OrenNayar {
                    rho: Vec3::ONE,
                    sigma,
                    variant,
                });
                let p = lobe.prepare(view(mu), Sides::Front);
                let e = cosine_albedo(&p);
                // The polynomial Ê is not exactly the integral of f_ss: allow its 4.7e-4.
                let tol = if variant == OrenNayarVariant::Energy {
                    1e-4
                } else {
                    1e-3
                };
                assert!((e - 1.0).abs() < tol, "σ {sigma} μ {mu} {variant:?}: {e}");
                assert!((p.albedo().reflect.x - 1.0).abs() < 1e-5);
            }
        }
    }
}

#[test]
fn eon_albedo_matches_quadrature_for_coloured_rho() {
    for mu in MUS {
        let lobe = Lobe::OrenNayar(OrenNayar {
            rho: Vec3::new(0.8, 0.4, 0.1),
            sigma: 0.7,
            variant: OrenNayarVariant::Energy,
        });
        let p = lobe.prepare(view(mu), Sides::Front);
        for c in 0..3 {
            let e = cosine_quadrature(N, |l, pdf| f64::from(p.eval(l).f_cos[c]) / pdf);
            assert!(
                (e - f64::from(p.albedo().reflect[c])).abs() < 1e-4,
                "μ {mu} channel {c}"
            );
        }
    }
}

fn dielectric_energy(alpha: f32, eta: f32, mu: f32) -> (f64, [f32; 3]) {
    let lobe = Lobe::Dielectric(Dielectric::new(
        Ggx::isotropic(alpha),
        Masking::HeightCorrelated,
        eta,
        DielectricMode::Rt,
    ));
    let p = lobe.prepare(view(mu), Sides::Front);
    let a = f64::from(alpha);
    let (er, et) = vndf_quadrature(N, a, a, d(view(mu)), Some(f64::from(eta)), |l| {
        f64::from(p.eval(l).f_cos.x)
    });
    (
        er + f64::from(eta * eta) * et,
        dielectric_albedos(Masking::HeightCorrelated, mu, alpha, eta),
    )
}

/// at μ_o = 0.05 the single-scattering energy is 0.912 (G1(V) = 0.83 there).
#[test]
fn furnace_dielectric_rt_energy() {
    for eta in [1.5f32, 1.0 / 1.5] {
        for alpha in [0.05f32, 0.5] {
            for mu in MUS {
                let (energy, [er, et, _]) = dielectric_energy(alpha, eta, mu);
                let table = f64::from(er + eta * eta * et);
                assert!(
                    energy <= 1.0 + 1e-4,
                    "η {eta} α {alpha} μ {mu}: energy {energy} > 1"
                );
                // Linear interpolation over 32 μ nodes follows the steep grazing end of a
                // smooth lobe only to ~7e-3 (spec §3.17's 1e-2 class); 2e-3 elsewhere.
                let tol = if mu < 0.1 { 1e-2 } else { 2e-3 };
                assert!(
                    (energy - table).abs() < tol,
                    "η {eta} α {alpha} μ {mu}: {energy} vs table {table}"
                );
                // Near-smooth interfaces keep their energy from either side, except at
                // grazing views, where masking alone loses more than §5.3's 1e-2 (η 1.5,
                // μ_o 0.2: 0.981; μ_o 0.05: 0.912).
                if alpha == 0.05 && mu >= 0.5 {
                    assert!((energy - 1.0).abs() < 1e-2, "α 0.05 μ {mu}: {energy}");
                }
            }
        }
    }
    // The spec's examples (0.9664 at α = 0.5, μ_o = 0.8; 0.9481 at μ_o = 0.5) are not
    // reproduced: this test's quadrature of the f32 leaf and the generator's independent f64
    // quadrature agree on 0.94576 and 0.89263 (with the spec's own f_t, which matches the
    // golden point 10.7795). Pinned here so a change is noticed.
    let (e08, _) = dielectric_energy(0.5, 1.5, 0.8);
    let (e05, _) = dielectric_energy(0.5, 1.5, 0.5);
    assert!((e08 - 0.94576).abs() < 2e-4, "{e08}");
    assert!((e05 - 0.89263).abs() < 2e-4, "{e05}");
}

fn microfacet_quadrature(lobe: MicrofacetR, mu: f32) -> (f64, Vec3) {
    let p = Lobe::MicrofacetR(lobe).prepare(view(mu), Sides::Front);
    let (ax, ay) = (f64::from(lobe.ggx.ax), f64::from(lobe.ggx.ay));
    let (e, _) = vndf_quadrature(N, ax, ay, d(view(mu)), None, |l| {
        f64::from(p.eval(l).f_cos.x)
    });
    (e, p.albedo().reflect)
}

#[test]
fn furnace_white_metal_with_turquin_is_one() {
    for alpha in [0.1f32, 0.5, 1.0] {
        for mu in MUS {
            let lobe = MicrofacetR {
                ggx: Ggx::isotropic(alpha),
                masking: Masking::HeightCorrelated,
                fresnel: Fresnel::Schlick {
                    f0: Vec3::ONE,
                    f90: Vec3::ONE,
                    q: 5.0,
                },
                comp: Compensation::Turquin(1.0),
            };
            let (e, albedo) = microfacet_quadrature(lobe, mu);
            assert!((e - 1.0).abs() < 1e-2, "α {alpha} μ {mu}: {e}");
            assert!((f64::from(albedo.x) - 1.0).abs() < 1e-2);
        }
    }
}

#[test]
/// Kulla–Conty is exact with respect to the table lookups; the table itself interpolates
/// `E(μ_o)` near grazing to ~3e-3 (α = 0.1, μ = 0.05), hence 5e-3.
fn furnace_white_metal_with_kulla_conty_is_one() {
    for alpha in [0.1f32, 0.5, 1.0] {
        for mu in MUS {
            let lobe = MicrofacetR {
                ggx: Ggx::isotropic(alpha),
                masking: Masking::HeightCorrelated,
                fresnel: Fresnel::One,
                comp: Compensation::KullaConty,
            };
            let p = Lobe::MicrofacetR(lobe).prepare(view(mu), Sides::Front);
            // VNDF quadrature of the single-scattering part plus cosine quadrature of the
            // whole lobe minus its single-scattering part: evaluate the lobe fully with both
            // maps and combine through the table-free identity E = E_ss + E_ms.
            let a = f64::from(alpha);
            let ss = MicrofacetR {
                comp: Compensation::None,
                ..lobe
            };
            let ps = Lobe::MicrofacetR(ss).prepare(view(mu), Sides::Front);
            let (e_ss, _) = vndf_quadrature(N, a, a, d(view(mu)), None, |l| {
                f64::from(ps.eval(l).f_cos.x)
            });
            let e_ms = cosine_quadrature(N, |l, pdf| {
                f64::from(p.eval(l).f_cos.x - ps.eval(l).f_cos.x) / pdf
            });
            let e = e_ss + e_ms;
            assert!(
                (e - 1.0).abs() < 5e-3,
                "α {alpha} μ {mu}: {e} (ss {e_ss}, ms {e_ms})"
            );
            assert!((f64::from(p.albedo().reflect.x) - 1.0).abs() < 2e-3);
        }
    }
}

#[test]
fn microfacet_albedo_tables_match_quadrature() {
    let fresnels = [
        Fresnel::One,
        Fresnel::Schlick {
            f0: Vec3::splat(0.04),
            f90: Vec3::ONE,
            q: 5.0,
        },
        Fresnel::Schlick {
            f0: Vec3::splat(0.2),
            f90: Vec3::splat(0.8),
            q: 2.5,
        },
        Fresnel::f82(Vec3::splat(0.9), Vec3::ONE, 5.0, Vec3::splat(0.6)),
        Fresnel::Dielectric { eta: 1.5 },
    ];
    for fresnel in fresnels {
        for masking in [Masking::HeightCorrelated, Masking::Separable] {
            for alpha in [0.1f32, 0.4, 0.9] {
                for mu in [0.2f32, 0.5, 1.0] {
                    let lobe = MicrofacetR {
                        ggx: Ggx::isotropic(alpha),
                        masking,
                        fresnel,
                        comp: Compensation::None,
                    };
                    let (e, albedo) = microfacet_quadrature(lobe, mu);
                    let tol = if matches!(fresnel, Fresnel::Dielectric { .. })
                        && masking == Masking::Separable
                    {
                        4e-3 // separable dielectric albedo is the HC table rescaled (documented)
                    } else {
                        2e-3
                    };
                    assert!(
                        (e - f64::from(albedo.x)).abs() < tol,
                        "{fresnel:?} {masking:?} α {alpha} μ {mu}: quadrature {e} vs table {}",
                        albedo.x
                    );
                }
            }
        }
    }
}

#[test]
fn conductor_albedo_fit_is_close() {
    let gold = Fresnel::Conductor {
        eta: Vec3::new(0.183, 0.421, 1.373),
        kappa: Vec3::new(3.424, 2.346, 1.770),
    };
    for alpha in [0.1f32, 0.5] {
        for mu in [0.3f32, 0.8] {
            let lobe = MicrofacetR {
                ggx: Ggx::isotropic(alpha),
                masking: Masking::HeightCorrelated,
                fresnel: gold,
                comp: Compensation::None,
            };
            let p = Lobe::MicrofacetR(lobe).prepare(view(mu), Sides::Front);
            for c in 0..3 {
                let a = f64::from(alpha);
                let (e, _) = vndf_quadrature(256, a, a, d(view(mu)), None, |l| {
                    f64::from(p.eval(l).f_cos[c])
                });
                assert!(
                    (e - f64::from(p.albedo().reflect[c])).abs() < 2.5e-2, // the F82 fit (spec §3.9) pins F(1), F(1/7) only
                    "α {alpha} μ {mu} c {c}: {e} vs {}",
                    p.albedo().reflect[c]
                );
            }
        }
    }
}

#[test]
fn golden_ggx_albedo_table_values() {
    // (i, j, separable, height-correlated) with α = (i/31)², μ = j/31.
    let rows = [
        (8, 8, 0.95865, 0.95895),
        (8, 31, 0.99528, 0.99528),
        (16, 4, 0.84139, 0.87324),
        (16, 16, 0.84508, 0.84742),
        (24, 16, 0.62274, 0.63943),
        (31, 1, 0.59453, 0.88820),
        (31, 16, 0.40478, 0.44384),
        (31, 31, 0.30685, 0.30685),
    ];
    for (i, j, sep, hc) in rows {
        let alpha = (i as f32 / 31.0).powi(2);
        let mu = j as f32 / 31.0;
        for (masking, want) in [(Masking::Separable, sep), (Masking::HeightCorrelated, hc)] {
            let got = f64::from(e1(masking, mu, alpha));
            assert!(
                (got - want).abs() < 1e-3,
                "{masking:?} α {alpha} μ {mu}: {got} vs {want}"
            );
        }
    }
}

#[test]
fn golden_eon_values() {
    for (sigma, mu, want) in [
        (0.25, 0.1, 0.992283),
        (0.25, 1.0, 0.932881),
        (0.5, 0.5, 0.924189),
        (0.5, 1.0, 0.874205),
        (1.0, 0.1, 0.974307),
        (1.0, 0.5, 0.865320),
        (1.0, 1.0, 0.776522),
    ] {
        let got = f64::from(eon_e_hat(mu, sigma));
        assert!((got - want).abs() < 2e-6, "Ê({sigma}, {mu}) = {got}");
        assert!((leaves_ref::eon_e_hat(f64::from(sigma), f64::from(mu)) - want).abs() < 2e-6);
        // Quadrature of f_ss (Fujii, ρ = 1) agrees with the closed form.
        let p = Lobe::OrenNayar(OrenNayar {
            rho: Vec3::ONE,
            sigma,
            variant: OrenNayarVariant::Fujii,
        })
        .prepare(view(mu), Sides::Front);
        let q = cosine_albedo(&p);
        assert!((q - want).abs() < 2e-5, "quadrature Ê({sigma}, {mu}) = {q}");
    }
    for (sigma, want) in [(0.25, 0.949786), (0.5, 0.905890), (1.0, 0.832811)] {
        assert!((leaves_ref::eon_e_avg(sigma) - want).abs() < 2e-6);
        assert!(
            (f64::from(vstructc::interp::diffuse::eon_e_avg(sigma as f32)) - want).abs() < 2e-6
        );
    }
    assert!((f64::from(vstructc::interp::diffuse::EON_C1) - 0.2877934).abs() < 1e-7);
    assert!((f64::from(vstructc::interp::diffuse::EON_C2) - 0.0724882).abs() < 1e-7);
}

#[test]
fn golden_qon_mia_sheen_values() {
    for (sigma, mu, want) in [
        (1.0f32, 1.0f32, 0.62406),
        (1.0, 0.5, 0.74714),
        (1.0, 0.2, 0.80065),
        (0.5, 1.0, 0.78448),
    ] {
        let got = f64::from(tables::lookup2(TableId::Qon, mu, sigma));
        assert!((got - want).abs() < 1e-3, "QON σ {sigma} μ {mu}: {got}");
    }
    for mu in [0.2f32, 0.5, 1.0] {
        let got = f64::from(tables::lookup2(TableId::Mia, mu, 0.0));
        assert!((got - 95.0 / 96.0).abs() < 1e-4, "mia σ 0 μ {mu}: {got}");
    }
    for (r, mu, want) in [
        (0.3f32, 0.1f32, 0.61436),
        (0.3, 0.5, 0.24151),
        (0.3, 1.0, 0.04295),
        (1.0, 0.1, 0.49402),
        (1.0, 0.5, 0.28729),
        (1.0, 1.0, 0.14142),
    ] {
        let got = f64::from(tables::lookup2(TableId::SheenMx, mu, tables::sheen_axis(r)));
        assert!((got - want).abs() < 2e-3, "sheen r {r} μ {mu}: {got}");
    }
}

#[test]
fn golden_dielectric_fresnel_averages() {
    for (eta, exact) in [
        (1.33f32, 0.065931),
        (1.5, 0.091778),
        (1.6, 0.106246),
        (2.0, 0.160597),
        (2.5, 0.221867),
        (1.0 / 1.5, 0.596346),
    ] {
        // 2∫F μ dμ of the f32 exact Fresnel by the midpoint rule in μ².
        let n = 200_000;
        let avg: f64 = (0..n)
            .map(|k| {
                let t = (k as f64 + 0.5) / n as f64;
                f64::from(vstructc::interp::fresnel::dielectric(t.sqrt() as f32, eta))
            })
            .sum::<f64>()
            / n as f64;
        assert!((avg - exact).abs() < 2e-5, "η {eta}: {avg} vs {exact}");
    }
    for (eta, fit) in [
        (1.33f32, 0.066238),
        (1.5, 0.093101),
        (1.6, 0.107712),
        (2.0, 0.160684),
        (2.5, 0.220455),
    ] {
        let got = f64::from(vstructc::interp::fresnel::dielectric_avg(eta));
        assert!((got - fit).abs() < 2e-5, "fit at {eta}: {got} vs {fit}");
    }
}

/// `∫ g dω` over the upper hemisphere by adaptive Simpson on 20 × 40 (θ, φ) cells (resolves
/// the concentrated LTC densities that a cosine grid misses).
fn hemisphere_integral(g: impl Fn(Vec3) -> f64) -> f64 {
    use std::f64::consts::PI;
    use vstructc_testkit::verify::adaptive_simpson_2d;
    let (nt, np) = (20, 40);
    let (dt, dp) = (0.5 * PI / nt as f64, 2.0 * PI / np as f64);
    let f = |t: f64, p: f64| {
        let (st, ct) = t.sin_cos();
        let d = Vec3::new((st * p.cos()) as f32, (st * p.sin()) as f32, ct as f32);
        g(d) * st
    };
    let mut acc = 0.0;
    for i in 0..nt {
        for j in 0..np {
            let (t0, p0) = (i as f64 * dt, j as f64 * dp);
            acc += adaptive_simpson_2d(&f, t0, p0, t0 + dt, p0 + dp, 1e-9, 8);
        }
    }
    acc
}

#[test]
fn golden_sheen_ltc_values_and_unit_mass() {
    for (r, mu, want) in [
        (0.5f32, 0.5f32, 0.149718),
        (1.0, 1.0, 0.344619),
        (1.0, 0.1, 0.695201),
    ] {
        assert!((f64::from(sheen_ltc_albedo(mu, r)) - want).abs() < 2e-6);
        assert!((ltc_e_hat(mu as f64, r as f64) - want).abs() < 2e-6);
    }
    for r in [0.05f32, 0.3, 1.0] {
        for mu in MUS {
            let p = Lobe::SheenLTC(SheenLTC { r }).prepare(view(mu), Sides::Front);
            let mass = hemisphere_integral(|l| f64::from(p.pdf(l)));
            assert!((mass - 1.0).abs() < 1e-4, "r {r} μ {mu}: mass {mass}");
            let e = hemisphere_integral(|l| f64::from(p.eval(l).f_cos.x));
            assert!(
                (e - f64::from(p.albedo().reflect.x)).abs() < 1e-4,
                "r {r} μ {mu}: {e}"
            );
        }
    }
    let _ = DVec3::ZERO;
}
