//! RenderMan `.args` reader.
//!
//! [`parse_args`] reads one file's bytes into a [`Definition`] whose id is given by the caller
//! (the file stem). Warnings and infos go to `diags`; a condition that rejects the file is
//! returned as `Err` (with code, file, line and column). The XML is tokenised with
//! `quick-xml`; everything above the token level (pages, tags, hints, types, defaults, vstruct
//! metadata, the error policy) is interpreted here. `docs/inputs-and-outputs.md` describes the
//! format as read.
//!
//! Choices where the spec is silent (documented here so users can rely on them):
//!
//! * `<help>` content (node-level and per property) is the raw inner markup with leading and
//!   trailing whitespace trimmed; entities inside it are left as written.
//! * A `<help>` child element wins over a `help` attribute on the same property.
//! * A property outside any `<page>` that has a `page` attribute gets that attribute as its
//!   page path.
//! * `isDynamicArray` true makes the type a dynamic array even when `arraySize` says
//!   otherwise. `arraySize` on `float2`/`float3` cannot be represented and is ignored (AR013).
//! * Empty `default` on an array: a fixed array gets `N` zero elements, a dynamic array the
//!   empty array (what the C conversions of the reference yield); an absent one gives no default.
//! * Other `<hintdict>`/`<hintlist>` children of a property are kept as raw XML in the
//!   property's metadata under `hintdict:NAME` / `hintlist:NAME`, after the attributes.
//! * Warnings gathered before a file is rejected are dropped: only the rejecting error is
//!   returned.
//! * A float default beyond the finite `f32` range (`1e39`, which `atof` makes infinite) is
//!   saturated to the largest finite `f32` of its sign with AR012 (warning): no writer could
//!   write an infinity back where a `copy` puts it.

use crate::diag::{Diagnostic, Diagnostics, Error, Location, Severity};
use crate::model::{
    CondSource, Definition, Direction, MemberDecl, MetaKey, Metadata, Property, SourceKind,
    meta_key,
};
use crate::types::{ArraySpec, BaseType, Type, Value};
use quick_xml::XmlVersion;
use quick_xml::events::{BytesStart, Event};
use quick_xml::reader::Reader;
use rustc_hash::FxHashMap as HashMap;
use std::borrow::Cow;
use std::sync::Arc;

/// Options of the `.args` reader.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ArgsOptions {
    /// Extension `args-child-meta`: accept `<string name="vstructmember"
    /// value="…"/>` (and the two other vstruct keys) as child elements of a property.
    pub child_meta: bool,
}

/// Parse an `.args` document with the default options.
pub fn parse_args(
    bytes: &[u8],
    path: &str,
    id: &str,
    diags: &mut Diagnostics,
) -> Result<Definition, Error> {
    parse_args_with(bytes, path, id, &ArgsOptions::default(), diags)
}

/// Parse an `.args` document with explicit options.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) fn parse_args_with(
    bytes: &[u8],
    path: &str,
    id: &str,
    options: &ArgsOptions,
    diags: &mut Diagnostics,
) -> Result<Definition, Error> {
    let file: Arc<str> = Arc::from(path);
    let text = decode_utf8(bytes, &file)?;
    reject_nul(text, &file)?;
    let mut parser = ArgsParser::new(text, file, id, options);
    parser.parse_document()?;
    parser.finish(diags)
}

/// NUL is not a legal XML character anywhere (XML 1.0 `Char`); quick-xml passes it through,
/// so it is rejected here (AR001 at the NUL).
fn reject_nul(text: &str, file: &Arc<str>) -> Result<(), Error> {
    let Some(offset) = memchr::memchr(0, text.as_bytes()) else {
        return Ok(());
    };
    let (line, column) = crate::diag::line_column(&text[..offset], offset);
    Err(Error::from(
        Diagnostic::error("AR001", "not well-formed XML: NUL character").at(Location::new(
            file.clone(),
            line,
            column,
        )),
    ))
}

/// Checks the bytes are UTF-8 (AR005 with the position of the first bad byte otherwise) and
/// strips a UTF-8 byte-order mark.
fn decode_utf8<'a>(bytes: &'a [u8], file: &Arc<str>) -> Result<&'a str, Error> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    std::str::from_utf8(bytes).map_err(|e| {
        let valid = e.valid_up_to();
        let prefix = std::str::from_utf8(&bytes[..valid]).unwrap_or("");
        let (line, column) = crate::diag::line_column(prefix, valid);
        Error::from(
            Diagnostic::error(
                "AR005",
                format!(
                    "invalid UTF-8 (byte 0x{:02X} at offset {valid})",
                    bytes[valid]
                ),
            )
            .at(Location::new(file.clone(), line, column)),
        )
    })
}

/// How many times `needle` occurs in `text`.
fn count_occurrences(text: &str, needle: &str) -> usize {
    memchr::memmem::find_iter(text.as_bytes(), needle.as_bytes()).count()
}

/// Reads the attributes of a start tag in the common plain form — `name="value"` separated by
/// whitespace, values with no entity or whitespace to normalise, no duplicate — borrowing
/// key and value from the file. Returns false at the first thing outside that form (the
/// caller then clears `out` and lets quick-xml read the tag, with its error reporting).
/// `base` is the byte offset of `raw` in the file.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn plain_attributes<'a>(raw: &'a str, base: usize, out: &mut Vec<Attr<'a>>) -> bool {
    let bytes = raw.as_bytes();
    let mut i = 0;
    loop {
        let gap = i;
        while i < bytes.len() && bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        if i == bytes.len() {
            return true;
        }
        if i == gap {
            return false; // whitespace precedes every attribute (after the element name, too)
        }
        let key_start = i;
        while i < bytes.len() && is_plain_name_byte(bytes[i]) {
            i += 1;
        }
        let starts_name = bytes[key_start].is_ascii_alphabetic() || bytes[key_start] == b'_';
        if i == key_start || !starts_name || bytes.get(i) != Some(&b'=') {
            return false;
        }
        let Some(&quote) = bytes.get(i + 1).filter(|q| matches!(q, b'"' | b'\'')) else {
            return false;
        };
        let value_start = i + 2;
        let Some(len) = memchr::memchr(quote, &bytes[value_start..]) else {
            return false;
        };
        let key = &raw[key_start..i];
        let value = &raw[value_start..value_start + len];
        if needs_normalisation(value) || out.iter().any(|a| a.key == key) {
            return false;
        }
        out.push(Attr {
            key: Cow::Borrowed(key),
            value: Cow::Borrowed(value),
            offset: base + value_start,
        });
        i = value_start + len + 1;
    }
}

/// ASCII bytes of an XML name (the fast path leaves anything else to quick-xml).
fn is_plain_name_byte(b: u8) -> bool {
    b.is_ascii_alphanumeric() || matches!(b, b'_' | b':' | b'-' | b'.')
}

/// True if an attribute value holds an entity or a character that XML attribute-value
/// normalisation replaces (tab, line feed, carriage return).
fn needs_normalisation(value: &str) -> bool {
    value.bytes().fold(false, |any, b| {
        any | matches!(b, b'&' | b'\t' | b'\n' | b'\r')
    })
}

/// Byte offsets of line starts, for fast offset → line:column mapping.
struct LineIndex {
    starts: Vec<usize>,
    /// `blocks[k]`: the characters before byte `k * COLUMN_BLOCK`. Built the first time a
    /// column lies more than one block into its line, so that a file written on one line
    /// (generated `.args` often are) costs a bounded count per position, not a count from
    /// the line's start.
    blocks: std::cell::OnceCell<Vec<usize>>,
}

/// Bytes per entry of [`LineIndex::blocks`].
const COLUMN_BLOCK: usize = 1024;

/// The characters that start in `bytes` (every byte but UTF-8 continuation bytes).
fn char_starts(bytes: &[u8]) -> usize {
    bytes.iter().filter(|&&b| (b as i8) >= -0x40).count()
}

impl LineIndex {
    fn new(text: &str) -> Self {
        let mut starts = vec![0];
        starts.extend(memchr::memchr_iter(b'\n', text.as_bytes()).map(|i| i + 1));
        LineIndex {
            starts,
            blocks: std::cell::OnceCell::new(),
        }
    }

    /// 1-based (line, column) of `offset`; columns count characters.
    fn line_column(&self, text: &str, offset: usize) -> (u32, u32) {
        let mut offset = offset.min(text.len());
        while !text.is_char_boundary(offset) {
            offset -= 1;
        }
        let line = self.starts.partition_point(|&s| s <= offset);
        let start = self.starts[line - 1];
        let column = if offset - start <= COLUMN_BLOCK {
            text[start..offset].chars().count()
        } else {
            self.chars_before(text, offset) - self.chars_before(text, start)
        };
        (line as u32, column as u32 + 1)
    }

    /// The characters before the byte `offset` (a character boundary) of `text`.
    fn chars_before(&self, text: &str, offset: usize) -> usize {
        let bytes = text.as_bytes();
        let blocks = self.blocks.get_or_init(|| {
            let mut before = 0;
            let mut blocks = Vec::with_capacity(bytes.len() / COLUMN_BLOCK + 1);
            for chunk in bytes.chunks(COLUMN_BLOCK) {
                blocks.push(before);
                before += char_starts(chunk);
            }
            blocks.push(before);
            blocks
        });
        let block = offset / COLUMN_BLOCK;
        blocks[block] + char_starts(&bytes[block * COLUMN_BLOCK..offset])
    }
}

/// One attribute of a start tag: key, decoded value, byte offset of the raw value in the file.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
struct Attr<'a> {
    /// The attribute's name.
    pub key: Cow<'a, str>,
    /// Its value, entities decoded.
    pub value: Cow<'a, str>,
    /// The byte offset of the raw value in the file.
    pub offset: usize,
}

/// Finds an attribute by key.
fn attr<'b, 'a>(attrs: &'b [Attr<'a>], key: &str) -> Option<&'b Attr<'a>> {
    attrs.iter().find(|a| a.key == key)
}

/// A child metadata element accepted by the `args-child-meta` extension.
struct ChildMeta {
    key: String,
    value: String,
    offset: usize,
}

/// Everything read from a property's child elements.
#[derive(Default)]
struct PropertyChildren {
    help: Option<String>,
    tags: Vec<String>,
    options: Vec<(String, String)>,
    raw_hints: Vec<(MetaKey, String)>,
    child_meta: Vec<ChildMeta>,
}

/// Shader kinds the spec lists as known.
/// Largest fixed `arraySize` accepted (robustness limit; the reference has none). A larger
/// size would make the zero-padded default allocate gigabytes, so it is reported (AR013) and
/// the property becomes a dynamic array, keeping whatever default values were written.
pub(crate) const MAX_FIXED_ARRAY: usize = 1 << 20;

/// Deepest `<page>` nesting accepted (robustness limit; real files use 1–3 levels). Deeper
/// nesting is rejected with AR001, so recursion and page-path building stay bounded.
pub(crate) const MAX_PAGE_DEPTH: usize = 64;

const KNOWN_KINDS: &[&str] = &[
    "bxdf",
    "pattern",
    "light",
    "lightfilter",
    "displacement",
    "displayfilter",
    "samplefilter",
    "integrator",
    "projection",
    "displaydriver",
];

/// Node-level elements stored verbatim in node metadata.
const RAW_NODE_ELEMENTS: &[&str] = &[
    "primvars",
    "departments",
    "rfmdata",
    "rfcdata",
    "rfhdata",
    "info",
    "usdSchemaDef",
    "sdrGlobalConfig",
    "attribute",
];

/// The three vstruct metadata keys.
const VSTRUCT_KEYS: &[&str] = &[
    "vstructmember",
    "vstructConditionalExpr",
    "vstructmemberaliases",
];

struct ArgsParser<'a> {
    text: &'a str,
    file: Arc<str>,
    lines: LineIndex,
    reader: Reader<&'a [u8]>,
    options: ArgsOptions,
    def: Definition,
    diags: Vec<Diagnostic>,
    pages: Vec<String>,
    /// `pages` joined with `:` (cached; `None` outside pages).
    page_path: Option<String>,
    kind: Option<String>,
    uses_sdr_definition_name: bool,
    /// Spare attribute vectors (see [`Self::attributes`]).
    attr_pool: Vec<Vec<Attr<'a>>>,
    /// Input names seen so far → index in `def.inputs` (names borrow from the file text
    /// unless entity decoding produced a new string).
    input_names: HashMap<Cow<'a, str>, usize>,
    /// Output names seen so far → index in `def.outputs`.
    output_names: HashMap<Cow<'a, str>, usize>,
}

type PResult<T> = Result<T, Error>;

impl<'a> ArgsParser<'a> {
    fn new(text: &'a str, file: Arc<str>, id: &str, options: &ArgsOptions) -> Self {
        let mut reader = Reader::from_str(text);
        let config = reader.config_mut();
        config.check_end_names = true;
        config.check_comments = true;
        config.expand_empty_elements = false;
        ArgsParser {
            text,
            lines: LineIndex::new(text),
            reader,
            options: *options,
            def: Definition {
                id: id.to_string(),
                kind: "unknown".to_string(),
                source: SourceKind::Args,
                path: file.clone(),
                // An upper bound of the property counts (a `<param` inside a comment also
                // counts), so that the property vectors never regrow.
                inputs: Vec::with_capacity(count_occurrences(text, "<param")),
                outputs: Vec::with_capacity(count_occurrences(text, "<output")),
                metadata: Metadata::new(),
            },
            file,
            diags: Vec::new(),
            pages: Vec::new(),
            page_path: None,
            kind: None,
            uses_sdr_definition_name: false,
            attr_pool: Vec::new(),
            input_names: HashMap::default(),
            output_names: HashMap::default(),
        }
    }

    fn finish(self, diags: &mut Diagnostics) -> PResult<Definition> {
        diags.extend(self.diags);
        Ok(self.def)
    }

    // ---- positions and diagnostics -------------------------------------------------------

    fn loc(&self, offset: usize) -> Location {
        let (line, column) = self.lines.line_column(self.text, offset);
        Location::new(self.file.clone(), line, column)
    }

    /// The same text as `slice`, with the file's lifetime, if `slice` borrows from the file.
    fn reborrow(&self, slice: &str) -> Option<&'a str> {
        let start = self.offset_of(slice)?;
        self.text.get(start..start + slice.len())
    }

    /// Byte offset of `slice` inside the file text, if it borrows from it.
    fn offset_of(&self, slice: &str) -> Option<usize> {
        let base = self.text.as_ptr() as usize;
        let p = slice.as_ptr() as usize;
        (p >= base && p + slice.len() <= base + self.text.len()).then(|| p - base)
    }

    fn report(&mut self, severity: Severity, code: &'static str, msg: String, offset: usize) {
        let d = Diagnostic::new(severity, code, msg).at(self.loc(offset));
        self.diags.push(d);
    }

    fn reject(&self, code: &'static str, msg: impl Into<String>, offset: usize) -> Error {
        Diagnostic::error(code, msg).at(self.loc(offset)).into()
    }

    fn xml_error(&self, e: quick_xml::Error) -> Error {
        let offset = self.reader.error_position() as usize;
        self.reject("AR001", format!("not well-formed XML: {e}"), offset)
    }

    // ---- event access --------------------------------------------------------------------

    /// The next event and the byte offset where it starts.
    fn next(&mut self) -> PResult<(usize, Event<'a>)> {
        let start = self.reader.buffer_position() as usize;
        match self.reader.read_event() {
            Ok(ev) => Ok((start, ev)),
            Err(e) => Err(self.xml_error(e)),
        }
    }

    /// Skips to the end of an element whose start tag was just read; returns the offset just
    /// after its end tag.
    fn skip_element(&mut self, e: &BytesStart<'_>) -> PResult<usize> {
        match self.reader.read_to_end(e.name()) {
            Ok(_) => Ok(self.reader.buffer_position() as usize),
            Err(err) => Err(self.xml_error(err)),
        }
    }

    /// Raw inner content of an element whose start tag was just read (or empty if
    /// self-closed).
    fn inner_raw(&mut self, e: &BytesStart<'_>, empty: bool) -> PResult<&'a str> {
        if empty {
            return Ok("");
        }
        match self.reader.read_to_end(e.name()) {
            Ok(span) => Ok(self
                .text
                .get(span.start as usize..span.end as usize)
                .unwrap_or("")),
            Err(err) => Err(self.xml_error(err)),
        }
    }

    /// Raw text of a whole element starting at `start` (start tag included).
    fn element_raw(&mut self, start: usize, e: &BytesStart<'_>, empty: bool) -> PResult<&'a str> {
        let end = if empty {
            self.reader.buffer_position() as usize
        } else {
            self.skip_element(e)?
        };
        Ok(self.text.get(start..end).unwrap_or(""))
    }

    /// Decoded attributes of a start tag at `start`, in document order. The vector comes from
    /// a small pool; give it back with [`Self::recycle`] on hot paths.
    fn attributes(&mut self, start: usize, e: &BytesStart<'_>) -> PResult<Vec<Attr<'a>>> {
        let mut out = self.attr_pool.pop().unwrap_or_default();
        if let Some(raw) = self.reborrow(e.attributes_raw())
            && let Some(base) = self.offset_of(raw)
            && plain_attributes(raw, base, &mut out)
        {
            return Ok(out);
        }
        out.clear();
        // quick-xml's own duplicate check allocates per element; ours scans the few
        // attributes already read.
        for a in e.attributes().with_checks(false) {
            let a = a.map_err(|err| {
                let rel = attr_error_position(&err);
                self.reject(
                    "AR001",
                    format!("not well-formed XML: bad attribute: {err}"),
                    start + 1 + rel,
                )
            })?;
            let key_offset = self.offset_of(a.key.as_ref()).unwrap_or(start);
            if out.iter().any(|prev: &Attr<'a>| prev.key == a.key.as_ref()) {
                return Err(self.reject(
                    "AR001",
                    format!(
                        "not well-formed XML: duplicate attribute `{}`",
                        a.key.as_ref()
                    ),
                    key_offset,
                ));
            }
            let offset = self.offset_of(&a.value).unwrap_or(start);
            // Most values need neither entity decoding nor whitespace normalisation; one
            // vectorisable scan skips quick-xml's byte-by-byte normalisation for them.
            let value = if needs_normalisation(&a.value) {
                a.normalized_value(XmlVersion::Implicit1_0)
            } else {
                Ok(a.value.clone())
            };
            let value = value.map_err(|err| {
                let at = offset + escape_error_position(&err);
                self.reject(
                    "AR001",
                    format!("not well-formed XML: {}", escape_message(&err)),
                    at,
                )
            })?;
            // Borrow key and value from the file text when they are slices of it (always,
            // for keys; for values that needed no normalisation), to avoid allocations.
            let key = self
                .reborrow(a.key.as_ref())
                .map_or_else(|| Cow::Owned(a.key.as_ref().to_string()), Cow::Borrowed);
            let value = match value {
                Cow::Borrowed(v) => self
                    .reborrow(v)
                    .map_or_else(|| Cow::Owned(v.to_string()), Cow::Borrowed),
                Cow::Owned(v) => Cow::Owned(v),
            };
            out.push(Attr { key, value, offset });
        }
        Ok(out)
    }

    /// Returns an attribute vector to the pool.
    fn recycle(&mut self, mut attrs: Vec<Attr<'a>>) {
        attrs.clear();
        self.attr_pool.push(attrs);
    }

    // ---- document ------------------------------------------------------------------------

    fn parse_document(&mut self) -> PResult<()> {
        let mut root_seen = false;
        loop {
            let (pos, ev) = self.next()?;
            match ev {
                Event::Decl(d) => self.check_declaration(pos, &d)?,
                Event::Start(e) | Event::Empty(e) if root_seen => {
                    let name = e.name().as_ref().to_string();
                    return Err(self.reject(
                        "AR001",
                        format!("not well-formed XML: element <{name}> after the root element"),
                        pos,
                    ));
                }
                Event::Start(e) => {
                    self.parse_root(pos, &e, false)?;
                    root_seen = true;
                }
                Event::Empty(e) => {
                    self.parse_root(pos, &e, true)?;
                    root_seen = true;
                }
                Event::Text(t) => {
                    if !t.as_ref().trim().is_empty() {
                        let what = if root_seen { "after" } else { "before" };
                        return Err(self.reject(
                            "AR001",
                            format!("not well-formed XML: text {what} the root element"),
                            pos,
                        ));
                    }
                }
                Event::CData(_) | Event::GeneralRef(_) => {
                    return Err(self.reject(
                        "AR001",
                        "not well-formed XML: character data outside the root element",
                        pos,
                    ));
                }
                Event::End(e) => {
                    let name = e.name().as_ref().to_string();
                    return Err(self.reject(
                        "AR001",
                        format!("not well-formed XML: unmatched end tag </{name}>"),
                        pos,
                    ));
                }
                Event::Comment(_) | Event::PI(_) | Event::DocType(_) => {}
                Event::Eof => break,
            }
        }
        if !root_seen {
            return Err(self.reject(
                "AR001",
                "not well-formed XML: no root element",
                self.text.len(),
            ));
        }
        if self.kind.is_none() {
            self.def.kind = "unknown".into();
        }
        Ok(())
    }

    /// AR005 for an XML declaration naming an encoding other than UTF-8 / ASCII.
    fn check_declaration(
        &mut self,
        pos: usize,
        d: &quick_xml::events::BytesDecl<'_>,
    ) -> PResult<()> {
        if let Some(Ok(enc)) = d.encoding() {
            let lower = enc.to_ascii_lowercase();
            let ok = matches!(
                lower.as_str(),
                "utf-8" | "utf8" | "us-ascii" | "ascii" | "iso-646-us"
            );
            if !ok {
                let offset = self.offset_of(&enc).unwrap_or(pos);
                return Err(self.reject(
                    "AR005",
                    format!("unsupported encoding `{enc}` (only UTF-8 and ASCII are read)"),
                    offset,
                ));
            }
        }
        Ok(())
    }

    fn parse_root(&mut self, pos: usize, e: &BytesStart<'a>, empty: bool) -> PResult<()> {
        let name = e.name().as_ref().to_string();
        if name != "args" {
            return Err(self.reject(
                "AR002",
                format!("root element is <{name}>, expected <args>"),
                pos,
            ));
        }
        let attrs = self.attributes(pos, e)?;
        match attr(&attrs, "format") {
            None => self.report(
                Severity::Warning,
                "AR014",
                "<args> has no `format` attribute (expected \"1.0\")".into(),
                pos,
            ),
            Some(a) if a.value.trim() != "1.0" => {
                let msg = format!(
                    "<args format=\"{}\"> is not format 1.0; read anyway",
                    a.value
                );
                let off = a.offset;
                self.report(Severity::Warning, "AR014", msg, off);
            }
            Some(_) => {}
        }
        if !empty {
            self.parse_container(false, pos)?;
        }
        if self.kind.is_none() {
            self.report(
                Severity::Warning,
                "AR010",
                "no <shaderType>: the shader kind is `unknown`".into(),
                pos,
            );
        }
        Ok(())
    }

    /// Body of `<args>` (`in_page == false`) or of a `<page>`: loops until the matching end
    /// tag.
    fn parse_container(&mut self, in_page: bool, start: usize) -> PResult<()> {
        loop {
            let (pos, ev) = self.next()?;
            match ev {
                Event::Start(e) => self.body_element(pos, &e, false, in_page)?,
                Event::Empty(e) => self.body_element(pos, &e, true, in_page)?,
                Event::End(_) => return Ok(()),
                Event::Eof => {
                    let element = if in_page { "page" } else { "args" };
                    return Err(self.unexpected_eof(element, start));
                }
                _ => {}
            }
        }
    }

    /// AR001 at the end of the file, naming the innermost element left open.
    fn unexpected_eof(&self, element: &str, start: usize) -> Error {
        Diagnostic::error(
            "AR001",
            format!("not well-formed XML: unexpected end of file: <{element}> is not closed"),
        )
        .at(self.loc(self.text.len()))
        .with_related(format!("<{element}> opened here"), self.loc(start))
        .into()
    }

    fn body_element(
        &mut self,
        pos: usize,
        e: &BytesStart<'a>,
        empty: bool,
        in_page: bool,
    ) -> PResult<()> {
        let name = e.name().0;
        match name {
            "param" => self.parse_property(pos, e, empty, Direction::In),
            "output" => self.parse_property(pos, e, empty, Direction::Out),
            "page" => self.parse_page(pos, e, empty),
            "help" if !in_page => {
                let raw = self.inner_raw(e, empty)?;
                self.def.metadata.push("help", raw.trim());
                Ok(())
            }
            "help" => self.inner_raw(e, empty).map(|_| ()),
            "shaderType" | "typeTag" if !in_page => self.parse_shader_type(pos, e, empty, name),
            "sdrGlobalConfig" if self.uses_sdr_definition_name => {
                self.report(
                    Severity::Warning,
                    "AR015",
                    "<sdrGlobalConfig> after a property that uses sdrDefinitionName is ignored"
                        .into(),
                    pos,
                );
                self.element_raw(pos, e, empty).map(|_| ())
            }
            n if RAW_NODE_ELEMENTS.contains(&n) => {
                let raw = self.element_raw(pos, e, empty)?;
                self.def.metadata.push(meta_key(name), raw);
                Ok(())
            }
            _ => {
                let where_ = if in_page { "<page>" } else { "<args>" };
                self.report(
                    Severity::Info,
                    "AR021",
                    format!("unknown element <{name}> in {where_} ignored"),
                    pos,
                );
                self.element_raw(pos, e, empty).map(|_| ())
            }
        }
    }

    fn parse_page(&mut self, pos: usize, e: &BytesStart<'a>, empty: bool) -> PResult<()> {
        let attrs = self.attributes(pos, e)?;
        let name = attr(&attrs, "name")
            .map(|a| a.value.to_string())
            .unwrap_or_default();
        if empty {
            return Ok(());
        }
        if self.pages.len() >= MAX_PAGE_DEPTH {
            return Err(self.reject(
                "AR001",
                format!("<page> nesting deeper than {MAX_PAGE_DEPTH} levels (vstructc limit)"),
                pos,
            ));
        }
        self.pages.push(name);
        let saved = self.page_path.replace(self.pages.join(":"));
        let r = self.parse_container(true, pos);
        self.pages.pop();
        self.page_path = saved;
        r
    }

    fn parse_shader_type(
        &mut self,
        pos: usize,
        e: &BytesStart<'a>,
        empty: bool,
        element: &str,
    ) -> PResult<()> {
        if element == "typeTag" {
            self.report(
                Severity::Info,
                "AR020",
                "deprecated <typeTag>: read as <shaderType>".into(),
                pos,
            );
        }
        let attrs = self.attributes(pos, e)?;
        let mut found = attr(&attrs, "name").map(|a| (a.value.to_string(), a.offset));
        if !empty {
            loop {
                let (cpos, ev) = self.next()?;
                let (c, c_empty) = match ev {
                    Event::Start(c) => (c, false),
                    Event::Empty(c) => (c, true),
                    Event::End(_) => break,
                    Event::Eof => return Err(self.unexpected_eof(element, pos)),
                    _ => continue,
                };
                let cname = c.name().0;
                let cattrs = self.attributes(cpos, &c)?;
                if cname == "tag" {
                    if found.is_none() {
                        found = attr(&cattrs, "value").map(|a| (a.value.to_string(), a.offset));
                    }
                } else {
                    self.report(
                        Severity::Info,
                        "AR021",
                        format!("unknown element <{cname}> in <{element}> ignored"),
                        cpos,
                    );
                }
                if !c_empty {
                    self.skip_element(&c)?;
                }
            }
        }
        if let Some((k, off)) = found {
            self.set_kind(k.trim(), off);
        }
        Ok(())
    }

    fn set_kind(&mut self, k: &str, offset: usize) {
        if !KNOWN_KINDS.contains(&k) {
            self.report(
                Severity::Info,
                "AR010",
                format!("shader type `{k}` is not a known kind; kept as is"),
                offset,
            );
        }
        let kind = match k {
            "lightfilter" => "lightFilter",
            "samplefilter" => "sampleFilter",
            "pixelfilter" => "pixelFilter",
            other => other,
        };
        self.def.kind = kind.to_string();
        self.kind = Some(kind.to_string());
    }

    // ---- properties ----------------------------------------------------------------------

    fn parse_property(
        &mut self,
        pos: usize,
        e: &BytesStart<'a>,
        empty: bool,
        direction: Direction,
    ) -> PResult<()> {
        let element = if direction == Direction::In {
            "param"
        } else {
            "output"
        };
        let attrs = self.attributes(pos, e)?;
        let PropertyChildren {
            help,
            tags,
            options,
            raw_hints,
            child_meta,
        } = if empty {
            PropertyChildren::default()
        } else {
            self.parse_property_children(element, pos)?
        };
        let Some(name_attr) = attr(&attrs, "name") else {
            return Err(self.reject(
                "AR003",
                format!("<{element}> without a `name` attribute"),
                pos,
            ));
        };
        let name = name_attr.value.clone();
        self.check_duplicate(name.clone(), direction, pos)?;

        // The type (and `declared_type`) is set from the attributes by `resolve_type` below.
        let mut prop = Property::new(
            name.into_owned(),
            direction,
            Type::scalar(BaseType::Unknown(String::new())),
            self.loc(pos),
        );
        prop.page = match &self.page_path {
            Some(p) => Some(p.clone()),
            None => attr(&attrs, "page").map(|a| a.value.to_string()),
        };
        prop.label = attr(&attrs, "label").map(|a| a.value.to_string());
        prop.widget = attr(&attrs, "widget").map(|a| a.value.to_string());
        prop.help = help.or_else(|| attr(&attrs, "help").map(|a| a.value.to_string()));
        if attr(&attrs, "sdrDefinitionName").is_some() {
            self.uses_sdr_definition_name = true;
        }
        if let Some(a) = attr(&attrs, "input") {
            let off = a.offset;
            self.report(
                Severity::Info,
                "AR020",
                "deprecated `input` attribute".into(),
                off,
            );
        }

        // Connection types: the deprecated `tag` attribute, then `<tags>` children.
        if let Some(a) = attr(&attrs, "tag") {
            let off = a.offset;
            prop.connection_types.push(a.value.to_string());
            self.report(
                Severity::Info,
                "AR020",
                "deprecated `tag` attribute: use <tags><tag value=…/></tags>".into(),
                off,
            );
        }
        prop.connection_types.extend(tags);

        // Options: the attribute, then hint children, in document order.
        if let Some(a) = attr(&attrs, "options") {
            prop.options.extend(parse_options_attr(&a.value));
        }
        prop.options.extend(options);

        self.resolve_type(&mut prop, &attrs, direction, pos);
        if direction == Direction::In {
            self.resolve_flags(&mut prop, &attrs);
            prop.default = self.resolve_default(&prop.ty, attr(&attrs, "default"), pos);
        } else {
            prop.connectable = true;
        }

        self.resolve_vstruct(&mut prop, &attrs, &child_meta);
        // Metadata: every attribute in document order, then raw hints, then child metadata
        // (extension) that `resolve_vstruct` accepted.
        let accepted_child_meta = std::mem::take(&mut prop.metadata);
        let entries = attrs.len() + raw_hints.len() + accepted_child_meta.len();
        let bytes: usize = attrs.iter().map(|a| a.value.len()).sum::<usize>()
            + raw_hints.iter().map(|(_, v)| v.len()).sum::<usize>()
            + accepted_child_meta
                .iter()
                .map(|(_, v)| v.len())
                .sum::<usize>();
        let mut metadata = Metadata::with_capacity(entries, bytes);
        for a in &attrs {
            metadata.push(meta_key(&a.key), &a.value);
        }
        for (k, v) in raw_hints {
            metadata.push(k, &v);
        }
        metadata.extend_from(&accepted_child_meta);
        prop.metadata = metadata;
        self.recycle(attrs);

        match direction {
            Direction::In => self.def.inputs.push(prop),
            Direction::Out => self.def.outputs.push(prop),
        }
        Ok(())
    }

    /// AR004 if a property of the same direction was declared before; otherwise records it
    /// (at the index it is about to take).
    fn check_duplicate(
        &mut self,
        name: Cow<'a, str>,
        direction: Direction,
        pos: usize,
    ) -> PResult<()> {
        let (seen, declared) = match direction {
            Direction::In => (&mut self.input_names, &self.def.inputs),
            Direction::Out => (&mut self.output_names, &self.def.outputs),
        };
        if let Some(&first) = seen.get(name.as_ref()) {
            let what = if direction == Direction::In {
                "parameter"
            } else {
                "output"
            };
            let first = declared[first].location.clone();
            return Err(
                Diagnostic::error("AR004", format!("duplicate {what} `{name}`"))
                    .at(self.loc(pos))
                    .with_related("first declared here", first)
                    .into(),
            );
        }
        seen.insert(name, declared.len());
        Ok(())
    }

    fn parse_property_children(
        &mut self,
        element: &str,
        start: usize,
    ) -> PResult<PropertyChildren> {
        let mut out = PropertyChildren::default();
        loop {
            let (pos, ev) = self.next()?;
            let (c, empty) = match ev {
                Event::Start(c) => (c, false),
                Event::Empty(c) => (c, true),
                Event::End(_) => return Ok(out),
                Event::Eof => return Err(self.unexpected_eof(element, start)),
                _ => continue,
            };
            let cname = c.name().0;
            match cname {
                "help" => {
                    let raw = self.inner_raw(&c, empty)?;
                    out.help = Some(raw.trim().to_string());
                }
                "tags" => {
                    if !empty {
                        self.parse_tags(&mut out.tags, pos)?;
                    }
                }
                "hintdict" | "hintlist" => self.parse_hint(pos, &c, empty, cname, &mut out)?,
                "string" if self.options.child_meta => {
                    let attrs = self.attributes(pos, &c)?;
                    let key = attr(&attrs, "name")
                        .map(|a| a.value.to_string())
                        .unwrap_or_default();
                    if VSTRUCT_KEYS.contains(&key.as_str())
                        && let Some(v) = attr(&attrs, "value")
                    {
                        out.child_meta.push(ChildMeta {
                            key,
                            value: v.value.to_string(),
                            offset: v.offset,
                        });
                    } else {
                        self.report(
                            Severity::Info,
                            "AR021",
                            format!(
                                "unknown element <string name=\"{key}\"> in <{element}> ignored"
                            ),
                            pos,
                        );
                    }
                    if !empty {
                        self.skip_element(&c)?;
                    }
                }
                _ => {
                    self.report(
                        Severity::Info,
                        "AR021",
                        format!("unknown element <{cname}> in <{element}> ignored"),
                        pos,
                    );
                    if !empty {
                        self.skip_element(&c)?;
                    }
                }
            }
        }
    }

    fn parse_tags(&mut self, tags: &mut Vec<String>, start: usize) -> PResult<()> {
        loop {
            let (pos, ev) = self.next()?;
            let (c, empty) = match ev {
                Event::Start(c) => (c, false),
                Event::Empty(c) => (c, true),
                Event::End(_) => return Ok(()),
                Event::Eof => return Err(self.unexpected_eof("tags", start)),
                _ => continue,
            };
            let cname = c.name().0;
            if cname == "tag" {
                let attrs = self.attributes(pos, &c)?;
                if let Some(v) = attr(&attrs, "value") {
                    tags.push(v.value.to_string());
                }
                self.recycle(attrs);
            } else {
                self.report(
                    Severity::Info,
                    "AR021",
                    format!("unknown element <{cname}> in <tags> ignored"),
                    pos,
                );
            }
            if !empty {
                self.skip_element(&c)?;
            }
        }
    }

    /// `<hintdict>` / `<hintlist>`: `options` is interpreted, others kept raw.
    fn parse_hint(
        &mut self,
        pos: usize,
        c: &BytesStart<'a>,
        empty: bool,
        element: &str,
        out: &mut PropertyChildren,
    ) -> PResult<()> {
        let attrs = self.attributes(pos, c)?;
        let name = attr(&attrs, "name")
            .map(|a| a.value.to_string())
            .unwrap_or_default();
        if name != "options" {
            let raw = self.element_raw(pos, c, empty)?;
            out.raw_hints
                .push((format!("{element}:{name}").into(), raw.to_string()));
            return Ok(());
        }
        if empty {
            return Ok(());
        }
        loop {
            let (cpos, ev) = self.next()?;
            let (item, item_empty) = match ev {
                Event::Start(i) => (i, false),
                Event::Empty(i) => (i, true),
                Event::End(_) => return Ok(()),
                Event::Eof => return Err(self.unexpected_eof(element, pos)),
                _ => continue,
            };
            let iattrs = self.attributes(cpos, &item)?;
            let value = attr(&iattrs, "value").map(|a| a.value.to_string());
            let label = attr(&iattrs, "name").map(|a| a.value.to_string());
            match (element, label, value) {
                ("hintdict", Some(l), Some(v)) => out.options.push((l, v)),
                ("hintlist", _, Some(v)) => out.options.push((v.clone(), v)),
                _ => {}
            }
            if !item_empty {
                self.skip_element(&item)?;
            }
        }
    }

    // ---- interpretation of attributes ----------------------------------------------------

    /// The property's type, from its `type` attribute or tag.
    fn resolve_type(
        &mut self,
        prop: &mut Property,
        attrs: &[Attr<'_>],
        direction: Direction,
        pos: usize,
    ) {
        let type_attr = attr(attrs, "type");
        if direction == Direction::Out
            && let Some(a) = type_attr
        {
            let off = a.offset;
            self.report(
                Severity::Info,
                "AR020",
                "deprecated `type` attribute on <output>: the first tag gives the type".into(),
                off,
            );
        }
        let (word, offset) = match type_attr {
            Some(a) => (Some(a.value.to_string()), a.offset),
            None => (prop.connection_types.first().cloned(), pos),
        };
        let mut ty = match &word {
            Some(w) => match args_type(w.trim()) {
                Some(t) => t,
                None => {
                    self.report(
                        Severity::Warning,
                        "AR011",
                        format!("unknown type `{w}` on `{}`", prop.name),
                        offset,
                    );
                    Type::scalar(BaseType::Unknown(w.clone()))
                }
            },
            None => {
                self.report(
                    Severity::Warning,
                    "AR011",
                    format!(
                        "`{}` has no type (no `type` attribute and no tag)",
                        prop.name
                    ),
                    pos,
                );
                Type::scalar(BaseType::Unknown(String::new()))
            }
        };
        prop.declared_type = word.unwrap_or_default();

        if let Some(rt) = attr(attrs, "renderType")
            && let Some(rest) = rt.value.trim().strip_prefix("terminal")
        {
            let kind = rest.trim();
            let kind = if kind.is_empty() {
                ty.base.word().to_string()
            } else {
                kind.to_string()
            };
            ty = Type {
                base: BaseType::Terminal(kind),
                array: ty.array,
            };
        }

        if direction == Direction::In {
            ty.array = self.resolve_array(&ty, attrs);
        }
        prop.ty = ty;
    }

    /// Array shape from `arraySize` / `isDynamicArray`.
    fn resolve_array(&mut self, ty: &Type, attrs: &[Attr<'_>]) -> ArraySpec {
        let dynamic = attr(attrs, "isDynamicArray").is_some_and(|a| args_bool(&a.value, true));
        let mut shape = ty.array;
        if let Some(a) = attr(attrs, "arraySize") {
            let off = a.offset;
            let parsed = a.value.trim().parse::<i64>();
            let spec = match parsed {
                Ok(n) if n > MAX_FIXED_ARRAY as i64 => {
                    self.report(
                        Severity::Warning,
                        "AR013",
                        format!("arraySize {n} exceeds the limit of {MAX_FIXED_ARRAY} elements; treated as a dynamic array"),
                        off,
                    );
                    Some(ArraySpec::Dynamic)
                }
                Ok(n) if n > 0 => Some(ArraySpec::Fixed(n as usize)),
                Ok(-1) => Some(ArraySpec::Dynamic),
                Ok(0) => Some(ArraySpec::None),
                _ => {
                    let v = a.value.to_string();
                    self.report(
                        Severity::Warning,
                        "AR013",
                        format!("arraySize `{v}` is not an integer (-1, 0 or a positive size); treated as scalar"),
                        off,
                    );
                    Some(ArraySpec::None)
                }
            };
            if ty.is_array() {
                if spec.is_some_and(|s| s != ArraySpec::None) {
                    self.report(
                        Severity::Warning,
                        "AR013",
                        format!(
                            "arraySize on `{}` (already an array) is not supported; ignored",
                            ty
                        ),
                        off,
                    );
                }
            } else if let Some(s) = spec {
                shape = s;
            }
        }
        if dynamic && !ty.is_array() {
            shape = ArraySpec::Dynamic;
        }
        shape
    }

    fn resolve_flags(&mut self, prop: &mut Property, attrs: &[Attr]) {
        prop.connectable = attr(attrs, "connectable").is_none_or(|a| args_bool(&a.value, true));
    }

    /// The property's default value; reports AR012.
    fn resolve_default(&mut self, ty: &Type, a: Option<&Attr>, pos: usize) -> Option<Value> {
        let (text, offset) = match a {
            Some(a) => (Some(a.value.as_ref()), a.offset),
            None => (None, pos),
        };
        let parsed = parse_default(ty, text);
        if let Some((severity, msg)) = parsed.issue {
            self.report(severity, "AR012", msg, offset);
        }
        parsed.value
    }

    /// The property's vstruct member declaration (attributes, or child elements with the
    /// `args-child-meta` extension).
    fn resolve_vstruct(
        &mut self,
        prop: &mut Property,
        attrs: &[Attr<'_>],
        child_meta: &[ChildMeta],
    ) {
        let mut get = |key: &'static str, me: &mut Self| -> Option<(&str, usize)> {
            let from_attr = attr(attrs, key).map(|a| (a.value.as_ref(), a.offset));
            let from_child = child_meta.iter().find(|c| c.key == key);
            match (from_attr, from_child) {
                (Some(a), Some(c)) => {
                    me.report(
                        Severity::Warning,
                        "AR023",
                        format!("child <string name=\"{key}\"> conflicts with the attribute; the attribute wins"),
                        c.offset,
                    );
                    Some(a)
                }
                (Some(a), None) => Some(a),
                (None, Some(c)) => {
                    prop.metadata.push(key, &c.value);
                    Some((c.value.as_str(), c.offset))
                }
                (None, None) => None,
            }
        };
        let member = get("vstructmember", self);
        let cond = get("vstructConditionalExpr", self);
        let alias = get("vstructmemberaliases", self);

        let split = member.and_then(|(m, _)| split_member(m));
        let Some((head, member_name)) = split else {
            if let Some((c, off)) = cond
                && !c.is_empty()
            {
                self.report(
                    Severity::Info,
                    "AR022",
                    format!(
                        "vstructConditionalExpr on `{}`, which is not a vstruct member, is ignored",
                        prop.name
                    ),
                    off,
                );
            }
            return;
        };
        let cond = cond
            .filter(|(c, _)| !c.is_empty())
            .map(|(text, off)| CondSource {
                text: text.to_string(),
                location: self.loc(off),
            });
        prop.vstruct = Some(MemberDecl {
            head,
            member: member_name,
            alias: alias
                .filter(|(a, _)| !a.is_empty())
                .map(|(a, _)| a.to_string()),
            cond,
        });
    }
}

/// Offset inside a raw attribute value of the `&` that starts a bad reference.
fn escape_error_position(e: &quick_xml::Error) -> usize {
    use quick_xml::escape::EscapeError as E;
    match e {
        quick_xml::Error::Escape(E::UnrecognizedEntity(r, _) | E::UnterminatedEntity(r)) => {
            r.start.saturating_sub(1)
        }
        _ => 0,
    }
}

/// A message for a bad reference in an attribute value, without quick-xml's byte ranges.
fn escape_message(e: &quick_xml::Error) -> String {
    use quick_xml::escape::EscapeError as E;
    match e {
        quick_xml::Error::Escape(E::UnrecognizedEntity(_, name)) => {
            format!("unknown entity `&{name};` in an attribute value")
        }
        quick_xml::Error::Escape(E::UnterminatedEntity(_)) => {
            "`&` without a closing `;` in an attribute value".to_string()
        }
        other => other.to_string(),
    }
}

/// Position (relative to the tag content) reported by an attribute error.
fn attr_error_position(e: &quick_xml::events::attributes::AttrError) -> usize {
    use quick_xml::events::attributes::AttrError as A;
    match *e {
        A::ExpectedEq(p)
        | A::ExpectedValue(p)
        | A::UnquotedValue(p)
        | A::ExpectedQuote(p, _)
        | A::Duplicated(p, _) => p,
    }
}

/// Splits `vstructmember` at the first `.`; `None` when head or member would be empty or there
/// is no dot. Nothing is trimmed.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) fn split_member(value: &str) -> Option<(String, String)> {
    let (head, member) = value.split_once('.')?;
    (!head.is_empty() && !member.is_empty()).then(|| (head.to_string(), member.to_string()))
}

/// `.args` booleans: `0`, `false`, `f` (any case) are false; empty is
/// `empty_is`; anything else is true.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn args_bool(value: &str, empty_is: bool) -> bool {
    let v = value.trim();
    if v.is_empty() {
        return empty_is;
    }
    !(v == "0" || v.eq_ignore_ascii_case("false") || v.eq_ignore_ascii_case("f"))
}

/// Parses an `options` attribute: `a|b|c` or `Label:value|…`.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn parse_options_attr(value: &str) -> Vec<(String, String)> {
    value
        .split('|')
        .filter(|item| !item.is_empty())
        .map(|item| match item.split_once(':') {
            Some((label, v)) => (label.to_string(), v.to_string()),
            None => (item.to_string(), item.to_string()),
        })
        .collect()
}

/// A type word of a `type` attribute or a tag; `None` if unknown.
pub(crate) fn args_type(word: &str) -> Option<Type> {
    if let Some(rest) = word.strip_prefix("struct")
        && rest.starts_with(char::is_whitespace)
    {
        return Some(Type::scalar(BaseType::Struct(Some(
            rest.trim().to_string(),
        ))));
    }
    let base = match word {
        "float" => BaseType::Float,
        "int" => BaseType::Int,
        "color" => BaseType::Color,
        "string" => BaseType::String,
        "normal" => BaseType::Normal,
        "vector" => BaseType::Vector,
        "point" => BaseType::Point,
        "matrix" => BaseType::Matrix,
        "struct" => BaseType::Struct(None),
        "vstruct" => BaseType::Vstruct,
        "float2" | "float3" => return Some(Type::parse_decl(word)),
        "bxdf" | "lightfilter" | "samplefilter" | "displayfilter" => {
            BaseType::Terminal(word.to_string())
        }
        _ => return None,
    };
    Some(Type::scalar(base))
}

// ---- defaults -------------------------------------------------------------

/// A parsed default and the most severe problem found.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) struct ParsedDefault {
    /// The value used (`None`: no default).
    pub value: Option<Value>,
    /// AR012 severity and message, if anything was off.
    pub issue: Option<(Severity, String)>,
}

/// Collects the most severe issue while parsing one default.
#[derive(Default)]
struct Issues {
    worst: Option<(Severity, String)>,
}

impl Issues {
    fn add(&mut self, severity: Severity, msg: String) {
        match &self.worst {
            Some((s, _)) if *s >= severity => {}
            _ => self.worst = Some((severity, msg)),
        }
    }
}

/// Length of the longest prefix of `s` that is a decimal float:
/// `[+-]?(d+(.d*)?|.d+)([eE][+-]?d+)?`; 0 if none.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn float_prefix_len(s: &str) -> usize {
    let b = s.as_bytes();
    let digits = |mut i: usize| {
        while i < b.len() && b[i].is_ascii_digit() {
            i += 1;
        }
        i
    };
    let mut i = 0;
    if i < b.len() && (b[i] == b'+' || b[i] == b'-') {
        i += 1;
    }
    let int_end = digits(i);
    let mut end = int_end;
    let mut has_digits = int_end > i;
    if end < b.len() && b[end] == b'.' {
        let frac_end = digits(end + 1);
        if has_digits || frac_end > end + 1 {
            has_digits = true;
            end = frac_end;
        }
    }
    if !has_digits {
        return 0;
    }
    if end < b.len() && (b[end] == b'e' || b[end] == b'E') {
        let mut j = end + 1;
        if j < b.len() && (b[j] == b'+' || b[j] == b'-') {
            j += 1;
        }
        let exp_end = digits(j);
        if exp_end > j {
            end = exp_end;
        }
    }
    end
}

/// One float token like C `atof` with the reporting rules for float defaults.
fn parse_float_token(tok: &str, issues: &mut Issues) -> f32 {
    let x = parse_float_prefix(tok, issues);
    if !x.is_finite() {
        // `atof` gives ±HUGE_VAL; no writer could write that value back, so it saturates.
        let used = crate::types::saturate_f32(x);
        issues.add(
            Severity::Warning,
            format!("`{tok}` is outside the f32 range; {used:e} is used"),
        );
        return used;
    }
    x
}

/// One float token like C `atof`, before the range check of [`parse_float_token`].
fn parse_float_prefix(tok: &str, issues: &mut Issues) -> f32 {
    let n = float_prefix_len(tok);
    let value = || tok[..n].parse::<f32>().unwrap_or(0.0);
    if n == tok.len() {
        return value();
    }
    if n == 0 {
        issues.add(
            Severity::Warning,
            format!("`{tok}` is not a number; 0 is used"),
        );
        return 0.0;
    }
    if &tok[n..] == "f" || &tok[n..] == "F" {
        issues.add(
            Severity::Info,
            format!("trailing `{}` in `{tok}` accepted", &tok[n..]),
        );
        return value();
    }
    let v = value();
    issues.add(
        Severity::Warning,
        format!("`{tok}` is not a number; {v} is used"),
    );
    v
}

/// One int token like C `atoi` with the reporting rule for int defaults.
fn parse_int_token(tok: &str, issues: &mut Issues) -> i32 {
    let b = tok.as_bytes();
    let mut i = 0;
    let negative = matches!(b.first(), Some(b'-'));
    if matches!(b.first(), Some(b'+' | b'-')) {
        i = 1;
    }
    let start = i;
    let mut acc: i64 = 0;
    while i < b.len() && b[i].is_ascii_digit() {
        acc = (acc * 10 + i64::from(b[i] - b'0')).min(i64::from(i32::MAX) + 1);
        i += 1;
    }
    let signed = if negative { -acc } else { acc };
    let v = signed.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32;
    if i == start || i != b.len() {
        issues.add(
            Severity::Warning,
            format!("`{tok}` is not an integer; {v} is used"),
        );
    }
    v
}

/// Splits a default into tokens on runs of whitespace and commas.
fn default_tokens(text: &str) -> Vec<&str> {
    token_iter(text).collect()
}

/// The whitespace- or comma-separated tokens of a default.
fn token_iter(text: &str) -> impl Iterator<Item = &str> {
    text.split(|c: char| c.is_whitespace() || c == ',')
        .filter(|t| !t.is_empty())
}

/// The most numbers a scalar (non-array) default can need: a matrix.
const MAX_SCALAR_TOKENS: usize = 16;

/// The first [`MAX_SCALAR_TOKENS`] tokens of a scalar default and the total token count,
/// without allocating (scalar defaults are parsed for almost every parameter).
fn scalar_tokens(text: &str) -> ([&str; MAX_SCALAR_TOKENS], usize) {
    let mut out = [""; MAX_SCALAR_TOKENS];
    let mut count = 0;
    for t in token_iter(text) {
        if let Some(slot) = out.get_mut(count) {
            *slot = t;
        }
        count += 1;
    }
    (out, count)
}

/// Builds one element of `base` from exactly `base.components()` numbers.
fn element(base: &BaseType, nums: &[f32], ints: &[i32]) -> Option<Value> {
    Some(match base {
        BaseType::Int => Value::Int(*ints.first()?),
        BaseType::Float => Value::Float(*nums.first()?),
        b if b.is_triple() => Value::Triple(b.clone(), nums.get(..3)?.try_into().ok()?),
        BaseType::HPoint => Value::HPoint(nums.get(..4)?.try_into().ok()?),
        BaseType::Matrix => Value::Matrix(nums.get(..16)?.try_into().ok()?),
        _ => return None,
    })
}

/// Parses a `default` attribute for `ty`. `text` is `None` when absent.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) fn parse_default(ty: &Type, text: Option<&str>) -> ParsedDefault {
    let mut issues = Issues::default();
    let value = default_value(ty, text, &mut issues);
    ParsedDefault {
        value,
        issue: issues.worst,
    }
}

fn default_value(ty: &Type, text: Option<&str>, issues: &mut Issues) -> Option<Value> {
    let base = &ty.base;
    let valued = base.is_numeric() || *base == BaseType::String;
    if !valued {
        return None; // struct, vstruct, terminal, closure, unknown (step 7)
    }
    if ty.is_array() {
        return array_default(ty, text?, issues);
    }
    let text = text.unwrap_or("");
    if *base == BaseType::String {
        return Some(Value::Str(text.to_string()));
    }
    let (tokens, count) = scalar_tokens(text);
    if count == 0 {
        return Value::zero_of(base); // step 8 (None for hpoint / matrix)
    }
    let c = base.components();
    if count != c {
        issues.add(
            Severity::Warning,
            format!("default `{text}` has {count} values, {base} needs {c}"),
        );
        return match base {
            BaseType::Int | BaseType::Float => scalar_element(base, &tokens[..1], issues),
            BaseType::Matrix => None,
            _ => Value::zero_of(base),
        };
    }
    scalar_element(base, &tokens[..c], issues)
}

/// One element of `base` from its tokens, converted into fixed buffers (no allocation).
fn scalar_element(base: &BaseType, tokens: &[&str], issues: &mut Issues) -> Option<Value> {
    let mut nums = [0.0f32; MAX_SCALAR_TOKENS];
    let mut ints = [0i32; MAX_SCALAR_TOKENS];
    let n = tokens.len().min(MAX_SCALAR_TOKENS);
    for (i, t) in tokens[..n].iter().enumerate() {
        if *base == BaseType::Int {
            ints[i] = parse_int_token(t, issues);
        } else {
            nums[i] = parse_float_token(t, issues);
        }
    }
    if *base == BaseType::Int {
        element(base, &[], &ints[..n])
    } else {
        element(base, &nums[..n], &[])
    }
}

/// Converts tokens to numbers per the element type (ints with `atoi`, others with `atof`).
fn numbers(base: &BaseType, tokens: &[&str], issues: &mut Issues) -> (Vec<f32>, Vec<i32>) {
    if *base == BaseType::Int {
        let ints: Vec<i32> = tokens.iter().map(|t| parse_int_token(t, issues)).collect();
        (Vec::new(), ints)
    } else {
        (
            tokens
                .iter()
                .map(|t| parse_float_token(t, issues))
                .collect(),
            Vec::new(),
        )
    }
}

fn array_default(ty: &Type, text: &str, issues: &mut Issues) -> Option<Value> {
    let base = &ty.base;
    let tokens = default_tokens(text);
    if *base == BaseType::String {
        let mut items: Vec<Value> = tokens.iter().map(|t| Value::Str(t.to_string())).collect();
        if let ArraySpec::Fixed(n) = ty.array {
            fit_fixed(
                &mut items,
                n,
                Value::Str(String::new()),
                text,
                issues,
                !tokens.is_empty(),
            );
        }
        return Some(Value::Array(base.clone(), items));
    }
    let c = base.components();
    let (nums, ints) = numbers(base, &tokens, issues);
    let count = tokens.len();
    let k = count / c;
    if !count.is_multiple_of(c) {
        issues.add(
            Severity::Warning,
            format!("default `{text}` has {count} values, not a multiple of {c}; the partial element is dropped"),
        );
    }
    let mut items: Vec<Value> = (0..k)
        .filter_map(|i| {
            let nums = nums.get(i * c..(i + 1) * c).unwrap_or(&[]);
            let ints = ints.get(i * c..(i + 1) * c).unwrap_or(&[]);
            element(base, nums, ints)
        })
        .collect();
    if let ArraySpec::Fixed(n) = ty.array {
        let zero = Value::zero_of(base)
            .or_else(|| (*base == BaseType::Matrix).then_some(Value::Matrix([0.0; 16])))?;
        fit_fixed(&mut items, n, zero, text, issues, count > 0);
    }
    Some(Value::Array(base.clone(), items))
}

/// Truncates or zero-pads a fixed array default to `n` elements, reporting when the count
/// was wrong (an empty default is silently padded).
fn fit_fixed(
    items: &mut Vec<Value>,
    n: usize,
    zero: Value,
    text: &str,
    issues: &mut Issues,
    report: bool,
) {
    if items.len() != n && report {
        issues.add(
            Severity::Warning,
            format!(
                "default `{text}` has {} elements, the array has {n}",
                items.len()
            ),
        );
    }
    items.truncate(n);
    items.resize(n, zero);
}
