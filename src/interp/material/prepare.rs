//! The general prepare: run the program, build the frames, the throughput and weight passes,
//! the view terms of the weighted lobes, dropping and selection (the module documentation
//! of [`super`] lists the steps); its working memory is a [`Scratch`].

use super::form::{CNode, LeafInfo, Material, Target, ThrOp, WeightPlan, clean, sat};
use super::leaf::leaf_lobe;
use super::prepared::Prepared;
use super::record::{Albedo, ShadingPoint};
use crate::interp::frame::Frame;
use crate::interp::lobe::{LobeAlbedo, PreparedLobe};
use crate::interp::simd::{Level, SCALAR_LEVEL, call_widest, widest_versions};
use crate::ir::algebra::{add_throughput, mix_throughput, mul_throughput};
use crate::ir::{Globals, MAX_LOBES, Reg, RunContext};
use glam::Vec3;
use std::cell::RefCell;
use std::f32::consts::TAU;

/// Reusable working memory of [`Material::prepare_with`] (register file and per-node
/// arrays). Sized on first use; later calls with materials of equal or smaller size do not
/// allocate.
#[derive(Debug, Default, Clone)]
pub struct Scratch {
    pub(super) slots: Vec<Vec3>,
    pub(super) regs: Vec<Vec3>,
    pub(super) mu: Vec<f32>,
    pub(super) thr: Vec<Vec3>,
    pub(super) w: Vec<Vec3>,
    pub(super) scope: Vec<Vec3>,
}

thread_local! {
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

impl Material {
    /// Prepare for one point and view using a per-thread scratch (see [`Scratch`]).
    pub fn prepare(&self, p: &ShadingPoint) -> Prepared {
        SCRATCH.with(|s| match s.try_borrow_mut() {
            Ok(mut s) => self.prepare_with(p, &mut s),
            Err(_) => self.prepare_with(p, &mut Scratch::default()),
        })
    }

    /// Prepare for one point and view (all seven steps) with caller-supplied scratch memory.
    pub fn prepare_with(&self, p: &ShadingPoint, s: &mut Scratch) -> Prepared {
        let mut out = Prepared::empty(Vec3::Z);
        self.prepare_into(p, s, &mut out);
        out
    }

    /// As [`Material::prepare_with`], overwriting `out` (whatever it held): the cheapest
    /// form when many points are prepared in a row, since a [`Prepared`] is a few KB.
    ///
    /// Runs the version compiled for `SCALAR_LEVEL` when the CPU has it (see
    /// module `simd`); every version computes the same bits.
    pub fn prepare_into(&self, p: &ShadingPoint, s: &mut Scratch, out: &mut Prepared) {
        self.prepare_into_at(SCALAR_LEVEL, p, s, out);
    }

    testkit_pub! {
        /// [`Material::prepare_into`] compiled for at most `level` (for tests and benchmarks:
        /// every level gives the same bits).
        fn prepare_into_at(
            &self,
            level: Level,
            p: &ShadingPoint,
            s: &mut Scratch,
            out: &mut Prepared,
        ) {
            self.prepare_at(level, true, p, s, out);
        }
    }

    /// The steps into `out`, then `eval`'s lobe packs when `packs` (and the options ask
    /// for them), in the version compiled for at most `level`: the body of
    /// [`Material::prepare_into_at`] and [`Material::prepare_unpacked_into_at`].
    pub(super) fn prepare_at(
        &self,
        level: Level,
        packs: bool,
        p: &ShadingPoint,
        s: &mut Scratch,
        out: &mut Prepared,
    ) {
        call_widest!(
            level,
            self.prepare_body(packs, p, s, out),
            prepare_avx512,
            prepare_avx2
        )
    }

    widest_versions!(
        prepare_body(packs: bool, p: &ShadingPoint, s: &mut Scratch, out: &mut Prepared) -> (),
        prepare_avx512,
        prepare_avx2
    );

    /// [`Material::prepare_at`]'s body.
    #[inline(always)]
    pub(super) fn prepare_body(
        &self,
        packs: bool,
        p: &ShadingPoint,
        s: &mut Scratch,
        out: &mut Prepared,
    ) {
        let fused = self.prepare_steps(p, s, out);
        if !(packs && self.options.pack_lobes) {
            return;
        }
        let lobes = &out.lobes[..out.count];
        match (&self.pack_grouping, fused) {
            // Every leaf survived the fused prepare: lobe k is leaf k, none flipped.
            (Some(g), Some(stamp)) if lobes.len() == self.leaves.len() => {
                out.plan.build_stamped(stamp, g, lobes)
            }
            // Lobe k is leaf k when none was dropped; an inactive lobe has no kernel key.
            (Some(g), _)
                if lobes.len() == self.leaves.len()
                    && lobes.iter().all(|a| !a.lobe.is_inactive()) =>
            {
                out.plan.build_from(g, lobes)
            }
            _ => out.plan.build(lobes),
        }
    }

    testkit_pub! {
        /// All seven prepare steps into `out`: [`Material::prepare_into`] without planning
        /// `eval`'s lobe packs, whatever
        /// [`PrepareOptions::pack_lobes`](super::PrepareOptions::pack_lobes) says, so every
        /// lobe is evaluated alone. For callers that evaluate once per prepare (the material
        /// preview), where filling the packs costs more than it saves, and for the batched
        /// path, which reads the lobes and never a lane's own `eval`; the results are the same
        /// to relative 1e-5.
        ///
        /// A uniform material ([`Material::prepares_uniform`]) seen from above its surface is
        /// prepared by a fused form of the steps, over fixed arrays with its constants folded
        /// in; it computes the same bits as [`Material::prepare_general_into`].
        fn prepare_unpacked_into(&self, p: &ShadingPoint, s: &mut Scratch, out: &mut Prepared) {
            self.prepare_unpacked_into_at(SCALAR_LEVEL, p, s, out);
        }
    }

    testkit_pub! {
        /// [`Material::prepare_unpacked_into`] compiled for at most `level` (every level gives
        /// the same bits).
        fn prepare_unpacked_into_at(
            &self,
            level: Level,
            p: &ShadingPoint,
            s: &mut Scratch,
            out: &mut Prepared,
        ) {
            self.prepare_at(level, false, p, s, out);
        }
    }

    /// [`Material::prepare_unpacked_into`], returning the uniform plan's stamp when the
    /// fused form prepared the point.
    #[inline(always)]
    pub(super) fn prepare_steps(
        &self,
        p: &ShadingPoint,
        s: &mut Scratch,
        out: &mut Prepared,
    ) -> Option<u64> {
        if let Some(plan) = &self.uniform
            && self.prepare_uniform_into(plan, p, out)
        {
            return Some(plan.stamp);
        }
        self.prepare_general_into(p, s, out);
        None
    }

    testkit_pub! {
        /// [`Material::prepare_unpacked_into`] by the general algorithm, whatever the material:
        /// the program, frames from registers, and the throughput and weight passes over
        /// [`Scratch`]'s per-node arrays. For comparisons and tests; the results are the same.
        fn prepare_general_into(&self, p: &ShadingPoint, s: &mut Scratch, out: &mut Prepared) {
            let v = p.v.normalize_or(Vec3::Z);
            out.reset(v);
            // The records are about to hold this algorithm's (possibly flipped) lobes.
            out.stamp = 0;
            // Step 1: the program, with the point's inputs (fallbacks where missing). A program
            // of constants was run once at compile time.
            let run = self.const_regs.is_none();
            if run {
                self.unpack_inputs(p.inputs, &mut s.slots);
                let n_frames = self.ir.frames.len().max(1);
                let mu0 = p.n.normalize_or(Vec3::Z).dot(v);
                s.mu.clear();
                s.mu.resize(n_frames, mu0);
                self.run(s, self.globals(p, v));
            }
            // Step 2: frames and μ_o.
            self.build_frames(p, self.regs(s), out);
            if run && self.rerun_for_mu {
                let mut changed = false;
                for (k, &fi) in self.frame_ids.iter().enumerate() {
                    let fi = fi as usize;
                    let mu = out.frames[k].z.dot(v);
                    if s.mu[fi] != mu {
                        s.mu[fi] = mu;
                        changed = true;
                    }
                }
                if changed {
                    self.run(s, self.globals(p, v));
                    self.build_frames(p, &s.regs, out);
                }
            }
            if self.nodes.is_empty() {
                return;
            }
            // V in each frame, once (every leaf of a frame reads it).
            let mut v_local = [Vec3::Z; MAX_LOBES];
            for (vl, f) in v_local.iter_mut().zip(&out.frames[..out.frame_count]) {
                *vl = f.to_local(v);
            }
            let regs = self.regs(s);
            // Leaves are prepared in place, at their leaf index, in their frames: those inside
            // some layer top first (step 3 needs their E_k(μ_o)), the others only when their
            // weight turns out non-zero. Step 6 then compacts the array.
            // Each prepared leaf's albedo is read once from its record and kept here for steps 3
            // and 5.
            let mut ready = [false; MAX_LOBES];
            let mut albedos = [LobeAlbedo::default(); MAX_LOBES];
            for (k, info) in self.leaves.iter().enumerate() {
                if self.need[info.node.index()] != 0 {
                    let lobe = &mut out.lobes[k].lobe;
                    self.prepare_leaf(info, regs, v_local[info.frame_slot as usize], lobe);
                    albedos[k] = lobe.albedo();
                    ready[k] = true;
                }
            }
            // Step 3: throughput, bottom-up, only in the modes that are read.
            self.throughput(s, &albedos, &ready);
            // Step 4: weights, top-down; emission and transparency accumulate.
            let mut weights = [Vec3::ZERO; MAX_LOBES];
            self.weights(s, &mut weights, out);
            // Step 5: V-only terms and albedos of the weighted lobes; step 6: drop.
            let regs = self.regs(s);
            let threshold = self.options.drop_threshold;
            // Step 7's albedo luminances, kept here rather than read back from the records just
            // written (a read of fresh, differently sized stores stalls store forwarding).
            let mut lums = [0.0f32; MAX_LOBES];
            let mut count = 0;
            for (k, info) in self.leaves.iter().enumerate() {
                let w = weights[k];
                if w == Vec3::ZERO {
                    continue;
                }
                if !ready[k] {
                    let lobe = &mut out.lobes[k].lobe;
                    self.prepare_leaf(info, regs, v_local[info.frame_slot as usize], lobe);
                    albedos[k] = lobe.albedo();
                }
                let albedo = Albedo::scaled(&albedos[k], w);
                let a_max = albedo.reflect + albedo.transmit.max(albedo.transmit_radiance);
                if threshold > 0.0 && a_max.max_element() <= threshold {
                    continue;
                }
                lums[count] = out.keep(count, k, w, albedo, info.frame_slot);
                out.flipped_any |= out.lobes[count].lobe.is_flipped();
                count += 1;
            }
            out.count = count;
            // Step 7: selection probabilities.
            out.select(&lums);
        }
    }

    pub(super) fn regs<'s>(&'s self, s: &'s Scratch) -> &'s [Vec3] {
        self.const_regs.as_deref().unwrap_or(&s.regs)
    }

    pub(super) fn globals(&self, p: &ShadingPoint, v: Vec3) -> Globals {
        Globals {
            p: p.p,
            n: p.n,
            t: p.t,
            i: v,
            u: p.uv.x,
            v: p.uv.y,
        }
    }

    pub(super) fn unpack_inputs(&self, packed: &[f32], slots: &mut Vec<Vec3>) {
        slots.clear();
        for (slot, &(o, w)) in self.ir.inputs.iter().zip(&self.layout) {
            let v = match packed.get(o..o + w) {
                Some([x]) => Vec3::splat(*x),
                Some([x, y, z]) => Vec3::new(*x, *y, *z),
                _ => slot.fallback_vec(),
            };
            slots.push(v);
        }
    }

    pub(super) fn run(&self, s: &mut Scratch, globals: Globals) {
        let ctx = RunContext {
            inputs: &s.slots,
            mu_o: &s.mu,
            globals,
        };
        self.ir.program.run_into(&ctx, &mut s.regs);
    }

    pub(super) fn build_frames(&self, p: &ShadingPoint, regs: &[Vec3], out: &mut Prepared) {
        let reg = |r: Option<Reg>| {
            r.and_then(|r| regs.get(r.index()).copied())
                .filter(|v| *v != Vec3::ZERO && v.is_finite())
        };
        for (k, slot) in self.frames.iter().enumerate() {
            let n = reg(slot.normal).unwrap_or(p.n);
            let t = reg(slot.tangent).unwrap_or(p.t);
            let mut f = Frame::new(n, t);
            if let Some(rot) = reg(slot.rotation) {
                f = f.rotated(rot.x * TAU);
            }
            out.frames[k] = f;
        }
        out.frame_count = self.frames.len();
    }

    /// Prepares leaf `info` at local view `v` into `out`.
    pub(super) fn prepare_leaf(
        &self,
        info: &LeafInfo,
        regs: &[Vec3],
        v: Vec3,
        out: &mut PreparedLobe,
    ) {
        match &info.const_lobe {
            Some(lobe) => lobe.prepare_into(v, self.options.sides, out),
            None => *out = leaf_lobe(&info.leaf.kind, regs).prepare(v, self.options.sides),
        }
    }

    pub(super) fn throughput(
        &self,
        s: &mut Scratch,
        albedos: &[LobeAlbedo; MAX_LOBES],
        ready: &[bool; MAX_LOBES],
    ) {
        s.thr.clear();
        let regs = self.const_regs.as_deref().unwrap_or(&s.regs);
        let reg = |r: Reg| regs.get(r.index()).copied().unwrap_or(Vec3::ZERO);
        let thr = &mut s.thr;
        // Step `i` writes slot `i`, reading only slots written before it.
        for op in &self.thr_ops {
            let t = match *op {
                ThrOp::Leaf { leaf, mode } => {
                    let info = &self.leaves[leaf as usize];
                    if ready[leaf as usize] && info.layerable {
                        let a = &albedos[leaf as usize];
                        let e = a.reflect + a.transmit_energy;
                        let (tint, ttint) = (reg(info.leaf.tint), reg(info.leaf.ttint));
                        crate::ir::algebra::leaf_throughput(mode, tint, ttint, e)
                    } else {
                        Vec3::ZERO
                    }
                }
                ThrOp::One => Vec3::ONE,
                ThrOp::Layer { top, base } => thr[top as usize] * thr[base as usize],
                ThrOp::Mix { a, b, m } => {
                    mix_throughput(thr[a as usize], thr[b as usize], sat(reg(m)))
                }
                ThrOp::Add { a, b } => add_throughput(thr[a as usize], thr[b as usize]),
                ThrOp::Multiply { f, c } => mul_throughput(thr[f as usize], reg(c).max(Vec3::ZERO)),
            };
            thr.push(t);
        }
    }

    pub(super) fn weights(
        &self,
        s: &mut Scratch,
        weights: &mut [Vec3; MAX_LOBES],
        out: &mut Prepared,
    ) {
        if let Some(plan) = &self.w_plan {
            return self.weights_planned(plan, s, weights, out);
        }
        let n = self.nodes.len();
        s.w.clear();
        s.w.resize(n, Vec3::ZERO);
        s.w[0] = Vec3::ONE;
        let regs = self.const_regs.as_deref().unwrap_or(&s.regs);
        let reg = |r: Reg| regs.get(r.index()).copied().unwrap_or(Vec3::ZERO);
        let w = &mut s.w;
        for i in 0..n {
            let wi = w[i];
            if wi == Vec3::ZERO {
                continue;
            }
            match self.nodes[i] {
                CNode::Leaf(k) => {
                    let tint = reg(self.leaves[k as usize].leaf.tint);
                    weights[k as usize] += clean(tint * wi);
                }
                CNode::Emission(r) => out.emission += clean(wi * reg(r)),
                CNode::Transparent(r) => out.transparency += clean(wi * reg(r)),
                CNode::Layer { top, base, mode } => {
                    w[top as usize] += wi;
                    let t = self.thr_slot[top as usize][mode as usize];
                    w[base as usize] += wi * s.thr[t as usize];
                }
                CNode::Mix { a, b, m } => {
                    let m = sat(reg(m));
                    w[a as usize] += (Vec3::ONE - m) * wi;
                    w[b as usize] += m * wi;
                }
                CNode::Add { a, b } => {
                    w[a as usize] += wi;
                    w[b as usize] += wi;
                }
                CNode::Multiply { f, c } => w[f as usize] += reg(c).max(Vec3::ZERO) * wi,
            }
        }
    }

    /// [`Material::weights`] for constant registers, from the compiled terms of
    /// [`compile_weights`](super::plan::compile_weights): each target's weight is its terms'
    /// sum, cleaned once, as the general pass does with the sum over a node's parents.
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
