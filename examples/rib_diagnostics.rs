//! RIB in, RIB out, with diagnostics: read a RIB scene, resolve its vstruct connections with
//! the library's pipeline, write the resolved RIB to standard output (everything outside the
//! shading networks is copied unchanged) and the diagnostics, with the node and parameter
//! each is about, to standard error.
//!
//! Run with `cargo run --example rib_diagnostics [-- scene.rib]` (default: a small scene
//! built in, with one vstruct connection that cannot be resolved).

use std::io::Write;
use vstructc::back::rib::write_rib;
use vstructc::front::NetFormat;
use vstructc::pipeline::{PipelineOptions, run};
use vstructc::registry::Registry;
use vstructc::{Diagnostics, Severity};

/// A layer mixed into a surface, and a second mixer input wired to a node that has no
/// `pxrMaterialOut` (VS010: the placeholder is kept).
const SCENE: &str = r#"##RenderMan RIB
version 3.04
WorldBegin
	AttributeBegin
		Attribute "identifier" "string name" ["ball"]
		Pattern "PxrLayer" "base"
			"int enableDiffuse" [1]
			"color diffuseColor" [0.2 0.5 0.2]
		Pattern "vsConstant" "notALayer"
		Pattern "PxrLayerMixer" "mixer"
			"reference vstruct baselayer" ["base:pxrMaterialOut"]
			"int layer1Enabled" [1]
			"reference vstruct layer1" ["notALayer:pxrMaterialOut"]
		Bxdf "PxrLayerSurface" "surface"
			"reference vstruct inputMaterial" ["mixer:pxrMaterialOut"]
		Sphere 1 -1 1 360
	AttributeEnd
WorldEnd
"#;

fn main() -> std::process::ExitCode {
    let (name, bytes) = match std::env::args().nth(1) {
        Some(path) => match std::fs::read(&path) {
            Ok(b) => (path, b),
            Err(e) => {
                eprintln!("error: {path}: {e}");
                return std::process::ExitCode::from(1);
            }
        },
        None => ("scene.rib".to_string(), SCENE.as_bytes().to_vec()),
    };
    let registry = Registry::embedded();
    let mut diags = Diagnostics::new();
    let out = match run(
        &name,
        &bytes,
        NetFormat::Rib,
        &registry,
        &PipelineOptions::default(),
        &mut diags,
    ) {
        Ok(out) => out,
        Err(e) => {
            eprintln!("error: {e}");
            return std::process::ExitCode::from(1);
        }
    };
    for d in &diags {
        eprintln!("{}", d.render_human());
        if let Some(node) = &d.node {
            eprintln!(
                "  node `{node}`{}; {}: {}",
                d.param
                    .as_deref()
                    .map(|p| format!(", parameter `{p}`"))
                    .unwrap_or_default(),
                d.code,
                d.code.meaning().unwrap_or("(no documented meaning)")
            );
        }
    }
    let mut stdout = std::io::stdout().lock();
    if let Err(e) = write_rib(&bytes, &out.network, &registry, &mut stdout) {
        eprintln!("error: {e}");
        return std::process::ExitCode::from(1);
    }
    let _ = stdout.flush();
    let worst = diags.iter().map(|d| d.severity).max();
    match worst {
        Some(Severity::Error) => std::process::ExitCode::from(1),
        _ => std::process::ExitCode::SUCCESS,
    }
}
