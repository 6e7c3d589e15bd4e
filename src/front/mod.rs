//! Front ends: readers that turn files into definitions ([`args`], [`oso`]) and networks
//! ([`rib`], [`json`], `usd`), and [`source`]: reading their bytes from files and streams within
//! bounds. [`read_network`] reads a network in either format ([`NetFormat`]).

pub mod args;
pub mod json;
pub mod oso;
mod remembered;
pub mod rib;
pub mod source;
#[cfg(feature = "usd")]
pub mod usd;

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
    /// A USD stage: `.usda`, `.usdc` or `.usdz` (`front::usd`, feature `usd`).
    Usd,
}

impl NetFormat {
    /// The format of `bytes` read from `name`, by the extension, else by the content. USD is
    /// `.usda`, `.usdc`, `.usdz`, `.usd`, or the `#usda`, `PXR-USDC` and zip signatures; it is
    /// [`NetFormat::Usd`], or IO003 when the library is built without its `usd` feature.
    /// MaterialX (`.mtlx`, or XML whose root is `<materialx>`) is IO003, which names the
    /// format, instead of the RIB reader's complaint about its first character. Otherwise
    /// `.json` and `.rib` decide, else the first non-blank byte: `{` is JSON, anything else
    /// RIB.
    ///
    /// ```
    /// use vstructc::front::NetFormat;
    /// assert_eq!(NetFormat::detect("a.rib", b"Bxdf").unwrap(), NetFormat::Rib);
    /// assert_eq!(NetFormat::detect("scene.rib", b"{").unwrap(), NetFormat::Rib);
    /// assert_eq!(NetFormat::detect("<stdin>", b"  {\"materials\": {}}").unwrap(), NetFormat::Json);
    /// # #[cfg(feature = "usd")] {
    /// assert_eq!(NetFormat::detect("look.usda", b"#usda 1.0\n").unwrap(), NetFormat::Usd);
    /// assert_eq!(NetFormat::detect("<stdin>", b"  #usda 1.0").unwrap(), NetFormat::Usd);
    /// assert_eq!(NetFormat::detect("<stdin>", b"PXR-USDC").unwrap(), NetFormat::Usd);
    /// # }
    /// let e = NetFormat::detect("<stdin>", b"<?xml version=\"1.0\"?>\n<materialx version=\"1.38\">").unwrap_err();
    /// assert!(e.to_string().contains("MaterialX"), "{e}");
    /// ```
    pub fn detect(name: &str, bytes: &[u8]) -> Result<NetFormat, Error> {
        let ext = std::path::Path::new(name)
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        let head = &bytes[..bytes.len().min(1024)];
        let unsupported = |message: String| -> Result<NetFormat, Error> {
            Err(crate::diag::Diagnostic::error("IO003", message)
                .at(crate::diag::Location::file(name))
                .into())
        };
        if let Some(what) = usd_signature(ext.as_deref(), head) {
            if cfg!(feature = "usd") {
                return Ok(NetFormat::Usd);
            }
            return unsupported(format!(
                "USD input ({what}) needs vstructc built with its `usd` feature; this build reads \
                 RIB and the JSON network form"
            ));
        }
        if let Some(what) = materialx_signature(ext.as_deref(), head) {
            return unsupported(format!(
                "MaterialX input is not supported ({what}); vstructc reads RIB, the JSON network \
                 form and USD"
            ));
        }
        Ok(NetFormat::rib_or_json(name, bytes))
    }

    /// RIB or JSON: by the extension (`.json`, `.rib`), else by the first non-blank byte.
    fn rib_or_json(name: &str, bytes: &[u8]) -> NetFormat {
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

/// How a USD input shows itself (lower-case extension, first bytes), in words.
fn usd_signature(ext: Option<&str>, head: &[u8]) -> Option<String> {
    match ext {
        Some(e @ ("usda" | "usdc" | "usdz" | "usd")) => Some(format!("`.{e}`")),
        _ if head.trim_ascii_start().starts_with(b"#usda") => {
            Some("USD text (`#usda`)".to_string())
        }
        _ if head.starts_with(b"PXR-USDC") => Some("binary USD (`PXR-USDC`)".to_string()),
        _ if head.starts_with(b"PK\x03\x04") => Some("a zip archive, as USDZ is".to_string()),
        _ => None,
    }
}

/// How a MaterialX input shows itself (lower-case extension, first bytes), in words.
fn materialx_signature(ext: Option<&str>, head: &[u8]) -> Option<&'static str> {
    if ext == Some("mtlx") {
        Some("`.mtlx`")
    } else if head.trim_ascii_start().starts_with(b"<")
        && memchr::memmem::find(head, b"<materialx").is_some()
    {
        Some("XML with a `<materialx>` root")
    } else {
        None
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

/// Read a network in `format` from `bytes` (named `name` in diagnostics): the RIB, JSON or
/// USD reader, with the parameter types of `types` (a [`crate::registry::Registry`]; `Sync`,
/// as the RIB reader may ask it from two threads). Reader warnings go to `diags`; an error
/// stops the read.
pub fn read_network(
    name: &str,
    bytes: &[u8],
    format: NetFormat,
    types: &(dyn ParamTypes + Sync),
    options: &ReadOptions,
    diags: &mut Diagnostics,
) -> Result<Network, Error> {
    match format {
        #[cfg(feature = "usd")]
        NetFormat::Usd => usd::parse_usd(bytes, name, types, &options.limits, diags),
        #[cfg(not(feature = "usd"))]
        NetFormat::Usd => Err(crate::diag::Diagnostic::error(
            "IO003",
            "USD input needs vstructc built with its `usd` feature",
        )
        .at(crate::diag::Location::file(name))
        .into()),
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
