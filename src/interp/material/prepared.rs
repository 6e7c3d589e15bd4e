//! A material prepared for one point and view ([`Prepared`]): eval, sample, albedo,
//! emission and transparency.

use super::packs;
use super::record::{ActiveLobe, Albedo, Eval, Sample};
use crate::interp::diffuse::Lambert;
use crate::interp::frame::Frame;
use crate::interp::lobe::{Lobe, Sides};
use crate::interp::math::{Rgb, lum};
use crate::interp::simd::{Level, SCALAR_LEVEL, call_widest, widest_versions};
use crate::ir::MAX_LOBES;
use glam::Vec3;

/// A material prepared for one point and view: at most `MAX_LOBES` weighted lobes,
/// their frames, emission and transparency. Plain data; `eval` and `sample` do not allocate.
#[derive(Debug, Clone, Copy)]
pub struct Prepared {
    pub(in crate::interp) lobes: [ActiveLobe; MAX_LOBES],
    pub(in crate::interp) count: usize,
    pub(in crate::interp) frames: [Frame; MAX_LOBES],
    pub(in crate::interp) frame_count: usize,
    /// Some lobe is flipped (seen from below): `eval` then flips per lobe.
    pub(super) flipped_any: bool,
    pub(super) v: Vec3,
    pub(super) emission: Rgb,
    pub(super) transparency: Rgb,
    /// Probability of choosing straight transmission in `sample`.
    pub(super) p_transparency: f32,
    /// Which lobes `eval` runs alone and which in packs.
    pub(super) plan: packs::EvalPlan,
    /// The [`UniformPlan::stamp`](super::form::UniformPlan::stamp) of the material whose fused
    /// prepare wrote `lobes` last with every leaf surviving (lobe `k` is leaf `k`, none
    /// flipped); 0 when the records may hold anything else. The next fused prepare of that
    /// material then writes only the records' view-dependent fields.
    pub(super) stamp: u64,
}

impl Default for Prepared {
    fn default() -> Self {
        Prepared::new()
    }
}

impl Prepared {
    pub(in crate::interp) fn empty(v: Vec3) -> Prepared {
        let placeholder = ActiveLobe {
            lobe: Lobe::Lambert(Lambert { rho: Vec3::ZERO }).prepare(Vec3::Z, Sides::Front),
            weight: Vec3::ZERO,
            albedo: Albedo::default(),
            prob: 0.0,
            frame: 0,
            leaf: 0,
        };
        Prepared {
            lobes: [placeholder; MAX_LOBES],
            count: 0,
            frames: [Frame::default(); MAX_LOBES],
            frame_count: 0,
            flipped_any: false,
            v,
            emission: Vec3::ZERO,
            transparency: Vec3::ZERO,
            p_transparency: 0.0,
            plan: packs::EvalPlan::empty(),
            stamp: 0,
        }
    }

    /// Forget everything but the storage: no lobes, no frames, no emission.
    pub(in crate::interp) fn reset(&mut self, v: Vec3) {
        self.count = 0;
        self.frame_count = 0;
        self.flipped_any = false;
        self.v = v;
        self.emission = Vec3::ZERO;
        self.transparency = Vec3::ZERO;
        self.p_transparency = 0.0;
        self.plan.clear();
    }

    /// An empty preparation (no lobes), e.g. as the target of
    /// [`Material::prepare_into`](super::Material::prepare_into).
    pub fn new() -> Prepared {
        Prepared::empty(Vec3::Z)
    }

    /// Step 6's survivor: leaf `k`'s record (prepared at index `k`) becomes lobe `at ≤ k`
    /// with its weight, albedo and frame. Returns step 7's share, `max(lum(A_k), 0)` with
    /// transmission in the radiance convention.
    #[inline(always)]
    pub(super) fn keep(
        &mut self,
        at: usize,
        k: usize,
        weight: Rgb,
        albedo: Albedo,
        frame: u8,
    ) -> f32 {
        if at != k {
            self.lobes[at].lobe = self.lobes[k].lobe;
        }
        let a = &mut self.lobes[at];
        a.weight = weight;
        a.albedo = albedo;
        a.frame = frame;
        a.leaf = k as u8;
        lum(albedo.reflect + albedo.transmit_radiance).max(0.0)
    }

    /// Step 7: `p_k = lum(A_k)/Σ lum(A_j)` (straight transmission takes part with
    /// `lum(τ)`); else proportional to `lum(w_k)`; else absorbing (all 0).
    /// `lums[k]` is `max(lum(A_k), 0)` with transmission in the radiance convention.
    #[inline(always)]
    pub(super) fn select(&mut self, lums: &[f32; MAX_LOBES]) {
        let n = self.count;
        // `lums` is read in place, never copied whole: its entries were just stored one by
        // one, and a wider load of them waits for every store to reach the cache (no store
        // forwarding).
        let mut sum = 0.0f32;
        for x in &lums[..n] {
            sum += *x;
        }
        let tau = lum(self.transparency).max(0.0);
        sum += tau;
        if sum.is_nan() || sum <= 0.0 {
            self.select_by_weight();
            return;
        }
        if sum == f32::INFINITY {
            self.absorb();
            return;
        }
        // One division: the probabilities are the shares times its reciprocal.
        let inv = 1.0 / sum;
        for (l, x) in self.lobes[..n].iter_mut().zip(lums) {
            l.prob = x * inv;
        }
        self.p_transparency = tau * inv;
    }

    /// [`Prepared::select`] when no lobe reflects: proportional to `lum(w_k)`, or absorbing.
    #[cold]
    pub(super) fn select_by_weight(&mut self) {
        let mut sum = 0.0f32;
        for l in &mut self.lobes[..self.count] {
            l.prob = lum(l.weight).max(0.0);
            sum += l.prob;
        }
        if !(sum > 0.0 && sum.is_finite()) {
            self.absorb();
            return;
        }
        let inv = 1.0 / sum;
        for l in &mut self.lobes[..self.count] {
            l.prob *= inv;
        }
        self.p_transparency = 0.0;
    }

    /// Absorbing: every probability 0 (the records may hold an earlier prepare's).
    pub(super) fn absorb(&mut self) {
        for l in &mut self.lobes[..self.count] {
            l.prob = 0.0;
        }
    }

    /// The lobes that survived step 6, with weights, albedos and probabilities.
    pub fn lobes(&self) -> &[ActiveLobe] {
        &self.lobes[..self.count]
    }

    /// The frame of lobe `k` (see [`ActiveLobe::frame`]).
    pub fn frame(&self, k: usize) -> Frame {
        self.frames[self.lobes[k].frame as usize]
    }

    /// The (normalised) view direction.
    pub fn view(&self) -> Vec3 {
        self.v
    }

    /// How many of [`Prepared::lobes`] [`Prepared::eval`] runs in lobe packs (several
    /// lobes of one family side by side, see
    /// [`PrepareOptions::pack_lobes`](super::PrepareOptions::pack_lobes)); the others are
    /// evaluated one by one. For inspection and tests.
    #[cfg(feature = "testkit")]
    pub fn packed_lobe_count(&self) -> usize {
        self.count - self.plan.solo(self.count).len()
    }

    /// `Σ_k w_k ⊙ f_k(V, L)·|μ_i|` and the mixture pdf at world direction `l`. Delta lobes
    /// contribute nothing.
    ///
    /// Runs the version compiled for `SCALAR_LEVEL` when the CPU has it (see
    /// module `simd`); every version computes the same bits.
    #[inline]
    pub fn eval(&self, l: Vec3) -> Eval {
        self.eval_at(SCALAR_LEVEL, l)
    }

    testkit_pub! {
        /// [`Prepared::eval`] compiled for at most `level` (every level gives the same bits).
        #[inline]
        fn eval_at(&self, level: Level, l: Vec3) -> Eval {
            call_widest!(level, self.eval_body(l), eval_avx512, eval_avx2)
        }
    }

    widest_versions!(eval_body(l: Vec3) -> Eval, eval_avx512, eval_avx2);

    #[inline(always)]
    pub(super) fn eval_body(&self, l: Vec3) -> Eval {
        self.eval_with::<true>(l)
    }

    testkit_pub! {
        /// [`Prepared::eval`]'s `f_cos` alone, for callers that need no density (the material
        /// preview): the lobes' pdf arithmetic is left out. Runs at `SCALAR_LEVEL` as `eval`
        /// does.
        #[inline]
        fn eval_f_cos(&self, l: Vec3) -> Rgb {
            self.eval_f_cos_at(SCALAR_LEVEL, l)
        }
    }

    testkit_pub! {
        /// [`Prepared::eval_f_cos`] compiled for at most `level` (every level gives the same
        /// bits).
        #[inline]
        fn eval_f_cos_at(&self, level: Level, l: Vec3) -> Rgb {
            call_widest!(
                level,
                self.f_cos_body(l),
                eval_f_cos_avx512,
                eval_f_cos_avx2
            )
        }
    }

    widest_versions!(f_cos_body(l: Vec3) -> Rgb, eval_f_cos_avx512, eval_f_cos_avx2);

    #[inline(always)]
    pub(super) fn f_cos_body(&self, l: Vec3) -> Rgb {
        self.eval_with::<false>(l).f_cos
    }

    /// [`Prepared::eval`], with the mixture pdf only when `PDF` (else 0): every leaf eval is
    /// inlined here, so the compiler drops what is not summed.
    #[inline(always)]
    pub(super) fn eval_with<const PDF: bool>(&self, l: Vec3) -> Eval {
        if self.frame_count == 1 && !self.flipped_any {
            // One frame, no lobe flipped (the common case): one transform, no frame table,
            // no per-lobe flip.
            let l = self.frames[0].to_local(l);
            let (mut f_cos, mut pdf) = self.plan.eval_one_frame::<PDF>(l);
            for &k in self.plan.solo(self.count) {
                let lobe = &self.lobes[k as usize];
                let e = lobe.lobe.eval_unflipped(l);
                f_cos += lobe.weight * e.f_cos;
                if PDF {
                    pdf += lobe.prob * e.pdf;
                }
            }
            return Eval { f_cos, pdf };
        }
        let mut local = [Vec3::ZERO; MAX_LOBES];
        for (loc, f) in local.iter_mut().zip(&self.frames[..self.frame_count]) {
            *loc = f.to_local(l);
        }
        let (mut f_cos, mut pdf) = self.plan.eval_frames::<PDF>(&local);
        for &k in self.plan.solo(self.count) {
            let lobe = &self.lobes[k as usize];
            let e = lobe.lobe.eval(local[lobe.frame as usize]);
            f_cos += lobe.weight * e.f_cos;
            if PDF {
                pdf += lobe.prob * e.pdf;
            }
        }
        Eval { f_cos, pdf }
    }

    /// The response of lobe `k` alone (weighted) at world direction `l`.
    pub fn eval_lobe(&self, k: usize, l: Vec3) -> Eval {
        let lobe = &self.lobes[k];
        let e = lobe.lobe.eval(self.frames[lobe.frame as usize].to_local(l));
        Eval {
            f_cos: lobe.weight * e.f_cos,
            pdf: e.pdf,
        }
    }

    /// One-sample MIS over the lobes: `u[0]` chooses a lobe and is rescaled to drive
    /// the lobe's own sampling with `u[1]`, `u[2]`. `None` when the material is absorbing or
    /// the sample carries no energy.
    pub fn sample(&self, u: [f32; 3]) -> Option<Sample> {
        let mut lo = 0.0;
        let mut chosen = None;
        for (k, lobe) in self.lobes[..self.count].iter().enumerate() {
            let hi = lo + lobe.prob;
            if u[0] < hi && lobe.prob > 0.0 {
                chosen = Some(k);
                break;
            }
            lo = hi;
        }
        if chosen.is_none() {
            if self.p_transparency > 0.0 {
                return self.sample_transparency();
            }
            // Rounding left u[0] past the last interval: take the last lobe that can be
            // chosen.
            chosen = self.lobes[..self.count].iter().rposition(|l| l.prob > 0.0);
            lo = self.lobes[..chosen?].iter().map(|l| l.prob).sum();
        }
        let k = chosen?;
        let lobe = &self.lobes[k];
        let u0 = ((u[0] - lo) / lobe.prob).clamp(0.0, ONE_MINUS_EPS);
        let frame = &self.frames[lobe.frame as usize];
        let s = lobe.lobe.sample([u0, u[1], u[2]])?;
        let l = frame.to_world(s.l);
        if s.delta {
            let pdf = lobe.prob * s.pdf;
            return (pdf > 0.0).then(|| Sample {
                l,
                weight: lobe.weight * s.weight / lobe.prob,
                pdf,
                delta: true,
                lobe: k as u8,
            });
        }
        let e = self.eval(l);
        if e.pdf.is_nan() || e.pdf <= 0.0 || e.pdf.is_infinite() {
            return None;
        }
        Some(Sample {
            l,
            weight: e.f_cos / e.pdf,
            pdf: e.pdf,
            delta: false,
            lobe: k as u8,
        })
    }

    pub(super) fn sample_transparency(&self) -> Option<Sample> {
        let p = self.p_transparency;
        Some(Sample {
            l: -self.v,
            weight: self.transparency / p,
            pdf: p,
            delta: true,
            lobe: Sample::TRANSPARENCY_LOBE,
        })
    }

    /// `Σ_k A_k`, split by hemisphere (transmission as energy and in the radiance
    /// convention).
    pub fn albedo(&self) -> Albedo {
        let mut a = Albedo::default();
        for l in &self.lobes[..self.count] {
            a.add(&l.albedo);
        }
        a
    }

    /// Accumulated emission.
    pub fn emission(&self) -> Rgb {
        self.emission
    }

    /// Accumulated straight-through transmittance (weight of `Transparent` leaves).
    pub fn transparency(&self) -> Rgb {
        self.transparency
    }

    /// True when `sample` can never return a direction.
    pub fn is_absorbing(&self) -> bool {
        self.p_transparency <= 0.0 && self.lobes().iter().all(|l| l.prob <= 0.0)
    }
}

/// The largest f32 below 1.
pub(super) const ONE_MINUS_EPS: f32 = 1.0 - f32::EPSILON / 2.0;
