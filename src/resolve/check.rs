//! The check of a network against its definitions, run before resolution: every authored
//! parameter must be an input that its node's definition declares, every connection must
//! name an output that the upstream definition declares (VS024, with the closest declared
//! names), and every node type must be in the registry (VS020, once per type, with the
//! closest known ids). Whatever the network came from (RIB, JSON, code), the same check.

use crate::diag::{Diagnostic, Diagnostics, closest_names, hint_text, join_bounded};
use crate::network::{Network, NodeId, Param};
use crate::registry::tables::VstructTables;
use crate::registry::{IndexedDefinition, Registry};
use rustc_hash::FxHashMap as HashMap;
use std::sync::Arc;

/// How many distinct misspelt names get suggestions in one run; past it the warnings come
/// without them, so that a hostile input with many distinct names stays cheap (each
/// suggestion compares the name with every declared name of the type).
const MAX_SUGGESTED: usize = 10_000;

/// Parameters every RenderMan shading node accepts beside its definition's inputs: names
/// beginning with `__` are the renderer's own (`__materialid`, `__instanceid`, …) and are not
/// checked.
fn reserved(name: &str) -> bool {
    name.starts_with("__")
}

/// `name` without one trailing element index (`colors[2]` → `colors`).
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn without_index(name: &str) -> Option<&str> {
    let open = name.strip_suffix(']')?.rfind('[')?;
    let digits = &name[open + 1..name.len() - 1];
    (!digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit())).then(|| &name[..open])
}

/// A node type as the check sees it.
#[derive(Clone)]
struct Known {
    def: Arc<IndexedDefinition>,
    tables: Option<Arc<VstructTables>>,
}

impl Known {
    fn declares_input(&self, name: &str) -> bool {
        let declared = |n: &str| {
            self.def.input(n).is_some() || self.tables.as_ref().is_some_and(|t| t.is_input_head(n))
        };
        declared(name) || reserved(name) || without_index(name).is_some_and(declared)
    }

    fn declares_output(&self, name: &str) -> bool {
        let declared = |n: &str| {
            self.def.output(n).is_some()
                || self.tables.as_ref().is_some_and(|t| t.is_output_head(n))
        };
        declared(name) || without_index(name).is_some_and(declared)
    }

    fn input_names(&self) -> impl Iterator<Item = &str> {
        let heads = self.tables.iter().flat_map(|t| t.input_heads());
        let inputs = self.def.definition().inputs.iter().map(|p| p.name.as_str());
        inputs.chain(heads.filter(|h| self.def.input(h).is_none()))
    }

    fn output_names(&self) -> impl Iterator<Item = &str> {
        let heads = self.tables.iter().flat_map(|t| t.output_heads());
        let outputs = self
            .def
            .definition()
            .outputs
            .iter()
            .map(|p| p.name.as_str());
        outputs.chain(heads.filter(|h| self.def.output(h).is_none()))
    }
}

/// A node type the registry does not know, and what the check learnt of its nodes.
struct Unknown {
    nodes: Vec<NodeId>,
    /// The first input head one of its nodes feeds, as `node.head`.
    feeds: Option<(NodeId, String)>,
}

struct Checker<'a> {
    net: &'a Network,
    registry: &'a Registry,
    types: HashMap<&'a str, Option<Known>>,
    unknown: Vec<(&'a str, Unknown)>,
    /// Position of each unknown type in `unknown`.
    unknown_index: HashMap<&'a str, usize>,
    /// Suggestions per (type, input or output, name), computed once each.
    suggested: HashMap<(&'a str, bool, &'a str), String>,
    out: Diagnostics,
}

/// Check `net` against `registry`: VS024 (a warning) for every authored parameter its node's
/// definition does not declare as an input or input head (element names such as `colors[2]`
/// count as their array; `__`-prefixed names are the renderer's and are not checked) and
/// every connection naming an output the upstream definition does not declare; VS020 once per
/// node type the registry does not know (a warning when such a node feeds an input head or
/// the id looks like a misspelling of a known one, an info otherwise). Each names the
/// closest declared names. [`super::resolve`] runs it first; a network that is lowered
/// without being resolved can be checked with it directly.
///
/// ```
/// use vstructc::network::Network;
/// use vstructc::registry::Registry;
/// use vstructc::resolve::check_definitions;
///
/// let mut net = Network::new();
/// let layer = net.add_node("paint", "PxrLayer");
/// let surface = net.add_node("ball", "PxrLayerSurface");
/// net.connect(surface, "inputMaterail", layer, "pxrMaterialOut");
/// let diags = check_definitions(&net, &Registry::embedded());
/// let d = diags.with_code("VS024").next().unwrap();
/// assert!(d.message.contains("did you mean `inputMaterial`?"), "{}", d.message);
/// ```
pub fn check_definitions(net: &Network, registry: &Registry) -> Diagnostics {
    check_in_order(net, registry, &net.nodes_sorted())
}

/// [`check_definitions`] over `order`, the network's nodes in sorted order.
pub(super) fn check_in_order(net: &Network, registry: &Registry, order: &[NodeId]) -> Diagnostics {
    let mut c = Checker {
        net,
        registry,
        types: HashMap::default(),
        unknown: Vec::new(),
        unknown_index: HashMap::default(),
        suggested: HashMap::default(),
        out: Diagnostics::new(),
    };
    for &node in order {
        c.check_node(node);
    }
    c.report_unknown();
    c.out
}

impl<'a> Checker<'a> {
    fn known(&mut self, shader: &'a str) -> Option<Known> {
        if let Some(k) = self.types.get(shader) {
            return k.clone();
        }
        let known = self.registry.indexed(shader).map(|def| Known {
            def,
            tables: self.registry.tables(shader),
        });
        self.types.insert(shader, known.clone());
        known
    }

    fn check_node(&mut self, node: NodeId) {
        let net = self.net;
        let n = &net[node];
        let shader = n.shader();
        let Some(known) = self.known(shader) else {
            self.unknown_node(shader, node);
            return;
        };
        for p in n.params() {
            if !known.declares_input(p.name()) {
                self.undeclared_input(node, shader, &known, p);
            }
            for link in p.connections() {
                let Some(up) = link.upstream_node() else {
                    continue;
                };
                let up_shader = net[up].shader();
                match self.known(up_shader) {
                    None => {
                        // The upstream node is counted when the walk reaches it (every node
                        // is in `order`); a connection only says whether it feeds a head.
                        let head = known
                            .tables
                            .as_ref()
                            .is_some_and(|t| t.is_input_head(p.name()));
                        if head {
                            self.unknown_feeds(up_shader, node, p.name());
                        }
                    }
                    Some(up_known) => match link.output() {
                        Some(out) if !up_known.declares_output(out) => {
                            self.undeclared_output(node, p, up, up_shader, &up_known, out);
                        }
                        _ => {}
                    },
                }
            }
        }
    }

    fn suggestions(
        &mut self,
        shader: &'a str,
        known: &Known,
        input: bool,
        name: &'a str,
    ) -> String {
        let key = (shader, input, name);
        if let Some(s) = self.suggested.get(&key) {
            return s.clone();
        }
        if self.suggested.len() >= MAX_SUGGESTED {
            return String::new();
        }
        let names = if input {
            closest_names(name, known.input_names())
        } else {
            closest_names(name, known.output_names())
        };
        let text = hint_text(&names);
        self.suggested.insert(key, text.clone());
        text
    }

    fn undeclared_input(&mut self, node: NodeId, shader: &'a str, known: &Known, p: &'a Param) {
        let name = p.name();
        let hint = self.suggestions(shader, known, true, name);
        let what = if p.is_connected() { "connects" } else { "sets" };
        let n = &self.net[node];
        let d = Diagnostic::warning(
            "VS024",
            format!(
                "{} {what} `{name}`, which `{shader}` does not declare as an input{hint}",
                n.display_name()
            ),
        );
        self.push(d, node, name, p);
    }

    fn undeclared_output(
        &mut self,
        node: NodeId,
        p: &Param,
        up: NodeId,
        up_shader: &'a str,
        up_known: &Known,
        out: &'a str,
    ) {
        let hint = self.suggestions(up_shader, up_known, false, out);
        let d = Diagnostic::warning(
            "VS024",
            format!(
                "{}.{} is connected to {}.{out}, but `{up_shader}` declares no output `{out}`{hint}",
                self.net[node].display_name(),
                p.name(),
                self.net[up].display_name(),
            ),
        );
        self.push(d, node, p.name(), p);
    }

    fn push(&mut self, d: Diagnostic, node: NodeId, name: &str, p: &Param) {
        let n = &self.net[node];
        let d = match n.param_location(p).or_else(|| n.location().cloned()) {
            Some(l) => d.at(l),
            None => d,
        };
        self.out.push(d.with_node(n.handle()).with_param(name));
    }

    /// The entry of the unknown type `shader`, made on first sight.
    fn unknown_entry(&mut self, shader: &'a str) -> &mut Unknown {
        let next = self.unknown.len();
        let i = *self.unknown_index.entry(shader).or_insert(next);
        if i == next {
            self.unknown.push((
                shader,
                Unknown {
                    nodes: Vec::new(),
                    feeds: None,
                },
            ));
        }
        &mut self.unknown[i].1
    }

    /// Records `node`, of the unknown type `shader` (once per node: the walk visits each
    /// node once).
    fn unknown_node(&mut self, shader: &'a str, node: NodeId) {
        self.unknown_entry(shader).nodes.push(node);
    }

    /// Records that a node of the unknown type `shader` feeds the input head `head` of
    /// `down` (the first such head is reported).
    fn unknown_feeds(&mut self, shader: &'a str, down: NodeId, head: &str) {
        let entry = self.unknown_entry(shader);
        if entry.feeds.is_none() {
            entry.feeds = Some((down, head.to_string()));
        }
    }

    fn report_unknown(&mut self) {
        if self.unknown.is_empty() {
            return;
        }
        let ids = self.registry.ids();
        for (shader, entry) in std::mem::take(&mut self.unknown) {
            // In sorted node order already: the check walks the nodes in that order.
            let nodes = entry.nodes;
            let suggestions = closest_names(shader, ids.iter().copied());
            let names = join_bounded(nodes.len(), |i| self.net[nodes[i]].display_name());
            let of = if nodes.len() == 1 {
                format!("of {names}")
            } else {
                format!("of {} nodes ({names})", nodes.len())
            };
            let feeds = entry.feeds.as_ref().map(|(down, head)| {
                format!(
                    ", and it feeds the head {}.{head}",
                    self.net[*down].display_name()
                )
            });
            let message = format!(
                "node type `{shader}` {of} is not in the registry: its parameters are kept \
                 verbatim and not checked{}{}",
                feeds.as_deref().unwrap_or(""),
                hint_text(&suggestions)
            );
            let d = if feeds.is_some() || !suggestions.is_empty() {
                Diagnostic::warning("VS020", message)
            } else {
                Diagnostic::info("VS020", message)
            };
            let first = &self.net[nodes[0]];
            let d = match first.location() {
                Some(l) => d.at(l.clone()),
                None => d,
            };
            self.out.push(d.with_node(first.handle()));
        }
    }
}
