//! A byte scanner for one material of the pieces' common case: it walks the material's text
//! and makes the calls the serde visitors make (the same [`NodeState`], [`Reader::close_node`],
//! [`Reader::canonical`] and [`Reader::finish_material`]), so what it builds and finds is
//! theirs. It settles only what it reads exactly as serde_json does: strings without escapes
//! or control characters, numbers whose value both read the same way (below), values nested a
//! few levels, the keys the format defines in the shapes it defines, each key once. On
//! anything else it returns `None` and the caller reads the material with serde_json (after
//! dropping what this reading recorded).
//!
//! Numbers: an integer of up to 19 digits is the `u64` (or `i64`) serde_json gives; a number
//! with a fraction or an exponent is read only when its digits fit in 2^53 and its decimal
//! exponent is within ±22, where one exact product or quotient of two exact doubles is the
//! correctly rounded value, which serde_json gives too (with or without `float_roundtrip`).
//!
//! Parameters read again: a parameter read without a finding whose text (from its name's
//! quote to the closing brace of its `{ "type", "value" }`) holds no other `}` is remembered
//! with its name, declaration and value. A later parameter whose text up to its first `}` is
//! the same bytes is the same member (the bytes decide what a member is), so it is taken from
//! memory with one hash and one comparison, sharing the value; its name is still checked
//! against the node's other parameters. A scene repeats the same parameters on thousands of
//! nodes.

use super::{
    Conn, FewKeys, J, MAT_KEYS, MAT_NODES, MaterialState, NodeState, Num, P, Reader, SeenKeys,
    Typed, ValueRead, to_value, to_value_seq,
};
use crate::front::remembered::{MAX_REMEMBERED_PARAMS, text_hash};
use crate::network::{RequestKind, Sym};
use std::borrow::Cow;
use std::sync::Arc;

/// Parameters written in at most this many bytes (from the name's quote to the closing
/// brace) are remembered.
const MAX_PARAM_TEXT: usize = 256;

/// Value trees nested deeper than this (within `terminals`, a value, …) go to serde_json.
const MAX_NEST: u32 = 24;

const ONES: u64 = 0x0101_0101_0101_0101;
const HIGHS: u64 = 0x8080_8080_8080_8080;

/// The high bit of each zero byte of `v` (exact up to the first zero byte: a borrow marks
/// only bytes above it).
#[inline]
fn zero_bytes(v: u64) -> u64 {
    v.wrapping_sub(ONES) & !v & HIGHS
}

/// Flags the bytes of `x` that end a plain ASCII string: `"`, `\\`, control characters
/// and bytes beyond ASCII (the lowest flag is the first such byte).
#[inline]
fn special(x: u64) -> u64 {
    zero_bytes(x ^ (ONES * u64::from(b'"')))
        | zero_bytes(x ^ (ONES * u64::from(b'\\')))
        | (x.wrapping_sub(ONES * 0x20) & !x & HIGHS)
        | (x & HIGHS)
}

/// `rest` past its leading spaces, eight bytes at a time.
#[inline]
fn skip_spaces(mut rest: &[u8]) -> &[u8] {
    while let Some((chunk, tail)) = rest.split_first_chunk::<8>() {
        let x = u64::from_le_bytes(*chunk) ^ (ONES * u64::from(b' '));
        if x != 0 {
            return rest
                .get((x.trailing_zeros() / 8) as usize..)
                .unwrap_or(tail);
        }
        rest = tail;
    }
    while let [b' ', tail @ ..] = rest {
        rest = tail;
    }
    rest
}

/// Exact powers of ten as doubles.
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// Reads the material `name` whose value starts at `at` in `text` as the `group`-th material,
/// as [`super::read_material`] does with the value alone: the position after the value, or
/// `None` when serde_json must read it (module docs). `n` is scratch room for one node, kept
/// from one material to the next.
///
/// `text` need not be UTF-8: every byte the scanner settles is either ASCII it matched
/// (whitespace, punctuation, a number, a literal) or inside a string, which it checks, so a
/// material it reads is valid UTF-8. Checking the strings as they are read touches the text
/// once, where a check of the whole text first read it twice.
pub(super) fn read_material<'de>(
    r: &mut Reader<'_>,
    n: &mut NodeState<'de>,
    name: &str,
    text: &'de [u8],
    at: usize,
    group: u32,
) -> Option<usize> {
    r.materials = group;
    r.needs_types = false;
    r.ctx.depth.set(0);
    r.ctx.deepest.set(0);
    let mut s = Scan { b: text, i: at };
    s.material(r, n, MaterialState::new(name), group)?;
    Some(s.i)
}

/// The text and the position in it.
struct Scan<'de> {
    b: &'de [u8],
    i: usize,
}

impl<'de> Scan<'de> {
    /// Past whitespace.
    #[inline]
    fn ws(&mut self) {
        if self.b.get(self.i).is_some_and(|&c| c > b' ') {
            return;
        }
        self.ws_run();
    }

    /// Past a run of whitespace; the indentation after a line break eight bytes at a time.
    fn ws_run(&mut self) {
        let Some(mut rest) = self.b.get(self.i..) else {
            return;
        };
        loop {
            match rest {
                [b'\n', tail @ ..] => rest = skip_spaces(tail),
                [b' ' | b'\r' | b'\t', tail @ ..] => rest = tail,
                _ => break,
            }
        }
        self.i = self.b.len() - rest.len();
    }

    /// The next byte after whitespace (not consumed).
    #[inline]
    fn peek(&mut self) -> Option<u8> {
        self.ws();
        self.b.get(self.i).copied()
    }

    /// Opens an object or array (`open`): true when it is empty (and then closed).
    #[inline]
    fn open(&mut self, open: u8, close: u8) -> Option<bool> {
        if self.peek()? != open {
            return None;
        }
        self.i += 1;
        if self.peek()? == close {
            self.i += 1;
            return Some(true);
        }
        Some(false)
    }

    /// After a member: true for a `,` (another follows), false for `close`.
    #[inline]
    fn next(&mut self, close: u8) -> Option<bool> {
        let c = self.peek()?;
        self.i += 1;
        match c {
            b',' => Some(true),
            c if c == close => Some(false),
            _ => None,
        }
    }

    /// A string without escapes or control characters, eight bytes at a time.
    #[inline]
    fn string(&mut self) -> Option<&'de str> {
        if self.peek()? != b'"' {
            return None;
        }
        let start = self.i + 1;
        let text = self.b.get(start..)?;
        let mut rest = text;
        while let Some((chunk, tail)) = rest.split_first_chunk::<8>() {
            let m = special(u64::from_le_bytes(*chunk));
            if m != 0 {
                rest = rest.get((m.trailing_zeros() / 8) as usize..)?;
                break;
            }
            rest = tail;
        }
        while let [c, tail @ ..] = rest {
            if *c < 0x20 || *c >= 0x80 || *c == b'"' || *c == b'\\' {
                break;
            }
            rest = tail;
        }
        let ascii = rest.first() == Some(&b'"');
        if !ascii {
            // Past the bytes beyond ASCII, if that is what stopped it.
            while let [c, tail @ ..] = rest {
                if *c < 0x20 || *c == b'"' || *c == b'\\' {
                    break;
                }
                rest = tail;
            }
            if rest.first() != Some(&b'"') {
                return None;
            }
        }
        let end = start + (text.len() - rest.len());
        self.i = end + 1;
        let inner = &self.b[start..end];
        if ascii {
            // SAFETY: the loops above stopped at the first byte beyond ASCII, and found none
            // before the closing quote: ASCII bytes are valid UTF-8.
            return Some(unsafe { std::str::from_utf8_unchecked(inner) });
        }
        std::str::from_utf8(inner).ok()
    }

    /// An object key and its colon.
    #[inline]
    fn key(&mut self) -> Option<&'de str> {
        let k = self.string()?;
        if self.peek()? != b':' {
            return None;
        }
        self.i += 1;
        Some(k)
    }

    /// Which of `keys` (each with its quotes and colon, as `"type":`) comes next: the text
    /// compared as it is, else the key read and compared; `None` for any other key.
    #[inline]
    fn slot(&mut self, keys: &[&[u8]]) -> Option<u8> {
        self.ws();
        let rest = self.b.get(self.i..)?;
        for (n, k) in keys.iter().enumerate() {
            if rest.starts_with(k) {
                self.i += k.len();
                return u8::try_from(n).ok();
            }
        }
        let key = self.key()?.as_bytes();
        let n = keys
            .iter()
            .position(|k| k.get(1..k.len().saturating_sub(2)) == Some(key))?;
        u8::try_from(n).ok()
    }

    /// A number (module docs).
    fn number(&mut self) -> Option<Num> {
        let b = self.b;
        let mut i = self.i;
        let negative = b.get(i) == Some(&b'-');
        if negative {
            i += 1;
        }
        let mut sig: u64 = 0;
        let mut digits = 0u32;
        match b.get(i)? {
            b'0' => {
                i += 1;
                if b.get(i).is_some_and(u8::is_ascii_digit) {
                    return None;
                }
            }
            b'1'..=b'9' => {
                while let Some(&c @ b'0'..=b'9') = b.get(i) {
                    sig = sig * 10 + u64::from(c - b'0');
                    digits += 1;
                    i += 1;
                    if digits > 19 {
                        return None;
                    }
                }
            }
            _ => return None,
        }
        let mut exp: i32 = 0;
        let mut float = false;
        if b.get(i) == Some(&b'.') {
            float = true;
            i += 1;
            let first = i;
            while let Some(&c @ b'0'..=b'9') = b.get(i) {
                sig = sig.checked_mul(10)?.checked_add(u64::from(c - b'0'))?;
                exp -= 1;
                i += 1;
                if i - first > 19 {
                    return None;
                }
            }
            if i == first {
                return None;
            }
        }
        if let Some(b'e' | b'E') = b.get(i) {
            float = true;
            i += 1;
            let minus = match b.get(i) {
                Some(b'-') => {
                    i += 1;
                    true
                }
                Some(b'+') => {
                    i += 1;
                    false
                }
                _ => false,
            };
            let first = i;
            let mut e: i32 = 0;
            while let Some(&c @ b'0'..=b'9') = b.get(i) {
                e = e * 10 + i32::from(c - b'0');
                i += 1;
                if i - first > 3 {
                    return None;
                }
            }
            if i == first {
                return None;
            }
            exp += if minus { -e } else { e };
        }
        self.i = i;
        if !float {
            return Some(if !negative {
                Num::U(sig)
            } else if sig == 0 {
                Num::F(-0.0)
            } else {
                Num::I(-(i64::try_from(sig).ok()?))
            });
        }
        if sig > 1 << 53 {
            return None;
        }
        let pow = *POW10.get(exp.unsigned_abs() as usize)?;
        let f = if exp >= 0 {
            sig as f64 * pow
        } else {
            sig as f64 / pow
        };
        Some(Num::F(if negative { -f } else { f }))
    }

    /// `word` (`true`, `false`, `null`).
    fn literal(&mut self, word: &[u8], j: J<'de>) -> Option<J<'de>> {
        if !self.b.get(self.i..)?.starts_with(word) {
            return None;
        }
        self.i += word.len();
        Some(j)
    }

    /// Any value, as a tree (`nest`: the levels above it).
    fn value(&mut self, nest: u32) -> Option<J<'de>> {
        match self.peek()? {
            b'"' => Some(J::Str(Cow::Borrowed(self.string()?))),
            b'-' | b'0'..=b'9' => Some(J::Num(self.number()?)),
            b't' => self.literal(b"true", J::Bool(true)),
            b'f' => self.literal(b"false", J::Bool(false)),
            b'n' => self.literal(b"null", J::Null),
            b'[' => {
                if nest >= MAX_NEST {
                    return None;
                }
                let mut items = Vec::new();
                if !self.open(b'[', b']')? {
                    loop {
                        items.push(self.value(nest + 1)?);
                        if !self.next(b']')? {
                            break;
                        }
                    }
                }
                Some(J::Arr(items))
            }
            b'{' => {
                if nest >= MAX_NEST {
                    return None;
                }
                let mut members: Vec<(Cow<'de, str>, J<'de>)> = Vec::new();
                if !self.open(b'{', b'}')? {
                    loop {
                        let k = self.key()?;
                        if members.len() >= 64 || members.iter().any(|(m, _)| m == k) {
                            return None;
                        }
                        let v = self.value(nest + 1)?;
                        members.push((Cow::Borrowed(k), v));
                        if !self.next(b'}')? {
                            break;
                        }
                    }
                }
                Some(J::Obj(members))
            }
            _ => None,
        }
    }

    /// The material object, as `MaterialSeed` reads it.
    fn material(
        &mut self,
        r: &mut Reader<'_>,
        n: &mut NodeState<'de>,
        mut m: MaterialState<'de>,
        group: u32,
    ) -> Option<()> {
        let mut seen = SeenKeys::default();
        if !self.open(b'{', b'}')? {
            loop {
                let key = self.key()?;
                if !seen.insert(Cow::Borrowed(key)) {
                    return None;
                }
                r.at(group, MAT_KEYS);
                match key {
                    "nodes" => {
                        m.has_nodes = true;
                        let pointer = P::Key(&P::Root(&m.pointer), key).render();
                        self.nodes(r, n, &mut m, &pointer, group)?;
                    }
                    "terminals" => {
                        let j = self.value(0)?;
                        let root = m.pointer.clone();
                        match r.object(&j, &P::Key(&P::Root(&root), key), "`terminals`") {
                            Ok(_) => m.terminals = Some(j),
                            Err(e) => r.fail(e),
                        }
                    }
                    "primvars" => {
                        let j = self.value(0)?;
                        let root = m.pointer.clone();
                        match r.primvars(&j, &P::Key(&P::Root(&root), key)) {
                            Ok(v) => m.primvars = v,
                            Err(e) => r.fail(e),
                        }
                    }
                    _ => return None,
                }
                if !self.next(b'}')? {
                    break;
                }
            }
        }
        r.finish_material(m, group);
        Some(())
    }

    /// A material's `nodes`, as `NodesSeed` reads them.
    fn nodes(
        &mut self,
        r: &mut Reader<'_>,
        n: &mut NodeState<'de>,
        m: &mut MaterialState<'de>,
        pointer: &str,
        group: u32,
    ) -> Option<()> {
        if self.open(b'{', b'}')? {
            return Some(());
        }
        loop {
            let name = self.key()?;
            if m.by_name.contains_key(name) {
                return None;
            }
            let nodes = P::Root(pointer);
            let pointer = P::Key(&nodes, name);
            n.reset();
            self.node(r, n)?;
            r.at(group, MAT_NODES);
            match r.close_node(name, n, RequestKind::Pattern, &pointer) {
                Ok((node, conns)) => {
                    let id = m.nodes.len() as u32;
                    m.nodes.push(node);
                    m.pending.push((id, Cow::Borrowed(name), conns));
                    m.by_name.insert(Cow::Borrowed(name), Some(id));
                }
                Err(e) => {
                    r.fail(e);
                    m.by_name.insert(Cow::Borrowed(name), None);
                }
            }
            if !self.next(b'}')? {
                return Some(());
            }
        }
    }

    /// One node, as `NodeSeed` reads it (its three keys only).
    fn node(&mut self, r: &mut Reader<'_>, n: &mut NodeState<'de>) -> Option<()> {
        if self.open(b'{', b'}')? {
            return Some(());
        }
        let mut seen = FewKeys::default();
        loop {
            let slot = self.slot(&[
                b"\"nodeTypeId\":",
                b"\"parameters\":",
                b"\"inputConnections\":",
            ])?;
            if !seen.insert(Some(slot), "") {
                return None;
            }
            match slot {
                0 => n.shader = Some(Cow::Borrowed(self.string()?)),
                1 => self.parameters(r, n)?,
                _ => self.inputs(n)?,
            }
            if !self.next(b'}')? {
                return Some(());
            }
        }
    }

    /// A node's `parameters`, each in the canonical form, as `ParamsSeed` and `ParamSeed`
    /// read them.
    fn parameters(&mut self, r: &mut Reader<'_>, n: &mut NodeState<'de>) -> Option<()> {
        if self.open(b'{', b'}')? {
            return Some(());
        }
        loop {
            self.ws();
            match self.recall_parameter(r) {
                Some((name, typed)) => {
                    if !n.add_parameter(name) {
                        return None;
                    }
                    n.settle(n.names.len() - 1, Ok(typed));
                }
                None => self.parameter(r, n)?,
            }
            if !self.next(b'}')? {
                return Some(());
            }
        }
    }

    /// The parameter here, if its text up to the first `}` is one read before (module docs).
    #[inline]
    fn recall_parameter(&mut self, r: &Reader<'_>) -> Option<(Sym, Typed)> {
        let rest = self.b.get(self.i..)?;
        let window = rest.get(..MAX_PARAM_TEXT).unwrap_or(rest);
        let text = &rest[..=memchr::memchr(b'}', window)?];
        let (name, (value, decl)) = r.memo.params.recall(0, text, text_hash(text))?;
        self.i += text.len();
        Some((*name, (value.clone(), decl.clone())))
    }

    /// One parameter in the canonical form, as `ParamSeed` reads it; remembered if its text
    /// ends at its first `}` (module docs).
    fn parameter(&mut self, r: &mut Reader<'_>, n: &mut NodeState<'de>) -> Option<()> {
        let at = self.i;
        let name = self.key()?;
        let sym = Sym::new(name);
        if !n.add_parameter(sym) {
            return None;
        }
        let index = n.names.len() - 1;
        if self.open(b'{', b'}')? {
            return None;
        }
        let mut seen = FewKeys::default();
        let mut ty = None;
        let mut decl = None;
        let mut value = None;
        loop {
            let slot = self.slot(&[b"\"type\":", b"\"value\":"])?;
            if !seen.insert(Some(slot), "") {
                return None;
            }
            if slot == 0 {
                let s = self.string()?;
                decl = r.inline_decl(s);
                ty = Some(s);
            } else {
                value = Some(match &decl {
                    Some(d) => ValueRead::Typed(self.typed(&d.ty)?),
                    None => ValueRead::Tree(self.value(0)?),
                });
            }
            if !self.next(b'}')? {
                break;
            }
        }
        // A typed value that converted is what `canonical` keeps; it decides the rest.
        // Pointers are rendered only for a finding, which sends the material to serde_json
        // before it is kept: an empty base is enough here.
        let read = match (ty, decl, value) {
            (Some(_), Some(decl), Some(ValueRead::Typed(Ok(value)))) => (Arc::new(value), decl),
            (ty, decl, value) => {
                let pointer = P::Key(&P::Root(""), name);
                r.canonical(name, ty, decl, value, &pointer).ok()?
            }
        };
        let text = &self.b[at..self.i];
        if text.len() <= MAX_PARAM_TEXT
            && memchr::memchr(b'}', text) == Some(text.len() - 1)
            && r.memo.params.len() < MAX_REMEMBERED_PARAMS
        {
            let remembered = (sym, (read.0.clone(), read.1.clone()));
            r.memo.params.remember(0, text, text_hash(text), remembered);
        }
        n.settle(index, Ok(read));
        Some(())
    }

    /// A value of type `t`, as `TypedSeed` converts it.
    fn typed(&mut self, t: &crate::types::Type) -> Option<Result<crate::types::Value, String>> {
        if self.peek()? != b'[' {
            return Some(to_value(t, &self.value(0)?));
        }
        let mut items: smallvec::SmallVec<[J<'de>; 16]> = smallvec::SmallVec::new();
        if !self.open(b'[', b']')? {
            loop {
                items.push(self.value(1)?);
                if !self.next(b']')? {
                    break;
                }
            }
        }
        Some(to_value_seq(t, &items))
    }

    /// A node's `inputConnections`, as `InputsSeed`, `ConnsSeed` and `ConnSeed` read them
    /// (connections with their two keys only).
    fn inputs(&mut self, n: &mut NodeState<'de>) -> Option<()> {
        if self.open(b'{', b'}')? {
            return Some(());
        }
        loop {
            let index = n.add_input(Cow::Borrowed(self.key()?))?;
            if !self.open(b'[', b']')? {
                loop {
                    let conn = self.connection()?;
                    n.inputs[index].1.push(conn);
                    if !self.next(b']')? {
                        break;
                    }
                }
            }
            if !self.next(b'}')? {
                return Some(());
            }
        }
    }

    /// One connection with both its keys, each a string.
    fn connection(&mut self) -> Option<Conn<'de>> {
        if self.open(b'{', b'}')? {
            return None;
        }
        let (mut node, mut output) = (None, None);
        loop {
            let slot = match self.slot(&[b"\"upstreamNode\":", b"\"upstreamOutputName\":"])? {
                0 => &mut node,
                _ => &mut output,
            };
            if slot.is_some() {
                return None;
            }
            *slot = Some(self.string()?);
            if !self.next(b'}')? {
                break;
            }
        }
        let (node, output) = (node?, output?);
        Some(Conn {
            node: Cow::Borrowed(node),
            output: (!output.is_empty()).then_some(Cow::Borrowed(output)),
        })
    }
}
