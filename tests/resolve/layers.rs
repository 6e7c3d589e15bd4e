//! The layering of `src/` (ARCHITECTURE.md, "imports point down"): `diag` imports nothing
//! of `limits`, the top-level modules import one another in one direction only, and the
//! files of `src/interp/material/` read top-down.
//!
//! The checks read the library's sources: every `use` declaration and every path written
//! from `crate::`, `super::` or `self::` in code (comments and literals left out) is
//! resolved to the module it names; an item that a folder's `mod.rs` re-exports counts as
//! an import of the file it comes from. A method call through a type names no module and is
//! not seen. The binary (`src/bin/`) is a crate of its own and is not read.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The files of `src/interp/material/`, top to bottom: a file may import only files after
/// it. (The module documentation of `src/interp/material/mod.rs` says what each holds.)
const MATERIAL_ORDER: &[&str] = &[
    "compile", "plan", "lanes", "batch", "prepare", "uniform", "prepared", "form", "packs", "leaf",
    "record",
];

/// A module path below the crate root (`["interp", "material"]`; empty for the root).
type ModPath = Vec<String>;

/// One path a module writes, resolved from the crate root.
struct Import {
    /// The module that writes it (a file's module, or an inline `mod` inside it).
    from: ModPath,
    /// What it names, from the crate root.
    to: ModPath,
    /// Written in a `use` declaration (rather than in code).
    in_use: bool,
    /// The file, for messages.
    file: PathBuf,
}

/// What the sources hold: every module and every path they write.
struct Crate {
    modules: BTreeSet<ModPath>,
    imports: Vec<Import>,
}

fn src_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// The library's `.rs` files under `dir` (not the binary's).
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .expect("src/ readable")
        .map(|e| e.expect("directory entry").path())
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            if path != src_dir().join("bin") {
                rust_files(&path, out);
            }
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The module a file defines: `src/a/b.rs` and `src/a/b/mod.rs` are `a::b`.
fn module_of(file: &Path) -> ModPath {
    let rel = file.strip_prefix(src_dir()).expect("under src/");
    let mut parts: Vec<String> = rel
        .iter()
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    let last = parts.pop().expect("a file name");
    let stem = last.trim_end_matches(".rs");
    if stem != "mod" && stem != "lib" {
        parts.push(stem.to_string());
    }
    parts
}

/// The source with comments, string and character literals blanked out, so that only code
/// is read (a path in a doc comment or a message is no import).
fn code_only(src: &str) -> String {
    let c: Vec<char> = src.chars().collect();
    let mut out = String::with_capacity(src.len());
    let mut i = 0;
    let at = |i: usize| c.get(i).copied().unwrap_or('\0');
    while i < c.len() {
        let ch = c[i];
        if ch == '/' && at(i + 1) == '/' {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if ch == '/' && at(i + 1) == '*' {
            let mut depth = 0;
            loop {
                if i >= c.len() {
                    break;
                }
                if c[i] == '/' && at(i + 1) == '*' {
                    depth += 1;
                    i += 2;
                } else if c[i] == '*' && at(i + 1) == '/' {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
            out.push(' ');
        } else if (ch == 'r' || (ch == 'b' && at(i + 1) == 'r'))
            && !(i > 0 && (c[i - 1].is_alphanumeric() || c[i - 1] == '_'))
            && {
                let mut j = i + if ch == 'b' { 2 } else { 1 };
                while at(j) == '#' {
                    j += 1;
                }
                at(j) == '"'
            }
        {
            // A raw string: `r##"…"##`.
            let mut j = i + if ch == 'b' { 2 } else { 1 };
            let mut hashes = 0;
            while at(j) == '#' {
                hashes += 1;
                j += 1;
            }
            j += 1;
            loop {
                if j >= c.len() {
                    break;
                }
                if c[j] == '"' && (1..=hashes).all(|k| at(j + k) == '#') {
                    j += 1 + hashes;
                    break;
                }
                j += 1;
            }
            i = j;
            out.push_str("\"\"");
        } else if ch == '"' {
            i += 1;
            while i < c.len() && c[i] != '"' {
                i += if c[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
            out.push_str("\"\"");
        } else if ch == '\'' && (at(i + 1) == '\\' || (at(i + 2) == '\'' && at(i + 1) != '\'')) {
            // A character literal (a lifetime has no closing quote).
            i += 1;
            while i < c.len() && c[i] != '\'' {
                i += if c[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
            out.push_str("' '");
        } else {
            out.push(ch);
            i += 1;
        }
    }
    out
}

/// Identifiers, `::` and single punctuation characters.
fn tokens(code: &str) -> Vec<String> {
    let c: Vec<char> = code.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < c.len() {
        let ch = c[i];
        if ch.is_whitespace() {
            i += 1;
        } else if ch.is_alphanumeric() || ch == '_' {
            let start = i;
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
            out.push(c[start..i].iter().collect());
        } else if ch == ':' && c.get(i + 1) == Some(&':') {
            out.push("::".to_string());
            i += 2;
        } else {
            out.push(ch.to_string());
            i += 1;
        }
    }
    out
}

fn is_ident(t: &str) -> bool {
    t.chars()
        .next()
        .is_some_and(|c| c.is_alphabetic() || c == '_')
}

/// The paths of a use tree (`a::{b, c::d as e, self}`), each with the name it brings into
/// scope (the alias, or the last segment; `None` for a glob).
fn use_tree(toks: &[String]) -> Vec<(Vec<String>, Option<String>)> {
    fn parse(
        toks: &[String],
        pos: &mut usize,
        prefix: &[String],
        out: &mut Vec<(Vec<String>, Option<String>)>,
    ) {
        let mut path = prefix.to_vec();
        loop {
            match toks.get(*pos).map(String::as_str) {
                Some("{") => {
                    *pos += 1;
                    loop {
                        match toks.get(*pos).map(String::as_str) {
                            Some("}") => {
                                *pos += 1;
                                break;
                            }
                            Some(",") => *pos += 1,
                            None => return,
                            _ => parse(toks, pos, &path, out),
                        }
                    }
                    return;
                }
                Some("*") => {
                    *pos += 1;
                    out.push((path, None));
                    return;
                }
                Some("::") => *pos += 1,
                Some(t) if is_ident(t) => {
                    *pos += 1;
                    if t == "self"
                        && !path.is_empty()
                        && toks.get(*pos).map(String::as_str) != Some("::")
                    {
                        let name = path.last().cloned();
                        out.push((path, name));
                        return;
                    }
                    path.push(t.to_string());
                    if toks.get(*pos).map(String::as_str) == Some("as") {
                        let alias = toks.get(*pos + 1).cloned();
                        *pos += 2;
                        out.push((path, alias));
                        return;
                    }
                    if toks.get(*pos).map(String::as_str) != Some("::") {
                        let name = path.last().cloned();
                        out.push((path, name));
                        return;
                    }
                }
                _ => {
                    if path.len() > prefix.len() {
                        let name = path.last().cloned();
                        out.push((path, name));
                    }
                    return;
                }
            }
        }
    }
    let mut out = Vec::new();
    let mut pos = 0;
    // Leading `::` (an extern crate) or none.
    parse(toks, &mut pos, &[], &mut out);
    out
}

/// `segs`, written in module `here`, from the crate root; `None` for a path into another
/// crate (std, glam, ...).
fn resolve(here: &[String], segs: &[String], modules: &BTreeSet<ModPath>) -> Option<ModPath> {
    let first = segs.first()?;
    let (mut base, rest): (ModPath, &[String]) = match first.as_str() {
        "crate" => (Vec::new(), &segs[1..]),
        "self" => (here.to_vec(), &segs[1..]),
        "super" => {
            let mut base = here.to_vec();
            let mut k = 0;
            while segs.get(k).is_some_and(|s| s == "super") {
                base.pop();
                k += 1;
            }
            (base, &segs[k..])
        }
        _ => {
            // A child module of `here` (edition 2024 paths are relative); anything else is
            // another crate or a local item.
            let mut child = here.to_vec();
            child.push(first.clone());
            if !modules.contains(&child) {
                return None;
            }
            (here.to_vec(), segs)
        }
    };
    base.extend(rest.iter().cloned());
    Some(base)
}

/// Reads `src/`.
fn read_crate() -> Crate {
    let mut files = Vec::new();
    rust_files(&src_dir(), &mut files);
    let mut modules: BTreeSet<ModPath> = files.iter().map(|f| module_of(f)).collect();
    let sources: Vec<(PathBuf, Vec<String>)> = files
        .iter()
        .map(|f| {
            let src = std::fs::read_to_string(f).expect("source readable");
            (f.clone(), tokens(&code_only(&src)))
        })
        .collect();
    // Inline modules first (`mod tests { … }`), so that paths into them resolve.
    let mut raw = Vec::new();
    for (file, toks) in &sources {
        let base = module_of(file);
        // (module, brace depth at which it closes)
        let mut stack: Vec<(ModPath, usize)> = vec![(base.clone(), usize::MAX)];
        let mut depth = 0usize;
        let mut i = 0;
        while i < toks.len() {
            let here = stack.last().expect("file module").0.clone();
            match toks[i].as_str() {
                "{" => depth += 1,
                "}" => {
                    depth = depth
                        .checked_sub(1)
                        .unwrap_or_else(|| panic!("{}: unbalanced braces", file.display()));
                    if stack.last().is_some_and(|(_, d)| *d == depth) {
                        stack.pop();
                    }
                }
                "mod" if toks.get(i + 2).map(String::as_str) == Some("{") => {
                    let mut inner = here.clone();
                    inner.push(toks[i + 1].clone());
                    modules.insert(inner.clone());
                    stack.push((inner, depth));
                    depth += 1;
                    i += 3;
                    continue;
                }
                "use" => {
                    let end = (i..toks.len())
                        .find(|&j| toks[j] == ";")
                        .unwrap_or(toks.len());
                    for (path, name) in use_tree(&toks[i + 1..end]) {
                        raw.push((file.clone(), here.clone(), path, name, true));
                    }
                    i = end;
                    continue;
                }
                "crate" | "super" | "self"
                    if toks.get(i + 1).map(String::as_str) == Some("::")
                        && !(i > 0 && (toks[i - 1] == "::" || toks[i - 1] == "$")) =>
                {
                    let mut path = vec![toks[i].clone()];
                    let mut j = i + 1;
                    while toks.get(j).map(String::as_str) == Some("::")
                        && toks.get(j + 1).is_some_and(|t| is_ident(t))
                    {
                        path.push(toks[j + 1].clone());
                        j += 2;
                    }
                    raw.push((file.clone(), here.clone(), path, None, false));
                    i = j;
                    continue;
                }
                _ => {}
            }
            i += 1;
        }
    }
    let imports = raw
        .into_iter()
        .filter_map(|(file, from, path, _, in_use)| {
            let to = resolve(&from, &path, &modules)?;
            let file = file
                .strip_prefix(env!("CARGO_MANIFEST_DIR"))
                .map(Path::to_path_buf)
                .unwrap_or(file);
            Some(Import {
                from,
                to,
                in_use,
                file,
            })
        })
        .collect();
    Crate { modules, imports }
}

impl Crate {
    /// The modules directly inside `parent`.
    fn children(&self, parent: &[String]) -> BTreeSet<String> {
        self.modules
            .iter()
            .filter(|m| m.len() == parent.len() + 1 && m.starts_with(parent))
            .map(|m| m[parent.len()].clone())
            .collect()
    }

    /// The imports among the children of `parent`: `a → b` when a file of child `a` names
    /// something in child `b`, or an item that `parent`'s own file re-exports from `b`. An
    /// item of `parent`'s own file is the node `(mod)`; its re-exports and module
    /// declarations are no import of it.
    fn graph(&self, parent: &[String]) -> BTreeMap<String, BTreeMap<String, PathBuf>> {
        let children = self.children(parent);
        let own = "(mod)".to_string();
        // Names `parent`'s own file brings in from a child: `pub use child::Item`.
        let mut reexports: BTreeMap<String, String> = BTreeMap::new();
        for im in &self.imports {
            if im.in_use
                && im.from == parent
                && im.to.len() > parent.len() + 1
                && im.to.starts_with(parent)
                && children.contains(&im.to[parent.len()])
            {
                reexports.insert(
                    im.to.last().expect("a path").clone(),
                    im.to[parent.len()].clone(),
                );
            }
        }
        let mut graph: BTreeMap<String, BTreeMap<String, PathBuf>> = BTreeMap::new();
        for im in &self.imports {
            if !im.from.starts_with(parent) || !im.to.starts_with(parent) {
                continue;
            }
            let from = match im.from.get(parent.len()) {
                Some(child) => child.clone(),
                // The folder's own file: its `use` declarations are re-exports.
                None if im.in_use => continue,
                None => own.clone(),
            };
            let to = match im.to.get(parent.len()) {
                Some(name) if children.contains(name) => name.clone(),
                Some(name) => reexports.get(name).cloned().unwrap_or_else(|| own.clone()),
                None => continue,
            };
            if from != to {
                graph
                    .entry(from)
                    .or_default()
                    .entry(to)
                    .or_insert_with(|| im.file.clone());
            }
        }
        graph
    }
}

/// The circles of `graph`, each as `a → b → … → a` with the file of each arrow.
fn circles(graph: &BTreeMap<String, BTreeMap<String, PathBuf>>) -> Vec<String> {
    // Each strongly connected component with more than one node is a circle; one path
    // around it is reported.
    let nodes: BTreeSet<&String> = graph
        .keys()
        .chain(graph.values().flat_map(|m| m.keys()))
        .collect();
    let reach = |from: &String| -> BTreeSet<String> {
        let mut seen = BTreeSet::new();
        let mut stack = vec![from.clone()];
        while let Some(n) = stack.pop() {
            for next in graph.get(&n).into_iter().flat_map(|m| m.keys()) {
                if seen.insert(next.clone()) {
                    stack.push(next.clone());
                }
            }
        }
        seen
    };
    let mut reported: BTreeSet<String> = BTreeSet::new();
    let mut out = Vec::new();
    for &n in &nodes {
        if reported.contains(n) || !reach(n).contains(n) {
            continue;
        }
        // Breadth-first back to `n`, for the shortest circle through it.
        let mut prev: BTreeMap<String, String> = BTreeMap::new();
        let mut queue = std::collections::VecDeque::from([n.clone()]);
        'search: while let Some(m) = queue.pop_front() {
            for next in graph.get(&m).into_iter().flat_map(|x| x.keys()) {
                if next == n {
                    prev.insert(format!("{n}#end"), m.clone());
                    break 'search;
                }
                if !prev.contains_key(next) {
                    prev.insert(next.clone(), m.clone());
                    queue.push_back(next.clone());
                }
            }
        }
        let mut back = Vec::new();
        let mut at = prev[&format!("{n}#end")].clone();
        while &at != n {
            back.push(at.clone());
            at = prev[&at].clone();
        }
        back.reverse();
        let path: Vec<String> = std::iter::once(n.clone())
            .chain(back)
            .chain(std::iter::once(n.clone()))
            .collect();
        let arrows: Vec<String> = path
            .windows(2)
            .map(|w| format!("{} → {} ({})", w[0], w[1], graph[&w[0]][&w[1]].display()))
            .collect();
        // Every node of the component is reported with this circle once.
        let component: BTreeSet<String> = reach(n)
            .into_iter()
            .filter(|m| reach(m).contains(n))
            .collect();
        reported.extend(component);
        out.push(arrows.join(", "));
    }
    out
}

#[test]
fn diag_imports_nothing_of_limits() {
    let krate = read_crate();
    let wrong: BTreeSet<String> = krate
        .imports
        .iter()
        .filter(|im| im.from.first().is_some_and(|m| m == "diag"))
        .filter(|im| im.to.first().is_some_and(|m| m == "limits"))
        .map(|im| format!("{}: {}", im.file.display(), im.to.join("::")))
        .collect();
    assert!(
        wrong.is_empty(),
        "diag sits below limits (limits builds diagnostics; the types both need are in \
         src/diag/limit.rs), but imports it:\n{}",
        wrong.into_iter().collect::<Vec<_>>().join("\n")
    );
}

#[test]
fn top_level_modules_import_one_another_one_way() {
    let circles = circles(&read_crate().graph(&[]));
    assert!(
        circles.is_empty(),
        "import circles among the top-level modules of src/ (move what both sides need into \
         the lower one):\n{}",
        circles.join("\n")
    );
}

#[test]
fn material_files_read_top_down() {
    let krate = read_crate();
    let folder: ModPath = vec!["interp".into(), "material".into()];
    let graph = krate.graph(&folder);
    let circles = circles(&graph);
    assert!(
        circles.is_empty(),
        "import circles in src/interp/material/:\n{}",
        circles.join("\n")
    );
    let children = krate.children(&folder);
    let listed: BTreeSet<String> = MATERIAL_ORDER.iter().map(|s| s.to_string()).collect();
    assert_eq!(
        children, listed,
        "src/interp/material/ holds files that MATERIAL_ORDER does not list, or lists files \
         that are gone: give each new file its place in the order"
    );
    let rank = |m: &str| MATERIAL_ORDER.iter().position(|x| *x == m);
    let mut upward = Vec::new();
    for (from, tos) in &graph {
        for (to, file) in tos {
            match (rank(from), rank(to)) {
                (Some(a), Some(b)) if a < b => {}
                _ => upward.push(format!("{from} → {to} ({})", file.display())),
            }
        }
    }
    assert!(
        upward.is_empty(),
        "files of src/interp/material/ that import a file above them, or the folder's mod.rs \
         (which only declares and re-exports; the order is MATERIAL_ORDER):\n{}",
        upward.join("\n")
    );
}

#[test]
fn no_interp_module_imports_back_into_material() {
    let graph = read_crate().graph(&["interp".to_string()]);
    let through_material: Vec<String> = circles(&graph)
        .into_iter()
        .filter(|c| c.split(", ").any(|arrow| arrow.starts_with("material → ")))
        .collect();
    assert!(
        through_material.is_empty(),
        "import circles through src/interp/material/ (the material sits above the leaves, \
         kernels and tables it uses):\n{}",
        through_material.join("\n")
    );
}

/// The reader's parts do what the checks rely on: comments and literals are not read, a use
/// tree gives each path with the name it brings in, and a circle is found with its arrows.
#[test]
fn the_reader_finds_circles_and_skips_comments() {
    let toks = tokens(&code_only(
        "// use crate::limits;\nlet s = \"crate::limits::X\"; let c = '\\''; \
         use crate::diag::{a, b::{c as d, self}};",
    ));
    assert!(!toks.iter().any(|t| t == "limits"), "{toks:?}");
    let start = toks.iter().position(|t| t == "use").unwrap();
    let end = toks.iter().rposition(|t| t == ";").unwrap();
    let paths: Vec<String> = use_tree(&toks[start + 1..end])
        .into_iter()
        .map(|(p, n)| format!("{}={}", p.join("::"), n.unwrap_or_default()))
        .collect();
    assert_eq!(
        paths,
        [
            "crate::diag::a=a",
            "crate::diag::b::c=d",
            "crate::diag::b=b"
        ]
    );
    let mut graph: BTreeMap<String, BTreeMap<String, PathBuf>> = BTreeMap::new();
    graph
        .entry("a".into())
        .or_default()
        .insert("b".into(), "a.rs".into());
    graph
        .entry("b".into())
        .or_default()
        .insert("c".into(), "b.rs".into());
    graph
        .entry("c".into())
        .or_default()
        .insert("a".into(), "c.rs".into());
    graph
        .entry("c".into())
        .or_default()
        .insert("d".into(), "c.rs".into());
    assert_eq!(
        circles(&graph),
        ["a → b (a.rs), b → c (b.rs), c → a (c.rs)"]
    );
}
