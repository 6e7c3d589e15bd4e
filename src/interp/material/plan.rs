//! The weight pass of a material with constant registers, compiled once into a
//! [`WeightPlan`] of per-path terms.

use super::compile::{CNode, LeafInfo, Material};
use super::prepare::{Scratch, clean, sat};
use super::prepared::Prepared;
use crate::ir::{MAX_LOBES, Reg};
use glam::Vec3;
use std::collections::HashMap;

impl Material {
    /// [`Material::weights`] for constant registers, from the compiled terms of
    /// [`compile_weights`]: each target's weight is its terms' sum, cleaned once, as the
    /// general pass does with the sum over a node's parents.
    pub(super) fn weights_planned(
        &self,
        plan: &WeightPlan,
        s: &mut Scratch,
        weights: &mut [Vec3; MAX_LOBES],
        out: &mut Prepared,
    ) {
        let thr = &s.thr[..];
        // Scope products, parents first (scope 0 is the root's 1).
        let scope = &mut s.scope;
        scope.clear();
        scope.push(Vec3::ONE);
        for &(parent, slot) in &plan.scopes {
            let w = scope[parent as usize] * thr[slot as usize];
            scope.push(w);
        }
        let acc = &mut s.w;
        acc.clear();
        acc.resize(plan.targets.len(), Vec3::ZERO);
        for t in &plan.terms {
            acc[t.target as usize] += t.c * scope[t.scope as usize];
        }
        for (target, &a) in plan.targets.iter().zip(acc.iter()) {
            match *target {
                Target::Leaf { leaf, tint } => weights[leaf as usize] = clean(tint * a),
                Target::Emission(e) => out.emission += clean(a * e),
                Target::Transparent(t) => out.transparency += clean(a * t),
            }
        }
    }
}

/// The weight pass of a material with constant registers, compiled: every
/// root-to-target path of the closure DAG is one term `c ⊙ Π thr[j]`, where `c` is the
/// product of the path's constant `mix` and `mul` factors and the `thr[j]` are the
/// throughputs of the layer tops the path passes under (the only view-dependent part).
/// Paths share their products through *scopes*: a scope is a sequence of layer tops passed
/// under, its product is its parent's times one throughput, so every product is one
/// multiplication whatever the nesting depth.
#[derive(Debug, Clone)]
pub(super) struct WeightPlan {
    pub(super) terms: Vec<WTerm>,
    /// Scope `i + 1` = scope `parent` × `thr[slot]`; scope 0 is 1. Parents come first.
    pub(super) scopes: Vec<(u32, u16)>,
    /// Leaves, emission and transparency nodes, each with its own accumulator.
    pub(super) targets: Vec<Target>,
    /// Every leaf weight is finite and non-negative at every point, whatever the albedos
    /// ([`weights_are_clean`]): [`clean`] of it is the identity, and the fused and
    /// lane-parallel prepares skip it.
    pub(super) weights_clean: bool,
}

/// One path of a [`WeightPlan`]: `c ⊙ scope` added to a target.
#[derive(Debug, Clone, Copy)]
pub(super) struct WTerm {
    pub(super) c: Vec3,
    /// The path's scope (its product of throughputs).
    pub(super) scope: u32,
    /// Index into [`WeightPlan::targets`].
    pub(super) target: u32,
}

/// What a [`WeightPlan`] term's weight goes to.
#[derive(Debug, Clone, Copy)]
pub(super) enum Target {
    /// `weights[leaf] = clean(tint ⊙ Σ)`.
    Leaf { leaf: u8, tint: Vec3 },
    /// `emission += clean(Σ ⊙ radiance)`.
    Emission(Vec3),
    /// `transparency += clean(Σ ⊙ tint)`.
    Transparent(Vec3),
}

/// Above this many paths a material keeps the general weight pass (a DAG that shares
/// nodes can have exponentially many).
pub(super) const MAX_WEIGHT_TERMS: usize = 256;

/// Compile the weight pass for constant registers `regs` ([`WeightPlan`]); `None` when the
/// DAG has more than [`MAX_WEIGHT_TERMS`] paths. Paths through a zero `mix` or `mul`
/// factor are left out (they carry no weight).
pub(super) fn compile_weights(
    nodes: &[CNode],
    leaves: &[LeafInfo],
    thr_slot: &[[u16; 4]],
    regs: &[Vec3],
) -> Option<WeightPlan> {
    let reg = |r: Reg| regs.get(r.index()).copied().unwrap_or(Vec3::ZERO);
    let mut plan = WeightPlan {
        terms: Vec::new(),
        scopes: Vec::new(),
        targets: Vec::new(),
        weights_clean: false,
    };
    if nodes.is_empty() {
        return Some(plan);
    }
    // Target index per node (leaves, emission and transparency), in node order.
    let mut target_of = vec![u32::MAX; nodes.len()];
    for (i, node) in nodes.iter().enumerate() {
        let t = match *node {
            CNode::Leaf(k) => Target::Leaf {
                leaf: k,
                tint: reg(leaves[k as usize].leaf.tint),
            },
            CNode::Emission(r) => Target::Emission(reg(r)),
            CNode::Transparent(r) => Target::Transparent(reg(r)),
            _ => continue,
        };
        target_of[i] = plan.targets.len() as u32;
        plan.targets.push(t);
    }
    // (parent scope, slot) → scope, so that paths under the same tops share one scope.
    let mut scope_of: HashMap<(u32, u16), u32> = HashMap::new();
    // Depth-first over paths with an explicit stack: (node, factor, scope).
    let mut stack: Vec<(u32, Vec3, u32)> = vec![(0, Vec3::ONE, 0)];
    while let Some((i, c, scope)) = stack.pop() {
        let mut push = |to: u32, f: Vec3, scope: u32| {
            if f != Vec3::ZERO {
                stack.push((to, c * f, scope));
            }
        };
        match nodes[i as usize] {
            CNode::Leaf(_) | CNode::Emission(_) | CNode::Transparent(_) => {
                if plan.terms.len() >= MAX_WEIGHT_TERMS {
                    return None;
                }
                plan.terms.push(WTerm {
                    c,
                    scope,
                    target: target_of[i as usize],
                });
            }
            CNode::Layer { top, base, mode } => {
                let slot = thr_slot[top as usize][mode as usize];
                let next = plan.scopes.len() as u32 + 1;
                let below = *scope_of.entry((scope, slot)).or_insert(next);
                if below == next {
                    plan.scopes.push((scope, slot));
                }
                push(top, Vec3::ONE, scope);
                push(base, Vec3::ONE, below);
            }
            CNode::Mix { a, b, m } => {
                let m = sat(reg(m));
                push(a, Vec3::ONE - m, scope);
                push(b, m, scope);
            }
            CNode::Add { a, b } => {
                push(a, Vec3::ONE, scope);
                push(b, Vec3::ONE, scope);
            }
            CNode::Multiply { f, c: r } => push(f, reg(r).max(Vec3::ZERO), scope),
        }
        if stack.len() > MAX_WEIGHT_TERMS * 4 {
            return None;
        }
    }
    plan.weights_clean = weights_are_clean(&plan);
    Some(plan)
}

/// Whether every leaf weight of `w_plan` is finite and non-negative (+0 rather than −0) at
/// every point, so that [`clean`] returns it bit for bit: true when every term's
/// constant and every leaf target's tint is finite, at most 1e15 and without a sign bit.
///
/// A weight is `tint ⊙ Σ c ⊙ scope`, and every scope is a product of throughputs, each of
/// them `sat` of something, a `max` with 0, a product or a convex sum of such: each in
/// [0, 1] up to rounding, never NaN (glam's `max(NaN, 0)` is 0), never −0. So each weight
/// is a sum of products of non-negative finite factors below 1e30.
pub(super) fn weights_are_clean(w_plan: &WeightPlan) -> bool {
    let ok = |v: Vec3| {
        v.to_array()
            .iter()
            .all(|x| x.is_finite() && x.is_sign_positive() && *x <= 1e15)
    };
    w_plan.terms.iter().all(|t| ok(t.c))
        && w_plan.targets.iter().all(|t| match *t {
            Target::Leaf { tint, .. } => ok(tint),
            _ => true,
        })
}
