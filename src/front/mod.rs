//! Front ends: readers that turn files into definitions ([`args`], [`oso`]) and networks
//! ([`rib`], [`json`]), and [`source`]: reading their bytes from files and streams within
//! bounds. [`read_network`] reads a network in either format ([`NetFormat`]).

pub mod args;
pub mod json;
pub mod oso;
pub mod rib;
pub mod source;

use crate::diag::{Diagnostics, Error};
use crate::limits::Limits;
use crate::network::{Network, ParamTypes};

/// The format of a network's text.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NetFormat {
    /// RenderMan RIB ([`rib`]).
    Rib,
    /// The JSON network form ([`json`]).
    Json,
}

impl NetFormat {
    /// The format of `bytes` read from `name`: by the extension (`.json`, `.rib`), else by
    /// the first non-blank byte (`{` is JSON, anything else RIB).
    ///
    /// ```
    /// use vstructc::front::NetFormat;
    /// assert_eq!(NetFormat::detect("scene.rib", b"{"), NetFormat::Rib);
    /// assert_eq!(NetFormat::detect("<stdin>", b"  {\"materials\": {}}"), NetFormat::Json);
    /// assert_eq!(NetFormat::detect("<stdin>", b"Bxdf"), NetFormat::Rib);
    /// ```
    pub fn detect(name: &str, bytes: &[u8]) -> NetFormat {
        match std::path::Path::new(name)
            .extension()
            .and_then(|e| e.to_str())
        {
            Some("json") => NetFormat::Json,
            Some("rib") => NetFormat::Rib,
            _ => match bytes.iter().find(|b| !b.is_ascii_whitespace()) {
                Some(b'{') => NetFormat::Json,
                _ => NetFormat::Rib,
            },
        }
    }
}

/// How [`read_network`] reads.
#[derive(Debug, Clone, Default)]
pub struct ReadOptions {
    /// RIB: single-quoted strings are an error (RB011) instead of an info.
    pub strict_rib: bool,
    /// Bounds on the input's size, its nodes, parameters and connections.
    pub limits: Limits,
}

/// Read a network in `format` from `bytes` (named `name` in diagnostics): the RIB or the
/// JSON reader, with the parameter types of `types` (a [`crate::registry::Registry`]).
/// Reader warnings go to `diags`; an error stops the read.
pub fn read_network(
    name: &str,
    bytes: &[u8],
    format: NetFormat,
    types: &dyn ParamTypes,
    options: &ReadOptions,
    diags: &mut Diagnostics,
) -> Result<Network, Error> {
    match format {
        NetFormat::Json => json::parse_json_limited(bytes, name, types, &options.limits, diags),
        NetFormat::Rib => rib::parse_rib(
            bytes,
            name,
            types,
            &rib::RibOptions {
                strict: options.strict_rib,
                limits: options.limits,
            },
            diags,
        ),
    }
}
