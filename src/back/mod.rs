//! Back ends: writers for RIB ([`rib`]), JSON ([`json`]), Graphviz dot and images.

pub mod json;
pub mod rib;
