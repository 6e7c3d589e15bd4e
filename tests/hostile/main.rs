//! Hostile input: every file in `tests/hostile/corpus/` and every generated monster input
//! goes through the real CLI and must end with exit status 0 or 1 (never 101 = panic, never
//! a signal), a positioned error or a documented warning on stderr, in at most 2 s.
//!
//! One module per area of attack; the shared runners (`run`, `check`, `scratch`,
//! `run_file`) live here and are visible to every module.

#[macro_use]
#[path = "../common/mod.rs"]
mod common;

mod cond;
mod diagnostics;
mod limits;
mod render;
mod values;
// FIFOs, device nodes, symlinks and file modes: Unix only.
#[cfg(unix)]
mod definitions;
#[cfg(unix)]
mod output;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

const LIMIT: Duration = Duration::from_secs(2);

/// What one hostile input must produce: exit status and a diagnostic code that must appear
/// on stderr (with a `-->` position line when `code` names an error or warning).
struct Expect {
    file: &'static str,
    status: i32,
    code: &'static str,
}

const fn e(file: &'static str, status: i32, code: &'static str) -> Expect {
    Expect { file, status, code }
}

/// One entry per file in `tests/hostile/corpus/`; the codes are the spec's (formats.md, vstruct.md).
const CORPUS: &[Expect] = &[
    e("bad_conditional.args", 0, "warning[VS001]"),
    e("huge_array_size.args", 0, "warning[AR013]"),
    e("invalid_utf8.args", 1, "error[AR005]"),
    e("nan_default.args", 0, "warning[AR012]"),
    e("nul.args", 1, "error[AR001]"),
    e("truncated.args", 1, "error[AR001]"),
    e("HugeArray.oso", 0, "warning[OS010]"),
    e("NanDefault.oso", 1, "error[OS002]"),
    e("Truncated.oso", 1, "error[OS003]"),
    e("cycle2.rib", 0, "warning[RB018]"),
    e("empty.rib", 0, ""),
    e("gzip.rib", 1, "error[RB001]"),
    e("head_self.rib", 0, "warning[VS010]"),
    e("huge_array_decl.rib", 0, "warning[RB014]"),
    e("huge_numbers.rib", 0, "warning[RB014]"),
    // Bytes inside RIB strings are passed through unchanged (formats.md §3.1: strings MAY
    // contain UTF-8; the reader does not judge them), so this resolves silently.
    e("invalid_utf8.rib", 0, ""),
    e("missing_handle.rib", 0, "warning[VS010]"),
    e("nan_values.rib", 1, "error[RB004]"),
    e("nul.rib", 1, "error[RB004]"),
    e("self_connection.rib", 0, "warning[RB018]"),
    e("truncated.rib", 1, "error[RB004]"),
    e("truncated_string.rib", 1, "error[RB003]"),
    e("invalid_utf8.json", 1, "error[JS001]"),
    e("truncated.json", 1, "error[JS001]"),
    e("wrong_types.json", 1, "error[JS003]"),
];

fn corpus_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/hostile/corpus")
}

/// The CLI arguments that read `path`: definitions through `info`, networks through `resolve`.
fn command_for(path: &Path) -> Vec<String> {
    let p = path.display().to_string();
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("");
    match path.extension().and_then(|s| s.to_str()) {
        Some("args") | Some("oso") => vec!["info".into(), stem.into(), "--args".into(), p],
        _ => vec!["resolve".into(), p],
    }
}

struct Outcome {
    status: Option<i32>,
    stderr: String,
    elapsed: Duration,
}

fn run(args: &[String]) -> Outcome {
    let start = Instant::now();
    let out = Command::new(env!("CARGO_BIN_EXE_vstructc"))
        .args(args)
        .env("VSTRUCTC_ARGS_PATH", "")
        .output()
        .expect("the vstructc binary runs");
    Outcome {
        status: out.status.code(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
        elapsed: start.elapsed(),
    }
}

/// The shared contract: 0 or 1 (a signal gives `None`), quick, and a diagnostic when asked.
fn check(name: &str, o: &Outcome, status: i32, code: &str) {
    assert!(
        matches!(o.status, Some(0) | Some(1)),
        "{name}: exit status {:?} (101 = panic, None = killed by a signal)\n{}",
        o.status,
        o.stderr
    );
    assert_eq!(o.status, Some(status), "{name}: stderr:\n{}", o.stderr);
    assert!(o.elapsed <= LIMIT, "{name}: took {:?}", o.elapsed);
    if !code.is_empty() {
        assert!(
            o.stderr.contains(code),
            "{name}: no `{code}` in:\n{}",
            o.stderr
        );
        if code.starts_with("error") || code.starts_with("warning") {
            assert!(
                o.stderr.contains("--> "),
                "{name}: unpositioned:\n{}",
                o.stderr
            );
        }
    }
}

#[test]
fn every_corpus_file_has_an_expectation() {
    let mut names: Vec<String> = std::fs::read_dir(corpus_dir())
        .expect("tests/hostile/corpus exists")
        .map(|e| {
            e.expect("dir entry")
                .file_name()
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    names.sort();
    let mut listed: Vec<&str> = CORPUS.iter().map(|c| c.file).collect();
    listed.sort();
    assert_eq!(names, listed);
}

#[test]
fn corpus_files_fail_cleanly() {
    for c in CORPUS {
        let path = corpus_dir().join(c.file);
        let o = run(&command_for(&path));
        check(c.file, &o, c.status, c.code);
    }
}

/// Write `text` to a fresh file in the target dir and return its path. The folder is removed
/// when the binary exits after a run without failures.
fn scratch(name: &str, text: impl AsRef<[u8]>) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("hostile");
    common::remove_at_exit(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    let path = dir.join(name);
    std::fs::write(&path, text).expect("scratch file");
    path
}

fn run_file(name: &str, text: impl AsRef<[u8]>) -> Outcome {
    let path = scratch(name, text);
    run(&command_for(&path))
}

#[test]
fn one_megabyte_strings() {
    let big = "x".repeat(1 << 20);
    let rib = format!(
        "Pattern \"PxrLayer\" \"{big}\" \"string __materialid\" [\"{big}\"]\n\
         Bxdf \"PxrLayerSurface\" \"s\" \"reference struct inputMaterial\" [\"{big}:pxrMaterialOut\"]\n"
    );
    let o = run_file("big_string.rib", rib);
    check("big_string.rib", &o, 0, "");
    let args = format!(
        "<args format=\"1.0\"><shaderType><tag value=\"pattern\"/></shaderType>\
         <param name=\"{big}\" type=\"string\" default=\"{big}\"><help>{big}</help></param></args>\n"
    );
    let o = run_file("BigString.args", args);
    check("BigString.args", &o, 0, "");
    // A single command-line argument is limited to 128 KiB by the OS: 100 kB there.
    let name = "y".repeat(100_000);
    let expr = vec![
        "expr".to_string(),
        format!("connect if {name} == 1 else ignore"),
    ];
    let o = run(&expr);
    assert!(matches!(o.status, Some(0) | Some(1)), "{:?}", o.status);
    assert!(o.elapsed <= LIMIT, "expr took {:?}", o.elapsed);
}

#[test]
fn deeply_nested_pages() {
    let depth = 10_000;
    let mut xml =
        String::from("<args format=\"1.0\"><shaderType><tag value=\"pattern\"/></shaderType>");
    xml.push_str(&"<page name=\"p\">".repeat(depth));
    xml.push_str("<param name=\"deep\" type=\"float\" default=\"1\"/>");
    xml.push_str(&"</page>".repeat(depth));
    xml.push_str("<output name=\"out\" type=\"float\"/></args>\n");
    let o = run_file("DeepPages.args", xml);
    check("DeepPages.args", &o, 1, "error[AR001]");
    assert!(o.stderr.contains("nesting deeper than 64"), "{}", o.stderr);
}

#[test]
fn deeply_nested_conditional_and_json() {
    let expr = format!(
        "connect if {}x == 1{} else ignore",
        "(".repeat(10_000),
        ")".repeat(10_000)
    );
    let o = run(&["expr".to_string(), expr]);
    assert_eq!(o.status, Some(1), "{}", o.stderr);
    assert!(o.stderr.contains("nested deeper than 64"), "{}", o.stderr);
    assert!(o.elapsed <= LIMIT);
    let json = format!("{}{}", "[".repeat(100_000), "]".repeat(100_000));
    let o = run_file("deep.json", json);
    check("deep.json", &o, 1, "error[JS001]");
}

/// A JSON network (formats.md §4) with the given nodes; each node is
/// `(handle, type, [(input, upstream, output)])`; the material's bxdf terminal is `s`.
/// A JSON node for generated networks: name, shader, connections (input, upstream, output).
type JsonNode<'a> = (String, &'a str, Vec<(String, String, &'a str)>);

fn json_net(nodes: &[JsonNode<'_>]) -> String {
    let mut out = String::from("{\"vstructcNetwork\": 1, \"materials\": {\"m\": {\"nodes\": {");
    for (i, (handle, ty, conns)) in nodes.iter().enumerate() {
        if i > 0 {
            out.push(',');
        }
        let _ = write!(
            out,
            "\"{handle}\": {{\"nodeTypeId\": \"{ty}\", \"inputConnections\": {{"
        );
        let mut by_input: Vec<(&String, Vec<String>)> = Vec::new();
        for (input, up, output) in conns {
            let link =
                format!("{{\"upstreamNode\": \"{up}\", \"upstreamOutputName\": \"{output}\"}}");
            match by_input.iter_mut().find(|(i, _)| *i == input) {
                Some((_, links)) => links.push(link),
                None => by_input.push((input, vec![link])),
            }
        }
        for (j, (input, links)) in by_input.iter().enumerate() {
            if j > 0 {
                out.push(',');
            }
            let _ = write!(out, "\"{input}\": [{}]", links.join(","));
        }
        out.push_str("}}");
    }
    out.push_str("}, \"terminals\": {\"bxdf\": {\"upstreamNode\": \"s\", \"upstreamOutputName\": \"bxdf_out\"}}}}}\n");
    out
}

/// A ring of `n` mixers, each `baselayer` fed by the next one's `pxrMaterialOut`.
fn mixer_ring(n: usize) -> String {
    let mut nodes: Vec<JsonNode<'_>> = (0..n)
        .map(|i| {
            let up = format!("m{}", (i + 1) % n);
            (
                format!("m{i}"),
                "PxrLayerMixer",
                vec![("baselayer".to_string(), up, "pxrMaterialOut")],
            )
        })
        .collect();
    nodes.push((
        "s".into(),
        "PxrLayerSurface",
        vec![("inputMaterial".into(), "m0".into(), "pxrMaterialOut")],
    ));
    json_net(&nodes)
}

#[test]
fn cycles_of_length_1_2_and_1000() {
    for n in [1usize, 2, 1000] {
        let name = format!("ring{n}.json");
        let o = run_file(&name, mixer_ring(n));
        check(&name, &o, 0, "warning[VS012]");
    }
}

/// A JSON network of `n` PxrLayers all connected to one PxrLayerSurface's `inputMaterial`.
fn fan_in_json(n: usize) -> String {
    let mut nodes: Vec<JsonNode<'_>> = Vec::new();
    let mut conns = Vec::new();
    for i in 0..n {
        nodes.push((format!("l{i}"), "PxrLayer", Vec::new()));
        conns.push((
            "inputMaterial".to_string(),
            format!("l{i}"),
            "pxrMaterialOut",
        ));
    }
    nodes.push(("s".into(), "PxrLayerSurface", conns));
    json_net(&nodes)
}

#[test]
fn ten_thousand_connections_on_one_head() {
    let o = run_file("fan_in.json", fan_in_json(10_000));
    check("fan_in.json", &o, 0, "warning[VS011]");

    // The same in RIB: one array of 10,000 connection strings on one head.
    let mut rib = String::new();
    let mut refs = String::new();
    for i in 0..10_000 {
        let _ = writeln!(
            rib,
            "Pattern \"PxrLayer\" \"l{i}\" \"int enableDiffuse\" [1]"
        );
        let _ = write!(refs, "\"l{i}:pxrMaterialOut\" ");
    }
    let _ = writeln!(
        rib,
        "Bxdf \"PxrLayerSurface\" \"s\" \"reference struct[10000] inputMaterial\" [{refs}]"
    );
    let o = run_file("fan_in.rib", rib);
    assert!(
        matches!(o.status, Some(0) | Some(1)),
        "{:?}\n{}",
        o.status,
        o.stderr
    );
    assert!(o.elapsed <= LIMIT, "fan_in.rib took {:?}", o.elapsed);
}

#[test]
fn self_connection_in_json_is_a_cycle_of_one() {
    let nodes = vec![
        (
            "m".to_string(),
            "PxrLayerMixer",
            vec![("baselayer".to_string(), "m".to_string(), "pxrMaterialOut")],
        ),
        (
            "s".to_string(),
            "PxrLayerSurface",
            vec![(
                "inputMaterial".to_string(),
                "m".to_string(),
                "pxrMaterialOut",
            )],
        ),
    ];
    let o = run_file("self.json", json_net(&nodes));
    check("self.json", &o, 0, "warning[VS012]");
    let nodes = vec![(
        "s".to_string(),
        "PxrLayerSurface",
        vec![(
            "inputMaterial".to_string(),
            "nobody".to_string(),
            "pxrMaterialOut",
        )],
    )];
    let o = run_file("missing.json", json_net(&nodes));
    check("missing.json", &o, 0, "warning[JS010]");
}

/// The later stages on the same hostile networks: lowering (`compile`) and the interpreter
/// (`render`, `eval`) may refuse a network or report problems in it, but exit 0 or 1, never
/// panic, and stay quick. Whatever `resolve` rejects they reject too (they read the same way).
#[test]
fn hostile_networks_through_compile_render_and_eval() {
    let scratch = std::env::temp_dir().join(format!("vstructc-hostile-{}", std::process::id()));
    std::fs::create_dir_all(&scratch).expect("scratch dir");
    for c in CORPUS {
        let path = corpus_dir().join(c.file);
        let ext = path.extension().and_then(|s| s.to_str()).unwrap_or("");
        if ext == "args" || ext == "oso" {
            continue;
        }
        let p = path.display().to_string();
        let png = scratch
            .join(format!("{}.png", c.file))
            .display()
            .to_string();
        let commands: [Vec<String>; 3] = [
            vec!["compile".into(), "--emit".into(), "lobes".into(), p.clone()],
            vec![
                "render".into(),
                "--size".into(),
                "16".into(),
                p.clone(),
                "-o".into(),
                png,
            ],
            vec![
                "eval".into(),
                p.clone(),
                "--wo".into(),
                "0,0,1".into(),
                "--wi".into(),
                "0.5,0.5,0.7".into(),
            ],
        ];
        let resolves = run(&command_for(&path)).status == Some(0);
        for args in &commands {
            let o = run(args);
            let name = format!("{} {}", args[0], c.file);
            assert!(
                matches!(o.status, Some(0) | Some(1)),
                "{name}: exit status {:?}\n{}",
                o.status,
                o.stderr
            );
            assert!(o.elapsed <= LIMIT, "{name}: took {:?}", o.elapsed);
            if !resolves {
                assert_eq!(o.status, Some(1), "{name}: accepted what resolve rejects");
            }
        }
    }
    let _ = std::fs::remove_dir_all(&scratch);
}

/// Peak resident set and CPU time of one `vstructc` run.
struct Usage {
    /// Peak resident set, KiB.
    max_rss_kib: u64,
    /// User plus system time.
    cpu: Duration,
}

/// A command that runs `vstructc args` under `/usr/bin/time`, which writes the child's
/// usage to `report` (read it with [`read_usage`] after the command ends; the command's exit
/// status is vstructc's, or 128 + N when signal N ended it).
///
/// Why not `wait4` on a direct child: Linux carries the resident-set high-water mark of the
/// address space a process was spawned from into its `ru_maxrss`, so every child of this
/// test process would report at least this process's own peak, which other tests in the
/// binary raise. `time` forks vstructc from its own small process.
fn timed_vstructc(args: &[&str], report: &Path) -> Command {
    let mut cmd = Command::new("/usr/bin/time");
    cmd.arg("-f")
        .arg("%M %U %S")
        .arg("-o")
        .arg(report)
        .arg(env!("CARGO_BIN_EXE_vstructc"))
        .args(args)
        .env("VSTRUCTC_ARGS_PATH", "");
    cmd
}

/// The usage `/usr/bin/time` wrote (its last line; a line before it may say how the child
/// ended).
fn read_usage(report: &Path) -> Usage {
    let text = std::fs::read_to_string(report).expect("/usr/bin/time wrote its report");
    let last = text.lines().last().unwrap_or_default();
    let fields: Vec<&str> = last.split_whitespace().collect();
    let [rss, user, system] = fields[..] else {
        panic!("unexpected /usr/bin/time report: {text:?}");
    };
    let secs = |s: &str| Duration::from_secs_f64(s.parse().expect("seconds"));
    Usage {
        max_rss_kib: rss.parse().expect("KiB"),
        cpu: secs(user) + secs(system),
    }
}
