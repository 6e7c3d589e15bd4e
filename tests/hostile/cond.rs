//! Long `and`/`or` chains in a `vstructConditionalExpr`: loading (`info`), resolution that
//! evaluates the chain (`resolve`), the explain story (`explain`) and `expr --json` finish
//! quickly, in bounded memory, with exit 0 or 1 — never a stack overflow (a signal).
//!
//! The chains have 1,000,000 terms (about 11 MB of expression text). Each run is measured
//! for the child's CPU time and peak resident set (`wait4`), against the limit of the
//! hostile suite (2 s) and 500 MB. CPU time rather than wall time: these runs are long enough
//! that, on a machine shared with parallel tests and builds, waiting for a core would
//! dominate the wall time; CPU time is what grows if the work stops being linear. A wall
//! limit several times larger still catches a hang.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::{Duration, Instant};

/// Terms in the long chains.
const TERMS: usize = 1_000_000;

/// Peak resident set allowed to one run.
const MAX_RSS_BYTES: u64 = 500 << 20;

/// The upstream definition: int inputs `a` (default 1), `b` (default 2), `c` (default 3) and
/// an output head `out` whose members carry the conditionals given as `(member, expr)`.
fn up_args(members: &[(&str, &str)]) -> String {
    let mut s = String::from(
        "<args format=\"1.0\"><shaderType><tag value=\"pattern\"/></shaderType>\n\
         <param name=\"a\" type=\"int\" default=\"1\"/>\n\
         <param name=\"b\" type=\"int\" default=\"2\"/>\n\
         <param name=\"c\" type=\"int\" default=\"3\"/>\n\
         <output name=\"out\"><tags><tag value=\"vstruct\"/></tags></output>\n",
    );
    for (member, expr) in members {
        let _ = writeln!(
            s,
            "<output name=\"out_{member}\" vstructmember=\"out.{member}\" \
             vstructConditionalExpr=\"{expr}\"><tags><tag value=\"float\"/></tags></output>"
        );
    }
    s.push_str("</args>\n");
    s
}

/// The downstream definition: input head `inputMaterial` with float members `p_NAME`.
fn down_args(members: &[&str]) -> String {
    let mut s = String::from(
        "<args format=\"1.0\"><shaderType><tag value=\"bxdf\"/></shaderType>\n\
         <param name=\"inputMaterial\" type=\"float\"><tags><tag value=\"vstruct\"/></tags></param>\n",
    );
    for m in members {
        let _ = writeln!(
            s,
            "<param name=\"p_{m}\" type=\"float\" default=\"0.5\" vstructmember=\"inputMaterial.{m}\"/>"
        );
    }
    s.push_str("</args>\n");
    s
}

/// `n` predicates joined by `sep`, cycling through `preds`.
fn chain(n: usize, preds: &[&str], sep: &str) -> String {
    let mut s = String::with_capacity(n * 12);
    for i in 0..n {
        if i > 0 {
            s.push_str(sep);
        }
        s.push_str(preds[i % preds.len()]);
    }
    s
}

/// The long conditionals as `(member, expression, chosen action)`: an `and` chain that is
/// true to the end (every term is evaluated), an `or` chain that is false to the end, and a
/// mixed chain (`or` of `and`s with parenthesised `or`s) that only its last term makes true.
fn long_conditionals() -> Vec<(&'static str, String, &'static str)> {
    let and = format!(
        "connect if {}",
        chain(TERMS, &["a == 1", "b == 2", "c >= 3"], " and ")
    );
    let or = format!(
        "set 1 if {} else set 0",
        chain(TERMS, &["a == 0", "b != 2", "c < 3"], " or ")
    );
    let groups = TERMS / 4;
    let mut mixed = String::from("connect if ");
    for i in 0..groups {
        if i > 0 {
            mixed.push_str(" or ");
        }
        mixed.push_str("(a == 0 or b == 0) and c == 3 and a is not connected");
    }
    mixed.push_str(" or a == 1");
    vec![
        ("and", and, "connect"),
        ("or", or, "set 0"),
        ("mixed", mixed, "connect"),
    ]
}

struct Measured {
    status: Option<i32>,
    stdout: String,
    stderr: String,
    elapsed: Duration,
    cpu: Duration,
    max_rss_bytes: u64,
}

/// Run the CLI, measuring wall time, CPU time and the child's peak resident set (under
/// `/usr/bin/time`, see `crate::timed_vstructc`).
fn measure(args: &[&str]) -> Measured {
    static RUN: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = RUN.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let report = crate::scratch(
        &format!("cond_measure_{}_{n}.usage", std::process::id()),
        "",
    );
    let start = Instant::now();
    let out = crate::timed_vstructc(args, &report)
        .stdin(Stdio::null())
        .output()
        .expect("/usr/bin/time runs");
    let usage = crate::read_usage(&report);
    Measured {
        status: out.status.code(),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
        elapsed: start.elapsed(),
        cpu: usage.cpu,
        max_rss_bytes: usage.max_rss_kib * 1024,
    }
}

/// Exit 0 or 1 (never a signal or a panic), within the CPU time and memory limits.
fn check_run(name: &str, m: &Measured, status: i32) {
    assert!(
        matches!(m.status, Some(0) | Some(1)),
        "{name}: exit status {:?} (101 = panic, None = killed by a signal)\n{}",
        m.status,
        tail(&m.stderr)
    );
    assert_eq!(m.status, Some(status), "{name}: {}", tail(&m.stderr));
    assert!(m.cpu <= super::LIMIT, "{name}: {:?} of CPU time", m.cpu);
    assert!(
        m.elapsed <= 5 * super::LIMIT,
        "{name}: took {:?}",
        m.elapsed
    );
    assert!(
        m.max_rss_bytes <= MAX_RSS_BYTES,
        "{name}: peak RSS {} MB",
        m.max_rss_bytes >> 20
    );
}

/// The last 2,000 bytes of a (possibly huge) output, for failure messages.
fn tail(s: &str) -> &str {
    let mut from = s.len().saturating_sub(2000);
    while !s.is_char_boundary(from) {
        from += 1;
    }
    &s[from..]
}

/// A folder `NAME` holding `Up.args`, `Down.args` and a network `net.rib` where `D` (Down) takes
/// `inputMaterial` from `U` (Up).
fn chain_setup(name: &str, conds: &[(&str, String)]) -> PathBuf {
    let root = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("hostile");
    crate::common::remove_at_exit(&root);
    let dir = root.join("cond").join(name);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    let members: Vec<(&str, &str)> = conds.iter().map(|(m, e)| (*m, e.as_str())).collect();
    std::fs::write(dir.join("Up.args"), up_args(&members)).expect("Up.args");
    let names: Vec<&str> = conds.iter().map(|(m, _)| *m).collect();
    std::fs::write(dir.join("Down.args"), down_args(&names)).expect("Down.args");
    std::fs::write(
        dir.join("net.rib"),
        "Pattern \"Up\" \"U\"\n\
         Bxdf \"Down\" \"D\" \"reference float inputMaterial\" [\"U:out\"]\n",
    )
    .expect("net.rib");
    dir
}

fn arg(p: &Path) -> String {
    p.display().to_string()
}

/// Each chain in a definition of its own: `info` loads it, `resolve` evaluates it to the end,
/// `explain` tells the story (the conditional printed whole, then what it read).
///
/// Nine runs of the command over 11 MB expressions: optimised only (`cargo test --release`,
/// and CI), where each takes a fraction of a second; a debug `cargo test` lists it as ignored.
/// The shorter chains of the other tests here run in every build.
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "nine runs over million-term chains: runs with `cargo test --release`"
)]
fn million_term_chains_load_resolve_and_explain() {
    for (member, expr, chosen) in long_conditionals() {
        let dir = chain_setup(member, &[(member, expr)]);
        let up = arg(&dir.join("Up.args"));
        let down = arg(&dir.join("Down.args"));
        let net = arg(&dir.join("net.rib"));

        let m = measure(&["info", "Up", "--args", &up]);
        check_run(&format!("info {member}"), &m, 0);
        assert!(
            m.stdout.contains("Conditional expressions (1)"),
            "{}",
            tail(&m.stdout)
        );

        let m = measure(&["resolve", &net, "--args", &up, "--args", &down]);
        check_run(&format!("resolve {member}"), &m, 0);
        let wanted = match chosen {
            "connect" => format!("\"reference float p_{member}\" [\"U:out_{member}\"]"),
            _ => format!("\"float p_{member}\" [0]"),
        };
        assert!(m.stdout.contains(&wanted), "{member}: {}", m.stdout);

        let target = format!("D.p_{member}");
        let m = measure(&["explain", &target, &net, "--args", &up, "--args", &down]);
        check_run(&format!("explain {member}"), &m, 0);
        let out = tail(&m.stdout);
        assert!(
            out.contains(&format!("chosen action: {chosen}")),
            "{member}: {out}"
        );
        assert!(out.contains("reads U.c = default 3"), "{member}: {out}");
    }
}

/// An `or` chain of undeclared parameters: VS009 at load for the three names only, and
/// VS015 for every evaluated comparison, each with a caret under its predicate. However long
/// the one-line expression, a caret note shows a bounded window of it (it showed the whole
/// line: 100,000 reports of a 1 MB line ran out of memory).
#[test]
fn long_chain_of_undeclared_names_has_bounded_diagnostics() {
    let n = 10_000;
    let conds = vec![(
        "undeclared",
        format!(
            "connect if {}",
            chain(n, &["x == 1", "y == 1", "z == 1"], " or ")
        ),
    )];
    let dir = chain_setup("undeclared", &conds);
    let up = arg(&dir.join("Up.args"));
    let down = arg(&dir.join("Down.args"));
    let net = arg(&dir.join("net.rib"));
    let longest_line = |s: &str| s.lines().map(|l| l.chars().count()).max().unwrap_or(0);

    let m = measure(&["info", "Up", "--args", &up]);
    check_run("info undeclared", &m, 0);
    assert_eq!(
        m.stderr.matches("warning[VS009]").count(),
        3,
        "{}",
        tail(&m.stderr)
    );
    assert!(longest_line(&m.stderr) < 420, "{}", tail(&m.stderr));

    let m = measure(&["resolve", &net, "--args", &up, "--args", &down]);
    check_run("resolve undeclared", &m, 0);
    assert!(m.stderr.contains("warning[VS015]"), "{}", tail(&m.stderr));
    assert!(m.stderr.contains("…"), "{}", tail(&m.stderr));
    assert!(longest_line(&m.stderr) < 420, "{}", tail(&m.stderr));
}

/// `expr --json` grows linearly with the chain: doubling the terms at most a little more
/// than doubles the output (it grew with the square before: 8,000 terms asked for 2.9 GB).
/// One command-line argument is limited to 128 KiB, hence the sizes.
#[test]
fn expr_json_is_linear_in_the_chain() {
    let size = |n: usize| {
        let text = format!("connect if {}", chain(n, &["a == 1", "b == 2"], " and "));
        let m = measure(&["expr", "--json", &text]);
        check_run(&format!("expr --json ({n} terms)"), &m, 0);
        let v: serde_json::Value = serde_json::from_str(&m.stdout).expect("JSON output");
        let terms = &v["statement"]["condition"]["terms"];
        assert_eq!(
            terms.as_array().map(Vec::len),
            Some(n),
            "one and node of n terms"
        );
        m.stdout.len()
    };
    let small = size(4_000);
    let large = size(8_000);
    let ratio = large as f64 / small as f64;
    assert!(
        (1.9..2.1).contains(&ratio),
        "4,000 terms: {small} bytes; 8,000 terms: {large} bytes (ratio {ratio:.2})"
    );
}

/// Parenthesis nesting keeps its limit, with a positioned error, inside a definition too.
#[test]
fn deep_parentheses_in_a_definition_are_a_positioned_warning() {
    let expr = format!(
        "connect if {}a == 1{}",
        "(".repeat(100_000),
        ")".repeat(100_000)
    );
    let dir = chain_setup("deep", &[("deep", expr)]);
    let up = arg(&dir.join("Up.args"));
    let m = measure(&["info", "Up", "--args", &up]);
    check_run("info deep", &m, 0);
    assert!(m.stderr.contains("warning[VS001]"), "{}", tail(&m.stderr));
    assert!(
        m.stderr.contains("nested deeper than 64"),
        "{}",
        tail(&m.stderr)
    );
    assert!(m.stderr.contains(" --> "), "{}", tail(&m.stderr));
}
