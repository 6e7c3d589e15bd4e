//! The structure-of-arrays kernels of the GGX conductor and dielectric (mode R) reflection leaves: their lanes
//! ([`crate::interp::soa`]), the per-lane setters that `Kernel::rebuild` and the lane-parallel
//! prepare share (both fold the slot's weight and probability into the same fields in the
//! same order) and the batched eval.

use super::{Dielectric, MicrofacetR, RatioGrid};
use crate::interp::fresnel::Fresnel;
use crate::interp::ggx::ViewTerms;
use crate::interp::math::safe_mu;
use crate::interp::tables::{LaneCoords, MuCurve};
use crate::interp::soa::{Acc, LaneWeights, Vec3x, add_baked, lane_l};
use crate::interp::fresnel::{self, dielectric_half};
use crate::interp::ggx::GgxView;
use glam::Vec3;

/// Conductor lanes (see [`crate::interp::microfacet::PreparedMicrofacetR`]).
#[derive(Debug, Clone, Copy)]
pub(in crate::interp) struct ConductorX<const W: usize> {
    pub(in crate::interp) g: GgxX<W>,
    /// `p G1(V)/(4 μ_o)` (`p`: the slot's probability): the pdf term is `D` times this.
    pub(in crate::interp) pdf_c: [f32; W],
    /// `η² − κ²` per channel.
    pub(in crate::interp) e2mk2: Vec3x<W>,
    /// `4 η² κ²` per channel.
    pub(in crate::interp) four_e2k2: Vec3x<W>,
    /// `w scale/(4 μ_o)` (`w`: the slot's weight): the `f·μ_i` term is `F D G2` times this.
    pub(in crate::interp) scale_q: Vec3x<W>,
}

/// Dielectric (mode R) lanes (see [`crate::interp::microfacet::PreparedDielectric`]).
#[derive(Debug, Clone, Copy)]
pub(in crate::interp) struct DielectricX<const W: usize> {
    pub(in crate::interp) g: GgxX<W>,
    /// `η² − 1`.
    pub(in crate::interp) e2m1: [f32; W],
    /// `p G1(V)/(4 μ_o)`: the pdf term is `D` times this.
    pub(in crate::interp) pdf_c: [f32; W],
    /// `w tint_r/(4 μ_o)`: the `f·μ_i` term is `F D G2` times this.
    pub(in crate::interp) tint_q: Vec3x<W>,
}

/// The view-dependent GGX terms shared by the microfacet kernels: each lane's
/// [`GgxView`] (copied from the scalar prepare in [`Kernel::rebuild`]) as arrays.
#[derive(Debug, Clone, Copy)]
pub(in crate::interp) struct GgxX<const W: usize> {
    pub(in crate::interp) v: Vec3x<W>,
    pub(in crate::interp) inv_ax: [f32; W],
    pub(in crate::interp) inv_ay: [f32; W],
    pub(in crate::interp) ax2: [f32; W],
    pub(in crate::interp) ay2: [f32; W],
    /// `π αx αy`.
    pub(in crate::interp) pi_axay: [f32; W],
    /// The masking as `c_z l_z + c_s S_l` (see [`GgxX::reflect_terms`]): height-correlated
    /// `(1 + 2Λv, 1)`, separable `(1 + Λv, 1 + Λv)`.
    pub(in crate::interp) c_z: [f32; W],
    pub(in crate::interp) c_s: [f32; W],
}

impl<const W: usize> GgxX<W> {
    pub(in crate::interp) fn zero() -> Self {
        GgxX {
            v: Vec3x::zero(),
            inv_ax: [0.0; W],
            inv_ay: [0.0; W],
            ax2: [0.0; W],
            ay2: [0.0; W],
            pi_axay: [0.0; W],
            c_z: [0.0; W],
            c_s: [0.0; W],
        }
    }

    #[inline(always)]
    pub(in crate::interp) fn set(&mut self, k: usize, v: Vec3, g: &GgxView) {
        self.set_consts(k, g);
        self.set_view(k, v, g);
    }

    /// Lane `k`'s view-independent constants.
    #[inline(always)]
    pub(in crate::interp) fn set_consts(&mut self, k: usize, g: &GgxView) {
        self.inv_ax[k] = g.inv_ax;
        self.inv_ay[k] = g.inv_ay;
        self.ax2[k] = g.ax2;
        self.ay2[k] = g.ay2;
        self.pi_axay[k] = g.pi_axay;
    }

    /// Lane `k`'s view and the masking coefficients at it.
    #[inline(always)]
    pub(in crate::interp) fn set_view(&mut self, k: usize, v: Vec3, g: &GgxView) {
        self.v.set(k, v);
        self.c_z[k] = g.c_z;
        self.c_s[k] = g.c_s;
    }

    /// Lane `k`'s constants.
    #[inline(always)]
    pub(in crate::interp) fn lane(&self, k: usize) -> GgxView {
        GgxView {
            inv_ax: self.inv_ax[k],
            inv_ay: self.inv_ay[k],
            ax2: self.ax2[k],
            ay2: self.ay2[k],
            pi_axay: self.pi_axay[k],
            c_z: self.c_z[k],
            c_s: self.c_s[k],
        }
    }

    /// Lane `k` at `(lx, ly, lz)` (`lz > 0` assumed by the caller's select): a Fresnel
    /// argument, `|H|²`, `D(h)` and `D(h)·G2`, by the scalar leaves' own formulas
    /// ([`GgxView::reflect`] with `SQUARED = false`, for the dielectric's Fresnel term of
    /// `V·H` and `|H|²`; [`GgxView::reflect_squared`] with `SQUARED = true`, for the
    /// conductor's of `(V·h)²`).
    #[inline(always)]
    pub(in crate::interp) fn reflect_terms<const SQUARED: bool>(
        &self,
        k: usize,
        lx: f32,
        ly: f32,
        lz: f32,
    ) -> (f32, f32, f32, f32) {
        let (vx, vy, vz) = self.v.lane(k);
        let (v, l) = (Vec3::new(vx, vy, vz), Vec3::new(lx, ly, lz));
        if SQUARED {
            self.lane(k).reflect_squared(v, l)
        } else {
            self.lane(k).reflect(v, l)
        }
    }

    /// [`GgxX::reflect_terms`] for every lane, as arrays (Fresnel argument, `|H|²`, `D`,
    /// `D G2`).
    ///
    /// A pass of its own: the kernels' per-lane work is a long chain through square roots
    /// and divisions (here, then again in the Fresnel term), and in one long loop body the
    /// out-of-order core holds only about one vector's chain at a time. Two short loops
    /// let it overlap the chains of every vector of lanes.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    pub(in crate::interp) fn reflect_pass<const SQUARED: bool>(
        &self,
        l: &Vec3x<W>,
        lw: &LaneWeights<W>,
    ) -> [[f32; W]; 4] {
        let mut out = [[0.0f32; W]; 4];
        for k in 0..W {
            let (lx, ly, lz) = lane_l(l, lw, k);
            (out[0][k], out[1][k], out[2][k], out[3][k]) =
                self.reflect_terms::<SQUARED>(k, lx, ly, lz);
        }
        out
    }
}

impl<const W: usize> ConductorX<W> {
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    pub(in crate::interp) fn accumulate<const PDF: bool>(&self, l: &Vec3x<W>, lw: &LaneWeights<W>, acc: &mut Acc<W>) {
        let [vh2, _, d, dg] = self.g.reflect_pass::<true>(l, lw);
        for k in 0..W {
            let lz = lw.sign[k] * l.z[k];
            let (c2, d, dg) = (vh2[k], d[k], dg[k]);
            let fr = [
                fresnel::conductor_c2(c2, self.e2mk2.x[k], self.four_e2k2.x[k]),
                fresnel::conductor_c2(c2, self.e2mk2.y[k], self.four_e2k2.y[k]),
                fresnel::conductor_c2(c2, self.e2mk2.z[k], self.four_e2k2.z[k]),
            ];
            let scale = self.scale_q.scaled(k, dg);
            let f = [0, 1, 2].map(|c| fr[c] * scale[c]);
            add_baked::<W, PDF>(acc, k, lz > 0.0, f, d * self.pdf_c[k]);
        }
    }
}

impl<const W: usize> DielectricX<W> {
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    pub(in crate::interp) fn accumulate<const PDF: bool>(&self, l: &Vec3x<W>, lw: &LaneWeights<W>, acc: &mut Acc<W>) {
        let [m, hh, d, dg] = self.g.reflect_pass::<false>(l, lw);
        for k in 0..W {
            let lz = lw.sign[k] * l.z[k];
            let (d, dg) = (d[k], dg[k]);
            let fr = dielectric_half(m[k], hh[k], self.e2m1[k]);
            let f = self.tint_q.scaled(k, fr * dg);
            add_baked::<W, PDF>(acc, k, lz > 0.0, f, d * self.pdf_c[k]);
        }
    }
}

impl<const W: usize> ConductorX<W> {
    /// Lane `k`'s complex index (per channel).
    #[inline(always)]
    pub(in crate::interp) fn set_ior(&mut self, k: usize, eta: Vec3, kappa: Vec3) {
        let (e2, k2) = (eta * eta, kappa * kappa);
        self.e2mk2.set(k, e2 - k2);
        self.four_e2k2.set(k, 4.0 * e2 * k2);
    }
}

impl<const W: usize> DielectricX<W> {
    /// Lane `k`'s terms besides the GGX view, with the slot's probability `p` and weight `w`
    /// folded in.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(in crate::interp) fn set(
        &mut self,
        k: usize,
        eta: f32,
        g1_v: f32,
        inv_mu: f32,
        tint_r: Vec3,
        p: f32,
        w: Vec3,
    ) {
        self.set_eta(k, eta);
        self.set_view(k, g1_v, inv_mu, tint_r, p, w);
    }

    /// Lane `k`'s index (view-independent for a lobe that is not flipped).
    #[inline(always)]
    pub(in crate::interp) fn set_eta(&mut self, k: usize, eta: f32) {
        self.e2m1[k] = eta * eta - 1.0;
    }

    /// Lane `k`'s view terms with the probability `p` and weight `w` folded in.
    #[inline(always)]
    pub(in crate::interp) fn set_view(&mut self, k: usize, g1_v: f32, inv_mu: f32, tint_r: Vec3, p: f32, w: Vec3) {
        let q = 0.25 * inv_mu;
        self.pdf_c[k] = g1_v * q * p;
        self.tint_q.set(k, tint_r * q * w);
    }
}

impl MicrofacetR {
    /// The lane-parallel prepare's albedo of a rough conductor lobe without compensation at
    /// `W` local views `v`: `E1` times the exact Fresnel's `ratios`, per lane, by the scalar
    /// prepare's own function.
    #[inline(always)]
    pub(in crate::interp) fn albedo_lanes<const W: usize>(
        &self,
        ratios: &RatioGrid,
        v: &Vec3x<W>,
        out: &mut Vec3x<W>,
    ) {
        for k in 0..W {
            out.set(k, self.ratio_albedo(Some(ratios), v.get(k)).min(Vec3::ONE));
        }
    }
}

impl<const W: usize> ConductorX<W> {
    /// The lane-parallel prepare's view terms: lane `k` holds the conductor `lobe` (with
    /// its GGX data `ggx_view`) at view `v[k]`, with the slot's weights and probabilities
    /// `lw` folded in as `Kernel::rebuild` folds them.
    #[inline(always)]
    pub(in crate::interp) fn set_views(
        &mut self,
        lobe: &MicrofacetR,
        ggx_view: &GgxView,
        v: &Vec3x<W>,
        lw: &LaneWeights<W>,
    ) {
        let Fresnel::Conductor { eta, kappa } = lobe.fresnel else {
            return;
        };
        for k in 0..W {
            let vk = v.get(k);
            let t = ViewTerms::from_constants(ggx_view, lobe.masking, vk);
            self.g.set(k, vk, &t.view);
            let inv_4mu = 0.25 / safe_mu(vk.z);
            self.pdf_c[k] = t.g1_v * inv_4mu * lw.p[k];
            self.set_ior(k, eta, kappa);
            self.scale_q.set(k, Vec3::ONE * inv_4mu * lw.w.get(k));
        }
    }
}

impl Dielectric {
    /// The lane-parallel prepare's albedo of a rough dielectric lobe in mode R (no Turquin
    /// factor) at `W` local views `v`: `E_R` at its index `eta` along the curve `e_r` (at
    /// the lanes' coordinates `at`), or, for an anisotropic lobe, whose albedo depends on
    /// the view's azimuth, per lane by the scalar prepare's own function (with its `aniso`
    /// ratios).
    #[allow(clippy::needless_range_loop)] // index loops over lanes vectorise best
    #[inline(always)]
    pub(in crate::interp) fn albedo_lanes_r<const W: usize>(
        &self,
        eta: f32,
        e_r: &MuCurve,
        aniso: Option<&RatioGrid>,
        v: &Vec3x<W>,
        at: &LaneCoords<W>,
        out: &mut Vec3x<W>,
    ) {
        if self.ggx.ax != self.ggx.ay {
            for k in 0..W {
                let [er, ..] = self.aniso_albedos(aniso, v.get(k), eta, [true, false, false]);
                out.set(k, self.tint_r * er);
            }
        } else {
            let e_r = e_r.at_lanes(at);
            for k in 0..W {
                out.set(k, self.tint_r * e_r[k]);
            }
        }
    }
}

impl<const W: usize> DielectricX<W> {
    /// The lane-parallel prepare's view terms of a dielectric in mode R: lane `k` holds
    /// `lobe` (with its GGX data `ggx_view` and index `eta`) at view `v[k]`, with the slot's
    /// weights and probabilities `lw` folded in as `Kernel::rebuild` folds them.
    #[inline(always)]
    pub(in crate::interp) fn set_views_r(
        &mut self,
        lobe: &Dielectric,
        ggx_view: &GgxView,
        eta: f32,
        v: &Vec3x<W>,
        lw: &LaneWeights<W>,
    ) {
        for k in 0..W {
            let vk = v.get(k);
            let t = ViewTerms::from_constants(ggx_view, lobe.masking, vk);
            self.g.set(k, vk, &t.view);
            let inv_mu = 1.0 / safe_mu(vk.z);
            self.set(k, eta, t.g1_v, inv_mu, lobe.tint_r, lw.p[k], lw.w.get(k));
        }
    }
}
