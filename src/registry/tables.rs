//! Per-type vstruct tables and head normalisation.
//!
//! Heads are recognised only by back-reference: the heads of a node type are exactly the
//! distinct head names of its members, per direction. Tags and declared types play no
//! part.
//!
//! Choices where the spec is silent:
//!
//! * VS007 (head without a property) and VS008 (nested head) look at properties of the same
//!   direction as the head's members (inputs and outputs are separate namespaces).
//! * VS001 is reported once per member carrying an unparsable conditional (each has its own
//!   location); the expression itself is parsed once per distinct text per type.
//! * VS001's position is the value start plus the decoded offset.
//! * VS003 points at the property (the readers keep no position per attribute).

use crate::cond::{self, ParseError, Statement};
use crate::diag::{Diagnostic, Location};
use crate::limits::Limits;
use crate::model::{CondSource, Definition, Direction, Property};
use crate::network::Sym;
use crate::types::BaseType;
use rustc_hash::{FxHashMap as HashMap, FxHashSet as HashSet};
use std::sync::Arc;

/// A member conditional: its source text and the parse result (shared between members with
/// the same text).
#[derive(Debug, Clone)]
pub struct CondEntry {
    /// The raw expression and where it is written.
    pub source: CondSource,
    /// The parse result.
    pub parsed: Arc<Result<Statement, ParseError>>,
}

impl CondEntry {
    /// The parsed statement, if the expression parsed.
    pub fn statement(&self) -> Option<&Statement> {
        self.parsed.as_ref().as_ref().ok()
    }
}

/// One input member of an input head.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct InputMember {
    /// The member property (an input of the node type); shared with the networks it is
    /// connected in.
    pub property: Arc<str>,
    /// Names tried in order: `[primary]` or `[primary, alias]`.
    pub names: Vec<String>,
    /// The property's interned name (what resolution gives the parameters it adds).
    pub(crate) sym: Sym,
}

/// One output member of an output head.
#[derive(Debug, Clone)]
pub struct OutputMember {
    /// The member property (an output of the node type); shared with the connections
    /// resolution makes from it.
    pub property: Arc<str>,
    /// Names it is found by: `[primary]` or `[primary, alias]`.
    pub names: Vec<String>,
    /// The property's interned name (what resolution's connections name).
    pub(crate) sym: Sym,
    /// Its conditional, if it has a non-empty one.
    pub cond: Option<CondEntry>,
}

/// An input head and its members in declaration order.
#[derive(Debug, Clone)]
pub struct InputHead {
    /// Head name.
    pub name: String,
    /// Members in declaration order.
    pub members: Vec<InputMember>,
}

/// An output head: its members and the reverse map name → member.
#[derive(Debug, Clone)]
pub struct OutputHead {
    /// Head name.
    pub name: String,
    /// Members in declaration order.
    pub members: Vec<OutputMember>,
    /// Name (primary or alias) → index in `members`; later declarations win (VS004).
    reverse: HashMap<String, usize>,
}

impl OutputHead {
    /// The member found by `name` (primary or alias).
    pub fn lookup(&self, name: &str) -> Option<&OutputMember> {
        self.reverse.get(name).map(|&i| &self.members[i])
    }
}

/// The vstruct tables of one node type.
#[derive(Debug, Clone, Default)]
pub struct VstructTables {
    inputs: Vec<InputHead>,
    outputs: Vec<OutputHead>,
    /// Head name → position in `inputs` (types with thousands of heads are looked up per
    /// expansion).
    input_index: HashMap<String, usize>,
    /// Head name → position in `outputs`.
    output_index: HashMap<String, usize>,
}

impl VstructTables {
    /// True if `head` is an input head.
    pub fn is_input_head(&self, head: &str) -> bool {
        self.input_head(head).is_some()
    }

    /// True if `head` is an output head.
    pub fn is_output_head(&self, head: &str) -> bool {
        self.output_head(head).is_some()
    }

    /// The input head named `head`.
    pub fn input_head(&self, head: &str) -> Option<&InputHead> {
        self.input_index.get(head).map(|&i| &self.inputs[i])
    }

    /// The output head named `head`.
    pub fn output_head(&self, head: &str) -> Option<&OutputHead> {
        self.output_index.get(head).map(|&i| &self.outputs[i])
    }

    /// Members of input head `head` in declaration order (empty if it is not one).
    pub fn members_in(&self, head: &str) -> &[InputMember] {
        self.input_head(head).map_or(&[], |h| &h.members)
    }

    /// Members of output head `head` in declaration order (empty if it is not one).
    pub fn members_out(&self, head: &str) -> &[OutputMember] {
        self.output_head(head).map_or(&[], |h| &h.members)
    }

    /// The output member of `head` named `name` (primary or alias).
    pub fn reverse_out(&self, head: &str, name: &str) -> Option<&OutputMember> {
        self.output_head(head)?.lookup(name)
    }

    /// Input head names in order of their first member.
    pub fn input_heads(&self) -> impl Iterator<Item = &str> {
        self.inputs.iter().map(|h| h.name.as_str())
    }

    /// Output head names in order of their first member.
    pub fn output_heads(&self) -> impl Iterator<Item = &str> {
        self.outputs.iter().map(|h| h.name.as_str())
    }

    /// True if the type has no heads at all.
    pub fn is_empty(&self) -> bool {
        self.inputs.is_empty() && self.outputs.is_empty()
    }

    /// Builds the tables of `def`, reporting VS001–VS009 into `diags`.
    pub fn build(def: &Definition, diags: &mut Vec<Diagnostic>) -> VstructTables {
        Self::build_limited(def, &Limits::default(), diags)
    }

    /// [`VstructTables::build`] with conditionals parsed within `limits` (expression terms
    /// and depth; a conditional beyond them is VS001 naming the limit, and its member has no
    /// condition).
    pub fn build_limited(
        def: &Definition,
        limits: &Limits,
        diags: &mut Vec<Diagnostic>,
    ) -> VstructTables {
        let mut b = Builder {
            def,
            diags,
            parsed: HashMap::default(),
            limits,
            input_names: def.inputs.iter().map(|p| p.name.as_str()).collect(),
        };
        b.check_malformed_members();
        let inputs = b.input_heads();
        let outputs = b.output_heads();
        let index = |names: &mut dyn Iterator<Item = &String>| -> HashMap<String, usize> {
            names.enumerate().map(|(i, n)| (n.clone(), i)).collect()
        };
        let input_index = index(&mut inputs.iter().map(|h| &h.name));
        let output_index = index(&mut outputs.iter().map(|h| &h.name));
        b.check_heads(&inputs, &outputs, &output_index);
        VstructTables {
            inputs,
            outputs,
            input_index,
            output_index,
        }
    }
}

/// The distinct head names of the members among `props`, in order of first appearance.
fn head_names(props: &[Property]) -> Vec<&str> {
    let mut seen = HashSet::default();
    props
        .iter()
        .filter_map(|p| p.vstruct.as_ref().map(|m| m.head.as_str()))
        .filter(|h| seen.insert(*h))
        .collect()
}

/// Registry normalisation: a property named like a head of its own direction
/// gets type `Vstruct` (array shape and declared type kept) and loses its default.
pub(crate) fn normalize_heads(def: &mut Definition) {
    fn normalize(props: &mut [Property]) {
        let heads: HashSet<String> = head_names(props).into_iter().map(String::from).collect();
        for p in props.iter_mut().filter(|p| heads.contains(&p.name)) {
            p.ty.base = BaseType::Vstruct;
            p.default = None;
        }
    }
    normalize(&mut def.inputs);
    normalize(&mut def.outputs);
}

/// The names a member is known by: `[primary]` or `[primary, alias]`.
fn member_names(p: &Property) -> Vec<String> {
    let Some(m) = &p.vstruct else {
        return Vec::new();
    };
    let mut names = vec![m.member.clone()];
    if let Some(a) = &m.alias
        && *a != m.member
    {
        names.push(a.clone());
    }
    names
}

struct Builder<'d, 'g> {
    def: &'d Definition,
    diags: &'g mut Vec<Diagnostic>,
    parsed: HashMap<String, Arc<Result<Statement, ParseError>>>,
    limits: &'g Limits,
    /// The names of the definition's inputs (conditionals' names are checked against them).
    input_names: HashSet<&'d str>,
}

impl Builder<'_, '_> {
    fn all(&self) -> impl Iterator<Item = &Property> {
        self.def.inputs.iter().chain(self.def.outputs.iter())
    }

    /// VS003 for `vstructmember` values that do not split; VS006 for suspicious aliases.
    fn check_malformed_members(&mut self) {
        let mut found = Vec::new();
        for p in self.all() {
            if p.vstruct.is_none()
                && let Some(v) = p.meta("vstructmember")
            {
                found.push(
                    Diagnostic::warning(
                        "VS003",
                        format!(
                            "malformed vstructmember `{v}` on `{}` (expected `head.member`); not a member",
                            p.name
                        ),
                    )
                    .at(p.location.clone()),
                );
            }
            if let Some(a) = p.vstruct.as_ref().and_then(|m| m.alias.as_ref())
                && a.contains(|c: char| c.is_whitespace() || c == ',')
            {
                found.push(
                    Diagnostic::warning(
                        "VS006",
                        format!(
                            "vstructmemberaliases `{a}` on `{}` contains whitespace or `,`; used as one alias",
                            p.name
                        ),
                    )
                    .at(p.location.clone()),
                );
            }
        }
        self.diags.extend(found);
    }

    /// Parses `cond` once per distinct text; reports VS001 for this member if it fails.
    fn parse_cond(&mut self, p: &Property, src: &CondSource) -> CondEntry {
        let parsed = self
            .parsed
            .entry(src.text.clone())
            .or_insert_with(|| {
                let ext = cond::Extensions::none();
                Arc::new(cond::parse_limited(&src.text, &ext, self.limits))
            })
            .clone();
        if let Err(e) = parsed.as_ref() {
            self.diags.push(vs001(p, src, e));
        }
        CondEntry {
            source: src.clone(),
            parsed,
        }
    }

    fn input_heads(&mut self) -> Vec<InputHead> {
        let def = self.def;
        let mut heads: Vec<InputHead> = Vec::new();
        let mut position: HashMap<&str, usize> = HashMap::default();
        for p in &def.inputs {
            let Some(m) = &p.vstruct else { continue };
            if let Some(src) = &m.cond {
                let entry = self.parse_cond(p, src);
                self.diags.push(
                    Diagnostic::info(
                        "VS002",
                        format!(
                            "conditional on input member `{}` is never consulted (only output members' conditionals are)",
                            p.name
                        ),
                    )
                    .at(entry.source.location.clone()),
                );
            }
            let member = InputMember {
                property: Arc::from(p.name.as_str()),
                sym: Sym::new(&p.name),
                names: member_names(p),
            };
            match position.get(m.head.as_str()) {
                Some(&i) => heads[i].members.push(member),
                None => {
                    position.insert(&m.head, heads.len());
                    heads.push(InputHead {
                        name: m.head.clone(),
                        members: vec![member],
                    });
                }
            }
        }
        heads
    }

    fn output_heads(&mut self) -> Vec<OutputHead> {
        let def = self.def;
        let mut heads: Vec<OutputHead> = Vec::new();
        let mut position: HashMap<&str, usize> = HashMap::default();
        for p in &def.outputs {
            let Some(m) = &p.vstruct else { continue };
            let cond = m.cond.as_ref().map(|src| self.parse_cond(p, src));
            if let Some((c, stmt)) = cond.as_ref().and_then(|c| Some((c, c.statement()?))) {
                self.check_cond_names(p, &c.source, stmt);
            }
            let idx = match position.get(m.head.as_str()) {
                Some(&i) => i,
                None => {
                    position.insert(&m.head, heads.len());
                    heads.push(OutputHead {
                        name: m.head.clone(),
                        members: Vec::new(),
                        reverse: HashMap::default(),
                    });
                    heads.len() - 1
                }
            };
            let names = member_names(p);
            let head = &mut heads[idx];
            let member_index = head.members.len();
            for n in &names {
                if let Some(prev) = head.reverse.insert(n.clone(), member_index) {
                    let prev_prop = &head.members[prev].property;
                    let prev_loc = def.output(prev_prop).map(|q| q.location.clone());
                    let mut d = Diagnostic::warning(
                        "VS004",
                        format!(
                            "output members `{prev_prop}` and `{}` of head `{}` share the name `{n}`; the later one (`{}`) wins",
                            p.name, m.head, p.name
                        ),
                    )
                    .at(p.location.clone());
                    if let Some(l) = prev_loc {
                        d = d.with_related("earlier member", l);
                    }
                    self.diags.push(d);
                }
            }
            head.members.push(OutputMember {
                property: Arc::from(p.name.as_str()),
                sym: Sym::new(&p.name),
                names,
                cond,
            });
        }
        heads
    }

    /// VS009: names read by an output member's conditional (predicates and `copy`) that are
    /// not inputs of the type, one warning per distinct name at its first occurrence (position,
    /// span and a caret note). Outputs do not count; a name with `[n]` is looked up literally.
    fn check_cond_names(&mut self, p: &Property, src: &CondSource, stmt: &Statement) {
        let mut reported = HashSet::default();
        for param in stmt.params() {
            let name = param.name.as_str();
            if self.input_names.contains(name) || !reported.insert(name) {
                continue;
            }
            let mut d = Diagnostic::warning(
                "VS009",
                format!(
                    "conditional of `{}` reads `{name}`, which is not an input of `{}`",
                    p.name, self.def.id
                ),
            )
            .at(position_in(src, param.span.start))
            .with_span(param.span.clone())
            .with_note(cond::render_caret(&src.text, param.span.clone()));
            if self.def.output(name).is_some() {
                d = d.with_note(format!(
                    "`{name}` is an output of `{}`; conditionals read inputs only",
                    self.def.id
                ));
            }
            self.diags.push(d.with_note(
                "the predicate always sees no operand / not connected / not set, and `copy` \
                 of it always fails",
            ));
        }
    }

    /// VS005, VS007, VS008.
    fn check_heads(
        &mut self,
        inputs: &[InputHead],
        outputs: &[OutputHead],
        output_index: &HashMap<String, usize>,
    ) {
        let def = self.def;
        let first_inputs = first_member_locations(&def.inputs);
        for h in inputs {
            if output_index.contains_key(&h.name) {
                let loc = first_inputs
                    .get(h.name.as_str())
                    .map_or_else(Location::default, |l| (*l).clone());
                self.diags.push(
                    Diagnostic::warning(
                        "VS005",
                        format!(
                            "head `{}` has both input and output members; they form separate input and output heads",
                            h.name
                        ),
                    )
                    .at(loc),
                );
            }
        }
        let in_names: Vec<&str> = inputs.iter().map(|h| h.name.as_str()).collect();
        let out_names: Vec<&str> = outputs.iter().map(|h| h.name.as_str()).collect();
        self.check_direction(&def.inputs, &in_names, Direction::In);
        self.check_direction(&def.outputs, &out_names, Direction::Out);
    }

    fn check_direction(&mut self, props: &[Property], heads: &[&str], dir: Direction) {
        let what = if dir == Direction::In {
            "input"
        } else {
            "output"
        };
        let declared: HashSet<&str> = props.iter().map(|p| p.name.as_str()).collect();
        let first = first_member_locations(props);
        for h in heads {
            if !declared.contains(h) {
                self.diags.push(
                    Diagnostic::info(
                        "VS007",
                        format!(
                            "{what} head `{h}` has members but no {what} named `{h}` is declared"
                        ),
                    )
                    .at(first
                        .get(h)
                        .map_or_else(Location::default, |l| (*l).clone())),
                );
            }
        }
        let heads: HashSet<&str> = heads.iter().copied().collect();
        for p in props {
            if p.vstruct.is_some() && heads.contains(p.name.as_str()) {
                self.diags.push(
                    Diagnostic::warning(
                        "VS008",
                        format!(
                            "member `{}` is itself a head of other members (nested vstruct); it is not expanded recursively",
                            p.name
                        ),
                    )
                    .at(p.location.clone()),
                );
            }
        }
    }
}

/// Head name → the location of its first member among `props`.
fn first_member_locations(props: &[Property]) -> HashMap<&str, &Location> {
    let mut first = HashMap::default();
    for p in props {
        if let Some(m) = &p.vstruct {
            first.entry(m.head.as_str()).or_insert(&p.location);
        }
    }
    first
}

/// VS001 for an unparsable conditional: the position is the value start plus the decoded
/// offset of the error span; notes show the expression with a caret line.
fn vs001(p: &Property, src: &CondSource, e: &ParseError) -> Diagnostic {
    let text = &src.text;
    let start = floor_boundary(text, e.span.start);
    let end = floor_boundary(text, e.span.end.max(e.span.start));
    let before = &text[..start];
    let loc = position_in(src, start);
    let caret_pad = before.chars().count();
    let caret_len = text[start..end].chars().count().max(1);
    Diagnostic::warning(
        "VS001",
        format!("conditional of `{}` does not parse: {}", p.name, e.message),
    )
    .at(loc)
    .with_span(e.span.clone())
    .with_note(format!(
        "{text}\n{}{}",
        " ".repeat(caret_pad),
        "^".repeat(caret_len)
    ))
}

/// Where byte `offset` of a conditional's text is: the value start plus the decoded offset.
fn position_in(src: &CondSource, offset: usize) -> Location {
    let before = &src.text[..floor_boundary(&src.text, offset)];
    let mut loc = src.location.clone();
    match before.rfind('\n') {
        Some(nl) => {
            loc.line += before.matches('\n').count() as u32;
            loc.column = before[nl + 1..].chars().count() as u32 + 1;
        }
        None => loc.column += before.chars().count() as u32,
    }
    loc
}

fn floor_boundary(text: &str, i: usize) -> usize {
    let mut i = i.min(text.len());
    while !text.is_char_boundary(i) {
        i -= 1;
    }
    i
}
