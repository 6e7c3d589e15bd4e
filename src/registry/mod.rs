//! The shader registry: definitions from `.args` and `.oso`, lookup by shader id, and the
//! per-type vstruct tables.
//!
//! A [`Registry`] is a plain value (no process-wide cache). Building one only lists the
//! search path; each shader id is parsed the first time it is looked up and cached, and its
//! [`VstructTables`] are built the first time they are asked for. Lookups take `&self` and are
//! thread-safe (the registry is `Send + Sync`).
//!
//! Search order: the explicit paths of [`RegistryOptions::paths`] in the
//! order given (directories scanned recursively, files in byte-wise sorted path order), then
//! the colon-separated entries of `VSTRUCTC_ARGS_PATH`, then the crate's own `args/` folder
//! compiled into the binary (named `<embedded>/X.args`). Definitions added in memory
//! ([`Registry::add_definition`]) come before all of these.
//!
//! Choices where the spec is silent:
//!
//! * RG001 for a definition that only shadows an *embedded* one is a `note` (the embedded
//!   definitions are a fallback, replacing them is the point of `--args`).
//! * RG001 and RG002 are reported when the id is first looked up, not when the search path is
//!   listed, so that unrelated shadowing in a large install does not flood every command.
//! * If the chosen definition is rejected (an error), the id has no definition: the other
//!   candidate is not used in its place.
//! * A missing or unreadable explicit path is AR005 (error); a missing `VSTRUCTC_ARGS_PATH`
//!   entry is AR005 as a warning.
//!
//! Folder walks and definition files are bounded, since a definitions folder may be shared
//! or hostile:
//!
//! * The walk follows symlinked folders but keeps the set of folders visited (device and
//!   inode): a symlink that leads back to a folder above it is RG003 (warning, naming the link
//!   and the folder), not followed, and the walk goes on; a folder reached a second time by
//!   another way is skipped (RG003 note), so its files are not listed twice.
//! * Only regular files are read: an entry named `*.args` or `*.oso` that is a FIFO, a device
//!   or a socket is RG004 (warning) and skipped; an explicit path or `VSTRUCTC_ARGS_PATH`
//!   entry that is one is RG004 as an error, respectively a warning.
//! * One definition file holds at most [`Limits::definition_file_bytes`] (64 MiB by default,
//!   [`RegistryOptions::limits`]); a larger one is LM001 (error naming the limit and the
//!   file's size) when its id is loaded, and the id has no definition.

mod param_types;
pub mod tables;

pub(crate) use crate::model::IndexedDefinition;
pub(crate) use crate::model::NumericRange;
pub use crate::model::{
    CondSource, Definition, Direction, MemberDecl, Metadata, Property, SourceKind,
};
pub use tables::{CondEntry, InputHead, InputMember, OutputHead, OutputMember, VstructTables};

use crate::diag::{Diagnostic, Diagnostics, Error, Location, Severity};
use crate::front::args::{ArgsOptions, parse_args_with};
use crate::front::oso::parse_oso;
use crate::front::source::{ReadError, kind_name, open_regular, read_regular_file};
use crate::limits::{Limit, LimitExceeded, Limits};
use rustc_hash::FxHashMap as HashMap;
use std::collections::BTreeMap;
use std::io::{BufRead, Read};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock};

/// Environment variable with extra definition folders (colon-separated).
pub(crate) const ARGS_PATH_ENV: &str = "VSTRUCTC_ARGS_PATH";

/// Pseudo-directory naming embedded definitions in paths and diagnostics.
pub(crate) const EMBEDDED_PREFIX: &str = "<embedded>";

/// How much of an `.oso` file is read to find its shader name while listing.
const OSO_PEEK_BYTES: u64 = 64 << 10;

/// The crate's own `args/` files compiled into the binary: `(path relative to args/, bytes)`,
/// in byte-wise sorted path order.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) fn embedded_files() -> &'static [(&'static str, &'static [u8])] {
    include!(concat!(env!("OUT_DIR"), "/embedded_args.rs"))
}

/// Which definition wins when a shader id has both an `.oso` and an `.args` definition.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Prefer {
    /// Compiled OSL first (the reference's order `[oso, args]`).
    #[default]
    Oso,
    /// `.args` first.
    Args,
}

/// How a [`Registry`] finds its definitions.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RegistryOptions {
    /// Explicit definition files or folders, searched first, in this order.
    pub paths: Vec<PathBuf>,
    /// Also search the folders named by `VSTRUCTC_ARGS_PATH`.
    pub use_env: bool,
    /// Also search the definitions compiled into the binary.
    pub use_embedded: bool,
    /// Priority between `.oso` and `.args` definitions of one id.
    pub prefer: Prefer,
    /// Options of the `.args` reader (extensions).
    pub args: ArgsOptions,
    /// Bounds; a definition file holds at most [`Limits::definition_file_bytes`].
    pub limits: Limits,
}

impl Default for RegistryOptions {
    /// No explicit paths; environment and embedded definitions on; `.oso` preferred.
    fn default() -> Self {
        RegistryOptions {
            paths: Vec::new(),
            use_env: true,
            use_embedded: true,
            prefer: Prefer::Oso,
            args: ArgsOptions::default(),
            limits: Limits::default(),
        }
    }
}

impl RegistryOptions {
    /// Only the given paths: no environment variable, no embedded definitions (for tests and
    /// tools that must not depend on the machine).
    pub fn only(paths: impl IntoIterator<Item = impl Into<PathBuf>>) -> Self {
        RegistryOptions {
            paths: paths.into_iter().map(Into::into).collect(),
            use_env: false,
            use_embedded: false,
            ..RegistryOptions::default()
        }
    }
}

/// Where a candidate definition comes from.
#[derive(Debug, Clone)]
enum Origin {
    File(PathBuf),
    Embedded(&'static [u8]),
    Memory(Arc<Definition>, Vec<Diagnostic>),
}

/// One definition file (or in-memory definition) that provides an id.
#[derive(Debug, Clone)]
struct Candidate {
    kind: SourceKind,
    /// Path as shown to users.
    name: Arc<str>,
    origin: Origin,
}

impl Candidate {
    fn is_embedded(&self) -> bool {
        matches!(self.origin, Origin::Embedded(_))
    }
}

/// A loaded id: its definition (if any) and the diagnostics of loading it.
#[derive(Debug)]
struct Loaded {
    def: Option<Arc<Definition>>,
    diags: Vec<Diagnostic>,
}

/// Tables of an id and the diagnostics of building them.
#[derive(Debug)]
struct Tabled {
    tables: Option<Arc<VstructTables>>,
    diags: Vec<Diagnostic>,
}

/// Lazily filled state of one id.
#[derive(Debug, Default)]
struct Entry {
    loaded: OnceLock<Loaded>,
    tables: OnceLock<Tabled>,
    indexed: OnceLock<Arc<IndexedDefinition>>,
}

/// Shader definitions by id, loaded lazily, with their vstruct tables.
#[derive(Debug)]
pub struct Registry {
    options: RegistryOptions,
    /// Every candidate per id, in search order.
    index: BTreeMap<String, Vec<Candidate>>,
    /// Diagnostics from listing the search path.
    index_diags: Vec<Diagnostic>,
    /// Loaded state per id (Fx hashing: the writers and lowering look ids up per parameter).
    entries: Mutex<HashMap<String, Arc<Entry>>>,
}

impl Default for Registry {
    /// Same as [`Registry::new`] with default options.
    fn default() -> Self {
        Registry::new(RegistryOptions::default())
    }
}

impl Registry {
    /// Lists the search path of `options` (reading no definition yet).
    pub fn new(options: RegistryOptions) -> Self {
        let mut reg = Registry {
            options,
            index: BTreeMap::new(),
            index_diags: Vec::new(),
            entries: Mutex::new(HashMap::default()),
        };
        for p in reg.options.paths.clone() {
            reg.index_path(&p, Severity::Error);
        }
        if reg.options.use_env
            && let Ok(var) = std::env::var(ARGS_PATH_ENV)
        {
            for entry in var.split(':').filter(|e| !e.is_empty()) {
                reg.index_path(Path::new(entry), Severity::Warning);
            }
        }
        if reg.options.use_embedded {
            for (rel, bytes) in embedded_files() {
                let id = file_stem(rel);
                let name: Arc<str> = Arc::from(format!("{EMBEDDED_PREFIX}/{rel}"));
                reg.push_candidate(
                    id,
                    Candidate {
                        kind: SourceKind::Args,
                        name,
                        origin: Origin::Embedded(bytes),
                    },
                );
            }
        }
        reg
    }

    /// A registry with only the embedded definitions (no explicit paths, no environment).
    pub fn embedded() -> Self {
        Registry::new(RegistryOptions {
            use_env: false,
            ..RegistryOptions::default()
        })
    }

    /// The options this registry was built with.
    pub fn options(&self) -> &RegistryOptions {
        &self.options
    }

    fn push_candidate(&mut self, id: String, c: Candidate) {
        self.index.entry(id).or_default().push(c);
    }

    /// Adds a file or (recursively) a folder to the end of the search path. `missing` is the
    /// severity of a path that cannot be used (error for explicit paths, warning for
    /// environment entries).
    fn index_path(&mut self, path: &Path, missing: Severity) {
        let at = || Location::file(path.to_string_lossy().as_ref());
        match std::fs::metadata(path) {
            Ok(m) if m.is_dir() => {
                let mut walk = FolderWalk::new(missing);
                walk.run(path);
                self.index_diags.append(&mut walk.diags);
                walk.files.sort_by(|a, b| {
                    a.as_os_str()
                        .as_encoded_bytes()
                        .cmp(b.as_os_str().as_encoded_bytes())
                });
                for f in walk.files {
                    self.index_file(&f, missing);
                }
            }
            Ok(m) if m.is_file() => self.index_file(path, missing),
            Ok(m) => self
                .index_diags
                .push(not_regular(missing, kind_name(m.file_type())).at(at())),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => self.index_diags.push(
                Diagnostic::new(missing, "AR005", "no such definition file or folder").at(at()),
            ),
            Err(e) => self
                .index_diags
                .push(Diagnostic::new(missing, "AR005", format!("cannot read: {e}")).at(at())),
        }
    }

    fn index_file(&mut self, path: &Path, severity: Severity) {
        let name: Arc<str> = Arc::from(path.to_string_lossy().as_ref());
        let kind = match path.extension().and_then(|e| e.to_str()) {
            Some("args") => SourceKind::Args,
            Some("oso") => SourceKind::Oso,
            _ => {
                self.index_diags.push(
                    Diagnostic::new(
                        severity,
                        "AR005",
                        "not a definition file (expected a .args or .oso extension)",
                    )
                    .at(Location::file(name)),
                );
                return;
            }
        };
        let stem = file_stem(&name);
        let id = match kind {
            SourceKind::Args => stem,
            SourceKind::Oso => peek_oso_name(path).unwrap_or(stem),
        };
        self.push_candidate(
            id,
            Candidate {
                kind,
                name,
                origin: Origin::File(path.to_path_buf()),
            },
        );
    }

    /// Adds an in-memory definition, ahead of every file of the same kind for its id (for
    /// bridges that have no files). Head normalisation is applied when it is looked up.
    pub fn add_definition(&mut self, def: Definition) {
        self.add_memory(def, Vec::new());
    }

    fn add_memory(&mut self, def: Definition, diags: Vec<Diagnostic>) {
        let id = def.id.clone();
        let c = Candidate {
            kind: def.source,
            name: def.path.clone(),
            origin: Origin::Memory(Arc::new(def), diags),
        };
        self.index.entry(id.clone()).or_default().insert(0, c);
        if let Ok(mut entries) = self.entries.lock() {
            entries.remove(&id);
        }
    }

    /// Parses `.args` text and adds it as definition `id` (path `<memory>/ID.args`). Warnings
    /// are kept with the definition and reported by [`Registry::diagnostics`] once it is
    /// looked up.
    pub fn add_args_text(&mut self, id: &str, text: &str) -> Result<(), Error> {
        let path = format!("<memory>/{id}.args");
        let mut diags = Diagnostics::new();
        let def = parse_args_with(text.as_bytes(), &path, id, &self.options.args, &mut diags)?;
        self.add_memory(def, diags.into_vec());
        Ok(())
    }

    /// Parses `.oso` text and adds it (path `<memory>/oso`); returns the shader id.
    pub fn add_oso_text(&mut self, text: &str) -> Result<String, Error> {
        let mut diags = Diagnostics::new();
        let def = parse_oso(text.as_bytes(), "<memory>/oso", &mut diags)?;
        let id = def.id.clone();
        self.add_memory(def, diags.into_vec());
        Ok(id)
    }

    /// Every id on the search path, sorted.
    pub fn ids(&self) -> Vec<&str> {
        self.index.keys().map(String::as_str).collect()
    }

    /// True if some file or in-memory definition provides `id` (without loading it).
    pub fn contains(&self, id: &str) -> bool {
        self.index.contains_key(id)
    }

    fn entry(&self, id: &str) -> Option<Arc<Entry>> {
        if !self.index.contains_key(id) {
            return None;
        }
        let mut entries = match self.entries.lock() {
            Ok(g) => g,
            Err(poisoned) => poisoned.into_inner(),
        };
        if let Some(entry) = entries.get(id) {
            return Some(entry.clone());
        }
        Some(entries.entry(id.to_string()).or_default().clone())
    }

    fn loaded(&self, id: &str) -> Option<(Arc<Entry>, Option<Arc<Definition>>)> {
        let entry = self.entry(id)?;
        let def = entry.loaded.get_or_init(|| self.load(id)).def.clone();
        Some((entry, def))
    }

    /// The definition of `id` (loading it on first use), after head normalisation, or `None`
    /// if no file provides it or the chosen file was rejected (see [`Registry::diagnostics`]).
    pub fn definition(&self, id: &str) -> Option<Arc<Definition>> {
        self.loaded(id).and_then(|(_, d)| d)
    }

    /// The definition of `id` with its input index (built on first use), for callers that
    /// look inputs up by name many times.
    pub(crate) fn indexed(&self, id: &str) -> Option<Arc<IndexedDefinition>> {
        let (entry, def) = self.loaded(id)?;
        let def = def?;
        Some(
            entry
                .indexed
                .get_or_init(|| Arc::new(IndexedDefinition::new(def)))
                .clone(),
        )
    }

    /// The vstruct tables of `id` (built on first use).
    pub fn tables(&self, id: &str) -> Option<Arc<VstructTables>> {
        let (entry, def) = self.loaded(id)?;
        let def = def?;
        let tabled = entry.tables.get_or_init(|| {
            let mut diags = Vec::new();
            let tables = VstructTables::build_limited(&def, &self.options.limits, &mut diags);
            Tabled {
                tables: Some(Arc::new(tables)),
                diags,
            }
        });
        tabled.tables.clone()
    }

    /// Loads every id and builds every table (for checks that want all diagnostics).
    pub fn load_all(&self) {
        for id in self.index.keys() {
            let _ = self.tables(id);
        }
    }

    /// Diagnostics of listing the search path and of every id loaded so far (definitions and
    /// tables), in the deterministic order of [`Diagnostics::sort`].
    pub fn diagnostics(&self) -> Diagnostics {
        let mut out = Diagnostics::from(self.index_diags.clone());
        let entries: Vec<(String, Arc<Entry>)> = match self.entries.lock() {
            Ok(g) => g.iter().map(|(k, v)| (k.clone(), v.clone())).collect(),
            Err(p) => p
                .into_inner()
                .iter()
                .map(|(k, v)| (k.clone(), v.clone()))
                .collect(),
        };
        let mut entries = entries;
        entries.sort_by(|a, b| a.0.cmp(&b.0));
        for (_, e) in entries {
            if let Some(l) = e.loaded.get() {
                out.extend(l.diags.iter().cloned());
            }
            if let Some(t) = e.tables.get() {
                out.extend(t.diags.iter().cloned());
            }
        }
        out.sort();
        out
    }

    /// The files that provide `id`, in search order, with their kind (for `info` and tools).
    pub fn sources(&self, id: &str) -> Vec<(SourceKind, Arc<str>)> {
        self.index
            .get(id)
            .map(|cs| cs.iter().map(|c| (c.kind, c.name.clone())).collect())
            .unwrap_or_default()
    }

    /// Picks the winning candidate for `id`, reports shadowing, and parses it.
    fn load(&self, id: &str) -> Loaded {
        let mut diags = Vec::new();
        let Some(cands) = self.index.get(id) else {
            return Loaded { def: None, diags };
        };
        let first_args = first_of_kind(cands, SourceKind::Args, &mut diags);
        let first_oso = first_of_kind(cands, SourceKind::Oso, &mut diags);
        let (chosen, shadowed) = match (self.options.prefer, first_oso, first_args) {
            (Prefer::Oso, Some(o), a) => (o, a),
            (Prefer::Args, o, Some(a)) => (a, o),
            (_, Some(o), None) => (o, None),
            (_, None, Some(a)) => (a, None),
            (_, None, None) => return Loaded { def: None, diags },
        };
        if let Some(s) = shadowed {
            diags.push(
                Diagnostic::info(
                    "RG002",
                    format!(
                        "`{id}`: {} shadows {} (priority {})",
                        chosen.name,
                        s.name,
                        match self.options.prefer {
                            Prefer::Oso => "[oso, args]",
                            Prefer::Args => "[args, oso]",
                        }
                    ),
                )
                .at(Location::file(s.name.clone()))
                .with_related("used instead", Location::file(chosen.name.clone())),
            );
        }
        let def = self.parse_candidate(id, chosen, &mut diags);
        Loaded {
            def: def.map(|mut d| {
                tables::normalize_heads(&mut d);
                Arc::new(d)
            }),
            diags,
        }
    }

    fn parse_candidate(
        &self,
        id: &str,
        c: &Candidate,
        diags: &mut Vec<Diagnostic>,
    ) -> Option<Definition> {
        let bytes: std::borrow::Cow<'_, [u8]> = match &c.origin {
            Origin::Memory(def, d) => {
                diags.extend(d.iter().cloned());
                return Some((**def).clone());
            }
            Origin::Embedded(b) => std::borrow::Cow::Borrowed(*b),
            Origin::File(p) => {
                match read_regular_file(p, self.options.limits.definition_file_bytes) {
                    Ok(b) => std::borrow::Cow::Owned(b),
                    Err(e) => {
                        diags.push(read_error(&e).at(Location::file(c.name.clone())));
                        return None;
                    }
                }
            }
        };
        let mut d = Diagnostics::new();
        let result = match c.kind {
            SourceKind::Args => parse_args_with(&bytes, &c.name, id, &self.options.args, &mut d),
            SourceKind::Oso => parse_oso(&bytes, &c.name, &mut d),
        };
        diags.extend(d);
        match result {
            Ok(mut def) => {
                // The id is the one the file was indexed under (the oso peek or the stem).
                def.id = id.to_string();
                let params = (def.inputs.len() + def.outputs.len()) as u64;
                match self.options.limits.check(Limit::ParamsPerNode, params) {
                    Ok(()) => Some(def),
                    Err(e) => {
                        diags.push(e.at(Location::file(c.name.clone())).to_diagnostic());
                        None
                    }
                }
            }
            Err(Error::Input(diag)) => {
                diags.push(*diag);
                None
            }
            Err(e) => {
                diags.push(
                    Diagnostic::error("AR005", e.to_string()).at(Location::file(c.name.clone())),
                );
                None
            }
        }
    }
}

/// The first candidate of `kind`; later ones of the same kind are reported (RG001).
fn first_of_kind<'c>(
    cands: &'c [Candidate],
    kind: SourceKind,
    diags: &mut Vec<Diagnostic>,
) -> Option<&'c Candidate> {
    let mut of_kind = cands.iter().filter(|c| c.kind == kind);
    let first = of_kind.next()?;
    for later in of_kind {
        let severity = if later.is_embedded() {
            Severity::Note
        } else {
            Severity::Warning
        };
        diags.push(
            Diagnostic::new(
                severity,
                "RG001",
                format!(
                    "duplicate definition ignored: {} is shadowed by {}",
                    later.name, first.name
                ),
            )
            .at(Location::file(later.name.clone()))
            .with_related("used instead", Location::file(first.name.clone())),
        );
    }
    Some(first)
}

/// The diagnostic of a definition file that could not be read: RG004 (not a regular file),
/// LM001 (above [`Limits::definition_file_bytes`]) or AR005 (the operating system refused).
fn read_error(e: &ReadError) -> Diagnostic {
    match e {
        ReadError::NotRegular { kind } => not_regular(Severity::Error, kind),
        &ReadError::TooLarge { size, limit, .. } => LimitExceeded {
            limit: Limit::DefinitionFileBytes,
            value: size,
            max: limit,
            location: None,
        }
        .to_diagnostic(),
        ReadError::Io(io) => Diagnostic::error("AR005", format!("cannot read file: {io}")),
    }
}

/// RG004: a definition path that names a FIFO, a device or a socket.
fn not_regular(severity: Severity, kind: &str) -> Diagnostic {
    Diagnostic::new(
        severity,
        "RG004",
        format!("not a regular file but {kind}; only regular files are read as definitions"),
    )
}

/// Identity of a folder, to recognise it when a symlink leads to it again.
#[cfg(unix)]
type FolderKey = (u64, u64);
#[cfg(not(unix))]
type FolderKey = PathBuf;

#[cfg(unix)]
fn folder_key(_: &Path, m: &std::fs::Metadata) -> FolderKey {
    use std::os::unix::fs::MetadataExt;
    (m.dev(), m.ino())
}

#[cfg(not(unix))]
fn folder_key(path: &Path, _: &std::fs::Metadata) -> FolderKey {
    std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf())
}

/// The recursive listing of a definitions folder: `*.args` and `*.oso` regular files (and
/// entries that cannot be examined, reported when loaded), with the walk's diagnostics.
struct FolderWalk {
    files: Vec<PathBuf>,
    diags: Vec<Diagnostic>,
    /// Every folder listed so far, with the path it was first reached by.
    seen: HashMap<FolderKey, PathBuf>,
    /// Severity of a folder that cannot be read.
    unreadable: Severity,
}

impl FolderWalk {
    fn new(unreadable: Severity) -> Self {
        FolderWalk {
            files: Vec::new(),
            diags: Vec::new(),
            seen: HashMap::default(),
            unreadable,
        }
    }

    /// Walks `root` and everything below it (an explicit stack: no recursion).
    fn run(&mut self, root: &Path) {
        if let Ok(m) = std::fs::metadata(root) {
            self.seen.insert(folder_key(root, &m), root.to_path_buf());
        }
        let mut todo = vec![root.to_path_buf()];
        while let Some(dir) = todo.pop() {
            let entries = match std::fs::read_dir(&dir) {
                Ok(entries) => entries,
                Err(e) => {
                    self.cannot_read(&dir, &e);
                    continue;
                }
            };
            let mut paths = Vec::new();
            for entry in entries {
                match entry {
                    Ok(entry) => paths.push(entry.path()),
                    Err(e) => {
                        self.cannot_read(&dir, &e);
                        break;
                    }
                }
            }
            // Sorted, so that which of two ways into one folder is listed (and which one
            // a diagnostic names) does not depend on the order the system returns entries.
            paths.sort_by(|a, b| {
                a.as_os_str()
                    .as_encoded_bytes()
                    .cmp(b.as_os_str().as_encoded_bytes())
            });
            let first_subfolder = todo.len();
            for path in paths {
                self.visit(path, &mut todo);
            }
            // Depth first in sorted order: the stack pops the first subfolder first.
            todo[first_subfolder..].reverse();
        }
    }

    fn cannot_read(&mut self, dir: &Path, e: &std::io::Error) {
        self.diags.push(
            Diagnostic::new(self.unreadable, "AR005", format!("cannot read folder: {e}"))
                .at(Location::file(dir.to_string_lossy().as_ref())),
        );
    }

    /// One folder entry: a folder to list (once), a definition file to keep, or a
    /// definition name on something that is not a regular file.
    fn visit(&mut self, path: PathBuf, todo: &mut Vec<PathBuf>) {
        let is_definition = path.extension().is_some_and(|e| e == "args" || e == "oso");
        let at = || Location::file(path.to_string_lossy().as_ref());
        match std::fs::metadata(&path) {
            Ok(m) if m.is_dir() => match self.seen.get(&folder_key(&path, &m)) {
                Some(first) if path.starts_with(first) => {
                    let d = Diagnostic::warning(
                        "RG003",
                        format!(
                            "symlink loop: `{}` leads back to `{}`; not followed",
                            path.display(),
                            first.display()
                        ),
                    )
                    .at(at());
                    self.diags.push(d);
                }
                Some(first) => {
                    let d = Diagnostic::note(
                        "RG003",
                        format!(
                            "`{}` is the folder `{}`, already listed; not listed again",
                            path.display(),
                            first.display()
                        ),
                    )
                    .at(at());
                    self.diags.push(d);
                }
                None => {
                    self.seen.insert(folder_key(&path, &m), path.clone());
                    todo.push(path);
                }
            },
            Ok(m) if m.is_file() => {
                if is_definition {
                    self.files.push(path);
                }
            }
            Ok(m) => {
                if is_definition {
                    let d = not_regular(Severity::Warning, kind_name(m.file_type())).at(at());
                    self.diags.push(d);
                }
            }
            // A dangling link or an entry that cannot be examined: kept, so that loading its
            // id reports why it cannot be read (AR005).
            Err(_) => {
                if is_definition {
                    self.files.push(path);
                }
            }
        }
    }
}

/// The file stem of a `/`-separated or OS path.
fn file_stem(path: &str) -> String {
    Path::new(path)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// The shader name on the shader line of an `.oso` file, read without parsing the rest.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn peek_oso_name(path: &Path) -> Option<String> {
    // Bounded: a file without line breaks must not be read whole just to list it.
    let (file, _) = open_regular(path).ok()?;
    let reader = std::io::BufReader::new(file.take(OSO_PEEK_BYTES));
    let mut header_seen = false;
    for line in reader.split(b'\n').take(256) {
        let line = line.ok()?;
        let line = String::from_utf8_lossy(&line);
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let mut words = line.split_whitespace();
        let first = words.next()?;
        if !header_seen {
            if first != "OpenShadingLanguage" {
                return None;
            }
            header_seen = true;
            continue;
        }
        return match first {
            "shader" | "surface" | "displacement" | "volume" | "light" => {
                words.next().map(str::to_string)
            }
            _ => None,
        };
    }
    None
}
