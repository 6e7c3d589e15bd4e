//! Human diagnostics with source snippets: the offending line under the location, with a
//! caret under the column (as rustc shows them), and colour when asked for.
//!
//! The library returns diagnostics as data ([`Diagnostic`]); rendering them for a reader is
//! the command line's job. A snippet is shown when the diagnostic has a line and the source
//! is at hand: a text the command registered ([`remember`]: the `expr` argument, standard
//! input), or a regular file of that name no larger than a network input may be (read once
//! per report and kept for the rest of it). Everything else prints as before: the headline,
//! `  --> file:line:col`, related locations and notes.

use annotate_snippets::{Level, Renderer, Snippet};
use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use vstructc::diag::{Diagnostic, Severity};

const MAX_HUMAN_LINE: usize = Diagnostic::MAX_HUMAN_LINE;

/// When diagnostics are coloured (`--color`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum ColorChoice {
    /// Colour when standard error is a terminal and `NO_COLOR` is unset or empty.
    #[default]
    Auto,
    /// Always colour (ANSI escapes), also into a pipe or file.
    Always,
    /// Never colour.
    Never,
}

impl ColorChoice {
    /// Whether to colour output written to standard error.
    pub fn colours_stderr(self) -> bool {
        use std::io::IsTerminal as _;
        self.colours(
            std::env::var_os("NO_COLOR").as_deref(),
            std::io::stderr().is_terminal(),
        )
    }

    /// Whether to colour, given the `NO_COLOR` variable and whether the output is a terminal.
    pub(crate) fn colours(self, no_color: Option<&std::ffi::OsStr>, terminal: bool) -> bool {
        match self {
            ColorChoice::Always => true,
            ColorChoice::Never => false,
            ColorChoice::Auto => terminal && no_color.is_none_or(|v| v.is_empty()),
        }
    }
}

/// Texts registered by name for snippets (inputs that are not files on disk).
static REMEMBERED: Mutex<Option<HashMap<String, Arc<str>>>> = Mutex::new(None);

/// The largest text [`remember`] keeps (a larger standard input is shown without snippets
/// rather than held twice).
const REMEMBER_MAX: usize = 16 << 20;

/// Registers `text` as the source of diagnostics located in `name` (`<expr>`, `<stdin>`).
pub fn remember(name: &str, text: &[u8]) {
    if text.len() > REMEMBER_MAX {
        return;
    }
    let text = String::from_utf8_lossy(text);
    if let Ok(mut map) = REMEMBERED.lock() {
        map.get_or_insert_with(HashMap::new)
            .insert(name.to_string(), Arc::from(text.as_ref()));
    }
}

/// A source text and the byte offset where each of its lines starts.
pub(crate) struct Source {
    text: Arc<str>,
    line_starts: Vec<usize>,
}

impl Source {
    pub(crate) fn new(text: Arc<str>) -> Source {
        let line_starts = std::iter::once(0)
            .chain(newlines(&text).map(|i| i + 1))
            .collect();
        Source { text, line_starts }
    }

    /// Line `line` (1-based) without its line ending, if there is one.
    pub(crate) fn line(&self, line: u32) -> Option<&str> {
        let i = (line as usize).checked_sub(1)?;
        let start = *self.line_starts.get(i)?;
        let end = self
            .line_starts
            .get(i + 1)
            .map_or(self.text.len(), |&next| next - 1);
        let l = &self.text[start..end];
        Some(l.strip_suffix('\r').unwrap_or(l))
    }
}

fn newlines(text: &str) -> impl Iterator<Item = usize> + '_ {
    memchr::memchr_iter(b'\n', text.as_bytes())
}

/// Sources looked up during one report: each file is read and indexed at most once, so a
/// report costs one pass over each file it shows lines of, however many diagnostics it has.
#[derive(Default)]
pub struct Sources {
    cache: HashMap<Arc<str>, Option<Source>>,
}

impl Sources {
    /// The source of `name`, if registered or a readable regular file of at most
    /// [`FILE_MAX`] bytes.
    fn get(&mut self, name: &Arc<str>) -> Option<&Source> {
        self.cache
            .entry(name.clone())
            .or_insert_with(|| load(name).map(Source::new))
            .as_ref()
    }
}

/// The largest file read again for snippets: a larger input's diagnostics show their
/// location without the line (reading gigabytes twice to print a line is not worth it).
const FILE_MAX: u64 = 64 << 20;

fn load(name: &str) -> Option<Arc<str>> {
    if let Some(text) = REMEMBERED
        .lock()
        .ok()
        .and_then(|m| m.as_ref().and_then(|m| m.get(name).cloned()))
    {
        return Some(text);
    }
    if name.starts_with('<') {
        return None;
    }
    // Only regular files: a FIFO or device named in a diagnostic is not read again.
    let meta = std::fs::metadata(name).ok()?;
    if !meta.is_file() || meta.len() > FILE_MAX {
        return None;
    }
    let bytes = std::fs::read(name).ok()?;
    Some(Arc::from(String::from_utf8_lossy(&bytes)))
}

/// Characters of a long source line shown on each side of the column.
pub(crate) const LINE_CONTEXT: usize = MAX_HUMAN_LINE / 2;

/// The part of `line` shown (at most [`LINE_CONTEXT`] characters each side of the 1-based
/// character `column`) and the byte range marked in it: `width` characters from the column
/// (at least one; an empty range just past the end of the line).
pub(crate) fn window(line: &str, column: u32, width: usize) -> (String, std::ops::Range<usize>) {
    let col = (column.max(1) - 1) as usize;
    let first = col.saturating_sub(LINE_CONTEXT);
    let cut_head = first > 0;
    let mut shown = String::new();
    if cut_head {
        shown.push('…');
    }
    let mut start = None;
    let mut end = None;
    let mut cut_tail = false;
    for (i, c) in line.chars().enumerate().skip(first) {
        if i == col {
            start = Some(shown.len());
        }
        if i == col + width.max(1) {
            end = Some(shown.len());
        }
        if i >= col + width.max(1) + LINE_CONTEXT {
            cut_tail = true;
            break;
        }
        // A tab is four spaces (so the caret lines up whatever the terminal's tab stops);
        // other control characters (a stray `\r`, a NUL) are shown as visible escapes.
        if c == '\t' {
            shown.push_str("    ");
        } else if c.is_control() {
            shown.extend(c.escape_default());
        } else {
            shown.push(c);
        }
    }
    let start = start.unwrap_or(shown.len());
    let end = end.unwrap_or(shown.len()).max(start);
    if cut_tail {
        shown.push('…');
    }
    (shown, start..end)
}

/// How many characters the caret marks: the diagnostic's span where its location is in the
/// text the span indexes (`<expr>`), else one.
fn marked_width(d: &Diagnostic, text: &str) -> usize {
    match (&d.span, &d.location) {
        (Some(span), Some(loc)) if &*loc.file == "<expr>" => text
            .get(span.clone())
            .map_or(1, |s| s.chars().take_while(|&c| c != '\n').count()),
        _ => 1,
    }
}

fn level(s: Severity) -> Level {
    match s {
        Severity::Error => Level::Error,
        Severity::Warning => Level::Warning,
        Severity::Info => Level::Info,
        Severity::Note => Level::Note,
    }
}

/// `d` for a reader: the headline and, when the source is at hand, the offending line with a
/// caret under the column; else `  --> file:line:col`. Then related locations and notes.
/// Every line is bounded ([`Diagnostic::MAX_HUMAN_LINE`]); `colour` adds ANSI escapes.
pub fn render(d: &Diagnostic, sources: &mut Sources, colour: bool) -> String {
    let plain = Renderer::plain();
    let renderer = if colour {
        // The caret is drawn as an error-level mark (`^`), in the diagnostic's own colour.
        let styled = Renderer::styled();
        let own = match d.severity {
            Severity::Error => anstyle_error(),
            Severity::Warning => anstyle_warning(),
            _ => anstyle_info(),
        };
        styled.error(own)
    } else {
        plain
    };
    let message = Diagnostic::bound_line(&d.message, MAX_HUMAN_LINE);
    let title = level(d.severity).title(&message).id(d.code.as_str());
    let mut out = String::new();
    let mut shown_location = false;
    if let Some(loc) = d.location.as_ref().filter(|l| l.line > 0) {
        let file = loc.file.clone();
        if let Some(source) = sources.get(&file)
            && let Some(line) = source.line(loc.line)
        {
            let (shown, range) = window(line, loc.column, marked_width(d, &source.text));
            let snippet = Snippet::source(&shown)
                .line_start(loc.line as usize)
                .origin(&file)
                .annotation(Level::Error.span(range));
            let rendered = renderer.render(title.snippet(snippet)).to_string();
            // The crate counts the column in the shown window; the location's own text
            // (the column in the whole line, a JSON Pointer) replaces its `file:line:col`.
            let marker = format!(" {file}:");
            let mut lines: Vec<String> = rendered.lines().map(str::to_string).collect();
            if let Some(origin_line) = lines.iter_mut().find(|l| l.contains("-->"))
                && let Some(at) = origin_line.rfind(&marker)
            {
                origin_line.truncate(at);
                origin_line.push_str(&format!(" {loc}"));
            }
            // The crate closes the snippet with an empty gutter line; notes follow instead.
            if lines
                .last()
                .is_some_and(|l| without_escapes(l).trim() == "|")
            {
                lines.pop();
            }
            out = lines.join("\n");
            shown_location = true;
        }
    }
    if !shown_location {
        let title = level(d.severity).title(&message).id(d.code.as_str());
        out = renderer.render(title).to_string();
        if let Some(loc) = &d.location {
            out.push_str(&format!("\n  --> {loc}"));
        }
    }
    for (label, loc) in &d.related {
        out.push_str(&format!("\n  note: {label}: {loc}"));
    }
    for note in &d.notes {
        for line in note.lines() {
            out.push_str("\n  ");
            out.push_str(line);
        }
    }
    out.lines()
        .map(|l| Diagnostic::bound_line(l, MAX_HUMAN_LINE).into_owned())
        .collect::<Vec<_>>()
        .join("\n")
}

/// `line` without its ANSI escape sequences (`ESC [ … letter`).
pub(crate) fn without_escapes(line: &str) -> String {
    let mut out = String::new();
    let mut chars = line.chars();
    while let Some(c) = chars.next() {
        if c == '\x1b' {
            for d in chars.by_ref() {
                if d.is_ascii_alphabetic() {
                    break;
                }
            }
        } else {
            out.push(c);
        }
    }
    out
}

fn anstyle_error() -> annotate_snippets::renderer::Style {
    annotate_snippets::renderer::AnsiColor::BrightRed
        .on_default()
        .bold()
}

fn anstyle_warning() -> annotate_snippets::renderer::Style {
    annotate_snippets::renderer::AnsiColor::BrightYellow
        .on_default()
        .bold()
}

fn anstyle_info() -> annotate_snippets::renderer::Style {
    annotate_snippets::renderer::AnsiColor::BrightBlue
        .on_default()
        .bold()
}
