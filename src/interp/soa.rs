//! Batched structure-of-arrays evaluation (spec closures.md §1.5, §6.1): `W` lanes, each a
//! different (point, V, L), one lobe kind. Every lane runs the same straight-line arithmetic
//! (branches become selects), so the compiler autovectorises the loops.
//!
//! Implemented here: the public batched GGX dielectric reflection lobe (the spec's batched
//! anchor), and the kernels the batched material path runs per lobe slot — Lambert,
//! Oren–Nayar/EON, GGX conductor and dielectric reflection, Ward, sheen (CK, LTC); other
//! families fall back to the scalar lobe lane by lane. Results equal the scalar
//! [`super::PreparedLobe::eval`] to relative 1e-5 (`tests/interp_soa_kernels.rs`).

use super::fresnel::Fresnel;
use super::ggx::Masking;
use super::sheen::SheenMasking;
use super::ward::WardVariant;
use glam::Vec3;
use std::f32::consts::{FRAC_1_PI, PI};

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

    /// Lane `k` as a tuple (the kernels' scalar form).
    #[inline(always)]
    fn lane(&self, k: usize) -> (f32, f32, f32) {
        (self.x[k], self.y[k], self.z[k])
    }

    /// Lane `k` scaled by `s`, as the kernels' RGB triple.
    #[inline(always)]
    fn scaled(&self, k: usize, s: f32) -> [f32; 3] {
        [self.x[k] * s, self.y[k] * s, self.z[k] * s]
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
            let valid = (vz > 0.0) & (lz > 0.0);
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
            // Exact dielectric Fresnel (total internal reflection gives 1).
            let f = dielectric1(vh, self.eta[k]);
            let value = f * d * g * 0.25 / vz.max(1e-7);
            scalar[k] = keep(valid, value);
        }
        for k in 0..W {
            out.x[k] = scalar[k] * self.tint.x[k];
            out.y[k] = scalar[k] * self.tint.y[k];
            out.z[k] = scalar[k] * self.tint.z[k];
        }
        out
    }
}

// ---------------------------------------------------------------------------------------
// Per-family kernels of the batched material path (`super::batch`).

/// A leaf family's prepared state over `W` lanes, structure of arrays: what
/// [`super::PreparedBatch::eval`] runs for a slot whose live lanes all hold the same family
/// in a configuration the kernel covers (otherwise the slot is evaluated lane by lane with
/// the scalar leaf). Lanes where the lobe is not live hold a copy of a live lane's
/// parameters (so every lane computes finite values) and weight 0.
///
/// Every kernel computes, per lane, the scalar leaf's formula in the same order with the
/// same guards written as selects; only the transcendentals differ ([`super::vmath`]), so
/// results equal the scalar path to relative 1e-5.
#[derive(Debug, Clone, Copy)]
pub(super) enum Kernel<const W: usize> {
    /// The scalar leaf per lane.
    Scalar,
    /// Lambert (and the subsurface proxy).
    Lambert {
        /// `ρ/π`.
        rho_pi: Vec3x<W>,
    },
    /// Oren–Nayar (QON, FON, EON).
    OrenNayar(OrenNayarX<W>),
    /// GGX reflection with a conductor Fresnel, no Kulla–Conty part.
    Conductor(ConductorX<W>),
    /// GGX dielectric in mode R.
    DielectricR(DielectricX<W>),
    /// Ward (classic and GM).
    Ward(WardX<W>),
    /// Conty–Kulla sheen with the MaterialX masking.
    SheenCK(SheenCKX<W>),
    /// LTC sheen.
    SheenLTC(SheenLTCX<W>),
}

/// Oren–Nayar lanes (see [`super::diffuse::PreparedOrenNayar`]).
#[derive(Debug, Clone, Copy)]
pub(super) struct OrenNayarX<const W: usize> {
    v: Vec3x<W>,
    rho_pi: Vec3x<W>,
    a: [f32; W],
    b: [f32; W],
    /// 1 where a negative `s` is kept (FON, EON), else 0.
    keep_negative_s: [f32; W],
    ms: Vec3x<W>,
    /// EON's `Ê(μ) = af + c·g(μ)` (exact form): `af`.
    af: [f32; W],
    /// ... and `c = σ af / π`.
    c: [f32; W],
    /// The fast polynomial `Ê` (per slot).
    fast: bool,
    sigma: [f32; W],
}

/// Conductor lanes (see [`super::microfacet::PreparedMicrofacetR`]).
#[derive(Debug, Clone, Copy)]
pub(super) struct ConductorX<const W: usize> {
    g: GgxX<W>,
    inv_4mu: [f32; W],
    eta: Vec3x<W>,
    kappa: Vec3x<W>,
    scale: Vec3x<W>,
}

/// Dielectric (mode R) lanes (see [`super::microfacet::PreparedDielectric`]).
#[derive(Debug, Clone, Copy)]
pub(super) struct DielectricX<const W: usize> {
    g: GgxX<W>,
    eta: [f32; W],
    inv_mu: [f32; W],
    tint_r: Vec3x<W>,
}

/// The view-dependent GGX terms shared by the microfacet kernels.
#[derive(Debug, Clone, Copy)]
struct GgxX<const W: usize> {
    v: Vec3x<W>,
    ax: [f32; W],
    ay: [f32; W],
    lambda_v: [f32; W],
    g1_v: [f32; W],
    /// 1 for separable masking, 0 for height-correlated.
    separable: [f32; W],
}

/// Ward lanes (see [`super::ward::PreparedWard`]).
#[derive(Debug, Clone, Copy)]
pub(super) struct WardX<const W: usize> {
    v: Vec3x<W>,
    inv_ax2: [f32; W],
    inv_ay2: [f32; W],
    norm: [f32; W],
    pdf_norm: [f32; W],
    /// 1 for GM, 0 for classic.
    gm: [f32; W],
    rho: Vec3x<W>,
}

/// Sheen CK lanes (see [`super::sheen::PreparedSheenCK`]).
#[derive(Debug, Clone, Copy)]
pub(super) struct SheenCKX<const W: usize> {
    v: Vec3x<W>,
    half_inv_r: [f32; W],
    norm: [f32; W],
}

/// Sheen LTC lanes (see [`super::sheen::PreparedSheenLTC`]).
#[derive(Debug, Clone, Copy)]
pub(super) struct SheenLTCX<const W: usize> {
    ax_x: Vec3x<W>,
    ax_y: Vec3x<W>,
    a: [f32; W],
    b: [f32; W],
    e_hat: [f32; W],
}

/// Accumulators of a batched evaluation: `Σ w f·μ_i` and `Σ p pdf` per lane.
#[derive(Debug, Clone, Copy)]
pub(super) struct Acc<const W: usize> {
    pub(super) f: Vec3x<W>,
    pub(super) pdf: [f32; W],
}

/// One slot's lane weights, probabilities and flip signs, as the kernels read them.
#[derive(Debug, Clone, Copy)]
pub(super) struct LaneWeights<const W: usize> {
    /// Weight `w_k` (0 where the lobe is not live).
    pub(super) w: Vec3x<W>,
    /// Selection probability (0 where not live).
    pub(super) p: [f32; W],
    /// −1 where the lobe's frame is flipped (L becomes `(x, −y, −z)`), else 1.
    pub(super) sign: [f32; W],
}

use super::lobe::{PreparedLobe, State};
use super::vmath;

impl<const W: usize> Kernel<W> {
    /// Makes this the kernel for one slot's lanes (`lobes(k)`: lane `k`'s lobe; `live[k]`:
    /// it is live there), or [`Kernel::Scalar`] when the lanes mix families or
    /// configurations no kernel covers. When the kernel already has the family's variant (a
    /// batch re-prepared for the same material), every lane is overwritten in place: a
    /// kernel is up to ~1 KB, and zeroing a fresh one and copying it into the slot cost more
    /// than filling it.
    pub(super) fn rebuild<'a>(
        &mut self,
        lobes: impl Fn(usize) -> &'a PreparedLobe,
        live: &[bool; W],
    ) {
        let Some(first) = (0..W).find(|&k| live[k]) else {
            *self = Kernel::Scalar;
            return;
        };
        // Dead lanes borrow the first live lane's parameters.
        let lane = |k: usize| if live[k] { lobes(k) } else { lobes(first) };
        let same = |f: &dyn Fn(&State) -> bool| (0..W).all(|k| f(&lane(k).state));
        // Every arm checks with `same` that all lanes hold its family, so filling lane by
        // lane overwrites everything the previous contents held.
        match &lobes(first).state {
            State::Lambert(_) if same(&|s| matches!(s, State::Lambert(_))) => {
                if !matches!(self, Kernel::Lambert { .. }) {
                    *self = Kernel::Lambert {
                        rho_pi: Vec3x::zero(),
                    };
                }
                if let Kernel::Lambert { rho_pi } = self {
                    for k in 0..W {
                        if let State::Lambert(p) = &lane(k).state {
                            rho_pi.set(k, p.rho_pi);
                        }
                    }
                }
            }
            State::OrenNayar(p0)
                if same(&|s| matches!(s, State::OrenNayar(p) if p.fast == p0.fast)) =>
            {
                if !matches!(self, Kernel::OrenNayar(_)) {
                    *self = Kernel::OrenNayar(OrenNayarX {
                        v: Vec3x::zero(),
                        rho_pi: Vec3x::zero(),
                        a: [0.0; W],
                        b: [0.0; W],
                        keep_negative_s: [0.0; W],
                        ms: Vec3x::zero(),
                        af: [0.0; W],
                        c: [0.0; W],
                        fast: false,
                        sigma: [0.0; W],
                    });
                }
                if let Kernel::OrenNayar(x) = self {
                    x.fast = p0.fast;
                    for k in 0..W {
                        if let State::OrenNayar(p) = &lane(k).state {
                            x.v.set(k, p.v);
                            x.rho_pi.set(k, p.rho_pi);
                            x.a[k] = p.a;
                            x.b[k] = p.b;
                            x.keep_negative_s[k] = flag(p.keep_negative_s);
                            x.ms.set(k, p.ms);
                            let af = 1.0 / (1.0 + super::diffuse::EON_C1 * p.sigma);
                            x.af[k] = af;
                            x.c[k] = p.sigma * af * FRAC_1_PI;
                            x.sigma[k] = p.sigma;
                        }
                    }
                }
            }
            State::MicrofacetR(_)
                if same(&|s| matches!(s, State::MicrofacetR(p) if conductor_ok(p))) =>
            {
                if !matches!(self, Kernel::Conductor(_)) {
                    *self = Kernel::Conductor(ConductorX {
                        g: GgxX::zero(),
                        inv_4mu: [0.0; W],
                        eta: Vec3x::zero(),
                        kappa: Vec3x::zero(),
                        scale: Vec3x::zero(),
                    });
                }
                if let Kernel::Conductor(x) = self {
                    for k in 0..W {
                        if let State::MicrofacetR(p) = &lane(k).state {
                            x.g.set(k, p.v, p.ggx.ax, p.ggx.ay, p.lambda_v, p.g1_v, p.masking);
                            x.inv_4mu[k] = p.inv_4mu;
                            if let Fresnel::Conductor { eta, kappa } = p.fresnel {
                                x.eta.set(k, eta);
                                x.kappa.set(k, kappa);
                            }
                            x.scale.set(k, p.scale);
                        }
                    }
                }
            }
            State::Dielectric(_)
                if same(
                    &|s| matches!(s, State::Dielectric(p) if p.refl && !p.trans && !p.delta),
                ) =>
            {
                if !matches!(self, Kernel::DielectricR(_)) {
                    *self = Kernel::DielectricR(DielectricX {
                        g: GgxX::zero(),
                        eta: [0.0; W],
                        inv_mu: [0.0; W],
                        tint_r: Vec3x::zero(),
                    });
                }
                if let Kernel::DielectricR(x) = self {
                    for k in 0..W {
                        if let State::Dielectric(p) = &lane(k).state {
                            x.g.set(k, p.v, p.ggx.ax, p.ggx.ay, p.lambda_v, p.g1_v, p.masking);
                            x.eta[k] = p.eta;
                            x.inv_mu[k] = p.inv_mu;
                            x.tint_r.set(k, p.tint_r);
                        }
                    }
                }
            }
            State::Ward(_) if same(&|s| matches!(s, State::Ward(_))) => {
                if !matches!(self, Kernel::Ward(_)) {
                    *self = Kernel::Ward(WardX {
                        v: Vec3x::zero(),
                        inv_ax2: [0.0; W],
                        inv_ay2: [0.0; W],
                        norm: [0.0; W],
                        pdf_norm: [0.0; W],
                        gm: [0.0; W],
                        rho: Vec3x::zero(),
                    });
                }
                if let Kernel::Ward(x) = self {
                    for k in 0..W {
                        if let State::Ward(p) = &lane(k).state {
                            x.v.set(k, p.v);
                            x.inv_ax2[k] = p.core.inv_ax2;
                            x.inv_ay2[k] = p.core.inv_ay2;
                            x.norm[k] = p.core.norm;
                            x.pdf_norm[k] = p.core.pdf_norm;
                            x.gm[k] = flag(p.variant == WardVariant::Gm);
                            x.rho.set(k, p.rho);
                        }
                    }
                }
            }
            State::SheenCK(_)
                if same(
                    &|s| matches!(s, State::SheenCK(p) if p.masking == SheenMasking::MaterialX),
                ) =>
            {
                if !matches!(self, Kernel::SheenCK(_)) {
                    *self = Kernel::SheenCK(SheenCKX {
                        v: Vec3x::zero(),
                        half_inv_r: [0.0; W],
                        norm: [0.0; W],
                    });
                }
                if let Kernel::SheenCK(x) = self {
                    for k in 0..W {
                        if let State::SheenCK(p) = &lane(k).state {
                            x.v.set(k, p.v);
                            x.half_inv_r[k] = p.half_inv_r;
                            x.norm[k] = p.norm;
                        }
                    }
                }
            }
            State::SheenLTC(_) if same(&|s| matches!(s, State::SheenLTC(_))) => {
                if !matches!(self, Kernel::SheenLTC(_)) {
                    *self = Kernel::SheenLTC(SheenLTCX {
                        ax_x: Vec3x::zero(),
                        ax_y: Vec3x::zero(),
                        a: [0.0; W],
                        b: [0.0; W],
                        e_hat: [0.0; W],
                    });
                }
                if let Kernel::SheenLTC(x) = self {
                    for k in 0..W {
                        if let State::SheenLTC(p) = &lane(k).state {
                            x.ax_x.set(k, p.ax_x);
                            x.ax_y.set(k, p.ax_y);
                            x.a[k] = p.a;
                            x.b[k] = p.b;
                            x.e_hat[k] = p.e_hat;
                        }
                    }
                }
            }
            _ => *self = Kernel::Scalar,
        }
    }

    /// Adds the slot's weighted response at local directions `l` (before the per-lane flip)
    /// to `acc`. Returns false for [`Kernel::Scalar`] (the caller evaluates lane by lane).
    #[inline]
    pub(super) fn accumulate(&self, l: &Vec3x<W>, lw: &LaneWeights<W>, acc: &mut Acc<W>) -> bool {
        match self {
            Kernel::Scalar => return false,
            Kernel::Lambert { rho_pi } => lambert(rho_pi, l, lw, acc),
            Kernel::OrenNayar(x) => x.accumulate(l, lw, acc),
            Kernel::Conductor(x) => x.accumulate(l, lw, acc),
            Kernel::DielectricR(x) => x.accumulate(l, lw, acc),
            Kernel::Ward(x) => x.accumulate(l, lw, acc),
            Kernel::SheenCK(x) => x.accumulate(l, lw, acc),
            Kernel::SheenLTC(x) => x.accumulate(l, lw, acc),
        }
        true
    }
}

/// A conductor lobe the kernel covers: conductor Fresnel, not a delta, no Kulla–Conty part.
fn conductor_ok(p: &super::microfacet::PreparedMicrofacetR) -> bool {
    p.fresnel.is_conductor() && !p.delta && p.e_row.is_none()
}

/// `x` where `c` holds, else +0, as a bit mask: a plain `if` lets LLVM turn the select
/// back into a branch around the computation of `x`, which stops the loop vectoriser on
/// baseline x86-64 (SSE2); the mask keeps every lane's arithmetic unconditional.
#[inline(always)]
fn keep(c: bool, x: f32) -> f32 {
    f32::from_bits(x.to_bits() & u32::from(c).wrapping_neg())
}

/// `a` where `c` holds, else `b` (bit-mask blend; see [`keep`]).
#[inline(always)]
fn pick(c: bool, a: f32, b: f32) -> f32 {
    vmath::select(c, a, b)
}

/// `acc += w ⊙ f_rgb`, `pdf += p·pdf` for lane `k`.
#[inline(always)]
fn add_rgb<const W: usize>(acc: &mut Acc<W>, lw: &LaneWeights<W>, k: usize, f: [f32; 3], pdf: f32) {
    acc.f.x[k] += lw.w.x[k] * f[0];
    acc.f.y[k] += lw.w.y[k] * f[1];
    acc.f.z[k] += lw.w.z[k] * f[2];
    acc.pdf[k] += lw.p[k] * pdf;
}

/// [`add_rgb`] of `f` and `pdf` where `valid` holds, nothing elsewhere (bit masks, no branch).
#[inline(always)]
fn add_valid<const W: usize>(
    acc: &mut Acc<W>,
    lw: &LaneWeights<W>,
    k: usize,
    valid: bool,
    f: [f32; 3],
    pdf: f32,
) {
    add_rgb(acc, lw, k, f.map(|c| keep(valid, c)), keep(valid, pdf));
}

/// 1 where `c` holds, else 0 (per-lane flags the kernels blend with).
fn flag(c: bool) -> f32 {
    f32::from(u8::from(c))
}

/// Lane `k` of `l` with the lane's flip applied.
#[inline(always)]
fn lane_l<const W: usize>(l: &Vec3x<W>, lw: &LaneWeights<W>, k: usize) -> (f32, f32, f32) {
    (l.x[k], lw.sign[k] * l.y[k], lw.sign[k] * l.z[k])
}

#[allow(clippy::needless_range_loop)] // index loops over lanes vectorise best
#[inline]
fn lambert<const W: usize>(rho_pi: &Vec3x<W>, l: &Vec3x<W>, lw: &LaneWeights<W>, acc: &mut Acc<W>) {
    for k in 0..W {
        let (_, _, lz) = lane_l(l, lw, k);
        let c = keep(lz > 0.0, lz);
        add_rgb(acc, lw, k, rho_pi.scaled(k, c), c * FRAC_1_PI);
    }
}

impl<const W: usize> OrenNayarX<W> {
    #[inline]
    fn accumulate(&self, l: &Vec3x<W>, lw: &LaneWeights<W>, acc: &mut Acc<W>) {
        // The `Ê` form is the same for every lane: one loop per form, no branch inside.
        if self.fast {
            self.run::<true>(l, lw, acc)
        } else {
            self.run::<false>(l, lw, acc)
        }
    }

    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn run<const FAST: bool>(&self, l: &Vec3x<W>, lw: &LaneWeights<W>, acc: &mut Acc<W>) {
        for k in 0..W {
            let (lx, ly, lz) = lane_l(l, lw, k);
            let (vx, vy, vz) = self.v.lane(k);
            let valid = lz > 0.0;
            let s = (vx * lx + vy * ly + vz * lz) - lz * vz;
            let st = pick(s > 0.0, s / lz.max(vz), s * self.keep_negative_s[k]);
            let ss = (self.a[k] + self.b[k] * st).max(0.0) * lz;
            let e_hat = if FAST {
                super::diffuse::eon_e_hat_fast(lz, self.sigma[k])
            } else {
                self.af[k] + self.c[k] * eon_g(lz)
            };
            let ms = (1.0 - e_hat) * lz;
            let (single, multiple) = (self.rho_pi.scaled(k, ss), self.ms.scaled(k, ms));
            let f = [0, 1, 2].map(|c| single[c] + multiple[c]);
            add_valid(acc, lw, k, valid, f, lz * FRAC_1_PI);
        }
    }
}

/// EON's `g(μ)` (see [`super::diffuse::eon_e_hat`]) with the branch-free `acos`.
#[inline(always)]
fn eon_g(mu: f32) -> f32 {
    let mu = mu.clamp(0.0, 1.0);
    let s = (1.0 - mu * mu).max(0.0).sqrt();
    let theta = vmath::acos(mu);
    s * (theta - s * mu) + (2.0 / 3.0) * s * (mu * (1.0 + s + s * s) / (1.0 + s) - 1.0)
}

impl<const W: usize> GgxX<W> {
    fn zero() -> Self {
        GgxX {
            v: Vec3x::zero(),
            ax: [0.0; W],
            ay: [0.0; W],
            lambda_v: [0.0; W],
            g1_v: [0.0; W],
            separable: [0.0; W],
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn set(&mut self, k: usize, v: Vec3, ax: f32, ay: f32, lambda_v: f32, g1_v: f32, m: Masking) {
        self.v.set(k, v);
        self.ax[k] = ax;
        self.ay[k] = ay;
        self.lambda_v[k] = lambda_v;
        self.g1_v[k] = g1_v;
        self.separable[k] = flag(m == Masking::Separable);
    }

    /// Lane `k` at `(lx, ly, lz)` (`lz > 0` assumed by the caller's select): the unit half
    /// vector's `V·h` (≥ 0), `D(h)` and `G2`.
    #[inline(always)]
    fn reflect_terms(&self, k: usize, lx: f32, ly: f32, lz: f32) -> (f32, f32, f32) {
        let (ax, ay) = (self.ax[k], self.ay[k]);
        let (vx, vy, vz) = self.v.lane(k);
        let (hx, hy, hz) = (vx + lx, vy + ly, vz + lz);
        let inv_len = 1.0 / (hx * hx + hy * hy + hz * hz).sqrt();
        let (hx, hy, hz) = (hx * inv_len, hy * inv_len, hz * inv_len);
        let vh = (vx * hx + vy * hy + vz * hz).max(0.0);
        let (tx, ty) = (hx / ax, hy / ay);
        let t = tx * tx + ty * ty + hz * hz;
        let d = 1.0 / (PI * ax * ay * t * t);
        let z2 = (lz * lz).max(1e-14);
        let x = (ax * ax * lx * lx + ay * ay * ly * ly) / z2;
        let lambda_l = x / (2.0 * (1.0 + (1.0 + x).sqrt()));
        let lv = self.lambda_v[k];
        let g_hc = 1.0 / (1.0 + lv + lambda_l);
        let g_sep = 1.0 / ((1.0 + lv) * (1.0 + lambda_l));
        let g = pick(self.separable[k] > 0.0, g_sep, g_hc);
        (vh, d, g)
    }
}

/// One channel of [`super::fresnel::conductor`].
#[inline(always)]
fn conductor1(c: f32, eta: f32, kappa: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let e2 = eta * eta;
    let k2 = kappa * kappa;
    let t0 = e2 - k2 - s2;
    let ab2 = (t0 * t0 + 4.0 * e2 * k2).sqrt();
    let a = (0.5 * (ab2 + t0)).max(0.0).sqrt();
    let two_ac = 2.0 * c * a;
    let rs = (ab2 - two_ac + c2) / (ab2 + two_ac + c2).max(1e-30);
    let num = c2 * ab2 - two_ac * s2 + s2 * s2;
    let den = (c2 * ab2 + two_ac * s2 + s2 * s2).max(1e-30);
    (0.5 * (rs + rs * num / den)).clamp(0.0, 1.0)
}

/// [`super::fresnel::dielectric`] without branches.
#[inline(always)]
fn dielectric1(mu: f32, eta: f32) -> f32 {
    let mu = mu.clamp(0.0, 1.0);
    let g2 = eta * eta + mu * mu - 1.0;
    let g = g2.max(0.0).sqrt();
    let a = (g - mu) / (g + mu).max(1e-30);
    let b = (mu * (g + mu) - 1.0) / (mu * (g - mu) + 1.0);
    let f = (0.5 * a * a * (1.0 + b * b)).min(1.0);
    pick(g2 < 0.0, 1.0, f)
}

impl<const W: usize> ConductorX<W> {
    #[allow(clippy::needless_range_loop)]
    #[inline]
    fn accumulate(&self, l: &Vec3x<W>, lw: &LaneWeights<W>, acc: &mut Acc<W>) {
        for k in 0..W {
            let (lx, ly, lz) = lane_l(l, lw, k);
            let (vh, d, g) = self.g.reflect_terms(k, lx, ly, lz);
            let q = d * g * self.inv_4mu[k];
            let fr = [
                conductor1(vh, self.eta.x[k], self.kappa.x[k]),
                conductor1(vh, self.eta.y[k], self.kappa.y[k]),
                conductor1(vh, self.eta.z[k], self.kappa.z[k]),
            ];
            let scale = self.scale.scaled(k, q);
            let f = [0, 1, 2].map(|c| fr[c] * scale[c]);
            let pdf = d * self.g.g1_v[k] * self.inv_4mu[k];
            add_valid(acc, lw, k, lz > 0.0, f, pdf);
        }
    }
}

impl<const W: usize> DielectricX<W> {
    #[allow(clippy::needless_range_loop)]
    #[inline]
    fn accumulate(&self, l: &Vec3x<W>, lw: &LaneWeights<W>, acc: &mut Acc<W>) {
        for k in 0..W {
            let (lx, ly, lz) = lane_l(l, lw, k);
            let (vh, d, g) = self.g.reflect_terms(k, lx, ly, lz);
            let fr = dielectric1(vh, self.eta[k]);
            let q = 0.25 * d * self.inv_mu[k];
            let f = self.tint_r.scaled(k, fr * g * q);
            add_valid(acc, lw, k, lz > 0.0, f, self.g.g1_v[k] * q);
        }
    }
}

impl<const W: usize> WardX<W> {
    #[allow(clippy::needless_range_loop)]
    #[inline]
    fn accumulate(&self, l: &Vec3x<W>, lw: &LaneWeights<W>, acc: &mut Acc<W>) {
        for k in 0..W {
            let (lx, ly, lz) = lane_l(l, lw, k);
            let (vx, vy, vz) = self.v.lane(k);
            let (hx, hy, hz) = (vx + lx, vy + ly, vz + lz);
            let hh2 = hx * hx + hy * hy + hz * hz;
            let vhh = vx * hx + vy * hy + vz * hz;
            let hz2 = hz * hz;
            let e = (hx * hx * self.inv_ax2[k] + hy * hy * self.inv_ay2[k]) / hz2;
            let ex = vmath::exp(-e);
            let f_classic = self.norm[k] * ex * lz.max(0.0).sqrt();
            let f_gm = self.norm[k] * hh2 / (hz2 * hz2) * ex * lz;
            let f = pick(self.gm[k] > 0.0, f_gm, f_classic);
            let pdf = self.pdf_norm[k] * ex * hh2 * hh2 / (hz2 * hz * vhh);
            let valid = (lz > 0.0) & (ex > 0.0);
            add_valid(acc, lw, k, valid, self.rho.scaled(k, f), pdf);
        }
    }
}

impl<const W: usize> SheenCKX<W> {
    #[allow(clippy::needless_range_loop)]
    #[inline]
    fn accumulate(&self, l: &Vec3x<W>, lw: &LaneWeights<W>, acc: &mut Acc<W>) {
        for k in 0..W {
            let (lx, ly, lz) = lane_l(l, lw, k);
            let (vx, vy, vz) = self.v.lane(k);
            let (hx, hy, hz) = (vx + lx, vy + ly, vz + lz);
            let sin2 = ((hx * hx + hy * hy) / (hx * hx + hy * hy + hz * hz)).min(1.0);
            let d = self.norm[k] * vmath::pow_pos(sin2, self.half_inv_r[k]);
            let (mi, mo) = (lz, vz);
            let f = d * mi / (4.0 * (mi + mo - mi * mo));
            add_valid(acc, lw, k, lz > 0.0, [f; 3], 0.5 * FRAC_1_PI);
        }
    }
}

impl<const W: usize> SheenLTCX<W> {
    #[allow(clippy::needless_range_loop)]
    #[inline]
    fn accumulate(&self, l: &Vec3x<W>, lw: &LaneWeights<W>, acc: &mut Acc<W>) {
        for k in 0..W {
            let (lx, ly, lz) = lane_l(l, lw, k);
            let wx = lx * self.ax_x.x[k] + ly * self.ax_x.y[k] + lz * self.ax_x.z[k];
            let wy = lx * self.ax_y.x[k] + ly * self.ax_y.y[k] + lz * self.ax_y.z[k];
            let (a, b) = (self.a[k], self.b[k]);
            let (px, py, pz) = (a * wx + b * lz, a * wy, lz);
            let kk = a / (px * px + py * py + pz * pz).max(1e-30);
            let d = lz.max(0.0) * FRAC_1_PI * kk * kk;
            add_valid(acc, lw, k, lz > 0.0, [self.e_hat[k] * d; 3], d);
        }
    }
}
