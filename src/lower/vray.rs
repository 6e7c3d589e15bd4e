//! (in progress)
use super::{Graph, Lower};
use crate::diag::Error;
use crate::ir::Cl;

/// Lower the terminal.
pub fn lower<G: Graph>(_cx: &mut Lower<'_, G>, _n: G::Id) -> Result<Cl, Error> {
    Ok(None)
}
