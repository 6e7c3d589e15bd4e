//! The structure-of-arrays kernels of the Conty–Kulla (MaterialX masking) and LTC sheen leaves: their lanes
//! ([`crate::interp::soa`]), the per-lane setters that `Kernel::rebuild` and the lane-parallel
//! prepare share (both fold the slot's weight and probability into the same fields in the
//! same order), the lane-parallel prepare's per-family steps (albedo and view terms of `W`
//! views from the bound leaf) and the batched eval.

use super::{SheenCKBound, SheenLTC, SheenLTCBound};
use crate::interp::soa::{Acc, LaneWeights, Vec3x, add_valid, lane_l};
use crate::interp::tables::LaneCoords;
use glam::Vec3;
use crate::interp::vmath;
use std::f32::consts::FRAC_1_PI;

/// Sheen CK lanes (see [`crate::interp::sheen::PreparedSheenCK`]).
#[derive(Debug, Clone, Copy)]
pub(in crate::interp) struct SheenCKX<const W: usize> {
    pub(in crate::interp) v: Vec3x<W>,
    pub(in crate::interp) half_inv_r: [f32; W],
    pub(in crate::interp) norm: [f32; W],
}

/// Sheen LTC lanes (see [`crate::interp::sheen::PreparedSheenLTC`]).
#[derive(Debug, Clone, Copy)]
pub(in crate::interp) struct SheenLTCX<const W: usize> {
    pub(in crate::interp) ax_x: Vec3x<W>,
    pub(in crate::interp) ax_y: Vec3x<W>,
    pub(in crate::interp) a: [f32; W],
    pub(in crate::interp) b: [f32; W],
    pub(in crate::interp) e_hat: [f32; W],
}

impl<const W: usize> SheenCKX<W> {
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    pub(in crate::interp) fn accumulate<const PDF: bool>(&self, l: &Vec3x<W>, lw: &LaneWeights<W>, acc: &mut Acc<W>) {
        for k in 0..W {
            let (lx, ly, lz) = lane_l(l, lw, k);
            let (vx, vy, vz) = self.v.lane(k);
            let (hx, hy, hz) = (vx + lx, vy + ly, vz + lz);
            let sin2 = ((hx * hx + hy * hy) / (hx * hx + hy * hy + hz * hz)).min(1.0);
            let d = self.norm[k] * vmath::pow_pos(sin2, self.half_inv_r[k]);
            let (mi, mo) = (lz, vz);
            let f = d * mi / (4.0 * (mi + mo - mi * mo));
            add_valid::<W, PDF>(acc, lw, k, lz > 0.0, [f; 3], 0.5 * FRAC_1_PI);
        }
    }
}

impl<const W: usize> SheenLTCX<W> {
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    pub(in crate::interp) fn accumulate<const PDF: bool>(&self, l: &Vec3x<W>, lw: &LaneWeights<W>, acc: &mut Acc<W>) {
        for k in 0..W {
            let (lx, ly, lz) = lane_l(l, lw, k);
            let wx = lx * self.ax_x.x[k] + ly * self.ax_x.y[k] + lz * self.ax_x.z[k];
            let wy = lx * self.ax_y.x[k] + ly * self.ax_y.y[k] + lz * self.ax_y.z[k];
            let (a, b) = (self.a[k], self.b[k]);
            let (px, py, pz) = (a * wx + b * lz, a * wy, lz);
            let kk = a / (px * px + py * py + pz * pz).max(1e-30);
            let d = lz.max(0.0) * FRAC_1_PI * kk * kk;
            add_valid::<W, PDF>(acc, lw, k, lz > 0.0, [self.e_hat[k] * d; 3], d);
        }
    }
}

impl<const W: usize> SheenLTCX<W> {
    /// Lane `k` from a prepared lobe.
    #[inline(always)]
    pub(in crate::interp) fn set(&mut self, k: usize, p: &crate::interp::sheen::PreparedSheenLTC) {
        self.ax_x.set(k, p.ax_x);
        self.ax_y.set(k, p.ax_y);
        self.a[k] = p.a;
        self.b[k] = p.b;
        self.e_hat[k] = p.e_hat;
    }
}

impl SheenCKBound {
    /// The lane-parallel prepare's albedo `E(μ_o)` of `W` views, at their coordinates `at`
    /// along this leaf's curve, as the scalar prepare computes it.
    #[allow(clippy::needless_range_loop)] // index loops over lanes vectorise best
    #[inline(always)]
    pub(in crate::interp) fn albedo_lanes<const W: usize>(
        &self,
        at: &LaneCoords<W>,
        out: &mut Vec3x<W>,
    ) {
        let e = self.curve.at_lanes(at);
        for k in 0..W {
            out.set(k, Vec3::splat(e[k]));
        }
    }
}

impl SheenLTCBound {
    /// The lane-parallel prepare's albedo `Ê(μ_o)` of `W` views with cosines `mu`, also left
    /// in `e_hat` for [`SheenLTCX::set_views`].
    #[allow(clippy::needless_range_loop)] // index loops over lanes vectorise best
    #[inline(always)]
    pub(in crate::interp) fn albedo_lanes<const W: usize>(
        &self,
        mu: &[f32; W],
        out: &mut Vec3x<W>,
        e_hat: &mut [f32; W],
    ) {
        for k in 0..W {
            e_hat[k] = self.albedo(mu[k].clamp(0.0, 1.0));
            out.set(k, Vec3::splat(e_hat[k]));
        }
    }
}

impl<const W: usize> SheenCKX<W> {
    /// The lane-parallel prepare's view terms: lane `k` holds the leaf `bound` at view
    /// `v[k]` (this family folds no weight into its fields).
    #[allow(clippy::needless_range_loop)] // index loops over lanes vectorise best
    #[inline(always)]
    pub(in crate::interp) fn set_views(&mut self, bound: &SheenCKBound, v: &Vec3x<W>) {
        for k in 0..W {
            self.v.set(k, v.get(k));
            self.half_inv_r[k] = bound.half_inv_r;
            self.norm[k] = bound.norm;
        }
    }
}

impl<const W: usize> SheenLTCX<W> {
    /// The lane-parallel prepare's view terms: lane `k` holds the leaf `bound` at view
    /// `v[k]`, with the albedo `e_hat[k]` [`SheenLTCBound::albedo_lanes`] computed.
    #[allow(clippy::needless_range_loop)] // index loops over lanes vectorise best
    #[inline(always)]
    pub(in crate::interp) fn set_views(
        &mut self,
        bound: &SheenLTCBound,
        v: &Vec3x<W>,
        e_hat: &[f32; W],
    ) {
        let e = *e_hat;
        for k in 0..W {
            self.set(
                k,
                &SheenLTC::prepare_bound_with_albedo(v.get(k), bound, e[k]),
            );
        }
    }
}
