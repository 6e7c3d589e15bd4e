//! RIB shading-network reader (see `docs/inputs-and-outputs.md`).
//!
//! [`parse_rib`] reads ASCII RIB bytes into a [`Network`]. Only the shading-node requests
//! `Pattern`, `Bxdf`, `Displace`, `Light` and `LightFilter` are interpreted; every other
//! request is tokenized (to find where it ends and to reject malformed or binary input) but not
//! stored: the writer ([`crate::back::rib`]) copies the bytes between interpreted requests from
//! the input unchanged. Each node records the byte ranges of its request, parameters and
//! comments ([`crate::network::NodeSource`]), never copies of the text, so reading a large
//! scene costs about one copy of its shading requests. An input from 1 MiB on is read on two
//! threads when the `parallel` feature is on and rayon may use more than one: a second thread
//! tokenizes the requests while the calling thread builds the network from them in file order,
//! and the parameters' declarations and values are read by whichever of the two has time,
//! with the same network, diagnostics and errors as on one thread.
//!
//! Choices where the spec is silent (documented here, tested in `tests/front/rib_reader.rs`):
//!
//! * A request that re-uses a handle with an empty parameter list (or only
//!   `"string __materialid"`) is a *use* of the earlier node only if it names the same shader;
//!   with a different shader it is a redefinition (RB017).
//! * `Integrator`, `Projection`, `DisplayFilter`, `SampleFilter` are passed through (the spec
//!   lists only the five requests above as interpreted).
//! * Decl words: `[class]` and `reference` may come in either order before the type; other
//!   unrecognised leading words are kept and reported as RB013.
//! * Values that do not fit the declared type (wrong count, strings for a numeric type, a
//!   non-integral number for `int`, a value for a type without value form such as `struct`)
//!   are RB014 warnings and kept as written: a flat [`Value::Array`] of their elements with the
//!   declared base type. Numbers outside the `f32` / `i32` range are RB014 and saturated.
//! * A `reference` parameter whose value contains numbers is RB014; it is kept as a value.
//! * An integral number written with a fraction or exponent (`1.`) is accepted for `int`.
//! * Strings with invalid UTF-8 are decoded with U+FFFD replacements.

// The tokenizer: public under `testkit` for its unit tests.
testkit_mods!(lexer);
mod params;
#[cfg(feature = "parallel")]
mod pipeline;

use crate::diag::{Diagnostic, Diagnostics, Error, Location};
use crate::front::remembered::text_hash;
use crate::limits::{Limit, LimitExceeded, Limits};
use crate::network::{
    Link, Links, Material, MaterialNodes, Network, Node, NodeId, NodeSource, Param, ParamAt,
    ParamTypes, RequestKind, SourceParam, Sym, Terminal,
};
use crate::types::{ArraySpec, BaseType, Type, Value};
use lexer::{Lexer, TokKind, Token, decode_str, decode_string};
use params::{ParamReader, Read, ReadParam};
use rustc_hash::{FxHashMap, FxHashSet};
use smallvec::SmallVec;
use std::borrow::Cow;
use std::ops::Range;
use std::sync::Arc;

/// Options of the RIB reader.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RibOptions {
    /// `--strict-rib`: single-quoted strings are an error (RB011) instead of an info.
    pub strict: bool,
    /// Bounds: the input's size, its nodes, each node's parameters and each input's
    /// connections ([`Network::check_limits`]); exceeding one is [`Error::Limit`].
    pub limits: Limits,
}

/// Legacy RSL shading requests: passed through; RB020 when they carry `reference` params.
const LEGACY_REQUESTS: &[&str] = &[
    "Surface",
    "Displacement",
    "Atmosphere",
    "Interior",
    "Exterior",
    "Deformation",
    "Imager",
    "LightSource",
    "AreaLightSource",
    "Shader",
];

/// Storage-class words that may precede the type in a decl.
const CLASSES: &[&str] = &[
    "constant",
    "uniform",
    "varying",
    "vertex",
    "facevarying",
    "facevertex",
];

/// Read a RIB file into a network.
///
/// `path` names the input in diagnostics. `types` supplies declared types for decls without
/// an inline type (RB012/RB006), the RB016 type check and the RB019 unknown-shader check;
/// it is `Sync` because a large input's parameters are read on two threads. Warnings and
/// infos go to `diags`; the first error stops reading and is returned (nothing is written
/// for a file with errors).
///
/// Materials: one per `Bxdf` (named by its `__materialid`, else its handle), `Displace`,
/// `Light` and `LightFilter` node version (named by handle), with the matching terminal and the
/// upstream closure as node set. A name already taken by an earlier material gets a `#n`
/// suffix (`ConstantCurvature#1`).
///
/// ```
/// use vstructc::front::rib::{RibOptions, parse_rib};
/// use vstructc::network::NoDefinitions;
/// use vstructc::{Diagnostics, Value};
///
/// let rib = br#"
/// Pattern "PxrFractal" "noise" "float frequency" [2]
/// Bxdf "PxrSurface" "Solid Material 21"
///     "reference float diffuseGain" ["noise:resultF"]
///     "string __materialid" ["RedSG"]
/// "#;
/// let mut diags = Diagnostics::new();
/// let net = parse_rib(rib, "scene.rib", &NoDefinitions, &RibOptions::default(), &mut diags).unwrap();
/// let noise = net.find("noise").unwrap();
/// let surface = net.find("Solid Material 21").unwrap();
/// assert_eq!(net.value(noise, "frequency"), Some(&Value::Float(2.0)));
/// assert_eq!(net.connections(surface, "diffuseGain")[0].upstream_node(), Some(noise));
/// assert_eq!(net.materials()[0].name, "RedSG");
/// assert!(diags.is_empty());
/// ```
pub fn parse_rib(
    bytes: &[u8],
    path: &str,
    types: &(dyn ParamTypes + Sync),
    options: &RibOptions,
    diags: &mut Diagnostics,
) -> Result<Network, Error> {
    parse_rib_path(bytes, path, types, options, diags, ReadPath::Auto)
}

/// [`parse_rib`], read along `read_path`.
fn parse_rib_path(
    bytes: &[u8],
    path: &str,
    types: &(dyn ParamTypes + Sync),
    options: &RibOptions,
    diags: &mut Diagnostics,
    read_path: ReadPath,
) -> Result<Network, Error> {
    let file: Arc<str> = Arc::from(path);
    options
        .limits
        .check(Limit::NetworkFileBytes, bytes.len() as u64)
        .map_err(|e| e.at(Location::file(file.clone())))?;
    if bytes.starts_with(&[0x1f, 0x8b]) {
        return Err(Diagnostic::error(
            "RB001",
            "gzip-compressed RIB is not supported; decompress it first",
        )
        .at(Location::new(file, 1, 1))
        .into());
    }
    let mut net = Network::new();
    net.reserve_for_input(bytes.len(), BYTES_PER_NODE, options.limits.nodes);
    let mut asm = Assembler {
        src: bytes,
        types,
        net,
        known: FxHashMap::default(),
        limits: options.limits,
        over_limit: None,
    };
    read_requests(bytes, &file, options, types, &mut asm, diags, read_path)?;
    let mut net = asm.net;
    // What `Network::check_limits` finds, without another walk over the network: the nodes
    // were counted while reading, and each node was checked as it was added.
    options
        .limits
        .check(Limit::Nodes, net.node_count() as u64)?;
    if let Some(e) = asm.over_limit {
        return Err(e.into());
    }
    add_materials(&mut net);
    Ok(net)
}

/// How [`read_requests`] reads a file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ReadPath {
    /// Pipelined ([`pipeline`]) when the input is large and more than one thread may run;
    /// on one thread otherwise.
    Auto,
    /// On the calling thread.
    #[cfg(feature = "testkit")]
    Serial,
    /// Pipelined whatever the input's size, with at most this many requests per batch
    /// (tests: every batch boundary behaves as within a batch).
    #[cfg(feature = "testkit")]
    Pipelined(usize),
}

/// Inputs from this size on are read pipelined (with the `parallel` feature and more than
/// one thread): below, starting a thread costs about what it saves.
#[cfg(feature = "parallel")]
const PIPELINE_MIN_BYTES: usize = 1 << 20;

/// Reads the requests of `bytes` into `asm`: tokenizing and assembling in turn on this
/// thread, or pipelined on two ([`pipeline`]). Both give the same network, the same
/// diagnostics in the same order and the same error.
fn read_requests(
    bytes: &[u8],
    file: &Arc<str>,
    options: &RibOptions,
    types: &(dyn ParamTypes + Sync),
    asm: &mut Assembler<'_, '_>,
    diags: &mut Diagnostics,
    path: ReadPath,
) -> Result<(), Error> {
    #[cfg(feature = "parallel")]
    {
        let batch = match path {
            ReadPath::Auto
                if bytes.len() >= PIPELINE_MIN_BYTES && rayon::current_num_threads() > 1 =>
            {
                Some((pipeline::MAX_BATCH_REQUESTS, pipeline::Reading::WhenBehind))
            }
            #[cfg(feature = "testkit")]
            ReadPath::Pipelined(n) => Some((n.max(1), pipeline::Reading::Alternate)),
            _ => None,
        };
        if let Some((batch, reading)) = batch {
            let read = pipeline::read(bytes, file, options, types, asm, diags, batch, reading);
            if let Some(result) = read {
                return result;
            }
        }
    }
    #[cfg(not(feature = "parallel"))]
    let _ = path;
    let mut scanner = Scanner::new(bytes, file.clone(), options.strict);
    let mut reader = ParamReader::new(bytes, file.clone(), types);
    // One buffer of each for every request: their room is reused.
    let mut args = Args::default();
    let mut occurrences = Vec::new();
    let mut reads = Vec::new();
    loop {
        args.pieces.clear();
        args.items.clear();
        occurrences.clear();
        let Some((kind, kw)) = scanner.next_request(&mut args, diags)? else {
            return Ok(());
        };
        let split = split_request(
            bytes,
            &scanner.lx,
            kind,
            &kw,
            &args.pieces,
            &mut occurrences,
        );
        reader.read_request(&split, &args.pieces, &args.items, &occurrences, &mut reads);
        asm.shading_request(
            &scanner.lx,
            kind,
            &kw,
            &args.pieces,
            &args.items,
            split,
            &occurrences,
            reads.drain(..),
            diags,
        )?;
        asm.check_nodes(&scanner.lx, &kw, &options.limits)?;
    }
}

/// [`parse_rib`] read on one thread (`batch` `None`) or pipelined in batches of at most
/// `batch` requests, whatever the input's size: tests compare them.
#[cfg(feature = "testkit")]
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn parse_rib_with(
    bytes: &[u8],
    path: &str,
    types: &(dyn ParamTypes + Sync),
    options: &RibOptions,
    diags: &mut Diagnostics,
    batch: Option<usize>,
) -> Result<Network, Error> {
    let read_path = batch.map_or(ReadPath::Serial, ReadPath::Pipelined);
    parse_rib_path(bytes, path, types, options, diags, read_path)
}

/// The request-level tokenizer: finds the shading requests and reads their arguments,
/// passing every other request over (RB020 for a legacy request with `reference`
/// parameters).
struct Scanner<'a> {
    lx: Lexer<'a>,
    src: &'a [u8],
    /// The token after the last request read (`None` at the end); `None` before the first.
    next: Option<Option<Token>>,
}

impl<'a> Scanner<'a> {
    fn new(src: &'a [u8], file: Arc<str>, strict: bool) -> Self {
        Scanner {
            lx: Lexer::new(src, file, strict),
            src,
            next: None,
        }
    }

    /// The next shading request: its kind and keyword token, with its arguments appended to
    /// `args` (array elements to [`Args::items`], so ranges stay valid across requests).
    /// `None` at the end of input.
    fn next_request(
        &mut self,
        args: &mut Args,
        diags: &mut Diagnostics,
    ) -> Result<Option<(RequestKind, Token)>, Error> {
        let lx = &mut self.lx;
        let mut next = match self.next.take() {
            Some(next) => next,
            None => lx.next_token(diags)?,
        };
        while let Some(tok) = next {
            match tok.kind {
                TokKind::Comment => next = lx.next_token(diags)?,
                TokKind::Ident => {
                    // Request names are ASCII: matched as bytes, no UTF-8 check.
                    let word = lx.bytes(&tok);
                    if let Some(kind) = RequestKind::ALL
                        .into_iter()
                        .find(|k| k.keyword().as_bytes() == word)
                    {
                        self.next = Some(read_args(lx, diags, true, args)?);
                        return Ok(Some((kind, tok)));
                    }
                    let legacy = LEGACY_REQUESTS.iter().find(|name| name.as_bytes() == word);
                    let (pieces, items) = (args.pieces.len(), args.items.len());
                    let after = read_args(lx, diags, legacy.is_some(), args)?;
                    if let Some(name) =
                        legacy.filter(|_| has_reference_decl(self.src, &args.pieces[pieces..]))
                    {
                        diags.push(
                            Diagnostic::info(
                                "RB020",
                                format!("legacy `{name}` request with `reference` parameters is passed through, not resolved"),
                            )
                            .at(lx.tok_loc(&tok)),
                        );
                    }
                    args.pieces.truncate(pieces);
                    args.items.truncate(items);
                    next = after;
                }
                _ => {
                    return Err(Diagnostic::error(
                        "RB004",
                        format!("unexpected {}: expected a request name", describe(&tok)),
                    )
                    .at(lx.tok_loc(&tok))
                    .into());
                }
            }
        }
        self.next = Some(None);
        Ok(None)
    }
}

/// Bytes of RIB per shading node assumed when room for the nodes is reserved: a node request
/// with a few parameters takes more (the bench scene takes about 310), so a file of shading
/// networks rarely outgrows the estimate, and one that is mostly geometry reserves address
/// space it never touches.
const BYTES_PER_NODE: usize = 256;

fn describe(t: &Token) -> &'static str {
    match t.kind {
        TokKind::Ident => "request name",
        TokKind::Number => "number",
        TokKind::Str => "string",
        TokKind::Open => "`[`",
        TokKind::Close => "`]`",
        TokKind::Comment => "comment",
    }
}

/// One argument of a request, or a comment between arguments.
#[derive(Debug, Clone)]
enum Piece {
    Comment(Token),
    /// A bare number or string.
    Value(Token),
    /// `[ … ]`: the brackets and the numbers/strings inside (comments inside are dropped; they
    /// stay in the value's byte range).
    Array {
        open: Token,
        /// Range into [`Args::items`].
        items: Range<usize>,
        close: Token,
    },
}

/// The arguments of one request: pieces in order, and the elements of all its arrays in one
/// buffer (one allocation per request rather than one per array).
#[derive(Debug, Default)]
struct Args {
    pieces: Vec<Piece>,
    items: Vec<Token>,
}

impl Piece {
    fn range(&self) -> Range<usize> {
        match self {
            Piece::Comment(t) | Piece::Value(t) => t.start..t.end,
            Piece::Array { open, close, .. } => open.start..close.end,
        }
    }
    fn end_line(&self) -> u32 {
        match self {
            Piece::Comment(t) | Piece::Value(t) => t.end_line,
            Piece::Array { close, .. } => close.end_line,
        }
    }
    fn first(&self) -> &Token {
        match self {
            Piece::Comment(t) | Piece::Value(t) => t,
            Piece::Array { open, .. } => open,
        }
    }
}

/// Read the arguments of a request, appended to `args`, up to the next request name
/// (returned) or the end. Validates arrays (flat, homogeneous, closed). With `keep == false`
/// nothing is stored, so pass-through requests of any size cost no memory.
fn read_args(
    lx: &mut Lexer<'_>,
    diags: &mut Diagnostics,
    keep: bool,
    args: &mut Args,
) -> Result<Option<Token>, Error> {
    let mut array: Option<(Token, usize, Option<TokKind>)> = None;
    loop {
        let Some(tok) = lx.next_token(diags)? else {
            if let Some((open, ..)) = array {
                return Err(unterminated_array(lx, &open));
            }
            return Ok(None);
        };
        match (tok.kind, array.as_mut()) {
            (TokKind::Ident, None) => return Ok(Some(tok)),
            (TokKind::Ident, Some((open, ..))) => {
                let open = *open;
                return Err(Diagnostic::error(
                    "RB004",
                    format!(
                        "unexpected request name inside the array opened at {}:{}; expected `]`",
                        open.line, open.col
                    ),
                )
                .at(lx.tok_loc(&tok))
                .into());
            }
            (TokKind::Comment, None) => {
                if keep {
                    args.pieces.push(Piece::Comment(tok));
                }
            }
            (TokKind::Comment, Some(_)) => {}
            (TokKind::Number | TokKind::Str, None) => {
                if keep {
                    args.pieces.push(Piece::Value(tok));
                }
            }
            (TokKind::Number | TokKind::Str, Some((open, _, kind))) => {
                match kind {
                    None => *kind = Some(tok.kind),
                    Some(k) if *k != tok.kind => {
                        let open = *open;
                        return Err(Diagnostic::error(
                            "RB005",
                            format!(
                                "mixed array: numbers and strings in the array opened at {}:{}",
                                open.line, open.col
                            ),
                        )
                        .at(lx.tok_loc(&tok))
                        .into());
                    }
                    Some(_) => {}
                }
                if keep {
                    args.items.push(tok);
                }
            }
            (TokKind::Open, None) => {
                // The usual array in one pass; anything else token by token.
                let first = args.items.len();
                if keep && let Some(close) = lx.flat_array(&mut args.items) {
                    let items = first..args.items.len();
                    args.pieces.push(Piece::Array {
                        open: tok,
                        items,
                        close,
                    });
                    continue;
                }
                array = Some((tok, first, None));
            }
            (TokKind::Open, Some(_)) => {
                return Err(
                    Diagnostic::error("RB004", "unexpected `[`: arrays cannot be nested")
                        .at(lx.tok_loc(&tok))
                        .into(),
                );
            }
            (TokKind::Close, None) => {
                return Err(
                    Diagnostic::error("RB004", "unexpected `]` without a matching `[`")
                        .at(lx.tok_loc(&tok))
                        .into(),
                );
            }
            (TokKind::Close, Some(_)) => {
                if let Some((open, first, _)) = array.take()
                    && keep
                {
                    let items = first..args.items.len();
                    args.pieces.push(Piece::Array {
                        open,
                        items,
                        close: tok,
                    });
                }
            }
        }
    }
}

fn unterminated_array(lx: &Lexer<'_>, open: &Token) -> Error {
    Diagnostic::error(
        "RB004",
        "unterminated array: missing `]` before the end of input",
    )
    .at(lx.tok_loc(open))
    .into()
}

/// True if a top-level string argument is a decl containing the word `reference`.
fn has_reference_decl(src: &[u8], pieces: &[Piece]) -> bool {
    pieces.iter().any(|p| match p {
        Piece::Value(t) if t.kind == TokKind::Str => decode_string(src, t)
            .split(|c: char| c.is_ascii_whitespace())
            .any(|w| w == "reference"),
        _ => false,
    })
}

/// The words of a decl string: `[class] [reference] type [[N]] name`.
#[derive(Debug, Default, PartialEq)]
#[cfg_attr(feature = "testkit", visibility::make(pub))]
struct DeclWords<'s> {
    /// The storage class (`uniform`, `varying`, ...), if any.
    pub class: Option<&'s str>,
    /// Whether `reference` precedes the type.
    pub reference: bool,
    /// The type word, if any.
    pub type_word: Option<&'s str>,
    /// The array size between brackets, if any.
    pub array: Option<&'s str>,
    /// The parameter name.
    pub name: &'s str,
    /// Words before the type that are none of the above.
    pub extra: Vec<&'s str>,
}

/// Splits a decl string into its words; `None` when it has no name.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn split_decl(text: &str) -> Option<DeclWords<'_>> {
    // Walk the words from the end (name, then `[N]`, then type) without collecting them.
    let mut words = text
        .split(|c: char| c.is_ascii() && lexer::is_space(c as u8))
        .filter(|w| !w.is_empty())
        .rev()
        .peekable();
    let name = words.next()?;
    let mut d = DeclWords {
        name,
        ..DeclWords::default()
    };
    if let Some(last) = words.peek()
        && last.len() >= 2
        && last.starts_with('[')
        && last.ends_with(']')
    {
        d.array = Some(&last[1..last.len() - 1]);
        words.next();
    }
    if let Some(&last) = words.peek()
        && last != "reference"
        && !CLASSES.contains(&last)
    {
        words.next();
        match (d.array, last.find('[')) {
            (None, Some(open)) if open > 0 && last.ends_with(']') => {
                d.type_word = Some(&last[..open]);
                d.array = Some(&last[open + 1..last.len() - 1]);
            }
            _ => d.type_word = Some(last),
        }
    }
    for w in words {
        if w == "reference" && !d.reference {
            d.reference = true;
        } else if CLASSES.contains(&w) && d.class.is_none() {
            d.class = Some(w);
        } else {
            d.extra.push(w);
        }
    }
    d.extra.reverse();
    Some(d)
}

/// The RIB type words of parameter declarations (plus `integrator`); anything else is `Unknown`.
fn rib_base_type(word: &str) -> Option<Type> {
    match word {
        "float" | "int" | "string" | "color" | "point" | "vector" | "normal" | "matrix"
        | "hpoint" | "float2" | "float3" | "struct" | "vstruct" | "bxdf" | "lightfilter"
        | "samplefilter" | "displayfilter" | "integrator" => Some(Type::parse_decl(word)),
        _ => None,
    }
}

/// One element of a value: a number (its text) or a decoded string (borrowed from the input
/// unless it has escapes).
enum Elem<'a> {
    Num(&'a str),
    Str(Cow<'a, str>),
}

/// The elements of one value: inline up to a matrix's sixteen.
type Elems<'a> = SmallVec<[Elem<'a>; 16]>;

/// Assembles nodes from shading requests.
struct Assembler<'a, 't> {
    src: &'a [u8],
    types: &'t dyn ParamTypes,
    net: Network,
    /// Whether the definitions know a shader, per address of its shared id (alive until
    /// the file is read): asked once per request, and a shader's address is quicker to
    /// look up than its name.
    known: FxHashMap<usize, bool>,
    limits: Limits,
    /// The first node, in order, beyond a bound on its parameters or an input's
    /// connections: reported once the whole file is read, as a check of the network would.
    over_limit: Option<LimitExceeded>,
}

/// Parameters written (decl string to end of value) in at most this many bytes are
/// remembered for sharing.
const MAX_SHARED_PARAM_BYTES: usize = 160;

/// Where a parameter's decl string is: enough to build its [`Location`] when a diagnostic
/// needs one (most parameters need none, and keep only line and column).
#[derive(Clone, Copy)]
struct At<'f> {
    file: &'f Arc<str>,
    line: u32,
    column: u32,
}

impl At<'_> {
    fn loc(&self) -> Location {
        Location::new(self.file.clone(), self.line, self.column)
    }
}

/// A position in a request's comment list ([`NodeSource::comments`]). A comment takes at
/// least two bytes (`#` and a line end), so a file within the default size limit
/// ([`Limits::network_file_bytes`], 4 GiB) holds fewer than `u32::MAX`; beyond, the position
/// saturates.
fn index_u32(i: usize) -> u32 {
    u32::try_from(i).unwrap_or(u32::MAX)
}

/// `range`, a part of the request starting at byte `start`, as offsets from that start
/// ([`SourceParam`] keeps 32-bit offsets); `None` beyond 4 GiB from the start.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn in_request(start: usize, range: Range<usize>) -> Option<Range<u32>> {
    let at = |b: usize| u32::try_from(b.checked_sub(start)?).ok();
    Some(at(range.start)?..at(range.end)?)
}

/// A parameter occurrence of a split request ([`Split::params`]).
struct Occurrence {
    decl_tok: Token,
    /// Its value in the request's pieces.
    value: usize,
    /// The parameter as written (decl string to the end of the value) and its
    /// [`text_hash`], when it is short enough to be remembered
    /// ([`MAX_SHARED_PARAM_BYTES`]): hashed here, on the tokenizer's thread when pipelined.
    text: Option<(Range<usize>, u64)>,
}

/// A shading request split into its parts before any parameter is interpreted
/// ([`split_request`]): the work that needs only the request's tokens, which the pipelined
/// reader does on the tokenizer's thread.
struct Split<'a> {
    shader: Cow<'a, str>,
    handle: Cow<'a, str>,
    /// Its parameter occurrences in order, in the buffer given to [`split_request`]
    /// ([`NodeSource::items`] has one item each).
    params: Range<usize>,
    items: Vec<SourceParam>,
    /// Every comment of the request in source order; those from `pending` on belong to no
    /// parameter occurrence.
    comments: Vec<Range<usize>>,
    pending: usize,
    /// The end of the last occurrence (or of the handle).
    end: usize,
    /// The error that ends the request after `params` (reading them may stop earlier).
    error: Option<Error>,
}

/// Splits the shading request of keyword `kw` and arguments `pieces` into its header, its
/// parameter occurrences (appended to `occurrences`), their source items and its comments,
/// up to the first error.
fn split_request<'a>(
    src: &'a [u8],
    lx: &Lexer<'_>,
    kind: RequestKind,
    kw: &Token,
    pieces: &[Piece],
    occurrences: &mut Vec<Occurrence>,
) -> Split<'a> {
    let from = occurrences.len();
    let mut split = Split {
        shader: Cow::Borrowed(""),
        handle: Cow::Borrowed(""),
        params: from..from,
        items: Vec::new(),
        comments: Vec::new(),
        pending: 0,
        end: kw.end,
        error: None,
    };
    if let Err(e) = split_into(src, lx, kind, kw, pieces, occurrences, &mut split) {
        split.error = Some(e);
    }
    split.params = from..occurrences.len();
    split
}

/// The body of [`split_request`]: fills `split` up to the first error.
fn split_into<'a>(
    src: &'a [u8],
    lx: &Lexer<'_>,
    kind: RequestKind,
    kw: &Token,
    pieces: &[Piece],
    occurrences: &mut Vec<Occurrence>,
    split: &mut Split<'a>,
) -> Result<(), Error> {
    let mut i = 0;
    let comments = &mut split.comments;
    let mut header_string = |what: &str, i: &mut usize| -> Result<(Cow<'a, str>, Token), Error> {
        while let Some(Piece::Comment(c)) = pieces.get(*i) {
            comments.push(c.start..c.end);
            *i += 1;
        }
        match pieces.get(*i) {
            Some(Piece::Value(t)) if t.kind == TokKind::Str => {
                *i += 1;
                Ok((decode_str(src, t), *t))
            }
            Some(p) => Err(Diagnostic::error(
                "RB004",
                format!(
                    "unexpected {} after `{kind}`: expected the {what} string",
                    piece_name(p)
                ),
            )
            .at(lx.tok_loc(p.first()))
            .into()),
            None => Err(Diagnostic::error(
                "RB004",
                format!("`{kind}` request without {what} string"),
            )
            .at(lx.tok_loc(kw))
            .into()),
        }
    };
    let (shader, _) = header_string("shader name", &mut i)?;
    split.shader = shader;
    let (handle, handle_tok) = header_string("handle", &mut i)?;
    split.handle = handle;
    split.end = handle_tok.end;

    // Exact room unless comments sit between parameters (a network of a million nodes
    // keeps these tables).
    let room = (pieces.len() - i) / 2;
    occurrences.reserve(room);
    split.items.reserve_exact(room);
    let comments = &mut split.comments;
    while i < pieces.len() {
        let decl_tok = match &pieces[i] {
            Piece::Comment(c) => {
                comments.push(c.start..c.end);
                i += 1;
                continue;
            }
            Piece::Value(t) if t.kind == TokKind::Str => *t,
            other => {
                return Err(Diagnostic::error(
                    "RB004",
                    format!(
                        "unexpected {}: expected a parameter declaration string",
                        piece_name(other)
                    ),
                )
                .at(lx.tok_loc(other.first()))
                .into());
            }
        };
        i += 1;
        while let Some(Piece::Comment(c)) = pieces.get(i) {
            comments.push(c.start..c.end);
            i += 1;
        }
        let Some(value_piece) = pieces.get(i) else {
            let decl_text = decode_string(src, &decl_tok);
            return Err(Diagnostic::error(
                "RB007",
                format!("parameter `{}` has no value", decl_text.trim()),
            )
            .at(lx.tok_loc(&decl_tok))
            .into());
        };
        let value = i;
        i += 1;
        let value_range = value_piece.range();
        split.end = value_range.end;
        let origin = split.items.len() as u32;
        let (Some(decl), Some(value_at)) = (
            in_request(kw.start, decl_tok.start..decl_tok.end),
            in_request(kw.start, value_range.clone()),
        ) else {
            return Err(Diagnostic::error(
                "RB021",
                format!("request `{}` is longer than 4 GiB", split.handle),
            )
            .at(lx.tok_loc(kw))
            .into());
        };
        let mut item = SourceParam::new(origin, decl, value_at, index_u32(split.pending));
        if let Some(Piece::Comment(c)) = pieces.get(i)
            && c.line == value_piece.end_line()
        {
            comments.push(c.start..c.end);
            item.set_trailing();
            split.end = c.end;
            i += 1;
        }
        split.pending = comments.len();
        split.items.push(item);
        let whole = decl_tok.start..value_range.end;
        let text = (whole.len() <= MAX_SHARED_PARAM_BYTES)
            .then(|| src.get(whole.clone()).map(|w| (whole, text_hash(w))))
            .flatten();
        occurrences.push(Occurrence {
            decl_tok,
            value,
            text,
        });
    }
    Ok(())
}

impl<'a> Assembler<'a, '_> {
    /// Reads the shading request of keyword `kw`, arguments `pieces` (array elements in
    /// `arena`) and parts `split` (parameter occurrences in `occurrences`, read as `reads`)
    /// into the network.
    #[allow(clippy::too_many_arguments)]
    fn shading_request(
        &mut self,
        lx: &Lexer<'_>,
        kind: RequestKind,
        kw: &Token,
        pieces: &[Piece],
        arena: &[Token],
        split: Split<'_>,
        occurrences: &[Occurrence],
        reads: impl Iterator<Item = Read>,
        diags: &mut Diagnostics,
    ) -> Result<(), Error> {
        let Split {
            shader,
            handle,
            params: occurrences_at,
            items,
            mut comments,
            pending,
            end,
            error,
        } = split;
        let occurrences = &occurrences[occurrences_at];
        if occurrences.is_empty()
            && let Some(e) = error
        {
            return Err(e);
        }
        // The network's copy (its address keys [`Assembler::known`]).
        let shader = self.net.shared_shader(&shader);
        let mut params: Vec<Param> = Vec::with_capacity(occurrences.len());
        for (origin, (o, read)) in occurrences.iter().zip(reads).enumerate() {
            diags.extend(read.diags);
            let (name, decl) = match read.param {
                ReadParam::Param(param) => {
                    params.push(param);
                    continue;
                }
                ReadParam::Failed(e) => return Err(e),
                ReadParam::Reference { name, decl } => (name, decl),
            };
            let location = At {
                file: lx.file(),
                line: o.decl_tok.line,
                column: o.decl_tok.col,
            };
            let toks = value_tokens(&pieces[o.value], arena);
            let links = self.read_links(&name, &location, &decl.ty, toks, diags)?;
            let at = ParamAt::LineColumn(location.line, location.column);
            let param = Param::from_shared(name, None, Some(decl), at, Some(origin as u32));
            params.push(param.with_source_links(links));
        }
        if let Some(e) = error {
            return Err(e);
        }
        let (repeated, shadowed) = duplicates(&params);
        for (p, _) in params.iter().zip(&repeated).filter(|(_, r)| **r) {
            let mut d = Diagnostic::warning(
                "RB015",
                format!(
                    "duplicate parameter `{}` on `{handle}`; the later one wins",
                    p.name()
                ),
            );
            if let Some((line, column)) = p.line_column() {
                d = d.at(lx.loc(line, column));
            }
            diags.push(d);
        }

        // One look-up of the handle for the re-use and redefinition checks.
        let versions = self.net.versions(&handle);
        let (prev, defined) = (versions.last().copied(), versions.len());
        if self.is_reuse(prev, &shader, &params) {
            return Ok(());
        }
        let location = lx.tok_loc(kw);
        if let Some(prev) = prev {
            let mut d = Diagnostic::warning(
                "RB017",
                format!(
                    "handle `{handle}` redefined (version {defined}); later references bind to this definition"
                ),
            )
            .at(location.clone());
            if let Some(l) = self.net[prev].location() {
                d = d.with_related("previous definition", l.clone());
            }
            diags.push(d);
        }
        if self.types.has_definitions() && !self.shader_known(&shader) {
            diags.push(
                Diagnostic::warning(
                    "RB019",
                    format!("shader `{shader}` of `{handle}` is not in the registry; its parameters are kept verbatim"),
                )
                .at(location.clone()),
            );
        }
        // Comments after the last parameter lie outside the span (they are passed through);
        // only comments inside the header of a request without parameters remain. (The
        // occurrences' own all end inside the span, which ends at or after their values.)
        comments.retain(|c| c.end <= end);
        self.add_node(
            kind,
            &handle,
            shader,
            location,
            params,
            NodeSource::new(kw.start..end, items, comments, pending),
            &shadowed,
        );
        Ok(())
    }

    /// Stops at the first node too many ([`Limit::Nodes`]), before the rest is read.
    fn check_nodes(&self, lx: &Lexer<'_>, kw: &Token, limits: &Limits) -> Result<(), Error> {
        limits
            .check(Limit::Nodes, self.net.node_count() as u64)
            .map_err(|e| e.at(lx.tok_loc(kw)).into())
    }

    /// A request whose handle is defined (`prev`, its latest version), for the same shader,
    /// with no parameters other than `string __materialid` re-uses the earlier node.
    fn is_reuse(&self, prev: Option<NodeId>, shader: &str, params: &[Param]) -> bool {
        let Some(prev) = prev else {
            return false;
        };
        self.net[prev].shader() == shader
            && params.iter().all(|p| {
                p.name() == "__materialid"
                    && p.decl()
                        .is_some_and(|d| !d.reference && d.ty == Type::scalar(BaseType::String))
            })
    }

    #[allow(clippy::too_many_arguments)]
    fn add_node(
        &mut self,
        kind: RequestKind,
        handle: &str,
        shader: Arc<str>,
        location: Location,
        mut params: Vec<Param>,
        mut source: NodeSource,
        shadowed: &[bool],
    ) {
        // Later duplicates win: earlier occurrences are not parameters, but their source
        // items stay (their comments move to the next written parameter).
        if shadowed.iter().any(|&s| s) {
            let mut kept = Vec::with_capacity(params.len());
            for ((p, &shadow), item) in params.into_iter().zip(shadowed).zip(&mut source.items) {
                if shadow {
                    item.set_param(None);
                } else {
                    item.set_param(Some(kept.len() as u32));
                    kept.push(p);
                }
            }
            params = kept;
        }
        let mut node = Node::new_shared(handle, shader, kind);
        node.set_raw_params(params);
        node.set_origin(Some(location), Some(source));
        let id = self.net.insert_node(node);
        self.net.add_source_edges(id);
        if self.over_limit.is_none() {
            // Checked while its parameters are still in the cache.
            self.over_limit = self.net.check_node_limits(id, &self.limits).err();
        }
    }

    /// Whether the definitions know `shared_shader`, the network's shared id (see
    /// [`Assembler::known`]).
    fn shader_known(&mut self, shared_shader: &Arc<str>) -> bool {
        let types = self.types;
        *self
            .known
            .entry(shared_shader.as_ptr() as usize)
            .or_insert_with(|| types.shader_known(shared_shader))
    }

    /// Connections of a `reference` parameter: one `handle:output` string per element, split
    /// at the last `:`, bound to the latest version of the handle defined so far.
    fn read_links(
        &mut self,
        name: &str,
        location: &At<'_>,
        ty: &Type,
        toks: &[Token],
        diags: &mut Diagnostics,
    ) -> Result<Links, Error> {
        let expected = match ty.array {
            ArraySpec::Fixed(n) => Some(n),
            ArraySpec::None => Some(1),
            ArraySpec::Dynamic => None,
        };
        if expected.is_some_and(|n| n != toks.len()) {
            diags.push(
                Diagnostic::warning(
                    "RB014",
                    format!(
                        "`{}` has {} connection(s) but its type `{ty}` takes {}",
                        name,
                        toks.len(),
                        expected.unwrap_or(0)
                    ),
                )
                .at(location.loc()),
            );
        }
        let mut links = Vec::with_capacity(toks.len());
        for t in toks {
            let s = decode_str(self.src, t);
            let (handle, output) = match s.rfind(':') {
                Some(k) if k + 1 == s.len() => {
                    return Err(Diagnostic::error(
                        "RB008",
                        format!("connection `{s}` of `{}` has an empty output name", name),
                    )
                    .at(location.loc())
                    .into());
                }
                Some(k) => (&s[..k], Some(&s[k + 1..])),
                None => (&*s, None),
            };
            let output = output.map(Sym::new);
            match self.net.find(handle) {
                Some(id) => links.push(Link::node_sym(id, output)),
                None => {
                    diags.push(
                        Diagnostic::warning(
                            "RB018",
                            format!("`{}` references `{handle}`, which is not defined before this request; kept as a dangling connection", name),
                        )
                        .at(location.loc()),
                    );
                    links.push(Link::missing_sym(handle, output));
                }
            }
        }
        Ok(Links::from_vec(links))
    }
}

/// For each parameter occurrence: whether an earlier occurrence has the same name (RB015),
/// and whether a later one does (this one is overridden).
fn duplicates(read: &[Param]) -> (Flags, Flags) {
    let mut repeated: Flags = smallvec::smallvec![false; read.len()];
    let mut shadowed: Flags = smallvec::smallvec![false; read.len()];
    // Names are interned: comparing two is comparing two pointers.
    let same = |a: &Param, b: &Param| a.name_sym() == b.name_sym();
    if read.len() <= SMALL_REQUEST {
        // Each occurrence against the nearest earlier one with its name.
        for j in 1..read.len() {
            if let Some(i) = (0..j).rev().find(|&i| same(&read[i], &read[j])) {
                repeated[j] = true;
                shadowed[i] = true;
            }
        }
        return (repeated, shadowed);
    }
    let mut order: Vec<usize> = (0..read.len()).collect();
    order.sort_by(|&a, &b| read[a].name().cmp(read[b].name()).then(a.cmp(&b)));
    for w in order.windows(2) {
        if same(&read[w[0]], &read[w[1]]) {
            repeated[w[1]] = true;
            shadowed[w[0]] = true;
        }
    }
    (repeated, shadowed)
}

/// One flag per parameter occurrence of a request.
type Flags = SmallVec<[bool; 32]>;

/// Requests with at most this many parameters are checked for duplicates pairwise (a sort
/// costs more for so few).
const SMALL_REQUEST: usize = 24;

/// The number and string tokens of a value: the bare token, or the array's elements.
fn value_tokens<'p>(value: &'p Piece, arena: &'p [Token]) -> &'p [Token] {
    match value {
        Piece::Value(t) => std::slice::from_ref(t),
        Piece::Array { items, .. } => arena.get(items.clone()).unwrap_or_default(),
        Piece::Comment(_) => &[],
    }
}

fn piece_name(p: &Piece) -> &'static str {
    match p {
        Piece::Array { .. } => "array",
        other => describe(other.first()),
    }
}

/// Decl type vs definition type, for RB016: same base type (any struct names match) and a
/// compatible shape (`[1]` matches a scalar, anything matches a dynamic array).
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn types_compatible(decl: &Type, def: &Type) -> bool {
    let base_ok = match (&decl.base, &def.base) {
        (BaseType::Struct(_), BaseType::Struct(_)) => true,
        (a, b) => a == b,
    };
    let shape_ok = match (decl.array, def.array) {
        (_, ArraySpec::Dynamic) => true,
        (ArraySpec::None, ArraySpec::None) => true,
        (ArraySpec::Fixed(1), ArraySpec::None) | (ArraySpec::None, ArraySpec::Fixed(1)) => true,
        (ArraySpec::Fixed(a), ArraySpec::Fixed(b)) => a == b,
        _ => false,
    };
    base_ok && shape_ok
}

/// Convert RIB value elements to a typed value (RB014 and a flat array when they do not fit).
fn convert_value(
    ty: &Type,
    elems: &[Elem<'_>],
    name: &str,
    location: &At<'_>,
    diags: &mut Diagnostics,
) -> Value {
    let warn = |diags: &mut Diagnostics, why: String| {
        diags.push(
            Diagnostic::warning(
                "RB014",
                format!("value of `{name}` does not match its type `{ty}`: {why}"),
            )
            .at(location.loc()),
        );
    };
    if let BaseType::Unknown(_) = ty.base {
        // Already reported as RB013; kept raw.
        return flat(&ty.base, elems, &mut |_| {});
    }
    let comps = ty.base.components();
    if comps == 0 {
        warn(diags, "this type has no value form".into());
        return flat(&ty.base, elems, &mut |_| {});
    }
    let is_string = ty.base == BaseType::String;
    if elems.iter().any(|e| matches!(e, Elem::Str(_)) != is_string) {
        let want = if is_string { "strings" } else { "numbers" };
        warn(diags, format!("expected {want}"));
        return flat(&ty.base, elems, &mut |_| {});
    }
    let count = match ty.array {
        ArraySpec::None => 1,
        ArraySpec::Fixed(n) => n,
        ArraySpec::Dynamic => elems.len() / comps,
    };
    // Saturating: `color[6148914691236517206]` must not overflow (it simply never matches).
    let expected = comps.saturating_mul(count);
    if elems.len() != expected {
        warn(
            diags,
            format!("{} element(s), expected {expected}", elems.len()),
        );
        return flat(&ty.base, elems, &mut |_| {});
    }
    let mut problems: Vec<String> = Vec::new();
    let mut note = |s: String| problems.push(s);
    let value = if ty.is_array() {
        let items = elems
            .chunks(comps)
            .map(|chunk| scalar(&ty.base, chunk, &mut note))
            .collect::<Option<Vec<Value>>>();
        items.map(|items| Value::Array(ty.base.clone(), items))
    } else {
        scalar(&ty.base, elems, &mut note)
    };
    for p in problems {
        warn(diags, p);
    }
    value.unwrap_or_else(|| flat(&ty.base, elems, &mut |_| {}))
}

/// One element of type `base` from exactly `components()` elements; `None` if it cannot be
/// represented (non-integral int).
fn scalar(base: &BaseType, elems: &[Elem<'_>], note: &mut dyn FnMut(String)) -> Option<Value> {
    // At most 16 components (a matrix): no allocation.
    let mut floats = || -> [f32; 16] {
        let mut out = [0.0f32; 16];
        for (o, e) in out.iter_mut().zip(elems) {
            if let Elem::Num(t) = e {
                *o = parse_f32(t, note);
            }
        }
        out
    };
    Some(match base {
        BaseType::Int => match &elems[0] {
            Elem::Num(t) => Value::Int(parse_int(t, note)?),
            Elem::Str(_) => return None,
        },
        BaseType::Float => Value::Float(floats()[0]),
        BaseType::String => match &elems[0] {
            Elem::Str(s) => Value::Str(s.to_string()),
            Elem::Num(_) => return None,
        },
        b if b.is_triple() => {
            let f = floats();
            Value::Triple(b.clone(), [f[0], f[1], f[2]])
        }
        BaseType::HPoint => {
            let f = floats();
            Value::HPoint([f[0], f[1], f[2], f[3]])
        }
        BaseType::Matrix => Value::Matrix(floats()),
        _ => return None,
    })
}

/// Parse a float, saturating (RB014) outside the f32 range.
fn parse_f32(text: &str, note: &mut dyn FnMut(String)) -> f32 {
    let x: f32 = text.parse().unwrap_or(0.0);
    if x.is_finite() {
        x
    } else {
        note(format!("{text} is outside the f32 range; saturated"));
        if x > 0.0 { f32::MAX } else { f32::MIN }
    }
}

/// Parse an int: integer text (saturated outside i32, RB014), or an integral float (`1.`).
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn parse_int(text: &str, note: &mut dyn FnMut(String)) -> Option<i32> {
    if let Ok(v) = text.parse::<i64>() {
        if let Ok(v) = i32::try_from(v) {
            return Some(v);
        }
        note(format!("{text} is outside the int range; saturated"));
        return Some(if v > 0 { i32::MAX } else { i32::MIN });
    }
    let x: f64 = text.parse().ok()?;
    if x.fract() == 0.0 && x >= f64::from(i32::MIN) && x <= f64::from(i32::MAX) {
        return Some(x as i32);
    }
    note(format!("{text} is not an integer"));
    None
}

/// A flat array of the elements as written: integer-looking numbers as `Int`, other numbers as
/// `Float`, strings as `Str`.
fn flat(base: &BaseType, elems: &[Elem<'_>], note: &mut dyn FnMut(String)) -> Value {
    let items = elems
        .iter()
        .map(|e| match e {
            Elem::Str(s) => Value::Str(s.to_string()),
            Elem::Num(t) => match t.parse::<i32>() {
                Ok(i) => Value::Int(i),
                Err(_) => Value::Float(parse_f32(t, note)),
            },
        })
        .collect();
    Value::Array(base.clone(), items)
}

/// One material per terminal node version, in file order.
fn add_materials(net: &mut Network) {
    let mut taken: FxHashSet<String> = FxHashSet::default();
    let mut suffixes: FxHashMap<String, usize> = FxHashMap::default();
    let terminals: Vec<NodeId> = net
        .node_ids()
        .filter(|&id| net[id].kind() != RequestKind::Pattern)
        .collect();
    for id in terminals {
        let node = &net[id];
        let Some(terminal) = node.kind().terminal_name() else {
            continue;
        };
        let base = match node.kind() {
            RequestKind::Bxdf => node.material_id().unwrap_or(node.handle()).to_string(),
            _ => node.handle().to_string(),
        };
        // The first free `base#n` (n ≥ 1). Names are only ever added to `taken`, so the
        // search for a base resumes where its last one stopped: a handle defined N times
        // costs N probes in all, not N² / 2.
        let mut name = base.clone();
        if taken.contains(&name) {
            let next = suffixes.entry(base.clone()).or_insert(1);
            while taken.contains(&name) {
                name = format!("{base}#{next}");
                *next += 1;
            }
        }
        taken.insert(name.clone());
        let material = Material {
            name,
            terminals: vec![Terminal {
                name: terminal.to_string(),
                link: Link::node(id, None),
            }],
            nodes: MaterialNodes::UpstreamOfTerminals,
            primvars: Vec::new(),
            location: node.location().cloned(),
        };
        net.materials_mut().push(material);
    }
}
