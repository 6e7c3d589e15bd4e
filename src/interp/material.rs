//! The interpreter API over a whole material: compile a
//! [`MaterialIr`] once into a [`Material`], then [`Material::prepare`] per (point, view) and
//! [`Prepared::eval`] / [`Prepared::sample`] / [`Prepared::albedo`] per light direction.
//!
//! # The compile step
//! [`Material::new`] checks the IR (child order, register and frame indices, lobe count) and
//! turns it into a flat, interpreter-friendly form: the closure nodes with their children as
//! plain indices, the leaves in node order with their compact frame slot, and, per node, the
//! set of tint modes in which its throughput is ever read (a node outside every layer top
//! needs none, so the throughput pass skips it). Everything that does not depend on the
//! point is decided there, once.
//!
//! # Prepare, without heap allocation
//! `prepare` follows seven steps in order: (1) run the program, (2) build the frames and
//! `μ_o`, (3) throughput bottom-up, (4) weights top-down, (5) view-only terms and albedos of
//! the weighted lobes, (6) drop negligible lobes, (7) selection probabilities. The register file
//! and the per-node throughput and weight arrays have the IR's (unbounded) sizes, so they live in a
//! reusable [`Scratch`]: [`Material::prepare_with`] takes one from the caller,
//! [`Material::prepare`] uses a per-thread scratch (allocated on a thread's first call, reused
//! afterwards). The result, [`Prepared`], is a fixed array of `MAX_LOBES` [`ActiveLobe`]s and never
//! allocates; `eval` and `sample` neither. A uniform material seen from above its surface is
//! prepared by a fused form of the same steps over fixed arrays (`material/uniform.rs`), with the
//! same results as the general form, [`Material::prepare_general_into`].
//!
//! # Choices where the spec is silent
//! * Frames whose normal comes from a register: the program runs once with every frame's
//!   `μ_o` taken from the shading normal; when a frame's own normal gives a different `μ_o`
//!   and the program reads `ViewMu`, it runs a second time with the corrected values (a
//!   normal that depends on `μ_o` would be circular anyway).
//! * Lobe weights are clamped to be non-negative and finite (a negative tint from a program
//!   would otherwise produce a negative response).
//! * Step 6 drops a lobe when `maxc(A_k) ≤ threshold` where the transmitted part of `A_k` is
//!   the larger of its radiance and energy forms (so that a transmission lobe is dropped
//!   only when it is negligible in both conventions).
//! * Step 7's selection uses `lum(A_k)` with transmission in the radiance convention: that is
//!   what the lobe's sample weights average to, so it is the choice with the least variance.
//! * `Transparent` leaves are not lobes (they do not count toward `MAX_LOBES`, and are not in
//!   [`Prepared::lobes`] or [`Prepared::albedo`]), but `sample` does choose straight
//!   transmission (`L = −V`, weight `τ/p`) with probability `lum(τ)/Σ`, reported with
//!   lobe index [`TRANSPARENCY_LOBE`]. The mean of sample weights is therefore
//!   `albedo().reflect + albedo().transmit_radiance + transparency()`.
//! * External inputs are packed 3 floats per colour/vector slot and 1 per scalar slot, in
//!   slot order ([`Material::input_layout`]); a slot that lies (even partly) beyond the end of
//!   [`ShadingPoint::inputs`] takes its fallback.

use super::diffuse::{Burley, Lambert, MiaDiffuse, OrenNayar, OrenNayarVariant};
use super::frame::Frame;
use super::fresnel::Fresnel as LobeFresnel;
use super::ggx::Ggx;
use super::lobe::{BoundLobe, Lobe, LobeAlbedo, PreparedLobe, Sides};
use super::math::{Rgb, lum};
use super::microfacet::{Compensation, Dielectric, MicrofacetR};
use super::sheen::{SheenCK, SheenLTC};
use super::simd::{Level, SCALAR_LEVEL, call_widest, widest_versions};
use super::ward::{MiaHighlight3, Ward};
use crate::diag::{Diagnostic, Error};
use crate::ir::algebra::{AlbedoSource, add_throughput, mix_throughput, mul_throughput};
use crate::ir::{
    FrameSlot, Fresnel, Globals, Leaf, LeafKind, MAX_LOBES, MaterialIr, Node, NodeId, OpCode, Reg,
    RunContext, TintMode,
};
use glam::{Vec2, Vec3};
use std::cell::RefCell;
use std::collections::HashMap;
use std::f32::consts::TAU;

mod lanes;
mod packs;
mod uniform;

/// The lobe index [`Sample::lobe`] reports for straight transmission through `Transparent`
/// leaves.
pub const TRANSPARENCY_LOBE: u8 = u8::MAX;

/// Default of [`PrepareOptions::drop_threshold`].
pub(crate) const DEFAULT_DROP_THRESHOLD: f32 = 1e-6;

/// One shading point as the interpreter sees it. Directions are world-space unit
/// vectors.
#[derive(Debug, Clone, Copy)]
pub struct ShadingPoint<'a> {
    /// Shading normal.
    pub n: Vec3,
    /// Surface tangent (the anisotropy direction unless a lobe's frame says otherwise).
    pub t: Vec3,
    /// Direction toward the viewer.
    pub v: Vec3,
    /// External input slots, packed (see [`Material::input_layout`]); slots beyond the end
    /// take their fallbacks.
    pub inputs: &'a [f32],
    /// Surface position (the program's `P` global).
    pub p: Vec3,
    /// Surface parameters (the program's `u`, `v` globals).
    pub uv: Vec2,
}

impl<'a> ShadingPoint<'a> {
    /// A point with normal `n`, tangent `t` and view `v`; no inputs, `P = 0`, `uv = 0`.
    pub fn new(n: Vec3, t: Vec3, v: Vec3) -> ShadingPoint<'static> {
        ShadingPoint {
            n,
            t,
            v,
            inputs: &[],
            p: Vec3::ZERO,
            uv: Vec2::ZERO,
        }
    }

    /// The same point with these packed inputs.
    pub fn with_inputs<'b>(self, inputs: &'b [f32]) -> ShadingPoint<'b> {
        ShadingPoint {
            n: self.n,
            t: self.t,
            v: self.v,
            inputs,
            p: self.p,
            uv: self.uv,
        }
    }

    /// The same point with these surface parameters.
    pub fn with_uv(self, uv: Vec2) -> Self {
        ShadingPoint { uv, ..self }
    }

    /// The same point at this position.
    pub fn with_position(self, p: Vec3) -> Self {
        ShadingPoint { p, ..self }
    }
}

/// Result of [`Prepared::eval`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Eval {
    /// `Σ_k w_k ⊙ f_k(V, L)·|μ_i|` (RGB).
    pub f_cos: Rgb,
    /// Mixture density `Σ_k p_k pdf_k(L)` per unit solid angle.
    pub pdf: f32,
}

/// Result of [`Prepared::sample`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Sampled direction (world space, unit).
    pub l: Vec3,
    /// `f_cos / pdf` over the mixture (one-sample balance heuristic); for delta lobes
    /// `w_k ⊙ R_k / p_k`.
    pub weight: Rgb,
    /// Mixture density; for delta lobes the discrete probability of the choice.
    pub pdf: f32,
    /// True for a delta direction (specular, straight transmission).
    pub delta: bool,
    /// Index of the chosen lobe in [`Prepared::lobes`], or [`TRANSPARENCY_LOBE`].
    pub lobe: u8,
}

/// Directional albedo of a prepared material or lobe, split by hemisphere.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Albedo {
    /// Reflected part.
    pub reflect: Rgb,
    /// Transmitted part as energy (`η'² E_T`): a lossless interface reports
    /// `reflect + transmit = 1`.
    pub transmit: Rgb,
    /// Transmitted part in the radiance convention (what sample weights average to).
    pub transmit_radiance: Rgb,
}

impl Albedo {
    /// `reflect + transmit` (energy).
    pub fn total(&self) -> Rgb {
        self.reflect + self.transmit
    }

    fn scaled(a: &LobeAlbedo, w: Rgb) -> Albedo {
        Albedo {
            reflect: w * a.reflect,
            transmit: w * a.transmit_energy,
            transmit_radiance: w * a.transmit,
        }
    }

    fn add(&mut self, o: &Albedo) {
        self.reflect += o.reflect;
        self.transmit += o.transmit;
        self.transmit_radiance += o.transmit_radiance;
    }
}

/// Options of [`Material`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PrepareOptions {
    /// Drop lobes with `maxc(A_k)` at or below this; 0 disables dropping.
    pub drop_threshold: f32,
    /// Whether reflection lobes also respond when seen from below (transmission lobes are
    /// always two-sided).
    pub sides: Sides,
    /// Whether [`Prepared::eval`] runs same-family lobes together, one per SIMD lane (the
    /// batched path's kernels; equal to the lobe-by-lobe sum to relative 1e-5). Off, every
    /// lobe is evaluated alone with its scalar leaf.
    pub pack_lobes: bool,
}

impl Default for PrepareOptions {
    fn default() -> Self {
        PrepareOptions {
            drop_threshold: DEFAULT_DROP_THRESHOLD,
            sides: Sides::Front,
            pack_lobes: true,
        }
    }
}

/// A lobe of a prepared material: the leaf's prepared state with its weight, albedo and
/// selection probability (the leaf-level
/// [`PreparedLobe`] is the `lobe` field).
#[derive(Debug, Clone, Copy)]
pub struct ActiveLobe {
    /// The leaf with its view-only terms, in its own frame.
    pub lobe: PreparedLobe,
    /// Weight `w_k` (includes the leaf's tint), summed over all paths.
    pub weight: Rgb,
    /// `A_k = w_k ⊙ E_k(μ_o)`.
    pub albedo: Albedo,
    /// Selection probability `p_k`.
    pub prob: f32,
    /// Index of the frame in the prepared frame list.
    pub frame: u8,
    /// Index of the leaf in [`Material::leaves`].
    pub leaf: u8,
}

/// A leaf of a compiled material.
#[derive(Debug, Clone)]
pub struct LeafInfo {
    /// The closure node.
    pub node: NodeId,
    /// The leaf (kind, registers, tints, IR frame, label).
    pub leaf: Leaf,
    /// Compact frame slot (index into the prepared frames).
    frame_slot: u8,
    /// Layerable.
    layerable: bool,
    /// The lobe, when every parameter register is a constant (built and bound once at
    /// compile time).
    const_lobe: Option<BoundLobe>,
}

#[derive(Debug, Clone, Copy)]
enum CNode {
    Leaf(u8),
    Emission(Reg),
    Transparent(Reg),
    Layer { top: u32, base: u32, mode: TintMode },
    Mix { a: u32, b: u32, m: Reg },
    Add { a: u32, b: u32 },
    Multiply { f: u32, c: Reg },
}

/// A [`MaterialIr`] compiled for the interpreter (see the module documentation).
#[derive(Debug, Clone)]
pub struct Material {
    ir: MaterialIr,
    nodes: Vec<CNode>,
    /// Bit `m` set: the node's throughput in mode `m` is read by some layer.
    need: Vec<u8>,
    /// Where node `i`'s throughput in mode `m` lives in [`Scratch`] (`NO_SLOT`: never read).
    thr_slot: Vec<[u16; 4]>,
    /// The throughput pass compiled to straight-line steps, bottom-up.
    thr_ops: Vec<ThrOp>,
    leaves: Vec<LeafInfo>,
    /// The IR frames used by leaves, in compact order.
    frames: Vec<FrameSlot>,
    /// Their indices in the IR.
    frame_ids: Vec<u32>,
    /// `(offset, width)` of each input slot in the packed input slice.
    layout: Vec<(usize, usize)>,
    /// Some frame has its own normal and the program reads `ViewMu`.
    rerun_for_mu: bool,
    /// The register file when the program reads no input, global or view (computed once).
    const_regs: Option<Vec<Vec3>>,
    /// The weight pass with every register read folded in, when the registers are
    /// constant (`const_regs`) and the DAG has few enough paths.
    w_plan: Option<WeightPlan>,
    /// The lane-parallel prepare's per-leaf data, when the material qualifies
    /// ([`lanes::LanePlan`]).
    lanes: Option<lanes::LanePlan>,
    /// The fused scalar prepare's constants, when the material qualifies
    /// ([`uniform::UniformPlan`]).
    uniform: Option<uniform::UniformPlan>,
    /// Which lobes `eval` packs together in a prepare where every leaf survives and is
    /// active; known at compile time when every leaf is a constant (`None` otherwise, and
    /// the grouping is made per prepare).
    pack_grouping: Option<packs::Grouping>,
    options: PrepareOptions,
}

/// Reusable working memory of [`Material::prepare_with`] (register file and per-node
/// arrays). Sized on first use; later calls with materials of equal or smaller size do not
/// allocate.
#[derive(Debug, Default, Clone)]
pub struct Scratch {
    slots: Vec<Vec3>,
    regs: Vec<Vec3>,
    mu: Vec<f32>,
    thr: Vec<Vec3>,
    w: Vec<Vec3>,
    scope: Vec<Vec3>,
}

thread_local! {
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

fn malformed(ir: &MaterialIr, what: String) -> Error {
    Error::Input(Box::new(Diagnostic::error(
        "IR001",
        format!("material `{}`: malformed closure IR: {what}", ir.name),
    )))
}

impl Material {
    /// Compile `ir` with default options. Errors: more than `MAX_LOBES` leaves (LW010), or a
    /// structurally invalid IR (IR001: a child that does not follow its parent, a register
    /// or frame out of range) — possible only for hand-built IRs.
    pub fn new(ir: &MaterialIr) -> Result<Material, Error> {
        Material::with_options(ir, PrepareOptions::default())
    }

    /// Compile `ir` with the given options.
    pub fn with_options(ir: &MaterialIr, options: PrepareOptions) -> Result<Material, Error> {
        let n = ir.nodes.len();
        let nregs = ir.program.len();
        let reg_ok = |r: Reg| r.index() < nregs;
        let mut nodes = Vec::with_capacity(n);
        let mut leaves: Vec<LeafInfo> = Vec::new();
        let mut frames: Vec<FrameSlot> = Vec::new();
        let mut frame_ids: Vec<u32> = Vec::new();
        let kappa_zero = |r: Reg| ir.program.constant(r) == Some(Vec3::ZERO);
        for (i, node) in ir.nodes.iter().enumerate() {
            for c in node.children() {
                if c.index() <= i || c.index() >= n {
                    return Err(malformed(ir, format!("node {i} has child {}", c.0)));
                }
            }
            if let Some(r) = node.regs().into_iter().find(|r| !reg_ok(*r)) {
                return Err(malformed(ir, format!("node {i} reads register {}", r.0)));
            }
            let ch = |id: NodeId| id.0;
            nodes.push(match node {
                Node::Leaf(leaf) => {
                    if leaves.len() >= MAX_LOBES {
                        return Err(Error::Input(Box::new(Diagnostic::error(
                            "LW010",
                            format!(
                                "material `{}` has more than {MAX_LOBES} BSDF lobes",
                                ir.name
                            ),
                        ))));
                    }
                    let slot = ir.frames.get(leaf.frame as usize).ok_or_else(|| {
                        malformed(ir, format!("leaf {i} uses frame {}", leaf.frame))
                    })?;
                    let fs = match frame_ids.iter().position(|&f| f == leaf.frame) {
                        Some(k) => k,
                        None => {
                            frame_ids.push(leaf.frame);
                            frames.push(*slot);
                            frames.len() - 1
                        }
                    };
                    let consts: Option<Vec<(Reg, Vec3)>> = leaf
                        .kind
                        .params()
                        .into_iter()
                        .map(|(_, r)| ir.program.constant(r).map(|c| (r, c)))
                        .collect();
                    let const_lobe = consts.map(|c| {
                        let mut regs = vec![Vec3::ZERO; nregs];
                        for (r, v) in c {
                            regs[r.index()] = v;
                        }
                        leaf_lobe(&leaf.kind, &regs).bind()
                    });
                    leaves.push(LeafInfo {
                        node: NodeId(i as u32),
                        leaf: leaf.clone(),
                        frame_slot: fs as u8,
                        layerable: leaf.kind.is_layerable(kappa_zero),
                        const_lobe,
                    });
                    CNode::Leaf((leaves.len() - 1) as u8)
                }
                Node::Emission { radiance } => CNode::Emission(*radiance),
                Node::Transparent { tint } => CNode::Transparent(*tint),
                Node::Layer { top, base, mode } => CNode::Layer {
                    top: ch(*top),
                    base: ch(*base),
                    mode: *mode,
                },
                Node::Mix { a, b, m } => CNode::Mix {
                    a: ch(*a),
                    b: ch(*b),
                    m: *m,
                },
                Node::Add { a, b } => CNode::Add {
                    a: ch(*a),
                    b: ch(*b),
                },
                Node::Multiply { f, c } => CNode::Multiply { f: ch(*f), c: *c },
            });
        }
        for f in &ir.frames {
            for r in [f.normal, f.tangent, f.rotation].into_iter().flatten() {
                if !reg_ok(r) {
                    return Err(malformed(ir, format!("a frame reads register {}", r.0)));
                }
            }
        }
        for (k, op) in ir.program.ops.iter().enumerate() {
            if op.operands().any(|r| r.index() >= k) {
                return Err(malformed(ir, format!("op {k} reads a later register")));
            }
        }
        let need = mode_needs(&nodes);
        let (thr_slot, thr_ops) = compile_throughput(&nodes, &need);
        let mut layout = Vec::with_capacity(ir.inputs.len());
        let mut off = 0;
        for s in &ir.inputs {
            let w = if s.ty.base.is_triple() { 3 } else { 1 };
            layout.push((off, w));
            off += w;
        }
        let rerun_for_mu = frames.iter().any(|f| f.normal.is_some())
            && ir.program.ops.iter().any(|op| op.code == OpCode::ViewMu);
        let const_regs = ir.program.ops.iter().all(|op| op.code.is_pure()).then(|| {
            ir.program.run(&RunContext {
                inputs: &[],
                mu_o: &[],
                globals: Globals::default(),
            })
        });
        let w_plan = const_regs
            .as_deref()
            .and_then(|regs| compile_weights(&nodes, &leaves, &thr_slot, regs));
        let pack_grouping = static_grouping(&leaves, options.sides);
        let mut m = Material {
            w_plan,
            pack_grouping,
            lanes: None,
            uniform: None,
            const_regs,
            ir: ir.clone(),
            nodes,
            need,
            thr_slot,
            thr_ops,
            leaves,
            frames,
            frame_ids,
            layout,
            rerun_for_mu,
            options,
        };
        m.lanes = lanes::LanePlan::new(&m);
        m.uniform = uniform::UniformPlan::new(&m);
        Ok(m)
    }

    /// The IR this material was compiled from.
    pub fn ir(&self) -> &MaterialIr {
        &self.ir
    }

    /// The material's name.
    pub fn name(&self) -> &str {
        &self.ir.name
    }

    /// True when the program reads no input, global or view: every point and view gets
    /// the same parameters (the program ran once, at compile time), so callers may leave
    /// [`ShadingPoint`]'s inputs, position and `uv` unset.
    pub fn is_uniform(&self) -> bool {
        self.const_regs.is_some()
    }

    /// True when the material qualifies for the uniform-material prepare that
    /// [`Material::prepare_batch_eval_into`] runs lane-parallel: constant registers, one
    /// frame (the point's), a batched kernel for every leaf. (A batch with a view at or
    /// below some lane's horizon still takes the general path.)
    pub fn prepares_lanes(&self) -> bool {
        self.lanes.is_some()
    }

    /// True when [`Material::prepare`] and its variants prepare a point seen from above its
    /// surface by the fused form of the steps for uniform materials (every material that
    /// [`Material::prepares_lanes`], unless its closure DAG needs more working slots than
    /// the fused form keeps on the stack). The results are those of
    /// [`Material::prepare_general_into`], bit for bit.
    pub fn prepares_uniform(&self) -> bool {
        self.uniform.is_some()
    }

    /// The options.
    pub fn options(&self) -> PrepareOptions {
        self.options
    }

    /// The BSDF leaves in node order ([`ActiveLobe::leaf`] indexes this).
    pub fn leaves(&self) -> &[LeafInfo] {
        &self.leaves
    }

    /// `(offset, width)` of each input slot in the packed input slice (width 3 for colours,
    /// vectors, normals and points, else 1).
    pub fn input_layout(&self) -> &[(usize, usize)] {
        &self.layout
    }

    /// Length of a fully packed input slice.
    pub fn input_len(&self) -> usize {
        self.layout.last().map_or(0, |&(o, w)| o + w)
    }

    /// Every slot's fallback, packed.
    pub fn fallback_inputs(&self) -> Vec<f32> {
        let mut out = vec![0.0; self.input_len()];
        for (slot, &(o, w)) in self.ir.inputs.iter().zip(&self.layout) {
            let v = slot.fallback_vec();
            out[o..o + w].copy_from_slice(&v.to_array()[..w]);
        }
        out
    }

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
    /// Runs the version compiled for [`SCALAR_LEVEL`] when the CPU has it (see
    /// [`super::simd`]); every version computes the same bits.
    pub fn prepare_into(&self, p: &ShadingPoint, s: &mut Scratch, out: &mut Prepared) {
        self.prepare_into_at(SCALAR_LEVEL, p, s, out);
    }

    /// [`Material::prepare_into`] compiled for at most `level` (for tests and benchmarks:
    /// every level gives the same bits).
    pub fn prepare_into_at(
        &self,
        level: Level,
        p: &ShadingPoint,
        s: &mut Scratch,
        out: &mut Prepared,
    ) {
        self.prepare_at(level, true, p, s, out);
    }

    /// The steps into `out`, then `eval`'s lobe packs when `packs` (and the options ask
    /// for them), in the version compiled for at most `level`: the body of
    /// [`Material::prepare_into_at`] and [`Material::prepare_unpacked_into_at`].
    fn prepare_at(
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
    fn prepare_body(&self, packs: bool, p: &ShadingPoint, s: &mut Scratch, out: &mut Prepared) {
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

    /// All seven prepare steps into `out`: [`Material::prepare_into`] without planning `eval`'s
    /// lobe packs, whatever [`PrepareOptions::pack_lobes`] says, so every lobe is evaluated
    /// alone. For callers that evaluate once per prepare (the material preview), where
    /// filling the packs costs more than it saves, and for the batched path, which reads
    /// the lobes and never a lane's own `eval`; the results are the same to relative 1e-5.
    ///
    /// A uniform material ([`Material::prepares_uniform`]) seen from above its surface is
    /// prepared by a fused form of the steps, over fixed arrays with its constants folded
    /// in; it computes the same bits as [`Material::prepare_general_into`].
    pub fn prepare_unpacked_into(&self, p: &ShadingPoint, s: &mut Scratch, out: &mut Prepared) {
        self.prepare_unpacked_into_at(SCALAR_LEVEL, p, s, out);
    }

    /// [`Material::prepare_unpacked_into`] compiled for at most `level` (every level gives
    /// the same bits).
    pub fn prepare_unpacked_into_at(
        &self,
        level: Level,
        p: &ShadingPoint,
        s: &mut Scratch,
        out: &mut Prepared,
    ) {
        self.prepare_at(level, false, p, s, out);
    }

    /// [`Material::prepare_unpacked_into`], returning the uniform plan's stamp when the
    /// fused form prepared the point.
    #[inline(always)]
    fn prepare_steps(&self, p: &ShadingPoint, s: &mut Scratch, out: &mut Prepared) -> Option<u64> {
        if let Some(plan) = &self.uniform
            && self.prepare_uniform_into(plan, p, out)
        {
            return Some(plan.stamp);
        }
        self.prepare_general_into(p, s, out);
        None
    }

    /// [`Material::prepare_unpacked_into`] by the general algorithm, whatever the material:
    /// the program, frames from registers, and the throughput and weight passes over
    /// [`Scratch`]'s per-node arrays. For comparisons and tests; the results are the same.
    pub fn prepare_general_into(&self, p: &ShadingPoint, s: &mut Scratch, out: &mut Prepared) {
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

    fn regs<'s>(&'s self, s: &'s Scratch) -> &'s [Vec3] {
        self.const_regs.as_deref().unwrap_or(&s.regs)
    }

    fn globals(&self, p: &ShadingPoint, v: Vec3) -> Globals {
        Globals {
            p: p.p,
            n: p.n,
            t: p.t,
            i: v,
            u: p.uv.x,
            v: p.uv.y,
        }
    }

    fn unpack_inputs(&self, packed: &[f32], slots: &mut Vec<Vec3>) {
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

    fn run(&self, s: &mut Scratch, globals: Globals) {
        let ctx = RunContext {
            inputs: &s.slots,
            mu_o: &s.mu,
            globals,
        };
        self.ir.program.run_into(&ctx, &mut s.regs);
    }

    fn build_frames(&self, p: &ShadingPoint, regs: &[Vec3], out: &mut Prepared) {
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
    fn prepare_leaf(&self, info: &LeafInfo, regs: &[Vec3], v: Vec3, out: &mut PreparedLobe) {
        match &info.const_lobe {
            Some(lobe) => lobe.prepare_into(v, self.options.sides, out),
            None => *out = leaf_lobe(&info.leaf.kind, regs).prepare(v, self.options.sides),
        }
    }

    fn throughput(
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

    fn weights(&self, s: &mut Scratch, weights: &mut [Vec3; MAX_LOBES], out: &mut Prepared) {
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
}

impl Material {
    /// [`Material::weights`] for constant registers, from the compiled terms of
    /// [`compile_weights`]: each target's weight is its terms' sum, cleaned once, as the
    /// general pass does with the sum over a node's parents.
    fn weights_planned(
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
struct WeightPlan {
    terms: Vec<WTerm>,
    /// Scope `i + 1` = scope `parent` × `thr[slot]`; scope 0 is 1. Parents come first.
    scopes: Vec<(u32, u16)>,
    /// Leaves, emission and transparency nodes, each with its own accumulator.
    targets: Vec<Target>,
    /// Every leaf weight is finite and non-negative at every point, whatever the albedos
    /// ([`weights_are_clean`]): [`clean`] of it is the identity, and the fused and
    /// lane-parallel prepares skip it.
    weights_clean: bool,
}

/// One path of a [`WeightPlan`]: `c ⊙ scope` added to a target.
#[derive(Debug, Clone, Copy)]
struct WTerm {
    c: Vec3,
    /// The path's scope (its product of throughputs).
    scope: u32,
    /// Index into [`WeightPlan::targets`].
    target: u32,
}

/// What a [`WeightPlan`] term's weight goes to.
#[derive(Debug, Clone, Copy)]
enum Target {
    /// `weights[leaf] = clean(tint ⊙ Σ)`.
    Leaf { leaf: u8, tint: Vec3 },
    /// `emission += clean(Σ ⊙ radiance)`.
    Emission(Vec3),
    /// `transparency += clean(Σ ⊙ tint)`.
    Transparent(Vec3),
}

/// Above this many paths a material keeps the general weight pass (a DAG that shares
/// nodes can have exponentially many).
const MAX_WEIGHT_TERMS: usize = 256;

/// Compile the weight pass for constant registers `regs` ([`WeightPlan`]); `None` when the
/// DAG has more than [`MAX_WEIGHT_TERMS`] paths. Paths through a zero `mix` or `mul`
/// factor are left out (they carry no weight).
fn compile_weights(
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
fn weights_are_clean(w_plan: &WeightPlan) -> bool {
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

impl MaterialIr {
    /// Compile this IR for the interpreter ([`Material::new`]).
    pub fn compile(&self) -> Result<Material, Error> {
        Material::new(self)
    }
}

/// Which tint modes each node's throughput is read in (bit `m` = [`TintMode`] `m`): a
/// layer's top is read in the layer's mode; every other child inherits its parent's set
/// (a layer's base inherits the layer's own set).
fn mode_needs(nodes: &[CNode]) -> Vec<u8> {
    let mut need = vec![0u8; nodes.len()];
    for i in 0..nodes.len() {
        let ni = need[i];
        match nodes[i] {
            CNode::Layer { top, base, mode } => {
                need[top as usize] |= 1 << (mode as u8);
                need[base as usize] |= ni;
            }
            CNode::Mix { a, b, .. } | CNode::Add { a, b } => {
                need[a as usize] |= ni;
                need[b as usize] |= ni;
            }
            CNode::Multiply { f, .. } => need[f as usize] |= ni,
            CNode::Leaf(_) | CNode::Emission(_) | CNode::Transparent(_) => {}
        }
    }
    need
}

/// One step of the compiled throughput pass: step `i` writes slot `i` from slots written
/// before it (bottom-up) and registers.
#[derive(Debug, Clone, Copy)]
enum ThrOp {
    /// A leaf's throughput in `mode` (0 for leaves that are not layerable or not prepared).
    Leaf { leaf: u8, mode: TintMode },
    /// Emission and transparency pass everything.
    One,
    /// `T_top(layer mode) · T_base(m)`.
    Layer { top: u16, base: u16 },
    /// `(1 − m) T_a + m T_b`.
    Mix { a: u16, b: u16, m: Reg },
    /// `max(T_a + T_b − 1, 0)`.
    Add { a: u16, b: u16 },
    /// `sat(1 − c (1 − T_f))`.
    Multiply { f: u16, c: Reg },
}

/// Marks a (node, mode) throughput that is never read.
const NO_SLOT: u16 = u16::MAX;

/// Compile the throughput pass: one slot and one step per (node, mode) pair that some layer
/// reads (`need`), ordered children first. Returns the slot table and the steps.
fn compile_throughput(nodes: &[CNode], need: &[u8]) -> (Vec<[u16; 4]>, Vec<ThrOp>) {
    let mut slot = vec![[NO_SLOT; 4]; nodes.len()];
    let mut ops = Vec::new();
    for i in (0..nodes.len()).rev() {
        for m in TintMode::ALL {
            if need[i] & (1 << (m as u8)) == 0 {
                continue;
            }
            let at = |j: u32, mode: TintMode| slot[j as usize][mode as usize];
            let op = match nodes[i] {
                CNode::Leaf(leaf) => ThrOp::Leaf { leaf, mode: m },
                CNode::Emission(_) | CNode::Transparent(_) => ThrOp::One,
                CNode::Layer { top, base, mode } => ThrOp::Layer {
                    top: at(top, mode),
                    base: at(base, m),
                },
                CNode::Mix { a, b, m: r } => ThrOp::Mix {
                    a: at(a, m),
                    b: at(b, m),
                    m: r,
                },
                CNode::Add { a, b } => ThrOp::Add {
                    a: at(a, m),
                    b: at(b, m),
                },
                CNode::Multiply { f, c } => ThrOp::Multiply { f: at(f, m), c },
            };
            slot[i][m as usize] = ops.len() as u16;
            ops.push(op);
        }
    }
    (slot, ops)
}

/// The lobe packs of a material whose leaves are all constants, for the prepare where
/// every leaf survives and is active (`None` when some leaf reads a register that is not a
/// constant: its kernel key may then vary by point). A constant leaf's key does not depend
/// on the view, so preparing it at the normal gives the key of every active prepare.
fn static_grouping(leaves: &[LeafInfo], sides: Sides) -> Option<packs::Grouping> {
    let mut keys = [None; MAX_LOBES];
    for (key, info) in keys.iter_mut().zip(leaves) {
        let lobe = info.const_lobe.as_ref()?.prepare(Vec3::Z, sides);
        *key = crate::interp::soa::kernel_key(&lobe.state);
    }
    Some(packs::Grouping::of_keys(&keys[..leaves.len()]))
}

fn sat(v: Vec3) -> Vec3 {
    v.clamp(Vec3::ZERO, Vec3::ONE)
}

/// Non-negative and finite (NaN and infinities become 0).
#[inline]
fn clean(v: Vec3) -> Vec3 {
    // A bit mask per channel, no branch. `x − x` is 0 exactly for finite x (NaN for ±∞ and
    // NaN); written as `x < ∞`, LLVM turns the test into integer classification code.
    #[allow(clippy::eq_op)] // `x − x` is the finiteness test (see above), not a slip
    let c = |x: f32| {
        let keep = (x > 0.0) & (x - x == 0.0);
        f32::from_bits(x.to_bits() & u32::from(keep).wrapping_neg())
    };
    Vec3::new(c(v.x), c(v.y), c(v.z))
}

/// The concrete lobe of an IR leaf with its parameter registers evaluated (`regs` is the
/// program's register file; missing registers read 0). Scalars read the first channel.
pub(crate) fn leaf_lobe(kind: &LeafKind, regs: &[Vec3]) -> Lobe {
    let r = |reg: Reg| regs.get(reg.index()).copied().unwrap_or(Vec3::ZERO);
    let x = |reg: Reg| r(reg).x;
    match *kind {
        LeafKind::Lambert { albedo } => Lobe::Lambert(Lambert { rho: r(albedo) }),
        LeafKind::Translucent { albedo } => Lobe::Translucent(Lambert { rho: r(albedo) }),
        LeafKind::SubsurfaceProxy { albedo } => Lobe::SubsurfaceProxy(Lambert { rho: r(albedo) }),
        LeafKind::OrenNayarQ { albedo, sigma } => Lobe::OrenNayar(OrenNayar {
            rho: r(albedo),
            sigma: x(sigma),
            variant: OrenNayarVariant::Qualitative,
        }),
        LeafKind::OrenNayarE { albedo, sigma } => Lobe::OrenNayar(OrenNayar {
            rho: r(albedo),
            sigma: x(sigma),
            variant: OrenNayarVariant::Energy,
        }),
        LeafKind::MiaDiffuse { albedo, sigma } => Lobe::MiaDiffuse(MiaDiffuse {
            rho: r(albedo),
            sigma: x(sigma),
        }),
        LeafKind::Burley { albedo, sigma } => Lobe::Burley(Burley {
            rho: r(albedo),
            sigma: x(sigma),
        }),
        LeafKind::MicrofacetR {
            alpha_x,
            alpha_y,
            fresnel,
            masking,
            comp,
        } => {
            let fresnel = match fresnel {
                Fresnel::One => LobeFresnel::One,
                Fresnel::Schlick { f0, f90, q } => LobeFresnel::Schlick {
                    f0: r(f0),
                    f90: r(f90),
                    q: x(q),
                },
                Fresnel::F82 { f0, f90, q, t } => LobeFresnel::f82(r(f0), r(f90), x(q), r(t)),
                Fresnel::Dielectric { eta } => LobeFresnel::Dielectric { eta: x(eta) },
                Fresnel::Conductor { eta, kappa } => LobeFresnel::Conductor {
                    eta: r(eta),
                    kappa: r(kappa),
                },
            };
            let k = x(comp);
            Lobe::MicrofacetR(MicrofacetR {
                ggx: Ggx::new(x(alpha_x), x(alpha_y)),
                masking,
                fresnel,
                comp: if k > 0.0 {
                    Compensation::Turquin(k.min(1.0))
                } else {
                    Compensation::None
                },
            })
        }
        LeafKind::Dielectric {
            alpha_x,
            alpha_y,
            eta,
            mode,
            refl_tint,
            trans_tint,
            t_fresnel,
            masking,
        } => Lobe::Dielectric(Dielectric {
            ggx: Ggx::new(x(alpha_x), x(alpha_y)),
            masking,
            eta: x(eta),
            mode,
            tint_r: r(refl_tint),
            tint_t: r(trans_tint),
            t_fresnel,
            turquin: 0.0,
        }),
        LeafKind::Ward {
            alpha_x,
            alpha_y,
            rho_s,
            variant,
        } => Lobe::Ward(Ward {
            ax: x(alpha_x),
            ay: x(alpha_y),
            rho: r(rho_s),
            variant,
        }),
        LeafKind::MiaHighlight3 {
            glossiness,
            anisotropy,
            variant,
        } => Lobe::MiaHighlight3(MiaHighlight3 {
            glossiness: x(glossiness),
            anisotropy: x(anisotropy),
            variant,
        }),
        LeafKind::SheenCk { roughness, masking } => Lobe::SheenCK(SheenCK {
            r: x(roughness),
            masking,
        }),
        LeafKind::SheenLtc { roughness } => Lobe::SheenLTC(SheenLTC { r: x(roughness) }),
    }
}

/// An [`AlbedoSource`] backed by the interpreter's leaves and tables: the leaf's
/// prepared albedo at a view with cosine `μ_o` (reflection plus transmission as energy),
/// without its tint. Use it wherever the closure algebra needs real `E_k(μ_o)`.
#[derive(Debug, Clone, Copy, Default)]
pub struct TableAlbedo;

impl AlbedoSource for TableAlbedo {
    fn albedo(&self, leaf: &Leaf, regs: &[Vec3], mu_o: f32) -> Vec3 {
        let mu = mu_o.clamp(-1.0, 1.0);
        let v = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
        // Bound, as a compiled material binds a constant leaf: an anisotropic lobe's Fresnel
        // ratios are then the baked ones the compiled material reads.
        let a = leaf_lobe(&leaf.kind, regs)
            .bind()
            .prepare(v, Sides::Front)
            .albedo();
        a.reflect + a.transmit_energy
    }
}

/// A material prepared for one point and view: at most `MAX_LOBES` weighted lobes,
/// their frames, emission and transparency. Plain data; `eval` and `sample` do not allocate.
#[derive(Debug, Clone, Copy)]
pub struct Prepared {
    pub(super) lobes: [ActiveLobe; MAX_LOBES],
    pub(super) count: usize,
    pub(super) frames: [Frame; MAX_LOBES],
    pub(super) frame_count: usize,
    /// Some lobe is flipped (seen from below): `eval` then flips per lobe.
    flipped_any: bool,
    v: Vec3,
    emission: Rgb,
    transparency: Rgb,
    /// Probability of choosing straight transmission in `sample`.
    p_transparency: f32,
    /// Which lobes `eval` runs alone and which in packs.
    plan: packs::EvalPlan,
    /// The [`uniform::UniformPlan::stamp`] of the material whose fused prepare wrote
    /// `lobes` last with every leaf surviving (lobe `k` is leaf `k`, none flipped); 0 when
    /// the records may hold anything else. The next fused prepare of that material then
    /// writes only the records' view-dependent fields.
    stamp: u64,
}

impl Default for Prepared {
    fn default() -> Self {
        Prepared::new()
    }
}

impl Prepared {
    pub(super) fn empty(v: Vec3) -> Prepared {
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
    pub(super) fn reset(&mut self, v: Vec3) {
        self.count = 0;
        self.frame_count = 0;
        self.flipped_any = false;
        self.v = v;
        self.emission = Vec3::ZERO;
        self.transparency = Vec3::ZERO;
        self.p_transparency = 0.0;
        self.plan.clear();
    }

    /// An empty preparation (no lobes), e.g. as the target of [`Material::prepare_into`].
    pub fn new() -> Prepared {
        Prepared::empty(Vec3::Z)
    }

    /// Step 6's survivor: leaf `k`'s record (prepared at index `k`) becomes lobe `at ≤ k`
    /// with its weight, albedo and frame. Returns step 7's share, `max(lum(A_k), 0)` with
    /// transmission in the radiance convention.
    #[inline(always)]
    fn keep(&mut self, at: usize, k: usize, weight: Rgb, albedo: Albedo, frame: u8) -> f32 {
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
    fn select(&mut self, lums: &[f32; MAX_LOBES]) {
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
    fn select_by_weight(&mut self) {
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
    fn absorb(&mut self) {
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
    /// lobes of one family side by side, see [`PrepareOptions::pack_lobes`]); the others
    /// are evaluated one by one. For inspection and tests.
    pub fn packed_lobe_count(&self) -> usize {
        self.count - self.plan.solo(self.count).len()
    }

    /// `Σ_k w_k ⊙ f_k(V, L)·|μ_i|` and the mixture pdf at world direction `l`. Delta lobes
    /// contribute nothing.
    ///
    /// Runs the version compiled for [`SCALAR_LEVEL`] when the CPU has it (see
    /// [`super::simd`]); every version computes the same bits.
    #[inline]
    pub fn eval(&self, l: Vec3) -> Eval {
        self.eval_at(SCALAR_LEVEL, l)
    }

    /// [`Prepared::eval`] compiled for at most `level` (every level gives the same bits).
    #[inline]
    pub fn eval_at(&self, level: Level, l: Vec3) -> Eval {
        call_widest!(level, self.eval_body(l), eval_avx512, eval_avx2)
    }

    widest_versions!(eval_body(l: Vec3) -> Eval, eval_avx512, eval_avx2);

    #[inline(always)]
    fn eval_body(&self, l: Vec3) -> Eval {
        self.eval_with::<true>(l)
    }

    /// [`Prepared::eval`]'s `f_cos` alone, for callers that need no density (the material
    /// preview): the lobes' pdf arithmetic is left out. Runs at [`SCALAR_LEVEL`] as `eval`
    /// does.
    #[inline]
    pub fn eval_f_cos(&self, l: Vec3) -> Rgb {
        self.eval_f_cos_at(SCALAR_LEVEL, l)
    }

    /// [`Prepared::eval_f_cos`] compiled for at most `level` (every level gives the same
    /// bits).
    #[inline]
    pub fn eval_f_cos_at(&self, level: Level, l: Vec3) -> Rgb {
        call_widest!(
            level,
            self.f_cos_body(l),
            eval_f_cos_avx512,
            eval_f_cos_avx2
        )
    }

    widest_versions!(f_cos_body(l: Vec3) -> Rgb, eval_f_cos_avx512, eval_f_cos_avx2);

    #[inline(always)]
    fn f_cos_body(&self, l: Vec3) -> Rgb {
        self.eval_with::<false>(l).f_cos
    }

    /// [`Prepared::eval`], with the mixture pdf only when `PDF` (else 0): every leaf eval is
    /// inlined here, so the compiler drops what is not summed.
    #[inline(always)]
    fn eval_with<const PDF: bool>(&self, l: Vec3) -> Eval {
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

    fn sample_transparency(&self) -> Option<Sample> {
        let p = self.p_transparency;
        Some(Sample {
            l: -self.v,
            weight: self.transparency / p,
            pdf: p,
            delta: true,
            lobe: TRANSPARENCY_LOBE,
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
const ONE_MINUS_EPS: f32 = 1.0 - f32::EPSILON / 2.0;
