//! The structure-of-arrays kernels of the Lambert and Oren–Nayar leaves: their lanes
//! ([`crate::interp::soa`]), the per-lane setters that `Kernel::rebuild` and the lane-parallel
//! prepare share (both fold the slot's weight and probability into the same fields in the
//! same order) and the batched eval.

use super::{
    EON_SIGMA_MIN, OrenNayar, OrenNayarBound, OrenNayarVariant, eon_e_hat, eon_e_hat_fast,
};
use crate::interp::math::Rgb;
use crate::interp::tables::LaneCoords;
use crate::interp::soa::{Acc, LaneWeights, Vec3x, add_baked, flag, lane_l, pick};
use crate::interp::vmath;
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// Oren–Nayar lanes (see [`crate::interp::diffuse::PreparedOrenNayar`]).
#[derive(Debug, Clone, Copy)]
pub(in crate::interp) struct OrenNayarX<const W: usize> {
    pub(in crate::interp) v: Vec3x<W>,
    /// `w ρ/π` (the slot's weight folded in).
    pub(in crate::interp) rho_pi: Vec3x<W>,
    pub(in crate::interp) a: [f32; W],
    pub(in crate::interp) b: [f32; W],
    /// 1 where a negative `s` is kept (FON, EON), else 0.
    pub(in crate::interp) keep_negative_s: [f32; W],
    /// `w ρ_ms` (weighted).
    pub(in crate::interp) ms: Vec3x<W>,
    /// EON's `Ê(μ) = af + c·g(μ)` (exact form): `af`.
    pub(in crate::interp) af: [f32; W],
    /// ... and `c = σ af / π`.
    pub(in crate::interp) c: [f32; W],
    /// The fast polynomial `Ê` (per slot).
    pub(in crate::interp) fast: bool,
    pub(in crate::interp) sigma: [f32; W],
}

#[allow(clippy::needless_range_loop)] // index loops over lanes vectorise best
#[inline(always)]
pub(in crate::interp) fn lambert<const W: usize, const PDF: bool>(
    rho_pi: &Vec3x<W>,
    l: &Vec3x<W>,
    lw: &LaneWeights<W>,
    acc: &mut Acc<W>,
) {
    for k in 0..W {
        let (_, _, lz) = lane_l(l, lw, k);
        // `rho_pi` carries the weight (see `Kernel::rebuild`).
        let f = rho_pi.scaled(k, lz);
        add_baked::<W, PDF>(acc, k, lz > 0.0, f, lw.p[k] * (lz * FRAC_1_PI));
    }
}

impl<const W: usize> OrenNayarX<W> {
    #[inline(always)]
    pub(in crate::interp) fn accumulate<const PDF: bool>(&self, l: &Vec3x<W>, lw: &LaneWeights<W>, acc: &mut Acc<W>) {
        // The `Ê` form is the same for every lane: one loop per form, no branch inside.
        if self.fast {
            self.run::<true, PDF>(l, lw, acc)
        } else {
            self.run::<false, PDF>(l, lw, acc)
        }
    }

    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    pub(in crate::interp) fn run<const FAST: bool, const PDF: bool>(
        &self,
        l: &Vec3x<W>,
        lw: &LaneWeights<W>,
        acc: &mut Acc<W>,
    ) {
        for k in 0..W {
            let (lx, ly, lz) = lane_l(l, lw, k);
            let (vx, vy, vz) = self.v.lane(k);
            let valid = lz > 0.0;
            let s = (vx * lx + vy * ly + vz * lz) - lz * vz;
            let st = pick(s > 0.0, s / lz.max(vz), s * self.keep_negative_s[k]);
            let ss = (self.a[k] + self.b[k] * st).max(0.0) * lz;
            let e_hat = if FAST {
                crate::interp::diffuse::eon_e_hat_fast(lz, self.sigma[k])
            } else {
                self.af[k] + self.c[k] * eon_g(lz)
            };
            let ms = (1.0 - e_hat) * lz;
            let (single, multiple) = (self.rho_pi.scaled(k, ss), self.ms.scaled(k, ms));
            let f = [0, 1, 2].map(|c| single[c] + multiple[c]);
            add_baked::<W, PDF>(acc, k, valid, f, lw.p[k] * (lz * FRAC_1_PI));
        }
    }
}

/// EON's `g(μ)` (see [`crate::interp::diffuse::eon_e_hat`]) with the branch-free `acos`.
#[inline(always)]
pub(in crate::interp) fn eon_g(mu: f32) -> f32 {
    let mu = mu.clamp(0.0, 1.0);
    let s = (1.0 - mu * mu).max(0.0).sqrt();
    let theta = vmath::acos(mu);
    s * (theta - s * mu) + (2.0 / 3.0) * s * (mu * (1.0 + s + s * s) / (1.0 + s) - 1.0)
}

impl<const W: usize> OrenNayarX<W> {
    /// Lane `k` from a prepared lobe, with the slot's weight `w` folded in.
    #[inline(always)]
    pub(in crate::interp) fn set(&mut self, k: usize, p: &crate::interp::diffuse::PreparedOrenNayar, w: Vec3) {
        self.set_consts(k, p);
        self.set_view(k, p, w);
    }

    /// Lane `k`'s view-independent terms.
    #[inline(always)]
    pub(in crate::interp) fn set_consts(&mut self, k: usize, p: &crate::interp::diffuse::PreparedOrenNayar) {
        self.a[k] = p.a;
        self.b[k] = p.b;
        self.keep_negative_s[k] = flag(p.keep_negative_s);
        let af = 1.0 / (1.0 + crate::interp::diffuse::EON_C1 * p.sigma);
        self.af[k] = af;
        self.c[k] = p.sigma * af * FRAC_1_PI;
        self.sigma[k] = p.sigma;
    }

    /// Lane `k`'s view and weighted albedos.
    #[inline(always)]
    pub(in crate::interp) fn set_view(&mut self, k: usize, p: &crate::interp::diffuse::PreparedOrenNayar, w: Vec3) {
        self.v.set(k, p.v);
        self.rho_pi.set(k, p.rho_pi * w);
        self.ms.set(k, p.ms * w);
    }
}

/// The lane-parallel prepare's view terms of a Lambert leaf (and the subsurface proxy):
/// lane `k` holds `ρ/π` with the slot's weight `lw.w[k]` folded in.
#[inline(always)]
pub(in crate::interp) fn lambert_set_views<const W: usize>(
    x: &mut Vec3x<W>,
    rho_pi: Rgb,
    lw: &LaneWeights<W>,
) {
    for k in 0..W {
        x.set(k, rho_pi * lw.w.get(k));
    }
}

impl OrenNayar {
    /// The lane-parallel prepare's albedo `E(μ_o)` of `W` views with cosines `mu` (at their
    /// coordinates `at` along the leaf's curves), as the scalar prepare computes it. The
    /// energy variants also leave `Ê(μ_o)` in `e_hat` for [`OrenNayarX::set_views`].
    #[allow(clippy::needless_range_loop)] // index loops over lanes vectorise best
    #[inline(always)]
    pub(in crate::interp) fn albedo_lanes<const W: usize>(
        &self,
        bound: &OrenNayarBound,
        mu: &[f32; W],
        at: &LaneCoords<W>,
        out: &mut Vec3x<W>,
        e_hat: &mut [f32; W],
    ) {
        let t = &bound.template;
        // Each branch is decided once, outside the loop over lanes, so that the loop has
        // none.
        let mut energy = |e_of: fn(f32, f32) -> f32, out: &mut Vec3x<W>| {
            for k in 0..W {
                let e_o = e_of(mu[k], t.sigma);
                e_hat[k] = e_o;
                out.set(k, self.rho * e_o + bound.rho_ms * (1.0 - e_o));
            }
        };
        match (self.variant, &bound.qon) {
            (OrenNayarVariant::Qualitative, Some(c)) => {
                let c = c.at_lanes(at);
                for k in 0..W {
                    out.set(k, self.rho * c[k]);
                }
            }
            (OrenNayarVariant::Fujii, _) => {
                for k in 0..W {
                    out.set(k, self.rho * eon_e_hat(mu[k], t.sigma));
                }
            }
            (OrenNayarVariant::Energy | OrenNayarVariant::EnergyFast, _)
                if t.sigma >= EON_SIGMA_MIN =>
            {
                if t.fast {
                    energy(eon_e_hat_fast, out);
                } else {
                    energy(eon_e_hat, out);
                }
            }
            // EON below the σ cut-off is Lambert: the template's albedo (QON always has its
            // curve).
            _ => {
                for k in 0..W {
                    out.set(k, t.albedo);
                }
            }
        }
    }
}

impl<const W: usize> OrenNayarX<W> {
    /// The lane-parallel prepare's view terms: lane `k` holds the leaf (`lobe`, `bound`) at
    /// view `v[k]`, with the slot's weight folded in as `Kernel::rebuild` folds it, and
    /// `e_hat` as [`OrenNayar::albedo_lanes`] left it (computing it once saves an `acos` or
    /// an `exp` per lane).
    #[allow(clippy::needless_range_loop)] // index loops over lanes vectorise best
    #[inline(always)]
    pub(in crate::interp) fn set_views(
        &mut self,
        lobe: &OrenNayar,
        bound: &OrenNayarBound,
        v: &Vec3x<W>,
        lw: &LaneWeights<W>,
        e_hat: &[f32; W],
    ) {
        let t = &bound.template;
        self.fast = t.fast;
        let energy = matches!(
            lobe.variant,
            OrenNayarVariant::Energy | OrenNayarVariant::EnergyFast
        ) && t.sigma >= EON_SIGMA_MIN;
        // `ms` is the template's (0) unless EON's multiple scattering is on; then `e_hat`
        // holds `Ê(μ_o)` (the albedo's, by the same form). One loop per case, with no branch
        // inside (it would stop the vectoriser).
        let fill = |with_ms: bool, x: &mut OrenNayarX<W>| {
            for k in 0..W {
                let mut p = *t;
                p.v = v.get(k);
                if with_ms {
                    p.ms = bound.ms_scale * (1.0 - e_hat[k]);
                }
                x.set(k, &p, lw.w.get(k));
            }
        };
        if energy {
            fill(true, self);
        } else {
            fill(false, self);
        }
    }
}
