//! The compile step: a [`MaterialIr`] checked and flattened into a [`Material`] (closure
//! nodes with plain child indices, leaves with compact frame slots, the throughput pass as
//! straight-line steps, and the plans of the fast prepares).

use super::form::{CNode, LanePlan, LeafInfo, Material, ThrOp, UniformPlan};
use super::leaf::leaf_lobe;
use super::packs::Grouping;
use super::plan::compile_weights;
use super::record::PrepareOptions;
use crate::diag::{Diagnostic, Error};
use crate::interp::lobe::Sides;
use crate::ir::{
    FrameSlot, Globals, MAX_LOBES, MaterialIr, Node, NodeId, OpCode, Reg, RunContext, TintMode,
};
use glam::Vec3;

pub(super) fn malformed(ir: &MaterialIr, what: String) -> Error {
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
        m.lanes = LanePlan::new(&m);
        m.uniform = UniformPlan::new(&m);
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
    /// [`ShadingPoint`](super::ShadingPoint)'s inputs, position and `uv` unset.
    pub fn is_uniform(&self) -> bool {
        self.const_regs.is_some()
    }

    testkit_pub! {
        /// True when the material qualifies for the uniform-material prepare that
        /// [`Material::prepare_batch_eval_into`] runs lane-parallel: constant registers, one
        /// frame (the point's), a batched kernel for every leaf. (A batch with a view at or
        /// below some lane's horizon still takes the general path.)
        fn prepares_lanes(&self) -> bool {
            self.lanes.is_some()
        }
    }

    /// True when [`Material::prepare`] and its variants prepare a point seen from above its
    /// surface by the fused form of the steps for uniform materials (every material that
    /// [`Material::prepares_lanes`], unless its closure DAG needs more working slots than
    /// the fused form keeps on the stack). The results are those of
    /// [`Material::prepare_general_into`], bit for bit.
    #[cfg(feature = "testkit")]
    pub fn prepares_uniform(&self) -> bool {
        self.uniform.is_some()
    }

    /// The options.
    pub fn options(&self) -> PrepareOptions {
        self.options
    }

    /// The BSDF leaves in node order ([`ActiveLobe::leaf`](super::ActiveLobe::leaf) indexes this).
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
pub(super) fn mode_needs(nodes: &[CNode]) -> Vec<u8> {
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

/// Marks a (node, mode) throughput that is never read.
pub(super) const NO_SLOT: u16 = u16::MAX;

/// Compile the throughput pass: one slot and one step per (node, mode) pair that some layer
/// reads (`need`), ordered children first. Returns the slot table and the steps.
pub(super) fn compile_throughput(nodes: &[CNode], need: &[u8]) -> (Vec<[u16; 4]>, Vec<ThrOp>) {
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
pub(super) fn static_grouping(leaves: &[LeafInfo], sides: Sides) -> Option<Grouping> {
    let mut keys = [None; MAX_LOBES];
    for (key, info) in keys.iter_mut().zip(leaves) {
        let lobe = info.const_lobe.as_ref()?.prepare(Vec3::Z, sides);
        *key = crate::interp::soa::kernel_key(&lobe.state);
    }
    Some(Grouping::of_keys(&keys[..leaves.len()]))
}
