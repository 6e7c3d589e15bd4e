//! Batched structure-of-arrays evaluation (spec closures.md §1.5, §6.1): `W` lanes, each a
//! different (point, V, L), one lobe kind. Every lane runs the same straight-line arithmetic
//! (branches become selects), so the compiler autovectorises the loops.
//!
//! Implemented here: the GGX dielectric reflection lobe (anisotropic, height-correlated,
//! exact Fresnel) — the spec's batched anchor. Results equal the scalar
//! [`super::PreparedLobe::eval`] to relative 1e-5.

use glam::Vec3;
use std::f32::consts::PI;

/// `W` vectors stored as three arrays.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Vec3x<const W: usize> {
    /// x components.
    pub x: [f32; W],
    /// y components.
    pub y: [f32; W],
    /// z components.
    pub z: [f32; W],
}

impl<const W: usize> Vec3x<W> {
    /// All zeros.
    pub fn zero() -> Self {
        Vec3x {
            x: [0.0; W],
            y: [0.0; W],
            z: [0.0; W],
        }
    }

    /// From `W` vectors.
    pub fn from_vecs(v: &[Vec3; W]) -> Self {
        let mut out = Self::zero();
        for (k, v) in v.iter().enumerate() {
            out.set(k, *v);
        }
        out
    }

    /// Lane `k`.
    pub fn get(&self, k: usize) -> Vec3 {
        Vec3::new(self.x[k], self.y[k], self.z[k])
    }

    /// Sets lane `k`.
    pub fn set(&mut self, k: usize, v: Vec3) {
        self.x[k] = v.x;
        self.y[k] = v.y;
        self.z[k] = v.z;
    }
}

/// `W` GGX dielectric reflection lobes (mode R, height-correlated masking, exact Fresnel),
/// parameters per lane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DielectricRBatch<const W: usize> {
    /// Width along the tangent (≥ 1e-3: the batch has no delta path).
    pub ax: [f32; W],
    /// Width along the bitangent.
    pub ay: [f32; W],
    /// Relative index η (interior over exterior, V outside).
    pub eta: [f32; W],
    /// Reflection tint (RGB per lane).
    pub tint: Vec3x<W>,
}

impl<const W: usize> DielectricRBatch<W> {
    /// `f·μ_i` per lane for local views `v` and lights `l` (both unit); lanes with `μ_o ≤ 0`
    /// or `μ_i ≤ 0` give 0.
    #[allow(clippy::needless_range_loop)] // index loops over lanes vectorise best
    pub fn eval(&self, v: &Vec3x<W>, l: &Vec3x<W>) -> Vec3x<W> {
        let mut out = Vec3x::zero();
        let mut scalar = [0.0f32; W];
        for k in 0..W {
            let (ax, ay) = (self.ax[k], self.ay[k]);
            let (vx, vy, vz) = (v.x[k], v.y[k], v.z[k]);
            let (lx, ly, lz) = (l.x[k], l.y[k], l.z[k]);
            let valid = vz > 0.0 && lz > 0.0;
            // Half vector.
            let (hx, hy, hz) = (vx + lx, vy + ly, vz + lz);
            let inv_len = 1.0 / (hx * hx + hy * hy + hz * hz).max(1e-30).sqrt();
            let (hx, hy, hz) = (hx * inv_len, hy * inv_len, hz * inv_len);
            let vh = (vx * hx + vy * hy + vz * hz).max(0.0);
            // D.
            let (tx, ty) = (hx / ax, hy / ay);
            let t = tx * tx + ty * ty + hz * hz;
            let d = 1.0 / (PI * ax * ay * t * t);
            // Height-correlated G2 from the two Λ.
            let lam = |wx: f32, wy: f32, wz: f32| {
                let x = (ax * ax * wx * wx + ay * ay * wy * wy) / (wz * wz).max(1e-14);
                x / (2.0 * (1.0 + (1.0 + x).sqrt()))
            };
            let g = 1.0 / (1.0 + lam(vx, vy, vz) + lam(lx, ly, lz));
            // Exact dielectric Fresnel (no TIR: V is outside, η ≥ 1 expected; guarded).
            let eta = self.eta[k];
            let g2 = (eta * eta + vh * vh - 1.0).max(0.0);
            let gg = g2.sqrt();
            let a = (gg - vh) / (gg + vh).max(1e-30);
            let b = (vh * (gg + vh) - 1.0) / (vh * (gg - vh) + 1.0);
            let f = (0.5 * a * a * (1.0 + b * b)).min(1.0);
            let value = f * d * g * 0.25 / vz.max(1e-7);
            scalar[k] = if valid { value } else { 0.0 };
        }
        for k in 0..W {
            out.x[k] = scalar[k] * self.tint.x[k];
            out.y[k] = scalar[k] * self.tint.y[k];
            out.z[k] = scalar[k] * self.tint.z[k];
        }
        out
    }
}
