//! Unit tests of the library's internals for this stage (reached through the `testkit` feature).

mod font;
mod packs;
mod preview;
mod vmath;
