//! The batched prepares of [`Material`] over `W` points: the prepare of each lane by the
//! scalar steps, and the lane-parallel prepare of a uniform material (structure-of-arrays
//! batching for previews).
//!
//! [`Material::prepare_batch_into`] runs the scalar prepare once per lane and then
//! transposes the per-lane records into the batch's kernels. Most of that work is the
//! general algorithm's bookkeeping, repeated per lane. For a material whose registers are all
//! constants (no inputs, textures or globals), whose leaves all use the point's own frame
//! and all have a batched kernel, [`Material::prepare_lanes`] instead runs the prepare steps
//! once for all lanes, each step a loop over lanes the compiler vectorises:
//!
//! 1. frames and V in the frame, per lane (the batch falls back to the scalar path when
//!    some lane's view is at or below the horizon: those lobes are inactive or flipped);
//! 2. each leaf's albedo `E(μ_o)` (its baked curve, or its closed form);
//! 3. the throughput pass and the compiled weight plan on lane arrays;
//! 4. drop and selection per lane;
//! 5. each surviving leaf's view terms, written straight into its kernel with the lane
//!    weights folded in as [`super::super::soa::Kernel::rebuild`] folds them.
//!
//! Every formula is the scalar leaf's, in the same order, so each lane agrees with
//! [`Material::prepare`] to rounding (`tests/interp/batch_lanes.rs`).

use super::batch::{PreparedBatch, ShadingBatch};
use super::form::{LanePlan, LeafLanes, Material, Target, ThrOp, clean, sat};
use super::prepare::Scratch;
use super::prepared::Prepared;
use crate::interp::diffuse::soa::lambert_set_views;
use crate::interp::frame::Frame;
use crate::interp::leaves::Leaf;
use crate::interp::lobe::{Aux, Lobe};
use crate::interp::math::lum;
use crate::interp::microfacet::{Compensation, DielectricMode};
use crate::interp::sheen::SheenMasking;
use crate::interp::simd::{Level, call_widest, widest_versions};
use crate::interp::soa::{Kernel, LaneWeights, Vec3x};
use crate::interp::tables::LaneCoords;
use crate::interp::vmath::{select, select3};
use crate::ir::algebra::{add_throughput, leaf_throughput, mix_throughput, mul_throughput};
use crate::ir::{MAX_LOBES, TintMode};
use glam::Vec3;

impl Material {
    /// Prepare `W` points at once.
    pub fn prepare_batch<const W: usize>(&self, p: &ShadingBatch<W>) -> PreparedBatch<W> {
        let mut s = Scratch::default();
        let lanes: [Prepared; W] = std::array::from_fn(|k| self.prepare_with(&p.lane(k), &mut s));
        PreparedBatch::from_lanes(lanes)
    }

    /// Prepare `W` points into an existing batch, reusing `scratch` (no heap allocation once
    /// the scratch is sized).
    pub fn prepare_batch_into<const W: usize>(
        &self,
        p: &ShadingBatch<W>,
        scratch: &mut Scratch,
        out: &mut PreparedBatch<W>,
    ) {
        for k in 0..W {
            self.prepare_unpacked_into(&p.lane(k), scratch, &mut out.lanes[k]);
        }
        out.transpose();
    }

    /// Prepare `W` points for [`PreparedBatch::eval`], [`PreparedBatch::albedo`],
    /// [`PreparedBatch::emission`] and [`PreparedBatch::transparency`] only: what a
    /// sampling-free renderer such as the material preview needs. A material whose
    /// registers are all constants, whose leaves share the point's frame and have batched
    /// kernels is prepared lane-parallel, without per-lane records
    /// ([`PreparedBatch::lane`] is then `None`); any other material, or a batch with a view
    /// at or below some lane's horizon, goes through [`Material::prepare_batch_into`]. Both
    /// ways give the same results to rounding.
    pub fn prepare_batch_eval_into<const W: usize>(
        &self,
        p: &ShadingBatch<W>,
        scratch: &mut Scratch,
        out: &mut PreparedBatch<W>,
    ) {
        self.prepare_batch_eval_at(Level::Avx512, p, scratch, out);
    }

    testkit_pub! {
        /// [`Material::prepare_batch_eval_into`] with the lane-parallel steps compiled for at most
        /// `level` (module `simd`; every level gives the same bits).
        fn prepare_batch_eval_at<const W: usize>(
            &self,
            level: Level,
            p: &ShadingBatch<W>,
            scratch: &mut Scratch,
            out: &mut PreparedBatch<W>,
        ) {
            if !self.prepare_lanes::<W, true>(level, p, out) {
                self.prepare_batch_into(p, scratch, out);
            }
        }
    }

    testkit_pub! {
        /// [`Material::prepare_batch_eval_into`] for [`PreparedBatch::eval_f_cos`] and the
        /// per-lane albedo, emission and transparency alone (the batched material preview): the
        /// lane-parallel path leaves out step 7's selection probabilities, which only the
        /// densities read. After that path [`PreparedBatch::eval`]'s pdf is NaN.
        fn prepare_batch_f_cos_into<const W: usize>(
            &self,
            p: &ShadingBatch<W>,
            scratch: &mut Scratch,
            out: &mut PreparedBatch<W>,
        ) {
            if !self.prepare_lanes::<W, false>(Level::Avx512, p, out) {
                self.prepare_batch_into(p, scratch, out);
            }
        }
    }
}

impl LanePlan {
    /// The plan of `m`, or `None` when some part of it needs the general path: registers
    /// that are not constants, a weight pass without a plan, frames of its own, or a leaf
    /// without a batched kernel.
    pub(super) fn new(m: &Material) -> Option<LanePlan> {
        m.const_regs.as_ref()?;
        m.w_plan.as_ref()?;
        let own_frame = |f: &crate::ir::FrameSlot| {
            f.normal.is_none() && f.tangent.is_none() && f.rotation.is_none()
        };
        if m.nodes.is_empty() || m.frames.len() != 1 || !own_frame(&m.frames[0]) {
            return None;
        }
        let leaves = m
            .leaves
            .iter()
            .map(|info| LeafLanes::new(info.const_lobe.as_ref()?))
            .collect::<Option<Vec<_>>>()?;
        Some(LanePlan { leaves })
    }
}

impl LeafLanes {
    /// The leaf's data when its family and configuration have a kernel (the same cases as
    /// `Kernel::rebuild`, for views above the horizon).
    fn new(b: &crate::interp::lobe::BoundLobe) -> Option<LeafLanes> {
        Some(match (&b.lobe, &b.aux) {
            (Lobe::Lambert(l) | Lobe::SubsurfaceProxy(l), _) => LeafLanes::Lambert {
                rho: l.rho,
                rho_pi: l.prepare(Vec3::Z, false).rho_pi,
            },
            (Lobe::OrenNayar(o), Aux::OrenNayar(bound)) => LeafLanes::OrenNayar {
                lobe: *o,
                bound: *bound,
            },
            (Lobe::MicrofacetR(m), Aux::Microfacet(bound))
                if m.fresnel.is_conductor()
                    && !m.ggx.is_delta()
                    && m.comp == Compensation::None =>
            {
                LeafLanes::Conductor {
                    lobe: *m,
                    ggx_view: bound.ggx_view,
                    ratios: bound.ratios?,
                }
            }
            // Turquin's factor makes the tint view-dependent; the scalar prepare applies it
            // only for `k > 0` (so a NaN strength is off too).
            (Lobe::Dielectric(d), Aux::Dielectric(bound))
                if d.mode == DielectricMode::R
                    && !d.ggx.is_delta()
                    && (d.turquin <= 0.0 || d.turquin.is_nan()) =>
            {
                LeafLanes::DielectricR {
                    lobe: *d,
                    ggx_view: bound.ggx_view,
                    eta: d.eta0(),
                    e_r: bound.curves?[0][0],
                    aniso: bound.aniso.and_then(|g| g[0]),
                }
            }
            (Lobe::Ward(w), Aux::Ward(bound)) => LeafLanes::Ward {
                lobe: *w,
                bound: *bound,
            },
            (Lobe::SheenCK(s), Aux::SheenCK(bound)) if s.masking == SheenMasking::MaterialX => {
                LeafLanes::SheenCK { bound: *bound }
            }
            (Lobe::SheenLTC(_), Aux::SheenLTC(bound)) => LeafLanes::SheenLTC { bound: *bound },
            _ => return None,
        })
    }

    /// The leaf's albedo `E(μ_o)` per lane (reflection only: none of these families
    /// transmits), as its scalar prepare computes it. Families whose view terms reuse a
    /// scalar of the albedo also leave it in `e_hat` for [`LeafLanes::fill`]: EON's `Ê(μ_o)`
    /// (energy variants) and the LTC sheen's `Ê` (the albedo itself).
    #[allow(clippy::needless_range_loop)] // index loops over lanes vectorise best
    #[inline(always)]
    fn albedo<const W: usize>(
        &self,
        v: &Vec3x<W>,
        at: &LaneCoords<W>,
        out: &mut Vec3x<W>,
        e_hat: &mut [f32; W],
    ) {
        let mu = &v.z;
        match self {
            LeafLanes::Lambert { rho, .. } => {
                for k in 0..W {
                    out.set(k, *rho);
                }
            }
            LeafLanes::OrenNayar { lobe, bound } => lobe.albedo_lanes(bound, mu, at, out, e_hat),
            LeafLanes::Conductor { lobe, ratios, .. } => lobe.albedo_lanes(ratios, v, out),
            LeafLanes::DielectricR {
                lobe,
                eta,
                e_r,
                aniso,
                ..
            } => lobe.albedo_lanes_r(*eta, e_r, aniso.as_ref(), v, at, out),
            LeafLanes::Ward { lobe, bound } => lobe.albedo_lanes(bound, v, at, out),
            LeafLanes::SheenCK { bound } => bound.albedo_lanes(at, out),
            LeafLanes::SheenLTC { bound } => bound.albedo_lanes(mu, out, e_hat),
        }
    }

    /// Writes the leaf's view terms at local views `v` into `kernel`, with the slot's lane
    /// weights and probabilities `lw` folded in as `Kernel::rebuild` folds them; `e_hat` is
    /// what [`LeafLanes::albedo`] left there (computing it once saves an `acos` or an `exp`
    /// per lane).
    #[allow(clippy::needless_range_loop)] // index loops over lanes vectorise best
    #[inline(always)]
    fn fill<const W: usize>(
        &self,
        kernel: &mut Kernel<W>,
        v: &Vec3x<W>,
        lw: &LaneWeights<W>,
        e_hat: &[f32; W],
    ) {
        match self {
            LeafLanes::Lambert { rho_pi, .. } => lambert_set_views(kernel.lambert_mut(), *rho_pi, lw),
            LeafLanes::OrenNayar { lobe, bound } => {
                kernel.oren_nayar_mut().set_views(lobe, bound, v, lw, e_hat)
            }
            LeafLanes::Conductor { lobe, ggx_view, .. } => {
                kernel.conductor_mut().set_views(lobe, ggx_view, v, lw)
            }
            LeafLanes::DielectricR {
                lobe,
                ggx_view,
                eta,
                ..
            } => kernel.dielectric_r_mut().set_views_r(lobe, ggx_view, *eta, v, lw),
            LeafLanes::Ward { lobe, bound } => kernel.ward_mut().set_views(lobe, bound, v, lw),
            LeafLanes::SheenCK { bound } => kernel.sheen_ck_mut().set_views(bound, v),
            LeafLanes::SheenLTC { bound } => kernel.sheen_ltc_mut().set_views(bound, v, e_hat),
        }
    }
}

/// `f(a, b)` lane by lane.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
fn zip<const W: usize>(a: &Vec3x<W>, b: &Vec3x<W>, f: impl Fn(Vec3, Vec3) -> Vec3) -> Vec3x<W> {
    let mut out = Vec3x::zero();
    for k in 0..W {
        out.set(k, f(a.get(k), b.get(k)));
    }
    out
}

/// `v` in every lane.
#[inline(always)]
fn splat<const W: usize>(v: Vec3) -> Vec3x<W> {
    Vec3x {
        x: [v.x; W],
        y: [v.y; W],
        z: [v.z; W],
    }
}

/// Whether the lane-parallel prepare computes step 7's selection probabilities (a type, so
/// that the compiled versions of [`Material::prepare_lanes`] infer it from an argument).
#[derive(Debug, Clone, Copy)]
pub(in crate::interp) struct Densities<const ON: bool>;

impl Material {
    /// Prepares batch `p` lane-parallel into `out` (see the module documentation), compiled
    /// for the widest vector extension up to `level` that the CPU has (as the batched
    /// kernels are, [`crate::interp::simd`]; every version computes the same bits). Returns
    /// false, leaving `out` to be overwritten by the general path, when this material has no
    /// [`LanePlan`] or some lane's view is at or below the horizon. Without `PDF` the slots
    /// get no selection probabilities (their `lw.p` are 0 and `out.densities` is false):
    /// for callers that read only `f·μ_i` and the albedos.
    pub(in crate::interp) fn prepare_lanes<const W: usize, const PDF: bool>(
        &self,
        level: Level,
        p: &ShadingBatch<W>,
        out: &mut PreparedBatch<W>,
    ) -> bool {
        if self.lanes.is_none() {
            return false;
        }
        call_widest!(
            level,
            self.prepare_lanes_body(p, out, Densities::<PDF>),
            prepare_lanes_avx512,
            prepare_lanes_avx2
        )
    }

    widest_versions!(
        [const W: usize, const PDF: bool] prepare_lanes_body(
            p: &ShadingBatch<W>,
            out: &mut PreparedBatch<W>,
            densities: Densities<PDF>
        ) -> bool,
        prepare_lanes_avx512,
        prepare_lanes_avx2
    );

    #[inline(always)]
    fn prepare_lanes_body<const W: usize, const PDF: bool>(
        &self,
        p: &ShadingBatch<W>,
        out: &mut PreparedBatch<W>,
        _densities: Densities<PDF>,
    ) -> bool {
        let (Some(plan), Some(w_plan), Some(regs)) =
            (&self.lanes, &self.w_plan, self.const_regs.as_deref())
        else {
            return false;
        };
        // Step 2: the point's frame and V in it.
        let mut v = Vec3x::<W>::zero();
        for k in 0..W {
            let f = Frame::new(p.n[k], p.t[k]);
            out.frames[0].set(k, &f);
            v.set(k, f.to_local(p.v[k].normalize_or(Vec3::Z)));
        }
        if !(0..W).all(|k| v.z[k] > 0.0 && v.get(k).is_finite()) {
            return false;
        }
        let reg = |r: crate::ir::Reg| regs.get(r.index()).copied().unwrap_or(Vec3::ZERO);
        // Working arrays: albedos per leaf, throughput slots, scope products, plan targets.
        let n_leaves = plan.leaves.len();
        let (n_thr, n_scopes) = (self.thr_ops.len(), w_plan.scopes.len() + 1);
        let need = 2 * n_leaves + n_thr + n_scopes + w_plan.targets.len();
        // Taken out of the batch for the duration (the steps below also write the batch).
        let mut work = std::mem::take(&mut out.work);
        if work.len() < need {
            work.resize(need, Vec3x::zero());
        }
        let (alb, rest) = work.split_at_mut(n_leaves);
        // Per leaf, `x` holds the albedo's scalar that `fill` reuses (see `LeafLanes::albedo`).
        let (e_hat, rest) = rest.split_at_mut(n_leaves);
        let (thr, rest) = rest.split_at_mut(n_thr);
        let (scope, acc) = rest.split_at_mut(n_scopes);
        // The leaves' albedos (every leaf: all are needed for the throughputs, the drop
        // and the selection).
        let at = LaneCoords::new(&v.z);
        for ((leaf, a), e) in plan.leaves.iter().zip(alb.iter_mut()).zip(e_hat.iter_mut()) {
            leaf.albedo(&v, &at, a, &mut e.x);
        }
        // Step 3: throughputs, bottom-up (op `j` writes slot `j`).
        for j in 0..n_thr {
            let t = match self.thr_ops[j] {
                ThrOp::Leaf { leaf, mode } => {
                    let info = &self.leaves[leaf as usize];
                    if info.layerable {
                        let (tint, ttint) = (reg(info.leaf.tint), reg(info.leaf.ttint));
                        let a = &alb[leaf as usize];
                        // One loop per mode, each with the mode a constant (no branch inside).
                        let thr_in =
                            |m: TintMode| zip(a, a, |e, _| leaf_throughput(m, tint, ttint, e));
                        match mode {
                            TintMode::Rgb => thr_in(TintMode::Rgb),
                            TintMode::Gray => thr_in(TintMode::Gray),
                            TintMode::Luminance => thr_in(TintMode::Luminance),
                            TintMode::MaxChannel => thr_in(TintMode::MaxChannel),
                        }
                    } else {
                        Vec3x::zero()
                    }
                }
                ThrOp::One => splat(Vec3::ONE),
                ThrOp::Layer { top, base } => {
                    zip(&thr[top as usize], &thr[base as usize], |t, b| t * b)
                }
                ThrOp::Mix { a, b, m } => {
                    let m = sat(reg(m));
                    zip(&thr[a as usize], &thr[b as usize], |a, b| {
                        mix_throughput(a, b, m)
                    })
                }
                ThrOp::Add { a, b } => zip(&thr[a as usize], &thr[b as usize], add_throughput),
                ThrOp::Multiply { f, c } => {
                    let c = reg(c).max(Vec3::ZERO);
                    let t = &thr[f as usize];
                    zip(t, t, |t, _| mul_throughput(t, c))
                }
            };
            thr[j] = t;
        }
        // Step 4: the weight plan (scope products, then each target's sum of terms).
        scope[0] = splat(Vec3::ONE);
        for (i, &(parent, slot)) in w_plan.scopes.iter().enumerate() {
            scope[i + 1] = zip(&scope[parent as usize], &thr[slot as usize], |s, t| s * t);
        }
        for a in acc.iter_mut() {
            *a = Vec3x::zero();
        }
        for t in &w_plan.terms {
            let (c, s) = (t.c, &scope[t.scope as usize]);
            let a = &mut acc[t.target as usize];
            *a = zip(a, s, |a, s| a + c * s);
        }
        let mut weights = [Vec3x::<W>::zero(); MAX_LOBES];
        out.emission = Vec3x::zero();
        out.transparency = Vec3x::zero();
        for (target, a) in w_plan.targets.iter().zip(acc.iter()) {
            match *target {
                Target::Leaf { leaf, tint } if w_plan.weights_clean => {
                    weights[leaf as usize] = zip(a, a, |a, _| tint * a);
                }
                Target::Leaf { leaf, tint } => {
                    weights[leaf as usize] = zip(a, a, |a, _| clean(tint * a));
                }
                Target::Emission(e) => {
                    out.emission = zip(&out.emission, a, |s, a| s + clean(a * e));
                }
                Target::Transparent(t) => {
                    out.transparency = zip(&out.transparency, a, |s, a| s + clean(a * t));
                }
            }
        }
        // Steps 5–7 per lane: the weighted albedos, the drop, the selection; then each leaf
        // that survives in some lane gets a slot.
        let lanes = self.select_lanes::<W, PDF>(&weights[..n_leaves], alb, out);
        // Copied out of the selection, so that the loop over leaves keeps them in registers.
        let (sum, ok) = (lanes.sum, lanes.ok);
        let mut count = 0;
        for (i, leaf) in plan.leaves.iter().enumerate() {
            let (live, prob) = (&lanes.live[i], &lanes.prob[i]);
            if !live.iter().any(|&l| l) {
                continue;
            }
            let slot = &mut out.slots[count];
            slot.frame = 0;
            slot.live = *live;
            for k in 0..W {
                let on = live[k];
                slot.lw.w.set(k, select3(on, weights[i].get(k), Vec3::ZERO));
                slot.lw.p[k] = if PDF {
                    select(on & ok[k], prob[k] / sum[k], 0.0)
                } else {
                    0.0
                };
            }
            slot.lw.sign = [1.0; W];
            leaf.fill(&mut slot.kernel, &v, &slot.lw, &e_hat[i].x);
            count += 1;
        }
        out.count = count;
        out.frame_count = 1;
        out.lanes_valid = false;
        out.densities = PDF;
        out.work = work;
        true
    }

    /// Steps 5–7 of the prepare per lane, as [`Material::prepare_into`] does them for one point:
    /// the weighted albedo `A = w ⊙ E` of each leaf with a non-zero weight, the drop
    /// (`maxc(A) ≤ threshold`), the lanes' total albedo (into `out.albedo`), and the
    /// selection probabilities `lum(A_k)/Σ` (straight transmission taking part; by weight
    /// when every albedo is 0; all 0 when nothing reflects). Without `PDF` only the lanes
    /// that survive and the total albedo: the probabilities and sums stay 0.
    #[allow(clippy::needless_range_loop)] // index loops over lanes vectorise best
    #[inline(always)]
    fn select_lanes<const W: usize, const PDF: bool>(
        &self,
        weights: &[Vec3x<W>],
        alb: &[Vec3x<W>],
        out: &mut PreparedBatch<W>,
    ) -> LaneSelection<W> {
        let threshold = self.options.drop_threshold;
        let mut sel = LaneSelection {
            live: [[false; W]; MAX_LOBES],
            prob: [[0.0; W]; MAX_LOBES],
            sum: [0.0; W],
            ok: [false; W],
        };
        // Leaf by leaf, the lanes side by side. A lobe that does not survive adds exact
        // zeros to the sums, which changes no bit of them.
        let mut total = Vec3x::<W>::zero();
        let mut sum = [0.0f32; W];
        for (i, (w, a)) in weights.iter().zip(alb).enumerate() {
            for k in 0..W {
                let w = w.get(k);
                let reflect = w * a.get(k);
                // `&` and `|`, not `&&` and `||`, and blends, not `if`s: a branch in a loop
                // over lanes stops the vectoriser.
                let dropped = (threshold > 0.0) & (reflect.max_element() <= threshold);
                let kept = ((w.x != 0.0) | (w.y != 0.0) | (w.z != 0.0)) & !dropped;
                sel.live[i][k] = kept;
                if PDF {
                    let x = select(kept, lum(reflect).max(0.0), 0.0);
                    sel.prob[i][k] = x;
                    sum[k] += x;
                }
                total.set(k, total.get(k) + select3(kept, reflect, Vec3::ZERO));
            }
        }
        out.albedo = total;
        if !PDF {
            return sel;
        }
        let mut none = false;
        for k in 0..W {
            sum[k] += lum(out.transparency.get(k)).max(0.0);
            // NaN or ≤ 0 (`|`, no branch: see above).
            none |= sum[k].is_nan() | (sum[k] <= 0.0);
        }
        if none {
            // Some lane where nothing reflects: by weight there (rare, so lane by lane).
            for k in 0..W {
                if sum[k] > 0.0 {
                    continue;
                }
                sum[k] = 0.0;
                for (i, w) in weights.iter().enumerate() {
                    if sel.live[i][k] {
                        let x = lum(w.get(k)).max(0.0);
                        sel.prob[i][k] = x;
                        sum[k] += x;
                    }
                }
            }
        }
        // Positive and finite (a NaN fails both tests).
        let ok: [bool; W] = std::array::from_fn(|k| (sum[k] > 0.0) & (sum[k] < f32::INFINITY));
        // The division by the sum happens as the slots are filled (a pass over every
        // leaf here vectorised across leaves, with gathers).
        sel.sum = sum;
        sel.ok = ok;
        sel
    }
}

/// Which leaves survive in which lanes, with their selection probabilities
/// `prob[i][k]/sum[k]` (0 where not `ok[k]`: nothing to select).
struct LaneSelection<const W: usize> {
    live: [[bool; W]; MAX_LOBES],
    /// `max(lum(A), 0)` (or of the weight, when every albedo of the lane is 0).
    prob: [[f32; W]; MAX_LOBES],
    sum: [f32; W],
    ok: [bool; W],
}
