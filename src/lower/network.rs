//! Adapters from the crate's network model and registry to the lowering's [`Graph`] and
//! [`Definitions`] traits, and the per-material entry point used by `vstructc compile`.

use super::{Binding, Definitions, Graph, lower_node};
use crate::diag::{Diagnostic, Diagnostics, Error, Location};
use crate::ir::MaterialIr;
use crate::network::{Network, NodeId};
use crate::registry::{Definition, Registry};
use crate::types::Value;
use std::sync::Arc;

impl Graph for Network {
    type Id = NodeId;
    fn shader(&self, n: NodeId) -> &str {
        self[n].shader()
    }
    fn handle(&self, n: NodeId) -> &str {
        self[n].handle()
    }
    fn value(&self, n: NodeId, param: &str) -> Option<&Value> {
        Network::value(self, n, param)
    }
    fn connection(&self, n: NodeId, param: &str) -> Option<(NodeId, &str)> {
        self.input(n, param).connection
    }
    fn input(&self, n: NodeId, param: &str) -> Binding<'_, NodeId> {
        let p = self[n].param(param);
        Binding {
            value: p.and_then(|p| p.value()),
            connection: p.and_then(|p| {
                p.connections()
                    .iter()
                    .find_map(|l| l.upstream_node().map(|u| (u, l.output().unwrap_or(""))))
            }),
        }
    }
    fn location(&self, n: NodeId) -> Option<Location> {
        self[n].location().cloned()
    }
}

impl Definitions for Registry {
    fn definition(&self, shader: &str) -> Option<Arc<Definition>> {
        Registry::definition(self, shader)
    }
}

/// The terminals to lower: every material's bxdf terminal (or `only` by material name or
/// node handle), as `(name, node)`.
pub fn terminals(net: &Network, only: Option<&str>) -> Result<Vec<(String, NodeId)>, Error> {
    let mut out = Vec::new();
    for m in net.materials() {
        for t in &m.terminals {
            let Some(node) = t.link.upstream_node() else {
                continue;
            };
            if super::recipe_for(net[node].shader()).is_none() && t.name != "bxdf" {
                continue;
            }
            if only.is_none_or(|o| o == m.name || o == net[node].handle()) {
                out.push((m.name.clone(), node));
            }
        }
    }
    // Networks without material records: every node with a recipe is a terminal.
    if out.is_empty() && net.materials().is_empty() {
        for id in net.nodes_sorted() {
            if super::recipe_for(net[id].shader()).is_some()
                && only.is_none_or(|o| o == net[id].handle())
            {
                out.push((net[id].handle().to_string(), id));
            }
        }
    }
    if out.is_empty()
        && let Some(o) = only
    {
        // The names `only` could have meant: material names and terminal handles.
        let mut names: Vec<&str> = Vec::new();
        for m in net.materials() {
            names.push(&m.name);
            names.extend(
                m.terminals
                    .iter()
                    .filter_map(|t| t.link.upstream_node())
                    .map(|n| net[n].handle()),
            );
        }
        if net.materials().is_empty() {
            names.extend(
                net.node_ids()
                    .filter(|&id| super::recipe_for(net[id].shader()).is_some())
                    .map(|id| net[id].handle()),
            );
        }
        names.sort_unstable();
        names.dedup();
        let hint = crate::diag::did_you_mean(o, names);
        return Err(Error::Usage(format!(
            "no material or terminal named `{o}`{hint}"
        )));
    }
    Ok(out)
}

/// Lower one terminal of a resolved network.
pub fn lower_terminal(
    net: &Network,
    registry: &Registry,
    node: NodeId,
    name: &str,
    diags: &mut Diagnostics,
) -> Result<MaterialIr, Error> {
    lower_node(net, registry, node, name, diags)
}

/// LW030 for every placeholder (a connection into a head) that survived resolution.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) fn report_placeholders(net: &Network, registry: &Registry, diags: &mut Diagnostics) {
    for id in net.nodes_sorted() {
        let Some(tables) = registry.tables(net[id].shader()) else {
            continue;
        };
        for input in net.connected_inputs(id) {
            if tables.is_input_head(&input) {
                let mut d = Diagnostic::warning(
                    "LW030",
                    format!(
                        "unresolved placeholder `{}.{input}` reached the lowering; it is ignored",
                        net[id].handle()
                    ),
                );
                if let Some(l) = net[id].location() {
                    d = d.at(l.clone());
                }
                diags.push(d.with_node(net[id].handle()).with_param(input.as_str()));
            }
        }
    }
}
