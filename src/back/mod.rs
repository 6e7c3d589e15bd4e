//! Back ends: writers for RIB ([`rib`]), JSON ([`json`]), USD ([`usd`]), Graphviz dot ([`dot`]) and images
//! ([`png`]: PNG and PFM), and [`output`]: how any of them reaches a file or standard output
//! safely.

pub mod dot;
pub mod json;
pub mod output;
pub mod png;
pub mod rib;
pub mod usd;
