//! Front ends: readers that turn files into definitions ([`args`], [`oso`]) and networks
//! ([`rib`], [`json`]), and [`source`]: reading their bytes from files and streams within
//! bounds.

pub mod args;
pub mod json;
pub mod oso;
pub mod rib;
pub mod source;
