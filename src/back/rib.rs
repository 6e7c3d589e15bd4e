//! RIB writer.
//!
//! [`write_rib`] writes a network back over the RIB source it was read from:
//!
//! 1. bytes outside interpreted requests (other requests, comments, whitespace, re-use
//!    requests) are copied unchanged;
//! 2. requests of unmodified nodes ([`Node::is_modified`]) are copied unchanged;
//! 3. modified nodes are re-serialised in place: the request line, then one parameter per line
//!    indented one tab deeper than the request; parameters read from the source keep their
//!    position (and their decl and value text when unchanged); new parameters are appended in
//!    the declaration order given by [`ParamTypes::input_position`]; removed parameters are
//!    omitted; comments keep their parameter (a comment on an omitted parameter moves to the
//!    next written one; a comment on the value line stays on that line).
//!
//! Nodes not read from this source (networks from JSON or built in code, or nodes added to a
//! read network) are written as fresh requests in dependency order (upstream first, ties in
//! insertion order). In a read network they are written as one block just before the first
//! source request that references one of them, or at the end when none does.
//!
//! Choices where the spec is silent:
//!
//! * A parameter whose connections changed but whose source decl was already `reference` keeps
//!   its decl text. A replaced value keeps its decl text when the decl's type still describes
//!   the value; otherwise the decl is written from the value's type.
//! * The type of a new connection: the definition's input type, else the upstream output's
//!   type, else the parameter's source decl type, else `float`.
//! * A fresh `Bxdf` that is the surface terminal of a material whose name differs from its
//!   handle and has no `__materialid` gets `"string __materialid" ["<material>"]`, so the
//!   material name survives a round trip.
//! * A connection is written as `"<upstream handle>:<output>"`. RIB references bind to the
//!   latest version of a handle defined earlier in the file, so a link to an older version, or
//!   to a node written later, cannot be expressed exactly; it is written by handle all the same.
//!   Likewise a whole-node reference to a handle containing `:` reads back as `handle:output`
//!   (references are split at the last `:`).
//! * Lines end in `\n`, also in files that use `\r\n` (only re-serialised requests are
//!   affected; pass-through bytes are copied as they are).
//! * A comment inside an array value (between `[` and `]`) is part of the value text: it is
//!   kept while the value is unchanged and dropped when the value is replaced.

use crate::network::{Link, Network, Node, NodeId, ParamChange, ParamTypes, Upstream};
use crate::network::{Memo, Param, RequestKind};
use crate::types::{ArraySpec, BaseType, Type, Value, format_f32, saturate_f32};
use rustc_hash::FxHashMap;
use std::borrow::Cow;
use std::cell::RefCell;
use std::collections::HashMap;
use std::io::{self, Write};
use std::ops::Range;

/// Write `net` as RIB over `source`, the bytes it was read from (empty for networks that were
/// not read from RIB), to `out`.
///
/// Fails with `InvalidInput` if a node's source span does not lie inside `source` (the network
/// was read from other bytes), or with the error of `out`.
///
/// With the `parallel` feature, a large network is formatted in pieces on rayon's pool while
/// the calling thread writes the finished pieces in order; the bytes are the same as a single
/// thread's, and a few pieces at a time are held in memory.
///
/// ```
/// use vstructc::back::rib::write_rib;
/// use vstructc::front::rib::{RibOptions, parse_rib};
/// use vstructc::network::NoDefinitions;
/// use vstructc::{Diagnostics, Value};
///
/// let src = b"Pattern \"PxrFractal\" \"f\"  \"int layers\" [3] # noise\nWorldBegin\n";
/// let mut diags = Diagnostics::new();
/// let mut net = parse_rib(src, "a.rib", &NoDefinitions, &RibOptions::default(), &mut diags).unwrap();
///
/// let mut same = Vec::new();
/// write_rib(src, &net, &NoDefinitions, &mut same).unwrap();
/// assert_eq!(same, src);
///
/// let f = net.find("f").unwrap();
/// net.set_param(f, "layers", Value::Int(6));
/// let mut out = Vec::new();
/// write_rib(src, &net, &NoDefinitions, &mut out).unwrap();
/// assert_eq!(
///     String::from_utf8(out).unwrap(),
///     "Pattern \"PxrFractal\" \"f\"\n\t\"int layers\" [6] # noise\nWorldBegin\n"
/// );
/// ```
pub fn write_rib(
    source: &[u8],
    net: &Network,
    types: &(dyn ParamTypes + Sync),
    out: &mut dyn Write,
) -> io::Result<()> {
    write_rib_chunked(
        source,
        net,
        types,
        out,
        CHUNK_NODES,
        cfg!(feature = "parallel"),
    )
}

/// Nodes per piece of output formatted on its own ([`write_rib_chunked`]): about 200 KB of a
/// resolved scene, few enough wake-ups of the threads and little memory held ahead.
const CHUNK_NODES: usize = 128;

/// Pieces formatted ahead of the one being written, per thread of the pool: bounds the
/// memory the parallel writer holds.
#[cfg(feature = "parallel")]
const AHEAD_PER_THREAD: usize = 1;

/// [`write_rib`] in pieces of `chunk_nodes` nodes (at least one). With `parallel` (and the
/// `parallel` feature, more than one thread in rayon's pool, and a caller outside the pool)
/// the pieces are formatted on the pool's threads, a bounded number ahead, while the calling
/// thread writes the finished ones in order; otherwise each is written as it is formatted.
/// Every way gives the same bytes: a piece's text depends only on the network, the source
/// and the definitions.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn write_rib_chunked(
    source: &[u8],
    net: &Network,
    types: &(dyn ParamTypes + Sync),
    out: &mut dyn Write,
    chunk_nodes: usize,
    parallel: bool,
) -> io::Result<()> {
    let mut surfaces = HashMap::new();
    for m in net.materials() {
        for t in m.terminals.iter().filter(|t| t.name == "surface") {
            if let Some(id) = t.link.upstream_node() {
                surfaces.entry(id).or_insert(m.name.as_str());
            }
        }
    }
    let plan = Plan::new(source, net, &surfaces);
    let pieces = plan.pieces(chunk_nodes.max(1));
    #[cfg(feature = "parallel")]
    if parallel && pieces.len() > 1 && crate::schedule::pool_can_help() {
        return plan.write_parallel(types, &pieces, out);
    }
    let _ = parallel;
    // One writer for every piece: its answers about definitions are kept from one to the next.
    let w = plan.writer(types);
    for piece in &pieces {
        plan.write_piece(&w, piece, out)?;
    }
    Ok(())
}

/// [`write_rib`] into a new byte vector.
///
/// ```
/// use vstructc::back::rib::write_rib_to_vec;
/// use vstructc::network::{NoDefinitions, Network};
/// use vstructc::Value;
/// let mut net = Network::new();
/// let n = net.add_node("f", "PxrFractal");
/// net.set_param(n, "layers", Value::Int(2));
/// let rib = write_rib_to_vec(b"", &net, &NoDefinitions).unwrap();
/// assert_eq!(String::from_utf8(rib).unwrap(), "Pattern \"PxrFractal\" \"f\"\n\t\"int layers\" [2]\n");
/// ```
#[cfg(any(test, feature = "testkit"))]
pub fn write_rib_to_vec(
    source: &[u8],
    net: &Network,
    types: &(dyn ParamTypes + Sync),
) -> io::Result<Vec<u8>> {
    let mut out = Vec::with_capacity(source.len() + 1024);
    write_rib(source, net, types, &mut out)?;
    Ok(out)
}

/// What the writer decides once for the whole output: the nodes read from the source in
/// source order, the others in dependency order, and where the block of the others goes.
struct Plan<'a> {
    source: &'a [u8],
    net: &'a Network,
    /// The name of the first material whose `surface` terminal is each node.
    surfaces: &'a HashMap<NodeId, &'a str>,
    /// Nodes read from the source, with their spans, in source order.
    sourced: Vec<(Range<usize>, NodeId)>,
    /// Nodes not read from the source, upstream first.
    fresh: Vec<NodeId>,
    /// The index in `sourced` of the request the fresh block is written before (`None`: at
    /// the end).
    block_before: Option<usize>,
}

/// A piece of the output, formatted on its own; the pieces of [`Plan::pieces`] in order are
/// the whole output.
enum Piece {
    /// The requests `sourced[k]` for these `k`, each after the source bytes before it.
    Sourced(Range<usize>),
    /// The source bytes after the last request (and the line break a fresh block at the end
    /// may need).
    Tail,
    /// The nodes `fresh[i]` for these `i`, of a fresh block at the end.
    Fresh(Range<usize>),
}

impl<'a> Plan<'a> {
    fn new(source: &'a [u8], net: &'a Network, surfaces: &'a HashMap<NodeId, &'a str>) -> Self {
        let mut sourced: Vec<(Range<usize>, NodeId)> = Vec::new();
        let mut fresh: Vec<NodeId> = Vec::new();
        for id in net.node_ids() {
            match net[id].source() {
                Some(s) => sourced.push((s.span.clone(), id)),
                None => fresh.push(id),
            }
        }
        sourced.sort_by_key(|(r, _)| r.start);
        let fresh = dependency_order(net, &fresh);
        let fresh_set: std::collections::HashSet<NodeId> = fresh.iter().copied().collect();
        // The fresh block goes before the first source request that references a fresh node
        // (no search when there is none: a resolved scene has millions of connections).
        let block_before = (!fresh.is_empty()).then(|| {
            sourced.iter().position(|(_, id)| {
                net[*id]
                    .params()
                    .flat_map(|p| p.connections())
                    .any(|l| l.upstream_node().is_some_and(|u| fresh_set.contains(&u)))
            })
        });
        Plan {
            source,
            net,
            surfaces,
            sourced,
            fresh,
            block_before: block_before.flatten(),
        }
    }

    /// The output in pieces of at most `nodes` nodes (at least one).
    fn pieces(&self, nodes: usize) -> Vec<Piece> {
        let nodes = nodes.max(1);
        let ranges = |n: usize| (0..n).step_by(nodes).map(move |k| k..(k + nodes).min(n));
        let mut pieces: Vec<Piece> = ranges(self.sourced.len()).map(Piece::Sourced).collect();
        pieces.push(Piece::Tail);
        if self.block_before.is_none() {
            pieces.extend(ranges(self.fresh.len()).map(Piece::Fresh));
        }
        pieces
    }

    /// A writer of pieces of this plan, asking `types` about definitions.
    fn writer<'p>(&'p self, types: &'p (dyn ParamTypes + Sync)) -> Writer<'p> {
        Writer {
            source: self.source,
            net: self.net,
            types: Memo::new(types),
            surfaces: self.surfaces,
            scratch: Default::default(),
            positions: Default::default(),
            input_types: Default::default(),
        }
    }

    /// Writes `piece` with `w` to `out`.
    fn write_piece(&self, w: &Writer<'_>, piece: &Piece, out: &mut dyn Write) -> io::Result<()> {
        match piece {
            Piece::Sourced(ks) => {
                let mut cursor = match ks.start {
                    0 => 0,
                    k => self.sourced[k - 1].0.end,
                };
                for k in ks.clone() {
                    let (span, id) = &self.sourced[k];
                    if span.start < cursor {
                        return Err(invalid("overlapping node source spans"));
                    }
                    out.write_all(w.bytes(&(cursor..span.start))?)?;
                    let indent = w.indent_before(span.start);
                    if self.block_before == Some(k) {
                        for &f in &self.fresh {
                            w.fresh_node(out, f, &indent)?;
                            out.write_all(b"\n\n")?;
                            out.write_all(&indent)?;
                        }
                    }
                    if self.net[*id].is_modified() {
                        w.reserialise(out, *id, &indent)?;
                    } else {
                        out.write_all(w.bytes(span)?)?;
                    }
                    cursor = span.end;
                }
            }
            Piece::Tail => {
                let cursor = self.sourced.last().map_or(0, |(span, _)| span.end);
                out.write_all(w.bytes(&(cursor..self.source.len()))?)?;
                if self.block_before.is_none()
                    && !self.fresh.is_empty()
                    && !self.source.is_empty()
                    && !self.source.ends_with(b"\n")
                {
                    out.write_all(b"\n")?;
                }
            }
            Piece::Fresh(is) => {
                for i in is.clone() {
                    if i > 0 {
                        out.write_all(b"\n")?;
                    }
                    w.fresh_node(out, self.fresh[i], b"")?;
                    out.write_all(b"\n")?;
                }
            }
        }
        Ok(())
    }

    /// Formats `pieces` on rayon's pool and writes them to `out` in order from the calling
    /// thread. Each thread of the pool takes the next piece when it holds a ticket; the
    /// calling thread hands out [`AHEAD_PER_THREAD`] tickets per thread at first and one
    /// more per piece written, so few pieces wait in memory. Stops at the first error in
    /// output order.
    #[cfg(feature = "parallel")]
    fn write_parallel(
        &self,
        types: &(dyn ParamTypes + Sync),
        pieces: &[Piece],
        out: &mut dyn Write,
    ) -> io::Result<()> {
        use std::sync::atomic::{AtomicUsize, Ordering};
        use std::sync::mpsc::{Receiver, SyncSender, channel, sync_channel};
        use std::sync::{Mutex, PoisonError};
        type Done<'s> = io::Result<PieceText<'s>>;
        let threads = rayon::current_num_threads();
        let (mut senders, mut receivers): (Vec<Mutex<Option<SyncSender<Done<'_>>>>>, Vec<_>) = (
            Vec::with_capacity(pieces.len()),
            Vec::with_capacity(pieces.len()),
        );
        for _ in pieces {
            let (tx, rx): (SyncSender<Done<'_>>, Receiver<Done<'_>>) = sync_channel(1);
            senders.push(Mutex::new(Some(tx)));
            receivers.push(rx);
        }
        let (tickets, ticket) = channel::<()>();
        let ticket = Mutex::new(ticket);
        let next = AtomicUsize::new(0);
        // Buffers of pieces already written, formatted into again: fresh memory costs a
        // page fault per page.
        let spare: Mutex<Vec<Vec<u8>>> = Mutex::new(Vec::new());
        let (senders, ticket, next, spare) = (&senders, &ticket, &next, &spare);
        rayon::in_place_scope(|scope| {
            for _ in 0..threads {
                scope.spawn(move |_| {
                    // One writer per thread: its answers about definitions are kept.
                    let w = self.writer(types);
                    loop {
                        let held = ticket.lock().is_ok_and(|t| t.recv().is_ok());
                        let i = next.fetch_add(1, Ordering::Relaxed);
                        if !held || i >= pieces.len() {
                            break;
                        }
                        // Taken before formatting: a panic drops it, which ends the wait of
                        // the writing thread.
                        let Some(done) = senders[i].lock().ok().and_then(|mut s| s.take()) else {
                            break;
                        };
                        let bytes = spare
                            .lock()
                            .unwrap_or_else(PoisonError::into_inner)
                            .pop()
                            .unwrap_or_default();
                        let mut text = PieceText::new(self.source, bytes);
                        let _ =
                            done.send(self.write_piece(&w, &pieces[i], &mut text).map(|()| text));
                    }
                });
            }
            let mut written = || -> io::Result<()> {
                for _ in 0..AHEAD_PER_THREAD * threads {
                    let _ = tickets.send(());
                }
                for result in receivers.drain(..) {
                    // A piece whose formatting panicked sends nothing; the scope passes the
                    // panic on when this closure returns.
                    let Ok(formatted) = result.recv() else {
                        return Ok(());
                    };
                    let text = formatted?;
                    text.write_to(out)?;
                    spare
                        .lock()
                        .unwrap_or_else(PoisonError::into_inner)
                        .push(text.bytes);
                    let _ = tickets.send(());
                }
                Ok(())
            };
            let result = written();
            // The threads waiting for a ticket stop.
            drop(tickets);
            result
        })
    }
}

/// Formats requests; its answers about definitions are kept from one request to the next (one
/// writer per thread that formats pieces).
struct Writer<'a> {
    source: &'a [u8],
    net: &'a Network,
    /// The definitions, with the answers already given (the writer asks for the type and
    /// position of every new parameter).
    types: Memo<'a>,
    /// The name of the first material whose `surface` terminal is each node.
    surfaces: &'a HashMap<NodeId, &'a str>,
    /// The buffer of the request being written, kept from one request to the next.
    scratch: RefCell<Vec<u8>>,
    /// Declaration positions of added parameters ([`ParamTypes::input_position`]).
    positions: ByAddress<Option<usize>>,
    /// Definition types of connected parameters written anew ([`ParamTypes::input_type`]).
    input_types: ByAddress<Option<Defined>>,
}

/// Source runs at least this long are not copied into a piece's text ([`PieceText`]).
#[cfg(feature = "parallel")]
const SOURCE_RUN: usize = 16 << 10;

/// The text of a piece formatted on another thread: its own bytes, with long runs of the
/// source (pass-through bytes, unmodified requests) kept as ranges of the source, so a scene
/// of mostly pass-through bytes is not copied a second time.
#[cfg(feature = "parallel")]
struct PieceText<'s> {
    source: &'s [u8],
    /// The formatted bytes, runs of the source left out.
    bytes: Vec<u8>,
    /// Each run of the source: where in `bytes` it goes, and its range in the source.
    runs: Vec<(usize, Range<usize>)>,
}

#[cfg(feature = "parallel")]
impl<'s> PieceText<'s> {
    /// An empty text over `source`, in `bytes` (emptied first).
    fn new(source: &'s [u8], mut bytes: Vec<u8>) -> Self {
        bytes.clear();
        PieceText {
            source,
            bytes,
            runs: Vec::new(),
        }
    }

    /// Writes the text, runs of the source in their places, to `out`.
    fn write_to(&self, out: &mut dyn Write) -> io::Result<()> {
        let mut from = 0;
        for (at, run) in &self.runs {
            out.write_all(&self.bytes[from..*at])?;
            out.write_all(&self.source[run.clone()])?;
            from = *at;
        }
        out.write_all(&self.bytes[from..])
    }
}

#[cfg(feature = "parallel")]
impl Write for PieceText<'_> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let source = self.source.as_ptr_range();
        let within = source.start <= buf.as_ptr() && buf.as_ptr_range().end <= source.end;
        if buf.len() >= SOURCE_RUN && within {
            let at = buf.as_ptr() as usize - source.start as usize;
            self.runs.push((self.bytes.len(), at..at + buf.len()));
        } else {
            self.bytes.extend_from_slice(buf);
        }
        Ok(buf.len())
    }

    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

/// The definition type of an input connected anew, and for a type that is not an array the
/// decl of one connection to it (`"reference color diffuseColor"`), written once.
struct Defined {
    ty: Type,
    single: Option<Box<[u8]>>,
}

/// Answers about one input of one shader, keyed by where the shader id and the input name
/// are stored ([`address_key`]). A resolved scene has millions of added parameters whose
/// names and shader ids are a few shared strings: a key of four numbers is hashed and
/// compared instead of two names per question.
type ByAddress<T> = RefCell<FxHashMap<[usize; 4], T>>;

/// The key of `shader` and `name` in a [`ByAddress`] table: address and length of each.
/// The strings are the network's (a node's shader id, a parameter's name) and the network
/// outlives the writer, so equal keys mean equal strings.
fn address_key(shader: &str, name: &str) -> [usize; 4] {
    [
        shader.as_ptr() as usize,
        shader.len(),
        name.as_ptr() as usize,
        name.len(),
    ]
}

/// Kahn's algorithm over `nodes` (edges among them only), ties in the given order; nodes on
/// cycles follow in the given order.
fn dependency_order(net: &Network, nodes: &[NodeId]) -> Vec<NodeId> {
    let pos: HashMap<NodeId, usize> = nodes.iter().enumerate().map(|(i, &n)| (n, i)).collect();
    let mut indegree = vec![0usize; nodes.len()];
    let mut downstream: Vec<Vec<usize>> = vec![Vec::new(); nodes.len()];
    for (i, &n) in nodes.iter().enumerate() {
        for u in net.upstream_nodes(n) {
            if let Some(&j) = pos.get(&u)
                && j != i
            {
                indegree[i] += 1;
                downstream[j].push(i);
            }
        }
    }
    let mut ready: std::collections::BTreeSet<usize> =
        (0..nodes.len()).filter(|&i| indegree[i] == 0).collect();
    let mut done = vec![false; nodes.len()];
    let mut order = Vec::with_capacity(nodes.len());
    while let Some(i) = ready.pop_first() {
        done[i] = true;
        order.push(nodes[i]);
        for &d in &downstream[i] {
            indegree[d] -= 1;
            if indegree[d] == 0 {
                ready.insert(d);
            }
        }
    }
    order.extend((0..nodes.len()).filter(|&i| !done[i]).map(|i| nodes[i]));
    order
}

fn invalid(msg: &str) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, msg.to_string())
}

impl Writer<'_> {
    fn bytes(&self, r: &Range<usize>) -> io::Result<&[u8]> {
        self.source.get(r.clone()).ok_or_else(|| {
            invalid("network source spans do not match the RIB bytes given to the writer")
        })
    }

    /// The spaces and tabs between the start of the line and `at`, if only those.
    fn indent_before(&self, at: usize) -> Vec<u8> {
        let line_start = self.source[..at]
            .iter()
            .rposition(|&b| b == b'\n')
            .map_or(0, |i| i + 1);
        let prefix = &self.source[line_start..at];
        if prefix.iter().all(|&b| b == b' ' || b == b'\t') {
            prefix.to_vec()
        } else {
            Vec::new()
        }
    }

    /// Appends the request line of `node` (keyword, shader and handle) to `h`.
    fn header(&self, node: &Node, h: &mut Vec<u8>) {
        h.extend_from_slice(node.kind().keyword().as_bytes());
        h.push(b' ');
        push_quoted(h, node.shader());
        h.push(b' ');
        push_quoted(h, node.handle());
    }

    /// Re-serialise a modified node read from the source (item 3 of the module docs).
    fn reserialise(&self, out: &mut dyn Write, id: NodeId, indent: &[u8]) -> io::Result<()> {
        let node = &self.net[id];
        let Some(src) = node.source() else {
            return self.fresh_node(out, id, indent);
        };
        let mut lines = Lines::new(indent, self.scratch.take());
        self.header(node, &mut lines.body);
        for (k, item) in src.items.iter().enumerate() {
            for c in src.leading_comments(k) {
                lines.pending.push(self.bytes(c)?);
            }
            let param = item.param().and_then(|k| node.all_params().get(k as usize));
            let trailing = match src.trailing_comment(k) {
                Some(c) => Some(self.bytes(c)?),
                None => None,
            };
            let Some((p, change)) = param
                .map(|p| (p, p.change()))
                .filter(|(_, change)| *change != ParamChange::Removed)
            else {
                // Comments of omitted parameters move to the next written parameter.
                lines.pending.extend(trailing);
                continue;
            };
            let t = lines.begin();
            match change {
                ParamChange::ValueReplaced => self.value_text(node, p, Some(src.decl(item)), t)?,
                ParamChange::Connected => self.connection_text(node, p, Some(src.decl(item)), t)?,
                _ => self.original_text(src.decl(item), src.value(item), t)?,
            }
            if let Some(c) = trailing {
                t.push(b' ');
                t.extend_from_slice(c);
            }
        }
        for c in src.end_comments() {
            lines.pending.push(self.bytes(c)?);
        }
        for p in self.added_params(node) {
            self.fresh_param_text(node, p, lines.begin())?;
        }
        self.scratch.replace(lines.finish(out)?);
        Ok(())
    }

    /// Parameters not from the source, in declaration order (unknown positions last, in the
    /// order they were added).
    fn added_params<'n>(&self, node: &'n Node) -> Vec<&'n Param> {
        let mut added: Vec<(usize, usize, &Param)> = node
            .all_params()
            .iter()
            .enumerate()
            .filter(|(_, p)| p.change() == ParamChange::Added)
            .map(|(i, p)| {
                let key = address_key(node.shader(), p.name());
                let known = self.positions.borrow().get(&key).copied();
                let pos = known.unwrap_or_else(|| {
                    let pos = self.types.input_position(node.shader(), p.name());
                    self.positions.borrow_mut().insert(key, pos);
                    pos
                });
                let pos = pos.unwrap_or(usize::MAX);
                (pos, i, p)
            })
            .collect();
        added.sort_by_key(|&(pos, i, _)| (pos, i));
        added.into_iter().map(|(_, _, p)| p).collect()
    }

    /// A node not read from the source: request line and every live parameter.
    fn fresh_node(&self, out: &mut dyn Write, id: NodeId, indent: &[u8]) -> io::Result<()> {
        let node = &self.net[id];
        let mut lines = Lines::new(indent, self.scratch.take());
        self.header(node, &mut lines.body);
        for p in node.params() {
            self.fresh_param_text(node, p, lines.begin())?;
        }
        if node.kind() == RequestKind::Bxdf
            && node.material_id().is_none()
            && let Some(name) = self.material_name_of(id)
            && name != node.handle()
        {
            let t = lines.begin();
            t.extend_from_slice(b"\"string __materialid\" [");
            push_quoted(t, name);
            t.push(b']');
        }
        self.scratch.replace(lines.finish(out)?);
        Ok(())
    }

    fn material_name_of(&self, id: NodeId) -> Option<&str> {
        self.surfaces.get(&id).copied()
    }

    /// Appends decl and value exactly as written (one space between them if the source had a
    /// line break or comment there).
    fn original_text(
        &self,
        decl: Range<usize>,
        value: Range<usize>,
        t: &mut Vec<u8>,
    ) -> io::Result<()> {
        let between = self.bytes(&(decl.end..value.start))?;
        if between.iter().all(|&b| b == b' ' || b == b'\t') {
            t.extend_from_slice(self.bytes(&(decl.start..value.end))?);
            return Ok(());
        }
        t.extend_from_slice(self.bytes(&decl)?);
        t.push(b' ');
        t.extend_from_slice(self.bytes(&value)?);
        Ok(())
    }

    /// Appends the decl and value of a parameter with a value.
    fn value_text(
        &self,
        node: &Node,
        p: &Param,
        source_decl: Option<Range<usize>>,
        t: &mut Vec<u8>,
    ) -> io::Result<()> {
        let Some(v) = p.value() else {
            return self.connection_text(node, p, source_decl, t);
        };
        match (source_decl, p.decl()) {
            (Some(s), Some(d)) if !d.reference && d.inline_type && value_fits(&d.ty, v) => {
                t.extend_from_slice(self.bytes(&s)?)
            }
            _ => {
                t.push(b'"');
                push_value_type(t, v);
                t.push(b' ');
                t.extend_from_slice(escape(p.name()).as_bytes());
                t.push(b'"');
            }
        }
        t.push(b' ');
        push_value(t, v);
        Ok(())
    }

    /// Appends the decl and connections of a connected parameter.
    fn connection_text(
        &self,
        node: &Node,
        p: &Param,
        source_decl: Option<Range<usize>>,
        t: &mut Vec<u8>,
    ) -> io::Result<()> {
        match (source_decl, p.decl()) {
            (Some(s), Some(d)) if d.reference => t.extend_from_slice(self.bytes(&s)?),
            _ => self.connection_decl(node, p, t),
        }
        t.push(b' ');
        self.push_links(t, p.connections());
        Ok(())
    }

    /// Appends the decl of a connected parameter written anew: `"reference TYPE NAME"` with
    /// the type of [`Writer::connection_type`]. The usual one (a defined input that is not an
    /// array, one connection) is copied as it was written the first time.
    fn connection_decl(&self, node: &Node, p: &Param, t: &mut Vec<u8>) {
        let key = address_key(node.shader(), p.name());
        let asked = {
            let known = self.input_types.borrow();
            match known.get(&key) {
                Some(Some(Defined {
                    single: Some(text), ..
                })) if p.connections().len() <= 1 => {
                    t.extend_from_slice(text);
                    return;
                }
                Some(_) => true,
                None => false,
            }
        };
        if !asked {
            let defined = self.types.input_type(node.shader(), p.name()).map(|ty| {
                let single = matches!(ty.array, ArraySpec::None).then(|| {
                    let mut text = b"\"reference ".to_vec();
                    text.extend_from_slice(decl_word(&ty.base).as_bytes());
                    text.push(b' ');
                    text.extend_from_slice(escape(p.name()).as_bytes());
                    text.push(b'"');
                    text.into_boxed_slice()
                });
                Defined { ty, single }
            });
            self.input_types.borrow_mut().insert(key, defined);
        }
        t.extend_from_slice(b"\"reference ");
        self.connection_type(node, p, t);
        t.push(b' ');
        t.extend_from_slice(escape(p.name()).as_bytes());
        t.push(b'"');
    }

    fn fresh_param_text(&self, node: &Node, p: &Param, t: &mut Vec<u8>) -> io::Result<()> {
        if p.is_connected() {
            self.connection_text(node, p, None, t)
        } else {
            self.value_text(node, p, None, t)
        }
    }

    /// Appends the decl type of a new connection: definition input type, else upstream output
    /// type, else the source decl's type, else `float`.
    fn connection_type(&self, node: &Node, p: &Param, t: &mut Vec<u8>) {
        let n = p.connections().len();
        let upstream_type = || {
            let link = p.connections().first()?;
            let up = self.net.get(link.upstream_node()?)?;
            self.types.output_type(up.shader(), link.output()?)
        };
        // Asked by `connection_decl` before.
        let known = self.input_types.borrow();
        let defined = known
            .get(&address_key(node.shader(), p.name()))
            .and_then(|d| d.as_ref().map(|d| &d.ty));
        let ty: Cow<'_, Type> = match defined {
            Some(ty) => Cow::Borrowed(ty),
            None => upstream_type()
                .map(Cow::Owned)
                .or_else(|| p.decl().map(|d| Cow::Borrowed(&d.ty)))
                .unwrap_or(Cow::Owned(Type::scalar(BaseType::Float))),
        };
        t.extend_from_slice(decl_word(&ty.base).as_bytes());
        match ty.array {
            ArraySpec::None if n <= 1 => {}
            ArraySpec::Fixed(k) if k == n => {
                let _ = write!(t, "[{k}]");
            }
            _ => {
                let _ = write!(t, "[{n}]");
            }
        }
    }

    /// Appends `links` as a RIB array of `"handle:output"` strings.
    fn push_links(&self, text: &mut Vec<u8>, links: &[Link]) {
        text.push(b'[');
        for (i, l) in links.iter().enumerate() {
            let handle = match l.upstream() {
                Upstream::Node(id) => self.net.get(id).map_or("", |n| n.handle()),
                Upstream::Missing(h) => h,
            };
            if i > 0 {
                text.push(b' ');
            }
            text.push(b'"');
            text.extend_from_slice(escape(handle).as_bytes());
            if let Some(o) = l.output() {
                text.push(b':');
                text.extend_from_slice(escape(o).as_bytes());
            }
            text.push(b'"');
        }
        text.push(b']');
    }
}

/// Accumulates a request: its header, then parameter lines; comments wait in `pending`
/// until the next parameter. Everything is appended to one buffer (a resolved scene has
/// millions of parameter lines).
struct Lines<'i, 's> {
    indent: &'i [u8],
    body: Vec<u8>,
    pending: Vec<&'s [u8]>,
}

impl<'i, 's> Lines<'i, 's> {
    /// Lines after `indent`, in `buffer` (emptied first).
    fn new(indent: &'i [u8], mut buffer: Vec<u8>) -> Self {
        buffer.clear();
        Lines {
            indent,
            body: buffer,
            pending: Vec::new(),
        }
    }

    /// Starts a new line (after its indent and tab).
    fn line(&mut self) {
        self.body.push(b'\n');
        self.body.extend_from_slice(self.indent);
        self.body.push(b'\t');
    }

    /// Writes the pending comments, each on its line, and starts the line of a parameter:
    /// the caller appends its text to the returned buffer.
    fn begin(&mut self) -> &mut Vec<u8> {
        for c in std::mem::take(&mut self.pending) {
            self.line();
            self.body.extend_from_slice(c);
        }
        self.line();
        &mut self.body
    }

    /// Writes the request to `out`; returns the buffer for the next one.
    fn finish(mut self, out: &mut dyn Write) -> io::Result<Vec<u8>> {
        for c in std::mem::take(&mut self.pending) {
            self.line();
            self.body.extend_from_slice(c);
        }
        out.write_all(&self.body)?;
        Ok(self.body)
    }
}

/// The RIB decl word of a base type (`struct` without its name; JSON-only types as the RIB type
/// that carries them).
fn decl_word(b: &BaseType) -> &str {
    match b {
        BaseType::Token | BaseType::Asset => "string",
        BaseType::Bool => "int",
        other => other.word(),
    }
}

/// Appends the decl type text describing value `v` (`float`, `color`, `int[1]`, …).
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn push_value_type(t: &mut Vec<u8>, v: &Value) {
    match v {
        Value::Array(b, items) => {
            let _ = write!(t, "{}[{}]", decl_word(b), items.len());
        }
        other => t.extend_from_slice(decl_word(&other.base_type()).as_bytes()),
    }
}

/// Appends `v` in RIB syntax ([`format_value`]).
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn push_value(t: &mut Vec<u8>, v: &Value) {
    match v {
        // The usual values of a resolved scene: no intermediate string.
        Value::Int(i) => push_int_value(t, *i),
        Value::Float(x) => {
            let _ = write!(t, "[{}]", saturate_f32(*x));
        }
        other => t.extend_from_slice(format_value(other).as_bytes()),
    }
}

/// Appends `s` as a RIB string literal ([`quote`]).
fn push_quoted(t: &mut Vec<u8>, s: &str) {
    t.push(b'"');
    t.extend_from_slice(escape(s).as_bytes());
    t.push(b'"');
}

/// True if a decl of type `ty` describes value `v` exactly (so its text can be kept).
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn value_fits(ty: &Type, v: &Value) -> bool {
    match (ty.array, v) {
        (ArraySpec::None, Value::Array(..)) => false,
        (ArraySpec::None, v) => v.base_type() == ty.base,
        (ArraySpec::Fixed(n), Value::Array(b, items)) => {
            items.len() == n
                && *b == ty.base
                && items.iter().all(|i| !matches!(i, Value::Array(..)))
        }
        (ArraySpec::Dynamic, Value::Array(b, _)) => *b == ty.base,
        _ => false,
    }
}

/// A value in RIB syntax, always bracketed: `[1]`, `[0.5]`, `["s"]`, `[1 0 0]`.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) fn format_value(v: &Value) -> String {
    let mut out = String::from("[");
    push_elements(v, &mut out);
    out.push(']');
    out
}

/// One float as RIB text. The reader takes finite numbers only, so a non-finite float (only
/// possible in a network built in code) is written saturated ([`saturate_f32`]).
fn rib_f32(x: f32) -> String {
    format_f32(saturate_f32(x))
}

/// Appends the elements of `v` to `out` (which ends in `[` or in an element), each after a
/// space unless it is the first.
fn push_elements(v: &Value, out: &mut String) {
    fn sep(out: &mut String) {
        if !out.ends_with('[') {
            out.push(' ');
        }
    }
    fn floats(out: &mut String, xs: &[f32]) {
        for x in xs {
            sep(out);
            out.push_str(&rib_f32(*x));
        }
    }
    match v {
        Value::Int(i) => {
            sep(out);
            out.push_str(&i.to_string());
        }
        Value::Float(x) => floats(out, &[*x]),
        Value::Str(s) | Value::Token(s) | Value::Asset(s) => {
            sep(out);
            out.push('"');
            out.push_str(&escape(s));
            out.push('"');
        }
        Value::Triple(_, xs) => floats(out, xs),
        Value::HPoint(xs) => floats(out, xs),
        Value::Matrix(xs) => floats(out, xs),
        Value::Bool(b) => {
            sep(out);
            out.push(if *b { '1' } else { '0' });
        }
        Value::Array(_, items) => {
            for i in items {
                push_elements(i, out);
            }
        }
    }
}

/// A RIB string literal: double quotes, `\"`, `\\`, `\n`, `\t` escaped, other control
/// characters as `\ddd`.
///
/// ```
/// use vstructc::back::rib::quote;
/// assert_eq!(quote("a \"b\"\n"), r#""a \"b\"\n""#);
/// assert_eq!(quote("\u{1}"), r#""\001""#);
/// ```
#[cfg(any(test, feature = "testkit"))]
pub fn quote(s: &str) -> String {
    format!("\"{}\"", escape(s))
}

/// Appends `[i]` (the usual int value of a resolved scene) without the formatting machinery.
fn push_int_value(t: &mut Vec<u8>, i: i32) {
    t.push(b'[');
    t.extend_from_slice(itoa::Buffer::new().format(i).as_bytes());
    t.push(b']');
}

/// `s` as the content of a RIB string: quotes and backslashes escaped, newline and tab as
/// `\n` and `\t`, other control characters in octal.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn escape(s: &str) -> Cow<'_, str> {
    // Names and handles almost never need escaping: use them as they are (the writer checks
    // millions of names).
    if !needs_escape(s.as_bytes()) {
        return Cow::Borrowed(s);
    }
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            c if (c as u32) < 0x20 || c as u32 == 0x7f => {
                out.push_str(&format!("\\{:03o}", c as u32));
            }
            c => out.push(c),
        }
    }
    Cow::Owned(out)
}

/// True if `s` holds a byte that [`escape`] changes: a control byte, DEL, `"` or `\\`.
fn needs_escape(s: &[u8]) -> bool {
    // Every byte without stopping early, which lets the compiler check whole vectors.
    s.iter().fold(false, |found, &b| {
        found | (b < 0x20) | (b == 0x7f) | (b == b'"') | (b == b'\\')
    })
}
