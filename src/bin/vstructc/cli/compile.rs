//! `vstructc compile [--args DIR]... [--emit ir|lobes|dot] [--material NAME] INPUT`: read a
//! RIB, JSON or USD network, resolve it (a no-op when it holds no placeholders), lower each
//! material (or only `--material`) and print its IR, flat lobe list or closure tree.
//!
//! The lobe list's numeric weights use the interpreter's albedo tables
//! ([`TableAlbedo`]); the snapshot tests print with `SimpleAlbedo` (smooth-surface estimates)
//! so that their numbers can be checked by hand.

use super::CommonOptions;
use super::input::{print_stdout, run_pipeline};
use super::json::{self, TypedValue, type_word};
use super::material::NO_MATERIAL;
use clap::ValueEnum;
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;
use vstructc::interp::TableAlbedo;
use vstructc::ir::{MaterialIr, Node};
use vstructc::pipeline::Lowering;

/// What `compile` prints.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ValueEnum)]
pub enum Emit {
    /// The IR: inputs, frames, program, closure nodes.
    #[default]
    Ir,
    /// The flat lobe list with symbolic and numeric weights.
    Lobes,
    /// Graphviz dot of the closure tree.
    Dot,
}

/// Arguments of `vstructc compile`.
#[derive(Debug, clap::Args)]
pub struct CompileArgs {
    /// The network: a RIB, JSON or USD file, or `-` for standard input.
    pub input: PathBuf,
    /// What to print.
    #[arg(long, value_enum, default_value_t = Emit::Ir)]
    pub emit: Emit,
    /// Lower only this material (material name or terminal node handle).
    #[arg(long, value_name = "NAME")]
    pub material: Option<String>,
    /// Resolve without evaluating conditionals.
    #[arg(long)]
    pub no_conditions: bool,
    /// Single-quoted RIB strings are an error instead of an info (RB011).
    #[arg(long)]
    pub strict_rib: bool,
    /// Print a JSON document on standard output (docs/json.md): each material's recipe,
    /// external inputs, closure nodes and lobes, and the `--emit` text.
    #[arg(long)]
    pub json: bool,
}

/// The `--json` document.
#[derive(Debug, Serialize)]
pub struct CompileDoc {
    /// What `text` holds: `ir`, `lobes` or `dot`.
    pub emit: &'static str,
    /// The lowered materials, in input order.
    pub materials: Vec<MaterialDoc>,
}

/// One lowered material.
#[derive(Debug, Serialize)]
pub struct MaterialDoc {
    /// Material name (or terminal node handle).
    pub name: String,
    /// The lowering recipe: `pxr_surface`, `vray_mtl`, `physical_material`, `mia_material`.
    pub recipe: &'static str,
    /// External per-point inputs (`--input NAME=VALUE` of `render` and `eval`).
    pub inputs: Vec<InputDoc>,
    /// The closure nodes; node 0 is the root (none: the material is black).
    pub nodes: Vec<NodeDoc>,
    /// Number of BSDF lobes.
    pub lobes: usize,
    /// The material as `--emit` prints it.
    pub text: String,
}

/// One external input slot.
#[derive(Debug, Serialize)]
pub struct InputDoc {
    /// Slot name (`node.output`).
    pub name: String,
    /// Type word of the parameter it feeds.
    #[serde(rename = "type")]
    pub ty: String,
    /// The value used when none is given.
    pub fallback: TypedValue,
}

/// One closure node.
#[derive(Debug, Serialize)]
pub struct NodeDoc {
    /// Index in `nodes`.
    pub id: u32,
    /// `leaf`, `emission`, `transparent`, `layer`, `mix`, `add` or `multiply`.
    #[serde(rename = "type")]
    pub ty: &'static str,
    /// Leaves: the lobe kind (`lambert`, `ggx`, …); null otherwise.
    pub kind: Option<&'static str>,
    /// Leaves: what the lobe is in the source material (`diffuse`, …); null otherwise.
    pub label: Option<String>,
    /// Child node ids in order (`layer`: top, base; `mix`, `add`: a, b; `multiply`: f).
    pub children: Vec<u32>,
}

fn emit_word(emit: Emit) -> &'static str {
    match emit {
        Emit::Ir => "ir",
        Emit::Lobes => "lobes",
        Emit::Dot => "dot",
    }
}

/// The `--json` form of one lowered material.
pub fn material_doc(ir: &MaterialIr, emit: Emit) -> MaterialDoc {
    let nodes: Vec<NodeDoc> = ir
        .nodes
        .iter()
        .enumerate()
        .map(|(i, n)| {
            let (ty, kind, label) = match n {
                Node::Leaf(l) => ("leaf", Some(l.kind.name()), Some(l.label.clone())),
                Node::Emission { .. } => ("emission", None, None),
                Node::Transparent { .. } => ("transparent", None, None),
                Node::Layer { .. } => ("layer", None, None),
                Node::Mix { .. } => ("mix", None, None),
                Node::Add { .. } => ("add", None, None),
                Node::Multiply { .. } => ("multiply", None, None),
            };
            NodeDoc {
                id: i as u32,
                ty,
                kind,
                label,
                children: n.children().iter().map(|c| c.0).collect(),
            }
        })
        .collect();
    MaterialDoc {
        name: ir.name.clone(),
        recipe: ir.recipe.name(),
        inputs: ir
            .inputs
            .iter()
            .map(|slot| InputDoc {
                name: slot.name.clone(),
                ty: type_word(&slot.ty),
                fallback: TypedValue::of(&slot.fallback),
            })
            .collect(),
        lobes: ir.nodes.iter().filter(|n| n.is_lobe()).count(),
        nodes,
        text: render(ir, emit),
    }
}

/// Render one lowered material.
pub fn render(ir: &MaterialIr, emit: Emit) -> String {
    match emit {
        Emit::Ir => ir.text(),
        Emit::Lobes => ir.lobes_text(&TableAlbedo),
        Emit::Dot => vstructc::back::dot::to_dot(ir),
    }
}

/// Run `vstructc compile`.
pub fn run(args: &CompileArgs, common: &CommonOptions) -> ExitCode {
    let lowering = match &args.material {
        Some(name) => Lowering::Only(name.clone()),
        None => Lowering::All,
    };
    let ran = match run_pipeline(
        &args.input,
        args.no_conditions,
        args.strict_rib,
        false,
        lowering,
        common,
    ) {
        Ok(ran) => ran,
        Err(status) => return status,
    };
    let materials = &ran.output.materials;
    if materials.is_empty() {
        let status = super::report(&ran.diags, common);
        if status != ExitCode::SUCCESS {
            return status;
        }
        eprintln_quiet!("error: {NO_MATERIAL}");
        return ExitCode::from(1);
    }
    let out = if args.json {
        let doc = CompileDoc {
            emit: emit_word(args.emit),
            materials: materials
                .iter()
                .map(|ir| material_doc(ir, args.emit))
                .collect(),
        };
        match json::to_text(&doc) {
            Ok(text) => text,
            Err(e) => {
                super::report(&ran.diags, common);
                eprintln_quiet!("error: {e}");
                return ExitCode::from(1);
            }
        }
    } else {
        materials
            .iter()
            .map(|ir| render(ir, args.emit) + "\n")
            .collect()
    };
    if let Err(failed) = print_stdout(&out, common) {
        super::report(&ran.diags, common);
        return failed;
    }
    super::report(&ran.diags, common)
}
