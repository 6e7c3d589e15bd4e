//! Unit tests of `network` (`src/network/mod.rs`).

use vstructc::Value;
use vstructc::network::*;
use vstructc::types::BaseType;

proptest::proptest! {
    /// The keyed sort gives the order of the plain definition: stable sort of ids by
    /// (handle byte-wise, version). Handles share long prefixes, differ after the eighth
    /// byte, contain NUL and multi-byte characters, and repeat (versions).
    #[test]
    fn nodes_sorted_is_handle_then_version_order(
        handles in proptest::collection::vec("(m1_|m12_)?[a\\x00é]{0,10}", 0..40)
    ) {
        let mut net = Network::new();
        for h in &handles {
            net.add_node(h, "X");
        }
        let mut expected: Vec<NodeId> = net.graph().node_indices().collect();
        expected.sort_by(|&x, &y| {
            let (nx, ny) = (&net.graph()[x], &net.graph()[y]);
            nx.handle().cmp(ny.handle()).then(nx.version().cmp(&ny.version()))
        });
        proptest::prop_assert_eq!(net.nodes_sorted(), expected);
    }
}

fn sourced_node(net: &mut Network) -> NodeId {
    let mut node = Node::new_raw("n", "PxrLayer", RequestKind::Pattern);
    node.set_raw_params(vec![
        Param::from_source(
            "b".into(),
            Some(Value::Int(1)),
            None,
            ParamAt::Unknown,
            Some(0),
        ),
        Param::from_source(
            "a".into(),
            Some(Value::Float(0.5)),
            None,
            ParamAt::Unknown,
            Some(1),
        ),
        Param::from_source("c".into(), None, None, ParamAt::Unknown, Some(2)),
    ]);
    let id = net.insert_node(node);
    let up = net.add_node("u", "PxrFractal");
    net.push_source_links(id, 2, vec![Link::node(up, Some("resultF"))]);
    id
}

#[test]
fn source_params_start_unchanged() {
    let mut net = Network::new();
    let n = sourced_node(&mut net);
    assert!(!net.is_modified(n));
    for p in net[n].params() {
        assert_eq!(p.change(), ParamChange::Unchanged, "{}", p.name());
    }
    // Setting the same value is not a change.
    net.set_param(n, "b", Value::Int(1));
    assert!(!net.is_modified(n));
}

#[test]
fn changes_are_classified() {
    let mut net = Network::new();
    let n = sourced_node(&mut net);
    let up = net.find("u").unwrap();
    net.set_param(n, "b", Value::Int(2));
    assert_eq!(net.param_change(n, "b"), ParamChange::ValueReplaced);
    net.connect(n, "a", up, "resultF");
    assert_eq!(net.param_change(n, "a"), ParamChange::Connected);
    net.clear_connections(n, "c");
    assert_eq!(net.param_change(n, "c"), ParamChange::Removed);
    net.set_param(n, "d", Value::Str("x".into()));
    assert_eq!(net.param_change(n, "d"), ParamChange::Added);
    assert!(net.is_modified(n));
    // Connected parameter keeps its old value.
    assert_eq!(net.value(n, "a"), Some(&Value::Float(0.5)));
}

#[test]
fn disconnecting_a_source_connection_with_value_is_value_replaced() {
    let mut net = Network::new();
    let n = sourced_node(&mut net);
    net.set_param(n, "c", Value::Float(1.0));
    // Still connected: only the unchanged connection is written.
    assert_eq!(net.param_change(n, "c"), ParamChange::Unchanged);
    net.clear_connections(n, "c");
    assert_eq!(net.param_change(n, "c"), ParamChange::ValueReplaced);
}

#[test]
fn added_then_removed_does_not_modify() {
    let mut net = Network::new();
    let n = sourced_node(&mut net);
    net.set_param(n, "tmp", Value::Int(1));
    net.remove_value(n, "tmp");
    assert_eq!(net.param_change(n, "tmp"), ParamChange::Removed);
    assert!(!net.is_modified(n));
}

#[test]
fn edges_mirror_links() {
    let mut net = Network::new();
    let a = net.add_node("a", "X");
    let b = net.add_node("b", "X");
    let d = net.add_node("d", "Y");
    net.connect(d, "x", a, "o1");
    net.connect(d, "x", b, "o2");
    net.push_link(d, "x", Link::missing("ghost", None));
    assert_eq!(net.graph().edge_count(), 2);
    let mut edges: Vec<_> = net.graph().edge_indices().collect();
    edges.sort_by_key(|&e| net.graph()[e].index);
    assert_eq!(net.edge_link(edges[0]).unwrap().1.output(), Some("o1"));
    assert_eq!(net.graph()[edges[1]].index, 1);
    assert_eq!(net.edge_link(edges[1]).unwrap().0.name(), "x");
    net.remove_connection(d, "x", 0);
    let w: Vec<_> = net.graph().edge_weights().cloned().collect();
    assert_eq!(w.len(), 1);
    assert_eq!(w[0].index, 0);
    assert_eq!(net.connections(d, "x")[1].missing_handle(), Some("ghost"));
    net.clear_connections(d, "x");
    assert_eq!(net.graph().edge_count(), 0);
}

/// Small nodes are scanned, larger ones indexed: look-ups find every parameter on both
/// sides of the boundary, whether the node grows one parameter at a time, by a reserved
/// block, or is read with many.
#[test]
fn lookups_across_the_small_node_boundary() {
    let mut net = Network::new();
    let one = net.add_node("one", "X");
    let block = net.add_node("block", "X");
    let names: Vec<String> = (0..3 * SMALL_NODE).map(|i| format!("p{i}")).collect();
    for (k, name) in names.iter().enumerate() {
        net.set_param(one, name, Value::Int(k as i32));
        for (j, seen) in names[..=k].iter().enumerate() {
            assert_eq!(net.value(one, seen), Some(&Value::Int(j as i32)));
        }
        assert!(net[one].param("absent").is_none());
    }
    net.set_param(block, "first", Value::Int(-1));
    net.reserve_params(block, 2 * SMALL_NODE);
    for (k, name) in names.iter().enumerate() {
        let name = Sym::new(name);
        let slot = net.slot_of(block, &name, name_hash(&name));
        net.set_slot(block, slot, name, Value::Int(k as i32));
    }
    assert_eq!(net.value(block, "first"), Some(&Value::Int(-1)));
    for (k, name) in names.iter().enumerate() {
        assert_eq!(net.value(block, name), Some(&Value::Int(k as i32)));
    }
    let mut read = Node::new_raw("read", "X", RequestKind::Pattern);
    read.set_raw_params(
        names
            .iter()
            .enumerate()
            .map(|(k, n)| {
                Param::from_source(
                    n.clone(),
                    Some(Value::Int(k as i32)),
                    None,
                    ParamAt::Unknown,
                    None,
                )
            })
            .collect(),
    );
    let read = net.insert_node(read);
    for (k, name) in names.iter().enumerate() {
        assert_eq!(net.value(read, name), Some(&Value::Int(k as i32)));
    }
    assert_eq!(net[read].key(), "read#0");
    assert_eq!(net[read].handle(), "read");
}

#[test]
fn lookup_and_order() {
    let mut net = Network::new();
    let n = net.add_node("n", "X");
    for name in ["zeta", "alpha", "mid"] {
        net.set_param(n, name, Value::Int(0));
    }
    let by_name: Vec<_> = net[n].params_by_name().map(Param::name).collect();
    assert_eq!(by_name, ["alpha", "mid", "zeta"]);
    let in_order: Vec<_> = net[n].params().map(Param::name).collect();
    assert_eq!(in_order, ["zeta", "alpha", "mid"]);
    assert!(net[n].param("nope").is_none());
    assert_eq!(
        net.value(n, "mid").map(Value::base_type),
        Some(BaseType::Int)
    );
}

#[test]
fn self_loop_and_cycles_are_representable() {
    let mut net = Network::new();
    let a = net.add_node("a", "X");
    let b = net.add_node("b", "X");
    net.connect(a, "in", b, "out");
    net.connect(b, "in", a, "out");
    net.connect(a, "self", a, "out");
    let c = net.upstream_closure(&[a]);
    assert_eq!(c, vec![a, b]);
    assert_eq!(net.upstream_nodes(a), vec![b, a]);
}

/// A resolved scene has millions of member parameters and connections: their sizes are the
/// memory budget of resolution (issue: tens of bytes per member), so they cannot grow back
/// unnoticed.
#[test]
fn params_and_links_stay_compact() {
    assert!(
        std::mem::size_of::<Link>() <= 16,
        "{}",
        std::mem::size_of::<Link>()
    );
    assert!(
        std::mem::size_of::<Param>() <= 40,
        "{}",
        std::mem::size_of::<Param>()
    );
    assert_eq!(std::mem::size_of::<Sym>(), 8);
    // One per parameter occurrence read from RIB.
    assert!(
        std::mem::size_of::<SourceParam>() <= 24,
        "{}",
        std::mem::size_of::<SourceParam>()
    );
    // One per node read from RIB.
    assert!(
        std::mem::size_of::<NodeSource>() <= 72,
        "{}",
        std::mem::size_of::<NodeSource>()
    );
}

/// Every thread keeps the names it met, and they are the process's one copy: names interned
/// first on other threads (each of them first, on several at once) are the same symbols on
/// this one, before and after it met them itself.
#[test]
fn names_are_one_copy_across_threads() {
    let names: Vec<String> = (0..64).map(|i| format!("threadName{i}")).collect();
    let met_here = Sym::new(&names[0]);
    let interned: Vec<Vec<Sym>> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..4)
            .map(|t| {
                let names = &names;
                scope.spawn(move || {
                    // Each thread walks the names from another place, so that each name is
                    // interned first by some thread.
                    let mut syms = vec![None; names.len()];
                    for k in 0..names.len() {
                        let i = (k + t * 16) % names.len();
                        syms[i] = Some(Sym::new(&names[i]));
                    }
                    syms.into_iter().map(Option::unwrap).collect()
                })
            })
            .collect();
        workers.into_iter().map(|w| w.join().unwrap()).collect()
    });
    for (i, name) in names.iter().enumerate() {
        let here = Sym::new(name);
        assert_eq!(here.as_str(), name);
        for syms in &interned {
            assert!(std::ptr::eq(syms[i].as_str(), here.as_str()), "{name}");
        }
    }
    assert!(std::ptr::eq(
        met_here.as_str(),
        Sym::new(&names[0]).as_str()
    ));
}

/// Interned names: one copy per name, equal names are the same symbol, and the order is
/// the names' byte-wise order.
#[test]
fn names_are_interned_once() {
    let a = Sym::new("diffuseGain");
    let b = Sym::new(&String::from("diffuseGain"));
    assert_eq!(a, b);
    assert!(std::ptr::eq(a.as_str(), b.as_str()));
    assert_eq!(a.name_hash(), name_hash("diffuseGain"));
    assert_ne!(a, Sym::new("diffuseGai"));
    assert!(Sym::new("a") < Sym::new("b"));
    let mut net = Network::new();
    let x = net.add_node("x", "X");
    let y = net.add_node("y", "X");
    net.connect(y, "in", x, "resultF");
    net.connect(y, "in", x, "resultG");
    net.push_link(y, "in", Link::missing("ghost", Some("resultF")));
    let links = net.connections(y, "in");
    assert_eq!(links.len(), 3);
    assert!(std::ptr::eq(
        links[0].output().unwrap(),
        links[2].output().unwrap()
    ));
    assert_eq!(links[2].upstream(), Upstream::Missing("ghost"));
    assert_eq!(
        net.remove_connection(y, "in", 1).unwrap().output(),
        Some("resultG")
    );
    assert_eq!(
        net.remove_connection(y, "in", 1).unwrap().missing_handle(),
        Some("ghost")
    );
    assert_eq!(net.connections(y, "in")[0].output(), Some("resultF"));
    assert_eq!(
        net.remove_connection(y, "in", 0).unwrap().upstream_node(),
        Some(x)
    );
    assert!(net.connections(y, "in").is_empty());
}
