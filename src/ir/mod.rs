//! The closure IR (spec closures.md §1.2, §2): parameter program and closure DAG. (in progress)
