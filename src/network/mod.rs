//! The shader-network model: nodes, authored values and connections on a petgraph
//! [`StableDiGraph`].
//!
//! * A [`Node`] is one shader instance: a handle, a shader id, the request kind that created it
//!   ([`RequestKind`]), and its [`Param`]s in source order. RIB handles may be defined several
//!   times; each definition is a *version* with the unique key `handle#k`.
//! * A [`Param`] holds an optional authored [`Value`] and an ordered list of [`Link`]s (its
//!   connections). A link names its upstream node — or, when the reference could not be bound,
//!   the missing handle ([`Upstream::Missing`]) — and the upstream output (`None` for a
//!   whole-node reference).
//! * Every link to an existing node is mirrored by a graph edge (upstream → downstream) whose
//!   weight is an [`Edge`]: upstream output, downstream input and element index, so graph
//!   algorithms (upstream closures, cycle checks) work on [`Network::graph`].
//! * [`Material`]s name terminal nodes (RIB: one per `Bxdf`/`Displace`/`Light`/`LightFilter`;
//!   JSON: the `materials` object).
//!
//! Every edit is cheap (parameter lookup is a binary search, connection edits touch only the
//! edited input), and every edit is tracked: [`Param::change`] tells the RIB writer whether a
//! parameter read from a file is unchanged, got a new value, became connected, was removed, or
//! was added.
//!
//! # Building a network in code
//!
//! ```
//! use vstructc::network::{Network, RequestKind};
//! use vstructc::Value;
//!
//! let mut net = Network::new();
//! let layer = net.add_node("PxrLayer1", "PxrLayer");
//! let mixer = net.add_node("PxrLayerMixer1", "PxrLayerMixer");
//! let surface = net.add_node_of_kind("PxrLayerSurface1", "PxrLayerSurface", RequestKind::Bxdf);
//! net.set_param(layer, "enableDiffuse", Value::Int(1));
//! net.connect(mixer, "baselayer", layer, "pxrMaterialOut");
//! net.connect(surface, "inputMaterial", mixer, "pxrMaterialOut");
//! let m = net.add_material("PxrLayerSurface1SG");
//! net.set_terminal(m, "surface", surface, None);
//!
//! assert_eq!(net.connections(surface, "inputMaterial")[0].upstream_node(), Some(mixer));
//! assert_eq!(net.value(layer, "enableDiffuse"), Some(&Value::Int(1)));
//! assert_eq!(net.find("PxrLayerMixer1"), Some(mixer));
//! ```

mod limits;
mod links;
mod param_types;
mod sym;

pub(crate) use links::Links;
pub(crate) use param_types::Memo;
pub use param_types::{NoDefinitions, ParamTypes};
#[cfg(not(feature = "testkit"))]
pub(crate) use sym::Sym;
#[cfg(feature = "testkit")]
pub use sym::Sym;

use crate::diag::Location;
use crate::types::{Type, Value};
use hashbrown::HashTable;
use petgraph::stable_graph::{EdgeIndex, NodeIndex, StableDiGraph};
use petgraph::visit::EdgeRef;
use rustc_hash::{FxBuildHasher, FxHashSet};
use smallvec::SmallVec;
use std::fmt;
use std::hash::BuildHasher;
use std::ops::{Index, Range};
use std::sync::Arc;

/// Identifies a node of a [`Network`] (a petgraph node index; stable across edits).
pub type NodeId = NodeIndex;

/// Identifies a graph edge of a [`Network`].
pub(crate) type EdgeId = EdgeIndex;

/// The request kind that created a node (RIB request name; JSON: from its terminal).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
pub enum RequestKind {
    /// `Pattern`: a pattern node.
    Pattern,
    /// `Bxdf`: a surface terminal.
    Bxdf,
    /// `Displace`: a displacement terminal.
    Displace,
    /// `Light`: a light terminal.
    Light,
    /// `LightFilter`: a light-filter terminal.
    LightFilter,
}

impl RequestKind {
    /// Every kind, in a fixed order.
    pub const ALL: [RequestKind; 5] = [
        RequestKind::Pattern,
        RequestKind::Bxdf,
        RequestKind::Displace,
        RequestKind::Light,
        RequestKind::LightFilter,
    ];

    /// The RIB request keyword.
    ///
    /// ```
    /// use vstructc::network::RequestKind;
    /// assert_eq!(RequestKind::LightFilter.keyword(), "LightFilter");
    /// ```
    pub fn keyword(self) -> &'static str {
        match self {
            RequestKind::Pattern => "Pattern",
            RequestKind::Bxdf => "Bxdf",
            RequestKind::Displace => "Displace",
            RequestKind::Light => "Light",
            RequestKind::LightFilter => "LightFilter",
        }
    }

    /// The kind of an interpreted RIB request keyword, `None` for every other request.
    ///
    /// ```
    /// use vstructc::network::RequestKind;
    /// assert_eq!(RequestKind::from_keyword("Bxdf"), Some(RequestKind::Bxdf));
    /// assert_eq!(RequestKind::from_keyword("Integrator"), None);
    /// ```
    pub fn from_keyword(word: &str) -> Option<RequestKind> {
        RequestKind::ALL.into_iter().find(|k| k.keyword() == word)
    }

    /// The terminal name of a node of this kind (`surface`, `displacement`, `light`,
    /// `lightFilter`); `None` for patterns.
    ///
    /// ```
    /// use vstructc::network::RequestKind;
    /// assert_eq!(RequestKind::Bxdf.terminal_name(), Some("surface"));
    /// assert_eq!(RequestKind::Pattern.terminal_name(), None);
    /// ```
    pub fn terminal_name(self) -> Option<&'static str> {
        match self {
            RequestKind::Pattern => None,
            RequestKind::Bxdf => Some("surface"),
            RequestKind::Displace => Some("displacement"),
            RequestKind::Light => Some("light"),
            RequestKind::LightFilter => Some("lightFilter"),
        }
    }

    /// The kind of a node that a JSON terminal of this name points at: `surface` and
    /// `volume` are `Bxdf`, `displacement` is `Displace`, `light` is `Light`, `lightFilter`
    /// is `LightFilter`; any other name leaves the node a `Pattern`.
    ///
    /// ```
    /// use vstructc::network::RequestKind;
    /// assert_eq!(RequestKind::from_terminal_name("volume"), RequestKind::Bxdf);
    /// assert_eq!(RequestKind::from_terminal_name("custom"), RequestKind::Pattern);
    /// ```
    pub fn from_terminal_name(name: &str) -> RequestKind {
        match name {
            "surface" | "volume" => RequestKind::Bxdf,
            "displacement" => RequestKind::Displace,
            "light" => RequestKind::Light,
            "lightFilter" => RequestKind::LightFilter,
            _ => RequestKind::Pattern,
        }
    }
}

impl fmt::Display for RequestKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.keyword())
    }
}

/// A parameter declaration as read from the source: the RIB decl string, or the JSON `type`.
#[derive(Debug, Clone, PartialEq)]
pub struct Decl {
    /// The decl text as written (decoded RIB string content, e.g. `reference color inputRGB`);
    /// for JSON the type string.
    pub text: String,
    /// Storage class word (`uniform`, `varying`, …), kept but meaningless for shader params.
    pub class: Option<String>,
    /// True for `reference` decls (connections).
    pub reference: bool,
    /// The interpreted type, including `[N]` as `Fixed(N)`. For a decl without inline type,
    /// the definition's type (RB012).
    pub ty: Type,
    /// False when the type came from the definition rather than the decl text.
    pub inline_type: bool,
}

/// The upstream end of a connection (see [`Link::upstream`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Upstream<'a> {
    /// An existing node of the network.
    Node(NodeId),
    /// A reference to a handle that names no node (RIB: not defined before the referencing
    /// request, RB018; JSON: not in the material, JS010). Kept so the writers reproduce it and
    /// resolution can report it (VS010).
    Missing(&'a str),
}

/// One connection of an input: upstream node (or missing handle) and output name.
///
/// Sixteen bytes: a resolved scene has millions of member connections. A bound link holds
/// the node index and the interned output name; a dangling one (rare) a box with the handle.
#[derive(Clone, PartialEq, Eq, Hash)]
pub struct Link(LinkRepr);

#[derive(Clone, PartialEq, Eq, Hash)]
enum LinkRepr {
    Node(NodeId, Option<Sym>),
    Missing(Box<MissingLink>),
}

/// A dangling connection's handle and output.
#[derive(Clone, PartialEq, Eq, Hash)]
struct MissingLink {
    handle: Box<str>,
    output: Option<Sym>,
}

impl fmt::Debug for Link {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Link")
            .field("upstream", &self.upstream())
            .field("output", &self.output())
            .finish()
    }
}

impl Link {
    /// A connection to output `output` of node `node` (`None`: whole-node reference).
    ///
    /// ```
    /// use vstructc::network::{Link, Network};
    /// let mut net = Network::new();
    /// let a = net.add_node("a", "PxrFractal");
    /// let link = Link::node(a, Some("resultF"));
    /// assert_eq!(link.upstream_node(), Some(a));
    /// assert_eq!(link.output(), Some("resultF"));
    /// ```
    pub fn node(node: NodeId, output: Option<&str>) -> Link {
        Link(LinkRepr::Node(node, output.map(Sym::new)))
    }

    /// A connection to output `output` of node `node`, with the name interned already.
    pub(crate) fn node_sym(node: NodeId, output: Option<Sym>) -> Link {
        Link(LinkRepr::Node(node, output))
    }

    /// A dangling connection to a handle that names no node.
    ///
    /// ```
    /// use vstructc::network::Link;
    /// let link = Link::missing("Ghost", Some("resultRGB"));
    /// assert_eq!(link.missing_handle(), Some("Ghost"));
    /// assert_eq!(link.upstream_node(), None);
    /// ```
    pub fn missing(handle: &str, output: Option<&str>) -> Link {
        Link::missing_sym(handle, output.map(Sym::new))
    }

    /// [`Link::missing`] with the output name interned already.
    pub(crate) fn missing_sym(handle: &str, output: Option<Sym>) -> Link {
        Link(LinkRepr::Missing(Box::new(MissingLink {
            handle: Box::from(handle),
            output,
        })))
    }

    /// The upstream node or missing handle.
    ///
    /// ```
    /// use vstructc::network::{Link, Upstream};
    /// assert_eq!(Link::missing("Ghost", None).upstream(), Upstream::Missing("Ghost"));
    /// ```
    pub fn upstream(&self) -> Upstream<'_> {
        match &self.0 {
            LinkRepr::Node(id, _) => Upstream::Node(*id),
            LinkRepr::Missing(m) => Upstream::Missing(&m.handle),
        }
    }

    /// The upstream node, if the link is bound.
    pub fn upstream_node(&self) -> Option<NodeId> {
        match self.0 {
            LinkRepr::Node(id, _) => Some(id),
            LinkRepr::Missing(_) => None,
        }
    }

    /// The missing handle, if the link is dangling.
    pub fn missing_handle(&self) -> Option<&str> {
        match &self.0 {
            LinkRepr::Missing(m) => Some(&m.handle),
            LinkRepr::Node(..) => None,
        }
    }

    /// The output name (`None`: whole-node reference).
    pub fn output(&self) -> Option<&str> {
        self.output_sym().map(Sym::as_str)
    }

    /// The interned output name.
    pub(crate) fn output_sym(&self) -> Option<Sym> {
        match &self.0 {
            LinkRepr::Node(_, output) => *output,
            LinkRepr::Missing(m) => m.output,
        }
    }
}

/// The weight of a graph edge (upstream → downstream): which connection of which downstream
/// input the edge mirrors. Two numbers rather than names, so that a resolved scene with
/// millions of connections keeps small edges; [`Network::edge_link`] gives the input and the
/// link (upstream output included).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Edge {
    /// Position of the downstream input in [`Node::all_params`] of the downstream node.
    pub param: u32,
    /// Element index: position in the downstream input's ordered connection list.
    pub index: u32,
}

/// How a parameter differs from what was read from the RIB source.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ParamChange {
    /// Read from the source and written back exactly as it was.
    Unchanged,
    /// Read from the source; it is now unconnected and its value was replaced (or it lost its
    /// connection and keeps a value). Written at its original position with the new value.
    ValueReplaced,
    /// Read from the source; its connections were set or changed. Written at its original
    /// position as a `reference` parameter.
    Connected,
    /// No longer has a value or a connection: not written (its comments move to the next
    /// written parameter). Also the state of a parameter added and then cleared again.
    Removed,
    /// Not from the source (added by code or resolution): appended in declaration order.
    Added,
}

/// One parameter of a node: authored value, connections, declaration and change state.
#[derive(Debug, Clone, PartialEq)]
pub struct Param {
    /// Interned: a resolved scene has millions of parameters and a few thousand names.
    name: Sym,
    /// Boxed, like `source`: most members of a resolved scene are connections, not values.
    /// Shared: resolution writes the same `set` value into many members (one per expansion
    /// with the same decision), and they share one block.
    value: Option<Arc<Value>>,
    /// Inline for the usual single connection (sixteen bytes): a resolved scene has millions
    /// of member connections, and a heap block each was most of their cost. The graph edges that mirror
    /// them are found through the downstream node's incoming edges when a link changes
    /// (removing a petgraph edge walks those anyway), so a parameter keeps no edge ids.
    links: Links,
    /// Boxed: most parameters of a resolved scene were added by resolution and have none, and
    /// a smaller `Param` keeps nodes with hundreds of members compact.
    /// Also holds the change flags: a parameter without a source is [`ParamChange::Added`]
    /// (or `Removed`) whatever was done to it, so only source parameters need them.
    source: Option<Box<ParamSource>>,
}

/// Where a parameter read from a file came from. Small and free of shared pointers: the
/// file name is the node's ([`Node::location`]), so a parameter keeps only its position.
#[derive(Debug, Clone, PartialEq)]
struct ParamSource {
    /// Shared by the parameters of every node that repeats the declaration.
    decl: Option<Arc<Decl>>,
    /// The index into [`NodeSource::items`]; [`NO_ORIGIN`] for none.
    origin: u32,
    /// [`ParamAt`] as a kind ([`AT_UNKNOWN`], [`AT_LINE_COLUMN`], [`AT_JSON`]) in `flags`
    /// and its line and column here: 24 bytes in all, for the hundreds of thousands of
    /// parameters a large scene reads.
    line: u32,
    column: u32,
    /// The `ParamAt` kind, [`VALUE_TOUCHED`] (the value was set or removed since the
    /// parameter was read) and [`LINKS_TOUCHED`] (the connections were set or changed).
    flags: u8,
}

const AT_UNKNOWN: u8 = 0;
const AT_LINE_COLUMN: u8 = 1;
const AT_JSON: u8 = 2;
const AT_MASK: u8 = 3;
const VALUE_TOUCHED: u8 = 4;
const LINKS_TOUCHED: u8 = 8;

impl ParamSource {
    fn at(&self) -> ParamAt {
        match self.flags & AT_MASK {
            AT_LINE_COLUMN => ParamAt::LineColumn(self.line, self.column),
            AT_JSON => ParamAt::JsonParameter,
            _ => ParamAt::Unknown,
        }
    }
}

/// [`ParamSource::origin`] of a parameter not read from a RIB request.
const NO_ORIGIN: u32 = u32::MAX;

/// Where a parameter was declared, relative to its node's file (crate-internal: readers).
/// [`Node::param_location`] turns it into a [`Location`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) enum ParamAt {
    /// Not known.
    Unknown,
    /// 1-based line and column (in characters) of the declaration in the node's file.
    LineColumn(u32, u32),
    /// A JSON node's `parameters` member of this name (under the node's JSON Pointer).
    JsonParameter,
}

impl Param {
    fn empty(name: Sym) -> Param {
        Param {
            name,
            value: None,
            links: Links::new(),
            source: None,
        }
    }

    /// A parameter as read from a file (for tests; the readers make theirs from names
    /// and values they may share with other parameters).
    #[cfg(feature = "testkit")]
    #[cfg_attr(feature = "testkit", visibility::make(pub))]
    pub(crate) fn from_source(
        name: String,
        value: Option<Value>,
        decl: Option<Decl>,
        at: ParamAt,
        origin: Option<u32>,
    ) -> Param {
        Param::from_shared(
            Sym::new(&name),
            value.map(Arc::new),
            decl.map(Arc::new),
            at,
            origin,
        )
    }

    /// A parameter as read from a file, with a name, value and declaration that may be
    /// shared with other parameters (the RIB reader shares repeated ones). Always inlined:
    /// called, it read its position back in one load from two stores that had not landed
    /// yet, and that stall was most of its time.
    #[inline(always)]
    pub(crate) fn from_shared(
        name: Sym,
        value: Option<Arc<Value>>,
        decl: Option<Arc<Decl>>,
        at: ParamAt,
        origin: Option<u32>,
    ) -> Param {
        Param {
            name,
            value,
            links: Links::new(),
            source: (decl.is_some() || at != ParamAt::Unknown || origin.is_some()).then(|| {
                let (kind, line, column) = match at {
                    ParamAt::Unknown => (AT_UNKNOWN, 0, 0),
                    ParamAt::LineColumn(line, column) => (AT_LINE_COLUMN, line, column),
                    ParamAt::JsonParameter => (AT_JSON, 0, 0),
                };
                Box::new(ParamSource {
                    decl,
                    origin: origin.unwrap_or(NO_ORIGIN),
                    line,
                    column,
                    flags: kind,
                })
            }),
        }
    }

    /// The parameter with the connections `links` as read from a file (not a change;
    /// crate-internal: readers). [`Network::add_source_edges`] mirrors them once the node is
    /// in a network.
    pub(crate) fn with_source_links(mut self, links: Links) -> Param {
        self.links = links;
        self
    }

    /// Record that the value was set or removed (a change only for a parameter read from a
    /// source).
    fn touch_value(&mut self) {
        if let Some(s) = &mut self.source {
            s.flags |= VALUE_TOUCHED;
        }
    }

    /// Record that the connections changed (see [`Param::touch_value`]).
    fn touch_links(&mut self) {
        if let Some(s) = &mut self.source {
            s.flags |= LINKS_TOUCHED;
        }
    }

    /// The parameter name.
    pub fn name(&self) -> &str {
        self.name.as_str()
    }

    /// The interned name.
    pub(crate) fn name_sym(&self) -> Sym {
        self.name
    }

    /// The authored value, if any. A connected parameter may still hold a value (a `connect`
    /// action keeps the old value); the connection takes precedence.
    pub fn value(&self) -> Option<&Value> {
        self.value.as_deref()
    }

    /// The connections, in connection order.
    pub fn connections(&self) -> &[Link] {
        &self.links
    }

    /// True if the parameter has at least one connection.
    pub fn is_connected(&self) -> bool {
        !self.links.is_empty()
    }

    /// True if the parameter has a value or a connection.
    pub fn is_live(&self) -> bool {
        self.value.is_some() || !self.links.is_empty()
    }

    /// The declaration read from the source, if any.
    pub fn decl(&self) -> Option<&Decl> {
        self.source.as_ref()?.decl.as_deref()
    }

    /// The 1-based line and column of the parameter's declaration in its node's file, if it
    /// was read from RIB ([`Node::param_location`] gives the whole location).
    pub fn line_column(&self) -> Option<(u32, u32)> {
        match self.source.as_ref()?.at() {
            ParamAt::LineColumn(line, column) => Some((line, column)),
            ParamAt::Unknown | ParamAt::JsonParameter => None,
        }
    }

    /// The index of this parameter's occurrence in [`NodeSource::items`], if it was read from
    /// a RIB request.
    pub fn source_item(&self) -> Option<usize> {
        let origin = self.source.as_ref()?.origin;
        (origin != NO_ORIGIN).then_some(origin as usize)
    }

    /// How the parameter differs from the source (see [`ParamChange`]).
    ///
    /// ```
    /// use vstructc::network::{Network, ParamChange};
    /// use vstructc::Value;
    /// let mut net = Network::new();
    /// let n = net.add_node("n", "PxrFractal");
    /// net.set_param(n, "layers", Value::Int(3));
    /// assert_eq!(net[n].param("layers").unwrap().change(), ParamChange::Added);
    /// ```
    pub fn change(&self) -> ParamChange {
        if !self.is_live() {
            return ParamChange::Removed;
        }
        if self.source_item().is_none() {
            return ParamChange::Added;
        }
        let (value_touched, links_touched) = self.source.as_ref().map_or((false, false), |s| {
            (s.flags & VALUE_TOUCHED != 0, s.flags & LINKS_TOUCHED != 0)
        });
        if links_touched && !self.links.is_empty() {
            ParamChange::Connected
        } else if !self.links.is_empty() {
            // Only the (unchanged) connection is written for a connected parameter.
            ParamChange::Unchanged
        } else if links_touched || value_touched {
            ParamChange::ValueReplaced
        } else {
            ParamChange::Unchanged
        }
    }
}

/// Where a node's request is in the RIB source, for the writer (byte ranges only; the bytes
/// stay with the caller).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NodeSource {
    /// From the request keyword to the end of its last argument, extended over a comment on
    /// the same line as the last value. Everything outside these spans is passed through.
    pub span: Range<usize>,
    /// Every parameter occurrence in source order (duplicates included).
    pub items: Vec<SourceParam>,
    /// The comments inside the span, in source order, each from `#` to the end of its line
    /// (newline excluded): the parameter occurrences' (an occurrence's own are given by
    /// [`NodeSource::leading_comments`] and [`NodeSource::trailing_comment`]), then those
    /// that precede no parameter ([`NodeSource::end_comments`]). One list per request: most
    /// requests have none.
    pub comments: Vec<Range<usize>>,
    /// Where the comments that precede no parameter start in `comments` (one list rather
    /// than two keeps a node of a large scene sixteen bytes smaller).
    end_start: u32,
}

impl NodeSource {
    /// A request's source: its span, its parameter occurrences, and its comments, those from
    /// `end_start` on preceding no parameter (crate-internal: the RIB reader).
    pub(crate) fn new(
        span: Range<usize>,
        items: Vec<SourceParam>,
        comments: Vec<Range<usize>>,
        end_start: usize,
    ) -> Self {
        NodeSource {
            span,
            items,
            comments,
            end_start: u32::try_from(end_start).unwrap_or(u32::MAX),
        }
    }

    /// The comments inside the span that precede no parameter (a request without
    /// parameters).
    pub fn end_comments(&self) -> &[Range<usize>] {
        self.comments.get(self.end_start as usize..).unwrap_or(&[])
    }

    /// The comments between the previous parameter occurrence and occurrence `index` of
    /// [`NodeSource::items`] (or inside it, between decl and value); none for an index out
    /// of range.
    pub fn leading_comments(&self, index: usize) -> &[Range<usize>] {
        let all = self.comments_of(index);
        let trailing = self.items.get(index).is_some_and(SourceParam::trailing);
        &all[..all.len() - usize::from(trailing && !all.is_empty())]
    }

    /// The comment on the same line as the end of the value of occurrence `index` of
    /// [`NodeSource::items`], if any.
    pub fn trailing_comment(&self, index: usize) -> Option<&Range<usize>> {
        let trailing = self.items.get(index).is_some_and(SourceParam::trailing);
        if trailing {
            self.comments_of(index).last()
        } else {
            None
        }
    }

    /// The bytes of `item`'s decl string token (quotes included) in the source.
    pub fn decl(&self, item: &SourceParam) -> Range<usize> {
        self.absolute(&item.decl)
    }

    /// The bytes of `item`'s value (array brackets or the bare value token included) in the
    /// source.
    pub fn value(&self, item: &SourceParam) -> Range<usize> {
        self.absolute(&item.value)
    }

    fn absolute(&self, r: &Range<u32>) -> Range<usize> {
        self.span.start + r.start as usize..self.span.start + r.end as usize
    }

    /// The comments of occurrence `index`: from where its own start to where the next
    /// occurrence's start (the last one's: to the end of the list).
    fn comments_of(&self, index: usize) -> &[Range<usize>] {
        let Some(item) = self.items.get(index) else {
            return &[];
        };
        let end = self
            .items
            .get(index + 1)
            .map_or(self.end_start, |next| next.comments) as usize;
        self.comments
            .get(item.comments as usize..end)
            .unwrap_or(&[])
    }
}

/// One parameter occurrence inside a RIB request: which parameter it defines and where its
/// decl, value and comments are ([`NodeSource::decl`], [`NodeSource::value`],
/// [`NodeSource::leading_comments`], [`NodeSource::trailing_comment`]). A scene holds one per
/// parameter read, so it is kept to 24 bytes: its byte ranges are 32-bit offsets from the
/// start of the request's span (a request is at most 4 GiB long), and its comments are given
/// by where they start alone (the occurrences' comments follow each other in
/// [`NodeSource::comments`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SourceParam {
    /// Index into [`Node::all_params`], or [`NO_PARAM`]; [`TRAILING`] set if the last of its
    /// comments is on the same line as the end of the value. (An index is below 2^31: each
    /// occurrence takes several bytes of a request of at most 4 GiB.)
    param: u32,
    /// The decl string token, relative to [`NodeSource::span`]'s start.
    decl: Range<u32>,
    /// The value, relative to [`NodeSource::span`]'s start.
    value: Range<u32>,
    /// Where this occurrence's comments start in [`NodeSource::comments`]: the leading ones,
    /// then the trailing one when [`TRAILING`] is set; they end where the next occurrence's
    /// start (the last occurrence's: where the comments preceding no parameter start).
    comments: u32,
}

/// [`SourceParam::param`] of an occurrence that defines no parameter.
const NO_PARAM: u32 = !TRAILING;

/// The flag of [`SourceParam::param`] for a trailing comment.
const TRAILING: u32 = 1 << 31;

impl SourceParam {
    /// An occurrence defining parameter `param`, its decl and value given relative to the
    /// start of the request's span, with its comments from `comments` in
    /// [`NodeSource::comments`].
    pub(crate) fn new(param: u32, decl: Range<u32>, value: Range<u32>, comments: u32) -> Self {
        debug_assert!(param < NO_PARAM, "occurrence index {param}");
        SourceParam {
            param: param & NO_PARAM,
            decl,
            value,
            comments,
        }
    }

    /// Index into [`Node::all_params`] of the parameter this occurrence defines; `None` when
    /// a later duplicate replaced it (RB015).
    pub fn param(&self) -> Option<u32> {
        let param = self.param & NO_PARAM;
        (param != NO_PARAM).then_some(param)
    }

    /// Sets the parameter this occurrence defines (`None`: replaced by a later duplicate).
    pub(crate) fn set_param(&mut self, param: Option<u32>) {
        self.param = (self.param & TRAILING) | (param.unwrap_or(NO_PARAM) & NO_PARAM);
    }

    /// Marks the last of this occurrence's comments as on the same line as the end of the
    /// value.
    pub(crate) fn set_trailing(&mut self) {
        self.param |= TRAILING;
    }

    fn trailing(&self) -> bool {
        self.param & TRAILING != 0
    }
}

/// One shader node (one RIB request, one JSON node).
#[derive(Debug, Clone)]
pub struct Node {
    /// `handle#version` once the node is in a network; the handle is its first
    /// `handle_len` bytes (one string for both).
    key: String,
    handle_len: usize,
    version: u32,
    /// Shared by every node of the network with this shader id.
    shader: Arc<str>,
    kind: RequestKind,
    params: Vec<Param>,
    /// Indices into `params`, hashed by parameter name, once the node has more than
    /// [`SMALL_NODE`] parameters (fewer are scanned). Resolution looks parameters up by
    /// name several times per member; nodes such as PxrLayerMixer have hundreds of them.
    /// Positions only (4 bytes an entry): the interned names keep their hashes, so the table
    /// grows without hashing a name again.
    by_name: HashTable<u32>,
    location: Option<Location>,
    source: Option<NodeSource>,
    dirty: bool,
}

/// Where a parameter is among a node's parameters: at a position, or not there yet (with the
/// hash of its name, so that adding it does not hash the name again).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) enum Slot {
    /// At this position of [`Node::all_params`].
    At(usize),
    /// Not a parameter of the node yet.
    Missing {
        /// [`name_hash`] of the name.
        hash: u64,
    },
}

impl Slot {
    /// The position, if the parameter exists.
    pub(crate) fn position(self) -> Option<usize> {
        match self {
            Slot::At(i) => Some(i),
            Slot::Missing { .. } => None,
        }
    }
}

/// The first eight bytes of `s` as a big-endian number, zero-padded: comparing two of these
/// orders strings as comparing their first eight bytes does.
fn prefix_key(s: &str) -> u64 {
    let mut bytes = [0u8; 8];
    let n = s.len().min(8);
    bytes[..n].copy_from_slice(&s.as_bytes()[..n]);
    u64::from_be_bytes(bytes)
}

/// The hash of a parameter name in a node's name index. Callers that look the same names up
/// in many nodes (resolution's members) compute it once and use the `*_hashed` look-ups.
///
/// The hash is 32 bits repeated in both halves, so the name index can store it in 4 bytes
/// and rebuild the full value when it grows (`unfold`).
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) fn name_hash(name: &str) -> u64 {
    let h = FxBuildHasher.hash_one(name);
    unfold((h ^ (h >> 32)) as u32)
}

/// The [`name_hash`] whose low half is `h`.
fn unfold(h: u32) -> u64 {
    u64::from(h) << 32 | u64::from(h)
}

/// The weight of the edge mirroring connection `index` of the parameter at position `param`.
/// A node's parameters and an input's connections are bounded by [`crate::Limits`] far below
/// `u32::MAX`; beyond it the numbers saturate.
fn edge_weight(param: usize, index: usize) -> Edge {
    Edge {
        param: u32::try_from(param).unwrap_or(u32::MAX),
        index: u32::try_from(index).unwrap_or(u32::MAX),
    }
}

/// A node with at most this many parameters has no name index: scanning them is as fast, and
/// most nodes of a scene are that small.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
const SMALL_NODE: usize = 8;

impl PartialEq for Node {
    /// Compares everything but the name index (which is derived from `params`).
    fn eq(&self, other: &Node) -> bool {
        self.key == other.key
            && self.handle_len == other.handle_len
            && self.version == other.version
            && self.shader == other.shader
            && self.kind == other.kind
            && self.params == other.params
            && self.location == other.location
            && self.source == other.source
            && self.dirty == other.dirty
    }
}

impl Node {
    /// A node with no parameters (crate-internal; use [`Network::add_node`]).
    #[cfg_attr(feature = "testkit", visibility::make(pub))]
    pub(crate) fn new_raw(handle: &str, shader: &str, kind: RequestKind) -> Node {
        Node::new_shared(handle, Arc::from(shader), kind)
    }

    /// [`Node::new_raw`] with a shared shader id (crate-internal: readers).
    pub(crate) fn new_shared(handle: &str, shader: Arc<str>, kind: RequestKind) -> Node {
        // Room for the `#version` suffix the network appends.
        let mut key = String::with_capacity(handle.len() + 4);
        key.push_str(handle);
        Node {
            key,
            handle_len: handle.len(),
            version: 0,
            shader,
            kind,
            params: Vec::new(),
            by_name: HashTable::new(),
            location: None,
            source: None,
            dirty: false,
        }
    }

    /// Replace the parameters (crate-internal: readers). Names must be unique.
    #[cfg_attr(feature = "testkit", visibility::make(pub))]
    pub(crate) fn set_raw_params(&mut self, params: Vec<Param>) {
        self.params = params;
        self.by_name = HashTable::new();
        if self.params.len() > SMALL_NODE {
            self.build_index(0);
        }
    }

    /// Builds the name index of a node that has none, with room for `additional` more names.
    fn build_index(&mut self, additional: usize) {
        let params = &self.params;
        let mut by_name = HashTable::with_capacity(params.len() + additional);
        for (i, p) in params.iter().enumerate() {
            by_name.insert_unique(p.name.name_hash(), i as u32, |&j| {
                params[j as usize].name.name_hash()
            });
        }
        self.by_name = by_name;
    }

    /// True if the node has a name index (see [`SMALL_NODE`]).
    fn indexed(&self) -> bool {
        self.params.len() > SMALL_NODE
    }

    /// Set where the node came from (crate-internal: readers).
    pub(crate) fn set_origin(&mut self, location: Option<Location>, source: Option<NodeSource>) {
        self.location = location;
        self.source = source;
    }

    /// The unique key: `handle#k` for version `k` of a handle.
    pub fn key(&self) -> &str {
        &self.key
    }

    /// The handle (RIB) or node name (JSON).
    pub fn handle(&self) -> &str {
        &self.key[..self.handle_len]
    }

    /// The version `k` of the handle (0 for the first definition).
    pub fn version(&self) -> u32 {
        self.version
    }

    /// The shader id (`nodeTypeId`).
    pub fn shader(&self) -> &str {
        &self.shader
    }

    /// The request kind.
    pub fn kind(&self) -> RequestKind {
        self.kind
    }

    /// Where the node was defined (RIB request keyword; JSON pointer), if known.
    pub fn location(&self) -> Option<&Location> {
        self.location.as_ref()
    }

    /// Where parameter `p` of this node was declared (RIB: the decl string's line and column;
    /// JSON: the pointer to its `parameters` member), if known. The location is built on
    /// demand: a parameter stores only its position, the file is the node's.
    ///
    /// ```
    /// use vstructc::front::rib::{RibOptions, parse_rib};
    /// use vstructc::network::NoDefinitions;
    /// use vstructc::Diagnostics;
    /// let src = b"Pattern \"PxrFractal\" \"f\"\n  \"int layers\" [3]\n";
    /// let mut diags = Diagnostics::new();
    /// let net = parse_rib(src, "a.rib", &NoDefinitions, &RibOptions::default(), &mut diags).unwrap();
    /// let f = &net[net.find("f").unwrap()];
    /// let at = f.param_location(f.param("layers").unwrap()).unwrap();
    /// assert_eq!(at.to_string(), "a.rib:2:3");
    /// ```
    pub fn param_location(&self, p: &Param) -> Option<Location> {
        let node = self.location.as_ref()?;
        match p.source.as_ref()?.at() {
            ParamAt::Unknown => None,
            ParamAt::LineColumn(line, column) => {
                Some(Location::new(node.file.clone(), line, column))
            }
            ParamAt::JsonParameter => {
                let mut pointer = node.pointer.clone()?;
                pointer.push_str("/parameters/");
                pointer.push_str(&p.name.replace('~', "~0").replace('/', "~1"));
                Some(Location {
                    file: node.file.clone(),
                    line: 0,
                    column: 0,
                    pointer: Some(pointer),
                })
            }
        }
    }

    /// The RIB source layout of the request, if the node was read from RIB.
    pub fn source(&self) -> Option<&NodeSource> {
        self.source.as_ref()
    }

    /// A name for messages: the handle, and for versions after the first, the line of the
    /// version (`Curvature (line 57)`).
    ///
    /// ```
    /// use vstructc::network::Network;
    /// let mut net = Network::new();
    /// let a = net.add_node("A", "PxrFractal");
    /// let b = net.add_node("A", "PxrFractal");
    /// assert_eq!(net[a].display_name(), "A");
    /// assert_eq!(net[b].display_name(), "A#1");
    /// ```
    pub fn display_name(&self) -> String {
        match (&self.location, self.version) {
            (_, 0) => self.handle().to_string(),
            (Some(loc), _) if loc.line > 0 => format!("{} (line {})", self.handle(), loc.line),
            _ => self.key.clone(),
        }
    }

    fn index_of(&self, name: &str) -> Option<usize> {
        self.index_of_hashed(name, name_hash(name))
    }

    /// [`Self::index_of`] with the name's [`name_hash`] already known.
    fn index_of_hashed(&self, name: &str, hash: u64) -> Option<usize> {
        let params = &self.params;
        if !self.indexed() {
            return params.iter().position(|p| &*p.name == name);
        }
        self.by_name
            .find(hash, |&i| &*params[i as usize].name == name)
            .map(|&i| i as usize)
    }

    fn index_or_insert(&mut self, name: &str) -> usize {
        match self.index_of(name) {
            Some(i) => i,
            None => self.insert_param(Sym::new(name)),
        }
    }

    /// Appends the parameter `name`, which the node does not have.
    fn insert_param(&mut self, name: Sym) -> usize {
        let idx = self.params.len();
        let hash = name.name_hash();
        let was_indexed = self.indexed();
        self.params.push(Param::empty(name));
        if was_indexed {
            let params = &self.params;
            self.by_name
                .insert_unique(hash, idx as u32, |&j| params[j as usize].name.name_hash());
        } else if self.indexed() {
            self.build_index(0);
        }
        idx
    }

    /// Indices of `params` in byte-wise name order.
    fn sorted_indices(&self, keep: impl Fn(&Param) -> bool) -> Vec<usize> {
        let mut order: Vec<usize> = (0..self.params.len())
            .filter(|&i| keep(&self.params[i]))
            .collect();
        order.sort_unstable_by(|&a, &b| self.params[a].name.cmp(&self.params[b].name));
        order
    }

    /// The parameter named `name`, if it exists (live or not).
    pub fn param(&self, name: &str) -> Option<&Param> {
        self.index_of(name).map(|i| &self.params[i])
    }

    /// Live parameters (with a value or a connection) in source order, then added ones in the
    /// order they were added.
    pub fn params(&self) -> impl Iterator<Item = &Param> + '_ {
        self.params.iter().filter(|p| p.is_live())
    }

    /// Every parameter entry, including removed ones, indexed as [`SourceParam::param`].
    pub fn all_params(&self) -> &[Param] {
        &self.params
    }

    /// Live parameters sorted by name (byte-wise).
    pub fn params_by_name(&self) -> impl Iterator<Item = &Param> + '_ {
        self.sorted_indices(Param::is_live)
            .into_iter()
            .map(|i| &self.params[i])
    }

    /// The authored value of `name`.
    pub fn value(&self, name: &str) -> Option<&Value> {
        self.param(name).and_then(Param::value)
    }

    /// The connections of input `name` in order (empty if none).
    pub fn connections(&self, name: &str) -> &[Link] {
        self.param(name).map_or(&[], |p| &p.links[..])
    }

    /// Names of connected inputs, sorted byte-wise.
    pub fn connected_inputs(&self) -> impl Iterator<Item = &str> + '_ {
        self.sorted_indices(Param::is_connected)
            .into_iter()
            .map(|i| &*self.params[i].name)
    }

    /// The `string __materialid` value, if authored.
    pub fn material_id(&self) -> Option<&str> {
        match self.value("__materialid") {
            Some(Value::Str(s)) => Some(s),
            _ => None,
        }
    }

    /// True if some parameter differs from the source (value replaced, connected, removed or
    /// added). Nodes not read from RIB report `true` when they have any parameter edits.
    pub fn is_modified(&self) -> bool {
        self.dirty
            && self.params.iter().any(|p| match p.change() {
                ParamChange::Unchanged => false,
                ParamChange::Removed => p.source_item().is_some(),
                _ => true,
            })
    }
}

/// A terminal of a material: a name (`surface`, `displacement`, …) and the connection to the
/// terminal node.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Terminal {
    /// Terminal name.
    pub name: String,
    /// The terminal node (or a missing handle) and output (`None`: the whole node).
    pub link: Link,
}

/// Which nodes belong to a material.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum MaterialNodes {
    /// The transitive upstream closure of the terminal nodes (RIB; networks built in code).
    UpstreamOfTerminals,
    /// An explicit node set (JSON `nodes`), in file order.
    Explicit(Vec<NodeId>),
}

/// A named material: terminals and a node set.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// Material name (RIB: `__materialid` or handle of the `Bxdf`).
    pub name: String,
    /// Terminals in order.
    pub terminals: Vec<Terminal>,
    /// The nodes of the material.
    pub nodes: MaterialNodes,
    /// JSON `primvars`, as given.
    pub primvars: Vec<String>,
    /// Where the material was defined, if known.
    pub location: Option<Location>,
}

/// The hash of a node handle in [`Network`]'s table of handles.
fn handle_hash(handle: &str) -> u64 {
    FxBuildHasher.hash_one(handle)
}

/// Nodes reserved at most before an input is read ([`Network::reserve_for_input`]; about
/// 64 MB of address space).
const MAX_RESERVED_NODES: usize = 1 << 18;

/// A shader network: nodes and connections on a petgraph [`StableDiGraph`], plus materials.
///
/// Nodes are never removed, so [`NodeId`]s stay valid. Methods taking a `NodeId` panic if it
/// does not belong to this network (a programming error, like indexing a `Vec` out of range).
#[derive(Debug, Clone, Default)]
pub struct Network {
    graph: StableDiGraph<Node, Edge>,
    /// Every version of each handle, oldest first (usually one, kept inline), with the
    /// [`handle_hash`] of the handle (the table grows without reading a node). The handle
    /// itself is read from the first version's node (nodes are never removed): a scene's
    /// handles are not stored a second time.
    handles: HashTable<(u64, SmallVec<[NodeId; 1]>)>,
    /// The shader ids of the nodes, each stored once.
    shaders: FxHashSet<Arc<str>>,
    materials: Vec<Material>,
    /// True between [`Network::suspend_edges`] and [`Network::restore_edges`]: links are not
    /// mirrored by graph edges then.
    edges_suspended: bool,
}

impl Index<NodeId> for Network {
    type Output = Node;
    /// The node `id`. Panics if `id` is not a node of this network.
    fn index(&self, id: NodeId) -> &Node {
        &self.graph[id]
    }
}

impl Network {
    /// An empty network.
    ///
    /// ```
    /// let net = vstructc::network::Network::new();
    /// assert_eq!(net.node_count(), 0);
    /// ```
    pub fn new() -> Network {
        Network::default()
    }

    /// The underlying graph: node weights are [`Node`]s, edges run upstream → downstream and
    /// carry an [`Edge`]. Dangling links have no edge.
    pub fn graph(&self) -> &StableDiGraph<Node, Edge> {
        &self.graph
    }

    /// The downstream input and the connection that graph edge `edge` mirrors, if the edge
    /// exists.
    ///
    /// ```
    /// use vstructc::network::Network;
    /// let mut net = Network::new();
    /// let a = net.add_node("a", "PxrFractal");
    /// let d = net.add_node("d", "PxrSurface");
    /// net.connect(d, "diffuseGain", a, "resultF");
    /// let e = net.graph().edge_indices().next().unwrap();
    /// let (input, link) = net.edge_link(e).unwrap();
    /// assert_eq!((input.name(), link.output()), ("diffuseGain", Some("resultF")));
    /// ```
    pub fn edge_link(&self, edge: EdgeIndex) -> Option<(&Param, &Link)> {
        let w = self.graph.edge_weight(edge)?;
        let (_, down) = self.graph.edge_endpoints(edge)?;
        let p = self.graph[down].params.get(w.param as usize)?;
        Some((p, p.links.get(w.index as usize)?))
    }

    /// Number of nodes (all versions).
    pub fn node_count(&self) -> usize {
        self.graph.node_count()
    }

    /// Add a `Pattern` node. If `handle` already names a node, this is a new version of it
    /// (key `handle#k`), as a RIB redefinition would be; [`Network::find`] then returns it.
    ///
    /// ```
    /// use vstructc::network::{Network, RequestKind};
    /// let mut net = Network::new();
    /// let n = net.add_node("PxrFractal1", "PxrFractal");
    /// assert_eq!(net[n].key(), "PxrFractal1#0");
    /// assert_eq!(net[n].kind(), RequestKind::Pattern);
    /// ```
    pub fn add_node(&mut self, handle: &str, shader: &str) -> NodeId {
        self.add_node_of_kind(handle, shader, RequestKind::Pattern)
    }

    /// Add a node of the given request kind (see [`Network::add_node`]).
    ///
    /// ```
    /// use vstructc::network::{Network, RequestKind};
    /// let mut net = Network::new();
    /// let s = net.add_node_of_kind("Surface1", "PxrSurface", RequestKind::Bxdf);
    /// assert_eq!(net[s].shader(), "PxrSurface");
    /// ```
    pub fn add_node_of_kind(&mut self, handle: &str, shader: &str, kind: RequestKind) -> NodeId {
        self.insert_node(Node::new_raw(handle, shader, kind))
    }

    /// Insert a prepared node, assigning its version and key (crate-internal: readers).
    #[cfg_attr(feature = "testkit", visibility::make(pub))]
    pub(crate) fn insert_node(&mut self, mut node: Node) -> NodeId {
        fn set_version(node: &mut Node, version: usize) {
            node.version = version as u32;
            node.key.truncate(node.handle_len);
            node.key.push('#');
            node.key.push_str(itoa::Buffer::new().format(version));
        }
        match self.shaders.get(&*node.shader) {
            Some(shared) => node.shader = shared.clone(),
            None => {
                self.shaders.insert(node.shader.clone());
            }
        }
        // One look-up of the handle.
        let hash = handle_hash(node.handle());
        let graph = &self.graph;
        let versions = self.handles.find_mut(hash, |(h, v)| {
            *h == hash && graph[v[0]].handle() == node.handle()
        });
        match versions {
            Some((_, versions)) => {
                set_version(&mut node, versions.len());
                let id = self.graph.add_node(node);
                versions.push(id);
                id
            }
            None => {
                set_version(&mut node, 0);
                let id = self.graph.add_node(node);
                self.handles
                    .insert_unique(hash, (hash, smallvec::smallvec![id]), |(h, _)| *h);
                id
            }
        }
    }

    /// Room for the nodes of an input of `len` bytes whose nodes take about
    /// `bytes_per_node` bytes each, and as many edges, for at most `max_nodes` nodes and
    /// [`MAX_RESERVED_NODES`] (crate-internal: readers). The tables then fill in place:
    /// growing them by doubling copied every node several times and touched twice the
    /// memory. Room that stays unused is address space, not memory, until something is
    /// written there.
    pub(crate) fn reserve_for_input(&mut self, len: usize, bytes_per_node: usize, max_nodes: u64) {
        let cap = usize::try_from(max_nodes).unwrap_or(usize::MAX);
        let nodes = (len / bytes_per_node.max(1))
            .min(MAX_RESERVED_NODES)
            .min(cap);
        self.graph.reserve_nodes(nodes);
        self.graph.reserve_edges(nodes);
    }

    /// The network's shared copy of shader id `shader` (crate-internal: readers build nodes
    /// with it rather than a copy of their own).
    pub(crate) fn shared_shader(&mut self, shader: &str) -> Arc<str> {
        if let Some(shared) = self.shaders.get(shader) {
            return shared.clone();
        }
        let shared: Arc<str> = Arc::from(shader);
        self.shaders.insert(shared.clone());
        shared
    }

    /// Change the request kind of node `id` (crate-internal: the JSON reader learns a node's
    /// kind from terminals that may follow the node in the document).
    pub(crate) fn set_node_kind(&mut self, id: NodeId, kind: RequestKind) {
        self.graph[id].kind = kind;
    }

    /// Set where node `id` was defined (crate-internal: the USD reader).
    #[cfg(feature = "usd")]
    pub(crate) fn set_node_location(&mut self, id: NodeId, location: Location) {
        self.graph[id].location = Some(location);
    }

    /// The node `id`, or `None` if it is not in this network.
    pub fn get(&self, id: NodeId) -> Option<&Node> {
        self.graph.node_weight(id)
    }

    /// The latest version of `handle` (the node a new reference would bind to).
    ///
    /// ```
    /// use vstructc::network::Network;
    /// let mut net = Network::new();
    /// let v0 = net.add_node("A", "PxrFractal");
    /// let v1 = net.add_node("A", "PxrWorley");
    /// assert_eq!(net.find("A"), Some(v1));
    /// assert_eq!(net.versions("A"), &[v0, v1]);
    /// assert_eq!(net.find("B"), None);
    /// ```
    pub fn find(&self, handle: &str) -> Option<NodeId> {
        self.versions(handle).last().copied()
    }

    /// Every version of `handle`, oldest first.
    pub fn versions(&self, handle: &str) -> &[NodeId] {
        let hash = handle_hash(handle);
        self.handles
            .find(hash, |(h, v)| {
                *h == hash && self.graph[v[0]].handle() == handle
            })
            .map_or(&[], |(_, v)| v.as_slice())
    }

    /// The node with key `handle#k`.
    ///
    /// ```
    /// use vstructc::network::Network;
    /// let mut net = Network::new();
    /// let v0 = net.add_node("Solid Material 21", "PxrSurface");
    /// let v1 = net.add_node("Solid Material 21", "PxrSurface");
    /// assert_eq!(net.by_key("Solid Material 21#1"), Some(v1));
    /// assert_eq!(net.by_key("Solid Material 21#0"), Some(v0));
    /// assert_eq!(net.by_key("Solid Material 21"), None);
    /// ```
    pub fn by_key(&self, key: &str) -> Option<NodeId> {
        let (handle, k) = key.rsplit_once('#')?;
        let k: usize = k.parse().ok()?;
        self.versions(handle).get(k).copied()
    }

    /// All node ids in insertion (file) order.
    pub fn node_ids(&self) -> impl Iterator<Item = NodeId> + '_ {
        self.graph.node_indices()
    }

    /// All node ids sorted by name: by handle (byte-wise), then version. This is the
    /// deterministic visiting order of resolution.
    ///
    /// ```
    /// use vstructc::network::Network;
    /// let mut net = Network::new();
    /// let b = net.add_node("b", "X");
    /// let a = net.add_node("a", "X");
    /// let b1 = net.add_node("b", "X");
    /// assert_eq!(net.nodes_sorted(), vec![a, b, b1]);
    /// ```
    pub fn nodes_sorted(&self) -> Vec<NodeId> {
        // Sorting the keys themselves rather than ids saves two graph look-ups per comparison,
        // and the handle's first eight bytes as a number decide most comparisons without
        // comparing strings (zero padding keeps that number in byte-wise order; equal
        // numbers fall through to the whole handle). Ties (none in networks the readers
        // build) fall back to the id, which is the order the stable sort of ids gave.
        let mut keys: Vec<(u64, &str, u32, NodeId)> = self
            .graph
            .node_indices()
            .map(|id| {
                let handle = self.graph[id].handle();
                (prefix_key(handle), handle, self.graph[id].version, id)
            })
            .collect();
        keys.sort_unstable();
        keys.into_iter().map(|(_, _, _, id)| id).collect()
    }

    /// The authored value of `node.name`.
    pub fn value(&self, node: NodeId, name: &str) -> Option<&Value> {
        self.graph[node].value(name)
    }

    /// Set the authored value of `node.name` (creating the parameter if needed); returns the
    /// previous value. Setting the value it already has is not a change.
    ///
    /// ```
    /// use vstructc::network::Network;
    /// use vstructc::Value;
    /// let mut net = Network::new();
    /// let n = net.add_node("L", "PxrLayer");
    /// assert_eq!(net.set_param(n, "enableClearcoat", Value::Int(0)), None);
    /// assert_eq!(net.set_param(n, "enableClearcoat", Value::Int(1)), Some(Value::Int(0)));
    /// assert_eq!(net.value(n, "enableClearcoat"), Some(&Value::Int(1)));
    /// ```
    pub fn set_param(&mut self, node: NodeId, name: &str, value: Value) -> Option<Value> {
        let slot = self.graph[node].index_or_insert(name);
        self.set_at(node, slot, value)
    }

    /// Remove the authored value of `node.name`; returns it.
    ///
    /// ```
    /// use vstructc::network::Network;
    /// use vstructc::Value;
    /// let mut net = Network::new();
    /// let n = net.add_node("L", "PxrLayer");
    /// net.set_param(n, "diffuseGain", Value::Float(0.5));
    /// assert_eq!(net.remove_value(n, "diffuseGain"), Some(Value::Float(0.5)));
    /// assert_eq!(net.value(n, "diffuseGain"), None);
    /// ```
    pub fn remove_value(&mut self, node: NodeId, name: &str) -> Option<Value> {
        let n = &mut self.graph[node];
        let i = n.index_of(name)?;
        let old = n.params[i].value.take().map(Arc::unwrap_or_clone);
        if old.is_some() {
            n.params[i].touch_value();
            n.dirty = true;
        }
        old
    }

    /// Make room for `additional` more parameters on `node` (a hint; nothing changes). The
    /// room is exact unless the node already has more than four times `additional`
    /// parameters: then it grows by a quarter, so that a node that gets a few parameters at a
    /// time thousands of times (one per expanded head) is not copied each time. Call it once
    /// with the total rather than once per parameter (resolution calls it once per head).
    pub fn reserve_params(&mut self, node: NodeId, additional: usize) {
        let n = &mut self.graph[node];
        if n.params.capacity() - n.params.len() < additional {
            n.params.reserve_exact(additional.max(n.params.len() / 4));
        }
        if n.indexed() {
            let params = &n.params;
            n.by_name
                .reserve(additional, |&j| params[j as usize].name.name_hash());
        } else if n.params.len() + additional > SMALL_NODE {
            n.build_index(additional);
        }
    }

    /// The connections of `node.input` in connection order (empty if none).
    pub fn connections(&self, node: NodeId, input: &str) -> &[Link] {
        self.graph[node].connections(input)
    }

    /// Names of the connected inputs of `node`, sorted byte-wise (a snapshot).
    ///
    /// ```
    /// use vstructc::network::Network;
    /// let mut net = Network::new();
    /// let up = net.add_node("up", "PxrFractal");
    /// let down = net.add_node("down", "PxrLayer");
    /// net.connect(down, "diffuseGain", up, "resultF");
    /// net.connect(down, "clearcoatRoughness", up, "resultF");
    /// assert_eq!(net.connected_inputs(down), vec!["clearcoatRoughness", "diffuseGain"]);
    /// ```
    pub fn connected_inputs(&self, node: NodeId) -> Vec<String> {
        self.graph[node]
            .connected_inputs()
            .map(str::to_string)
            .collect()
    }

    /// Append a connection `up.output → down.input` (after any existing connections of the
    /// input).
    ///
    /// ```
    /// use vstructc::network::Network;
    /// let mut net = Network::new();
    /// let a = net.add_node("a", "PxrFractal");
    /// let b = net.add_node("b", "PxrFractal");
    /// let m = net.add_node("m", "PxrBlend");
    /// net.connect(m, "inputs", a, "resultF");
    /// net.connect(m, "inputs", b, "resultF");
    /// let ups: Vec<_> = net.connections(m, "inputs").iter().map(|l| l.upstream_node()).collect();
    /// assert_eq!(ups, vec![Some(a), Some(b)]);
    /// ```
    pub fn connect(&mut self, down: NodeId, input: &str, up: NodeId, output: &str) {
        self.push_link(down, input, Link::node(up, Some(output)));
    }

    /// Append a whole-node reference `up → down.input` (no output name).
    pub fn connect_node(&mut self, down: NodeId, input: &str, up: NodeId) {
        self.push_link(down, input, Link::node(up, None));
    }

    /// Append a connection (bound or dangling) to `down.input`.
    ///
    /// ```
    /// use vstructc::network::{Link, Network};
    /// let mut net = Network::new();
    /// let d = net.add_node("d", "PxrLayerMixer");
    /// net.push_link(d, "baselayer", Link::missing("NotThere", Some("pxrMaterialOut")));
    /// assert_eq!(net.connections(d, "baselayer")[0].missing_handle(), Some("NotThere"));
    /// ```
    pub fn push_link(&mut self, down: NodeId, input: &str, link: Link) {
        let i = self.graph[down].index_or_insert(input);
        self.append_link(down, i, link);
    }

    /// Append `link` to the parameter at position `i` of `down`, with its graph edge.
    fn append_link(&mut self, down: NodeId, i: usize, link: Link) {
        let index = self.graph[down].params[i].links.len();
        self.add_edge_for(down, i, &link, index);
        let n = &mut self.graph[down];
        let p = &mut n.params[i];
        p.links.push(link);
        p.touch_links();
        n.dirty = true;
    }

    /// Append links read from a file without marking the parameter changed (crate-internal).
    #[cfg_attr(feature = "testkit", visibility::make(pub))]
    pub(crate) fn push_source_links(&mut self, down: NodeId, param: usize, links: Vec<Link>) {
        for link in links {
            let index = self.graph[down].params[param].links.len();
            self.add_edge_for(down, param, &link, index);
            self.graph[down].params[param].links.push(link);
        }
    }

    /// Mirror by graph edges the connections that the parameters of node `down` were built
    /// with ([`Param::with_source_links`]), in parameter and connection order
    /// (crate-internal: readers).
    pub(crate) fn add_source_edges(&mut self, down: NodeId) {
        if self.edges_suspended {
            return;
        }
        let mut edges: SmallVec<[(NodeId, Edge); 4]> = SmallVec::new();
        for (param, p) in self.graph[down].params.iter().enumerate() {
            for (index, link) in p.links.iter().enumerate() {
                if let Some(up) = link.upstream_node() {
                    edges.push((up, edge_weight(param, index)));
                }
            }
        }
        for (up, edge) in edges {
            self.graph.add_edge(up, down, edge);
        }
    }

    /// The graph edge of `link`, the `index`-th connection of parameter `param` of `down`
    /// (none for a dangling link). The edge shares the parameter and output names.
    fn add_edge_for(&mut self, down: NodeId, param: usize, link: &Link, index: usize) {
        if self.edges_suspended {
            return;
        }
        let Some(up) = link.upstream_node() else {
            return;
        };
        self.graph.add_edge(up, down, edge_weight(param, index));
    }

    /// The graph edges mirroring the links of parameter `param` of `down`, with their
    /// element index (none while edges are suspended).
    fn edges_of(&self, down: NodeId, param: usize) -> Vec<(EdgeId, usize)> {
        let p = &self.graph[down].params[param];
        // A parameter without bound links has no edges: no walk (building a node's inputs
        // one by one stays linear).
        if self.edges_suspended || p.links.iter().all(|l| l.upstream_node().is_none()) {
            return Vec::new();
        }
        let param = param as u32;
        self.graph
            .edges_directed(down, petgraph::Direction::Incoming)
            .filter(|e| e.weight().param == param)
            .map(|e| (e.id(), e.weight().index as usize))
            .collect()
    }

    /// Stop mirroring links by graph edges until [`Network::restore_edges`] (crate-internal:
    /// resolution). Removing an edge from petgraph's lists walks every edge of both its
    /// nodes, so replacing the placeholder connections of a node read by N others, or the N
    /// connections of one input, one by one took time quadratic in N; resolution edits
    /// connections only, and the edges are rebuilt from the links once at its end.
    pub(crate) fn suspend_edges(&mut self) {
        self.graph.clear_edges();
        self.edges_suspended = true;
    }

    /// Mirror every link by a graph edge again, in node, parameter and connection order
    /// (see [`Network::suspend_edges`]).
    pub(crate) fn restore_edges(&mut self) {
        if !std::mem::replace(&mut self.edges_suspended, false) {
            return;
        }
        let ids: Vec<NodeId> = self.graph.node_indices().collect();
        // Exact room: a resolved scene has millions of edges, and doubling the edge table
        // while it fills would leave up to half of it unused (and copy it each time).
        let edges: usize = ids
            .iter()
            .flat_map(|&id| &self.graph[id].params)
            .map(|p| {
                p.links
                    .iter()
                    .filter(|l| l.upstream_node().is_some())
                    .count()
            })
            .sum();
        self.graph.reserve_exact_edges(edges);
        for down in ids {
            for i in 0..self.graph[down].params.len() {
                for index in 0..self.graph[down].params[i].links.len() {
                    let p = &self.graph[down].params[i];
                    let Some(up) = p.links[index].upstream_node() else {
                        continue;
                    };
                    self.graph.add_edge(up, down, edge_weight(i, index));
                }
            }
        }
    }

    /// Replace the connections of `down.input` with `links` (in that order); returns the old
    /// ones. Setting the same list again is not a change.
    ///
    /// ```
    /// use vstructc::network::{Link, Network};
    /// let mut net = Network::new();
    /// let u = net.add_node("u", "PxrLayer");
    /// let m = net.add_node("m", "PxrLayer");
    /// let d = net.add_node("d", "PxrLayerMixer");
    /// net.connect(d, "baselayer_diffuseGain", m, "pxrMaterialOut_diffuseGain");
    /// net.set_connections(d, "baselayer_diffuseGain", vec![Link::node(u, Some("pxrMaterialOut_diffuseGain"))]);
    /// assert_eq!(net.connections(d, "baselayer_diffuseGain")[0].upstream_node(), Some(u));
    /// assert_eq!(net.graph().edge_count(), 1);
    /// ```
    pub fn set_connections(&mut self, down: NodeId, input: &str, links: Vec<Link>) -> Vec<Link> {
        let i = match self.graph[down].index_of(input) {
            Some(i) => i,
            None if links.is_empty() => return Vec::new(),
            None => self.graph[down].index_or_insert(input),
        };
        self.replace_links(down, i, Links::from_vec(links))
            .into_vec()
    }

    /// Where `node.name` is, given the name's [`name_hash`] (resolution hashes each member
    /// name once per run rather than once per node).
    #[cfg_attr(feature = "testkit", visibility::make(pub))]
    pub(crate) fn slot_of(&self, node: NodeId, name: &str, hash: u64) -> Slot {
        match self.graph[node].index_of_hashed(name, hash) {
            Some(i) => Slot::At(i),
            None => Slot::Missing { hash },
        }
    }

    /// The parameter at position `slot` (from [`Network::slot_of`]).
    pub(crate) fn param_at(&self, node: NodeId, slot: usize) -> &Param {
        &self.graph[node].params[slot]
    }

    /// Make `up.output` the only connection of `down.input`, sharing both names (the fast
    /// path of resolution, which connects hundreds of members per material). `slot` is where
    /// `down.input` is (see [`Network::slot_of`]).
    pub(crate) fn connect_slot(
        &mut self,
        down: NodeId,
        slot: Slot,
        input: Sym,
        up: NodeId,
        output: Sym,
    ) {
        let link = Link::node_sym(up, Some(output));
        let i = match slot {
            Slot::At(i) => i,
            Slot::Missing { .. } => {
                // A new parameter has no links or edges to replace.
                let i = self.graph[down].insert_param(input);
                self.append_link(down, i, link);
                return;
            }
        };
        self.replace_links(down, i, Links::One(link));
    }

    /// [`Network::set_param`] for a member whose position is known (see
    /// `Network::connect_slot`).
    #[cfg_attr(feature = "testkit", visibility::make(pub))]
    pub(crate) fn set_slot(
        &mut self,
        node: NodeId,
        slot: Slot,
        name: Sym,
        value: Value,
    ) -> Option<Value> {
        let i = match slot {
            Slot::At(i) => i,
            Slot::Missing { .. } => self.graph[node].insert_param(name),
        };
        self.set_at(node, i, value)
    }

    /// Set the value of the parameter at position `i`; returns the previous value.
    fn set_at(&mut self, node: NodeId, i: usize, value: Value) -> Option<Value> {
        let n = &mut self.graph[node];
        let p = &mut n.params[i];
        if p.value.as_deref() == Some(&value) {
            return Some(value);
        }
        p.touch_value();
        n.dirty = true;
        p.value.replace(Arc::new(value)).map(Arc::unwrap_or_clone)
    }

    /// Give the parameter `name` of `node`, which is not there yet, the shared `value`
    /// (resolution's fast path for `set` into a new member).
    pub(crate) fn add_shared_value(&mut self, node: NodeId, name: Sym, value: &Arc<Value>) {
        let n = &mut self.graph[node];
        let i = n.insert_param(name);
        let p = &mut n.params[i];
        p.value = Some(value.clone());
        p.touch_value();
        n.dirty = true;
    }

    fn replace_links(&mut self, down: NodeId, i: usize, links: Links) -> Links {
        if self.graph[down].params[i].links == links {
            return links;
        }
        for (e, _) in self.edges_of(down, i) {
            self.graph.remove_edge(e);
        }
        for (index, link) in links.iter().enumerate() {
            self.add_edge_for(down, i, link, index);
        }
        let n = &mut self.graph[down];
        let p = &mut n.params[i];
        p.touch_links();
        n.dirty = true;
        std::mem::replace(&mut p.links, links)
    }

    /// Remove every connection of `down.input`; returns them.
    ///
    /// ```
    /// use vstructc::network::Network;
    /// let mut net = Network::new();
    /// let u = net.add_node("u", "PxrLayer");
    /// let d = net.add_node("d", "PxrLayerMixer");
    /// net.connect(d, "baselayer", u, "pxrMaterialOut");
    /// assert_eq!(net.clear_connections(d, "baselayer").len(), 1);
    /// assert!(net.connections(d, "baselayer").is_empty());
    /// assert_eq!(net.graph().edge_count(), 0);
    /// ```
    pub fn clear_connections(&mut self, down: NodeId, input: &str) -> Vec<Link> {
        self.set_connections(down, input, Vec::new())
    }

    /// Remove the connection at `index` of `down.input`; later connections move up.
    ///
    /// ```
    /// use vstructc::network::Network;
    /// let mut net = Network::new();
    /// let a = net.add_node("a", "X");
    /// let b = net.add_node("b", "X");
    /// let d = net.add_node("d", "Y");
    /// net.connect(d, "in", a, "out");
    /// net.connect(d, "in", b, "out");
    /// net.remove_connection(d, "in", 0);
    /// assert_eq!(net.connections(d, "in")[0].upstream_node(), Some(b));
    /// let e = net.graph().edge_indices().next().unwrap();
    /// assert_eq!(net.graph()[e].index, 0);
    /// ```
    pub fn remove_connection(&mut self, down: NodeId, input: &str, index: usize) -> Option<Link> {
        let i = self.graph[down].index_of(input)?;
        if index >= self.graph[down].params[i].links.len() {
            return None;
        }
        for (e, k) in self.edges_of(down, i) {
            if k == index {
                self.graph.remove_edge(e);
            } else if k > index
                && let Some(w) = self.graph.edge_weight_mut(e)
            {
                w.index = edge_weight(i, k - 1).index;
            }
        }
        let n = &mut self.graph[down];
        let p = &mut n.params[i];
        let link = p.links.remove(index);
        p.touch_links();
        n.dirty = true;
        Some(link)
    }

    /// Remove both the value and the connections of `node.name` (the parameter is then not
    /// written).
    ///
    /// ```
    /// use vstructc::network::Network;
    /// use vstructc::Value;
    /// let mut net = Network::new();
    /// let n = net.add_node("n", "PxrLayerMixer");
    /// net.set_param(n, "baselayer", Value::Float(0.0));
    /// net.remove_param(n, "baselayer");
    /// assert!(net[n].params().next().is_none());
    /// ```
    pub fn remove_param(&mut self, node: NodeId, name: &str) {
        self.remove_value(node, name);
        self.clear_connections(node, name);
    }

    /// Nodes that feed `node` directly: distinct, in parameter order then connection order.
    /// Dangling links are skipped.
    pub fn upstream_nodes(&self, node: NodeId) -> Vec<NodeId> {
        let mut ups: Vec<NodeId> = Vec::new();
        let mut seen = rustc_hash::FxHashSet::default();
        for p in &self.graph[node].params {
            for u in p.links.iter().filter_map(Link::upstream_node) {
                if seen.insert(u) {
                    ups.push(u);
                }
            }
        }
        ups
    }

    /// The transitive upstream closure of `roots` (roots included), in breadth-first order
    /// from the roots, each node once. Dangling links are not followed.
    ///
    /// ```
    /// use vstructc::network::Network;
    /// let mut net = Network::new();
    /// let a = net.add_node("a", "X");
    /// let b = net.add_node("b", "X");
    /// let c = net.add_node("c", "X");
    /// let lone = net.add_node("lone", "X");
    /// net.connect(b, "in", a, "out");
    /// net.connect(c, "in", b, "out");
    /// assert_eq!(net.upstream_closure(&[c]), vec![c, b, a]);
    /// assert!(!net.upstream_closure(&[c]).contains(&lone));
    /// ```
    pub fn upstream_closure(&self, roots: &[NodeId]) -> Vec<NodeId> {
        let mut seen = std::collections::HashSet::new();
        let mut order = Vec::new();
        let mut queue = std::collections::VecDeque::new();
        for &r in roots {
            if self.graph.contains_node(r) && seen.insert(r) {
                queue.push_back(r);
            }
        }
        while let Some(n) = queue.pop_front() {
            order.push(n);
            // Walk inputs in parameter source order so the result is deterministic.
            for p in &self.graph[n].params {
                for link in p.links.iter() {
                    if let Some(u) = link.upstream_node()
                        && seen.insert(u)
                    {
                        queue.push_back(u);
                    }
                }
            }
        }
        order
    }

    /// The materials, in definition order.
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// Mutable access to the materials.
    pub fn materials_mut(&mut self) -> &mut Vec<Material> {
        &mut self.materials
    }

    /// Add a material with no terminals whose nodes are the upstream closure of its
    /// terminals; returns its index.
    ///
    /// ```
    /// use vstructc::network::{Network, RequestKind};
    /// let mut net = Network::new();
    /// let s = net.add_node_of_kind("S", "PxrSurface", RequestKind::Bxdf);
    /// let m = net.add_material("MySG");
    /// net.set_terminal(m, "surface", s, None);
    /// assert_eq!(net.materials()[m].terminals[0].link.upstream_node(), Some(s));
    /// assert_eq!(net.material_nodes(m), vec![s]);
    /// ```
    pub fn add_material(&mut self, name: &str) -> usize {
        self.materials.push(Material {
            name: name.to_string(),
            terminals: Vec::new(),
            nodes: MaterialNodes::UpstreamOfTerminals,
            primvars: Vec::new(),
            location: None,
        });
        self.materials.len() - 1
    }

    /// Set terminal `name` of material `material` to `node` (output `None`: the whole node),
    /// replacing a terminal of the same name.
    pub fn set_terminal(
        &mut self,
        material: usize,
        name: &str,
        node: NodeId,
        output: Option<&str>,
    ) {
        let link = Link::node(node, output);
        let m = &mut self.materials[material];
        match m.terminals.iter_mut().find(|t| t.name == name) {
            Some(t) => t.link = link,
            None => m.terminals.push(Terminal {
                name: name.to_string(),
                link,
            }),
        }
    }

    /// The node set of material `material`: its explicit node list, or the upstream closure of
    /// its terminal nodes.
    pub fn material_nodes(&self, material: usize) -> Vec<NodeId> {
        let m = &self.materials[material];
        match &m.nodes {
            MaterialNodes::Explicit(ids) => ids.clone(),
            MaterialNodes::UpstreamOfTerminals => {
                let roots: Vec<NodeId> = m
                    .terminals
                    .iter()
                    .filter_map(|t| t.link.upstream_node())
                    .collect();
                self.upstream_closure(&roots)
            }
        }
    }

    /// The change state of `node.name` (`Removed` if the node has no such parameter).
    pub fn param_change(&self, node: NodeId, name: &str) -> ParamChange {
        self.graph[node]
            .param(name)
            .map_or(ParamChange::Removed, Param::change)
    }

    /// True if `node` was modified since it was read (see [`Node::is_modified`]).
    pub fn is_modified(&self, node: NodeId) -> bool {
        self.graph[node].is_modified()
    }
}
