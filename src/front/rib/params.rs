//! Reading the parameters of a shading request: each occurrence's declaration and value,
//! into a [`Param`] ready for its node, or, for a `reference` parameter, its name and
//! declaration, whose connections the [`super::Assembler`] binds (only it knows which
//! handles are defined so far).
//!
//! A [`ParamReader`] needs nothing of the network: the pipelined reader keeps one on each of
//! its threads, and either reads a batch's parameters (the tokenizer's thread when the
//! assembler is behind, the assembler otherwise), so the two threads share the work. Both
//! read exactly what the one-thread reader reads: what a reader remembers only saves work
//! (an occurrence read before without a diagnostic is read again identically), and the
//! diagnostics of each occurrence travel with it ([`Read::diags`]).

use super::lexer::{TokKind, Token, decode_str, decode_string};
use super::{
    At, DeclWords, Elem, Elems, Occurrence, Piece, Split, convert_value, rib_base_type, split_decl,
    types_compatible, value_tokens,
};
use crate::diag::{Diagnostic, Diagnostics, Error};
use crate::front::remembered::{MAX_REMEMBERED_PARAMS, Remembered, text_hash};
use crate::network::{Decl, Memo, Param, ParamAt, ParamTypes, Sym};
use crate::types::{ArraySpec, BaseType, Type, Value};
use rustc_hash::FxHashMap;
use smallvec::SmallVec;
use std::sync::Arc;

/// Values written in at most this many bytes are remembered for sharing.
const MAX_SHARED_VALUE_BYTES: usize = 48;

/// What reading one parameter occurrence gave.
pub(super) enum ReadParam {
    /// A parameter with a value, complete.
    Param(Param),
    /// A `reference` parameter whose elements are all strings: its connections are bound
    /// by the assembler, which builds the parameter.
    Reference { name: Sym, decl: Arc<Decl> },
    /// Reading it failed: the read ends here.
    Failed(Error),
}

/// One parameter occurrence as read, with the diagnostics reading it reported (most have
/// none, and an empty list costs no allocation).
pub(super) struct Read {
    /// What was read.
    pub param: ReadParam,
    /// What reading it reported, in order.
    pub diags: Vec<Diagnostic>,
}

/// A parameter name and declaration shared by the parameters that repeat a decl token.
type SharedDecl = (Sym, Arc<Decl>);

/// A parameter name, declaration and value shared by the parameters that repeat a decl and
/// value text.
type SharedParam = (Sym, Arc<Decl>, Arc<Value>);

/// Reads parameter occurrences into parameters, remembering what it read: a scene repeats
/// the same declarations and parameters on thousands of nodes.
pub(super) struct ParamReader<'a, 't> {
    file: Arc<str>,
    tables: Tables<'a, 't>,
}

/// What a [`ParamReader`] reads with and remembers.
struct Tables<'a, 't> {
    src: &'a [u8],
    types: Memo<'t>,
    /// A number per shader name read so far: what was read for one shader is not another's
    /// (types come from its definition).
    shaders: FxHashMap<Box<str>, usize>,
    /// Declarations read before, per shader and decl token (as written): their parameters
    /// share one name and one [`Decl`]. Only declarations read without a diagnostic are
    /// kept, so a hit reports nothing, exactly as reading them again would.
    decls: Remembered<SharedDecl>,
    /// Parameters with a short value read before without a diagnostic, per shader and text
    /// from the decl string to the end of the value: such a parameter is read again with one
    /// hash and one comparison of bytes.
    params: Remembered<SharedParam>,
}

/// A parameter occurrence with what [`Tables::read_param`] needs of its request.
struct Raw<'p> {
    occurrence: &'p Occurrence,
    location: At<'p>,
    value: &'p Piece,
    /// The request's array elements.
    arena: &'p [Token],
    /// The index of this occurrence in the request.
    origin: u32,
}

impl<'a, 't> ParamReader<'a, 't> {
    /// A reader of the parameters in `src` (named `file`), typed by `types`.
    pub(super) fn new(src: &'a [u8], file: Arc<str>, types: &'t dyn ParamTypes) -> Self {
        let tables = Tables {
            src,
            types: Memo::new(types),
            shaders: FxHashMap::default(),
            decls: Remembered::default(),
            params: Remembered::default(),
        };
        ParamReader { file, tables }
    }

    /// Reads the parameter occurrences of the request split as `split` (arguments `pieces`,
    /// array elements `arena`, occurrences `occurrences`) in order into `out`, up to and
    /// including the first that fails. Returns how many it read.
    pub(super) fn read_request(
        &mut self,
        split: &Split<'_>,
        pieces: &[Piece],
        arena: &[Token],
        occurrences: &[Occurrence],
        out: &mut Vec<Read>,
    ) -> usize {
        let occurrences = &occurrences[split.params.clone()];
        if occurrences.is_empty() {
            return 0;
        }
        let tables = &mut self.tables;
        let shader = tables.shader_id(&split.shader);
        // The parameters remembered before this request, their shared parts cloned one
        // after the other: each clone is an atomic increment, which waits for every store
        // before it, and between two parameters' stores it was most of a parameter's time.
        // (Entries are never changed or removed, so what this finds is what reading the
        // occurrences in turn would find.)
        let mut recalled: SmallVec<[Option<SharedParam>; 16]> = SmallVec::new();
        recalled.extend(occurrences.iter().map(|o| {
            let (whole, hash) = o.text.as_ref()?;
            let text = tables.src.get(whole.clone())?;
            let (name, decl, value) = tables.params.recall(shader, text, *hash)?;
            Some((*name, decl.clone(), value.clone()))
        }));
        out.reserve(occurrences.len());
        for (origin, (o, recalled)) in occurrences.iter().zip(recalled).enumerate() {
            let at = ParamAt::LineColumn(o.decl_tok.line, o.decl_tok.col);
            let origin = origin as u32;
            if let Some((name, decl, value)) = recalled {
                let param = Param::from_shared(name, Some(value), Some(decl), at, Some(origin));
                out.push(Read {
                    param: ReadParam::Param(param),
                    diags: Vec::new(),
                });
                continue;
            }
            let raw = Raw {
                occurrence: o,
                location: At {
                    file: &self.file,
                    line: o.decl_tok.line,
                    column: o.decl_tok.col,
                },
                value: &pieces[o.value],
                arena,
                origin,
            };
            let mut diags = Diagnostics::new();
            let param = tables
                .read_param(shader, &split.shader, raw, &mut diags)
                .unwrap_or_else(ReadParam::Failed);
            let failed = matches!(param, ReadParam::Failed(_));
            out.push(Read {
                param,
                diags: diags.into_vec(),
            });
            if failed {
                return origin as usize + 1;
            }
        }
        occurrences.len()
    }
}

impl<'a> Tables<'a, '_> {
    /// The number of shader `name` (see [`Tables::shaders`]).
    fn shader_id(&mut self, name: &str) -> usize {
        if let Some(&id) = self.shaders.get(name) {
            return id;
        }
        let id = self.shaders.len();
        self.shaders.insert(Box::from(name), id);
        id
    }

    /// Reads one parameter occurrence of shader `shader_name` (number `shader`).
    fn read_param(
        &mut self,
        shader: usize,
        shader_name: &str,
        raw: Raw<'_>,
        diags: &mut Diagnostics,
    ) -> Result<ReadParam, Error> {
        let Raw {
            occurrence,
            location,
            value,
            arena,
            origin,
        } = raw;
        let at = ParamAt::LineColumn(location.line, location.column);
        // The whole parameter as written, when it may have been read before (an earlier
        // occurrence of this request may have remembered it).
        let src = self.src;
        let whole = occurrence
            .text
            .clone()
            .and_then(|(whole, hash)| Some((src.get(whole)?, hash)));
        if let Some((name, decl, value)) =
            whole.and_then(|(w, hash)| self.params.recall(shader, w, hash))
        {
            let param = Param::from_shared(
                *name,
                Some(value.clone()),
                Some(decl.clone()),
                at,
                Some(origin),
            );
            return Ok(ReadParam::Param(param));
        }
        let (name, decl, remembered) =
            self.declaration(shader, shader_name, &occurrence.decl_tok, &location, diags)?;
        let toks = value_tokens(value, arena);
        if decl.reference && toks.iter().all(|t| t.kind == TokKind::Str) {
            return Ok(ReadParam::Reference { name, decl });
        }
        if decl.reference {
            diags.push(
                Diagnostic::warning(
                    "RB014",
                    format!("`reference` parameter `{name}` has numbers instead of `handle:output` strings; kept as a value"),
                )
                .at(location.loc()),
            );
        }
        let text = &src[value.range()];
        let elems = self.elems(toks);
        let before = diags.len();
        let value = Arc::new(convert_value(&decl.ty, &elems, &name, &location, diags));
        // Remembered only when reading it again would report nothing (the declaration and
        // the value read cleanly, and a `reference` with numbers is RB014 each time).
        if let Some((whole, hash)) = whole.filter(|_| {
            remembered
                && !decl.reference
                && diags.len() == before
                && text.len() <= MAX_SHARED_VALUE_BYTES
                && self.params.len() < MAX_REMEMBERED_PARAMS
        }) {
            let shared = (name, decl.clone(), value.clone());
            self.params.remember(shader, whole, hash, shared);
        }
        let param = Param::from_shared(name, Some(value), Some(decl), at, Some(origin));
        Ok(ReadParam::Param(param))
    }

    /// The name and declaration of a parameter from its decl token, and whether they are
    /// remembered: per shader and token text, when reading them reported nothing (see
    /// [`Tables::decls`]).
    fn declaration(
        &mut self,
        shader_id: usize,
        shader: &str,
        decl_tok: &Token,
        location: &At<'_>,
        diags: &mut Diagnostics,
    ) -> Result<(Sym, Arc<Decl>, bool), Error> {
        let raw = &self.src[decl_tok.start..decl_tok.end];
        let hash = text_hash(raw);
        if let Some((name, decl)) = self.decls.recall(shader_id, raw, hash) {
            return Ok((*name, decl.clone(), true));
        }
        let before = diags.len();
        let decl_text = decode_string(self.src, decl_tok);
        let Some(words) = split_decl(&decl_text) else {
            return Err(Diagnostic::error("RB006", "empty parameter declaration")
                .at(location.loc())
                .into());
        };
        let name = Sym::new(words.name);
        if !words.extra.is_empty() {
            diags.push(
                Diagnostic::warning(
                    "RB013",
                    format!(
                        "unknown word(s) `{}` in the declaration of `{name}`",
                        words.extra.join(" ")
                    ),
                )
                .at(location.loc()),
            );
        }
        let (ty, inline_type) = self.decl_type(shader, &words, location, diags)?;
        let class = words.class.map(str::to_string);
        let reference = words.reference;
        let decl = Decl {
            text: decl_text,
            class,
            reference,
            ty,
            inline_type,
        };
        if inline_type {
            self.check_definition_type(shader, &name, &decl, location, diags);
        }
        let decl = Arc::new(decl);
        if diags.len() != before {
            return Ok((name, decl, false));
        }
        self.decls
            .remember(shader_id, raw, hash, (name, decl.clone()));
        Ok((name, decl, true))
    }

    /// The parameter type: inline, or from the definition (RB012), or RB006.
    fn decl_type(
        &self,
        shader: &str,
        words: &DeclWords<'_>,
        location: &At<'_>,
        diags: &mut Diagnostics,
    ) -> Result<(Type, bool), Error> {
        let array = match words.array {
            None => None,
            Some(n) => match n.parse::<usize>() {
                Ok(n) => Some(n),
                Err(_) => {
                    let word = format!("{}[{n}]", words.type_word.unwrap_or(""));
                    return Ok(unknown_type(word, words.name, location, diags));
                }
            },
        };
        let Some(word) = words.type_word else {
            let Some(mut ty) = self.types.input_type(shader, words.name) else {
                return Err(Diagnostic::error(
                    "RB006",
                    format!(
                        "parameter `{}` has no type and `{shader}` does not declare it",
                        words.name
                    ),
                )
                .at(location.loc())
                .into());
            };
            diags.push(
                Diagnostic::warning(
                    "RB012",
                    format!(
                        "parameter `{}` has no inline type; using `{ty}` from `{shader}`",
                        words.name
                    ),
                )
                .at(location.loc()),
            );
            if let (Some(n), ArraySpec::None) = (array, ty.array) {
                ty.array = ArraySpec::Fixed(n);
            }
            return Ok((ty, false));
        };
        let Some(mut ty) = rib_base_type(word) else {
            return Ok(unknown_type(word.to_string(), words.name, location, diags));
        };
        if let Some(n) = array {
            if ty.is_array() {
                let word = format!("{word}[{n}]");
                return Ok(unknown_type(word, words.name, location, diags));
            }
            ty.array = ArraySpec::Fixed(n);
        }
        Ok((ty, true))
    }

    /// RB016: the inline type differs from the definition's (not on input heads).
    fn check_definition_type(
        &self,
        shader: &str,
        name: &str,
        decl: &Decl,
        location: &At<'_>,
        diags: &mut Diagnostics,
    ) {
        if !self.types.has_definitions()
            || matches!(decl.ty.base, BaseType::Unknown(_))
            || self.types.is_input_head(shader, name)
        {
            return;
        }
        let Some(def) = self.types.input_type(shader, name) else {
            return;
        };
        if !types_compatible(&decl.ty, &def) {
            let what = if decl.reference {
                "connection"
            } else {
                "value"
            };
            diags.push(
                Diagnostic::warning(
                    "RB016",
                    format!(
                        "{what} `{name}` is declared `{}` but `{shader}` declares it `{def}`",
                        decl.ty
                    ),
                )
                .at(location.loc()),
            );
        }
    }

    /// The elements of a value's tokens.
    fn elems(&self, toks: &[Token]) -> Elems<'a> {
        let src: &'a [u8] = self.src;
        toks.iter()
            .map(|t| {
                if t.kind == TokKind::Str {
                    Elem::Str(decode_str(src, t))
                } else {
                    Elem::Num(std::str::from_utf8(&src[t.start..t.end]).unwrap_or("0"))
                }
            })
            .collect()
    }
}

/// RB013 for the type `word` of parameter `name`, which RIB does not know: the parameter
/// keeps it as written (an inline type).
fn unknown_type(
    word: String,
    name: &str,
    location: &At<'_>,
    diags: &mut Diagnostics,
) -> (Type, bool) {
    diags.push(
        Diagnostic::warning("RB013", format!("unknown type `{word}` of `{name}`"))
            .at(location.loc()),
    );
    (Type::scalar(BaseType::Unknown(word)), true)
}
