//! The scalar prepare of a uniform material: the seven prepare steps for one point, fused into
//! one pass over fixed arrays.
//!
//! [`Material::prepare_general_into`] runs the steps for any material: the program, frames
//! from registers, leaves prepared only when some layer or weight reads them, a throughput
//! pass that looks its registers up, and the per-node arrays of a [`super::Scratch`]. For
//! the materials the lane-parallel prepare covers ([`LanePlan`](super::form::LanePlan): constant
//! registers, a compiled weight plan, one frame, the point's own) most of that is decided
//! at compile time, and what is left per point is short:
//!
//! 1. the point's frame and V in it (a view at or below the horizon, or not finite, goes to
//!    the general path: lobes there may be inactive or flipped);
//! 2. every leaf's record from its bound constant lobe, and its albedo: only the record's
//!    view-dependent fields when the records hold this material's leaves from the previous
//!    point ([`Prepared`]'s stamp), else the leaf's template first;
//! 3. the throughput steps with their registers folded to constants ([`UniformThr`]);
//! 4. the weight plan's scopes and terms, and each target's sum (in a tree, where each
//!    target has one term, the term itself);
//! 5. and 6. in the same pass over the targets, each leaf's weighted albedo and the drop,
//!    compacting the records;
//! 7. the selection probabilities.
//!
//! Every formula is the general path's, in the same order, so the two agree bit for bit
//! (`tests/interp/uniform.rs`).

use super::form::{
    LeafTarget, LightTarget, Material, Target, ThrOp, TreeTerm, UniformLeaf, UniformPlan,
    UniformThr, WeightPlan, clean, sat,
};
use super::prepared::Prepared;
use super::record::{Albedo, ShadingPoint};
use crate::interp::frame::Frame;
use crate::interp::lobe::Sides;
use crate::ir::algebra::{add_throughput, leaf_throughput, mix_throughput, mul_throughput};
use crate::ir::{MAX_LOBES, Reg, TintMode};
use glam::Vec3;
use std::sync::atomic::{AtomicU64, Ordering};

/// Throughput steps, scopes and weight targets a uniform plan may have: the per-point
/// arrays are fixed, on the stack. A material with more takes the general path.
const MAX_UNIFORM_SLOTS: usize = 16;

impl UniformPlan {
    /// The plan of `m`, or `None` when it needs the general path: no lane plan (see the
    /// module documentation), a leaf without a bound constant lobe, more steps, scopes or
    /// targets than [`MAX_UNIFORM_SLOTS`], or leaf targets out of leaf order.
    pub(super) fn new(m: &Material) -> Option<UniformPlan> {
        m.lanes.as_ref()?;
        let regs = m.const_regs.as_deref()?;
        let w_plan = m.w_plan.as_ref()?;
        let leaves = m
            .leaves
            .iter()
            .map(|info| info.const_lobe)
            .collect::<Option<Vec<_>>>()?;
        if m.thr_ops.len() > MAX_UNIFORM_SLOTS
            || w_plan.scopes.len() + 1 > MAX_UNIFORM_SLOTS
            || w_plan.targets.len() > MAX_UNIFORM_SLOTS
        {
            return None;
        }
        // The fused pass compacts records as it meets leaf targets, so they must come in
        // leaf order (they do: both follow the nodes; checked rather than assumed).
        let leaf_targets = w_plan.targets.iter().filter_map(|t| match t {
            Target::Leaf { leaf, .. } => Some(*leaf),
            _ => None,
        });
        if !leaf_targets.eq(0..m.leaves.len() as u8) {
            return None;
        }
        let reg = |r: Reg| regs.get(r.index()).copied().unwrap_or(Vec3::ZERO);
        let thr = m
            .thr_ops
            .iter()
            .map(|op| match *op {
                ThrOp::Leaf { leaf, mode } => {
                    let info = &m.leaves[leaf as usize];
                    let (tint, ttint) = (reg(info.leaf.tint), reg(info.leaf.ttint));
                    if !info.layerable {
                        UniformThr::Const(Vec3::ZERO)
                    } else if mode == TintMode::Rgb && tint == Vec3::ONE && ttint == Vec3::ONE {
                        UniformThr::LeafPlain { leaf }
                    } else {
                        UniformThr::Leaf {
                            leaf,
                            mode,
                            tint,
                            ttint,
                        }
                    }
                }
                ThrOp::One => UniformThr::Const(Vec3::ONE),
                ThrOp::Layer { top, base } => UniformThr::Layer {
                    top: top as u8,
                    base: base as u8,
                },
                ThrOp::Mix { a, b, m } => UniformThr::Mix {
                    a: a as u8,
                    b: b as u8,
                    m: sat(reg(m)),
                },
                ThrOp::Add { a, b } => UniformThr::Add {
                    a: a as u8,
                    b: b as u8,
                },
                ThrOp::Multiply { f, c } => UniformThr::Multiply {
                    f: f as u8,
                    c: reg(c).max(Vec3::ZERO),
                },
            })
            .collect();
        // Relaxed: the counter only has to hand out distinct values.
        static NEXT_STAMP: AtomicU64 = AtomicU64::new(1);
        let stamp = NEXT_STAMP.fetch_add(1, Ordering::Relaxed);
        let templates = leaves
            .iter()
            .map(|lobe| lobe.prepare(Vec3::Z, Sides::Front))
            .collect();
        let leaves = leaves
            .into_iter()
            .map(|lobe| UniformLeaf {
                lobe,
                refresh: lobe.refresh_leaf(),
            })
            .collect();
        let single = single_terms(w_plan);
        let term = |t: usize| match &single {
            Some(terms) => terms[t],
            None => TreeTerm {
                c: Vec3::ZERO,
                scope: 0,
            },
        };
        let (mut leaf_targets, mut light_targets) = (Vec::new(), Vec::new());
        for (t, &kind) in w_plan.targets.iter().enumerate() {
            let (term, target) = (term(t), t as u8);
            match kind {
                Target::Leaf { leaf, tint } => leaf_targets.push(LeafTarget {
                    tint,
                    term,
                    target,
                    leaf,
                }),
                _ => light_targets.push(LightTarget { kind, term, target }),
            }
        }
        Some(UniformPlan {
            stamp,
            leaves,
            templates,
            thr,
            tree: single.is_some(),
            leaf_targets,
            light_targets,
            weights_clean: w_plan.weights_clean,
        })
    }
}

/// Each target's one term in target order, or `None` when some target has more than one
/// (the plan is not a tree, [`UniformPlan::tree`]).
fn single_terms(w_plan: &WeightPlan) -> Option<Vec<TreeTerm>> {
    let mut single = vec![None; w_plan.targets.len()];
    for t in &w_plan.terms {
        let slot = single.get_mut(t.target as usize)?;
        if slot.is_some() {
            return None;
        }
        // Scopes are fewer than `MAX_UNIFORM_SLOTS` (checked by `UniformPlan::new`).
        *slot = Some(TreeTerm {
            c: t.c,
            scope: t.scope as u8,
        });
    }
    Some(
        single
            .into_iter()
            .map(|t| {
                t.unwrap_or(TreeTerm {
                    c: Vec3::ZERO,
                    scope: 0,
                })
            })
            .collect(),
    )
}

impl Material {
    /// Steps 1–7 of the prepare for a material with a [`UniformPlan`], into `out`. Returns false,
    /// having reset `out` and written only its frame, when the view is at or below the
    /// horizon of the point's frame or not finite: the general path then prepares the
    /// point.
    #[inline(always)]
    pub(super) fn prepare_uniform_into(
        &self,
        plan: &UniformPlan,
        p: &ShadingPoint,
        out: &mut Prepared,
    ) -> bool {
        let v = p.v.normalize_or(Vec3::Z);
        out.reset(v);
        // A plan exists only with a weight plan (`UniformPlan::new`).
        let Some(w_plan) = &self.w_plan else {
            return false;
        };
        // Step 2: the point's frame (the general path's `build_frames` for a frame without
        // registers) and V in it.
        let frame = Frame::new(p.n, p.t);
        out.frames[0] = frame;
        out.frame_count = 1;
        let v_local = frame.to_local(v);
        if !(v_local.z > 0.0 && v_local.is_finite()) {
            return false;
        }
        // Every leaf's record and albedo (all leaves are constants, so each is bound). Every
        // family of the plan reflects only (its transmitted parts are 0). Records this
        // material wrote at the previous point, every leaf in place, already hold their
        // view-independent fields; others start from the templates.
        if out.stamp != plan.stamp {
            for (template, a) in plan.templates.iter().zip(&mut out.lobes) {
                a.lobe = *template;
            }
        }
        let mut albedos = [Vec3::ZERO; MAX_LOBES];
        for ((leaf, a), alb) in plan.leaves.iter().zip(&mut out.lobes).zip(&mut albedos) {
            *alb = leaf
                .refresh
                .refresh_above_into(&leaf.lobe, v_local, &mut a.lobe);
        }
        // Step 3: throughputs, bottom-up (step `j` writes slot `j`).
        let mut thr = [Vec3::ZERO; MAX_UNIFORM_SLOTS];
        for (j, op) in plan.thr.iter().enumerate() {
            thr[j] = match *op {
                UniformThr::Leaf {
                    leaf,
                    mode,
                    tint,
                    ttint,
                } => leaf_throughput(mode, tint, ttint, albedos[leaf as usize]),
                UniformThr::LeafPlain { leaf } => sat(Vec3::ONE - albedos[leaf as usize]),
                UniformThr::Const(c) => c,
                UniformThr::Layer { top, base } => thr[top as usize] * thr[base as usize],
                UniformThr::Mix { a, b, m } => mix_throughput(thr[a as usize], thr[b as usize], m),
                UniformThr::Add { a, b } => add_throughput(thr[a as usize], thr[b as usize]),
                UniformThr::Multiply { f, c } => mul_throughput(thr[f as usize], c),
            };
        }
        // Step 4: the weight plan (scope products, then each target's sum of its terms).
        // Scope 0 is 1; the others are written before they are read (parents first). Zeros
        // fill the array in a few wide stores, where ones took one store per channel.
        let mut scope = [Vec3::ZERO; MAX_UNIFORM_SLOTS];
        scope[0] = Vec3::ONE;
        for (i, &(parent, slot)) in w_plan.scopes.iter().enumerate() {
            scope[i + 1] = scope[parent as usize] * thr[slot as usize];
        }
        // The targets' sums: in a tree each is its one term, computed where it is read; else
        // accumulated by target index first.
        let mut lums = [0.0f32; MAX_LOBES];
        let count = if plan.tree {
            // `0 + c·s` and `c·s` differ only in the sign of a zero, which `clean` maps to +0
            // either way (and with `weights_clean`, `c` and `s` are unsigned, so the product
            // is +0 already).
            let sum = |term: TreeTerm, _| term.c * scope[term.scope as usize];
            self.weigh_targets(plan, &albedos, sum, &mut lums, out)
        } else {
            let mut acc = [Vec3::ZERO; MAX_UNIFORM_SLOTS];
            for t in &w_plan.terms {
                acc[t.target as usize] += t.c * scope[t.scope as usize];
            }
            let sum = |_, target: u8| acc[target as usize];
            self.weigh_targets(plan, &albedos, sum, &mut lums, out)
        };
        out.count = count;
        // A dropped lobe moved the records after it down: they are no longer in place.
        out.stamp = if count == plan.leaves.len() {
            plan.stamp
        } else {
            0
        };
        // A lobe flips only for a view below its surface (`v_local.z > 0` here).
        out.flipped_any = false;
        // Step 7: selection probabilities.
        out.select(&lums);
        true
    }

    /// Steps 5 and 6 with the end of step 4: each target's weight from its sum (`sum` of its
    /// term and its index), and for a leaf its weighted albedo and the drop, compacting the
    /// records in place; emission and transparency go to `out`. Writes each kept lobe's
    /// share of step 7 into `lums` and returns how many were kept.
    ///
    /// Leaf targets come in leaf order (both follow the nodes), so a record only ever moves
    /// down.
    #[inline(always)]
    fn weigh_targets(
        &self,
        plan: &UniformPlan,
        albedos: &[Vec3; MAX_LOBES],
        sum: impl Fn(TreeTerm, u8) -> Vec3,
        lums: &mut [f32; MAX_LOBES],
        out: &mut Prepared,
    ) -> usize {
        let threshold = self.options.drop_threshold;
        let mut count = 0;
        for t in &plan.leaf_targets {
            let k = t.leaf as usize;
            let w = t.tint * sum(t.term, t.target);
            let w = if plan.weights_clean { w } else { clean(w) };
            if w == Vec3::ZERO {
                continue;
            }
            let reflect = w * albedos[k];
            if threshold > 0.0 && reflect.max_element() <= threshold {
                continue;
            }
            let albedo = Albedo {
                reflect,
                ..Albedo::default()
            };
            lums[count] = out.keep(count, k, w, albedo, 0);
            count += 1;
        }
        // Summed in locals: `out`'s fields would be reloaded after every store.
        let (mut emission, mut transparency) = (Vec3::ZERO, Vec3::ZERO);
        for t in &plan.light_targets {
            let a = sum(t.term, t.target);
            match t.kind {
                Target::Emission(e) => emission += clean(a * e),
                Target::Transparent(tint) => transparency += clean(a * tint),
                Target::Leaf { .. } => {}
            }
        }
        out.emission = emission;
        out.transparency = transparency;
        count
    }
}
