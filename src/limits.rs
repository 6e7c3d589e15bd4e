//! Resource limits a bridge can set: one [`Limits`] value accepted by the readers, the
//! registry, resolution and the preview renderer.
//!
//! Every bound that protects vstructc from hostile or broken input lives here with a
//! documented default. Exceeding one stops the affected input with a typed
//! [`LimitExceeded`] (wrapped in [`crate::Error::Limit`]) that names the limit, the value
//! found and the maximum, and carries a positioned diagnostic with code `LM001`.
//!
//! The defaults are far above anything a production scene needs (a 10,000-material scene has
//! 40,000 nodes; the largest shipped definition has a few hundred parameters) and far below
//! what would exhaust a workstation, so a bridge rarely needs to change them; one that reads
//! untrusted input may lower them.
//!
//! ```
//! use vstructc::limits::{Limit, Limits};
//! let strict = Limits { nodes: 1_000, ..Limits::default() };
//! assert!(strict.check(Limit::Nodes, 1_000).is_ok());
//! let err = strict.check(Limit::Nodes, 1_001).unwrap_err();
//! assert_eq!(err.limit, Limit::Nodes);
//! assert_eq!((err.value, err.max), (1_001, 1_000));
//! ```

// The names of the bounds and their error are `diag`'s (`Error::Limit` holds one), so that
// the arrow between the two modules points one way: `limits` uses `diag`.
pub use crate::diag::limit::{Limit, LimitExceeded};

/// The bounds applied to one run. `Default` gives the documented defaults.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Limits {
    /// Bytes of one definition file (`.args`, `.oso`). Default 64 MiB.
    pub definition_file_bytes: u64,
    /// Bytes of one network input (RIB, JSON), including one read from standard input or a
    /// pipe. Default 4 GiB.
    pub network_file_bytes: u64,
    /// Shader nodes in one network. Default 16,777,216 (2^24).
    pub nodes: u64,
    /// Connections on one input of one node (fan-in). Default 1,048,576 (2^20).
    pub connections_per_input: u64,
    /// Parameters (authored values and connected inputs) of one node, and parameters
    /// declared by one definition. Default 1,048,576 (2^20).
    pub params_per_node: u64,
    /// Comparison and `is` terms in one conditional expression. Default 4,194,304 (2^22).
    pub expr_terms: u64,
    /// Parenthesis nesting in one conditional expression. Default 64.
    pub expr_depth: u64,
    /// Pixels of one preview image (one ball, `size × size`). Default 67,108,864
    /// (8192 × 8192).
    pub preview_pixels: u64,
}

/// The default of [`Limits::expr_depth`]: the deepest parenthesis nesting of a conditional
/// (real expressions use 1–3 levels; the parser recurses once per level).
pub(crate) const DEFAULT_EXPR_DEPTH: u64 = 64;

impl Default for Limits {
    fn default() -> Self {
        Limits {
            definition_file_bytes: 64 << 20,
            network_file_bytes: 4 << 30,
            nodes: 1 << 24,
            connections_per_input: 1 << 20,
            params_per_node: 1 << 20,
            expr_terms: 1 << 22,
            expr_depth: DEFAULT_EXPR_DEPTH,
            preview_pixels: 8192 * 8192,
        }
    }
}

impl Limits {
    /// The maximum for `limit`.
    pub fn max(&self, limit: Limit) -> u64 {
        match limit {
            Limit::DefinitionFileBytes => self.definition_file_bytes,
            Limit::NetworkFileBytes => self.network_file_bytes,
            Limit::Nodes => self.nodes,
            Limit::ConnectionsPerInput => self.connections_per_input,
            Limit::ParamsPerNode => self.params_per_node,
            Limit::ExprTerms => self.expr_terms,
            Limit::ExprDepth => self.expr_depth,
            Limit::PreviewPixels => self.preview_pixels,
        }
    }

    /// `Ok` when `value` is within `limit`, else the typed error (with no location; add one
    /// with [`LimitExceeded::at`]).
    pub fn check(&self, limit: Limit, value: u64) -> Result<(), LimitExceeded> {
        let max = self.max(limit);
        if value <= max {
            Ok(())
        } else {
            Err(LimitExceeded {
                limit,
                value,
                max,
                location: None,
            })
        }
    }
}
