//! Unit tests of `resolve::plan` (`src/resolve/plan.rs`).

use std::sync::Arc;
use vstructc::Value;
use vstructc::network::{Network, Slot, name_hash};
use vstructc::resolve::plan::*;

fn encoded(value: Option<Value>, connected: bool) -> Vec<u8> {
    let mut net = Network::new();
    let up = net.add_node("up", "PxrFractal");
    let n = net.add_node("n", "PxrLayer");
    if let Some(v) = value {
        net.set_param(n, "p", v);
    }
    if connected {
        net.connect(n, "p", up, "resultF");
    }
    let mut out = Vec::new();
    let param = net[n].param("p");
    encode_param(&mut out, param);
    out
}

#[test]
fn states_a_conditional_can_tell_apart_encode_differently() {
    let states = [
        encoded(None, false),
        encoded(None, true),
        encoded(Some(Value::Int(1)), false),
        encoded(Some(Value::Int(1)), true),
        encoded(Some(Value::Int(0)), false),
        encoded(Some(Value::Float(0.0)), false),
        encoded(Some(Value::Float(-0.0)), false),
        encoded(Some(Value::Float(1.0)), false),
        encoded(Some(Value::Str("1".into())), false),
        encoded(Some(Value::Str("10".into())), false),
        encoded(Some(Value::Token("1".into())), false),
        encoded(Some(Value::Bool(true)), false),
    ];
    for (i, a) in states.iter().enumerate() {
        for b in &states[i + 1..] {
            assert_ne!(a, b);
        }
    }
    assert_eq!(
        encoded(Some(Value::Int(7)), true),
        encoded(Some(Value::Int(7)), true)
    );
}

#[test]
fn scanning_and_looking_up_find_the_same_slots() {
    let mut net = Network::new();
    let n = net.add_node("n", "PxrLayer");
    let mut set = NameSet::default();
    for name in ["a", "b", "c", "d", "e", "b"] {
        set.insert(Arc::from(name));
    }
    assert_eq!(set.names().count(), 5);
    let mut repeated = NameSet::default();
    for name in ["a", "b", "a"] {
        repeated.push(Arc::from(name));
    }
    assert_eq!(repeated.names().count(), 3);
    let mut other = Network::new();
    let m = other.add_node("m", "PxrLayer");
    other.set_param(m, "a", Value::Int(0));
    let mut slots = Vec::new();
    repeated.find_in(&other, m, &mut slots);
    assert_eq!(
        slots,
        [
            Slot::At(0),
            Slot::Missing {
                hash: name_hash("b")
            },
            Slot::At(0)
        ],
        "both occurrences found"
    );
    let mut scanned = Vec::new();
    let mut looked_up = Vec::new();
    for (k, name) in ["x", "d", "y", "a", "z", "w", "v"].into_iter().enumerate() {
        net.set_param(n, name, Value::Int(k as i32));
        set.find_in(&net, n, &mut scanned);
        let by_lookup = set.names().map(|(m, h)| net.slot_of(n, m, *h));
        looked_up.clear();
        looked_up.extend(by_lookup);
        assert_eq!(scanned, looked_up, "after adding {name}");
    }
    assert_eq!(scanned[0], Slot::At(3));
    assert_eq!(scanned[3], Slot::At(1));
}

#[test]
fn the_cache_is_bounded() {
    let mut cache = DecisionCache::default();
    let mut reads = NameSet::default();
    reads.insert(Arc::from("p"));
    let plan = Plan {
        id: 0,
        members: Vec::new(),
        properties: NameSet::default(),
        reads,
    };
    let mut net = Network::new();
    let n = net.add_node("n", "PxrLayer");
    for i in 0..MAX_CACHED as i32 + 10 {
        net.set_param(n, "p", Value::Int(i));
        let miss = cache
            .lookup(&plan, 0, &net, n)
            .err()
            .expect("a new state misses");
        cache.insert(miss, Arc::new(Decision::default()));
    }
    assert_eq!(cache.cached(), MAX_CACHED);
    net.set_param(n, "p", Value::Int(3));
    assert!(cache.lookup(&plan, 0, &net, n).is_ok());
}
