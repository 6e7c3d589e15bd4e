//! Registry search path, priority, laziness and in-memory definitions (formats.md §1.4).

use std::path::PathBuf;
use std::process::Command;
use std::sync::Arc;
use vstructc::registry::{
    Definition, Prefer, Registry, RegistryOptions, SourceKind, embedded_files,
};
use vstructc::{Diagnostics, Severity};

fn search(sub: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/args/search")
        .join(sub)
}

fn count(diags: &Diagnostics, code: &str) -> usize {
    diags.count(code)
}

#[test]
fn first_path_wins_and_later_duplicate_is_rg001() {
    let reg = Registry::new(RegistryOptions::only([search("a"), search("b")]));
    let def = reg.definition("Dup").unwrap();
    assert!(def.input("fromA").is_some());
    assert_eq!(def.kind, "pattern");
    let diags = reg.diagnostics();
    let rg001: Vec<_> = diags.with_code("RG001").collect();
    assert_eq!(rg001.len(), 1, "{diags:?}");
    assert_eq!(rg001[0].severity, Severity::Warning);
    let loc = rg001[0].location.as_ref().unwrap();
    assert!(loc.file.ends_with("b/Dup.args"), "{loc}");

    // Reversed order, reversed winner.
    let reg = Registry::new(RegistryOptions::only([search("b"), search("a")]));
    assert!(reg.definition("Dup").unwrap().input("fromB").is_some());
}

#[test]
fn folders_are_scanned_recursively_in_byte_order() {
    let reg = Registry::new(RegistryOptions::only([search("a")]));
    assert_eq!(reg.ids(), ["Dup", "Same"]);
    let def = reg.definition("Same").unwrap();
    assert!(def.input("fromSub1").is_some(), "sub1 sorts before sub2");
    let sources = reg.sources("Same");
    assert_eq!(sources.len(), 2);
    assert!(sources[0].1.ends_with("sub1/Same.args"));
}

#[test]
fn loading_is_lazy_and_cached() {
    let reg = Registry::new(RegistryOptions::only([search("b")]));
    // Broken.args is rejected (AR003) only once it is looked up.
    assert!(reg.diagnostics().is_empty());
    assert!(reg.contains("Broken"));
    assert!(reg.definition("Broken").is_none());
    let diags = reg.diagnostics();
    assert_eq!(count(&diags, "AR003"), 1, "{diags:?}");
    // Asking again neither re-parses nor repeats the error.
    assert!(reg.definition("Broken").is_none());
    assert_eq!(count(&reg.diagnostics(), "AR003"), 1);
    // The same Arc comes back for a good id, also from several threads.
    let first = reg.definition("Dup").unwrap();
    std::thread::scope(|s| {
        for _ in 0..4 {
            s.spawn(|| {
                let d = reg.definition("Dup").unwrap();
                assert!(Arc::ptr_eq(&d, &first));
                let t1 = reg.tables("Dup").unwrap();
                let t2 = reg.tables("Dup").unwrap();
                assert!(Arc::ptr_eq(&t1, &t2));
            });
        }
    });
    assert!(reg.definition("Nope").is_none());
    assert!(reg.tables("Nope").is_none());
}

#[test]
fn missing_explicit_path_is_ar005() {
    let reg = Registry::new(RegistryOptions::only([search("does-not-exist")]));
    let diags = reg.diagnostics();
    assert_eq!(count(&diags, "AR005"), 1);
    assert!(diags.has_errors());
}

fn oso_twin(id: &str) -> Definition {
    Definition {
        id: id.to_string(),
        kind: "pattern".into(),
        source: SourceKind::Oso,
        path: Arc::from(format!("<memory>/{id}.oso")),
        inputs: Vec::new(),
        outputs: Vec::new(),
        metadata: Default::default(),
    }
}

#[test]
fn oso_shadows_args_by_default_with_rg002() {
    let mut reg = Registry::new(RegistryOptions::only([search("a")]));
    reg.add_definition(oso_twin("Dup"));
    let def = reg.definition("Dup").unwrap();
    assert_eq!(def.source, SourceKind::Oso);
    let diags = reg.diagnostics();
    let rg002: Vec<_> = diags.with_code("RG002").collect();
    assert_eq!(rg002.len(), 1, "{diags:?}");
    assert_eq!(rg002[0].severity, Severity::Info);
    assert!(
        rg002[0]
            .location
            .as_ref()
            .unwrap()
            .file
            .ends_with("Dup.args")
    );
}

#[test]
fn prefer_args_reverses_the_priority() {
    let mut opts = RegistryOptions::only([search("a")]);
    opts.prefer = Prefer::Args;
    let mut reg = Registry::new(opts);
    reg.add_definition(oso_twin("Dup"));
    let def = reg.definition("Dup").unwrap();
    assert_eq!(def.source, SourceKind::Args);
    assert_eq!(count(&reg.diagnostics(), "RG002"), 1);
}

#[test]
fn in_memory_definitions_come_first_and_replace_cached_ones() {
    let mut reg = Registry::new(RegistryOptions::only([search("a")]));
    assert!(reg.definition("Dup").unwrap().input("fromA").is_some());
    let text = r#"<args format="1.0"><shaderType name="bxdf"/>
        <param name="inputMaterial" type="float"><tags><tag value="vstruct"/></tags></param>
        <param name="gain" type="float" vstructmember="inputMaterial.gain" default="1"/>
        </args>"#;
    reg.add_args_text("Dup", text).unwrap();
    let def = reg.definition("Dup").unwrap();
    assert_eq!(&*def.path, "<memory>/Dup.args");
    assert_eq!(def.kind, "bxdf");
    let t = reg.tables("Dup").unwrap();
    assert_eq!(&*t.members_in("inputMaterial")[0].property, "gain");
    // Bad text is refused with its diagnostic and leaves the registry unchanged.
    let err = reg
        .add_args_text("Other", "<args><param/></args>")
        .unwrap_err();
    assert_eq!(err.code(), Some("AR003"));
    assert!(!reg.contains("Other"));
}

#[test]
fn embedded_definitions_load_without_errors() {
    let reg = Registry::embedded();
    let ids = reg.ids();
    assert_eq!(ids.len(), embedded_files().len());
    for (rel, _) in embedded_files() {
        let stem = rel.rsplit('/').next().unwrap().trim_end_matches(".args");
        assert!(ids.contains(&stem), "{rel}");
        let def = reg
            .definition(stem)
            .unwrap_or_else(|| panic!("{rel}: {:?}", reg.diagnostics()));
        assert_eq!(&*def.path, format!("<embedded>/{rel}"));
    }
    assert!(!reg.diagnostics().has_errors(), "{:?}", reg.diagnostics());
}

#[test]
fn explicit_paths_shadow_embedded_ones_quietly() {
    let (rel, _) = embedded_files().first().expect("definitions are embedded");
    let stem = rel.rsplit('/').next().unwrap().trim_end_matches(".args");
    let dir = std::env::temp_dir().join(format!("vstructc-shadow-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join(format!("{stem}.args")),
        r#"<args format="1.0"><shaderType name="pattern"/><param name="mine" type="int"/></args>"#,
    )
    .unwrap();
    let reg = Registry::new(RegistryOptions {
        paths: vec![dir.clone()],
        use_env: false,
        ..RegistryOptions::default()
    });
    assert!(reg.definition(stem).unwrap().input("mine").is_some());
    let diags = reg.diagnostics();
    let rg001: Vec<_> = diags.with_code("RG001").collect();
    assert_eq!(rg001.len(), 1);
    assert_eq!(
        rg001[0].severity,
        Severity::Note,
        "shadowing the fallback is not a warning"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

fn vstructc(args: &[&str], env: Option<&str>) -> std::process::Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_vstructc"));
    cmd.args(args).current_dir(env!("CARGO_MANIFEST_DIR"));
    match env {
        Some(v) => cmd.env("VSTRUCTC_ARGS_PATH", v),
        None => cmd.env_remove("VSTRUCTC_ARGS_PATH"),
    };
    cmd.output().unwrap()
}

#[test]
fn environment_path_comes_after_explicit_paths() {
    let a = "tests/data/args/search/a";
    let b = "tests/data/args/search/b";
    let out = vstructc(
        &["info", "Dup"],
        Some(&format!("/nonexistent-vstructc::{b}")),
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(stdout.contains("fromB"), "{stdout}");
    // A stale environment entry is a warning, not a failure.
    assert!(stderr.contains("warning[AR005]"), "{stderr}");
    let out = vstructc(&["info", "Dup", "--args", a], Some(b));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("fromA"), "{stdout}");
    assert!(String::from_utf8_lossy(&out.stderr).contains("warning[RG001]"));
}
