//! The compiled form of a material: [`Material`] and everything it holds, the data that
//! the compile step writes and the prepares read (the flat closure nodes, the leaves, the
//! throughput steps, and the plans of the weight pass and of the fused and lane-parallel
//! prepares), and the clamps the passes share.
//!
//! Types only, with the clamps: the code that builds a plan or runs one lives in the file of
//! its step, above this one, so that every file of the folder imports only files below it
//! (see the module documentation of [`super`]).

use super::packs::Grouping;
use super::record::PrepareOptions;
use crate::interp::diffuse::{OrenNayar, OrenNayarBound};
use crate::interp::ggx::GgxView;
use crate::interp::lobe::{BoundLobe, PreparedLobe, RefreshLeaf};
use crate::interp::math::Rgb;
use crate::interp::microfacet::{Dielectric, MicrofacetR, RatioGrid};
use crate::interp::sheen::{SheenCKBound, SheenLTCBound};
use crate::interp::tables::MuCurve;
use crate::interp::ward::{Ward, WardBound};
use crate::ir::{FrameSlot, Leaf, MaterialIr, NodeId, Reg, TintMode};
use glam::Vec3;

/// A leaf of a compiled material.
#[derive(Debug, Clone)]
pub struct LeafInfo {
    /// The closure node.
    pub node: NodeId,
    /// The leaf (kind, registers, tints, IR frame, label).
    pub leaf: Leaf,
    /// Compact frame slot (index into the prepared frames).
    pub(super) frame_slot: u8,
    /// Layerable.
    pub(super) layerable: bool,
    /// The lobe, when every parameter register is a constant (built and bound once at
    /// compile time).
    pub(super) const_lobe: Option<BoundLobe>,
}

#[derive(Debug, Clone, Copy)]
pub(super) enum CNode {
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
    pub(super) ir: MaterialIr,
    pub(super) nodes: Vec<CNode>,
    /// Bit `m` set: the node's throughput in mode `m` is read by some layer.
    pub(super) need: Vec<u8>,
    /// Where node `i`'s throughput in mode `m` lives in [`Scratch`](super::Scratch) (`NO_SLOT`:
    /// never read).
    pub(super) thr_slot: Vec<[u16; 4]>,
    /// The throughput pass compiled to straight-line steps, bottom-up.
    pub(super) thr_ops: Vec<ThrOp>,
    pub(super) leaves: Vec<LeafInfo>,
    /// The IR frames used by leaves, in compact order.
    pub(super) frames: Vec<FrameSlot>,
    /// Their indices in the IR.
    pub(super) frame_ids: Vec<u32>,
    /// `(offset, width)` of each input slot in the packed input slice.
    pub(super) layout: Vec<(usize, usize)>,
    /// Some frame has its own normal and the program reads `ViewMu`.
    pub(super) rerun_for_mu: bool,
    /// The register file when the program reads no input, global or view (computed once).
    pub(super) const_regs: Option<Vec<Vec3>>,
    /// The weight pass with every register read folded in, when the registers are
    /// constant (`const_regs`) and the DAG has few enough paths.
    pub(super) w_plan: Option<WeightPlan>,
    /// The lane-parallel prepare's per-leaf data, when the material qualifies
    /// ([`LanePlan`]).
    pub(super) lanes: Option<LanePlan>,
    /// The fused scalar prepare's constants, when the material qualifies
    /// ([`UniformPlan`]).
    pub(super) uniform: Option<UniformPlan>,
    /// Which lobes `eval` packs together in a prepare where every leaf survives and is
    /// active; known at compile time when every leaf is a constant (`None` otherwise, and
    /// the grouping is made per prepare).
    pub(super) pack_grouping: Option<Grouping>,
    pub(super) options: PrepareOptions,
}

/// One step of the compiled throughput pass: step `i` writes slot `i` from slots written
/// before it (bottom-up) and registers.
#[derive(Debug, Clone, Copy)]
pub(super) enum ThrOp {
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
    /// ([`weights_are_clean`](super::plan::weights_are_clean)): [`clean`] of it is the
    /// identity, and the fused and lane-parallel prepares skip it.
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

/// What the lane-parallel prepare keeps of one leaf: its family's view-independent data
/// (from the leaf's [`crate::interp::lobe::BoundLobe`]). One per leaf, built at compile
/// time, so the size difference between variants costs nothing worth boxing for.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Copy)]
pub(super) enum LeafLanes {
    /// Lambert (and the subsurface proxy): `ρ` and `ρ/π`.
    Lambert { rho: Rgb, rho_pi: Rgb },
    /// Oren–Nayar (any variant).
    OrenNayar {
        lobe: OrenNayar,
        bound: OrenNayarBound,
    },
    /// GGX reflection with a conductor Fresnel, no compensation: its albedo is `E1` times
    /// the exact Fresnel's ratio grid ([`MicrofacetR::ratio_albedo`]).
    Conductor {
        lobe: MicrofacetR,
        ggx_view: GgxView,
        /// The lobe's baked albedo or Fresnel ratios (`MicrofacetBound::ratios`; every rough
        /// conductor has them).
        ratios: RatioGrid,
    },
    /// GGX dielectric in mode R without Turquin's factor: `E_R` at the lobe's η.
    DielectricR {
        lobe: Dielectric,
        ggx_view: GgxView,
        eta: f32,
        e_r: MuCurve,
        /// An anisotropic lobe's ratios at η (`DielectricBound::aniso`).
        aniso: Option<RatioGrid>,
    },
    /// Ward (classic or GM).
    Ward { lobe: Ward, bound: WardBound },
    /// Conty–Kulla sheen with the MaterialX masking.
    SheenCK { bound: SheenCKBound },
    /// LTC sheen (its fits at the lobe's roughness).
    SheenLTC { bound: SheenLTCBound },
}

/// The per-leaf data of a material that [`Material::prepare_lanes`] can prepare.
#[derive(Debug, Clone)]
pub(in crate::interp) struct LanePlan {
    pub(super) leaves: Vec<LeafLanes>,
}

/// One step of the throughput pass with its registers read at compile time (the
/// [`ThrOp`] it comes from says what each computes).
#[derive(Debug, Clone, Copy)]
pub(super) enum UniformThr {
    /// A layerable leaf's throughput in `mode`, with its tints.
    Leaf {
        leaf: u8,
        mode: TintMode,
        tint: Vec3,
        ttint: Vec3,
    },
    /// [`UniformThr::Leaf`] in mode RGB with both tints 1: `sat(1 − E)` (the same bits:
    /// products with 1 are exact).
    LeafPlain { leaf: u8 },
    /// A constant: 0 for a leaf that is not layerable, 1 for emission and transparency.
    Const(Vec3),
    /// `T_top · T_base`.
    Layer { top: u8, base: u8 },
    /// `(1 − m) T_a + m T_b`, `m` saturated.
    Mix { a: u8, b: u8, m: Vec3 },
    /// `max(T_a + T_b − 1, 0)`.
    Add { a: u8, b: u8 },
    /// `sat(1 − c (1 − T_f))`, `c` clamped at 0.
    Multiply { f: u8, c: Vec3 },
}

/// A leaf of a [`UniformPlan`]: its bound lobe, and the same as its refresh reads it.
#[derive(Debug, Clone, Copy)]
pub(super) struct UniformLeaf {
    pub(super) lobe: BoundLobe,
    pub(super) refresh: RefreshLeaf,
}

/// A target's one term in a tree plan (`c ⊙ scope`; `(0, 0)` for a target without a term
/// or in a plan that is not a tree, where the sum is accumulated by target index).
#[derive(Debug, Clone, Copy)]
pub(super) struct TreeTerm {
    pub(super) c: Vec3,
    pub(super) scope: u8,
}

/// A leaf target of a [`UniformPlan`]: the leaf, its tint, its index among the weight
/// plan's targets and its term.
#[derive(Debug, Clone, Copy)]
pub(super) struct LeafTarget {
    pub(super) tint: Vec3,
    pub(super) term: TreeTerm,
    pub(super) target: u8,
    pub(super) leaf: u8,
}

/// An emission or transparency target of a [`UniformPlan`] (a [`Target`] that is not a
/// leaf), with its index among the weight plan's targets and its term.
#[derive(Debug, Clone, Copy)]
pub(super) struct LightTarget {
    pub(super) kind: Target,
    pub(super) term: TreeTerm,
    pub(super) target: u8,
}

/// What [`Material::prepare_uniform_into`] needs beyond the material's weight plan: the
/// bound leaves, their records' templates, the throughput steps with constants folded in,
/// and the material's stamp.
#[derive(Debug, Clone)]
pub(super) struct UniformPlan {
    /// Unique per compiled material (clones share it, with their constants): lets a
    /// [`Prepared`](super::Prepared) tell that its records and lobe packs hold this material's
    /// view-independent fields (`Prepared::stamp`,
    /// [`super::packs::EvalPlan::build_stamped`]).
    pub(super) stamp: u64,
    /// Every leaf's bound constant lobe with what its refresh reads, in leaf order (side by
    /// side, not inside the larger [`LeafInfo`]s).
    pub(super) leaves: Vec<UniformLeaf>,
    /// Every leaf's record at the view straight up: its view-independent fields are those
    /// of the record at any view above the surface, so a record is this template with
    /// the view-dependent fields written over ([`RefreshLeaf::refresh_above_into`]).
    pub(super) templates: Vec<PreparedLobe>,
    /// The throughput steps, bottom-up (step `j` writes slot `j`).
    pub(super) thr: Vec<UniformThr>,
    /// True when no weight target has more than one term (a tree: one path to each node):
    /// each target's sum is then its one product, and the targets carry their terms.
    pub(super) tree: bool,
    /// The leaf targets of the weight plan, in leaf order.
    pub(super) leaf_targets: Vec<LeafTarget>,
    /// The emission and transparency targets, in target order.
    pub(super) light_targets: Vec<LightTarget>,
    /// [`WeightPlan::weights_clean`]: [`clean`] would return every leaf
    /// weight unchanged, so it is skipped.
    pub(super) weights_clean: bool,
}

/// Clamped to [0, 1] per channel.
pub(super) fn sat(v: Vec3) -> Vec3 {
    v.clamp(Vec3::ZERO, Vec3::ONE)
}

/// Non-negative and finite (NaN and infinities become 0).
#[inline]
pub(super) fn clean(v: Vec3) -> Vec3 {
    // A bit mask per channel, no branch. `x − x` is 0 exactly for finite x (NaN for ±∞ and
    // NaN); written as `x < ∞`, LLVM turns the test into integer classification code.
    #[allow(clippy::eq_op)] // `x − x` is the finiteness test (see above), not a slip
    let c = |x: f32| {
        let keep = (x > 0.0) & (x - x == 0.0);
        f32::from_bits(x.to_bits() & u32::from(keep).wrapping_neg())
    };
    Vec3::new(c(v.x), c(v.y), c(v.z))
}
