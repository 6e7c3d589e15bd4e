//! The closure IR: a parameter program (straight-line SSA
//! over `f32x3` registers) and a closure DAG ([`closure`]) whose leaves are BSDF
//! lobes. Internally, the closure algebra computes the flat form (lobes with weights) for one
//! point and view and passes optimise; [`MaterialIr::text`] and [`MaterialIr::lobes_text`] render the stable text forms.
//!
//! Lowering builds IRs with a builder that folds constants, shares identical ops and nodes,
//! and drops closures that are statically zero while it builds (so lowering code can build
//! the full tree of a recipe and let disabled parts vanish).

pub mod closure;
pub(crate) mod print;

// The parameter program, the flat form and the passes are internals: public only to the
// crate's own tests and benches (feature `testkit`).
testkit_mods!(algebra, passes, program);

#[cfg(not(feature = "testkit"))]
pub(crate) use algebra::{AlbedoSource, Flat};
#[cfg(feature = "testkit")]
pub use algebra::{AlbedoSource, Flat, FlatLobe, SimpleAlbedo};
pub use closure::{
    DielectricMode, Fresnel, Leaf, LeafKind, Masking, Node, NodeId, SheenMasking, TintMode,
    WardVariant,
};
#[cfg(feature = "testkit")]
pub use program::{Global, Globals, Op, OpCode, Program, ProgramBuilder, Reg, RunContext};
#[cfg(not(feature = "testkit"))]
pub(crate) use program::{Global, Globals, OpCode, Program, ProgramBuilder, Reg, RunContext};

use crate::types::{Type, Value};
use glam::Vec3;
use rustc_hash::FxHashMap as HashMap;

/// Maximum number of BSDF lobes of one material. `Emission` and `Transparent` leaves
/// do not count; the mia three-Ward highlight counts as one.
pub const MAX_LOBES: usize = 16;

/// Which lowering recipe produced an IR.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RecipeId {
    /// PxrSurface / PxrLayerSurface.
    PxrSurface,
    /// VRayMtl.
    VRayMtl,
    /// 3ds Max Physical Material.
    PhysicalMaterial,
    /// mia_material.
    MiaMaterial,
    /// Built by hand (tests, API users).
    Custom,
}

impl RecipeId {
    /// Name used by the printers.
    pub fn name(self) -> &'static str {
        match self {
            RecipeId::PxrSurface => "pxr_surface",
            RecipeId::VRayMtl => "vray_mtl",
            RecipeId::PhysicalMaterial => "physical_material",
            RecipeId::MiaMaterial => "mia_material",
            RecipeId::Custom => "custom",
        }
    }
}

/// An external per-point value: the output of a pattern the lowering does not
/// interpret.
#[derive(Debug, Clone, PartialEq)]
pub struct InputSlot {
    /// Slot name (`node.output`).
    pub name: String,
    /// Type of the downstream parameter.
    pub ty: Type,
    /// Used when the caller supplies no value: the downstream parameter's value.
    pub fallback: Value,
    /// Where the value comes from (`node.output`).
    pub origin: String,
}

impl InputSlot {
    /// The fallback as a register value (scalars broadcast).
    pub fn fallback_vec(&self) -> Vec3 {
        value_to_vec3(&self.fallback)
    }
}

/// A value as a register: scalars broadcast, triples as they are, anything else 0.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) fn value_to_vec3(v: &Value) -> Vec3 {
    // The common scalar and triple cases without collecting the numbers.
    match v {
        Value::Int(i) => return Vec3::splat(*i as f32),
        Value::Float(x) => return Vec3::splat(*x),
        Value::Bool(b) => return Vec3::splat(if *b { 1.0 } else { 0.0 }),
        Value::Triple(_, c) => return Vec3::from_array(*c),
        _ => {}
    }
    let n = v.numbers();
    match n.len() {
        0 => Vec3::ZERO,
        1 | 2 => Vec3::splat(n[0]),
        _ => Vec3::new(n[0], n[1], n[2]),
    }
}

/// A shading frame used by lobes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) struct FrameSlot {
    /// Normal register; `None` (or a zero value) means the shading normal.
    pub normal: Option<Reg>,
    /// Tangent register; `None` (or a zero value) means the surface tangent.
    pub tangent: Option<Reg>,
    /// Rotation of the tangent about the normal, in turns.
    pub rotation: Option<Reg>,
}

/// A material lowered to the closure IR.
#[derive(Debug, Clone, PartialEq)]
pub struct MaterialIr {
    /// Material (or terminal node) name.
    pub name: String,
    /// The recipe that produced it.
    pub recipe: RecipeId,
    /// External per-point inputs.
    pub inputs: Vec<InputSlot>,
    /// The parameter program.
    #[cfg(feature = "testkit")]
    pub program: Program,
    #[cfg(not(feature = "testkit"))]
    pub(crate) program: Program,
    /// The closure DAG; node 0 is the root and every child has a larger index than its
    /// parents. Empty when the material has no closure at all (black).
    pub nodes: Vec<Node>,
    /// Frames used by lobes.
    #[cfg(feature = "testkit")]
    pub frames: Vec<FrameSlot>,
    #[cfg(not(feature = "testkit"))]
    pub(crate) frames: Vec<FrameSlot>,
    /// Number of BSDF lobes (≤ [`MAX_LOBES`]).
    pub max_static_lobes: u8,
}

impl MaterialIr {
    /// The IR as text: inputs, the closure tree and the weight program (what `compile
    /// --emit ir` prints).
    pub fn text(&self) -> String {
        print::ir_text(self)
    }

    /// The flat lobe list as text (what `compile --emit lobes` prints): each lobe with its
    /// symbolic weight, then numeric weights at `μ_o = 1` and `0.5` with the inputs'
    /// fallbacks and the leaves' albedos from `albedo`.
    pub fn lobes_text(&self, albedo: &dyn AlbedoSource) -> String {
        print::lobes_text(self, albedo)
    }

    /// The fallback value of every input slot.
    pub fn fallback_inputs(&self) -> Vec<Vec3> {
        self.inputs.iter().map(InputSlot::fallback_vec).collect()
    }

    /// Index of the input slot with this name.
    pub fn input_index(&self, name: &str) -> Option<usize> {
        self.inputs.iter().position(|s| s.name == name)
    }

    /// Run the program with the given slot values (fallbacks where `None`), every frame
    /// seeing `μ_o = mu_o`.
    pub fn run_program(&self, inputs: Option<&[Vec3]>, mu_o: f32) -> Vec<Vec3> {
        let fallback;
        let inputs = match inputs {
            Some(i) => i,
            None => {
                fallback = self.fallback_inputs();
                &fallback
            }
        };
        let mu = vec![mu_o; self.frames.len().max(1)];
        self.program.run(&RunContext {
            inputs,
            mu_o: &mu,
            globals: Globals::default(),
        })
    }

    /// Weights of the flat form for one point: run the program, then the throughput and
    /// weight passes with `albedo` supplying each layered leaf's `E(μ_o)`.
    pub fn weights(&self, inputs: Option<&[Vec3]>, mu_o: f32, albedo: &dyn AlbedoSource) -> Flat {
        let regs = self.run_program(inputs, mu_o);
        let mu = vec![mu_o; self.frames.len().max(1)];
        algebra::flatten(self, &regs, &mu, albedo)
    }

    /// The BSDF leaves, in node order.
    pub fn leaves(&self) -> impl Iterator<Item = (NodeId, &Leaf)> + '_ {
        self.nodes.iter().enumerate().filter_map(|(i, n)| match n {
            Node::Leaf(l) => Some((NodeId(i as u32), l)),
            _ => None,
        })
    }

    /// Number of BSDF leaves.
    pub fn lobe_count(&self) -> usize {
        self.leaves().count()
    }
}

/// A closure under construction: `None` is the empty closure (no response, throughput 1).
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) type Cl = Option<NodeId>;

/// Builds a [`MaterialIr`]: program, input slots, frames and the closure DAG.
#[derive(Debug, Default)]
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) struct IrBuilder {
    /// The program builder (folding, CSE).
    pub prog: ProgramBuilder,
    nodes: Vec<Node>,
    node_ids: HashMap<Node, NodeId>,
    inputs: Vec<InputSlot>,
    frames: Vec<FrameSlot>,
}

impl IrBuilder {
    /// An empty builder with the default frame (shading normal, surface tangent) as frame 0.
    pub fn new() -> Self {
        IrBuilder {
            frames: vec![FrameSlot::default()],
            ..Default::default()
        }
    }

    /// The register of the external slot fed by `origin`, creating the slot on first use.
    pub fn input_slot(&mut self, origin: &str, ty: Type, fallback: Value) -> Reg {
        let idx = match self.inputs.iter().position(|s| s.origin == origin) {
            Some(i) => i,
            None => {
                self.inputs.push(InputSlot {
                    name: origin.to_string(),
                    ty,
                    fallback,
                    origin: origin.to_string(),
                });
                self.inputs.len() - 1
            }
        };
        self.prog.input(idx as u32)
    }

    /// The input slots so far.
    pub fn inputs(&self) -> &[InputSlot] {
        &self.inputs
    }

    /// The index of a frame, created on first use. A frame whose registers are all absent
    /// or constant zero is the default frame 0.
    pub fn frame(&mut self, slot: FrameSlot) -> u32 {
        let zero_or_none =
            |r: Option<Reg>| r.is_none_or(|r| self.prog.constant(r) == Some(Vec3::ZERO));
        let slot = FrameSlot {
            normal: slot.normal.filter(|_| !zero_or_none(slot.normal)),
            tangent: slot.tangent.filter(|_| !zero_or_none(slot.tangent)),
            rotation: slot.rotation.filter(|_| !zero_or_none(slot.rotation)),
        };
        match self.frames.iter().position(|f| *f == slot) {
            Some(i) => i as u32,
            None => {
                self.frames.push(slot);
                (self.frames.len() - 1) as u32
            }
        }
    }

    fn node(&mut self, n: Node) -> NodeId {
        if let Some(&id) = self.node_ids.get(&n) {
            return id;
        }
        let id = NodeId(self.nodes.len() as u32);
        self.nodes.push(n.clone());
        self.node_ids.insert(n, id);
        id
    }

    /// The node with this id.
    pub fn node_at(&self, id: NodeId) -> &Node {
        &self.nodes[id.index()]
    }

    fn is_zero(&self, r: Reg) -> bool {
        self.prog.constant(r) == Some(Vec3::ZERO)
    }

    fn is_one(&self, r: Reg) -> bool {
        self.prog.constant(r) == Some(Vec3::ONE)
    }

    /// True when a leaf's response is statically zero: zero tint, or a parameter that
    /// scales the whole response (albedo, Fresnel colours, ρ_s) is the constant zero.
    pub fn leaf_is_dead(&self, leaf: &Leaf) -> bool {
        if self.is_zero(leaf.tint) {
            return true;
        }
        match leaf.kind {
            LeafKind::Lambert { albedo }
            | LeafKind::Translucent { albedo }
            | LeafKind::SubsurfaceProxy { albedo }
            | LeafKind::OrenNayarQ { albedo, .. }
            | LeafKind::OrenNayarE { albedo, .. }
            | LeafKind::MiaDiffuse { albedo, .. }
            | LeafKind::Burley { albedo, .. } => self.is_zero(albedo),
            LeafKind::Ward { rho_s, .. } => self.is_zero(rho_s),
            LeafKind::MicrofacetR {
                fresnel: Fresnel::Schlick { f0, f90, .. } | Fresnel::F82 { f0, f90, .. },
                ..
            } => self.is_zero(f0) && self.is_zero(f90),
            LeafKind::MicrofacetR { .. } => false,
            LeafKind::Dielectric {
                mode,
                refl_tint,
                trans_tint,
                ..
            } => match mode {
                DielectricMode::R => self.is_zero(refl_tint),
                DielectricMode::T => self.is_zero(trans_tint),
                DielectricMode::Rt => self.is_zero(refl_tint) && self.is_zero(trans_tint),
            },
            _ => false,
        }
    }

    /// A leaf; the empty closure when it is statically dead.
    pub fn leaf(&mut self, leaf: Leaf) -> Cl {
        if self.leaf_is_dead(&leaf) {
            return None;
        }
        Some(self.node(Node::Leaf(leaf)))
    }

    /// A leaf with tint and ttint 1 on frame 0.
    pub fn simple_leaf(&mut self, kind: LeafKind, label: &str) -> Cl {
        let one = self.prog.constf(1.0);
        self.leaf(Leaf {
            kind,
            tint: one,
            ttint: one,
            frame: 0,
            label: label.to_string(),
        })
    }

    /// Emission with the given radiance.
    pub fn emission(&mut self, radiance: Reg) -> Cl {
        if self.is_zero(radiance) {
            return None;
        }
        Some(self.node(Node::Emission { radiance }))
    }

    /// Straight-through transmission with the given tint.
    pub fn transparent(&mut self, tint: Reg) -> Cl {
        if self.is_zero(tint) {
            return None;
        }
        Some(self.node(Node::Transparent { tint }))
    }

    /// `layer[mode](top, base)`.
    pub fn layer(&mut self, top: Cl, base: Cl, mode: TintMode) -> Cl {
        match (top, base) {
            (None, b) => b,
            (t, None) => t,
            (Some(top), Some(base)) => Some(self.node(Node::Layer { top, base, mode })),
        }
    }

    /// `mix(a, b, m)` = `(1 − m)a + m b`, m clamped to [0, 1].
    pub fn mix(&mut self, a: Cl, b: Cl, m: Reg) -> Cl {
        let m = self.prog.saturate(m);
        if self.is_zero(m) {
            return a;
        }
        if self.is_one(m) {
            return b;
        }
        match (a, b) {
            (None, None) => None,
            (Some(a), None) => {
                let c = self.prog.one_minus(m);
                self.mul(Some(a), c)
            }
            (None, Some(b)) => self.mul(Some(b), m),
            (Some(a), Some(b)) if a == b => Some(a),
            (Some(a), Some(b)) => Some(self.node(Node::Mix { a, b, m })),
        }
    }

    /// `add(a, b)`.
    pub fn add(&mut self, a: Cl, b: Cl) -> Cl {
        match (a, b) {
            (None, b) => b,
            (a, None) => a,
            (Some(a), Some(b)) => Some(self.node(Node::Add { a, b })),
        }
    }

    /// Sum of several closures, left to right.
    pub fn add_all(&mut self, items: &[Cl]) -> Cl {
        items.iter().fold(None, |acc, &c| self.add(acc, c))
    }

    /// `mul(f, c)`, c ≥ 0 (negative factors are clamped to 0 by the algebra).
    pub fn mul(&mut self, f: Cl, c: Reg) -> Cl {
        let f = f?;
        if self.is_zero(c) {
            return None;
        }
        if self.is_one(c) {
            return Some(f);
        }
        Some(self.node(Node::Multiply { f, c }))
    }

    /// Finish: reorder the nodes reachable from `root` so that the root is node 0 and every
    /// node precedes its children, run the optimisation passes, and check `MAX_LOBES`
    /// (LW010 when exceeded).
    pub fn finish(
        self,
        name: &str,
        recipe: RecipeId,
        root: Cl,
    ) -> Result<MaterialIr, Box<crate::diag::Diagnostic>> {
        let nodes = match root {
            Some(r) => passes::topo_from_root(&self.nodes, r),
            None => Vec::new(),
        };
        let program = self.prog.program();
        let ir = MaterialIr {
            name: name.to_string(),
            recipe,
            inputs: self.inputs,
            program,
            nodes,
            frames: self.frames,
            max_static_lobes: 0,
        };
        passes::optimize_with(ir, Some(self.prog))
    }
}
