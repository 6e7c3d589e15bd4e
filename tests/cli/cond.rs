//! `vstructc expr` through the built binary.

use std::process::{Command, Output};

fn vstructc(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vstructc"))
        .args(args)
        .output()
        .expect("run vstructc")
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn prints_the_desugared_statement_and_the_ast() {
    let o = vstructc(&["expr", "ignore if x == 1"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let out = stdout(&o);
    let mut lines = out.lines();
    assert_eq!(lines.next(), Some("ignore if x == 1 else connect"));
    assert!(out.contains("Statement @0..16"), "{out}");
    assert!(
        out.contains("    Cmp @10..16: \"x\" == NUMBER 1.0"),
        "{out}"
    );
    assert!(out.contains("fallback: Connect (implied at 16)"), "{out}");
}

#[test]
fn parse_error_shows_caret_and_exits_1() {
    let o = vstructc(&["expr", "connect if x = 1"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stdout(&o).is_empty());
    let err = stderr(&o);
    assert!(
        err.starts_with(
            "error[VS001]: conditional expression: expected a comparison \
             (`==`, `!=`, `<`, `>`, `<=` or `>=`), `is` or `is not`, found `=`\n"
        ),
        "{err}"
    );
    assert!(err.contains("--> <expr>:1:14"), "{err}");
    // The caret sits under column 14 of the echoed expression.
    let lines: Vec<&str> = err.lines().collect();
    let i = lines
        .iter()
        .position(|l| l.ends_with("| connect if x = 1"))
        .expect("expression echoed");
    let indent = lines[i].find("connect").unwrap();
    assert_eq!(lines[i + 1].find('^'), Some(indent + 13), "{err}");
    assert_eq!(lines[i + 1].matches('^').count(), 1, "{err}");
}

#[test]
fn json_output_on_success() {
    let o = vstructc(&["expr", "--json", "set 1 if e == 1 else set 0"]);
    assert_eq!(o.status.code(), Some(0));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(v["desugared"], "set 1 if e == 1 else set 0");
    assert_eq!(v["statement"]["action"]["action"], "set");
    assert_eq!(v["statement"]["action"]["literal"]["value"], 1.0);
    assert_eq!(v["statement"]["condition"]["expr"], "cmp");
    assert_eq!(v["statement"]["condition"]["op"], "==");
    assert_eq!(v["statement"]["condition"]["param"]["span"]["start"], 9);
    assert_eq!(v["statement"]["fallback"]["literal"]["text"], "0");
}

#[test]
fn json_output_on_error() {
    let o = vstructc(&["expr", "--json", "x == y"]);
    assert_eq!(o.status.code(), Some(1));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let e = &v["error"];
    assert_eq!(e["code"], "VS001");
    assert_eq!(e["column"], 6);
    assert_eq!(e["span"], serde_json::json!([5, 6]));
    assert_eq!(e["found"], "PARAM \"y\"");
    assert_eq!(e["expected"], serde_json::json!(["NUMBER", "STRING"]));
    assert_eq!(e["message"], "expected NUMBER or STRING, found PARAM \"y\"");
}

#[test]
fn diag_format_json_on_stderr() {
    let o = vstructc(&["expr", "--diag-format", "json", "copy if"]);
    assert_eq!(o.status.code(), Some(1));
    let line = stderr(&o);
    let v: serde_json::Value = serde_json::from_str(line.trim()).unwrap();
    assert_eq!(v["code"], "VS001");
    assert_eq!(v["severity"], "error");
    assert_eq!(v["location"]["column"], 6);
}

#[test]
fn extensions_change_the_grammar() {
    let text = "connect if x == 1 else connect if y == 1";
    assert_eq!(vstructc(&["expr", text]).status.code(), Some(1));
    let o = vstructc(&["expr", "--ext", "else-if", text]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stdout(&o).starts_with("connect if x == 1 else connect if y == 1 else ignore\n"));
    assert!(stdout(&o).contains("else-if #1:"));
    let o = vstructc(&["expr", "--ext", "all", text]);
    assert_eq!(o.status.code(), Some(0));
}

#[test]
fn unknown_extension_is_a_usage_error() {
    let o = vstructc(&["expr", "--ext", "elseif", "connect"]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(err.contains("unknown extension `elseif`"), "{err}");
    assert!(
        err.contains("else-if") && err.contains("array-index"),
        "{err}"
    );
}

#[test]
fn expression_starting_with_minus_is_text() {
    let o = vstructc(&["expr", "-1 == x"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("found the number -1"), "{}", stderr(&o));
}
