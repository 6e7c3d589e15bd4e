//! RenderMan `.args` reader (spec formats.md §2). (in progress)
//!
//! Interface contract: [`parse_args`] reads one file's bytes into a [`Definition`] whose id is
//! given by the caller (the file stem). Warnings and infos go to `diags`; a condition that
//! rejects the file is returned as `Err` (with code, file, line and column).

use crate::diag::{Diagnostic, Diagnostics, Error, Location};
use crate::registry::Definition;

/// Parse an `.args` document.
pub fn parse_args(
    _bytes: &[u8],
    path: &str,
    _id: &str,
    _diags: &mut Diagnostics,
) -> Result<Definition, Error> {
    Err(
        Diagnostic::error("AR001", "the .args reader is not implemented yet")
            .at(Location::file(path))
            .into(),
    )
}
