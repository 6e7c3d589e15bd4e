//! A crate file (`.usdc`) read alone, without composing a stage: its tables decoded here
//! ([`tables`]) when the file is laid out as writers lay it out, each spec's type and fields
//! indexed by path, and the values the reader reads most decoded here too; any other value
//! is read through `openusd`'s crate reader. [`CrateLayer`] answers the reader's
//! [`Specs`] questions, and walks the prims by path index for the reader's fast path.

mod tables;

use super::{
    AttrFields, FieldRead, InputAt, PRIM_KEEPS, PrimKind, ROOT_CHANGES, Specs, all_differ,
    default_of, distinct_inputs, prim_kind, samples_of, targets_of, tokens_of, type_name_of,
};
// What the walks' comparison reads besides.
#[cfg(feature = "testkit")]
use super::{flat_prims, property_path};
use openusd::sdf;
use rustc_hash::FxHashMap;
use std::borrow::Cow;
use std::io;
use std::sync::Arc;
use tables::{
    CRATE_BOOL, CRATE_DOUBLE, CRATE_FLOAT, CRATE_INT, CRATE_PATH_LIST_OP, CRATE_SPECIFIER,
    CRATE_STRING, CRATE_TOKEN, CRATE_TOKEN_VECTOR, CRATE_VEC3F, CrateTables, NO_PATH, PathTree,
    Rep, le_size,
};

/// The crate file type [`CrateLayer`] reads values through when it does not decode them.
type CrateFile = openusd::usdc::CrateFile<io::Cursor<Arc<[u8]>>>;

/// The hash [`CrateLayer`] finds a spec by: its path's text, hashed with FxHash.
fn path_hash(path: &sdf::Path) -> u64 {
    use std::hash::BuildHasher;
    rustc_hash::FxBuildHasher.hash_one(path.as_str())
}

/// A crate file's specs, indexed once: each spec's type and fields by path, each field
/// name's token, so that a field is found by comparing token indices in the spec's field
/// set (`openusd`'s own crate data compares names and hashes paths with SipHash). The
/// tables are decoded here ([`CrateTables`]) when the file is laid out as writers lay it
/// out, else by `openusd`; the values the reader reads most (tokens, token arrays and
/// vectors, specifiers, booleans, ints, floats, doubles, 3-vectors of floats, path list
/// operations) are decoded here, any other by `openusd`, which then reads the file once.
pub(super) struct CrateLayer {
    /// `openusd`'s reading of the file: at once when the tables are not decoded here, else
    /// when a value not decoded here is first asked for.
    file: std::sync::Mutex<Option<CrateFile>>,
    /// The file's bytes (shared with `file`'s reader), for the values decoded here.
    bytes: Arc<[u8]>,
    /// The file's version: whether it is at least 0.5.0, and at least 0.7.0 (the layout of
    /// array headers).
    v05: bool,
    v07: bool,
    /// The file's tokens, each made a token once (values that are tokens, or arrays of
    /// tokens, are answered with clones of these).
    tokens: Vec<openusd::tf::Token>,
    /// The token index of each string.
    strings: Vec<usize>,
    /// Each field: its name's token index and its value representation.
    fields: Vec<(usize, u64)>,
    /// Field indices, each field set ended by nothing.
    fieldsets: Vec<Option<usize>>,
    paths: Vec<sdf::Path>,
    /// Each spec: its path's index in `paths`, its type and the start of its field set in
    /// `fieldsets`, found by the hash of its path (so the paths are not copied): made
    /// from `specs_in` when a spec is first looked up by path.
    specs: std::sync::OnceLock<hashbrown::HashTable<(usize, sdf::SpecType, usize)>>,
    /// Each spec: its path index, its field set's start and its type.
    specs_in: Vec<(usize, usize, sdf::SpecType)>,
    /// The path tree, when the tables are decoded here and no two paths are the same.
    tree: Option<PathTree>,
    /// Whether values not decoded here are read as none rather than by `openusd` (set
    /// only to compare the walks by index and by text on damaged files, where `openusd`
    /// may fail).
    decoded_only: std::sync::atomic::AtomicBool,
    /// With the tree: the type and field set start of the spec of each path index.
    spec_at: Vec<Option<(sdf::SpecType, usize)>>,
    /// The token index of each field name (under the names `openusd`'s layers use:
    /// `propertyChildren` for the crate's `properties`).
    names: FxHashMap<String, usize>,
    /// The field name of each token index that names a field.
    field_names: FxHashMap<usize, String>,
    /// The token indices of the fields [`Specs::attribute`] reads: `typeName`, `default`,
    /// `connectionPaths`, `timeSamples`.
    attribute_fields: [Option<usize>; 4],
    /// The token indices of the prim fields the walk by path index reads: `specifier`,
    /// `primChildren`, `propertyChildren`.
    prim_fields: [Option<usize>; 3],
}

impl CrateLayer {
    /// The crate file `bytes`, or nothing when it does not read or is not sound (then the
    /// stage is composed, and reports why).
    pub(super) fn open(bytes: &[u8]) -> Option<Self> {
        let bytes: Arc<[u8]> = Arc::from(bytes);
        let (tables, file) = match CrateTables::decode(&bytes) {
            Some(tables) => (tables, None),
            None => {
                let mut file = CrateFile::open(io::Cursor::new(bytes.clone())).ok()?;
                file.validate().ok()?;
                let v = file.version();
                let tables = CrateTables {
                    version: [v.major, v.minor, v.patch],
                    tokens: file
                        .tokens
                        .iter()
                        .map(|t| openusd::tf::Token::from(t.as_str()))
                        .collect(),
                    strings: file.strings.clone(),
                    fields: file
                        .fields
                        .iter()
                        .map(|f| (f.token_index, f.value_rep.0))
                        .collect(),
                    fieldsets: std::mem::take(&mut file.fieldsets),
                    paths: std::mem::take(&mut file.paths),
                    tree: None,
                    specs: std::mem::take(&mut file.specs)
                        .into_iter()
                        .map(|s| (s.path_index, s.fieldset_index, s.spec_type))
                        .collect(),
                };
                (tables, Some(file))
            }
        };
        let CrateTables {
            version,
            tokens,
            strings,
            fields,
            fieldsets,
            paths,
            tree,
            specs: specs_in,
        } = tables;
        let mut spec_at = vec![None; if tree.is_some() { paths.len() } else { 0 }];
        for &(path_index, fieldset_index, spec_type) in &specs_in {
            paths.get(path_index)?;
            fieldsets.get(fieldset_index)?;
            // Paths all differ here: the last spec of a path index is its path's.
            if let Some(slot) = spec_at.get_mut(path_index) {
                *slot = Some((spec_type, fieldset_index));
            }
        }
        // Each token that names a field once (fields repeat their name, once per value): a
        // name given by two tokens keeps the token of its last field, as in file order.
        let mut names = FxHashMap::default();
        let mut field_names = FxHashMap::default();
        let mut seen = vec![false; tokens.len()];
        for &(token_index, _) in fields.iter().rev() {
            let (Some(token), Some(seen)) = (tokens.get(token_index), seen.get_mut(token_index))
            else {
                return None;
            };
            if std::mem::replace(seen, true) {
                continue;
            }
            let name = match token.as_str() {
                "properties" => "propertyChildren",
                t => t,
            };
            names.entry(name.to_string()).or_insert(token_index);
            field_names.insert(token_index, name.to_string());
        }
        let attribute_fields = [
            sdf::FieldKey::TypeName,
            sdf::FieldKey::Default,
            sdf::FieldKey::ConnectionPaths,
            sdf::FieldKey::TimeSamples,
        ]
        .map(|k| names.get(k.as_str()).copied());
        let prim_fields =
            ["specifier", "primChildren", "propertyChildren"].map(|k| names.get(k).copied());
        Some(CrateLayer {
            file: std::sync::Mutex::new(file),
            bytes,
            v05: version[1] >= 5,
            v07: version[1] >= 7,
            tokens,
            strings,
            fields,
            fieldsets,
            paths,
            tree,
            decoded_only: std::sync::atomic::AtomicBool::new(false),
            spec_at,
            specs_in,
            specs: std::sync::OnceLock::new(),
            names,
            field_names,
            attribute_fields,
            prim_fields,
        })
    }

    /// The type and the field set start of the spec at `path`.
    fn spec(&self, path: &sdf::Path) -> Option<(sdf::SpecType, usize)> {
        self.specs
            .get_or_init(|| {
                let paths = &self.paths;
                let mut specs = hashbrown::HashTable::with_capacity(self.specs_in.len());
                for &(path_index, fieldset_index, spec_type) in &self.specs_in {
                    let path = &paths[path_index];
                    let entry = (path_index, spec_type, fieldset_index);
                    // A path given twice keeps its last spec, as a map would.
                    match specs.entry(
                        path_hash(path),
                        |&(i, ..): &(usize, _, _)| paths[i] == *path,
                        |&(i, ..)| path_hash(&paths[i]),
                    ) {
                        hashbrown::hash_table::Entry::Occupied(mut e) => *e.get_mut() = entry,
                        hashbrown::hash_table::Entry::Vacant(e) => {
                            e.insert(entry);
                        }
                    }
                }
                specs
            })
            .find(path_hash(path), |&(i, ..)| self.paths[i] == *path)
            .map(|&(_, ty, start)| (ty, start))
    }

    /// The value representation of field `field` when it may be decoded here: any but a
    /// compressed one (`openusd` decodes those).
    fn own_rep(&self, field: usize) -> Option<Rep> {
        let rep = Rep(self.fields.get(field)?.1);
        (!rep.is_compressed()).then_some(rep)
    }

    /// The token of field `field` when it is an inlined token (as `typeName` is), without
    /// the 160-byte value [`CrateLayer::own_value`] would build and move.
    fn own_token(&self, field: usize) -> Option<openusd::tf::Token> {
        let rep = self.own_rep(field)?;
        match rep.layout() {
            (CRATE_TOKEN, false, true) => self.tokens.get(rep.low() as usize).cloned(),
            _ => None,
        }
    }

    /// The targets of field `field` when it is a path list operation decoded here (as
    /// `connectionPaths` is), without the value [`CrateLayer::own_value`] would build.
    fn own_targets(&self, field: usize) -> Option<Vec<sdf::Path>> {
        let rep = self.own_rep(field)?;
        match rep.layout() {
            (CRATE_PATH_LIST_OP, false, false) => {
                let at = usize::try_from(rep.payload()).ok()?;
                Some(self.path_list_op(at)?.compose_over(&[]))
            }
            _ => None,
        }
    }

    /// The value of field `field` when it is of a type decoded here (see [`CrateLayer`])
    /// and laid out as writers lay it out; nothing for any other, which `openusd` decodes.
    fn own_value(&self, field: usize) -> Option<sdf::Value> {
        let rep = self.own_rep(field)?;
        let at = usize::try_from(rep.payload()).ok()?;
        match rep.layout() {
            (CRATE_TOKEN, false, true) => self
                .tokens
                .get(rep.low() as usize)
                .map(|t| sdf::Value::Token(t.clone())),
            (CRATE_TOKEN, true, false) | (CRATE_TOKEN_VECTOR, false, false) => {
                let tokens = self.token_list(rep)?.map(|t| t.cloned());
                tokens.collect::<Option<_>>().map(sdf::Value::TokenVec)
            }
            (CRATE_STRING, false, true) => {
                let token = self.strings.get(rep.low() as usize)?;
                Some(sdf::Value::String(
                    self.tokens.get(*token)?.as_str().to_string(),
                ))
            }
            (CRATE_SPECIFIER, false, true) => {
                sdf::Specifier::from_repr(rep.low() as i32).map(sdf::Value::Specifier)
            }
            (CRATE_BOOL, false, true) => Some(sdf::Value::Bool(rep.low() != 0)),
            (CRATE_INT, false, true) => Some(sdf::Value::Int(rep.low() as i32)),
            (CRATE_FLOAT, false, true) => Some(sdf::Value::Float(f32::from_bits(rep.low()))),
            // An inlined double is kept as a float.
            (CRATE_DOUBLE, false, true) => {
                Some(sdf::Value::Double(f64::from(f32::from_bits(rep.low()))))
            }
            // Inlined, each component is a signed byte.
            (CRATE_VEC3F, false, true) => {
                let [x, y, z, _] = rep.low().to_le_bytes().map(|b| f32::from(b as i8));
                Some(sdf::Value::Vec3f(openusd::gf::vec3f(x, y, z)))
            }
            (CRATE_VEC3F, false, false) => {
                let b = self.bytes.get(at..at.checked_add(12)?)?;
                let f = |i: usize| f32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]);
                Some(sdf::Value::Vec3f(openusd::gf::vec3f(f(0), f(4), f(8))))
            }
            (CRATE_PATH_LIST_OP, false, false) => self.path_list_op(at).map(sdf::Value::PathListOp),
            _ => None,
        }
    }

    /// The list operation on paths at `at`: a header byte saying which lists follow (and
    /// whether the operation is explicit), then each list present (explicit, added,
    /// prepended, appended, deleted, ordered) as a 64-bit count and 32-bit path indices.
    fn path_list_op(&self, at: usize) -> Option<sdf::ListOp<sdf::Path>> {
        let header = *self.bytes.get(at)?;
        let mut pos = at + 1;
        let mut list = |bit: u8| -> Option<Vec<sdf::Path>> {
            if header & bit == 0 {
                return Some(Vec::new());
            }
            let count = le_size(&self.bytes, pos)?;
            let start = pos.checked_add(8)?;
            let end = start.checked_add(count.checked_mul(4)?)?;
            let items = self.bytes.get(start..end)?;
            pos = end;
            items
                .chunks_exact(4)
                .map(|c| {
                    let i = u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as usize;
                    self.paths.get(i).cloned()
                })
                .collect()
        };
        let mut op = sdf::ListOp::<sdf::Path> {
            explicit: header & 1 != 0,
            ..Default::default()
        };
        op.explicit_items = list(1 << 1)?;
        op.added_items = list(1 << 2)?;
        op.prepended_items = list(1 << 5)?;
        op.appended_items = list(1 << 6)?;
        op.deleted_items = list(1 << 3)?;
        op.ordered_items = list(1 << 4)?;
        Some(op)
    }

    /// The tokens of a list of tokens at `rep`, an array of tokens (its header: before
    /// 0.5.0 a 32-bit shape, then the count, 32-bit before 0.7.0, else 64-bit) or a token
    /// vector (a 64-bit count), each from its 32-bit index (none for an index that names no
    /// token); nothing for another value or when the indices lie outside the file.
    fn token_list(
        &self,
        rep: Rep,
    ) -> Option<impl Iterator<Item = Option<&openusd::tf::Token>> + '_> {
        let at = usize::try_from(rep.payload()).ok()?;
        let (pos, count) = match rep.layout() {
            (CRATE_TOKEN, true, false) if at == 0 => (0, 0),
            (CRATE_TOKEN, true, false) => self.token_array_span(at)?,
            (CRATE_TOKEN_VECTOR, false, false) => (at.checked_add(8)?, le_size(&self.bytes, at)?),
            _ => return None,
        };
        let items = self
            .bytes
            .get(pos..pos.checked_add(count.checked_mul(4)?)?)?;
        Some(items.chunks_exact(4).map(|c| {
            let i = u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as usize;
            self.tokens.get(i)
        }))
    }

    /// Where the token indices of the array of tokens at `at` (not 0) start, and how many
    /// there are (see [`CrateLayer::token_list`]).
    fn token_array_span(&self, at: usize) -> Option<(usize, usize)> {
        let mut pos = at;
        if !self.v05 {
            pos = pos.checked_add(4)?;
        }
        let count = if self.v07 {
            let count = le_size(&self.bytes, pos)?;
            pos += 8;
            count
        } else {
            let b = self.bytes.get(pos..pos.checked_add(4)?)?;
            pos += 4;
            u32::from_le_bytes(b.try_into().ok()?) as usize
        };
        Some((pos, count))
    }

    /// The texts of the tokens of field `field` when [`CrateLayer::own_value`] decodes it
    /// as a list of tokens, borrowed from the file's tokens; nothing for anything else
    /// (then the field is read as a value).
    fn own_token_texts(&self, field: usize) -> Option<Vec<&str>> {
        let texts = self.token_list(self.own_rep(field)?)?;
        let texts = texts.map(|t| t.map(|t| t.as_str()));
        texts.collect()
    }

    /// The value of field `field` (the field `name` of the spec at `path`): decoded here,
    /// or by `openusd` (which reads the file the first time).
    fn read_field(&self, field: usize, path: &sdf::Path, name: &str) -> FieldRead<'static> {
        if let Some(v) = self.own_value(field) {
            return Ok(Some(std::borrow::Cow::Owned(v)));
        }
        if self.decoded_only.load(std::sync::atomic::Ordering::Relaxed) {
            return Ok(None);
        }
        let failed = |source: Box<dyn std::error::Error + Send + Sync>| sdf::DataError::Decode {
            path: path.clone(),
            field: name.to_string(),
            source,
        };
        // A poisoned lock is taken as it is: a panic of `openusd` is raised again where
        // the walk reaches the read that panicked ([`ShaderRead`]), which ends the reading.
        let mut slot = self
            .file
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if slot.is_none() {
            let opened = CrateFile::open(io::Cursor::new(self.bytes.clone()));
            *slot = Some(opened.map_err(|e| failed(e.into()))?);
        }
        let Some(file) = slot.as_mut() else {
            return Ok(None);
        };
        let Some(rep) = file.fields.get(field).map(|f| f.value_rep) else {
            return Ok(None);
        };
        match file.value(rep) {
            Ok(v) => Ok(Some(std::borrow::Cow::Owned(v))),
            Err(e) => Err(failed(e.into())),
        }
    }

    /// The field indices of the field set starting at `start`.
    fn field_set(&self, start: usize) -> &[Option<usize>] {
        let rest = self.fieldsets.get(start..).unwrap_or(&[]);
        let end = rest.iter().position(Option::is_none).unwrap_or(rest.len());
        &rest[..end]
    }

    /// The token indices of the fields of the field set starting at `start`, with each
    /// field's index.
    fn set_fields(&self, start: usize) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.field_set(start)
            .iter()
            .flatten()
            .filter_map(|&i| self.fields.get(i).map(|&(token, _)| (i, token)))
    }
    /// The first field of the field set at `start` named by token `token`, read (`path`
    /// and `name`: the spec's path and the field's name, for errors).
    fn field_in(
        &self,
        start: usize,
        token: Option<usize>,
        path: &sdf::Path,
        name: &str,
    ) -> FieldRead<'static> {
        match self.field_index(start, token) {
            Some(i) => self.read_field(i, path, name),
            None => Ok(None),
        }
    }

    /// The index of the first field of the field set at `start` named by token `token`.
    fn field_index(&self, start: usize, token: Option<usize>) -> Option<usize> {
        let token = token?;
        self.set_fields(start)
            .find(|&(_, t)| t == token)
            .map(|(i, _)| i)
    }

    /// What the reader reads of the attribute spec at `path` whose field set starts at
    /// `start`: one walk of the field set for the four fields.
    fn attribute_fields_of(&self, start: usize, path: &sdf::Path) -> AttrFields {
        let mut found = [None; 4];
        for (i, token) in self.set_fields(start) {
            if let Some(k) = self.attribute_fields.iter().position(|&t| t == Some(token))
                && found[k].is_none()
            {
                found[k] = Some(i);
            }
        }
        let keys = [
            sdf::FieldKey::TypeName,
            sdf::FieldKey::Default,
            sdf::FieldKey::ConnectionPaths,
            sdf::FieldKey::TimeSamples,
        ];
        let read = |k: usize| -> FieldRead<'static> {
            match found[k] {
                Some(i) => self.read_field(i, path, keys[k].as_str()),
                None => Ok(None),
            }
        };
        // The usual type name and targets straight from the file; any other form through a
        // value, as every other field.
        let type_name = found[0].and_then(|i| self.own_token(i));
        let targets = found[2].and_then(|i| self.own_targets(i));
        AttrFields {
            type_name: type_name.unwrap_or_else(|| type_name_of(read(0))),
            default: default_of(read(1)),
            targets: targets.unwrap_or_else(|| targets_of(read(2))),
            samples: samples_of(read(3)),
        }
    }

    /// The type and field set start of the spec of path index `index` (with the tree).
    fn spec_of(&self, index: usize) -> Option<(sdf::SpecType, usize)> {
        self.spec_at.get(index).copied().flatten()
    }

    /// The path index of child `name` of path index `parent` (a property when
    /// `property`), trying `hint` first (the sibling after the child found before).
    fn child_named(
        &self,
        parent: usize,
        name: &str,
        property: bool,
        hint: Option<usize>,
    ) -> Option<usize> {
        let tree = self.tree.as_ref()?;
        let is = |c: usize| {
            let e = tree.element[c];
            (e < 0) == property
                && self
                    .tokens
                    .get(e.unsigned_abs() as usize)
                    .is_some_and(|t| t.as_str() == name)
        };
        // From the hint to the last child, then from the first: children are mostly
        // listed in the order their paths are.
        let from_hint = std::iter::successors(hint, |&c| match tree.next_sibling.get(c) {
            Some(&n) if n != NO_PATH => Some(n as usize),
            _ => None,
        });
        from_hint
            .chain(tree.children(parent).take_while(|&c| Some(c) != hint))
            .find(|&c| is(c))
    }

    /// The sibling after path index `index` (a hint for [`CrateLayer::child_named`]).
    fn next_of(&self, index: usize) -> Option<usize> {
        let n = *self.tree.as_ref()?.next_sibling.get(index)?;
        (n != NO_PATH).then_some(n as usize)
    }

    /// The kind of the prim at path index `index`, as [`Reader::kind_of`] reads it.
    pub(super) fn kind_at(&self, index: usize) -> Option<PrimKind> {
        let (_, start) = self.spec_of(index)?;
        let path = self.paths.get(index)?;
        let t = self
            .field_in(
                start,
                self.attribute_fields[0],
                path,
                sdf::FieldKey::TypeName.as_str(),
            )
            .ok()??;
        prim_kind(t.as_ref())
    }

    /// The `default` of property `name` of the prim at path index `prim`.
    pub(super) fn property_default(
        &self,
        prim: usize,
        name: &str,
    ) -> Result<Option<sdf::Value>, String> {
        let Some(index) = self.child_named(prim, name, true, None) else {
            return Ok(None);
        };
        let (Some((_, start)), Some(path)) = (self.spec_of(index), self.paths.get(index)) else {
            return Ok(None);
        };
        default_of(self.field_in(
            start,
            self.attribute_fields[1],
            path,
            sdf::FieldKey::Default.as_str(),
        ))
    }

    /// The connection targets of property `name` of the prim at path index `prim`.
    pub(super) fn property_targets(&self, prim: usize, name: &str) -> Vec<sdf::Path> {
        let Some(index) = self.child_named(prim, name, true, None) else {
            return Vec::new();
        };
        let (Some((_, start)), Some(path)) = (self.spec_of(index), self.paths.get(index)) else {
            return Vec::new();
        };
        targets_of(self.field_in(
            start,
            self.attribute_fields[2],
            path,
            sdf::FieldKey::ConnectionPaths.as_str(),
        ))
    }

    /// The `inputs:` attributes of the prim at path index `prim`, as [`Reader::inputs`]
    /// gives them, each with its path index; those without a spec are left out, as
    /// [`Reader::attr_fields`] would leave them.
    pub(super) fn inputs_at(&self, prim: usize) -> Vec<InputAt<'_>> {
        let (Some((_, start)), Some(path)) = (self.spec_of(prim), self.paths.get(prim)) else {
            return Vec::new();
        };
        // The property names, borrowed from the file's tokens when decoded here.
        let field = self.field_index(start, self.prim_fields[2]);
        let read;
        let names: Vec<&str> = match field.and_then(|i| self.own_token_texts(i)) {
            Some(names) => names,
            None => {
                let value =
                    field.map_or(Ok(None), |i| self.read_field(i, path, "propertyChildren"));
                read = tokens_of(value);
                read.iter().map(|t| t.as_str()).collect()
            }
        };
        let mut out = Vec::with_capacity(names.len());
        let mut hint = None;
        for (name, input) in distinct_inputs(&names) {
            let Some(index) = self.child_named(prim, name, true, hint) else {
                continue;
            };
            hint = self.next_of(index);
            // The input's name from the file's own token (the child's element), so that
            // it is not copied.
            let input = self
                .tree
                .as_ref()
                .and_then(|tree| tree.element.get(index))
                .and_then(|&e| self.tokens.get(e.unsigned_abs() as usize))
                .and_then(|t| t.as_str().strip_prefix("inputs:"))
                .filter(|own| *own == input)
                .map_or_else(|| Cow::Owned(input.to_string()), Cow::Borrowed);
            if let Some(p) = self.paths.get(index) {
                out.push((Cow::Borrowed(p), input, Some(index)));
            }
        }
        out
    }

    /// What the reader reads of the attribute at path index `index`, or nothing when its
    /// spec is not an attribute's.
    pub(super) fn attribute_at(&self, index: usize) -> Option<AttrFields> {
        let (ty, start) = self.spec_of(index)?;
        if ty != sdf::SpecType::Attribute {
            return None;
        }
        Some(self.attribute_fields_of(start, self.paths.get(index)?))
    }

    /// [`flat_prims`] by path index, each prim with its path index: one spec found per
    /// prim, its children found among its path's children. Nothing when there is no tree
    /// or a child's name is no identifier (then [`flat_prims`] decides); `Some(None)` when
    /// something composes.
    pub(super) fn flat_prims_by_index(&self) -> Option<Option<(Vec<sdf::Path>, Vec<usize>)>> {
        let tree = self.tree.as_ref()?;
        let Some((_, start)) = self.spec_of(tree.root) else {
            return Some(None);
        };
        if self
            .set_fields(start)
            .filter_map(|(_, token)| self.field_names.get(&token))
            .any(|name| ROOT_CHANGES.contains(&name.as_str()))
        {
            return Some(None);
        }
        // A prim's children by path index; `Err` when a name is no identifier.
        let children = |index: usize, start: usize| -> Result<Option<Vec<usize>>, ()> {
            let path = &self.paths[index];
            let names = match self.field_in(start, self.prim_fields[1], path, "primChildren") {
                Err(_) => return Ok(None),
                Ok(None) => return Ok(Some(Vec::new())),
                Ok(Some(v)) => match v.into_owned() {
                    sdf::Value::TokenVec(names) if all_differ(&names) => names,
                    _ => return Ok(None),
                },
            };
            let mut out = Vec::with_capacity(names.len());
            let mut hint = None;
            for n in &names {
                if !sdf::Path::is_valid_identifier(n.as_str()) {
                    return Err(());
                }
                match self.child_named(index, n.as_str(), false, hint) {
                    Some(c) => {
                        hint = self.next_of(c);
                        out.push(c);
                    }
                    // No path of that text, so no spec: not a flat prim.
                    None => return Ok(None),
                }
            }
            Ok(Some(out))
        };
        let Some(mut stack) = children(tree.root, start).ok()? else {
            return Some(None);
        };
        stack.reverse();
        let mut paths = Vec::new();
        let mut indices = Vec::new();
        while let Some(index) = stack.pop() {
            let Some((sdf::SpecType::Prim, start)) = self.spec_of(index) else {
                return Some(None);
            };
            let within = self
                .set_fields(start)
                .filter_map(|(_, token)| self.field_names.get(&token))
                .all(|name| PRIM_KEEPS.contains(&name.as_str()));
            if !within {
                return Some(None);
            }
            let path = &self.paths[index];
            match self
                .field_in(start, self.prim_fields[0], path, "specifier")
                .ok()
                .flatten()
                .as_deref()
            {
                Some(sdf::Value::Specifier(sdf::Specifier::Def)) => {}
                _ => return Some(None),
            }
            let Some(mut kids) = children(index, start).ok()? else {
                return Some(None);
            };
            kids.reverse();
            stack.extend(kids);
            paths.push(path.clone());
            indices.push(index);
        }
        Some(Some((paths, indices)))
    }
}

impl Specs for CrateLayer {
    fn as_crate(&self) -> Option<&CrateLayer> {
        Some(self)
    }

    fn drop_soon(self: Box<Self>) {
        #[cfg(feature = "parallel")]
        if crate::schedule::pool_can_help() {
            rayon::spawn(move || drop(self));
        }
    }

    fn spec_type(&self, path: &sdf::Path) -> Option<sdf::SpecType> {
        self.spec(path).map(|s| s.0)
    }

    fn try_field(
        &self,
        path: &sdf::Path,
        field: &str,
    ) -> Result<Option<std::borrow::Cow<'_, sdf::Value>>, sdf::DataError> {
        let Some((_, start)) = self.spec(path) else {
            return Ok(None);
        };
        self.field_in(start, self.names.get(field).copied(), path, field)
    }

    /// One look-up and one walk of the spec's field set for the four fields.
    fn attribute(&self, path: &sdf::Path) -> Option<AttrFields> {
        let (ty, start) = self.spec(path)?;
        (ty == sdf::SpecType::Attribute).then(|| self.attribute_fields_of(start, path))
    }

    /// One look-up and one walk of the spec's field set, comparing names without copying
    /// them.
    fn fields_within(&self, path: &sdf::Path, allowed: &[&str]) -> Option<bool> {
        let (_, start) = self.spec(path)?;
        Some(
            self.set_fields(start)
                .filter_map(|(_, token)| self.field_names.get(&token))
                .all(|name| allowed.contains(&name.as_str())),
        )
    }

    fn list_fields(&self, path: &sdf::Path) -> Option<Vec<String>> {
        let (_, start) = self.spec(path)?;
        Some(
            self.set_fields(start)
                .filter_map(|(_, token)| self.field_names.get(&token).cloned())
                .collect(),
        )
    }
}

/// Checks the crate file tables and values the reader decodes itself against `openusd`'s
/// reading of the same file: every table equal, and every value decoded here (tokens,
/// strings, numbers, 3-vectors of floats, specifiers, path list operations) equal to
/// `openusd`'s decoding of that field; and the prims and attributes found by path index
/// as found by path text. The number of values
/// compared, or the first difference (or a file whose tables are not decoded here, or that
/// `openusd` does not read).
#[cfg(feature = "testkit")]
pub fn crate_values_agree(bytes: &[u8]) -> Result<usize, String> {
    let ours = CrateTables::decode(bytes).ok_or("the tables are not decoded here")?;
    let layer = CrateLayer::open(bytes).ok_or("the crate file does not open")?;
    let compared = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let mut file =
            CrateFile::open(io::Cursor::new(Arc::from(bytes))).map_err(|e| format!("{e:#}"))?;
        file.validate().map_err(|e| format!("{e:#}"))?;
        let v = file.version();
        if ours.version != [v.major, v.minor, v.patch] {
            return Err("versions differ".to_string());
        }
        let tokens: Vec<&str> = ours.tokens.iter().map(|t| t.as_str()).collect();
        if tokens != file.tokens || ours.strings != file.strings {
            return Err("tokens or strings differ".to_string());
        }
        let fields: Vec<(usize, u64)> = file
            .fields
            .iter()
            .map(|f| (f.token_index, f.value_rep.0))
            .collect();
        if ours.fields != fields {
            return Err("fields differ".to_string());
        }
        if ours.fieldsets != file.fieldsets {
            return Err("field sets differ".to_string());
        }
        if ours.paths != file.paths {
            return Err("paths differ".to_string());
        }
        let specs: Vec<(usize, usize, sdf::SpecType)> = file
            .specs
            .iter()
            .map(|s| (s.path_index, s.fieldset_index, s.spec_type))
            .collect();
        if ours.specs != specs {
            return Err("specs differ".to_string());
        }
        let mut checked = 0;
        for i in 0..file.fields.len() {
            let Some(own) = layer.own_value(i) else {
                continue;
            };
            let rep = file.fields[i].value_rep;
            let theirs = file.value(rep).map_err(|e| format!("field {i}: {e:#}"))?;
            if own != theirs {
                return Err(format!("field {i}: {own:?} against {theirs:?}"));
            }
            checked += 1;
        }
        walks_agree(&layer)?;
        Ok(checked)
    }));
    compared.unwrap_or_else(|_| Err("openusd failed on this file".to_string()))
}

/// Whether crate file `layer`, walked by path index, gives what it gives looked up by
/// path text: the same prims, kinds, inputs and what is read of them, `info:` texts and
/// terminal connections (nothing to compare when there is no path tree). Only values
/// decoded here are read (`openusd` may fail on a damaged file's); each side is read on
/// its own.
#[cfg(feature = "testkit")]
fn walks_agree(layer: &CrateLayer) -> Result<(), String> {
    fn caught<T>(f: impl FnOnce() -> T) -> Option<T> {
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).ok()
    }
    layer
        .decoded_only
        .store(true, std::sync::atomic::Ordering::Relaxed);
    let walked = caught(|| layer.flat_prims_by_index());
    if walked.as_ref().is_some_and(Option::is_none) {
        return Ok(());
    }
    let walked = walked.flatten();
    if caught(|| flat_prims(layer)) != walked.as_ref().map(|w| w.as_ref().map(|(p, _)| p.clone())) {
        return Err("the prims walked by index differ".to_string());
    }
    let Some(Some((prims, indices))) = walked else {
        return Ok(());
    };
    let seen = |a: &AttrFields| {
        format!(
            "{} {:?} {:?} {}",
            a.type_name, a.default, a.targets, a.samples
        )
    };
    for (prim, &index) in prims.iter().zip(&indices) {
        let kind = caught(|| {
            layer
                .try_field(prim, sdf::FieldKey::TypeName.as_str())
                .ok()
                .flatten()
                .and_then(|t| prim_kind(t.as_ref()))
        });
        if caught(|| layer.kind_at(index)) != kind {
            return Err(format!("`{prim}`: kinds differ"));
        }
        for name in [
            "info:id",
            "info:implementationSource",
            "outputs:surface",
            "outputs:ri:surface",
        ] {
            let Some(path) = property_path(prim, name) else {
                continue;
            };
            let by_text = caught(|| {
                (
                    default_of(layer.try_field(&path, sdf::FieldKey::Default.as_str())),
                    targets_of(layer.try_field(&path, sdf::FieldKey::ConnectionPaths.as_str())),
                )
            });
            let by_index = caught(|| {
                (
                    layer.property_default(index, name),
                    layer.property_targets(index, name),
                )
            });
            if by_text != by_index {
                return Err(format!("`{path}`: read by index, it differs"));
            }
        }
        let by_text = caught(|| {
            let names = tokens_of(layer.try_field(prim, "propertyChildren"));
            let mut unique = rustc_hash::FxHashSet::default();
            names
                .iter()
                .filter_map(|n| {
                    let input = n.as_str().strip_prefix("inputs:")?;
                    unique.insert(input).then_some(())?;
                    let path = property_path(prim, n.as_str())?;
                    let a = layer.attribute(&path)?;
                    Some(format!("{path} {input} {}", seen(&a)))
                })
                .collect::<Vec<String>>()
        });
        let by_index = caught(|| {
            layer
                .inputs_at(index)
                .into_iter()
                .filter_map(|(path, input, at)| {
                    let a = layer.attribute_at(at?)?;
                    Some(format!("{path} {input} {}", seen(&a)))
                })
                .collect::<Vec<String>>()
        });
        if by_text != by_index {
            return Err(format!("`{prim}`: the inputs read by index differ"));
        }
    }
    Ok(())
}
