//! Whole materials: energy (furnace and albedo), sampling against evaluation (chi-square)
//! and the preview renders against their references.

#[macro_use]
#[path = "../common/mod.rs"]
mod common;

mod energy;
mod examples;
mod leaves_chi2;
mod leaves_furnace;
mod material_chi2;
mod render_regression;
