//! Compiled OSL `.oso` reader (spec formats.md §4). (in progress)
//!
//! Interface contract: [`parse_oso`] reads one file's bytes into a [`Definition`] whose id is
//! the shader name. Warnings and infos go to `diags`; a condition that rejects the file is
//! returned as `Err` (with code, file, line and column).

use crate::diag::{Diagnostic, Diagnostics, Error, Location};
use crate::registry::Definition;

/// Parse an `.oso` document.
pub fn parse_oso(_bytes: &[u8], path: &str, _diags: &mut Diagnostics) -> Result<Definition, Error> {
    Err(
        Diagnostic::error("OS001", "the .oso reader is not implemented yet")
            .at(Location::file(path))
            .into(),
    )
}
