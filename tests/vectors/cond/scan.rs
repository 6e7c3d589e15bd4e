//! Extract `vstructConditionalExpr` values from the fixture files with simple scanning (the
//! real readers live elsewhere; this must not depend on them). Shared by
//! `tests/cond/fixtures.rs` and `benches/cond_parse.rs` through `#[path]`.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// The attribute / metadata key.
pub const KEY: &str = "vstructConditionalExpr";

/// Decode an XML attribute value: entity and character references, and attribute-value
/// normalisation of literal tab, newline and carriage return to a space.
pub fn decode_xml_attr(raw: &str) -> String {
    let mut out = String::with_capacity(raw.len());
    let mut rest = raw;
    while let Some(c) = rest.chars().next() {
        if c == '&'
            && let Some(end) = rest.find(';')
        {
            let entity = &rest[1..end];
            let decoded = match entity {
                "amp" => Some('&'),
                "lt" => Some('<'),
                "gt" => Some('>'),
                "quot" => Some('"'),
                "apos" => Some('\''),
                e => e
                    .strip_prefix("#x")
                    .and_then(|h| u32::from_str_radix(h, 16).ok())
                    .or_else(|| e.strip_prefix('#').and_then(|d| d.parse().ok()))
                    .and_then(char::from_u32),
            };
            if let Some(d) = decoded {
                out.push(d);
                rest = &rest[end + 1..];
                continue;
            }
        }
        out.push(if matches!(c, '\t' | '\n' | '\r') {
            ' '
        } else {
            c
        });
        rest = &rest[c.len_utf8()..];
    }
    out
}

/// Replace XML comments by spaces (keeping offsets), so commented-out attributes are not
/// counted.
fn blank_xml_comments(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(start) = rest.find("<!--") {
        out.push_str(&rest[..start]);
        let after = &rest[start..];
        let len = after.find("-->").map_or(after.len(), |e| e + 3);
        out.extend(
            after[..len]
                .chars()
                .map(|c| if c == '\n' { '\n' } else { ' ' }),
        );
        rest = &after[len..];
    }
    out.push_str(rest);
    out
}

/// Every `vstructConditionalExpr="…"` (or `'…'`) attribute value of an `.args` text, decoded.
pub fn args_exprs(text: &str) -> Vec<String> {
    let text = blank_xml_comments(text);
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(i) = text[from..].find(KEY) {
        let at = from + i;
        from = at + KEY.len();
        let before = text[..at].chars().next_back();
        if !before.is_some_and(char::is_whitespace) {
            continue;
        }
        let rest = text[from..].trim_start();
        let Some(rest) = rest.strip_prefix('=') else {
            continue;
        };
        let rest = rest.trim_start();
        let Some(quote) = rest.chars().next().filter(|q| *q == '"' || *q == '\'') else {
            continue;
        };
        let body = &rest[1..];
        if let Some(end) = body.find(quote) {
            out.push(decode_xml_attr(&body[..end]));
        }
    }
    out
}

/// C-unescape the body of a string literal (`\"`, `\\`, `\n`, `\t`, … ; unknown escapes
/// keep the character).
pub fn c_unescape(body: &str) -> String {
    let mut out = String::with_capacity(body.len());
    let mut chars = body.chars();
    while let Some(c) = chars.next() {
        if c != '\\' {
            out.push(c);
            continue;
        }
        match chars.next() {
            Some('n') => out.push('\n'),
            Some('t') => out.push('\t'),
            Some('r') => out.push('\r'),
            Some('v') => out.push('\u{0b}'),
            Some('f') => out.push('\u{0c}'),
            Some(other) => out.push(other),
            None => out.push('\\'),
        }
    }
    out
}

/// The body of the C string literal starting at `text[0] == '"'` and the rest after it.
fn c_string(text: &str) -> Option<(&str, &str)> {
    let body = text.strip_prefix('"')?;
    let mut escaped = false;
    for (i, c) in body.char_indices() {
        match (escaped, c) {
            (true, _) => escaped = false,
            (false, '\\') => escaped = true,
            (false, '"') => return Some((&body[..i], &body[i + 1..])),
            _ => {}
        }
    }
    None
}

/// Every `%meta{string,vstructConditionalExpr,"…"}` value of an `.oso` text, C-unescaped.
pub fn oso_exprs(text: &str) -> Vec<String> {
    let marker = format!("%meta{{string,{KEY},");
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find(&marker) {
        rest = &rest[i + marker.len()..];
        if let Some((body, after)) = c_string(rest) {
            out.push(c_unescape(body));
            rest = after;
        }
    }
    out
}

/// Every `vstructConditionalExpr = "…" "…" …` in preprocessed OSL, adjacent string literals
/// joined and C-unescaped.
pub fn osl_exprs(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(i) = text[from..].find(KEY) {
        from += i + KEY.len();
        let Some(mut rest) = text[from..].trim_start().strip_prefix('=') else {
            continue;
        };
        let mut joined = String::new();
        let mut pieces = 0;
        while let Some((body, after)) = c_string(rest.trim_start()) {
            joined.push_str(&c_unescape(body));
            pieces += 1;
            rest = after;
        }
        if pieces > 0 {
            out.push(joined);
        }
    }
    out
}

/// The output of `cpp` on one file.
pub struct Preprocessed {
    /// The preprocessed text.
    pub text: String,
    /// True if `cpp` exited successfully.
    pub ok: bool,
    /// What `cpp` printed on stderr.
    pub stderr: String,
}

/// Run `cpp -P -I include -I . FILE` in `dir`. `None` if `cpp` cannot be started.
pub fn preprocess_osl(dir: &Path, file: &str) -> Option<Preprocessed> {
    let output = Command::new("cpp")
        .args(["-P", "-I", "include", "-I", ".", file])
        .current_dir(dir)
        .output()
        .ok()?;
    Some(Preprocessed {
        text: String::from_utf8_lossy(&output.stdout).into_owned(),
        ok: output.status.success(),
        stderr: String::from_utf8_lossy(&output.stderr).into_owned(),
    })
}

/// Files with one of the extensions under `dir`, sorted.
pub fn files_with_ext(dir: &Path, ext: &str) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == ext) {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// The OSL sources whose conditionals are checked, relative to `fixtures/osl/laika`.
pub const OSL_FILES: [&str; 4] = [
    "material/v2_PxrSurfaceAdapter.osl",
    "material/v2_PxrSurface.osl",
    "material/v2_PxrSurfaceModify.osl",
    "material/v2_Displacement.osl",
];

/// Every distinct expression in the fixtures (args, oso, and the OSL if `cpp` runs), in
/// first-seen order.
pub fn distinct_fixture_exprs(fixtures: &Path) -> Vec<String> {
    let mut all = Vec::new();
    for f in files_with_ext(&fixtures.join("args"), "args") {
        all.extend(args_exprs(&std::fs::read_to_string(f).unwrap_or_default()));
    }
    for f in files_with_ext(&fixtures.join("oso"), "oso") {
        all.extend(oso_exprs(&std::fs::read_to_string(f).unwrap_or_default()));
    }
    let osl_dir = fixtures.join("osl/laika");
    for file in OSL_FILES {
        if let Some(p) = preprocess_osl(&osl_dir, file) {
            all.extend(osl_exprs(&p.text));
        }
    }
    let mut distinct: Vec<String> = Vec::new();
    for e in all {
        if !distinct.contains(&e) {
            distinct.push(e);
        }
    }
    distinct
}
