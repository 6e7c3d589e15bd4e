//! The names of the bounds and the error of exceeding one: what
//! [`Error::Limit`](super::Error::Limit) holds.
//!
//! They live here, below `limits`, so that `diag` imports nothing above it: `limits` builds
//! these errors and re-exports both types, which is where a bridge names them
//! (`vstructc::limits::{Limit, LimitExceeded}`).

use super::{Diagnostic, Location};
use std::fmt;

/// One of the bounds of [`Limits`](crate::limits::Limits).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Limit {
    /// [`Limits::definition_file_bytes`](crate::limits::Limits::definition_file_bytes).
    DefinitionFileBytes,
    /// [`Limits::network_file_bytes`](crate::limits::Limits::network_file_bytes).
    NetworkFileBytes,
    /// [`Limits::nodes`](crate::limits::Limits::nodes).
    Nodes,
    /// [`Limits::connections_per_input`](crate::limits::Limits::connections_per_input).
    ConnectionsPerInput,
    /// [`Limits::params_per_node`](crate::limits::Limits::params_per_node).
    ParamsPerNode,
    /// [`Limits::expr_terms`](crate::limits::Limits::expr_terms).
    ExprTerms,
    /// [`Limits::expr_depth`](crate::limits::Limits::expr_depth).
    ExprDepth,
    /// [`Limits::preview_pixels`](crate::limits::Limits::preview_pixels).
    PreviewPixels,
}

impl Limit {
    /// The field name in [`Limits`](crate::limits::Limits), as messages print it.
    pub fn name(self) -> &'static str {
        match self {
            Limit::DefinitionFileBytes => "definition_file_bytes",
            Limit::NetworkFileBytes => "network_file_bytes",
            Limit::Nodes => "nodes",
            Limit::ConnectionsPerInput => "connections_per_input",
            Limit::ParamsPerNode => "params_per_node",
            Limit::ExprTerms => "expr_terms",
            Limit::ExprDepth => "expr_depth",
            Limit::PreviewPixels => "preview_pixels",
        }
    }

    /// What the limit counts, for messages ("bytes", "nodes", ...).
    pub fn unit(self) -> &'static str {
        match self {
            Limit::DefinitionFileBytes | Limit::NetworkFileBytes => "bytes",
            Limit::Nodes => "nodes",
            Limit::ConnectionsPerInput => "connections on one input",
            Limit::ParamsPerNode => "parameters",
            Limit::ExprTerms => "terms",
            Limit::ExprDepth => "levels of parentheses",
            Limit::PreviewPixels => "pixels",
        }
    }
}

impl fmt::Display for Limit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A [`Limits`](crate::limits::Limits) bound was exceeded: which one, the value found and the maximum.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{value} {unit} exceed the limit {name} = {max}", unit = limit.unit(), name = limit.name())]
pub struct LimitExceeded {
    /// The bound.
    pub limit: Limit,
    /// The value found (for streamed input, the count when reading stopped).
    pub value: u64,
    /// The bound's maximum.
    pub max: u64,
    /// Where the input exceeded it, when known.
    pub location: Option<Location>,
}

impl LimitExceeded {
    /// The same error at `location`.
    pub fn at(mut self, location: Location) -> Self {
        self.location = Some(location);
        self
    }

    /// The error as a positioned diagnostic (code `LM001`, severity error).
    pub fn to_diagnostic(&self) -> Diagnostic {
        let d = Diagnostic::error("LM001", self.to_string());
        match &self.location {
            Some(loc) => d.at(loc.clone()),
            None => d,
        }
    }
}
