//! Human diagnostics show the offending source line with a caret under the column, in colour
//! only when asked for (or on a terminal); JSON diagnostics stay as they were.

use std::io::Write;
use std::process::{Command, Output, Stdio};

fn vstructc(args: &[&str], stdin: Option<&str>) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_vstructc"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env_remove("VSTRUCTC_ARGS_PATH")
        .env_remove("NO_COLOR")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut input = child.stdin.take().unwrap();
    input.write_all(stdin.unwrap_or("").as_bytes()).unwrap();
    drop(input);
    child.wait_with_output().unwrap()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn a_rib_error_shows_its_line_with_a_caret() {
    let out = vstructc(
        &[
            "resolve",
            "tests/data/rib/rb004_unexpected.rib",
            "-o",
            "/dev/null",
        ],
        None,
    );
    assert_eq!(out.status.code(), Some(1));
    insta::assert_snapshot!(stderr(&out));
}

#[test]
fn a_rib_warning_on_standard_input_shows_its_line() {
    let rib = "Bxdf \"PxrSurface\" \"ball\"\n\t\"color diffuseColour\" [0.8 0.2 0.2]\n";
    let out = vstructc(&["resolve", "-", "-o", "/dev/null"], Some(rib));
    assert_eq!(out.status.code(), Some(0));
    insta::assert_snapshot!(stderr(&out));
}

#[test]
fn an_args_error_shows_its_line_with_a_caret() {
    let out = vstructc(
        &[
            "info",
            "mismatched_end",
            "--args",
            "tests/data/args/malformed/mismatched_end.args",
        ],
        None,
    );
    assert_eq!(out.status.code(), Some(1));
    insta::assert_snapshot!(stderr(&out));
}

#[test]
fn an_expr_error_says_once_what_was_expected_in_words() {
    let out = vstructc(&["expr", "set 1 if diffuseGain 3"], None);
    assert_eq!(out.status.code(), Some(1));
    let err = stderr(&out);
    for token_name in ["IS_NOT", "NUMBER", "PARAM", "CONNECTED"] {
        assert!(!err.contains(token_name), "{err}");
    }
    assert_eq!(err.matches("`<=`").count(), 1, "{err}");
    insta::assert_snapshot!(err);
}

#[test]
fn an_expr_error_marks_the_whole_token() {
    let out = vstructc(&["expr", "connect if diffuseGain == 1 and or"], None);
    assert_eq!(out.status.code(), Some(1));
    insta::assert_snapshot!(stderr(&out));
}

#[test]
fn json_diagnostics_have_no_snippet() {
    let out = vstructc(
        &[
            "--diag-format",
            "json",
            "resolve",
            "tests/data/rib/rb004_unexpected.rib",
            "-o",
            "/dev/null",
        ],
        None,
    );
    let err = stderr(&out);
    assert_eq!(err.lines().count(), 1, "{err}");
    let v: serde_json::Value = serde_json::from_str(err.trim()).unwrap();
    assert_eq!(v["code"], "RB004");
    assert_eq!(v["location"]["line"], 2);
    assert!(!err.contains('\u{1b}'), "{err}");
}

#[test]
fn colour_is_emitted_with_always_and_never_with_never() {
    let rib = [
        "resolve",
        "tests/data/rib/rb004_unexpected.rib",
        "-o",
        "/dev/null",
    ];
    let with = |flag: &[&str]| {
        let args: Vec<&str> = flag.iter().chain(rib.iter()).copied().collect();
        stderr(&vstructc(&args, None))
    };
    let always = with(&["--color", "always"]);
    assert!(always.contains("\u{1b}["), "{always}");
    let never = with(&["--color", "never"]);
    assert!(!never.contains('\u{1b}'), "{never}");
    // Into a pipe, `auto` does not colour.
    let auto = with(&[]);
    assert!(!auto.contains('\u{1b}'), "{auto}");
    assert_eq!(auto, never);
    // Without escapes, the coloured report says the same.
    let stripped = crate::snippet::without_escapes(&always);
    assert_eq!(stripped, never);
}

#[test]
fn no_color_is_respected_in_auto_mode_only() {
    let run = |color: &str| {
        let out = Command::new(env!("CARGO_BIN_EXE_vstructc"))
            .args(["--color", color, "expr", "set 1 if x is"])
            .env("NO_COLOR", "1")
            .output()
            .unwrap();
        stderr(&out)
    };
    assert!(!run("auto").contains('\u{1b}'));
    assert!(run("always").contains('\u{1b}'));
}
