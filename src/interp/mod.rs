//! The embedded CPU interpreter (spec closures.md §1, §3): BSDF leaves, eval, sample, albedo.
//! (in progress)
