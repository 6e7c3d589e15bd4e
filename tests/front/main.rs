//! Readers and writers: `.args` and `.oso` definitions (including the shipped ones and
//! their generator), RIB and JSON networks in and out, and nothing lost on the way.

#[macro_use]
#[path = "../common/mod.rs"]
mod common;

mod args_elements;
mod args_fixtures;
mod args_malformed;
mod json_reader;
mod json_writer;
mod no_lost_data;
mod oso_fuzz;
mod oso_reader;
mod own_args;
mod own_args_gen;
mod rib_examples;
mod rib_fixtures;
mod rib_reader;
mod rib_writer;
mod unit;
