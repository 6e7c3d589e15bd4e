//! The weight pass of a material with constant registers, compiled once into a
//! [`WeightPlan`] of per-path terms.

use super::form::{CNode, LeafInfo, Target, WTerm, WeightPlan, sat};
use crate::ir::Reg;
use glam::Vec3;
use std::collections::HashMap;

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
