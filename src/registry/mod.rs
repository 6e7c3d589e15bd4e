//! The shader registry: definitions from `.args` and `.oso`, lookup by shader id, and the
//! per-type vstruct tables (spec formats.md §1, vstruct.md §2).

pub mod model;
pub mod tables;

pub use model::{CondSource, Definition, Direction, MemberDecl, Property, SourceKind};
