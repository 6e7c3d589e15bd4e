//! Checking a network against [`Limits`]: its node count, each node's parameter count and
//! each input's connection count. Readers call it on what they read and resolution on what
//! it is given, so a network built in code by a bridge meets the same bounds as a file.

use super::{Network, NodeId};
use crate::diag::Location;
use crate::limits::{Limit, LimitExceeded, Limits};

impl Network {
    /// The first bound of `limits` this network exceeds (nodes, then parameters per node,
    /// then connections per input, in node order), located at the node or parameter when
    /// it came from a file. Linear in the size of the network.
    ///
    /// ```
    /// use vstructc::limits::{Limit, Limits};
    /// use vstructc::network::Network;
    /// let mut net = Network::new();
    /// let a = net.add_node("a", "PxrLayer");
    /// let b = net.add_node("b", "PxrLayerMixer");
    /// net.connect(b, "baselayer", a, "pxrMaterialOut");
    /// net.connect(b, "baselayer", a, "pxrMaterialOut");
    /// assert!(net.check_limits(&Limits::default()).is_ok());
    /// let strict = Limits { connections_per_input: 1, ..Limits::default() };
    /// let e = net.check_limits(&strict).unwrap_err();
    /// assert_eq!((e.limit, e.value), (Limit::ConnectionsPerInput, 2));
    /// ```
    pub fn check_limits(&self, limits: &Limits) -> Result<(), LimitExceeded> {
        limits.check(Limit::Nodes, self.node_count() as u64)?;
        self.node_ids()
            .try_for_each(|id| self.check_node_limits(id, limits))
    }

    /// The first bound of `limits` node `id` exceeds: its parameter count, then each
    /// input's connection count in order ([`Network::check_limits`] for one node; the RIB
    /// reader checks each node as it adds it).
    pub(crate) fn check_node_limits(
        &self,
        id: NodeId,
        limits: &Limits,
    ) -> Result<(), LimitExceeded> {
        let node = &self[id];
        let at_node = |e: LimitExceeded| match node.location() {
            Some(loc) => e.at(loc.clone()),
            None => e.at(Location::file(format!("node {}", node.handle()))),
        };
        let params = node.all_params();
        limits
            .check(Limit::ParamsPerNode, params.len() as u64)
            .map_err(at_node)?;
        for p in params {
            limits
                .check(Limit::ConnectionsPerInput, p.connections().len() as u64)
                .map_err(|e| match node.param_location(p) {
                    Some(loc) => e.at(loc),
                    None => at_node(e),
                })?;
        }
        Ok(())
    }
}
