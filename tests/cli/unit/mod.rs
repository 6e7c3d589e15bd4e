//! Unit tests of the command line's internals (its modules compiled into this binary).

mod group;
mod snippet;
