//! The whole way from a network's text to closure IR, or to compiled materials, in one call:
//! read (RIB, JSON or USD), resolve, optionally delete the placeholders that stayed unresolved,
//! report the ones lowering will ignore, pick the material terminals and lower them.
//!
//! The `vstructc` commands `resolve`, `compile`, `render` and `eval` are [`run`] plus
//! printing; a bridge holding a network in memory starts at [`lower`] or [`compile`].
//!
//! ```
//! use vstructc::Diagnostics;
//! use vstructc::front::NetFormat;
//! use vstructc::pipeline::{Lowering, PipelineOptions, run};
//! use vstructc::registry::Registry;
//!
//! let rib = br#"Bxdf "PxrSurface" "ball" "color diffuseColor" [0.8 0.2 0.2]"#;
//! let registry = Registry::embedded();
//! let options = PipelineOptions { lowering: Lowering::All, ..Default::default() };
//! let mut diags = Diagnostics::new();
//! let out = run("ball.rib", rib, NetFormat::Rib, &registry, &options, &mut diags).unwrap();
//! assert_eq!(out.materials.len(), 1);
//! assert!(!diags.has_errors());
//! ```

use crate::diag::{Diagnostics, Error};
use crate::front::{NetFormat, ReadOptions, read_network};
use crate::interp::Material;
use crate::ir::MaterialIr;
use crate::lower::network::{lower_terminal, report_placeholders, terminals};
use crate::network::Network;
use crate::registry::Registry;
use crate::resolve::{ResolveOptions, resolve};

/// Which materials [`run`] lowers.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub enum Lowering {
    /// None: read and resolve only.
    #[default]
    None,
    /// Every material's bxdf terminal.
    All,
    /// Only this material, by material name or terminal node handle; a name the network does
    /// not have is [`Error::Usage`].
    Only(String),
}

impl Lowering {
    fn only(&self) -> Option<&str> {
        match self {
            Lowering::Only(name) => Some(name),
            _ => None,
        }
    }
}

/// Options of [`run`].
#[derive(Debug, Clone, Default)]
pub struct PipelineOptions {
    /// Resolution options; their [`ResolveOptions::limits`] bound the reader too.
    pub resolve: ResolveOptions,
    /// RIB: single-quoted strings are an error (RB011) instead of an info.
    pub strict_rib: bool,
    /// Which materials to lower.
    pub lowering: Lowering,
}

/// What [`run`] produced.
#[derive(Debug)]
pub struct PipelineOutput {
    /// The resolved network.
    pub network: Network,
    /// The lowered materials, in material order (empty for [`Lowering::None`]).
    pub materials: Vec<MaterialIr>,
}

/// Read `bytes` (named `name` in diagnostics) as a network in `format`, resolve it against
/// `registry` and lower the materials `options` asks for. Diagnostics of every stage
/// (the reader's, the registry's, resolution's and lowering's) go to `diags`, sorted, each
/// identical one once ([`Diagnostics::dedup`]; the reader's RB019 is left out: resolution's
/// VS020 reports unknown node types for every format); a
/// material that cannot be lowered is an error diagnostic there, not a failure. Fails when
/// the input cannot be read ([`Error::Input`], [`Error::Limit`]) or
/// [`Lowering::Only`] names no material ([`Error::Usage`]).
pub fn run(
    name: &str,
    bytes: &[u8],
    format: NetFormat,
    registry: &Registry,
    options: &PipelineOptions,
    diags: &mut Diagnostics,
) -> Result<PipelineOutput, Error> {
    let read = ReadOptions {
        strict_rib: options.strict_rib,
        limits: options.resolve.limits,
    };
    let mut read_diags = Diagnostics::new();
    let network = read_network(name, bytes, format, registry, &read, &mut read_diags);
    // The RIB reader's RB019 (a shader not in the registry) says what resolution's definition
    // check says for every input format (VS020, once per type, with suggestions).
    diags.extend(read_diags.into_iter().filter(|d| d.code != "RB019"));
    let mut network = network?;
    let res = resolve(&mut network, registry, &options.resolve);
    diags.extend(registry.diagnostics());
    diags.extend(res.diagnostics);
    let materials = match options.lowering {
        Lowering::None => Vec::new(),
        _ => {
            report_placeholders(&network, registry, diags);
            lower(&network, registry, &options.lowering, diags)?
        }
    };
    diags.sort();
    diags.dedup();
    Ok(PipelineOutput { network, materials })
}

/// Lower the materials of a resolved `network` that `which` selects ([`Lowering::None`]
/// selects none). A material that cannot be lowered is an error diagnostic in `diags` and
/// is left out; fails only when [`Lowering::Only`] names no material ([`Error::Usage`]) or
/// on an error that is not about one material.
pub fn lower(
    network: &Network,
    registry: &Registry,
    which: &Lowering,
    diags: &mut Diagnostics,
) -> Result<Vec<MaterialIr>, Error> {
    if *which == Lowering::None {
        return Ok(Vec::new());
    }
    let mut out = Vec::new();
    for (name, node) in terminals(network, which.only())? {
        match lower_terminal(network, registry, node, &name, diags) {
            Ok(ir) => out.push(ir),
            Err(Error::Input(d)) => diags.push(*d),
            Err(e) => return Err(e),
        }
    }
    Ok(out)
}

/// [`lower`], then compile each material for the interpreter: from a resolved network to
/// [`Material`]s ready for [`Material::prepare`] and `eval`, `sample`, `albedo`. A material
/// that cannot be lowered or compiled is an error diagnostic in `diags` and is left out.
///
/// ```
/// use vstructc::glam::Vec3;
/// use vstructc::interp::ShadingPoint;
/// use vstructc::network::{Network, RequestKind};
/// use vstructc::pipeline::{Lowering, compile};
/// use vstructc::registry::Registry;
/// use vstructc::{BaseType, Diagnostics, Value};
///
/// let registry = Registry::embedded();
/// let mut net = Network::new();
/// let bxdf = net.add_node_of_kind("ball", "PxrSurface", RequestKind::Bxdf);
/// net.set_param(bxdf, "diffuseColor", Value::Triple(BaseType::Color, [0.8, 0.2, 0.2]));
/// let m = net.add_material("ball");
/// net.set_terminal(m, "bxdf", bxdf, None);
/// let mut diags = Diagnostics::new();
/// let materials = compile(&net, &registry, &Lowering::All, &mut diags).unwrap();
/// let point = ShadingPoint::new(Vec3::Z, Vec3::X, Vec3::Z);
/// let f = materials[0].prepare(&point).eval(Vec3::Z).f_cos;
/// assert!(f.x > f.y);
/// ```
pub fn compile(
    network: &Network,
    registry: &Registry,
    which: &Lowering,
    diags: &mut Diagnostics,
) -> Result<Vec<Material>, Error> {
    let mut out = Vec::new();
    for ir in lower(network, registry, which, diags)? {
        match Material::new(&ir) {
            Ok(m) => out.push(m),
            Err(Error::Input(d)) => diags.push(*d),
            Err(e) => return Err(e),
        }
    }
    Ok(out)
}
