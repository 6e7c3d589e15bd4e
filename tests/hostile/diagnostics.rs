//! Diagnostic volume: a flood of one warning prints at most `--max-diagnostics` of it
//! (20 by default in human output) and one line counting the rest; one diagnostic's text
//! stays short whatever the size of what it is about; JSON output keeps everything unless a
//! limit is asked for.

use crate::{check, run, scratch};
use std::fmt::Write as _;

/// `n` patterns, each referencing a handle defined nowhere before it (RB018 each).
fn forward_references(n: usize) -> String {
    let mut rib = String::with_capacity(n * 80);
    for i in 0..n {
        let _ = writeln!(
            rib,
            "Pattern \"PxrLayer\" \"p{i}\" \"reference color diffuseColor\" [\"q{i}:resultRGB\"]"
        );
    }
    rib
}

fn resolve_args(input: &std::path::Path, extra: &[&str]) -> Vec<String> {
    let out = input.with_extension("out.rib");
    let mut args: Vec<String> = extra.iter().map(|s| s.to_string()).collect();
    args.extend([
        "resolve".to_string(),
        input.display().to_string(),
        "-o".to_string(),
        out.display().to_string(),
    ]);
    args
}

/// `resolve PATH`, which must exit 0 (the message shows the start of stderr: it may be huge).
fn resolved_with_status_0(path: &std::path::Path) -> crate::Outcome {
    let o = run(&resolve_args(path, &[]));
    assert_eq!(
        o.status,
        Some(0),
        "{}",
        &o.stderr[..o.stderr.len().min(2000)]
    );
    o
}

fn count(stderr: &str, needle: &str) -> usize {
    stderr.lines().filter(|l| l.contains(needle)).count()
}

/// 250,000 forward references (the same holds for 1,000,000: 101 lines; the test keeps the
/// suite fast) print 20 warnings and one summary line, not 250,000 warnings.
#[test]
fn a_flood_of_forward_references_prints_a_bounded_number_of_lines() {
    let n = 250_000;
    let path = scratch("forward_flood.rib", forward_references(n));
    let o = resolved_with_status_0(&path);
    assert_eq!(count(&o.stderr, "warning[RB018]"), 20);
    // Each warning: headline, location, and the source line between gutter and caret.
    assert!(
        o.stderr.lines().count() <= 5 * 20 + 1,
        "{} lines",
        o.stderr.lines().count()
    );
    let summary = format!(
        "note: {} more RB018 diagnostics not shown (--max-diagnostics 0 shows all)",
        n - 20
    );
    assert!(o.stderr.contains(&summary), "{}", o.stderr);
}

#[test]
fn max_diagnostics_sets_the_limit_and_0_shows_all() {
    let path = scratch("forward_100.rib", forward_references(100));
    let all = run(&resolve_args(&path, &["--max-diagnostics", "0"]));
    check("--max-diagnostics 0", &all, 0, "warning[RB018]");
    assert_eq!(count(&all.stderr, "warning[RB018]"), 100);
    assert!(!all.stderr.contains("not shown"), "{}", all.stderr);
    let five = run(&resolve_args(&path, &["--max-diagnostics", "5"]));
    check("--max-diagnostics 5", &five, 0, "warning[RB018]");
    assert_eq!(count(&five.stderr, "warning[RB018]"), 5);
    assert!(
        five.stderr
            .contains("note: 95 more RB018 diagnostics not shown"),
        "{}",
        five.stderr
    );
    // The limit does not change the exit status: --deny-warnings counts what is not shown.
    let denied = run(&resolve_args(
        &path,
        &["--max-diagnostics", "1", "--deny-warnings"],
    ));
    assert_eq!(denied.status, Some(1), "{}", denied.stderr);
}

#[test]
fn json_diagnostics_keep_everything_unless_limited() {
    let path = scratch("forward_json.rib", forward_references(100));
    let all = run(&resolve_args(&path, &["--diag-format", "json"]));
    assert_eq!(all.status, Some(0), "{}", all.stderr);
    assert_eq!(count(&all.stderr, "\"code\":\"RB018\""), 100);
    assert!(!all.stderr.contains("suppressed"), "{}", all.stderr);
    for line in all.stderr.lines() {
        serde_json::from_str::<serde_json::Value>(line).expect("one JSON object per line");
    }
    let capped = run(&resolve_args(
        &path,
        &["--diag-format", "json", "--max-diagnostics", "3"],
    ));
    assert_eq!(capped.status, Some(0), "{}", capped.stderr);
    let lines: Vec<serde_json::Value> = capped
        .stderr
        .lines()
        .map(|l| serde_json::from_str(l).expect("one JSON object per line"))
        .collect();
    assert_eq!(lines.len(), 4, "{}", capped.stderr);
    assert_eq!(
        lines[3],
        serde_json::json!({"code": "RB018", "suppressed": 97})
    );
}

/// A cycle of 100,000 mixers is one warning naming its first and last hops and its length,
/// not a 3.7 MB line.
#[test]
fn a_long_cycle_is_one_short_warning() {
    let n = 100_000;
    let path = scratch("ring100k.json", crate::mixer_ring(n));
    let o = resolved_with_status_0(&path);
    let line = o
        .stderr
        .lines()
        .find(|l| l.starts_with("warning[VS012]"))
        .unwrap_or_else(|| panic!("no VS012 in {}", o.stderr));
    assert!(line.len() < 600, "{} bytes: {line}", line.len());
    assert!(line.contains("cycle of 100000 nodes"), "{line}");
    assert!(line.contains("m0.baselayer ← m1.pxrMaterialOut"), "{line}");
    assert!(
        line.contains("m99999.baselayer ← m0.pxrMaterialOut"),
        "{line}"
    );
    assert!(line.contains(&format!("… {} more …", n - 6)), "{line}");
    // JSON output carries the same bounded message (a smaller ring keeps the test quick).
    let path = scratch("ring1000.json", crate::mixer_ring(1000));
    let json = run(&resolve_args(&path, &["--diag-format", "json"]));
    assert!(
        json.stderr.contains("cycle of 1000 nodes"),
        "{}",
        json.stderr
    );
    assert!(json.stderr.len() < 2000, "{} bytes", json.stderr.len());
}

/// A head fed by 10,000 connections names the first and last few dropped ones.
#[test]
fn a_wide_fan_in_is_one_short_warning() {
    let path = scratch("fan_in_bounded.json", crate::fan_in_json(10_000));
    let o = run(&resolve_args(&path, &[]));
    check("fan_in_bounded.json", &o, 0, "warning[VS011]");
    let line = o
        .stderr
        .lines()
        .find(|l| l.starts_with("warning[VS011]"))
        .expect("VS011");
    assert!(line.len() < 600, "{} bytes: {line}", line.len());
    assert!(line.contains("… 9993 more …"), "{line}");
}

/// Whatever a message holds, a printed line is bounded: a 1 MB handle in a warning is cut
/// in the middle, and says how much was left out.
#[test]
fn a_huge_handle_in_a_message_is_cut() {
    let big = "h".repeat(1 << 20);
    let rib = format!(
        "Pattern \"PxrLayer\" \"p\" \"reference color diffuseColor\" [\"{big}:resultRGB\"]\n"
    );
    let path = scratch("huge_handle.rib", rib);
    let o = run(&resolve_args(&path, &[]));
    check("huge_handle.rib", &o, 0, "warning[RB018]");
    for line in o.stderr.lines() {
        assert!(
            line.chars().count() < 2100,
            "a line of {} bytes",
            line.len()
        );
    }
    assert!(o.stderr.contains("characters left out"), "{}", o.stderr);
    // JSON output keeps the whole message.
    let json = run(&resolve_args(&path, &["--diag-format", "json"]));
    assert!(json.stderr.contains(&big));
}

/// Two members whose conditionals compare a string with a number: two VS015 warnings with
/// the same code, place (the downstream node) and message. Human output prints it once; JSON
/// output keeps both (their notes name different members).
#[test]
fn identical_diagnostics_print_once_in_human_output() {
    let dir = scratch(
        "dup_network.rib",
        "Pattern \"Up\" \"u\"\n\
        Bxdf \"Down\" \"d\" \"reference struct inputMaterial\" [\"u:out\"]\n",
    );
    let defs = dir.with_file_name("dup_defs");
    std::fs::create_dir_all(&defs).expect("definitions folder");
    std::fs::write(
        defs.join("Up.args"),
        r#"<args format="1.0"><shaderType><tag value="pattern"/></shaderType>
  <param name="s" type="string" default="abc"/>
  <output name="out"><tags><tag value="vstruct"/></tags></output>
  <output name="out_a" vstructmember="out.a" vstructConditionalExpr="connect if s == 1"><tags><tag value="float"/></tags></output>
  <output name="out_b" vstructmember="out.b" vstructConditionalExpr="connect if s == 1"><tags><tag value="float"/></tags></output>
</args>"#,
    )
    .expect("Up.args");
    std::fs::write(
        defs.join("Down.args"),
        r#"<args format="1.0"><shaderType><tag value="bxdf"/></shaderType>
  <param name="inputMaterial" type="float" readOnly="true"><tags><tag value="vstruct"/></tags></param>
  <param name="p_a" type="float" vstructmember="inputMaterial.a"/>
  <param name="p_b" type="float" vstructmember="inputMaterial.b"/>
</args>"#,
    )
    .expect("Down.args");
    let defs = defs.display().to_string();
    let human = run(&resolve_args(&dir, &["--args", &defs]));
    check("dup human", &human, 0, "warning[VS015]");
    assert_eq!(
        count(&human.stderr, "warning[VS015]"),
        1,
        "{}",
        human.stderr
    );
    let json = run(&resolve_args(
        &dir,
        &["--args", &defs, "--diag-format", "json"],
    ));
    assert_eq!(json.status, Some(0), "{}", json.stderr);
    assert_eq!(
        count(&json.stderr, "\"code\":\"VS015\""),
        2,
        "{}",
        json.stderr
    );
}
