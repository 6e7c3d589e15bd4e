//! Front ends: readers that turn files into definitions ([`args`], [`oso`]) and networks
//! ([`rib`], [`json`]).

pub mod args;
pub mod json;
pub mod oso;
pub mod rib;
