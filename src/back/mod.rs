//! Back ends: writers for RIB ([`rib`]), JSON ([`json`]), Graphviz dot ([`dot`]) and images ([`png`]: PNG and PFM).

pub mod dot;
pub mod json;
pub mod png;
pub mod rib;
