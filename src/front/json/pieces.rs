//! The JSON reader in pieces on rayon's pool: the members of `materials` are split into
//! pieces of consecutive materials, each piece is read on a thread of the pool into
//! [`MaterialOut`]s with its findings, and the calling thread adds them to the network in
//! document order, a window of pieces behind the reading.
//!
//! The split needs no scan of the text. The whitespace before the first material's name
//! (with a line break in it) makes a separator pattern, `,` + that whitespace + `"`, which in
//! text laid out line by line only occurs between two materials (a line break is never inside
//! a JSON string). A piece starts at the first occurrence of the pattern after its target
//! offset and reads materials until it passes the start of the next piece: the calling
//! thread checks that it ended exactly there, so a guess that was not a boundary is found
//! out, never trusted. Each material is read by the byte scanner of `scan`, which finds its
//! end, when it settles it; else its value is read alone by serde_json, as the text up to the
//! next occurrence of the pattern (a complete JSON value there, or the guess was wrong and
//! the value's end is found by matching brackets).
//!
//! Anything this path does not settle the way the one-thread reader does (a syntax error, a
//! duplicate key, a name with escapes, text on one line, a misplaced guess, deeply nested
//! values) makes [`read`] return `None`, and the caller reads the document on one thread:
//! that reader then reports the error with its line and column. Otherwise the text is valid
//! JSON: the document's own members are read from the text with an empty `materials`, and
//! the findings of all are reported in the order of the checks, as on one thread.
//! Materials with shorthand values need the declared types, which the pool's threads do not
//! get (`ParamTypes` is not `Sync`): the calling thread reads those again.

use super::{DocSeed, Found, MaterialOut, Memo, NodeState, Order, Reader, read_material, scan};
use crate::network::{Network, ParamTypes};
use memchr::memmem;
use rustc_hash::FxHashSet;
use serde::de::DeserializeSeed;
use std::ops::Range;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc::channel;

/// Bytes per piece, about: some forty materials of the bench scene, so that handing a piece
/// to the pool costs little against reading it.
pub(super) const PIECE_BYTES: usize = 256 * 1024;

/// Bytes of JSON per node assumed when room for the nodes is reserved: a node of the bench
/// scene takes about 1 KB as the writer lays it out, and a terser file outgrows the room
/// only by a doubling or two.
const BYTES_PER_NODE: usize = 512;

/// Value trees nested deeper than this within a material send the document to the
/// one-thread reader: serde_json's nesting limit counts the levels above the material too.
const MAX_DEPTH: u32 = 64;

/// Findings with their place in the order of the checks.
type Findings = Vec<(Order, Found)>;

/// One material of a piece (its name's and value's byte ranges in the text).
enum Read {
    Done {
        name: Range<usize>,
        out: MaterialOut,
    },
    /// It holds a shorthand value: the calling thread reads it again, with the types.
    NeedsTypes {
        name: Range<usize>,
        value: Range<usize>,
    },
}

/// A piece read: its materials and their findings (groups counted from its first material).
struct PieceRead {
    /// Where it started: the `{` of `materials` or a `,` between two materials.
    start: usize,
    materials: Vec<Read>,
    found: Findings,
    /// Where it ended: the `,` before the next piece's first material, or the `}` that closes
    /// `materials` (`closed`).
    end: usize,
    closed: bool,
}

/// Reads `text` in pieces of about `piece` bytes: the network and the findings (unsorted),
/// or `None` when the document must be read on one thread (module docs). The text is checked
/// to be UTF-8 as the threads read it: the scanner checks each string it reads, and the rest
/// is ASCII it matched or text given to serde_json as `str`.
pub(super) fn read(
    text: &[u8],
    file: &Arc<str>,
    types: &dyn ParamTypes,
    piece: usize,
) -> Option<(Network, Findings)> {
    let b = text;
    let (open, pattern) = locate_materials(b)?;
    let mut starts = vec![open];
    let mut target = open + piece;
    while target < b.len() {
        let Some(k) = memmem::find(&b[target..], &pattern) else {
            break;
        };
        starts.push(target + k);
        target += k + piece.max(1);
    }
    let stops: Vec<usize> = starts[1..]
        .iter()
        .copied()
        .chain(std::iter::once(usize::MAX))
        .collect();
    let mut net = Network::new();
    net.reserve_for_input(text.len(), BYTES_PER_NODE, u64::MAX);
    let mut asm = Assembler {
        text,
        net,
        found: Vec::new(),
        main: Reader::new(file.clone(), Some(types), None),
        names: FxHashSet::default(),
        materials: 0,
        expected: open,
        close: None,
        failed: false,
    };
    // Each thread of the pool takes the next piece in document order and sends it, read, to
    // the calling thread, which adds the pieces in order as they arrive (the ones that come
    // early wait in `early`). No thread waits for another's piece but the calling thread.
    let next = AtomicUsize::new(0);
    let stop = AtomicBool::new(false);
    let (tx, rx) = channel::<(usize, Option<PieceRead>)>();
    rayon::in_place_scope(|scope| {
        for _ in 0..rayon::current_num_threads().min(starts.len()) {
            let (tx, next, stop, starts, stops) = (tx.clone(), &next, &stop, &starts, &stops);
            let pattern = &pattern;
            scope.spawn(move |_| {
                let mut memo = Memo::default();
                while !stop.load(Ordering::Relaxed) {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(&start) = starts.get(i) else {
                        return;
                    };
                    let read = read_piece(text, file, start, stops[i], pattern, &mut memo);
                    if tx.send((i, read)).is_err() {
                        return;
                    }
                }
            });
        }
        drop(tx);
        let mut early: Vec<Option<Option<PieceRead>>> = Vec::new();
        let mut want = 0;
        for (i, read) in &rx {
            if i >= early.len() {
                early.resize_with(i + 1, || None);
            }
            early[i] = Some(read);
            while let Some(read) = early.get_mut(want).and_then(Option::take) {
                asm.add(read);
                want += 1;
            }
            if asm.failed || asm.close.is_some() {
                stop.store(true, Ordering::Relaxed);
                break;
            }
        }
    });
    if asm.failed {
        return None;
    }
    let close = asm.close?;
    // The document's own members, with an empty `materials` in place of the one read.
    let mut skeleton = Vec::with_capacity(open + 2 + (b.len() - close));
    skeleton.extend_from_slice(&b[..open]);
    skeleton.extend_from_slice(b"{}");
    skeleton.extend_from_slice(&b[close + 1..]);
    let skeleton = String::from_utf8(skeleton).ok()?;
    let mut doc = Reader::new(file.clone(), Some(types), None);
    let mut de = serde_json::Deserializer::from_str(&skeleton);
    DocSeed(&mut doc)
        .deserialize(&mut de)
        .and_then(|()| de.end())
        .ok()?;
    let mut found = asm.found;
    found.append(&mut doc.found);
    found.append(&mut asm.main.found);
    Some((asm.net, found))
}

/// The calling thread's side: adds the pieces to the network in document order.
struct Assembler<'a, 't> {
    text: &'a [u8],
    net: Network,
    found: Findings,
    /// Reads the materials that need the declared types.
    main: Reader<'t>,
    /// The material names so far (a duplicate is the one-thread reader's error).
    names: FxHashSet<&'a str>,
    materials: u32,
    /// Where the next piece must start.
    expected: usize,
    /// The `}` that closes `materials`, once a piece reached it.
    close: Option<usize>,
    failed: bool,
}

impl Assembler<'_, '_> {
    fn add(&mut self, piece: Option<PieceRead>) {
        let Some(p) = piece.filter(|p| p.start == self.expected) else {
            self.failed = true;
            return;
        };
        let base = self.materials;
        for m in p.materials {
            self.materials += 1;
            let name = match &m {
                Read::Done { name, .. } | Read::NeedsTypes { name, .. } => {
                    utf8(&self.text[name.clone()])
                }
            };
            let Some(name) = name.filter(|name| self.names.insert(name)) else {
                self.failed = true;
                return;
            };
            match m {
                Read::Done { out, .. } => out.add_to(&mut self.net),
                Read::NeedsTypes { value, .. } => {
                    let read = utf8(&self.text[value])
                        .map(|value| read_material(&mut self.main, name, value, self.materials));
                    if !matches!(read, Some(Ok(()))) || self.main.ctx.deepest.get() > MAX_DEPTH {
                        self.failed = true;
                        return;
                    }
                    for out in self.main.done.drain(..) {
                        out.add_to(&mut self.net);
                    }
                }
            }
        }
        self.found.extend(p.found.into_iter().map(|(mut order, f)| {
            order.group += base;
            (order, f)
        }));
        if p.closed {
            self.close = Some(p.end);
        } else {
            self.expected = p.end;
        }
    }
}

/// Reads the materials from `start` (the `{` of `materials` or a `,` before a material) until
/// the `,` at or after `stop`, or the end of `materials`. `None` when the text there is not
/// what the one-thread reader would accept the same way. `memo`: what the thread's readers
/// remember, kept from one piece to the next.
fn read_piece(
    text: &[u8],
    file: &Arc<str>,
    start: usize,
    stop: usize,
    pattern: &[u8],
    memo: &mut Memo,
) -> Option<PieceRead> {
    let mut r = Reader::new(file.clone(), None, None);
    r.memo = std::mem::take(memo);
    let read = read_materials(&mut r, text, start, stop, pattern);
    *memo = std::mem::take(&mut r.memo);
    read
}

/// [`read_piece`] with the piece's reader.
fn read_materials(
    r: &mut Reader<'_>,
    text: &[u8],
    start: usize,
    stop: usize,
    pattern: &[u8],
) -> Option<PieceRead> {
    let b = text;
    let mut n = NodeState::default();
    let mut materials = Vec::new();
    let mut pos = start;
    loop {
        let k = skip_ws(b, pos + 1);
        let key_end = string_end(b, k)?;
        let name = k + 1..key_end;
        let name_text = utf8(&b[name.clone()])?;
        let colon = skip_ws(b, key_end + 1);
        if b.get(colon) != Some(&b':') {
            return None;
        }
        let v = skip_ws(b, colon + 1);
        if b.get(v) != Some(&b'{') {
            return None;
        }
        let group = materials.len() as u32 + 1;
        let (found, done) = (r.found.len(), r.done.len());
        let mut end = scan::read_material(r, &mut n, name_text, b, v, group);
        if end.is_none() {
            r.found.truncate(found);
            r.done.truncate(done);
            if let Some(q) = memmem::find(&b[v..], pattern).map(|k| v + k) {
                let read = utf8(&b[v..q]).map(|value| read_material(r, name_text, value, group));
                if matches!(read, Some(Ok(()))) {
                    end = Some(q);
                } else {
                    r.found.truncate(found);
                    r.done.truncate(done);
                }
            }
        }
        let end = match end {
            Some(end) => end,
            None => {
                let end = value_end(b, v)?;
                read_material(r, name_text, utf8(&b[v..end])?, group).ok()?;
                end
            }
        };
        if r.ctx.deepest.get() > MAX_DEPTH {
            return None;
        }
        if r.needs_types {
            r.found.truncate(found);
            r.done.truncate(done);
            materials.push(Read::NeedsTypes {
                name,
                value: v..end,
            });
        } else {
            let out = r.done.pop()?;
            materials.push(Read::Done { name, out });
        }
        pos = skip_ws(b, end);
        let closed = match b.get(pos) {
            Some(b'}') => true,
            Some(b',') if pos >= stop => false,
            Some(b',') => continue,
            _ => return None,
        };
        return Some(PieceRead {
            start,
            materials,
            found: std::mem::take(&mut r.found),
            end: pos,
            closed,
        });
    }
}

/// The position of the `{` that opens the document's `materials`, and the separator pattern
/// of its members (module docs). `None` for a document this path leaves to one thread.
fn locate_materials(b: &[u8]) -> Option<(usize, Vec<u8>)> {
    let mut i = skip_ws(b, 0);
    if b.get(i) != Some(&b'{') {
        return None;
    }
    loop {
        let k = skip_ws(b, i + 1);
        let key_end = string_end(b, k)?;
        let colon = skip_ws(b, key_end + 1);
        if b.get(colon) != Some(&b':') {
            return None;
        }
        let v = skip_ws(b, colon + 1);
        if &b[k + 1..key_end] == b"materials" {
            if b.get(v) != Some(&b'{') {
                return None;
            }
            let first = skip_ws(b, v + 1);
            let ws = &b[v + 1..first];
            if b.get(first) != Some(&b'"') || !ws.contains(&b'\n') {
                return None;
            }
            let mut pattern = Vec::with_capacity(ws.len() + 2);
            pattern.push(b',');
            pattern.extend_from_slice(ws);
            pattern.push(b'"');
            return Some((v, pattern));
        }
        i = skip_ws(b, any_value_end(b, v)?);
        if b.get(i) != Some(&b',') {
            return None;
        }
    }
}

/// `bytes` as text, if they are UTF-8.
fn utf8(bytes: &[u8]) -> Option<&str> {
    std::str::from_utf8(bytes).ok()
}

/// The position after the JSON whitespace from `i`.
fn skip_ws(b: &[u8], mut i: usize) -> usize {
    while let Some(b' ' | b'\t' | b'\n' | b'\r') = b.get(i) {
        i += 1;
    }
    i
}

/// The position of the quote that closes the string opening at `k`, for a string without
/// escapes or control characters (`None` otherwise, or when no string opens at `k`).
fn string_end(b: &[u8], k: usize) -> Option<usize> {
    if b.get(k) != Some(&b'"') {
        return None;
    }
    let rest = b.get(k + 1..)?;
    let n = memchr::memchr2(b'"', b'\\', rest)?;
    if rest[n] == b'\\' || rest[..n].iter().any(|&c| c < 0x20) {
        return None;
    }
    Some(k + 1 + n)
}

/// The position after the string opening at `k` (escapes skipped, not checked).
fn string_skip(b: &[u8], k: usize) -> Option<usize> {
    let mut j = k + 1;
    loop {
        let n = j + memchr::memchr2(b'"', b'\\', b.get(j..)?)?;
        if b[n] == b'\\' {
            j = n + 2;
        } else {
            return Some(n + 1);
        }
    }
}

/// The position after the object or array opening at `v`, by matching brackets outside
/// strings (a well-formed value's end; the reading of the value checks the rest).
fn value_end(b: &[u8], v: usize) -> Option<usize> {
    let mut depth = 0usize;
    let mut i = v;
    while let Some(&c) = b.get(i) {
        match c {
            b'"' => {
                i = string_skip(b, i)?;
                continue;
            }
            b'{' | b'[' => depth += 1,
            b'}' | b']' => {
                depth = depth.checked_sub(1)?;
                if depth == 0 {
                    return Some(i + 1);
                }
            }
            _ => {}
        }
        i += 1;
    }
    None
}

/// The position after the JSON value starting at `v` (a scalar ends before the next
/// delimiter or whitespace).
fn any_value_end(b: &[u8], v: usize) -> Option<usize> {
    match b.get(v)? {
        b'{' | b'[' => value_end(b, v),
        b'"' => string_skip(b, v),
        _ => {
            let mut i = v;
            while let Some(&c) = b.get(i) {
                if matches!(c, b',' | b'}' | b']' | b' ' | b'\t' | b'\n' | b'\r') {
                    break;
                }
                i += 1;
            }
            (i > v).then_some(i)
        }
    }
}
