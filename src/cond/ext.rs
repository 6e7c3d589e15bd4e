//! Opt-in extensions: a small set type parsed from names.
//!
//! Every extension is off by default; without it behaviour is exactly the reference's. The set
//! holds every extension name (language, evaluation, registry and resolver extensions alike,
//! so that `--ext NAME` is validated in one place), the `.args` reader's `args-child-meta`
//! included. The extensions are described in `docs/conditional-language.md` and
//! `docs/resolution.md`.

use std::fmt;
use std::str::FromStr;

/// One opt-in extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Extension {
    /// `else-if`: chained `A if C1 else B if C2 else …` statements.
    ElseIf,
    /// `strict-ne`: `p != literal` is `not (p == literal)` in every case.
    StrictNe,
    /// `token-strings`: string literals compare with token and asset operands by text.
    TokenStrings,
    /// `set-tuples`: `set NUMBER` broadcasts to `color`/`point`/`vector`/`normal`.
    SetTuples,
    /// `copy-convert`: `copy` converts int↔float and broadcasts scalars to triples.
    CopyConvert,
    /// `multi-alias`: `vstructmemberaliases` is a list (registry).
    MultiAlias,
    /// `array-heads`: heads with several connections feed array members (resolver).
    ArrayHeads,
    /// `nested`: members that are themselves input heads are expanded (resolver).
    Nested,
    /// `array-index`: a predicate on `name[i]` reads element `i` of array `name`.
    ArrayIndex,
    /// `args-child-meta`: vstruct metadata as child elements in `.args`.
    ArgsChildMeta,
}

impl Extension {
    /// Every extension, in the order of the specification.
    pub const ALL: [Extension; 10] = [
        Extension::ElseIf,
        Extension::StrictNe,
        Extension::TokenStrings,
        Extension::SetTuples,
        Extension::CopyConvert,
        Extension::MultiAlias,
        Extension::ArrayHeads,
        Extension::Nested,
        Extension::ArrayIndex,
        Extension::ArgsChildMeta,
    ];

    /// The name used on the command line (`--ext NAME`).
    pub fn name(self) -> &'static str {
        match self {
            Extension::ElseIf => "else-if",
            Extension::StrictNe => "strict-ne",
            Extension::TokenStrings => "token-strings",
            Extension::SetTuples => "set-tuples",
            Extension::CopyConvert => "copy-convert",
            Extension::MultiAlias => "multi-alias",
            Extension::ArrayHeads => "array-heads",
            Extension::Nested => "nested",
            Extension::ArrayIndex => "array-index",
            Extension::ArgsChildMeta => "args-child-meta",
        }
    }

    fn bit(self) -> u16 {
        1 << (self as u16)
    }
}

impl fmt::Display for Extension {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Extension {
    type Err = UnknownExtension;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Extension::ALL
            .into_iter()
            .find(|e| e.name() == s)
            .ok_or_else(|| UnknownExtension {
                name: s.to_string(),
            })
    }
}

/// An `--ext` name that is neither an extension nor `all`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UnknownExtension {
    /// The name as given.
    pub name: String,
}

impl fmt::Display for UnknownExtension {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "unknown extension `{}`; valid names are: ", self.name)?;
        for e in Extension::ALL {
            write!(f, "{}, ", e.name())?;
        }
        f.write_str("all")
    }
}

impl std::error::Error for UnknownExtension {}

impl From<UnknownExtension> for crate::diag::Error {
    fn from(e: UnknownExtension) -> Self {
        crate::diag::Error::Usage(e.to_string())
    }
}

/// A set of enabled extensions. The default is the empty set (compat mode).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Extensions {
    bits: u16,
}

impl Extensions {
    /// No extension enabled (compat mode).
    pub const fn none() -> Self {
        Extensions { bits: 0 }
    }

    /// Every extension enabled (`--ext all`).
    pub fn all() -> Self {
        Extension::ALL.into_iter().collect()
    }

    /// Parse `--ext` values. Each value may itself be a comma-separated list; `all` enables
    /// everything. An unknown name is an error that lists the valid ones.
    pub fn from_names<S: AsRef<str>>(
        names: impl IntoIterator<Item = S>,
    ) -> Result<Self, UnknownExtension> {
        let mut set = Extensions::none();
        for value in names {
            for name in value.as_ref().split(',').map(str::trim) {
                if name.is_empty() {
                    continue;
                }
                if name == "all" {
                    set = set.union(Extensions::all());
                } else {
                    set.insert(name.parse()?);
                }
            }
        }
        Ok(set)
    }

    /// True if `ext` is enabled.
    pub fn contains(&self, ext: Extension) -> bool {
        self.bits & ext.bit() != 0
    }

    /// Enable `ext`.
    pub fn insert(&mut self, ext: Extension) {
        self.bits |= ext.bit();
    }

    /// This set with `ext` enabled (builder form).
    pub fn with(mut self, ext: Extension) -> Self {
        self.insert(ext);
        self
    }

    /// Extensions enabled in either set.
    pub fn union(self, other: Extensions) -> Self {
        Extensions {
            bits: self.bits | other.bits,
        }
    }

    /// True if no extension is enabled.
    pub fn is_empty(&self) -> bool {
        self.bits == 0
    }

    /// The enabled extensions in specification order.
    pub fn iter(&self) -> impl Iterator<Item = Extension> + '_ {
        Extension::ALL.into_iter().filter(|e| self.contains(*e))
    }

    /// The enabled extensions' names in specification order.
    pub fn names(&self) -> Vec<&'static str> {
        self.iter().map(Extension::name).collect()
    }
}

impl FromIterator<Extension> for Extensions {
    fn from_iter<I: IntoIterator<Item = Extension>>(iter: I) -> Self {
        let mut set = Extensions::none();
        for e in iter {
            set.insert(e);
        }
        set
    }
}

impl From<Extension> for Extensions {
    fn from(e: Extension) -> Self {
        Extensions::none().with(e)
    }
}

impl fmt::Display for Extensions {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.names().join(","))
    }
}
