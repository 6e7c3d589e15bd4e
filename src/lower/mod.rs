//! Lowering of resolved shader networks to the closure IR, one module
//! per material model: `pxr` (PxrSurface / PxrLayerSurface, with PxrLayer and
//! PxrLayerMixer interpreted as program expressions), `vray`, `physical`, `mia`, and
//! the small fused pattern set `patterns` (internal modules).
//!
//! The lowering reads the network through the small [`Graph`] trait and definitions through
//! [`Definitions`], so that it works on the crate's network model and on hand-built graphs
//! (`SimpleGraph`, for tests) alike.
//!
//! Parameter binding, in order of preference: a connection from an interpreted
//! pattern → program expression; a connection from any other node → external input slot
//! (LW002, info) whose fallback is the downstream parameter's value; an authored value; the
//! definition default; the recipe's built-in default (LW003, warning, once per node type
//! without definition).

pub mod network;

// One module per material model. The recipes are internals: public only to the crate's own
// tests (feature `testkit`), which check their built-in defaults against the shipped `.args`.
testkit_mods!(mia, patterns, physical, pxr, vray);

use crate::diag::{Diagnostic, Diagnostics, Error, Location};
use crate::ir::{IrBuilder, MaterialIr, Reg, value_to_vec3};
use crate::registry::{Definition, IndexedDefinition, NumericRange};
use crate::types::{BaseType, Type, Value};
use glam::Vec3;
use rustc_hash::{FxHashMap, FxHashSet};
#[cfg(any(test, feature = "testkit"))]
use std::collections::HashMap;
use std::fmt::Debug;
use std::hash::Hash;
use std::sync::Arc;

/// Read access to a (resolved) shader network, as the lowering needs it.
pub trait Graph {
    /// Node identifier.
    type Id: Copy + Eq + Hash + Debug;
    /// The node's shader type (`PxrLayer`, `VRayMtl`, ...).
    fn shader(&self, n: Self::Id) -> &str;
    /// The node's handle (unique name).
    fn handle(&self, n: Self::Id) -> &str;
    /// The authored value of an input, if any.
    fn value(&self, n: Self::Id, param: &str) -> Option<&Value>;
    /// The first connection into an input: upstream node and output name (empty when the
    /// connection names no output).
    fn connection(&self, n: Self::Id, param: &str) -> Option<(Self::Id, &str)>;
    /// [`Graph::value`] and [`Graph::connection`] of one input, in one look-up where the
    /// graph can do that.
    fn input(&self, n: Self::Id, param: &str) -> Binding<'_, Self::Id> {
        Binding {
            value: self.value(n, param),
            connection: self.connection(n, param),
        }
    }
    /// Where the node is defined, for diagnostics.
    fn location(&self, n: Self::Id) -> Option<Location>;
}

/// What a graph holds for one input: its authored value and its first connection.
#[derive(Debug, Clone, Copy)]
pub struct Binding<'g, Id> {
    /// The authored value, if any.
    pub value: Option<&'g Value>,
    /// The first connection: upstream node and output name (empty when none is named).
    pub connection: Option<(Id, &'g str)>,
}

/// Shader definitions by id.
pub trait Definitions {
    /// The definition of `shader`, if known.
    fn definition(&self, shader: &str) -> Option<Arc<Definition>>;
}

/// No definitions at all: every recipe uses its built-in defaults (LW003).
#[derive(Debug, Clone, Copy, Default)]
#[cfg(any(test, feature = "testkit"))]
pub struct NoDefinitions;

#[cfg(any(test, feature = "testkit"))]
impl Definitions for NoDefinitions {
    fn definition(&self, _shader: &str) -> Option<Arc<Definition>> {
        None
    }
}

#[cfg(any(test, feature = "testkit"))]
impl Definitions for HashMap<String, Arc<Definition>> {
    fn definition(&self, shader: &str) -> Option<Arc<Definition>> {
        self.get(shader).cloned()
    }
}

/// A small in-memory network for tests and API users who build materials by hand.
#[derive(Debug, Clone, Default)]
#[cfg(any(test, feature = "testkit"))]
pub struct SimpleGraph {
    nodes: Vec<SimpleNode>,
}

#[derive(Debug, Clone)]
#[cfg(any(test, feature = "testkit"))]
struct SimpleNode {
    handle: String,
    shader: String,
    values: HashMap<String, Value>,
    conns: HashMap<String, (usize, String)>,
}

#[cfg(any(test, feature = "testkit"))]
impl SimpleGraph {
    /// An empty graph.
    pub fn new() -> Self {
        Self::default()
    }
    /// Add a node; returns its id.
    pub fn node(&mut self, handle: &str, shader: &str) -> usize {
        self.nodes.push(SimpleNode {
            handle: handle.into(),
            shader: shader.into(),
            values: HashMap::new(),
            conns: HashMap::new(),
        });
        self.nodes.len() - 1
    }
    /// Author a value (replacing an earlier one).
    pub fn set(&mut self, n: usize, param: &str, v: Value) -> &mut Self {
        self.nodes[n].values.insert(param.into(), v);
        self
    }
    /// Author a float.
    pub fn setf(&mut self, n: usize, param: &str, x: f32) -> &mut Self {
        self.set(n, param, Value::Float(x))
    }
    /// Author an int.
    pub fn seti(&mut self, n: usize, param: &str, x: i32) -> &mut Self {
        self.set(n, param, Value::Int(x))
    }
    /// Author a colour.
    pub fn setc(&mut self, n: usize, param: &str, c: [f32; 3]) -> &mut Self {
        self.set(n, param, Value::Triple(BaseType::Color, c))
    }
    /// Connect `up.output` to `down.param` (replacing an earlier connection).
    pub fn connect(&mut self, down: usize, param: &str, up: usize, output: &str) -> &mut Self {
        self.nodes[down]
            .conns
            .insert(param.into(), (up, output.into()));
        self
    }
    /// The id of the node with this handle.
    pub fn find(&self, handle: &str) -> Option<usize> {
        self.nodes.iter().position(|n| n.handle == handle)
    }
}

#[cfg(any(test, feature = "testkit"))]
impl Graph for SimpleGraph {
    type Id = usize;
    fn shader(&self, n: usize) -> &str {
        &self.nodes[n].shader
    }
    fn handle(&self, n: usize) -> &str {
        &self.nodes[n].handle
    }
    fn value(&self, n: usize, param: &str) -> Option<&Value> {
        self.nodes[n].values.get(param)
    }
    fn connection(&self, n: usize, param: &str) -> Option<(usize, &str)> {
        self.nodes[n]
            .conns
            .get(param)
            .map(|(u, o)| (*u, o.as_str()))
    }
    fn location(&self, _n: usize) -> Option<Location> {
        None
    }
}

/// Which recipe lowers a terminal of this shader type, if any.
pub(crate) fn recipe_for(shader: &str) -> Option<crate::ir::RecipeId> {
    use crate::ir::RecipeId::*;
    Some(match shader {
        "PxrSurface" | "PxrLayerSurface" => PxrSurface,
        "VRayMtl" => VRayMtl,
        "PhysicalMaterial" => PhysicalMaterial,
        "mia_material" | "mia_material_x" => MiaMaterial,
        _ => return None,
    })
}

/// Lower the terminal `node` of `graph` to a [`MaterialIr`] named `name`. Diagnostics
/// (LW002, LW003, LW020, ...) are appended to `diags`; LW001, LW010 and LW011 are errors.
pub fn lower_node<G: Graph>(
    graph: &G,
    defs: &dyn Definitions,
    node: G::Id,
    name: &str,
    diags: &mut Diagnostics,
) -> Result<MaterialIr, Error> {
    lower_node_cached(
        graph,
        defs,
        &mut DefinitionCache::default(),
        node,
        name,
        diags,
    )
}

/// Indexed definitions by shader type, kept across the materials one thread lowers: indexing
/// a definition such as PxrLayerMixer (hundreds of inputs) costs more than lowering a
/// material, and a per-thread cache keeps threads off each other's reference counts.
#[derive(Debug, Default)]
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) struct DefinitionCache {
    by_shader: FxHashMap<String, Option<Arc<IndexedDefinition>>>,
}

impl DefinitionCache {
    fn get(&mut self, defs: &dyn Definitions, shader: &str) -> Option<Arc<IndexedDefinition>> {
        // `get` before `entry`: the hit path then hashes once and allocates nothing.
        if let Some(d) = self.by_shader.get(shader) {
            return d.clone();
        }
        let d = defs
            .definition(shader)
            .map(|d| Arc::new(IndexedDefinition::new(d)));
        self.by_shader.insert(shader.to_string(), d.clone());
        d
    }
}

/// [`lower_node`] with a definition cache shared across calls (as `lower_many` does).
pub(crate) fn lower_node_cached<G: Graph>(
    graph: &G,
    defs: &dyn Definitions,
    cache: &mut DefinitionCache,
    node: G::Id,
    name: &str,
    diags: &mut Diagnostics,
) -> Result<MaterialIr, Error> {
    let shader = graph.shader(node);
    let Some(recipe) = recipe_for(shader) else {
        let mut d = Diagnostic::error(
            "LW001",
            format!(
                "no lowering recipe for shader type `{shader}` (node `{}`)",
                graph.handle(node)
            ),
        )
        .with_note("recipes exist for PxrSurface, PxrLayerSurface, VRayMtl, PhysicalMaterial, mia_material");
        if let Some(l) = graph.location(node) {
            d = d.at(l);
        }
        return Err(d.with_node(graph.handle(node)).into());
    };
    let mut cx = Lower::new(graph, defs, cache, diags);
    let root = match recipe {
        crate::ir::RecipeId::PxrSurface => pxr::lower_surface(&mut cx, node),
        crate::ir::RecipeId::VRayMtl => vray::lower(&mut cx, node),
        crate::ir::RecipeId::PhysicalMaterial => physical::lower(&mut cx, node),
        crate::ir::RecipeId::MiaMaterial => mia::lower(&mut cx, node),
        crate::ir::RecipeId::Custom => Ok(None),
    };
    let root = root?;
    let b = std::mem::take(&mut cx.b);
    b.finish(name, recipe, root).map_err(|d| {
        let d = match graph.location(node) {
            Some(l) if d.location.is_none() => d.at(l),
            _ => *d,
        };
        Error::Input(Box::new(d))
    })
}

/// A reusable buffer for parameter names built from parts: `format!` allocates for every
/// binding, and a PxrLayerMixer builds hundreds of names per material.
#[derive(Debug, Default)]
pub(crate) struct NameBuf(String);

impl NameBuf {
    /// The concatenation of `parts`, valid until the next call.
    pub(crate) fn join(&mut self, parts: &[&str]) -> &str {
        self.0.clear();
        for p in parts {
            self.0.push_str(p);
        }
        &self.0
    }
}

/// Gate and compositing factor of mixer layers 1–4 for one lobe group.
pub(crate) type MixerGates = [(Reg, Reg); 4];

/// The lowering context: the graph, definitions, the IR builder and diagnostics.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) struct Lower<'a, G: Graph> {
    /// The network.
    pub graph: &'a G,
    /// Definitions.
    pub defs: &'a dyn Definitions,
    /// The IR under construction.
    pub b: IrBuilder,
    /// Diagnostics sink.
    pub diags: &'a mut Diagnostics,
    cache: &'a mut DefinitionCache,
    /// The definition of the node looked up last: bindings come in runs per node.
    last_definition: Option<(G::Id, Option<Arc<IndexedDefinition>>)>,
    outputs: FxHashMap<(G::Id, String), Reg>,
    /// Per PxrLayerMixer node and lobe group: gates and compositing factors (see
    /// `pxr::mixer_gates`).
    pub(crate) mixer_gates: FxHashMap<(G::Id, &'static str), MixerGates>,
    visiting: Vec<G::Id>,
    warned_no_def: FxHashSet<String>,
    /// LW020 already reported in this material: (node, parameter).
    noted: FxHashSet<(G::Id, String)>,
}

impl<'a, G: Graph> Lower<'a, G> {
    /// A fresh context that looks definitions up through `cache` (which may outlive it and
    /// serve many materials).
    pub(crate) fn new(
        graph: &'a G,
        defs: &'a dyn Definitions,
        cache: &'a mut DefinitionCache,
        diags: &'a mut Diagnostics,
    ) -> Self {
        Lower {
            graph,
            defs,
            b: IrBuilder::new(),
            diags,
            cache,
            last_definition: None,
            outputs: FxHashMap::default(),
            mixer_gates: FxHashMap::default(),
            visiting: Vec::new(),
            warned_no_def: FxHashSet::default(),
            noted: FxHashSet::default(),
        }
    }

    /// The definition of a node's shader, with its inputs indexed by name (cached).
    pub(crate) fn definition(&mut self, n: G::Id) -> Option<&IndexedDefinition> {
        if self.last_definition.as_ref().is_none_or(|(id, _)| *id != n) {
            let d = self.cache.get(self.defs, self.graph.shader(n));
            self.last_definition = Some((n, d));
        }
        self.last_definition
            .as_ref()
            .and_then(|(_, d)| d.as_deref())
    }

    /// LW020 (an info): parameter `param` of node `n` is approximated or ignored, as
    /// `message` says. Reported only when the parameter is authored (a value, which
    /// resolution may have written, or a connection), once per material, node and parameter:
    /// a default is the recipe's to document, not a finding about the network.
    pub(crate) fn approximated(&mut self, n: G::Id, param: &str, message: impl Into<String>) {
        let input = self.graph.input(n, param);
        if input.value.is_none() && input.connection.is_none() {
            return;
        }
        if self.noted.insert((n, param.to_string())) {
            self.diag(n, Diagnostic::info("LW020", message).with_param(param));
        }
    }

    /// Emit a diagnostic located at node `n`.
    pub(crate) fn diag(&mut self, n: G::Id, d: Diagnostic) {
        let d = match self.graph.location(n) {
            Some(l) => d.at(l),
            None => d,
        };
        self.diags.push(d.with_node(self.graph.handle(n)));
    }

    /// Bind parameter `param` of node `n` with `builtin` as the recipe's default.
    pub(crate) fn param(&mut self, n: G::Id, param: &str, builtin: Value) -> Result<Reg, Error> {
        let graph = self.graph;
        let input = graph.input(n, param);
        if let Some((up, output)) = input.connection {
            if let Some(r) = self.pattern_output(up, output)? {
                return Ok(r);
            }
            let (fallback, range, ty) = self.static_binding(n, param, input.value, &builtin);
            let fallback = self.clamp_to_range(n, param, fallback, range);
            let origin = if output.is_empty() {
                graph.handle(up).to_string()
            } else {
                format!("{}.{}", graph.handle(up), output)
            };
            let known = self.b.inputs().iter().any(|s| s.origin == origin);
            if !known {
                self.diag(
                    n,
                    Diagnostic::info(
                        "LW002",
                        format!(
                            "`{}.{param}` is connected to `{origin}` ({}), which the lowering does not interpret; it becomes an external input slot with fallback {fallback}",
                            self.graph.handle(n),
                            self.graph.shader(up)
                        ),
                    ),
                );
            }
            return Ok(self.b.input_slot(&origin, ty, fallback));
        }
        let (v, range, _) = self.static_binding(n, param, input.value, &builtin);
        let v = self.clamp_to_range(n, param, v, range);
        Ok(self.b.prog.constant3(value_to_vec3(&v)))
    }

    /// For an unconnected binding, in one definition lookup: the static value (authored,
    /// definition default or `builtin`), the documented range and the parameter's type.
    fn static_binding(
        &mut self,
        n: G::Id,
        param: &str,
        authored: Option<&Value>,
        builtin: &Value,
    ) -> (Value, NumericRange, Type) {
        let undeclared = || {
            (
                authored.unwrap_or(builtin).clone(),
                NumericRange::default(),
                Type::scalar(builtin.base_type()),
            )
        };
        if let Some(def) = self.definition(n) {
            return match def.input_with_range(param) {
                Some((p, range)) => {
                    let v = authored.or(p.default.as_ref()).unwrap_or(builtin).clone();
                    (v, range, p.ty.clone())
                }
                None => undeclared(),
            };
        }
        self.warn_no_definition(n);
        undeclared()
    }

    /// A constant outside the parameter's documented range (the definition's `min` /
    /// `max` metadata) is clamped to it (LW022, info). Connected values are not clamped: they
    /// are only known per shading point.
    fn clamp_to_range(&mut self, n: G::Id, param: &str, v: Value, range: NumericRange) -> Value {
        if range.is_open() {
            return v;
        }
        let NumericRange { min: lo, max: hi } = range;
        let clamp = |x: f32| {
            let x = lo.map_or(x, |l| x.max(l));
            hi.map_or(x, |h| x.min(h))
        };
        let clamped = match &v {
            Value::Float(x) => Value::Float(clamp(*x)),
            Value::Int(i) => Value::Int(clamp(*i as f32).round() as i32),
            Value::Triple(b, c) => Value::Triple(b.clone(), c.map(clamp)),
            _ => return v,
        };
        if clamped != v {
            let range = |b: Option<f32>, open: &str| b.map_or(open.to_string(), |x| x.to_string());
            self.diag(
                n,
                Diagnostic::info(
                    "LW022",
                    format!(
                        "`{}.{param}` = {v} is outside its documented range [{}, {}]; clamped to {clamped}",
                        self.graph.handle(n),
                        range(lo, "-inf"),
                        range(hi, "inf")
                    ),
                ),
            );
        }
        clamped
    }

    /// A float parameter.
    pub(crate) fn pf(&mut self, n: G::Id, param: &str, builtin: f32) -> Result<Reg, Error> {
        self.param(n, param, Value::Float(builtin))
    }
    /// An int parameter.
    pub(crate) fn pi(&mut self, n: G::Id, param: &str, builtin: i32) -> Result<Reg, Error> {
        self.param(n, param, Value::Int(builtin))
    }
    /// A colour parameter.
    pub(crate) fn pc(&mut self, n: G::Id, param: &str, builtin: [f32; 3]) -> Result<Reg, Error> {
        self.param(n, param, Value::Triple(BaseType::Color, builtin))
    }
    /// A normal/vector parameter.
    pub(crate) fn pv(&mut self, n: G::Id, param: &str, builtin: [f32; 3]) -> Result<Reg, Error> {
        self.param(n, param, Value::Triple(BaseType::Vector, builtin))
    }

    /// The constant scalar value of a parameter when it is not connected (authored,
    /// definition default or built-in), for structural choices such as Fresnel modes.
    pub(crate) fn static_scalar(&mut self, n: G::Id, param: &str, builtin: f32) -> Option<f32> {
        let graph = self.graph;
        let input = graph.input(n, param);
        if input.connection.is_some() {
            return None;
        }
        let (v, ..) = self.static_binding(n, param, input.value, &Value::Float(builtin));
        Some(value_to_vec3(&v).x)
    }

    /// True when the parameter is connected to anything.
    pub(crate) fn is_connected(&self, n: G::Id, param: &str) -> bool {
        self.graph.connection(n, param).is_some()
    }

    /// LW003, once per shader type: the registry has no definition of `n`'s type.
    fn warn_no_definition(&mut self, n: G::Id) {
        let graph = self.graph;
        let shader = graph.shader(n);
        if self.warned_no_def.insert(shader.to_string()) {
            self.diag(
                n,
                Diagnostic::warning(
                    "LW003",
                    format!(
                        "no definition of `{shader}` in the registry; the lowering uses its built-in defaults"
                    ),
                ),
            );
        }
    }

    /// The program expression of `up.output` when `up` is a pattern the lowering interprets
    /// (memoised); `None` when it is not interpreted. LW011 on a cycle.
    pub(crate) fn pattern_output(&mut self, up: G::Id, output: &str) -> Result<Option<Reg>, Error> {
        let graph = self.graph;
        let shader = graph.shader(up);
        if !is_interpreted(shader) {
            return Ok(None);
        }
        let key = (up, output.to_string());
        if let Some(&r) = self.outputs.get(&key) {
            return Ok(Some(r));
        }
        if self.visiting.contains(&up) {
            let path: Vec<String> = self
                .visiting
                .iter()
                .map(|&v| self.graph.handle(v).to_string())
                .collect();
            let mut d = Diagnostic::error(
                "LW011",
                format!(
                    "cycle among interpreted patterns through `{}`",
                    self.graph.handle(up)
                ),
            )
            .with_note(format!(
                "path: {} -> {}",
                path.join(" -> "),
                self.graph.handle(up)
            ));
            if let Some(l) = self.graph.location(up) {
                d = d.at(l);
            }
            return Err(d.with_node(self.graph.handle(up)).into());
        }
        self.visiting.push(up);
        let r = match shader {
            "PxrLayer" => pxr::layer_output(self, up, output),
            "PxrLayerMixer" => pxr::mixer_output(self, up, output),
            _ => patterns::output(self, up, output),
        };
        self.visiting.pop();
        let r = r?;
        if let Some(r) = r {
            self.outputs.insert(key, r);
        }
        Ok(r)
    }

    /// An isotropic height-correlated GGX dielectric leaf with untinted Fresnel colours, as
    /// every recipe uses it: `R` mode for a coat (with `ttint` filtering what lies below) and
    /// `T` mode without the `(1 − F)` factor, for refraction under a separate reflection layer
    /// that already removes the reflected energy.
    pub(crate) fn dielectric(
        &mut self,
        mode: crate::ir::closure::DielectricMode,
        alpha: Reg,
        eta: Reg,
        tint: Reg,
        ttint: Reg,
        label: &str,
    ) -> crate::ir::Cl {
        use crate::ir::closure::{DielectricMode, Leaf, LeafKind};
        let one = self.constf(1.0);
        self.b.leaf(Leaf {
            kind: LeafKind::Dielectric {
                alpha_x: alpha,
                alpha_y: alpha,
                eta,
                mode,
                refl_tint: one,
                trans_tint: one,
                t_fresnel: matches!(mode, DielectricMode::R),
                masking: crate::ir::closure::Masking::HeightCorrelated,
            },
            tint,
            ttint,
            frame: 0,
            label: label.into(),
        })
    }

    /// A constant register.
    pub(crate) fn constf(&mut self, x: f32) -> Reg {
        self.b.prog.constf(x)
    }
}

/// True for the pattern types the lowering turns into program expressions.
pub(crate) fn is_interpreted(shader: &str) -> bool {
    matches!(shader, "PxrLayer" | "PxrLayerMixer") || patterns::is_pattern(shader)
}

/// Anisotropic widths from roughness `r` and anisotropy `a ∈ [−1, 1]`:
/// `α = clamp(r², 1e-6, 1)`, `s = √(1 − min(|a|, 0.98))`, `α_x = min(α/s, 1)`, `α_y = α s`,
/// roles swapped for `a < 0`.
pub(crate) fn aniso_alpha(b: &mut IrBuilder, r: Reg, a: Reg) -> (Reg, Reg) {
    let p = &mut b.prog;
    let r2 = p.mul(r, r);
    let alpha = p.clamp(r2, 1e-6, 1.0);
    if p.constant(a) == Some(Vec3::ZERO) {
        // Isotropic: one register for both widths.
        return (alpha, alpha);
    }
    let aa = p.un(crate::ir::OpCode::Abs, a);
    let cap = p.constf(0.98);
    let aa = p.bin(crate::ir::OpCode::Min, aa, cap);
    let one_minus = p.one_minus(aa);
    let s = p.un(crate::ir::OpCode::Sqrt, one_minus);
    let q = p.div(alpha, s);
    let one = p.constf(1.0);
    let big = p.bin(crate::ir::OpCode::Min, q, one);
    let small = p.mul(alpha, s);
    let zero = p.constf(0.0);
    let pos = p.bin(crate::ir::OpCode::CmpGe, a, zero);
    let ax = p.select(pos, big, small);
    let ay = p.select(pos, small, big);
    (ax, ay)
}

/// Lower every terminal of a [`SimpleGraph`]-like graph given as `(name, node)` pairs,
/// optionally in parallel (rayon) — materials are independent.
/// (Test and bench support: the pipeline lowers through `pipeline::lower`.)
#[cfg(any(test, feature = "testkit"))]
pub fn lower_many<G: Graph + Sync>(
    graph: &G,
    defs: &(dyn Definitions + Sync),
    terminals: &[(String, G::Id)],
    parallel: bool,
) -> Vec<(Result<MaterialIr, Error>, Diagnostics)>
where
    G::Id: Send + Sync,
{
    let one = |cache: &mut DefinitionCache, (name, id): &(String, G::Id)| {
        let mut d = Diagnostics::new();
        let r = lower_node_cached(graph, defs, cache, *id, name, &mut d);
        (r, d)
    };
    #[cfg(feature = "parallel")]
    if parallel {
        use rayon::prelude::*;
        return terminals
            .par_iter()
            // Each rayon job builds its own cache; jobs of at least 128 materials keep
            // that one-time indexing small next to the lowering itself.
            .with_min_len(128)
            .map_init(DefinitionCache::default, one)
            .collect();
    }
    #[cfg(not(feature = "parallel"))]
    let _ = parallel;
    let mut cache = DefinitionCache::default();
    terminals.iter().map(|t| one(&mut cache, t)).collect()
}
