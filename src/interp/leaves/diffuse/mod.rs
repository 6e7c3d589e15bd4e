//! Diffuse leaves: Lambert, Translucent, Oren–Nayar
//! (QON, FON, EON), MiaDiffuse and Burley. All are cosine-sampled.
//!
//! Prepared forms assume the (possibly flipped) view has `μ_o > 0`.

use crate::interp::leaves::{Leaf, LobeAlbedo, LobeEval, LobeSample, PreparedLeaf};
use crate::interp::math::{Rgb, pdf_cosine, pow5, sample_cosine};
use crate::interp::tables::{self, MuCurve, TableId};
use glam::Vec3;
use std::f32::consts::{FRAC_1_PI, PI};

pub(crate) mod soa;

/// `c1 = 1/2 − 2/(3π)` of EON.
pub const EON_C1: f32 = 0.5 - 2.0 / (3.0 * PI);
/// `c2 = 2/3 − 28/(15π)` of EON.
pub const EON_C2: f32 = 2.0 / 3.0 - 28.0 / (15.0 * PI);
/// Below this σ, EON is evaluated as Lambert (its `f_ms` is 0/0 at σ = 0).
pub(crate) const EON_SIGMA_MIN: f32 = 1e-4;

/// Cosine-samples a reflection lobe given its `f·μ_i` (weight = `f_cos/pdf`).
#[inline]
pub(crate) fn cosine_sample(u: [f32; 3], f_cos: impl Fn(Vec3) -> Rgb) -> Option<LobeSample> {
    let l = sample_cosine(u[0], u[1])?;
    let pdf = pdf_cosine(l.z);
    Some(LobeSample {
        l,
        weight: f_cos(l) / pdf,
        pdf,
        delta: false,
    })
}

/// `f = ρ/π` (Lambert); also the subsurface proxy.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lambert {
    /// Albedo ρ.
    pub rho: Rgb,
}

/// Prepared Lambert (and Translucent: same data, other hemisphere).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PreparedLambert {
    pub(in crate::interp) rho: Rgb,
    pub(in crate::interp) rho_pi: Rgb,
}

impl Leaf for Lambert {
    type Prepared = PreparedLambert;
    type Bound = ();

    /// Precomputes the view-only terms.
    fn prepare(&self, _v: Vec3, _flipped: bool) -> Self::Prepared {
        PreparedLambert {
            rho: self.rho,
            rho_pi: self.rho * FRAC_1_PI,
        }
    }

    /// Nothing to bind: the view-independent terms are the parameters.
    fn bind(&self) {}

    /// [`Leaf::prepare`].
    #[inline(always)]
    fn prepare_bound(&self, v: Vec3, flipped: bool, _: &()) -> Self::Prepared {
        self.prepare(v, flipped)
    }
}

/// A prepared Lambert read as translucent: the same `ρ` on the lower hemisphere
/// (`Lobe::Translucent`).
#[derive(Debug, Clone, Copy)]
pub struct PreparedTranslucent(pub(in crate::interp) PreparedLambert);

impl PreparedLeaf for PreparedTranslucent {
    /// Translucent: `ρ |μ_i| / π` on the lower hemisphere.
    #[inline(always)]
    fn eval(&self, l: Vec3) -> LobeEval {
        if l.z >= 0.0 {
            return LobeEval::ZERO;
        }
        LobeEval {
            f_cos: self.0.rho_pi * -l.z,
            pdf: -l.z * FRAC_1_PI,
        }
    }

    /// Translucent density.
    #[inline]
    fn pdf(&self, l: Vec3) -> f32 {
        pdf_cosine(-l.z)
    }

    /// Translucent: cosine sample mirrored to the lower hemisphere; weight ρ.
    fn sample(&self, u: [f32; 3]) -> Option<LobeSample> {
        let l = sample_cosine(u[0], u[1])?;
        Some(LobeSample {
            l: Vec3::new(l.x, l.y, -l.z),
            weight: self.0.rho,
            pdf: pdf_cosine(l.z),
            delta: false,
        })
    }

    /// Translucent albedo: ρ, transmitted (no index change: energy equals radiance).
    fn albedo(&self) -> LobeAlbedo {
        LobeAlbedo {
            reflect: Vec3::ZERO,
            transmit: self.0.rho,
            transmit_energy: self.0.rho,
        }
    }
}

impl PreparedLeaf for PreparedLambert {
    /// `ρ μ_i / π` on the upper hemisphere.
    #[inline(always)]
    fn eval(&self, l: Vec3) -> LobeEval {
        if l.z <= 0.0 {
            return LobeEval::ZERO;
        }
        LobeEval {
            f_cos: self.rho_pi * l.z,
            pdf: l.z * FRAC_1_PI,
        }
    }

    /// Cosine density.
    #[inline]
    fn pdf(&self, l: Vec3) -> f32 {
        pdf_cosine(l.z)
    }

    /// Cosine sample; weight ρ.
    fn sample(&self, u: [f32; 3]) -> Option<LobeSample> {
        let l = sample_cosine(u[0], u[1])?;
        Some(LobeSample {
            l,
            weight: self.rho,
            pdf: pdf_cosine(l.z),
            delta: false,
        })
    }

    /// Albedo ρ.
    fn albedo(&self) -> LobeAlbedo {
        LobeAlbedo::reflect(self.rho)
    }
}

/// Oren–Nayar variant.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OrenNayarVariant {
    /// Qualitative model (Oren & Nayar 1994), albedo from a table.
    Qualitative,
    /// Fujii's single-scattering form (the `f_ss` of EON), albedo `ρ Ê(μ_o)`.
    #[cfg_attr(not(feature = "testkit"), allow(dead_code))]
    Fujii,
    /// Energy-preserving Oren–Nayar (Portsmouth, Kutz & Hill 2025), exact `Ê` (two `acos`).
    Energy,
    /// EON with the polynomial `Ê` (max error 4.7e-4; no `acos`).
    EnergyFast,
}

/// Oren–Nayar family lobe.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrenNayar {
    /// Albedo colour ρ.
    pub rho: Rgb,
    /// Roughness σ ∈ [0, 1] (clamped).
    pub sigma: f32,
    /// Which model.
    pub variant: OrenNayarVariant,
}

/// EON's `Ê(μ)` (directional albedo of `f_ss` at ρ = 1) by the exact closed form.
#[inline(always)]
pub fn eon_e_hat(mu: f32, sigma: f32) -> f32 {
    let af = 1.0 / (1.0 + EON_C1 * sigma);
    af + sigma * af * FRAC_1_PI * eon_g(mu)
}

/// EON's `Ê(μ)` by the polynomial fit in `1 − μ`.
#[inline(always)]
pub fn eon_e_hat_fast(mu: f32, sigma: f32) -> f32 {
    let m = 1.0 - mu.clamp(0.0, 1.0);
    let g = m * (0.057_108_53 + m * (0.491_881_87 + m * (-0.332_181_44 + m * 0.071_442_99)));
    (1.0 + sigma * g) / (1.0 + EON_C1 * sigma)
}

/// EON's `G(θ)`, `θ = acos μ`, rewritten without the `1/cosθ` singularity:
/// `(sinθ/cosθ)(1 − sin³θ) = sinθ·μ(1 + s + s²)/(1 + s)` with `s = sinθ`.
#[inline(always)]
fn eon_g(mu: f32) -> f32 {
    let mu = mu.clamp(0.0, 1.0);
    let s = (1.0 - mu * mu).max(0.0).sqrt();
    // The polynomial `acos` (error < 5e-7, `vmath` tests): no library call per evaluation.
    let theta = crate::interp::vmath::acos(mu);
    s * (theta - s * mu) + (2.0 / 3.0) * s * (mu * (1.0 + s + s * s) / (1.0 + s) - 1.0)
}

/// EON's average albedo `Ē = A_F (1 + c2 σ)`.
pub fn eon_e_avg(sigma: f32) -> f32 {
    (1.0 + EON_C2 * sigma) / (1.0 + EON_C1 * sigma)
}

/// Prepared Oren–Nayar lobe.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PreparedOrenNayar {
    pub(in crate::interp) v: Vec3,
    pub(in crate::interp) rho_pi: Rgb,
    /// Constant term (A or A_F).
    pub(in crate::interp) a: f32,
    /// Coefficient of `s/t` (B or σ A_F).
    pub(in crate::interp) b: f32,
    /// FON/EON keep negative `s` (QON drops it).
    pub(in crate::interp) keep_negative_s: bool,
    /// EON: `ρ_ms (1 − Ê(μ_o)) / (π (1 − Ē))`; zero otherwise.
    pub(in crate::interp) ms: Rgb,
    pub(in crate::interp) sigma: f32,
    pub(in crate::interp) fast: bool,
    pub(in crate::interp) albedo: Rgb,
}

/// The view-independent part of an [`OrenNayar`] lobe's prepare ([`OrenNayar::bind`]):
/// the prepared lobe at `μ_o = 1` as a template, EON's multiple-scattering colour terms,
/// and the QON albedo curve.
#[derive(Debug, Clone, Copy)]
pub struct OrenNayarBound {
    pub(in crate::interp) template: PreparedOrenNayar,
    /// EON: `ρ_ms` and `ρ_ms/(π(1 − Ē))` (zero below the σ cut-off and for QON/FON).
    pub(in crate::interp) rho_ms: Rgb,
    pub(in crate::interp) ms_scale: Rgb,
    pub(in crate::interp) qon: Option<MuCurve>,
}

impl Leaf for OrenNayar {
    type Prepared = PreparedOrenNayar;
    type Bound = OrenNayarBound;

    /// Precomputes the view-only terms for view `v` (`v.z > 0`).
    fn prepare(&self, v: Vec3, _flipped: bool) -> Self::Prepared {
        let sigma = if self.sigma.is_nan() {
            0.0
        } else {
            self.sigma.clamp(0.0, 1.0)
        };
        let rho_pi = self.rho * FRAC_1_PI;
        let mut p = PreparedOrenNayar {
            v,
            rho_pi,
            a: 1.0,
            b: 0.0,
            keep_negative_s: false,
            ms: Vec3::ZERO,
            sigma,
            fast: self.variant == OrenNayarVariant::EnergyFast,
            albedo: self.rho,
        };
        match self.variant {
            OrenNayarVariant::Qualitative => {
                let s2 = sigma * sigma;
                p.a = 1.0 - 0.5 * s2 / (s2 + 0.33);
                p.b = 0.45 * s2 / (s2 + 0.09);
                p.albedo = self.rho * tables::lookup2(TableId::Qon, v.z, sigma);
            }
            OrenNayarVariant::Fujii => {
                let af = 1.0 / (1.0 + EON_C1 * sigma);
                (p.a, p.b, p.keep_negative_s) = (af, sigma * af, true);
                p.albedo = self.rho * eon_e_hat(v.z, sigma);
            }
            OrenNayarVariant::Energy | OrenNayarVariant::EnergyFast => {
                if sigma >= EON_SIGMA_MIN {
                    let af = 1.0 / (1.0 + EON_C1 * sigma);
                    (p.a, p.b, p.keep_negative_s) = (af, sigma * af, true);
                    let e_o = p.e_hat(v.z);
                    let e_avg = eon_e_avg(sigma);
                    let rho_ms = eon_rho_ms(self.rho, e_avg);
                    p.ms = rho_ms * ((1.0 - e_o) * FRAC_1_PI / (1.0 - e_avg));
                    p.albedo = self.rho * e_o + rho_ms * (1.0 - e_o);
                }
            }
        }
        p
    }

    /// The view-independent part of [`OrenNayar::prepare`].
    fn bind(&self) -> Self::Bound {
        let template = self.prepare(Vec3::Z, false);
        let (mut rho_ms, mut ms_scale) = (Vec3::ZERO, Vec3::ZERO);
        let energy = matches!(
            self.variant,
            OrenNayarVariant::Energy | OrenNayarVariant::EnergyFast
        );
        if energy && template.sigma >= EON_SIGMA_MIN {
            let e_avg = eon_e_avg(template.sigma);
            rho_ms = eon_rho_ms(self.rho, e_avg);
            ms_scale = rho_ms * (FRAC_1_PI / (1.0 - e_avg));
        }
        let qon = (self.variant == OrenNayarVariant::Qualitative)
            .then(|| MuCurve::new2(TableId::Qon, template.sigma));
        OrenNayarBound {
            template,
            rho_ms,
            ms_scale,
            qon,
        }
    }

    /// [`OrenNayar::prepare`] with the result of [`OrenNayar::bind`].
    // Inlined into `Lobe::prepare_aux_into` so the state is stored straight into its record.
    #[inline(always)]
    fn prepare_bound(&self, v: Vec3, _flipped: bool, b: &OrenNayarBound) -> Self::Prepared {
        let mut p = b.template;
        self.set_view(&mut p, v, false, b);
        p
    }

    /// The view-dependent fields of `p`, a record [`OrenNayar::prepare_bound`] made of
    /// this lobe with `b` (at any view): all that changes from view to view.
    #[inline(always)]
    fn set_view(&self, p: &mut Self::Prepared, v: Vec3, _flipped: bool, b: &OrenNayarBound) {
        p.v = v;
        match self.variant {
            OrenNayarVariant::Qualitative => {
                p.albedo = self.rho * b.qon.as_ref().map_or(1.0, |c| c.at(v.z));
            }
            OrenNayarVariant::Fujii => p.albedo = self.rho * eon_e_hat(v.z, p.sigma),
            OrenNayarVariant::Energy | OrenNayarVariant::EnergyFast => {
                if p.sigma >= EON_SIGMA_MIN {
                    let e_o = p.e_hat(v.z);
                    p.ms = b.ms_scale * (1.0 - e_o);
                    p.albedo = self.rho * e_o + b.rho_ms * (1.0 - e_o);
                }
            }
        }
    }
}

/// EON's multiple-scattering colour `ρ_ms = ρ² Ē / (1 − ρ(1 − Ē))`.
fn eon_rho_ms(rho: Rgb, e_avg: f32) -> Rgb {
    rho * rho * e_avg / (Vec3::ONE - rho * (1.0 - e_avg)).max(Vec3::splat(1e-6))
}

impl PreparedOrenNayar {
    #[inline(always)]
    fn e_hat(&self, mu: f32) -> f32 {
        if self.fast {
            eon_e_hat_fast(mu, self.sigma)
        } else {
            eon_e_hat(mu, self.sigma)
        }
    }

    /// The bracket `A + B·s/t` of the single-scattering term.
    #[inline]
    fn ss_factor(&self, l: Vec3) -> f32 {
        let s = self.v.dot(l) - l.z * self.v.z;
        let st = if s > 0.0 {
            s / l.z.max(self.v.z)
        } else if self.keep_negative_s {
            s
        } else {
            0.0
        };
        self.a + self.b * st
    }
}

impl PreparedLeaf for PreparedOrenNayar {
    /// `f·μ_i` and the cosine pdf.
    #[inline(always)]
    fn eval(&self, l: Vec3) -> LobeEval {
        if l.z <= 0.0 {
            return LobeEval::ZERO;
        }
        let mut f = self.rho_pi * (self.ss_factor(l).max(0.0) * l.z);
        if self.ms != Vec3::ZERO {
            f += self.ms * ((1.0 - self.e_hat(l.z)) * l.z);
        }
        LobeEval {
            f_cos: f,
            pdf: l.z * FRAC_1_PI,
        }
    }

    /// Cosine density.
    #[inline]
    fn pdf(&self, l: Vec3) -> f32 {
        pdf_cosine(l.z)
    }

    /// Cosine sample.
    fn sample(&self, u: [f32; 3]) -> Option<LobeSample> {
        cosine_sample(u, |l| self.eval(l).f_cos)
    }

    /// Directional albedo at this view.
    fn albedo(&self) -> LobeAlbedo {
        LobeAlbedo::reflect(self.albedo)
    }
}

/// The MiaDiffuse smoothstep terminator `s(μ)`: `μ` for μ ≥ 0.25, `8μ²(1 − 2μ)` below.
#[inline]
pub fn mia_terminator(mu: f32) -> f32 {
    if mu >= 0.25 {
        mu
    } else if mu <= 0.0 {
        0.0
    } else {
        8.0 * mu * mu * (1.0 - 2.0 * mu)
    }
}

/// mia_material's diffuse: QON with its light-side cosine replaced by [`mia_terminator`].
/// Not reciprocal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MiaDiffuse {
    /// Albedo colour ρ.
    pub rho: Rgb,
    /// Roughness σ ∈ [0, 1].
    pub sigma: f32,
}

/// Prepared MiaDiffuse.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PreparedMiaDiffuse {
    qon: PreparedOrenNayar,
}

impl Leaf for MiaDiffuse {
    type Prepared = PreparedMiaDiffuse;
    type Bound = ();

    /// Precomputes the view-only terms for `v` (`v.z > 0`).
    fn prepare(&self, v: Vec3, _flipped: bool) -> Self::Prepared {
        let on = OrenNayar {
            rho: self.rho,
            sigma: self.sigma,
            variant: OrenNayarVariant::Qualitative,
        };
        let mut qon = on.prepare(v, false);
        qon.albedo = self.rho * tables::lookup2(TableId::Mia, v.z, qon.sigma);
        PreparedMiaDiffuse { qon }
    }

    /// Nothing to bind: the view-independent terms are the parameters.
    fn bind(&self) {}

    /// [`Leaf::prepare`].
    #[inline(always)]
    fn prepare_bound(&self, v: Vec3, flipped: bool, _: &()) -> Self::Prepared {
        self.prepare(v, flipped)
    }
}

impl PreparedLeaf for PreparedMiaDiffuse {
    /// `f_QON(V, L)·s(μ_i)` and the cosine pdf.
    #[inline(always)]
    fn eval(&self, l: Vec3) -> LobeEval {
        if l.z <= 0.0 {
            return LobeEval::ZERO;
        }
        LobeEval {
            f_cos: self.qon.rho_pi * (self.qon.ss_factor(l) * mia_terminator(l.z)),
            pdf: l.z * FRAC_1_PI,
        }
    }

    /// Cosine density.
    #[inline]
    fn pdf(&self, l: Vec3) -> f32 {
        pdf_cosine(l.z)
    }

    /// Cosine sample.
    fn sample(&self, u: [f32; 3]) -> Option<LobeSample> {
        cosine_sample(u, |l| self.eval(l).f_cos)
    }

    /// Directional albedo (table).
    fn albedo(&self) -> LobeAlbedo {
        LobeAlbedo::reflect(self.qon.albedo)
    }
}

/// Burley's diffuse with roughness σ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Burley {
    /// Albedo colour ρ.
    pub rho: Rgb,
    /// Roughness σ ∈ [0, 1].
    pub sigma: f32,
}

/// Prepared Burley.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PreparedBurley {
    v: Vec3,
    rho_pi: Rgb,
    sigma: f32,
    /// `(1 − μ_o)⁵`.
    w_o: f32,
    albedo: Rgb,
}

/// Hill's albedo fit of Burley diffuse (loose; for selection only).
pub(crate) fn burley_albedo_fit(mu: f32, sigma: f32) -> f32 {
    let a = 0.97619 - 0.488095 * pow5(1.0 - mu);
    let b = 1.55754 + (-2.02221 + (2.56283 - 1.06244 * mu) * mu) * mu;
    a + (b - a) * sigma
}

impl Leaf for Burley {
    type Prepared = PreparedBurley;
    type Bound = ();

    /// Precomputes the view-only terms for `v` (`v.z > 0`).
    fn prepare(&self, v: Vec3, _flipped: bool) -> Self::Prepared {
        let sigma = if self.sigma.is_nan() {
            0.0
        } else {
            self.sigma.clamp(0.0, 1.0)
        };
        PreparedBurley {
            v,
            rho_pi: self.rho * FRAC_1_PI,
            sigma,
            w_o: pow5(1.0 - v.z.min(1.0)),
            albedo: self.rho * burley_albedo_fit(v.z, sigma),
        }
    }

    /// Nothing to bind: the view-independent terms are the parameters.
    fn bind(&self) {}

    /// [`Leaf::prepare`].
    #[inline(always)]
    fn prepare_bound(&self, v: Vec3, flipped: bool, _: &()) -> Self::Prepared {
        self.prepare(v, flipped)
    }
}

impl PreparedLeaf for PreparedBurley {
    /// `(ρ/π) F_D(μ_i) F_D(μ_o) μ_i` with `F_D90 = 1/2 + 2σ(L·h)²`, `(L·h)² = (1 + V·L)/2`.
    #[inline(always)]
    fn eval(&self, l: Vec3) -> LobeEval {
        if l.z <= 0.0 {
            return LobeEval::ZERO;
        }
        let lh2 = 0.5 * (1.0 + self.v.dot(l));
        let fd90m1 = 2.0 * self.sigma * lh2 - 0.5;
        let fd_i = 1.0 + fd90m1 * pow5(1.0 - l.z.min(1.0));
        let fd_o = 1.0 + fd90m1 * self.w_o;
        LobeEval {
            f_cos: self.rho_pi * (fd_i * fd_o * l.z).max(0.0),
            pdf: l.z * FRAC_1_PI,
        }
    }

    /// Cosine density.
    #[inline]
    fn pdf(&self, l: Vec3) -> f32 {
        pdf_cosine(l.z)
    }

    /// Cosine sample.
    fn sample(&self, u: [f32; 3]) -> Option<LobeSample> {
        cosine_sample(u, |l| self.eval(l).f_cos)
    }

    /// Directional albedo (Hill's fit).
    fn albedo(&self) -> LobeAlbedo {
        LobeAlbedo::reflect(self.albedo)
    }
}