//! Definitions and networks: the registry (search paths, vstruct tables), the network API,
//! vstruct resolution (rules, examples, the golden network) and its linear scaling; and the
//! import layering of the library's sources (`layers`).

#[macro_use]
#[path = "../common/mod.rs"]
mod common;

mod check;
mod examples;
mod golden;
mod large_scene;
mod layers;
mod network_api;
mod registry_search;
mod registry_tables;
mod rules;
mod scale;
mod unit;
mod usd;
mod usd_strings;
