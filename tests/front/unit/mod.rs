//! Unit tests of the library's internals for this stage (reached through the `testkit` feature).

mod args;
mod json;
mod json_writer;
mod oso;
#[cfg(unix)]
mod output;
mod rib;
mod rib_lexer;
mod rib_writer;
mod source;
