//! Sheen leaves: Conty–Kulla "Charlie" sheen with MaterialX or
//! original masking, and Zeltner, Burley & Chiang's LTC sheen.
//!
//! Prepared forms assume the (possibly flipped) view has `μ_o > 0`.

use crate::interp::leaves::{Leaf, LobeAlbedo, LobeEval, LobeSample, PreparedLeaf};
use crate::interp::math::{sample_cosine, sample_uniform_hemisphere};
use crate::interp::tables::{self, MuCurve, TableId};
use glam::Vec3;
use std::f32::consts::{FRAC_1_PI, PI};

pub use crate::ir::closure::SheenMasking;

pub(crate) mod soa;

/// Smallest Conty–Kulla roughness.
pub(crate) const SHEEN_CK_MIN_R: f32 = 0.005;

/// Conty–Kulla sheen (layerable).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SheenCK {
    /// Roughness r, clamped to [0.005, 1].
    pub r: f32,
    /// Masking variant.
    pub masking: SheenMasking,
}

/// Coefficients `(a, b, c, d, e)` of the original masking's `L(x)`.
fn ck_coefficients(r: f32) -> [f32; 5] {
    let p0 = [21.5473, 3.82987, 0.19823, -1.97760, -4.32054];
    let p1 = [25.3245, 3.32435, 0.16801, -1.27393, -4.85967];
    let t = (1.0 - r) * (1.0 - r);
    [0, 1, 2, 3, 4].map(|k| p0[k] + (p1[k] - p0[k]) * t)
}

/// `ln Λ(μ)` of the original masking.
fn ck_ln_lambda(c: &[f32; 5], mu: f32) -> f32 {
    let big_l = |x: f32| c[0] / (1.0 + c[1] * x.max(0.0).powf(c[2])) + c[3] * x + c[4];
    if mu < 0.5 {
        big_l(mu)
    } else {
        2.0 * big_l(0.5) - big_l(1.0 - mu)
    }
}

/// The view-independent part of a [`SheenCK`] lobe's prepare ([`SheenCK::bind`]): its
/// albedo curve and the terms of its clamped roughness.
#[derive(Debug, Clone, Copy)]
pub struct SheenCKBound {
    pub(in crate::interp) curve: MuCurve,
    pub(in crate::interp) half_inv_r: f32,
    pub(in crate::interp) norm: f32,
    coef: [f32; 5],
}

/// Prepared [`SheenCK`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PreparedSheenCK {
    pub(in crate::interp) v: Vec3,
    pub(in crate::interp) half_inv_r: f32,
    pub(in crate::interp) norm: f32,
    pub(in crate::interp) masking: SheenMasking,
    pub(in crate::interp) coef: [f32; 5],
    pub(in crate::interp) lambda_o: f32,
    pub(in crate::interp) inv_4mu: f32,
    pub(in crate::interp) albedo: f32,
}

impl SheenCK {

    fn table(&self) -> TableId {
        match self.masking {
            SheenMasking::MaterialX => TableId::SheenMx,
            SheenMasking::Original => TableId::SheenOrig,
        }
    }

    /// The roughness clamped to its range (NaN → 1).
    fn clamped_r(&self) -> f32 {
        if self.r.is_nan() {
            1.0
        } else {
            self.r.clamp(SHEEN_CK_MIN_R, 1.0)
        }
    }

    /// The albedo table at this lobe's roughness, for [`SheenCK::prepare_bound`].
    pub fn albedo_curve(&self) -> MuCurve {
        MuCurve::new2(self.table(), tables::sheen_axis(self.clamped_r()))
    }

    /// The prepared lobe given its table albedo `e` at `μ_o`.
    #[inline]
    fn prepare_with_albedo(&self, v: Vec3, e: f32) -> PreparedSheenCK {
        let r = self.clamped_r();
        let coef = ck_coefficients(r);
        PreparedSheenCK {
            v,
            half_inv_r: 0.5 / r,
            norm: (2.0 + 1.0 / r) * 0.5 * FRAC_1_PI,
            masking: self.masking,
            coef,
            // Λ(μ_o) is read by the original masking only (it costs a `powf` and an `exp`).
            lambda_o: match self.masking {
                SheenMasking::Original => ck_ln_lambda(&coef, v.z).exp(),
                SheenMasking::MaterialX => 0.0,
            },
            inv_4mu: 0.25 / v.z.max(1e-7),
            albedo: e,
        }
    }
}

impl Leaf for SheenCK {
    type Prepared = PreparedSheenCK;
    type Bound = SheenCKBound;

    /// Precomputes the view-only terms for `v` (`v.z > 0`).
    fn prepare(&self, v: Vec3, _flipped: bool) -> Self::Prepared {
        // One lookup: baking the whole curve ([`SheenCK::albedo_curve`]) pays only when
        // reused.
        let e = tables::lookup2(self.table(), v.z, tables::sheen_axis(self.clamped_r()));
        self.prepare_with_albedo(v, e)
    }

    /// The view-independent part of [`SheenCK::prepare`] ([`SheenCKBound`]).
    fn bind(&self) -> Self::Bound {
        let p = self.prepare_with_albedo(Vec3::Z, 0.0);
        SheenCKBound {
            curve: self.albedo_curve(),
            half_inv_r: p.half_inv_r,
            norm: p.norm,
            coef: p.coef,
        }
    }

    /// [`SheenCK::prepare`] with the result of [`SheenCK::bind`].
    // Inlined into `Lobe::prepare_aux_into` so the state is stored straight into its record.
    #[inline(always)]
    fn prepare_bound(&self, v: Vec3, _flipped: bool, b: &SheenCKBound) -> Self::Prepared {
        let mut p = PreparedSheenCK {
            v,
            half_inv_r: b.half_inv_r,
            norm: b.norm,
            masking: self.masking,
            coef: b.coef,
            lambda_o: 0.0,
            inv_4mu: 0.0,
            albedo: 0.0,
        };
        self.set_view(&mut p, v, false, b);
        p
    }

    /// The view-dependent fields of `p`, a record [`SheenCK::prepare_bound`] made of this
    /// lobe with `b` (at any view): all that changes from view to view.
    #[inline(always)]
    fn set_view(&self, p: &mut Self::Prepared, v: Vec3, _flipped: bool, b: &SheenCKBound) {
        p.v = v;
        p.lambda_o = match self.masking {
            SheenMasking::Original => ck_ln_lambda(&b.coef, v.z).exp(),
            SheenMasking::MaterialX => 0.0,
        };
        p.inv_4mu = 0.25 / v.z.max(1e-7);
        p.albedo = b.curve.at(v.z);
    }
}

impl PreparedLeaf for PreparedSheenCK {
    /// `f·μ_i` and the uniform-hemisphere pdf.
    #[inline(always)]
    fn eval(&self, l: Vec3) -> LobeEval {
        if l.z <= 0.0 {
            return LobeEval::ZERO;
        }
        let hh = self.v + l;
        let sin2 = ((hh.x * hh.x + hh.y * hh.y) / hh.length_squared()).min(1.0);
        let d = self.norm * sin2.powf(self.half_inv_r);
        let (mi, mo) = (l.z, self.v.z);
        let f = match self.masking {
            SheenMasking::MaterialX => d * mi / (4.0 * (mi + mo - mi * mo)),
            SheenMasking::Original => {
                let m = 1.0 - mi;
                let m2 = m * m;
                let m8 = m2 * m2 * m2 * m2;
                let lambda_i = (ck_ln_lambda(&self.coef, mi) * (1.0 + 2.0 * m8)).exp();
                d * self.inv_4mu / (1.0 + lambda_i + self.lambda_o)
            }
        };
        LobeEval {
            f_cos: Vec3::splat(f),
            pdf: 0.5 * FRAC_1_PI,
        }
    }

    /// Uniform-hemisphere density.
    #[inline]
    fn pdf(&self, l: Vec3) -> f32 {
        if l.z > 0.0 { 0.5 * FRAC_1_PI } else { 0.0 }
    }

    /// Uniform-hemisphere sample.
    fn sample(&self, u: [f32; 3]) -> Option<LobeSample> {
        let l = sample_uniform_hemisphere(u[0], u[1]);
        let e = self.eval(l);
        (e.pdf > 0.0).then(|| LobeSample {
            l,
            weight: e.f_cos * (2.0 * PI),
            pdf: e.pdf,
            delta: false,
        })
    }

    /// Directional albedo (table).
    fn albedo(&self) -> LobeAlbedo {
        LobeAlbedo::reflect(Vec3::splat(self.albedo))
    }
}

/// Zeltner–Burley–Chiang LTC sheen (OpenPBR fuzz; layerable; non-reciprocal).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SheenLTC {
    /// Roughness r, clamped to [0.01, 1].
    pub r: f32,
}

/// The LTC sheen's fitted directional albedo `Ê(μ_o, r)` (clamped at 0).
#[inline(always)]
#[cfg(feature = "testkit")]
pub fn sheen_ltc_albedo(x: f32, y: f32) -> f32 {
    SheenLTCBound::at_roughness(y).albedo(x)
}

/// The view-independent part of a [`SheenLTC`] lobe: its clamped roughness and the three
/// roughness-only rational fits of `Ê` (three divisions a prepare would otherwise repeat;
/// the same operations in the same order, so the same bits).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SheenLTCBound {
    /// Roughness as the fits take it (clamped to [0.01, 1]; NaN reads 1).
    y: f32,
    /// Width, mean and offset of `Ê`'s Gaussian in `μ_o`.
    s: f32,
    m: f32,
    o: f32,
    /// `s·√(2π)`.
    s_norm: f32,
}

impl SheenLTCBound {
    /// The fits at roughness `y` (already clamped).
    #[inline(always)]
    fn at_roughness(y: f32) -> SheenLTCBound {
        let s = y * (0.0206607 + 1.58491 * y) / (0.0379424 + y * (1.32227 + y));
        let m = y * (-0.193854 + y * (-1.14885 + y * (1.7932 - 0.95943 * y * y))) / (0.046391 + y);
        let o =
            y * (0.000654023 + (-0.0207818 + 0.119681 * y) * y) / (1.26264 + y * (-1.92021 + y));
        SheenLTCBound {
            y,
            s,
            m,
            o,
            s_norm: s * (2.0 * PI).sqrt(),
        }
    }

    /// `Ê(x)` at `x = μ_o` (clamped at 0).
    #[inline(always)]
    pub fn albedo(&self, x: f32) -> f32 {
        let q = (x - self.m) / self.s;
        (crate::interp::vmath::exp(-0.5 * q * q) / self.s_norm + self.o).max(0.0)
    }
}

/// The LTC coefficients `(a, b)` at `(μ_o, r)`.
#[inline(always)]
pub(crate) fn sheen_ltc_coefficients(x: f32, y: f32) -> (f32, f32) {
    let a = (2.58126 * x + 0.813703 * y) * y / (1.0 + 0.310327 * x * x + 2.60994 * x * y);
    let b = (1.0 - x).max(0.0).sqrt() * (y - 1.0) * y * y * y
        / (0.0000254053 + 1.71228 * x - 1.71506 * x * y + 1.34174 * y * y);
    (a, b)
}

/// Prepared [`SheenLTC`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PreparedSheenLTC {
    /// LTC frame axes in the lobe's local frame (`X` toward V's tangential part).
    pub(in crate::interp) ax_x: Vec3,
    pub(in crate::interp) ax_y: Vec3,
    pub(in crate::interp) a: f32,
    pub(in crate::interp) b: f32,
    pub(in crate::interp) e_hat: f32,
}

impl SheenLTC {

    /// [`SheenLTC::prepare_bound`] given its albedo `e_hat` (`fit.albedo(μ_o)`, clamped
    /// `μ_o`), for callers that have already computed it.
    #[inline(always)]
    pub(in crate::interp) fn prepare_bound_with_albedo(
        v: Vec3,
        fit: &SheenLTCBound,
        e_hat: f32,
    ) -> PreparedSheenLTC {
        let y = fit.y;
        let x = v.z.clamp(0.0, 1.0);
        let t = Vec3::new(v.x, v.y, 0.0);
        // Blended, not branched (see `Frame::new`).
        let ax_x = crate::interp::vmath::select3(t.length_squared() > 1e-14, t.normalize(), Vec3::X);
        let (a, b) = sheen_ltc_coefficients(x, y);
        PreparedSheenLTC {
            ax_x,
            ax_y: Vec3::Z.cross(ax_x),
            a: a.max(1e-7),
            b,
            e_hat,
        }
    }
}

impl Leaf for SheenLTC {
    type Prepared = PreparedSheenLTC;
    type Bound = SheenLTCBound;

    /// Precomputes the view-only terms (LTC frame, coefficients, `Ê`) for `v` (`v.z > 0`).
    #[inline(always)]
    fn prepare(&self, v: Vec3, _flipped: bool) -> Self::Prepared {
        self.prepare_bound(v, false, &self.bind())
    }

    /// The view-independent part of [`SheenLTC::prepare`].
    fn bind(&self) -> Self::Bound {
        let y = if self.r.is_nan() {
            1.0
        } else {
            self.r.clamp(0.01, 1.0)
        };
        SheenLTCBound::at_roughness(y)
    }

    /// [`SheenLTC::prepare`] with the result of [`SheenLTC::bind`].
    // Inlined into `Lobe::prepare_aux_into` so the state is stored straight into its record.
    #[inline(always)]
    fn prepare_bound(&self, v: Vec3, _flipped: bool, fit: &SheenLTCBound) -> Self::Prepared {
        Self::prepare_bound_with_albedo(v, fit, fit.albedo(v.z.clamp(0.0, 1.0)))
    }
}

impl PreparedSheenLTC {
    /// The LTC density `D(w)` of a direction with `l.z > 0`.
    #[inline]
    fn density(&self, l: Vec3) -> f32 {
        let (wx, wy, wz) = (l.dot(self.ax_x), l.dot(self.ax_y), l.z);
        let wp = Vec3::new(self.a * wx + self.b * wz, self.a * wy, wz);
        let k = self.a / wp.length_squared().max(1e-30);
        wz.max(0.0) * FRAC_1_PI * k * k
    }
}

impl PreparedLeaf for PreparedSheenLTC {
    /// `Ê·D(w)` and the exact pdf `D(w)`.
    #[inline(always)]
    fn eval(&self, l: Vec3) -> LobeEval {
        if l.z <= 0.0 {
            return LobeEval::ZERO;
        }
        let d = self.density(l);
        LobeEval {
            f_cos: Vec3::splat(self.e_hat * d),
            pdf: d,
        }
    }

    /// Exact pdf `D(w)`.
    #[inline]
    fn pdf(&self, l: Vec3) -> f32 {
        if l.z <= 0.0 { 0.0 } else { self.density(l) }
    }

    /// Exact LTC sample: cosine-sample `w'`, map by the LTC matrix; weight `Ê`.
    fn sample(&self, u: [f32; 3]) -> Option<LobeSample> {
        let wp = sample_cosine(u[0], u[1])?;
        let w = Vec3::new((wp.x - self.b * wp.z) / self.a, wp.y / self.a, wp.z).normalize();
        let l = self.ax_x * w.x + self.ax_y * w.y + Vec3::Z * w.z;
        if l.z <= 0.0 {
            return None;
        }
        let pdf = self.density(l);
        (pdf > 0.0).then(|| LobeSample {
            l,
            weight: Vec3::splat(self.e_hat),
            pdf,
            delta: false,
        })
    }

    /// Directional albedo: exactly `Ê` (the LTC has unit mass).
    fn albedo(&self) -> LobeAlbedo {
        LobeAlbedo::reflect(Vec3::splat(self.e_hat))
    }
}
