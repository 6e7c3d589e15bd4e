//! Unit tests of `cond::ext` (`src/cond/ext.rs`).

use vstructc::cond::*;

#[test]
fn names_round_trip_and_are_distinct() {
    for e in Extension::ALL {
        assert_eq!(e.name().parse::<Extension>(), Ok(e));
    }
    let all = Extensions::all();
    assert_eq!(all.iter().count(), Extension::ALL.len());
}

#[test]
fn default_is_empty() {
    let set = Extensions::default();
    assert!(set.is_empty());
    assert!(Extension::ALL.iter().all(|e| !set.contains(*e)));
}

#[test]
fn from_names_accepts_lists_and_all() {
    let set = Extensions::from_names(["else-if", "strict-ne,set-tuples"]).unwrap();
    assert_eq!(set.names(), ["else-if", "strict-ne", "set-tuples"]);
    assert!(!set.contains(Extension::Nested));
    assert_eq!(Extensions::from_names(["all"]).unwrap(), Extensions::all());
}

#[test]
fn unknown_name_lists_valid_ones() {
    let err = Extensions::from_names(["else_if"]).unwrap_err();
    let msg = err.to_string();
    assert!(msg.contains("`else_if`"), "{msg}");
    for e in Extension::ALL {
        assert!(msg.contains(e.name()), "{msg}");
    }
    assert!(msg.ends_with("all"));
    let as_error: vstructc::diag::Error = err.into();
    assert!(matches!(as_error, vstructc::diag::Error::Usage(_)));
}
