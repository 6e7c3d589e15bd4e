//! Back ends: writers for RIB ([`rib`]), JSON ([`json`]), USD ([`usd`]), Graphviz dot ([`dot`]) and images
//! ([`png`]: PNG and PFM), and [`output`]: how any of them reaches a file or standard output
//! safely.

pub mod dot;
pub mod json;
pub mod output;
pub mod png;
pub mod rib;
pub mod usd;

/// Whether a writer asked to use rayon's pool (`parallel`) should format its `pieces` pieces
/// there: with the `parallel` feature, more than one piece and more than one thread, and not
/// from a thread of the pool itself (waiting there for pieces could hold the very thread
/// that would format them).
#[cfg(feature = "parallel")]
fn pool_helps(parallel: bool, pieces: usize) -> bool {
    parallel
        && pieces > 1
        && rayon::current_num_threads() > 1
        && rayon::current_thread_index().is_none()
}
