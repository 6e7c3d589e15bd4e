//! IR leaves to interpreter lobes: [`leaf_lobe`] evaluates a leaf's parameter registers into
//! its concrete lobe, and [`TableAlbedo`] gives the closure algebra the leaves' albedos.

use crate::interp::diffuse::{Burley, Lambert, MiaDiffuse, OrenNayar, OrenNayarVariant};
use crate::interp::fresnel::Fresnel as LobeFresnel;
use crate::interp::ggx::Ggx;
use crate::interp::lobe::{Lobe, Sides};
use crate::interp::microfacet::{Compensation, Dielectric, MicrofacetR};
use crate::interp::sheen::{SheenCK, SheenLTC};
use crate::interp::ward::{MiaHighlight3, Ward};
use crate::ir::algebra::AlbedoSource;
use crate::ir::{Fresnel, Leaf, LeafKind, Reg};
use glam::Vec3;

/// The concrete lobe of an IR leaf with its parameter registers evaluated (`regs` is the
/// program's register file; missing registers read 0). Scalars read the first channel.
pub(crate) fn leaf_lobe(kind: &LeafKind, regs: &[Vec3]) -> Lobe {
    let r = |reg: Reg| regs.get(reg.index()).copied().unwrap_or(Vec3::ZERO);
    let x = |reg: Reg| r(reg).x;
    match *kind {
        LeafKind::Lambert { albedo } => Lobe::Lambert(Lambert { rho: r(albedo) }),
        LeafKind::Translucent { albedo } => Lobe::Translucent(Lambert { rho: r(albedo) }),
        LeafKind::SubsurfaceProxy { albedo } => Lobe::SubsurfaceProxy(Lambert { rho: r(albedo) }),
        LeafKind::OrenNayarQ { albedo, sigma } => Lobe::OrenNayar(OrenNayar {
            rho: r(albedo),
            sigma: x(sigma),
            variant: OrenNayarVariant::Qualitative,
        }),
        LeafKind::OrenNayarE { albedo, sigma } => Lobe::OrenNayar(OrenNayar {
            rho: r(albedo),
            sigma: x(sigma),
            variant: OrenNayarVariant::Energy,
        }),
        LeafKind::MiaDiffuse { albedo, sigma } => Lobe::MiaDiffuse(MiaDiffuse {
            rho: r(albedo),
            sigma: x(sigma),
        }),
        LeafKind::Burley { albedo, sigma } => Lobe::Burley(Burley {
            rho: r(albedo),
            sigma: x(sigma),
        }),
        LeafKind::MicrofacetR {
            alpha_x,
            alpha_y,
            fresnel,
            masking,
            comp,
        } => {
            let fresnel = match fresnel {
                Fresnel::One => LobeFresnel::One,
                Fresnel::Schlick { f0, f90, q } => LobeFresnel::Schlick {
                    f0: r(f0),
                    f90: r(f90),
                    q: x(q),
                },
                Fresnel::F82 { f0, f90, q, t } => LobeFresnel::f82(r(f0), r(f90), x(q), r(t)),
                Fresnel::Dielectric { eta } => LobeFresnel::Dielectric { eta: x(eta) },
                Fresnel::Conductor { eta, kappa } => LobeFresnel::Conductor {
                    eta: r(eta),
                    kappa: r(kappa),
                },
            };
            let k = x(comp);
            Lobe::MicrofacetR(MicrofacetR {
                ggx: Ggx::new(x(alpha_x), x(alpha_y)),
                masking,
                fresnel,
                comp: if k > 0.0 {
                    Compensation::Turquin(k.min(1.0))
                } else {
                    Compensation::None
                },
            })
        }
        LeafKind::Dielectric {
            alpha_x,
            alpha_y,
            eta,
            mode,
            refl_tint,
            trans_tint,
            t_fresnel,
            masking,
        } => Lobe::Dielectric(Dielectric {
            ggx: Ggx::new(x(alpha_x), x(alpha_y)),
            masking,
            eta: x(eta),
            mode,
            tint_r: r(refl_tint),
            tint_t: r(trans_tint),
            t_fresnel,
            turquin: 0.0,
        }),
        LeafKind::Ward {
            alpha_x,
            alpha_y,
            rho_s,
            variant,
        } => Lobe::Ward(Ward {
            ax: x(alpha_x),
            ay: x(alpha_y),
            rho: r(rho_s),
            variant,
        }),
        LeafKind::MiaHighlight3 {
            glossiness,
            anisotropy,
            variant,
        } => Lobe::MiaHighlight3(MiaHighlight3 {
            glossiness: x(glossiness),
            anisotropy: x(anisotropy),
            variant,
        }),
        LeafKind::SheenCk { roughness, masking } => Lobe::SheenCK(SheenCK {
            r: x(roughness),
            masking,
        }),
        LeafKind::SheenLtc { roughness } => Lobe::SheenLTC(SheenLTC { r: x(roughness) }),
    }
}

/// The closure algebra's albedo source, backed by the interpreter's leaves and tables: the
/// leaf's prepared albedo at a view with cosine `μ_o` (reflection plus transmission as energy),
/// without its tint. Use it wherever the closure algebra needs real `E_k(μ_o)`.
#[derive(Debug, Clone, Copy, Default)]
pub struct TableAlbedo;

impl AlbedoSource for TableAlbedo {
    fn albedo(&self, leaf: &Leaf, regs: &[Vec3], mu_o: f32) -> Vec3 {
        let mu = mu_o.clamp(-1.0, 1.0);
        let v = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
        // Bound, as a compiled material binds a constant leaf: an anisotropic lobe's Fresnel
        // ratios are then the baked ones the compiled material reads.
        let a = leaf_lobe(&leaf.kind, regs)
            .bind()
            .prepare(v, Sides::Front)
            .albedo();
        a.reflect + a.transmit_energy
    }
}
