//! Unit tests of the library's internals for this stage (reached through the `testkit` feature).

mod check;
mod diag;
mod limits;
mod network;
mod pipeline;
mod plan;
mod pool;
mod registry;
mod types;
