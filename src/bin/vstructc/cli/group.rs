//! Grouping of human diagnostics: one diagnostic per message shape across nodes.
//!
//! A scene of thousands of materials built from one template often gives every material the
//! same finding. The library returns each of them (and `--diag-format json` prints each);
//! the human report prints one diagnostic that says how many nodes it concerns and names the
//! first few, with the first one's location and snippet.
//!
//! The rule ("the same message shape"): two diagnostics are grouped when both name a node
//! ([`Diagnostic::node`]), their nodes differ, and they have the same severity, code, notes
//! and message once every occurrence of their own node's handle as a whole name is replaced
//! by `<node>` (whole: not preceded or followed by a letter, digit or `_`). Anything else in
//! the message (another node's handle, a value, a parameter name) must be equal, so a group
//! states one fact about each of its nodes. Diagnostics without a node are never grouped.

use std::collections::{HashMap, HashSet};
use vstructc::diag::{Diagnostic, Severity};

/// What the grouped message puts where a node's handle was.
pub const NODE: &str = "<node>";

/// How many nodes a grouped message names.
pub const NAMED: usize = 3;

/// One entry of a human report: a diagnostic alone, or the first of a group with the handles
/// of every node the group holds (in list order, the first diagnostic's node first).
#[derive(Debug)]
pub struct Entry<'a> {
    /// The first diagnostic of the entry.
    pub first: &'a Diagnostic,
    /// The nodes of a group of more than one diagnostic; empty for a diagnostic alone.
    pub nodes: Vec<&'a str>,
}

impl Entry<'_> {
    /// How many diagnostics the entry stands for.
    pub fn count(&self) -> usize {
        self.nodes.len().max(1)
    }

    /// The diagnostic to print: the first one, or for a group its message shape followed by
    /// the number of nodes and the first [`NAMED`] of them.
    pub fn diagnostic(&self) -> std::borrow::Cow<'_, Diagnostic> {
        if self.nodes.len() < 2 {
            return std::borrow::Cow::Borrowed(self.first);
        }
        let node = self.first.node.as_deref().unwrap_or_default();
        let mut named: Vec<&str> = self.nodes.iter().copied().take(NAMED).collect();
        if self.nodes.len() > NAMED {
            named.push("…");
        }
        let mut d = self.first.clone();
        d.message = format!(
            "{} on {} nodes ({})",
            shape(&self.first.message, node),
            thousands(self.nodes.len()),
            named.join(", ")
        );
        std::borrow::Cow::Owned(d)
    }
}

/// `n` with a comma between groups of three digits (`2,000`).
pub fn thousands(n: usize) -> String {
    let digits = n.to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3);
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

fn is_name_char(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// `text` with every whole occurrence of `handle` replaced by [`NODE`].
pub fn shape(text: &str, handle: &str) -> String {
    if handle.is_empty() {
        return text.to_string();
    }
    let mut out = String::with_capacity(text.len());
    let mut rest = 0;
    let mut from = 0;
    while let Some(found) = text[from..].find(handle) {
        let at = from + found;
        let end = at + handle.len();
        let before = text[..at]
            .chars()
            .next_back()
            .is_none_or(|c| !is_name_char(c));
        let after = text[end..].chars().next().is_none_or(|c| !is_name_char(c));
        if before && after {
            out.push_str(&text[rest..at]);
            out.push_str(NODE);
            rest = end;
            from = end;
        } else {
            // Step over one character: occurrences may overlap (`aa` in `aaa`).
            from = at + text[at..].chars().next().map_or(1, char::len_utf8);
        }
    }
    out.push_str(&text[rest..]);
    out
}

/// What must be equal for two diagnostics to be grouped.
#[derive(Hash, PartialEq, Eq)]
struct Key {
    severity: Severity,
    code: &'static str,
    message: String,
    notes: Vec<String>,
}

/// `items` as report entries, in the order of each entry's first diagnostic: those of the
/// same message shape on different nodes as one entry (see the module's rule). Linear in the
/// number of diagnostics and the length of their text.
pub fn group<'a>(items: &[&'a Diagnostic]) -> Vec<Entry<'a>> {
    let mut entries: Vec<Entry<'a>> = Vec::with_capacity(items.len());
    let mut index: HashMap<Key, usize> = HashMap::new();
    // (entry, node) of every diagnostic in a groupable entry.
    let mut members: HashSet<(usize, &'a str)> = HashSet::new();
    for &d in items {
        let alone = Entry {
            first: d,
            nodes: Vec::new(),
        };
        let Some(node) = d.node.as_deref() else {
            entries.push(alone);
            continue;
        };
        let key = Key {
            severity: d.severity,
            code: d.code.as_str(),
            message: shape(&d.message, node),
            notes: d.notes.iter().map(|n| shape(n, node)).collect(),
        };
        match index.get(&key) {
            Some(&i) => {
                // A second diagnostic of one shape about the same node says something else
                // (another place in it): an entry of its own.
                if !members.insert((i, node)) {
                    entries.push(alone);
                    continue;
                }
                let entry = &mut entries[i];
                if entry.nodes.is_empty() {
                    entry
                        .nodes
                        .push(entry.first.node.as_deref().unwrap_or_default());
                }
                entry.nodes.push(node);
            }
            None => {
                members.insert((entries.len(), node));
                index.insert(key, entries.len());
                entries.push(alone);
            }
        }
    }
    entries
}
