//! The leaf instruction set: [`Lobe`] (parameters inline, one enum variant per leaf family)
//! and [`PreparedLobe`] (the same with every view-only term precomputed).
//!
//! Everything here works in the lobe's local frame (normal `+z`):
//! callers transform V and L with a [`super::Frame`]. The interpreter calls
//! [`Lobe::prepare`] once per (point, V) and then [`PreparedLobe::eval`],
//! [`PreparedLobe::sample`], [`PreparedLobe::pdf`] and [`PreparedLobe::albedo`] as often as
//! it likes; none of them allocates, recurses or uses trait objects.
//!
//! Hemispheres: reflection lobes return 0 unless `μ_i > 0` and `μ_o > 0`; transmission lobes
//! need `μ_i μ_o < 0`. With [`Sides::Both`] a lobe seen from below (`μ_o < 0`) flips its
//! frame (`z → −z`, `y → −y`) first; with [`Sides::Front`] it is inactive (zero) instead.
//! Lobes with a transmission part (Dielectric, Translucent) and Transparent are always
//! two-sided. A view exactly on the horizon (`μ_o = 0`) makes every BSDF lobe inactive.

use super::diffuse::{
    Burley, Lambert, MiaDiffuse, OrenNayar, OrenNayarBound, OrenNayarVariant, PreparedBurley,
    PreparedLambert, PreparedMiaDiffuse, PreparedOrenNayar, PreparedTranslucent,
};
use super::emission::{Emission, Transparent};
use super::math::{Rgb, flip};
use super::microfacet::{
    Dielectric, DielectricBound, MicrofacetBound, MicrofacetR, PreparedDielectric,
    PreparedMicrofacetR,
};
#[cfg(feature = "testkit")]
use super::{
    microfacet::{Compensation, DielectricMode},
    sheen::SheenMasking,
};
use super::sheen::{
    PreparedSheenCK, PreparedSheenLTC, SheenCK, SheenCKBound, SheenLTC, SheenLTCBound,
};
use super::ward::{MiaHighlight3, PreparedMiaHighlight3, PreparedWard, Ward, WardBound};
use super::leaves::{Leaf, PreparedLeaf};
pub use super::leaves::{LobeAlbedo, LobeEval, LobeSample};
use glam::Vec3;

/// Layering class of a leaf.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg(feature = "testkit")]
pub enum LobeClass {
    /// Throughput 0.
    Opaque,
    /// Throughput from its albedo and the layer's tint mode.
    Layerable,
    /// Throughput 1 (emission, transparency).
    PassThrough,
}

/// Reciprocity of a leaf.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg(feature = "testkit")]
pub enum Reciprocity {
    /// `f(V, L) = f(L, V)`.
    Reciprocal,
    /// `f(V, L)/η_V² = f(L, V)/η_L²` (dielectric transmission).
    Generalized,
    /// Not reciprocal (by construction).
    NonReciprocal,
    /// Not a BSDF (emission, transparency).
    NotApplicable,
}

/// Whether a reflection lobe also responds when seen from below.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Sides {
    /// One-sided: zero for `μ_o ≤ 0`.
    #[default]
    Front,
    /// Two-sided: the frame flips for `μ_o < 0`.
    Both,
}

/// Names of the leaf kinds (for inspection, AOVs and reports).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LobeKind {
    /// Lambert.
    Lambert,
    /// Lambert on the opposite hemisphere.
    Translucent,
    /// Qualitative Oren–Nayar.
    OrenNayarQ,
    /// Fujii Oren–Nayar (single scattering of EON).
    OrenNayarF,
    /// Energy-preserving Oren–Nayar.
    OrenNayarE,
    /// mia_material diffuse.
    MiaDiffuse,
    /// Burley diffuse.
    Burley,
    /// Lambert standing in for subsurface scattering.
    SubsurfaceProxy,
    /// GGX reflection with a Fresnel form.
    MicrofacetR,
    /// GGX dielectric interface.
    Dielectric,
    /// Ward (classic or GM).
    Ward,
    /// mia_material's three-lobe highlight.
    MiaHighlight3,
    /// Conty–Kulla sheen.
    SheenCK,
    /// LTC sheen.
    SheenLTC,
    /// Emission.
    Emission,
    /// Straight transparency.
    Transparent,
}

impl LobeKind {
    /// Lower-case name (`lambert`, `microfacet_r`, ...).
    pub fn name(self) -> &'static str {
        match self {
            LobeKind::Lambert => "lambert",
            LobeKind::Translucent => "translucent",
            LobeKind::OrenNayarQ => "oren_nayar_q",
            LobeKind::OrenNayarF => "oren_nayar_f",
            LobeKind::OrenNayarE => "oren_nayar_e",
            LobeKind::MiaDiffuse => "mia_diffuse",
            LobeKind::Burley => "burley",
            LobeKind::SubsurfaceProxy => "subsurface_proxy",
            LobeKind::MicrofacetR => "microfacet_r",
            LobeKind::Dielectric => "dielectric",
            LobeKind::Ward => "ward",
            LobeKind::MiaHighlight3 => "mia_highlight3",
            LobeKind::SheenCK => "sheen_ck",
            LobeKind::SheenLTC => "sheen_ltc",
            LobeKind::Emission => "emission",
            LobeKind::Transparent => "transparent",
        }
    }
}

/// One leaf with its parameters inline.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Lobe {
    /// Lambert, `f = ρ/π`.
    Lambert(Lambert),
    /// Lambert on the opposite hemisphere (two-sided).
    Translucent(Lambert),
    /// Oren–Nayar family (QON, FON, EON).
    OrenNayar(OrenNayar),
    /// mia_material's diffuse.
    MiaDiffuse(MiaDiffuse),
    /// Burley diffuse.
    Burley(Burley),
    /// Lambert standing in for subsurface scattering (flagged for renderers).
    SubsurfaceProxy(Lambert),
    /// GGX reflection with a Fresnel form (generalized Schlick, F82, dielectric, conductor).
    MicrofacetR(MicrofacetR),
    /// GGX dielectric interface (R, T or RT; two-sided).
    Dielectric(Dielectric),
    /// Ward (classic or GM).
    Ward(Ward),
    /// mia_material's three-lobe highlight.
    MiaHighlight3(MiaHighlight3),
    /// Conty–Kulla sheen.
    SheenCK(SheenCK),
    /// LTC sheen.
    SheenLTC(SheenLTC),
    /// Emission (not part of the BSDF).
    #[cfg_attr(not(feature = "testkit"), allow(dead_code))]
    Emission(Emission),
    /// Straight transparency (delta).
    #[cfg_attr(not(feature = "testkit"), allow(dead_code))]
    Transparent(Transparent),
}

/// A lobe with its view-only terms computed: what `eval`/`sample` run on.
#[derive(Debug, Clone, Copy)]
pub struct PreparedLobe {
    pub(super) kind: LobeKind,
    /// The frame was flipped (view below the surface of a two-sided lobe).
    pub(super) flipped: bool,
    pub(super) state: State,
}

#[derive(Debug, Clone, Copy)]
pub(super) enum State {
    Inactive,
    Lambert(PreparedLambert),
    Translucent(PreparedTranslucent),
    OrenNayar(PreparedOrenNayar),
    MiaDiffuse(PreparedMiaDiffuse),
    Burley(PreparedBurley),
    MicrofacetR(PreparedMicrofacetR),
    Dielectric(PreparedDielectric),
    Ward(PreparedWard),
    MiaHighlight3(PreparedMiaHighlight3),
    SheenCK(PreparedSheenCK),
    SheenLTC(PreparedSheenLTC),
    Emission(Rgb),
    Transparent(Transparent, Vec3),
}

impl Lobe {
    /// The leaf's kind.
    pub fn kind(&self) -> LobeKind {
        match self {
            Lobe::Lambert(_) => LobeKind::Lambert,
            Lobe::Translucent(_) => LobeKind::Translucent,
            Lobe::OrenNayar(o) => match o.variant {
                OrenNayarVariant::Qualitative => LobeKind::OrenNayarQ,
                OrenNayarVariant::Fujii => LobeKind::OrenNayarF,
                OrenNayarVariant::Energy | OrenNayarVariant::EnergyFast => LobeKind::OrenNayarE,
            },
            Lobe::MiaDiffuse(_) => LobeKind::MiaDiffuse,
            Lobe::Burley(_) => LobeKind::Burley,
            Lobe::SubsurfaceProxy(_) => LobeKind::SubsurfaceProxy,
            Lobe::MicrofacetR(_) => LobeKind::MicrofacetR,
            Lobe::Dielectric(_) => LobeKind::Dielectric,
            Lobe::Ward(_) => LobeKind::Ward,
            Lobe::MiaHighlight3(_) => LobeKind::MiaHighlight3,
            Lobe::SheenCK(_) => LobeKind::SheenCK,
            Lobe::SheenLTC(_) => LobeKind::SheenLTC,
            Lobe::Emission(_) => LobeKind::Emission,
            Lobe::Transparent(_) => LobeKind::Transparent,
        }
    }

    /// Layering class.
    #[cfg(feature = "testkit")]
    pub fn class(&self) -> LobeClass {
        match self {
            Lobe::MicrofacetR(m) if m.fresnel.is_conductor() => LobeClass::Opaque,
            Lobe::Dielectric(d) if d.mode != DielectricMode::R => LobeClass::Opaque,
            Lobe::MicrofacetR(_)
            | Lobe::Dielectric(_)
            | Lobe::Ward(_)
            | Lobe::MiaHighlight3(_)
            | Lobe::SheenCK(_)
            | Lobe::SheenLTC(_) => LobeClass::Layerable,
            Lobe::Emission(_) | Lobe::Transparent(_) => LobeClass::PassThrough,
            _ => LobeClass::Opaque,
        }
    }

    /// Reciprocity.
    #[cfg(feature = "testkit")]
    pub fn reciprocity(&self) -> Reciprocity {
        let turquin = |k: f32| k > 0.0;
        match self {
            // mia's highlight is divided by its directional albedo at μ_o.
            Lobe::MiaDiffuse(_) | Lobe::SheenLTC(_) | Lobe::MiaHighlight3(_) => {
                Reciprocity::NonReciprocal
            }
            Lobe::SheenCK(s) if s.masking == SheenMasking::Original => Reciprocity::NonReciprocal,
            Lobe::MicrofacetR(MicrofacetR {
                comp: Compensation::Turquin(k),
                ..
            }) if turquin(*k) => Reciprocity::NonReciprocal,
            Lobe::Dielectric(d) if turquin(d.turquin) && d.mode != DielectricMode::T => {
                Reciprocity::NonReciprocal
            }
            Lobe::Dielectric(d) if d.mode != DielectricMode::R => Reciprocity::Generalized,
            Lobe::Emission(_) | Lobe::Transparent(_) => Reciprocity::NotApplicable,
            _ => Reciprocity::Reciprocal,
        }
    }

    /// True for leaves that may see light from below the surface whatever [`Sides`] says.
    pub fn is_two_sided(&self) -> bool {
        matches!(
            self,
            Lobe::Translucent(_) | Lobe::Dielectric(_) | Lobe::Transparent(_)
        )
    }

    /// Precomputes every view-only term for local view `v` (unit, local frame).
    pub fn prepare(&self, v: Vec3, sides: Sides) -> PreparedLobe {
        self.prepare_aux(v, sides, &Aux::None)
    }

    /// This lobe with its view-independent precomputation done once ([`BoundLobe`]).
    pub fn bind(&self) -> BoundLobe {
        let aux = match self {
            Lobe::MicrofacetR(m) => Aux::Microfacet(m.bind()),
            Lobe::Dielectric(d) => Aux::Dielectric(d.bind()),
            Lobe::Ward(w) => Aux::Ward(w.bind()),
            Lobe::SheenCK(s) => Aux::SheenCK(s.bind()),
            Lobe::SheenLTC(s) => Aux::SheenLTC(s.bind()),
            Lobe::OrenNayar(o) => Aux::OrenNayar(o.bind()),
            _ => Aux::None,
        };
        BoundLobe { lobe: *self, aux }
    }

    #[inline]
    fn prepare_aux(&self, v: Vec3, sides: Sides, aux: &Aux) -> PreparedLobe {
        let mut out = PreparedLobe {
            kind: LobeKind::Lambert,
            flipped: false,
            state: State::Inactive,
        };
        self.prepare_aux_into(v, sides, aux, &mut out);
        out
    }

    /// [`Lobe::prepare_aux`] writing into `out`: each family's state is built in the
    /// record, not in a temporary that is then copied (a prepared lobe is ~170 bytes; the
    /// copies were a tenth of a material's prepare, and reading a temporary just written
    /// with narrower stores stalls store forwarding).
    #[inline]
    fn prepare_aux_into(&self, v: Vec3, sides: Sides, aux: &Aux, out: &mut PreparedLobe) {
        out.kind = self.kind();
        out.flipped = false;
        if let Lobe::Emission(e) = self {
            out.state = State::Emission(e.radiance);
            return;
        }
        if let Lobe::Transparent(t) = self {
            out.state = State::Transparent(*t, v);
            return;
        }
        let may_flip = sides == Sides::Both || self.is_two_sided();
        let flipped = v.z < 0.0 && may_flip;
        out.flipped = flipped;
        let v = if flipped { flip(v) } else { v };
        if v.z <= 0.0 || !v.is_finite() {
            out.state = State::Inactive;
            return;
        }
        // A record at a fixed index usually held the same family at the previous prepare:
        // then the new state is written over the old one field by field, with no temporary
        // (copying a freshly written temporary stalls store forwarding).
        macro_rules! put {
            ($variant:ident, $value:expr) => {
                match &mut out.state {
                    State::$variant(p) => *p = $value,
                    s => *s = State::$variant($value),
                }
            };
        }
        match self {
            Lobe::Lambert(l) | Lobe::SubsurfaceProxy(l) => put!(Lambert, l.prepare(v, false)),
            Lobe::Translucent(l) => put!(Translucent, PreparedTranslucent(l.prepare(v, false))),
            Lobe::OrenNayar(o) => put!(
                OrenNayar,
                match aux {
                    Aux::OrenNayar(b) => o.prepare_bound(v, false, b),
                    _ => o.prepare(v, false),
                }
            ),
            Lobe::MiaDiffuse(m) => put!(MiaDiffuse, m.prepare(v, false)),
            Lobe::Burley(b) => put!(Burley, b.prepare(v, false)),
            Lobe::MicrofacetR(m) => put!(
                MicrofacetR,
                match aux {
                    Aux::Microfacet(b) => m.prepare_bound(v, false, b),
                    _ => m.prepare(v, false),
                }
            ),
            Lobe::Dielectric(d) => put!(
                Dielectric,
                match aux {
                    Aux::Dielectric(b) => d.prepare_bound(v, flipped, b),
                    _ => d.prepare(v, flipped),
                }
            ),
            Lobe::Ward(w) => put!(
                Ward,
                match aux {
                    Aux::Ward(c) => w.prepare_bound(v, false, c),
                    _ => w.prepare(v, false),
                }
            ),
            Lobe::MiaHighlight3(m) => put!(MiaHighlight3, m.prepare(v, false)),
            Lobe::SheenCK(s) => put!(
                SheenCK,
                match aux {
                    Aux::SheenCK(c) => s.prepare_bound(v, false, c),
                    _ => s.prepare(v, false),
                }
            ),
            Lobe::SheenLTC(s) => put!(
                SheenLTC,
                match aux {
                    Aux::SheenLTC(b) => s.prepare_bound(v, false, b),
                    _ => s.prepare(v, false),
                }
            ),
            Lobe::Emission(_) | Lobe::Transparent(_) => out.state = State::Inactive,
        }
    }
}

/// A [`Lobe`] with the part of `prepare` that depends on neither the point nor the view
/// computed once (a conductor's albedo along μ and F82 fit; the albedo tables at the lobe's roughness,
/// index and exponent): what a compiled material keeps for leaves whose parameters are
/// constants. [`BoundLobe::prepare`] equals [`Lobe::prepare`].
#[derive(Debug, Clone, Copy)]
pub struct BoundLobe {
    pub(super) lobe: Lobe,
    pub(super) aux: Aux,
}

/// The per-family view-independent data of a [`BoundLobe`]. One per constant leaf, built
/// at compile time; the size difference between variants is harmless there, and boxing
/// would add an indirection to every prepare.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Copy)]
pub(super) enum Aux {
    None,
    Microfacet(MicrofacetBound),
    Dielectric(DielectricBound),
    Ward(WardBound),
    SheenCK(SheenCKBound),
    SheenLTC(SheenLTCBound),
    OrenNayar(OrenNayarBound),
}

impl BoundLobe {
    /// The lobe.
    #[cfg(feature = "testkit")]
    pub fn lobe(&self) -> &Lobe {
        &self.lobe
    }

    /// [`Lobe::prepare`] without redoing the view-independent part.
    #[inline]
    pub fn prepare(&self, v: Vec3, sides: Sides) -> PreparedLobe {
        self.lobe.prepare_aux(v, sides, &self.aux)
    }

    /// [`BoundLobe::prepare`] into an existing record.
    #[inline]
    pub(super) fn prepare_into(&self, v: Vec3, sides: Sides, out: &mut PreparedLobe) {
        self.lobe.prepare_aux_into(v, sides, &self.aux, out)
    }
}

/// A [`BoundLobe`] as the refresh of a record above the surface reads it: the family's
/// lobe and bound data in one variant, so one dispatch picks the family's `set_view`
/// (matching the lobe and its bound data as a pair costs a dispatch each, per leaf and
/// point).
#[allow(clippy::large_enum_variant)] // one per leaf of a uniform material, read per point
#[derive(Debug, Clone, Copy)]
pub(super) enum RefreshLeaf {
    /// A Lambert or subsurface proxy: nothing depends on the view.
    Lambert,
    OrenNayar(OrenNayar, OrenNayarBound),
    MicrofacetR(MicrofacetR, MicrofacetBound),
    Dielectric(Dielectric, DielectricBound),
    Ward(Ward, WardBound),
    SheenCK(SheenCK, SheenCKBound),
    /// Every field of the LTC sheen depends on the view: its record is written whole.
    SheenLTC(SheenLTC, SheenLTCBound),
    /// Any other lobe, prepared whole.
    Whole,
}

impl BoundLobe {
    /// This lobe as [`RefreshLeaf::refresh_above_into`] reads it.
    pub(super) fn refresh_leaf(&self) -> RefreshLeaf {
        match (&self.lobe, &self.aux) {
            (Lobe::Lambert(_) | Lobe::SubsurfaceProxy(_), _) => RefreshLeaf::Lambert,
            (Lobe::OrenNayar(o), Aux::OrenNayar(b)) => RefreshLeaf::OrenNayar(*o, *b),
            (Lobe::MicrofacetR(m), Aux::Microfacet(b)) => RefreshLeaf::MicrofacetR(*m, *b),
            (Lobe::Dielectric(d), Aux::Dielectric(b)) => RefreshLeaf::Dielectric(*d, *b),
            (Lobe::Ward(w), Aux::Ward(b)) => RefreshLeaf::Ward(*w, *b),
            (Lobe::SheenCK(s), Aux::SheenCK(b)) => RefreshLeaf::SheenCK(*s, *b),
            (Lobe::SheenLTC(s), Aux::SheenLTC(b)) => RefreshLeaf::SheenLTC(*s, *b),
            _ => RefreshLeaf::Whole,
        }
    }
}

impl RefreshLeaf {
    /// [`BoundLobe::prepare_into`] of the lobe `lobe` (of which this is
    /// [`BoundLobe::refresh_leaf`]) for a view `v` above the surface (`v.z > 0` and
    /// finite, where no lobe flips or goes inactive), returning the reflected part of its
    /// albedo: the per-leaf step of the uniform-material prepare. `out` must hold a record
    /// of that lobe prepared above the surface at some other view (an earlier point's, or
    /// the view straight up): its kind, flip flag and view-independent fields are already
    /// there, so only the view-dependent ones are written (each family's `set_view`, which
    /// its `prepare_bound` also ends with). The record and the albedo are the same bits. A
    /// record of another family is prepared whole.
    #[inline(always)]
    pub(super) fn refresh_above_into(
        &self,
        lobe: &BoundLobe,
        v: Vec3,
        out: &mut PreparedLobe,
    ) -> Rgb {
        debug_assert!(v.z > 0.0 && v.is_finite() && !out.flipped);
        match (self, &mut out.state) {
            (RefreshLeaf::Lambert, State::Lambert(p)) => p.albedo().reflect,
            (RefreshLeaf::OrenNayar(o, b), State::OrenNayar(p)) => {
                o.set_view(p, v, false, b);
                p.albedo().reflect
            }
            (RefreshLeaf::MicrofacetR(m, b), State::MicrofacetR(p)) => {
                m.set_view(p, v, false, b);
                p.albedo().reflect
            }
            (RefreshLeaf::Dielectric(d, b), State::Dielectric(p)) => {
                d.set_view(p, v, false, b);
                p.albedo().reflect
            }
            (RefreshLeaf::Ward(w, b), State::Ward(p)) => {
                w.set_view(p, v, false, b);
                p.albedo().reflect
            }
            (RefreshLeaf::SheenCK(s, b), State::SheenCK(p)) => {
                s.set_view(p, v, false, b);
                p.albedo().reflect
            }
            (RefreshLeaf::SheenLTC(s, b), State::SheenLTC(p)) => {
                s.set_view(p, v, false, b);
                p.albedo().reflect
            }
            _ => {
                lobe.prepare_into(v, Sides::Front, out);
                out.albedo().reflect
            }
        }
    }
}

impl PreparedLobe {
    /// The leaf's kind.
    pub fn kind(&self) -> LobeKind {
        self.kind
    }

    /// True for the subsurface proxy (renderers may substitute a BSSRDF).
    pub fn is_subsurface(&self) -> bool {
        self.kind == LobeKind::SubsurfaceProxy
    }

    /// True when the view was below the surface and the frame was flipped.
    pub fn is_flipped(&self) -> bool {
        self.flipped
    }

    /// True when the lobe has no response at this view (back-facing one-sided lobe, or a
    /// view on the horizon).
    pub fn is_inactive(&self) -> bool {
        matches!(self.state, State::Inactive)
    }

    /// True for delta lobes (transparency; GGX lobes below the delta cut-off).
    pub fn is_delta(&self) -> bool {
        match &self.state {
            State::Transparent(..) => true,
            State::MicrofacetR(m) => m.is_delta(),
            State::Dielectric(d) => d.is_delta(),
            _ => false,
        }
    }

    /// `f(V, L)·|μ_i|` (RGB) and the pdf of [`PreparedLobe::sample`] at `l` (local frame).
    // Always inlined, as are the family `eval`s it dispatches to: a non-inlined call returns
    // its `LobeEval` through memory, written as 8 + 4 + 4 bytes and read back as 16, and that
    // store-forwarding stall was half of `Prepared::eval`'s own time (perf annotate).
    #[inline(always)]
    pub fn eval(&self, l: Vec3) -> LobeEval {
        self.eval_unflipped(if self.flipped { flip(l) } else { l })
    }

    /// [`PreparedLobe::eval`] of a lobe that is not flipped ([`PreparedLobe::is_flipped`]),
    /// or with `l` already flipped. The material's eval takes this path when no lobe is
    /// flipped: the test of the flag, and the selection of `l` that follows it, sit at the
    /// head of every lobe's dependency chain (measured: up to 12 ns per lobe when one lobe
    /// is evaluated in a loop; about 3 % of ref10's eval, where lobes overlap).
    #[inline(always)]
    pub(super) fn eval_unflipped(&self, l: Vec3) -> LobeEval {
        match &self.state {
            State::Inactive | State::Emission(_) | State::Transparent(..) => LobeEval::ZERO,
            State::Lambert(p) => p.eval(l),
            State::Translucent(p) => p.eval(l),
            State::OrenNayar(p) => p.eval(l),
            State::MiaDiffuse(p) => p.eval(l),
            State::Burley(p) => p.eval(l),
            State::MicrofacetR(p) => p.eval(l),
            State::Dielectric(p) => p.eval(l),
            State::Ward(p) => p.eval(l),
            State::MiaHighlight3(p) => p.eval(l),
            State::SheenCK(p) => p.eval(l),
            State::SheenLTC(p) => p.eval(l),
        }
    }

    /// Density of [`PreparedLobe::sample`] at `l` (0 for delta lobes).
    #[inline]
    pub fn pdf(&self, l: Vec3) -> f32 {
        let l = if self.flipped { flip(l) } else { l };
        match &self.state {
            State::Inactive | State::Emission(_) | State::Transparent(..) => 0.0,
            State::Lambert(p) => p.pdf(l),
            State::Translucent(p) => p.pdf(l),
            State::OrenNayar(p) => p.pdf(l),
            State::MiaDiffuse(p) => p.pdf(l),
            State::Burley(p) => p.pdf(l),
            State::MicrofacetR(p) => p.pdf(l),
            State::Dielectric(p) => p.pdf(l),
            State::Ward(p) => p.pdf(l),
            State::MiaHighlight3(p) => p.pdf(l),
            State::SheenCK(p) => p.pdf(l),
            State::SheenLTC(p) => p.pdf(l),
        }
    }

    /// Samples a direction from `u ∈ [0, 1)³` (`u[0]`, `u[1]` drive the direction; `u[2]`
    /// any discrete choice inside the lobe). `None` when the sample carries no energy.
    #[inline]
    pub fn sample(&self, u: [f32; 3]) -> Option<LobeSample> {
        let s = match &self.state {
            State::Inactive | State::Emission(_) => None,
            State::Transparent(t, v) => return Some(t.sample(*v)),
            State::Lambert(p) => p.sample(u),
            State::Translucent(p) => p.sample(u),
            State::OrenNayar(p) => p.sample(u),
            State::MiaDiffuse(p) => p.sample(u),
            State::Burley(p) => p.sample(u),
            State::MicrofacetR(p) => p.sample(u),
            State::Dielectric(p) => p.sample(u),
            State::Ward(p) => p.sample(u),
            State::MiaHighlight3(p) => p.sample(u),
            State::SheenCK(p) => p.sample(u),
            State::SheenLTC(p) => p.sample(u),
        }?;
        if s.pdf.is_nan() || s.pdf <= 0.0 || !s.weight.is_finite() {
            return None;
        }
        Some(if self.flipped {
            LobeSample { l: flip(s.l), ..s }
        } else {
            s
        })
    }

    /// Directional albedo at the prepared view (tables or closed forms).
    pub fn albedo(&self) -> LobeAlbedo {
        match &self.state {
            State::Inactive | State::Emission(_) => LobeAlbedo::default(),
            State::Transparent(t, _) => t.albedo(),
            State::Lambert(p) => p.albedo(),
            State::Translucent(p) => p.albedo(),
            State::OrenNayar(p) => p.albedo(),
            State::MiaDiffuse(p) => p.albedo(),
            State::Burley(p) => p.albedo(),
            State::MicrofacetR(p) => p.albedo(),
            State::Dielectric(p) => p.albedo(),
            State::Ward(p) => p.albedo(),
            State::MiaHighlight3(p) => p.albedo(),
            State::SheenCK(p) => p.albedo(),
            State::SheenLTC(p) => p.albedo(),
        }
    }

    /// Emitted radiance (emission leaves only).
    pub fn emission(&self) -> Rgb {
        match self.state {
            State::Emission(e) => e,
            _ => Vec3::ZERO,
        }
    }

    /// Straight-through transmittance (transparent leaves only).
    pub fn transparency(&self) -> Rgb {
        match self.state {
            State::Transparent(t, _) => t.tint,
            _ => Vec3::ZERO,
        }
    }
}
