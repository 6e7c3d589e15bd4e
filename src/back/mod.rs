//! Back ends: writers for RIB ([`rib`]), JSON ([`json`]), Graphviz dot and images.

pub mod dot;
pub mod json;
pub mod rib;
