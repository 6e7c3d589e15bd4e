//! Unit tests of the library's internals for this stage (reached through the `testkit` feature).

mod action;
mod ast;
mod error;
mod ext;
mod lexer;
