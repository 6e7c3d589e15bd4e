//! GGX microfacet leaves: reflection with any Fresnel
//! form (generalized Schlick, Hoffman F82, exact dielectric, conductor) with optional Turquin
//! or Kulla–Conty energy compensation, and the dielectric with reflection and/or refraction.
//!
//! Prepared forms assume the (possibly flipped) view has `μ_o > 0`.

use crate::interp::fresnel::{self, Fresnel};
use crate::interp::ggx::{Ggx, GgxView, Masking, ViewTerms, g2};
use crate::interp::leaves::{Leaf, LobeAlbedo, LobeEval, LobeSample, PreparedLeaf};
use crate::interp::math::{Rgb, lum, pdf_cosine, reflect, refract, safe_mu, sample_cosine};
use crate::interp::tables::{self, MuCurve, Row, TableId};
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// Multiple-scattering energy compensation of a microfacet lobe.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Compensation {
    /// Single scattering only.
    #[default]
    None,
    /// Turquin 2019 with strength k ∈ [0, 1] (non-reciprocal).
    Turquin(f32),
    /// Kulla & Conty 2017: an added diffuse-like lobe (reciprocal).
    #[cfg_attr(not(feature = "testkit"), allow(dead_code))]
    KullaConty,
}

/// `E1(μ, α)` (F = 1) for a masking variant.
#[inline]
pub fn e1(masking: Masking, mu: f32, alpha: f32) -> f32 {
    tables::lookup2(e1_table(masking), mu, tables::ggx_axis(alpha))
}

fn e1_table(masking: Masking) -> TableId {
    match masking {
        Masking::HeightCorrelated => TableId::E1Hc,
        Masking::Separable => TableId::E1Sep,
    }
}

fn aniso_tables(masking: Masking) -> [TableId; 3] {
    match masking {
        Masking::HeightCorrelated => [
            TableId::E1HcAniso,
            TableId::E1HcAniso22,
            TableId::E1HcAniso45,
        ],
        Masking::Separable => [
            TableId::E1SepAniso,
            TableId::E1SepAniso22,
            TableId::E1SepAniso45,
        ],
    }
}

/// The F = 1 reflection albedo of an anisotropic GGX lobe at local view `v`:
/// the anisotropic `E1` table at the view's azimuth ([`tables::aniso_albedo`]).
#[inline]
pub fn ggx_aniso_e1(ggx: &Ggx, masking: Masking, v: Vec3) -> f32 {
    tables::aniso_albedo(aniso_tables(masking), v, (ggx.ax, ggx.ay), tables::ggx_axis)
}

/// Strata of [`vndf_quadrature`] along the visible normal's azimuth and along its
/// elevation.
const RATIO_GRID: (usize, usize) = (16, 16);

/// [`RATIO_GRID`] for a dielectric seen from its denser side.
const RATIO_GRID_DENSE: (usize, usize) = (32, 32);

/// A deterministic VNDF-stratified quadrature over the visible normals of `ggx` at view `v`
/// (`v_z > 0`): `visit(h, v·h, w)` for each of the [`RATIO_GRID`] cell midpoints, with the
/// second coordinate warped as the tables' generator warps it (`u₂ = 1 − (1 − t)²`, weight
/// `w = 2(1 − t)`) so that the grazing tail of half vectors is sampled smoothly.
///
/// Anisotropic lobes use it for the *ratio* of a Fresnel-weighted albedo to the F = 1
/// albedo (the two sums share their samples, so most of the quadrature error cancels), and
/// multiply the ratio by the anisotropic `E1` table: the Fresnel moments depend on both
/// widths and on the view's azimuth, which no isotropic table at one effective width
/// reproduces (measured up to 36 % off at anisotropy 0.95 for dielectric transmission).
#[inline]
fn vndf_quadrature(ggx: &Ggx, v: Vec3, visit: impl FnMut(Vec3, f32, f32)) {
    vndf_quadrature_n(ggx, v, RATIO_GRID, visit)
}

/// [`vndf_quadrature`] with `(n1, n2)` strata.
#[inline]
fn vndf_quadrature_n(
    ggx: &Ggx,
    v: Vec3,
    (n1, n2): (usize, usize),
    mut visit: impl FnMut(Vec3, f32, f32),
) {
    for i in 0..n1 {
        let u1 = (i as f32 + 0.5) / n1 as f32;
        for j in 0..n2 {
            let t = 1.0 - (j as f32 + 0.5) / n2 as f32;
            let h = ggx.sample_vndf(v, u1, 1.0 - t * t);
            visit(h, v.dot(h), 2.0 * t);
        }
    }
}

/// `G2/G1(V)` for a lit direction with Smith `Λ(L) = lambda_l`, per masking variant.
#[inline(always)]
fn g2_over_g1(masking: Masking, lambda_v: f32, lambda_l: f32) -> f32 {
    match masking {
        Masking::HeightCorrelated => (1.0 + lambda_v) / (1.0 + lambda_v + lambda_l),
        Masking::Separable => 1.0 / (1.0 + lambda_l),
    }
}

/// The ratio of the Fresnel-weighted to the F = 1 reflection albedo of an anisotropic GGX
/// lobe at view `v` ([`vndf_quadrature`]); 1 for `Fresnel::One`.
fn aniso_fresnel_ratio(f: &Fresnel, ggx: &Ggx, masking: Masking, v: Vec3) -> Rgb {
    if matches!(f, Fresnel::One) {
        return Vec3::ONE;
    }
    let lambda_v = ggx.lambda(v);
    let (mut one, mut weighted) = (0.0f32, Vec3::ZERO);
    vndf_quadrature(ggx, v, |h, vh, w| {
        let l = 2.0 * vh * h - v;
        if l.z > 0.0 {
            let w = w * g2_over_g1(masking, lambda_v, ggx.lambda(l));
            one += w;
            weighted += w * f.eval(vh);
        }
    });
    if one > 0.0 {
        weighted / one
    } else {
        f.eval(v.z)
    }
}

/// The dielectric albedos `[E_R, E_T, E_T without (1 − F)]` of an anisotropic lobe divided
/// by its F = 1 reflection albedo ([`vndf_quadrature`]; transmission in the radiance
/// convention, entries not in `want` are 0).
fn aniso_dielectric_ratios(
    ggx: &Ggx,
    masking: Masking,
    v: Vec3,
    eta: f32,
    want: [bool; 3],
) -> [f32; 3] {
    let lambda_v = ggx.lambda(v);
    let inv_eta2 = 1.0 / (eta * eta);
    let (mut one, mut acc) = (0.0f32, [0.0f32; 3]);
    // From the denser side, total internal reflection makes the Fresnel factor jump inside
    // the cells: four times the strata there (measured up to 4.4e-2 off the integral of
    // `eval` with 16 × 16, 1.4e-2 with 32 × 32).
    let strata = if eta < 1.0 {
        RATIO_GRID_DENSE
    } else {
        RATIO_GRID
    };
    vndf_quadrature_n(ggx, v, strata, |h, vh, w| {
        let f = fresnel::dielectric(vh, eta);
        let lr = 2.0 * vh * h - v;
        if lr.z > 0.0 {
            let wr = w * g2_over_g1(masking, lambda_v, ggx.lambda(lr));
            one += wr;
            acc[0] += wr * f;
        }
        if (want[1] || want[2])
            && let Some(lt) = refract(v, h, eta).filter(|l| l.z < 0.0) {
                let wt = w * inv_eta2 * g2_over_g1(masking, lambda_v, ggx.lambda(lt));
                acc[1] += wt * (1.0 - f);
                acc[2] += wt;
            }
    });
    let inv = if one > 0.0 { 1.0 / one } else { 0.0 };
    let mut k = 0;
    acc.map(|a| {
        k += 1;
        if want[k - 1] { a * inv } else { 0.0 }
    })
}

/// Views along μ of a [`RatioGrid`].
const RATIO_MU: usize = 32;

/// Three Fresnel ratios of a constant anisotropic lobe ([`vndf_quadrature`]), computed once
/// per bind at the `RATIO_MU` view cosines of the tables, `μ = max(i/31, 1e-4)`, and at the
/// five azimuths `kπ/8` of the anisotropic tables, and read back like those tables: linearly
/// in μ, by
/// [`tables::azimuth_interpolate`] in azimuth. A prepare then costs ten interpolations
/// instead of a quadrature (measured: 11 µs per prepare with the quadrature, 256 half
/// vectors). Lobes whose parameters vary per point compute the quadrature at the view.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(in crate::interp) struct RatioGrid {
    /// `[channel][μ node][azimuth node]`.
    nodes: [[[f32; 5]; RATIO_MU]; 3],
    /// An isotropic lobe's grid ([`RatioGrid::isotropic`]): the albedo `E1 · R` itself, the
    /// same at every azimuth node, read along μ only.
    isotropic: bool,
}

impl RatioGrid {
    /// The grid of `ratios(v)` at its nodes.
    fn new(ratios: impl Fn(Vec3) -> [f32; 3]) -> RatioGrid {
        RatioGrid::build(false, ratios)
    }

    /// The grid of `f` at its nodes; an isotropic lobe's `f` is evaluated once per view
    /// cosine (at azimuth 0) and stored at every azimuth node.
    #[allow(clippy::needless_range_loop)] // the nodes are stored channel-major
    fn build(isotropic: bool, f: impl Fn(Vec3) -> [f32; 3]) -> RatioGrid {
        let mut nodes = [[[0.0; 5]; RATIO_MU]; 3];
        for i in 0..RATIO_MU {
            let mu = (i as f32 / (RATIO_MU - 1) as f32).max(1e-4);
            let s = (1.0 - mu * mu).max(0.0).sqrt();
            let at_azimuth = |k: usize| {
                let (sin, cos) = (k as f32 * std::f32::consts::FRAC_PI_8).sin_cos();
                f(Vec3::new(s * cos, s * sin, mu))
            };
            if isotropic {
                let r = at_azimuth(0);
                for c in 0..3 {
                    nodes[c][i] = [r[c]; 5];
                }
            } else {
                for k in 0..5 {
                    let r = at_azimuth(k);
                    for c in 0..3 {
                        nodes[c][i][k] = r[c];
                    }
                }
            }
        }
        RatioGrid { nodes, isotropic }
    }

    /// The μ node below `mu` and the blend weight towards the next one.
    #[inline(always)]
    fn mu_coord(mu: f32) -> (usize, f32) {
        #[allow(clippy::manual_clamp)] // NaN → 0, as `tables::axis_coord`
        let t = mu.max(0.0).min(1.0) * (RATIO_MU - 1) as f32;
        let i = (t as usize).min(RATIO_MU - 2);
        (i, t - i as f32)
    }

    /// The ratios at local view `v`.
    #[inline]
    fn at(&self, v: Vec3) -> [f32; 3] {
        let (i, w) = RatioGrid::mu_coord(v.z);
        let x = 2.0 * tables::aniso_weight(v) - 1.0;
        self.nodes.map(|c| {
            let (lo, hi) = (
                tables::azimuth_interpolate(c[i], x),
                tables::azimuth_interpolate(c[i + 1], x),
            );
            lo + (hi - lo) * w
        })
    }

    /// The grid of an isotropic lobe's albedo `albedo(μ)`, read back by
    /// [`RatioGrid::at_mu`].
    fn isotropic(albedo: impl Fn(Vec3) -> [f32; 3]) -> RatioGrid {
        RatioGrid::build(true, albedo)
    }

    /// An isotropic grid's values at view cosine `mu`, linearly between the μ nodes.
    #[inline]
    fn at_mu(&self, mu: f32) -> [f32; 3] {
        let (i, w) = RatioGrid::mu_coord(mu);
        self.nodes.map(|c| c[i][0] + (c[i + 1][0] - c[i][0]) * w)
    }
}

/// True when a GGX lobe needs the anisotropic albedo ([`ggx_aniso_e1`] and a Fresnel ratio).
#[inline(always)]
fn is_aniso(ggx: &Ggx) -> bool {
    ggx.ax != ggx.ay && !ggx.is_delta()
}

/// `E_avg = 2∫E1 μ dμ` for a masking variant.
pub(crate) fn e1_avg(masking: Masking, alpha: f32) -> f32 {
    let t = match masking {
        Masking::HeightCorrelated => TableId::EavgE1Hc,
        Masking::Separable => TableId::EavgE1Sep,
    };
    tables::lookup1(t, tables::ggx_axis(alpha))
}

/// Single-scattering directional albedo of GGX reflection with Fresnel `f` (from the tables):
/// `F0 E1 + (F90 − F0) S_q − a H82`; conductors through their F82 fit; exact
/// dielectric Fresnel through the dielectric `E_R` table (height-correlated; separable
/// masking rescales it by `E1_sep/E1_hc`, an approximation).
pub fn reflection_albedo(f: &Fresnel, masking: Masking, mu: f32, alpha: f32) -> Rgb {
    let y = tables::ggx_axis(alpha);
    let (sq, h82) = match masking {
        Masking::HeightCorrelated => (TableId::SqHc, TableId::H82Hc),
        Masking::Separable => (TableId::SqSep, TableId::H82Sep),
    };
    let e1v = tables::lookup2(e1_table(masking), mu, y);
    let schlick = |f0: Rgb, f90: Rgb, q: f32| {
        f0 * e1v + (f90 - f0) * tables::lookup3(sq, mu, y, tables::q_axis(q))
    };
    match *f {
        Fresnel::One => Vec3::splat(e1v),
        Fresnel::Schlick { f0, f90, q } => schlick(f0, f90, q),
        Fresnel::F82 { f0, f90, q, a } => {
            (schlick(f0, f90, q) - a * tables::lookup2(h82, mu, y)).max(Vec3::ZERO)
        }
        Fresnel::Dielectric { eta } => Vec3::splat(dielectric_albedos(masking, mu, alpha, eta)[0]),
        Fresnel::Conductor { eta, kappa } => {
            let (f0, t) = fresnel::conductor_to_f82(eta, kappa);
            let a = fresnel::f82_coefficient(f0, Vec3::ONE, 5.0, t);
            (schlick(f0, Vec3::ONE, 5.0) - a * tables::lookup2(h82, mu, y))
                .clamp(Vec3::ZERO, Vec3::ONE)
        }
    }
}

/// Dielectric albedos `[E_R, E_T, E_T without (1 − F)]` (transmission in the radiance
/// convention) from the tables; η outside [1/3, 3] is clamped.
pub fn dielectric_albedos(masking: Masking, mu: f32, alpha: f32, eta: f32) -> [f32; 3] {
    dielectric_albedos_masked(masking, mu, alpha, eta, [true; 3])
}

/// As [`dielectric_albedos`], looking up only the entries selected by `want` (others 0).
pub(crate) fn dielectric_albedos_masked(
    masking: Masking,
    mu: f32,
    alpha: f32,
    eta: f32,
    want: [bool; 3],
) -> [f32; 3] {
    let (inv, z) = tables::eta_axis(eta);
    let ids = if inv {
        [TableId::ErDielInv, TableId::EtDielInv, TableId::EtnDielInv]
    } else {
        [TableId::ErDiel, TableId::EtDiel, TableId::EtnDiel]
    };
    let y = tables::ggx_axis(alpha);
    let mut k = 0;
    let mut out = ids.map(|t| {
        k += 1;
        if want[k - 1] {
            tables::lookup3(t, mu, y, z)
        } else {
            0.0
        }
    });
    if masking == Masking::Separable {
        let r =
            e1(Masking::Separable, mu, alpha) / e1(Masking::HeightCorrelated, mu, alpha).max(1e-6);
        out = out.map(|e| e * r);
    }
    out
}

/// Turquin's factor `1 + k F_avg (1 − E_ss)/E_ss`.
fn turquin_scale(k: f32, f_avg: Rgb, masking: Masking, mu: f32, alpha: f32) -> Rgb {
    if k <= 0.0 {
        return Vec3::ONE;
    }
    let ess = e1(masking, mu, alpha).max(1e-4);
    Vec3::ONE + k.min(1.0) * f_avg * ((1.0 - ess) / ess)
}

/// GGX reflection with a Fresnel form and optional energy compensation. Layerable, except
/// with a conductor Fresnel (opaque).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MicrofacetR {
    /// The distribution (a delta when `max(α_x, α_y) < 1e-3`).
    pub ggx: Ggx,
    /// Masking–shadowing variant.
    pub masking: Masking,
    /// Fresnel factor.
    pub fresnel: Fresnel,
    /// Energy compensation.
    pub comp: Compensation,
}

/// Prepared [`MicrofacetR`].
#[derive(Debug, Clone, Copy)]
pub struct PreparedMicrofacetR {
    pub(in crate::interp) ggx: Ggx,
    pub(in crate::interp) masking: Masking,
    pub(in crate::interp) fresnel: Fresnel,
    pub(in crate::interp) v: Vec3,
    pub(in crate::interp) lambda_v: f32,
    /// The distribution's constants for `D` and `G2` at this view.
    pub(in crate::interp) view: GgxView,
    pub(in crate::interp) g1_v: f32,
    pub(in crate::interp) inv_4mu: f32,
    /// Turquin factor (1 when off).
    pub(in crate::interp) scale: Rgb,
    /// Kulla–Conty: `F_ms (1 − E(μ_o)) / (π (1 − E_avg))` (0 when off).
    pub(in crate::interp) ms: Rgb,
    pub(in crate::interp) e_row: Option<Row>,
    /// Probability of sampling the Kulla–Conty part.
    pub(in crate::interp) p_ms: f32,
    pub(in crate::interp) delta: bool,
    pub(in crate::interp) albedo: Rgb,
}

/// The view-independent part of a GGX reflection lobe's `prepare` ([`MicrofacetR::bind`]):
/// the Fresnel form the tables read and the albedo tables at the lobe's roughness.
#[derive(Debug, Clone, Copy)]
pub struct MicrofacetBound {
    pub(in crate::interp) albedo_fresnel: Fresnel,
    /// The distribution's view-independent constants ([`GgxView::constants`]).
    pub(in crate::interp) ggx_view: GgxView,
    /// `None` for a dielectric Fresnel (its albedo comes from the dielectric tables), and
    /// in the one-off bound of [`MicrofacetR::prepare`] (direct lookups).
    pub(in crate::interp) curves: Option<ReflectionCurves>,
    /// [`Ggx::lookup_alpha`], computed once.
    pub(in crate::interp) alpha: f32,
    /// The distribution is a delta ([`Ggx::is_delta`]).
    pub(in crate::interp) delta: bool,
    /// The Fresnel ratio per channel of a lobe that [`MicrofacetR::uses_ratio`] (`None`
    /// for other lobes, and in the one-off bound of [`MicrofacetR::prepare`]).
    pub(in crate::interp) ratios: Option<RatioGrid>,
}

/// `E1`, `S_q` and `H82` at a fixed roughness (and exponent).
#[derive(Debug, Clone, Copy)]
pub(in crate::interp) struct ReflectionCurves {
    e1: MuCurve,
    sq: Option<MuCurve>,
    h82: Option<MuCurve>,
}

impl ReflectionCurves {
    /// [`reflection_albedo`] for the forms the curves were built for (One, Schlick, F82).
    #[inline(always)]
    pub(in crate::interp) fn albedo(&self, f: &Fresnel, mu: f32) -> Rgb {
        let e1v = self.e1.at(mu);
        let sq = |c: &Option<MuCurve>| c.as_ref().map_or(0.0, |c| c.at(mu));
        let schlick = |f0: Rgb, f90: Rgb| f0 * e1v + (f90 - f0) * sq(&self.sq);
        match *f {
            Fresnel::Schlick { f0, f90, .. } => schlick(f0, f90),
            Fresnel::F82 { f0, f90, a, .. } => {
                f82_albedo(f0, f90, a, e1v, sq(&self.sq), sq(&self.h82))
            }
            _ => Vec3::splat(e1v),
        }
    }
}

/// The F82 albedo of [`ReflectionCurves::albedo`] from the curves' values `E1`, `S_q`, `H82`
/// at `μ_o` (also used by the lane-parallel prepare).
#[inline(always)]
pub(in crate::interp) fn f82_albedo(f0: Rgb, f90: Rgb, a: Rgb, e1: f32, sq: f32, h82: f32) -> Rgb {
    (f0 * e1 + (f90 - f0) * sq - a * h82).max(Vec3::ZERO)
}

impl MicrofacetR {
    /// True when the lobe's albedo is `E1` times the ratio of its own Fresnel to F = 1
    /// ([`MicrofacetR::ratio_albedo`]): an anisotropic lobe, whose albedo depends on the
    /// view's azimuth, and any rough conductor, whose complex Fresnel the
    /// generalized-Schlick tables only approximate (its F82 fit reads up to 3 % off).
    #[inline(always)]
    pub(in crate::interp) fn uses_ratio(&self) -> bool {
        is_aniso(&self.ggx) || (self.fresnel.is_conductor() && !self.ggx.is_delta())
    }

    /// The albedo of a lobe that [`MicrofacetR::uses_ratio`] at local view `v`, before any
    /// clamp or compensation: the `E1` table (the anisotropic one for an anisotropic lobe)
    /// times the ratio of the lobe's own Fresnel (a conductor's exact complex Fresnel, not
    /// its F82 fit) to F = 1, from `grid` (a bound lobe's; an isotropic lobe's holds the
    /// product) or else the quadrature at `v` ([`vndf_quadrature`]). Shared by the scalar and
    /// the lane-parallel prepares, so they agree bit for bit.
    pub(in crate::interp) fn ratio_albedo(&self, grid: Option<&RatioGrid>, v: Vec3) -> Rgb {
        let ratio = match grid {
            Some(g) if g.isotropic => return Vec3::from_array(g.at_mu(v.z)),
            Some(g) => Vec3::from_array(g.at(v)),
            None => aniso_fresnel_ratio(&self.fresnel, &self.ggx, self.masking, v),
        };
        let e1v = if is_aniso(&self.ggx) {
            ggx_aniso_e1(&self.ggx, self.masking, v)
        } else {
            e1(self.masking, v.z, self.ggx.lookup_alpha())
        };
        e1v * ratio
    }

    /// The Fresnel form the albedo tables read: a conductor through its F82 fit,
    /// any other form as it is. The fit costs two complex Fresnel evaluations, so a compiled
    /// material computes it once per constant leaf ([`MicrofacetR::prepare_bound`]).
    pub fn albedo_fresnel(&self) -> Fresnel {
        match self.fresnel {
            Fresnel::Conductor { eta, kappa } => {
                let (f0, t) = fresnel::conductor_to_f82(eta, kappa);
                Fresnel::F82 {
                    f0,
                    f90: Vec3::ONE,
                    q: 5.0,
                    a: fresnel::f82_coefficient(f0, Vec3::ONE, 5.0, t),
                }
            }
            f => f,
        }
    }
}

impl Leaf for MicrofacetR {
    type Prepared = PreparedMicrofacetR;
    type Bound = MicrofacetBound;

    /// Precomputes the view-only terms for `v` (`v.z > 0`).
    fn prepare(&self, v: Vec3, _flipped: bool) -> Self::Prepared {
        // Direct table lookups: baking the curves ([`MicrofacetR::bind`]) pays only when
        // reused.
        let bound = MicrofacetBound {
            albedo_fresnel: self.albedo_fresnel(),
            ggx_view: GgxView::constants(&self.ggx),
            curves: None,
            alpha: self.ggx.lookup_alpha(),
            delta: self.ggx.is_delta(),
            ratios: None,
        };
        self.prepare_bound(v, false, &bound)
    }

    /// The view-independent part of [`MicrofacetR::prepare`], for
    /// [`MicrofacetR::prepare_bound`].
    fn bind(&self) -> Self::Bound {
        let albedo_fresnel = self.albedo_fresnel();
        let y = tables::ggx_axis(self.ggx.lookup_alpha());
        let (sq, h82) = match self.masking {
            Masking::HeightCorrelated => (TableId::SqHc, TableId::H82Hc),
            Masking::Separable => (TableId::SqSep, TableId::H82Sep),
        };
        let curves = match albedo_fresnel {
            Fresnel::One => Some((None, None)),
            Fresnel::Schlick { q, .. } => {
                Some((Some(MuCurve::new3(sq, y, tables::q_axis(q))), None))
            }
            Fresnel::F82 { q, .. } => Some((
                Some(MuCurve::new3(sq, y, tables::q_axis(q))),
                Some(MuCurve::new2(h82, y)),
            )),
            Fresnel::Dielectric { .. } | Fresnel::Conductor { .. } => None,
        };
        MicrofacetBound {
            albedo_fresnel,
            ggx_view: GgxView::constants(&self.ggx),
            curves: curves.map(|(sq, h82)| ReflectionCurves {
                e1: MuCurve::new2(e1_table(self.masking), y),
                sq,
                h82,
            }),
            alpha: self.ggx.lookup_alpha(),
            delta: self.ggx.is_delta(),
            ratios: (self.uses_ratio() && self.fresnel != Fresnel::One).then(|| {
                let ratio =
                    |v| aniso_fresnel_ratio(&self.fresnel, &self.ggx, self.masking, v).to_array();
                if is_aniso(&self.ggx) {
                    RatioGrid::new(ratio)
                } else {
                    // The albedo itself (E1 · R), so a prepare reads one curve.
                    let alpha = self.ggx.lookup_alpha();
                    RatioGrid::isotropic(|v| {
                        let e1v = e1(self.masking, v.z, alpha);
                        ratio(v).map(|r| e1v * r)
                    })
                }
            }),
        }
    }

    /// As [`MicrofacetR::prepare`], with `bound` the result of [`MicrofacetR::bind`]
    /// (computed once by the caller).
    // Inlined into `Lobe::prepare_aux_into` so the state is stored straight into its record.
    #[inline(always)]
    fn prepare_bound(&self, v: Vec3, _flipped: bool, bound: &MicrofacetBound) -> Self::Prepared {
        let mut p = PreparedMicrofacetR {
            ggx: self.ggx,
            masking: self.masking,
            fresnel: self.fresnel,
            v,
            lambda_v: 0.0,
            view: bound.ggx_view,
            g1_v: 0.0,
            inv_4mu: 0.0,
            scale: Vec3::ONE,
            ms: Vec3::ZERO,
            e_row: None,
            p_ms: 0.0,
            delta: bound.delta,
            albedo: Vec3::ZERO,
        };
        self.set_view(&mut p, v, false, bound);
        p
    }

    /// The view-dependent fields of `p`, a record [`MicrofacetR::prepare_bound`] made of
    /// this lobe with `bound` (at any view): all that changes from view to view, so a
    /// record kept from an earlier point is brought to `v` by this alone.
    #[inline(always)]
    fn set_view(&self, p: &mut Self::Prepared, v: Vec3, _flipped: bool, bound: &MicrofacetBound) {
        let albedo_fresnel = &bound.albedo_fresnel;
        // A conductor's albedo and average Fresnel are its F82 fit's, clamped to [0, 1].
        let conductor = self.fresnel.is_conductor();
        let clamp1 = |c: Rgb| if conductor { c.min(Vec3::ONE) } else { c };
        let f_average = || clamp1(albedo_fresnel.average());
        let alpha = bound.alpha;
        let t = ViewTerms::from_constants(&bound.ggx_view, self.masking, v);
        p.v = v;
        p.lambda_v = t.lambda_v;
        p.view.c_z = t.view.c_z;
        p.view.c_s = t.view.c_s;
        p.g1_v = t.g1_v;
        p.inv_4mu = 0.25 / safe_mu(v.z);
        if p.delta {
            p.albedo = self.fresnel.eval(v.z);
            return;
        }
        // An anisotropic lobe's albedo depends on the view's azimuth, which the curves along
        // μ do not see, and a conductor's exact Fresnel is not a form the curves hold: both
        // are E1 times a Fresnel ratio.
        let ess = clamp1(match &bound.curves {
            _ if self.uses_ratio() => self.ratio_albedo(bound.ratios.as_ref(), v),
            Some(c) => c.albedo(albedo_fresnel, v.z),
            None => reflection_albedo(albedo_fresnel, self.masking, v.z, alpha),
        });
        match self.comp {
            Compensation::None => p.albedo = ess,
            Compensation::Turquin(k) => {
                p.scale = turquin_scale(k, f_average(), self.masking, v.z, alpha);
                p.albedo = ess * p.scale;
            }
            Compensation::KullaConty => {
                let f_avg = f_average();
                let e_avg = e1_avg(self.masking, alpha).min(1.0 - 1e-6);
                let f_ms = f_avg * f_avg * e_avg / (Vec3::ONE - f_avg * (1.0 - e_avg));
                let e_o = e1(self.masking, v.z, alpha);
                p.ms = f_ms * ((1.0 - e_o) * FRAC_1_PI / (1.0 - e_avg));
                p.e_row = Some(Row::new(e1_table(self.masking), tables::ggx_axis(alpha)));
                let a_ms = f_ms * (1.0 - e_o);
                let total = lum(ess + a_ms);
                p.p_ms = if total > 0.0 {
                    (lum(a_ms) / total).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                p.albedo = ess + a_ms;
            }
        }
    }
}

impl PreparedMicrofacetR {
    /// True when the lobe is a specular delta.
    pub fn is_delta(&self) -> bool {
        self.delta
    }
}

impl PreparedLeaf for PreparedMicrofacetR {
    /// Single-scattering `f·μ_i` and VNDF pdf at `l` (`l.z > 0`), plus the KC part.
    #[inline(always)]
    fn eval(&self, l: Vec3) -> LobeEval {
        if self.delta || l.z <= 0.0 {
            return LobeEval::ZERO;
        }
        let (vh2, _, d, dg) = self.view.reflect_squared(self.v, l);
        let f = self.fresnel.eval_squared(vh2) * (dg * self.inv_4mu) * self.scale;
        let pdf = d * self.g1_v * self.inv_4mu;
        match self.e_row {
            None => LobeEval { f_cos: f, pdf },
            Some(row) => LobeEval {
                f_cos: f + self.ms * ((1.0 - row.at(l.z)) * l.z),
                pdf: (1.0 - self.p_ms) * pdf + self.p_ms * pdf_cosine(l.z),
            },
        }
    }

    /// Density of [`PreparedMicrofacetR::sample`] at `l`.
    #[inline]
    fn pdf(&self, l: Vec3) -> f32 {
        if self.delta || l.z <= 0.0 {
            return 0.0;
        }
        let (_, _, d, _) = self.view.reflect_squared(self.v, l);
        let pdf = d * self.g1_v * self.inv_4mu;
        (1.0 - self.p_ms) * pdf + self.p_ms * pdf_cosine(l.z)
    }

    /// VNDF sample (`u[0]`, `u[1]`); `u[2]` chooses the Kulla–Conty part when present.
    fn sample(&self, u: [f32; 3]) -> Option<LobeSample> {
        if self.delta {
            return Some(LobeSample {
                l: Vec3::new(-self.v.x, -self.v.y, self.v.z),
                weight: self.fresnel.eval(self.v.z) * self.scale,
                pdf: 1.0,
                delta: true,
            });
        }
        if self.e_row.is_some() {
            let l = if u[2] < self.p_ms {
                sample_cosine(u[0], u[1])?
            } else {
                reflect(self.v, self.ggx.sample_vndf(self.v, u[0], u[1]))
            };
            let e = self.eval(l);
            if e.pdf <= 0.0 {
                return None;
            }
            return Some(LobeSample {
                l,
                weight: e.f_cos / e.pdf,
                pdf: e.pdf,
                delta: false,
            });
        }
        let h = self.ggx.sample_vndf(self.v, u[0], u[1]);
        let vh = self.v.dot(h);
        let l = reflect(self.v, h);
        if l.z <= 0.0 || vh <= 0.0 {
            return None;
        }
        let g = g2(self.masking, self.lambda_v, self.ggx.lambda(l));
        let pdf = self.ggx.d(h) * self.g1_v * self.inv_4mu;
        if pdf <= 0.0 {
            return None;
        }
        Some(LobeSample {
            l,
            weight: self.fresnel.eval(vh) * self.scale * (g / self.g1_v),
            pdf,
            delta: false,
        })
    }

    /// Directional albedo (tables; compensation included).
    fn albedo(&self) -> LobeAlbedo {
        LobeAlbedo::reflect(self.albedo)
    }
}

pub use crate::ir::closure::DielectricMode;

pub(crate) mod soa;

/// GGX dielectric interface with exact Fresnel. Transmission uses the radiance
/// convention of Walter et al. 2007.
///
/// Choices where the spec is silent or slips:
/// * The refraction density includes the Jacobian factor `η'²`:
///   `pdf_T = (1 − P_R) D_V(h) η'² |L·h| / (V·h + η' L·h)²` (Walter 2007 eq. 17; pbrt-v4).
///   Without `η'²` the density does not integrate to one and the χ² test fails. Sample
///   weights then average to the radiance-convention `E_T`.
/// * With `t_fresnel = false` the reflection probability uses the transmission factor 1
///   instead of `1 − F`: `P_R = F lum(T_r) / (F lum(T_r) + lum(T_t))`.
/// * Seen from below, a mode `T` lobe with `t_fresnel = false` is the whole interface: it
///   evaluates as `RT` with `t_fresnel` on (the reflection layer the recipe puts above it is
///   one-sided), so glass seen from inside reflects with the inverted index and
///   conserves energy.
/// * Delta refraction (α below the cut-off) has weight `T_t (1 − F)/η'²` (radiance
///   convention, consistent with `E_T`), not `1 − F`.
/// * `eval`'s Fresnel factor for a refraction pair is computed from the optically denser
///   side, and `sample` returns `eval`'s density and `f/pdf` for the sampled direction, so
///   that both are exactly what `pdf(L)` gives (f32 conditioning near the critical angle).
/// * Separable masking reuses the height-correlated `E_R`/`E_T` tables rescaled by
///   `E1_sep/E1_hc` (no separable dielectric tables are generated).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dielectric {
    /// The distribution (a delta when `max(α_x, α_y) < 1e-3`).
    pub ggx: Ggx,
    /// Masking–shadowing variant.
    pub masking: Masking,
    /// Interior over exterior index (inverted when the view is below the surface).
    pub eta: f32,
    /// Which hemispheres.
    pub mode: DielectricMode,
    /// Reflection tint `T_r`.
    pub tint_r: Rgb,
    /// Transmission tint `T_t`.
    pub tint_t: Rgb,
    /// Keep the `(1 − F)` factor of the transmission lobe (default true).
    pub t_fresnel: bool,
    /// Turquin compensation strength k of the reflection part (0 = off).
    pub turquin: f32,
}

impl Dielectric {
    /// A dielectric with unit tints, `t_fresnel` on, no compensation.
    #[cfg(feature = "testkit")]
    pub fn new(ggx: Ggx, masking: Masking, eta: f32, mode: DielectricMode) -> Dielectric {
        Dielectric {
            ggx,
            masking,
            eta,
            mode,
            tint_r: Vec3::ONE,
            tint_t: Vec3::ONE,
            t_fresnel: true,
            turquin: 0.0,
        }
    }
}

/// Prepared [`Dielectric`].
#[derive(Debug, Clone, Copy)]
pub struct PreparedDielectric {
    pub(in crate::interp) ggx: Ggx,
    pub(in crate::interp) masking: Masking,
    /// Index on L's (transmitted) side over V's side.
    pub(in crate::interp) eta: f32,
    pub(in crate::interp) v: Vec3,
    pub(in crate::interp) lambda_v: f32,
    /// The distribution's constants for `D` and `G2` at this view.
    pub(in crate::interp) view: GgxView,
    pub(in crate::interp) g1_v: f32,
    pub(in crate::interp) inv_mu: f32,
    pub(in crate::interp) refl: bool,
    pub(in crate::interp) trans: bool,
    pub(in crate::interp) tint_r: Rgb,
    pub(in crate::interp) tint_t: Rgb,
    pub(in crate::interp) lum_r: f32,
    pub(in crate::interp) lum_t: f32,
    pub(in crate::interp) t_fresnel: bool,
    pub(in crate::interp) delta: bool,
    pub(in crate::interp) albedo: LobeAlbedo,
}

/// The view-independent part of a dielectric's `prepare` ([`Dielectric::bind`]): its albedo
/// tables `[E_R, E_T, E_T without (1 − F)]` at its roughness, for η and for 1/η (a view from
/// below). Only height-correlated, non-delta lobes have them.
#[derive(Debug, Clone, Copy)]
pub struct DielectricBound {
    pub(in crate::interp) curves: Option<[[MuCurve; 3]; 2]>,
    /// An anisotropic lobe's ratios `[E_R, E_T, E_T without (1 − F)]/E1` at η and at 1/η
    /// ([`Dielectric::aniso_albedos`]; `None` for an isotropic or delta lobe, and in the
    /// one-off bound of [`Dielectric::prepare`]).
    pub(in crate::interp) aniso: Option<[Option<RatioGrid>; 2]>,
    /// The distribution's view-independent constants ([`GgxView::constants`]).
    pub(in crate::interp) ggx_view: GgxView,
    /// The lobe's view-independent scalars.
    pub(in crate::interp) consts: DielectricConsts,
}

/// The scalars of a dielectric's `prepare` that do not depend on the view, computed once
/// per bind rather than per point.
#[derive(Debug, Clone, Copy)]
pub(in crate::interp) struct DielectricConsts {
    /// [`Dielectric::eta0`].
    eta0: f32,
    /// The distribution is a delta.
    delta: bool,
    /// [`Ggx::lookup_alpha`].
    alpha: f32,
    /// `max(lum(tint_r), 0)` before any Turquin factor, and `max(lum(tint_t), 0)`.
    lum_r: f32,
    lum_t: f32,
}

impl Dielectric {
    /// `[E_R, E_T, E_T without (1 − F)]` of an anisotropic lobe at local view `v` and relative
    /// index `eta` (the anisotropic `E1` table times the ratios: `grid`'s, a bound lobe's at
    /// `eta`, else the quadrature's at `v`, [`vndf_quadrature`]; entries not in `want` are
    /// 0), shared by the scalar
    /// and the lane-parallel prepares.
    pub(in crate::interp) fn aniso_albedos(
        &self,
        grid: Option<&RatioGrid>,
        v: Vec3,
        eta: f32,
        want: [bool; 3],
    ) -> [f32; 3] {
        let e1 = ggx_aniso_e1(&self.ggx, self.masking, v);
        let ratios = match grid {
            Some(g) => g.at(v),
            None => aniso_dielectric_ratios(&self.ggx, self.masking, v, eta, want),
        };
        let mut k = 0;
        ratios.map(|r| {
            k += 1;
            if want[k - 1] { r * e1 } else { 0.0 }
        })
    }

    /// η, with invalid values replaced by 1.
    pub(in crate::interp) fn eta0(&self) -> f32 {
        if self.eta.is_finite() && self.eta > 0.0 {
            self.eta
        } else {
            1.0
        }
    }

    /// True when this lobe, seen from below (`flipped`), stands for the whole interface: a
    /// transmission lobe without its `(1 − F)` factor leaves the reflection to a separate
    /// layer above it, and that layer is one-sided, so from inside the lobe reflects (Fresnel
    /// with the inverted index, total internal reflection beyond the critical angle) and
    /// keeps `(1 − F)` on its transmission, as an `RT` lobe does.
    #[inline(always)]
    fn whole_interface(&self, flipped: bool) -> bool {
        flipped && self.mode == DielectricMode::T && !self.t_fresnel
    }

    /// The view-independent scalars of [`Dielectric::prepare`].
    fn consts(&self) -> DielectricConsts {
        DielectricConsts {
            eta0: self.eta0(),
            delta: self.ggx.is_delta(),
            alpha: self.ggx.lookup_alpha(),
            lum_r: lum(self.tint_r).max(0.0),
            lum_t: lum(self.tint_t).max(0.0),
        }
    }
}

impl Leaf for Dielectric {
    type Prepared = PreparedDielectric;
    type Bound = DielectricBound;

    /// Precomputes the view-only terms for `v` (`v.z > 0`); `flipped` says the view was
    /// below the surface (the frame was flipped), so η is inverted.
    fn prepare(&self, v: Vec3, flipped: bool) -> Self::Prepared {
        let bound = DielectricBound {
            curves: None,
            aniso: None,
            ggx_view: GgxView::constants(&self.ggx),
            consts: self.consts(),
        };
        self.prepare_bound(v, flipped, &bound)
    }

    /// The view-independent part of [`Dielectric::prepare`].
    fn bind(&self) -> Self::Bound {
        let ggx_view = GgxView::constants(&self.ggx);
        let consts = self.consts();
        let aniso = is_aniso(&self.ggx).then(|| {
            // A reflection-only lobe needs no transmission ratios.
            let want = [
                true,
                self.mode != DielectricMode::R,
                self.mode != DielectricMode::R,
            ];
            [consts.eta0, 1.0 / consts.eta0].map(|eta| {
                Some(RatioGrid::new(|v| {
                    aniso_dielectric_ratios(&self.ggx, self.masking, v, eta, want)
                }))
            })
        });
        if self.masking != Masking::HeightCorrelated || self.ggx.is_delta() {
            return DielectricBound {
                curves: None,
                aniso,
                ggx_view,
                consts,
            };
        }
        let y = tables::ggx_axis(self.ggx.lookup_alpha());
        let at = |eta: f32| {
            let (inv, z) = tables::eta_axis(eta);
            let ids = if inv {
                [TableId::ErDielInv, TableId::EtDielInv, TableId::EtnDielInv]
            } else {
                [TableId::ErDiel, TableId::EtDiel, TableId::EtnDiel]
            };
            ids.map(|t| MuCurve::new3(t, y, z))
        };
        let eta0 = consts.eta0;
        DielectricBound {
            curves: Some([at(eta0), at(1.0 / eta0)]),
            aniso,
            ggx_view,
            consts,
        }
    }

    /// [`Dielectric::prepare`] with the result of [`Dielectric::bind`].
    // Inlined into `Lobe::prepare_aux_into` so the state is stored straight into its record.
    #[inline(always)]
    fn prepare_bound(
        &self,
        v: Vec3,
        flipped: bool,
        bound: &DielectricBound,
    ) -> Self::Prepared {
        let c = &bound.consts;
        let whole = self.whole_interface(flipped);
        let mut p = PreparedDielectric {
            ggx: self.ggx,
            masking: self.masking,
            eta: if flipped { 1.0 / c.eta0 } else { c.eta0 },
            v,
            lambda_v: 0.0,
            view: bound.ggx_view,
            g1_v: 0.0,
            inv_mu: 0.0,
            refl: self.mode != DielectricMode::T || whole,
            trans: self.mode != DielectricMode::R,
            tint_r: self.tint_r,
            tint_t: self.tint_t,
            lum_r: c.lum_r,
            lum_t: c.lum_t,
            t_fresnel: self.t_fresnel || whole,
            delta: c.delta,
            albedo: LobeAlbedo::default(),
        };
        self.set_view(&mut p, v, flipped, bound);
        p
    }

    /// The view-dependent fields of `p`, a record [`Dielectric::prepare_bound`] made of
    /// this lobe with `bound` and `flipped` (at any view): all that changes from view to
    /// view, so a record kept from an earlier point is brought to `v` by this alone.
    #[inline(always)]
    fn set_view(
        &self,
        p: &mut Self::Prepared,
        v: Vec3,
        flipped: bool,
        bound: &DielectricBound,
    ) {
        let eta = p.eta;
        let t = ViewTerms::from_constants(&bound.ggx_view, self.masking, v);
        let alpha = bound.consts.alpha;
        p.v = v;
        p.lambda_v = t.lambda_v;
        p.view.c_z = t.view.c_z;
        p.view.c_s = t.view.c_s;
        p.g1_v = t.g1_v;
        p.inv_mu = 1.0 / safe_mu(v.z);
        // Turquin's factor only when on: the dielectric's average Fresnel costs a logarithm.
        if self.turquin > 0.0 {
            let f_avg = Vec3::splat(fresnel::dielectric_avg(eta));
            p.tint_r = self.tint_r * turquin_scale(self.turquin, f_avg, self.masking, v.z, alpha);
            p.lum_r = lum(p.tint_r).max(0.0);
        }
        let (refl, trans) = (p.refl, p.trans);
        let [er, et, etn] = if p.delta {
            let f = fresnel::dielectric(v.z, eta);
            let t = if f < 1.0 { 1.0 / (eta * eta) } else { 0.0 };
            [f, (1.0 - f) * t, t]
        } else {
            let want = [refl, trans && p.t_fresnel, trans && !p.t_fresnel];
            match &bound.curves {
                _ if is_aniso(&self.ggx) => {
                    let grid = bound
                        .aniso
                        .as_ref()
                        .and_then(|g| g[usize::from(flipped)].as_ref());
                    self.aniso_albedos(grid, v, eta, want)
                }
                Some(c) => {
                    let c = &c[usize::from(flipped)];
                    let at = |i: usize| if want[i] { c[i].at(v.z) } else { 0.0 };
                    [at(0), at(1), at(2)]
                }
                None => dielectric_albedos_masked(self.masking, v.z, alpha, eta, want),
            }
        };
        if refl {
            p.albedo.reflect = p.tint_r * er;
        }
        if trans {
            p.albedo.transmit = self.tint_t * if p.t_fresnel { et } else { etn };
            p.albedo.transmit_energy = p.albedo.transmit * (eta * eta);
        }
    }
}

impl PreparedDielectric {
    /// True when the lobe is a specular delta.
    pub fn is_delta(&self) -> bool {
        self.delta
    }

    /// Relative index `η'` of the transmitted side over the view side.
    #[cfg(feature = "testkit")]
    pub fn eta(&self) -> f32 {
        self.eta
    }

    #[inline]
    fn t_factor(&self, f: f32) -> f32 {
        if self.t_fresnel { 1.0 - f } else { 1.0 }
    }

    /// Probability of choosing reflection for a microfacet with Fresnel `f`.
    #[inline]
    fn p_reflect(&self, f: f32) -> f32 {
        match (self.refl, self.trans) {
            (true, false) => 1.0,
            (false, _) => 0.0,
            (true, true) => {
                let a = f * self.lum_r;
                let b = self.t_factor(f) * self.lum_t;
                if a + b > 0.0 { a / (a + b) } else { f }
            }
        }
    }

    /// The transmission half vector (oriented to `+z`) when `(v, l)` is a valid refraction
    /// pair: `(h, V·h, L·h, |V + η'L|²)` with `V·h > 0 > L·h`. The last value is the
    /// squared Walter denominator `(V·h + η' L·h)²`, computed without cancellation.
    #[inline]
    fn transmission_half(&self, l: Vec3) -> Option<(Vec3, f32, f32, f32)> {
        let ht = self.v + self.eta * l;
        let ht = if ht.z < 0.0 { -ht } else { ht };
        let len2 = ht.length_squared();
        if len2 < 1e-20 {
            return None;
        }
        let h = ht / len2.sqrt();
        let (vh, lh) = (self.v.dot(h), l.dot(h));
        (vh > 0.0 && lh < 0.0).then_some((h, vh, lh, len2))
    }

    /// Fresnel reflectance of a refraction pair, computed from the optically denser side:
    /// `F(V·h, η)` equals `F(|L·h|, 1/η)`, and for η < 1 the latter avoids the cancellation in
    /// `η² + μ² − 1` near the critical angle (it keeps `1 − F` accurate in f32).
    #[inline]
    fn fresnel_t(&self, vh: f32, lh: f32) -> f32 {
        if self.eta < 1.0 {
            fresnel::dielectric(-lh, 1.0 / self.eta)
        } else {
            fresnel::dielectric(vh, self.eta)
        }
    }

    fn sample_delta(&self, u: f32) -> Option<LobeSample> {
        let f = fresnel::dielectric(self.v.z, self.eta);
        let p_r = self.p_reflect(f);
        if u < p_r {
            return Some(LobeSample {
                l: Vec3::new(-self.v.x, -self.v.y, self.v.z),
                weight: self.tint_r * (f / p_r),
                pdf: p_r,
                delta: true,
            });
        }
        let l = refract(self.v, Vec3::Z, self.eta)?;
        let p_t = 1.0 - p_r;
        (p_t > 0.0).then(|| LobeSample {
            l,
            weight: self.tint_t * (self.t_factor(f) / (self.eta * self.eta * p_t)),
            pdf: p_t,
            delta: true,
        })
    }
}

impl PreparedLeaf for PreparedDielectric {
    /// `f·|μ_i|` and the pdf of [`PreparedDielectric::sample`].
    #[inline(always)]
    fn eval(&self, l: Vec3) -> LobeEval {
        if self.delta {
            return LobeEval::ZERO;
        }
        if l.z > 0.0 {
            if !self.refl {
                return LobeEval::ZERO;
            }
            // D, G2 and the Fresnel term from the unnormalised half vector, as the batched
            // kernels compute them.
            let (vh, hh, d, dg) = self.view.reflect(self.v, l);
            let f = fresnel::dielectric_half(vh, hh, self.eta * self.eta - 1.0);
            let q = 0.25 * self.inv_mu;
            LobeEval {
                f_cos: self.tint_r * (f * dg * q),
                pdf: self.p_reflect(f) * self.g1_v * d * q,
            }
        } else if l.z < 0.0 {
            if !self.trans {
                return LobeEval::ZERO;
            }
            let Some((h, vh, lh, denom2)) = self.transmission_half(l) else {
                return LobeEval::ZERO;
            };
            let f = self.fresnel_t(vh, lh);
            let d = self.ggx.d(h);
            let g = g2(self.masking, self.lambda_v, self.ggx.lambda(l));
            let jac = -lh / denom2;
            let base = d * vh * jac * self.inv_mu;
            LobeEval {
                f_cos: self.tint_t * (self.t_factor(f) * g * base),
                pdf: (1.0 - self.p_reflect(f)) * self.g1_v * base * (self.eta * self.eta),
            }
        } else {
            LobeEval::ZERO
        }
    }

    /// Density of [`PreparedDielectric::sample`] at `l`.
    #[inline]
    fn pdf(&self, l: Vec3) -> f32 {
        self.eval(l).pdf
    }

    /// VNDF sample (`u[0]`, `u[1]`), reflection or refraction chosen with `u[2]`.
    fn sample(&self, u: [f32; 3]) -> Option<LobeSample> {
        if self.delta {
            return self.sample_delta(u[2]);
        }
        let h = self.ggx.sample_vndf(self.v, u[0], u[1]);
        let vh = self.v.dot(h);
        if vh <= 0.0 {
            return None;
        }
        let p_r = self.p_reflect(fresnel::dielectric(vh, self.eta));
        let l = if u[2] < p_r {
            let l = reflect(self.v, h);
            if l.z <= 0.0 {
                return None;
            }
            l
        } else {
            let l = refract(self.v, h, self.eta)?;
            if l.z >= 0.0 {
                return None;
            }
            l
        };
        // The Fresnel factor is ill-conditioned in f32 near the critical angle and refraction
        // near grazing, so density and weight are those `eval` gives for the returned
        // direction (bit-consistent with `pdf(L)`, as MIS needs).
        let e = self.eval(l);
        (e.pdf > 0.0).then(|| LobeSample {
            l,
            weight: e.f_cos / e.pdf,
            pdf: e.pdf,
            delta: false,
        })
    }

    /// Reflected and transmitted albedos (transmission also as energy, `η'² E_T`).
    fn albedo(&self) -> LobeAlbedo {
        self.albedo
    }
}
