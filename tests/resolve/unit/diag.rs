//! Unit tests of `diag` (`src/diag.rs`).

use vstructc::diag::*;

#[test]
fn long_lists_are_joined_with_their_ends_and_a_count() {
    assert_eq!(join_bounded(3, |i| i.to_string()), "0, 1, 2");
    assert_eq!(join_bounded(7, |i| i.to_string()), "0, 1, 2, 3, 4, 5, 6");
    let mut asked = Vec::new();
    let text = join_bounded(10, |i| {
        asked.push(i);
        i.to_string()
    });
    assert_eq!(text, "0, 1, 2, … 4 more …, 7, 8, 9");
    assert_eq!(
        asked,
        [0, 1, 2, 7, 8, 9],
        "only the named items are formatted"
    );
}

#[test]
fn line_column_counts_characters() {
    let text = "ab\ncé\nx";
    assert_eq!(line_column(text, 0), (1, 1));
    assert_eq!(line_column(text, 3), (2, 1));
    // 'é' is two bytes; offset 6 is after it.
    assert_eq!(line_column(text, 6), (2, 3));
    assert_eq!(line_column(text, 100), (3, 2));
}

#[test]
fn sort_orders_by_file_position_code() {
    let mut d = Diagnostics::new();
    d.push(Diagnostic::warning("VS002", "b").at(Location::new("f", 2, 1)));
    d.push(Diagnostic::warning("VS001", "a").at(Location::new("f", 2, 1)));
    d.push(Diagnostic::warning("VS009", "none"));
    d.push(Diagnostic::warning("VS003", "c").at(Location::new("f", 1, 9)));
    d.sort();
    let codes: Vec<_> = d.iter().map(|x| x.code.as_str()).collect();
    assert_eq!(codes, ["VS003", "VS001", "VS002", "VS009"]);
}

#[test]
fn volume_limit_counts_distinct_diagnostics_per_code() {
    let mut d = Diagnostics::new();
    for line in [1, 1, 2, 3, 3, 4] {
        d.push(Diagnostic::warning("RB018", "r").at(Location::new("f", line, 1)));
    }
    d.push(Diagnostic::warning("RB018", "other").at(Location::new("f", 1, 1)));
    d.push(Diagnostic::info("VS018", "v"));
    d.push(Diagnostic::note("VS021", "n"));
    let shown = d.volume_limited(2, true, |d| d.severity != Severity::Note);
    let lines: Vec<(&str, u32)> = shown
        .items
        .iter()
        .map(|d| (d.code.as_str(), d.location.as_ref().map_or(0, |l| l.line)))
        .collect();
    assert_eq!(lines, [("RB018", 1), ("RB018", 2), ("VS018", 0)]);
    // Lines 3 and 4, and the other message on line 1: three distinct ones left out.
    assert_eq!(shown.suppressed, [("RB018", 3)]);
    let all = d.volume_limited(0, true, |_| true);
    assert_eq!(all.items.len(), 7);
    assert!(all.suppressed.is_empty());
    let every = d.volume_limited(0, false, |_| true);
    assert_eq!(every.items.len(), 9);
}

#[test]
fn bound_line_keeps_both_ends_of_multibyte_text() {
    let line = format!("{}{}", "é".repeat(3000), "←end");
    let short = Diagnostic::bound_line(&line, 100);
    assert!(
        short.starts_with("éé") && short.ends_with("←end"),
        "{short}"
    );
    assert!(short.contains("[2904 characters left out]"), "{short}");
    assert_eq!(Diagnostic::bound_line("short", 100), "short");
}

#[test]
fn human_rendering_has_code_and_location() {
    let d = Diagnostic::error("AR004", "duplicate parameter `x`").at(Location::new("a.args", 3, 5));
    assert_eq!(
        d.render_human(),
        "error[AR004]: duplicate parameter `x`\n  --> a.args:3:5"
    );
    assert!(d.render_json().contains("\"code\":\"AR004\""));
}

/// The rows `| CODE | severity | meaning |` of the user documentation's tables.
fn documented() -> Vec<(String, String)> {
    let docs = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs");
    let mut rows = Vec::new();
    for entry in std::fs::read_dir(docs).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "md") {
            continue;
        }
        for line in std::fs::read_to_string(&path).unwrap().lines() {
            let cells: Vec<&str> = line.split(" | ").collect();
            let code = cells[0].trim_start_matches("| ");
            let is_code = code.len() == 5
                && code[..2].bytes().all(|b| b.is_ascii_uppercase())
                && code[2..].bytes().all(|b| b.is_ascii_digit());
            if line.starts_with("| ") && cells.len() >= 3 && is_code {
                let meaning = cells[2..].join(" | ");
                rows.push((code.to_string(), meaning.trim_end_matches(" |").to_string()));
            }
        }
    }
    rows.sort();
    rows
}

/// Every code's meaning is the documented one, and every documented code has one.
#[test]
fn code_meanings_are_the_documented_ones() {
    let table: Vec<(String, String)> = Code::all()
        .map(|(c, m)| (c.to_string(), m.to_string()))
        .collect();
    let mut sorted = table.clone();
    sorted.sort();
    assert_eq!(table, sorted, "CODES must stay sorted (binary search)");
    assert_eq!(table, documented());
    assert!(
        Code::new("VS009")
            .meaning()
            .unwrap()
            .contains("not an input")
    );
}

/// Every code the library reports (a quoted code literal in `src/`) has a meaning.
#[test]
fn every_reported_code_has_a_meaning() {
    fn scan(dir: &std::path::Path, found: &mut std::collections::BTreeSet<String>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                scan(&path, found);
            } else if path.ends_with("diag/codes.rs") {
                // The table itself.
                continue;
            } else if path.extension().is_some_and(|e| e == "rs") {
                let text = std::fs::read_to_string(&path).unwrap();
                let b = text.as_bytes();
                for i in 0..b.len().saturating_sub(6) {
                    let lit = &b[i..i + 7];
                    if lit[0] == b'"'
                        && lit[6] == b'"'
                        && lit[1..3].iter().all(u8::is_ascii_uppercase)
                        && lit[3..6].iter().all(u8::is_ascii_digit)
                    {
                        found.insert(text[i + 1..i + 6].to_string());
                    }
                }
            }
        }
    }
    let mut found = std::collections::BTreeSet::new();
    scan(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src"),
        &mut found,
    );
    assert!(found.len() > 50, "{found:?}");
    let missing: Vec<&String> = found
        .iter()
        .filter(|c| Code::all().all(|(known, _)| known != c.as_str()))
        .filter(|c| c.as_str() != "XX999")
        .collect();
    assert!(
        missing.is_empty(),
        "codes without a documented meaning: {missing:?}"
    );
}

#[test]
fn severity_orders_error_highest() {
    let mut all = [
        Severity::Error,
        Severity::Note,
        Severity::Warning,
        Severity::Info,
    ];
    all.sort();
    assert_eq!(
        all,
        [
            Severity::Note,
            Severity::Info,
            Severity::Warning,
            Severity::Error
        ]
    );
    let mut d = Diagnostics::new();
    d.push(Diagnostic::info("VS018", "i"));
    assert!(!d.has_warnings());
    d.push(Diagnostic::warning("VS010", "w"));
    assert!(d.has_warnings() && !d.has_errors());
}
