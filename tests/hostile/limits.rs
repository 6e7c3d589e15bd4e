//! `Limits`: every bound a bridge can set is accepted where it applies (the RIB and JSON
//! readers, the registry, the conditional parser, resolution; the preview's pixel bound is in
//! `render.rs`), and exceeding one is the typed `LimitExceeded` naming the limit, the value
//! and the maximum, at a position when the input has one.

use std::fmt::Write as _;
use vstructc::cond::Extensions;
use vstructc::front::json::parse_json_limited;
use vstructc::front::rib::{RibOptions, parse_rib};
use vstructc::limits::{Limit, LimitExceeded, Limits};
use vstructc::network::{Network, NoDefinitions};
use vstructc::registry::{Registry, RegistryOptions};
use vstructc::resolve::{ResolveOptions, resolve};
use vstructc::{Diagnostics, Error, Value};

/// `n` pattern nodes, the last with `fan` connections on one input and `params` values.
fn rib(n: usize, fan: usize, params: usize) -> String {
    let mut text = String::new();
    for i in 0..n {
        let _ = write!(text, "Pattern \"P\" \"n{i}\"");
        if i + 1 == n {
            for k in 0..params {
                let _ = write!(text, " \"float p{k}\" [{k}]");
            }
            let targets: Vec<String> = (0..fan).map(|_| "\"n0:out\"".to_string()).collect();
            let _ = write!(
                text,
                " \"reference float[{fan}] x\" [{}]",
                targets.join(" ")
            );
        }
        text.push('\n');
    }
    text
}

fn read_rib(text: &str, limits: Limits) -> Result<Network, Error> {
    let options = RibOptions {
        limits,
        ..RibOptions::default()
    };
    let mut d = Diagnostics::new();
    parse_rib(text.as_bytes(), "l.rib", &NoDefinitions, &options, &mut d)
}

fn exceeded(result: Result<Network, Error>) -> LimitExceeded {
    match result {
        Err(Error::Limit(e)) => *e,
        Err(e) => panic!("expected a limit error, got {e}"),
        Ok(_) => panic!("expected a limit error, the input was read"),
    }
}

#[test]
fn the_rib_reader_applies_every_network_bound() {
    let text = rib(5, 3, 4);
    assert!(read_rib(&text, Limits::default()).is_ok());

    let e = exceeded(read_rib(
        &text,
        Limits {
            nodes: 4,
            ..Limits::default()
        },
    ));
    assert_eq!((e.limit, e.value, e.max), (Limit::Nodes, 5, 4));
    // It stops at the request that is one too many: line 5.
    assert_eq!(e.location.as_ref().map(|l| l.line), Some(5));

    let e = exceeded(read_rib(
        &text,
        Limits {
            connections_per_input: 2,
            ..Limits::default()
        },
    ));
    assert_eq!((e.limit, e.value), (Limit::ConnectionsPerInput, 3));
    assert_eq!(e.location.as_ref().map(|l| &*l.file), Some("l.rib"));

    let e = exceeded(read_rib(
        &text,
        Limits {
            params_per_node: 4,
            ..Limits::default()
        },
    ));
    assert_eq!((e.limit, e.value), (Limit::ParamsPerNode, 5));

    let e = exceeded(read_rib(
        &text,
        Limits {
            network_file_bytes: text.len() as u64 - 1,
            ..Limits::default()
        },
    ));
    assert_eq!(e.limit, Limit::NetworkFileBytes);
    assert_eq!(e.value, text.len() as u64);
}

/// A node beyond a bound is reported once the whole file is read, as a check of the network
/// reports it: of two such nodes the first, and an error later in the file instead (reading
/// stops there).
#[test]
fn the_rib_reader_reports_the_first_node_beyond_a_bound_once_read() {
    let limits = Limits {
        params_per_node: 1,
        ..Limits::default()
    };
    let two = concat!(
        "Pattern \"P\" \"a\"\n",
        "Pattern \"P\" \"b\" \"float x\" [1] \"float y\" [2]\n",
        "Pattern \"P\" \"c\" \"float x\" [1] \"float y\" [2] \"float z\" [3]\n",
    );
    let e = exceeded(read_rib(two, limits));
    assert_eq!((e.limit, e.value), (Limit::ParamsPerNode, 2));
    assert_eq!(e.location.as_ref().map(|l| l.line), Some(2));
    let net = read_rib(two, Limits::default()).unwrap();
    assert_eq!(
        net.check_limits(&limits).map_err(|e| (e.value, e.location)),
        Err((2, e.location))
    );
    match read_rib(&format!("{two}]\n"), limits) {
        Err(Error::Input(d)) => assert_eq!(d.code.as_str(), "RB004"),
        other => panic!("expected the later RB004, got {other:?}"),
    }
}

#[test]
fn the_json_reader_applies_the_network_bounds() {
    let text = r#"{ "vstructcNetwork": 1, "materials": { "M": {
        "nodes": {
          "a": { "nodeTypeId": "P", "parameters": { "x": { "type": "float", "value": 1 } } },
          "b": { "nodeTypeId": "P", "inputConnections": { "y": [
                 { "upstreamNode": "a", "upstreamOutputName": "out" },
                 { "upstreamNode": "a", "upstreamOutputName": "out" } ] } } },
        "terminals": {} } } }"#;
    let read = |limits: Limits| {
        let mut d = Diagnostics::new();
        parse_json_limited(text.as_bytes(), "l.json", &NoDefinitions, &limits, &mut d)
    };
    assert!(read(Limits::default()).is_ok());
    let e = exceeded(read(Limits {
        nodes: 1,
        ..Limits::default()
    }));
    assert_eq!((e.limit, e.value), (Limit::Nodes, 2));
    let e = exceeded(read(Limits {
        connections_per_input: 1,
        ..Limits::default()
    }));
    assert_eq!((e.limit, e.value), (Limit::ConnectionsPerInput, 2));
    let e = exceeded(read(Limits {
        network_file_bytes: 10,
        ..Limits::default()
    }));
    assert_eq!(e.limit, Limit::NetworkFileBytes);
}

/// A definition with more parameters than `params_per_node`, and conditionals beyond
/// `expr_terms` and `expr_depth`, in a registry built with those limits.
#[test]
fn the_registry_applies_definition_and_expression_bounds() {
    let dir = tempfile::tempdir().unwrap();
    let chain = (0..10)
        .map(|k| format!("p{k} == 1"))
        .collect::<Vec<_>>()
        .join(" and ");
    let nested = format!("connect if {}x == 1{}", "(".repeat(5), ")".repeat(5));
    let args = format!(
        r#"<args format="1.0">
  <shaderType><tag value="pattern"/></shaderType>
  <param name="a" type="float"/>
  <param name="b" type="float"/>
  <output name="out_x" vstructmember="out.x" vstructConditionalExpr="connect if {chain}">
    <tags><tag value="float"/></tags></output>
  <output name="out_y" vstructmember="out.y" vstructConditionalExpr="{nested}">
    <tags><tag value="float"/></tags></output>
</args>
"#
    );
    std::fs::write(dir.path().join("Bounded.args"), args).unwrap();
    let registry = |limits: Limits| {
        Registry::new(RegistryOptions {
            limits,
            ..RegistryOptions::only([dir.path()])
        })
    };

    let generous = registry(Limits::default());
    let tables = generous.tables("Bounded").expect("tables");
    assert!(
        generous.diagnostics().iter().all(|d| d.code != "VS001"),
        "{:?}",
        generous.diagnostics()
    );
    drop(tables);

    let tight = registry(Limits {
        expr_terms: 9,
        expr_depth: 4,
        ..Limits::default()
    });
    tight.tables("Bounded").expect("tables");
    let messages: Vec<String> = tight
        .diagnostics()
        .iter()
        .filter(|d| d.code == "VS001")
        .map(|d| d.message.clone())
        .collect();
    assert!(
        messages.iter().any(|m| m.contains("expr_terms")),
        "{messages:?}"
    );
    assert!(
        messages.iter().any(|m| m.contains("deeper than 4 levels")),
        "{messages:?}"
    );

    let few = registry(Limits {
        params_per_node: 3,
        ..Limits::default()
    });
    assert!(few.definition("Bounded").is_none());
    let lm = few.diagnostics();
    let d = lm.iter().find(|d| d.code == "LM001").expect("LM001");
    assert!(d.message.contains("params_per_node"), "{}", d.message);
    assert!(
        d.location
            .as_ref()
            .is_some_and(|l| l.file.ends_with("Bounded.args"))
    );
}

#[test]
fn the_parser_reports_the_exceeded_bound_typed() {
    let limits = Limits {
        expr_terms: 2,
        ..Limits::default()
    };
    let text = "connect if a == 1 and b == 1 and c == 1";
    let e = vstructc::cond::internals::parse_statement_limited(text, &Extensions::none(), &limits)
        .unwrap_err();
    let limit = e.limit.expect("typed limit");
    assert_eq!(
        (limit.limit, limit.value, limit.max),
        (Limit::ExprTerms, 3, 2)
    );
    // The caret is on the third term.
    assert_eq!(&text[e.span.clone()], "c");
    assert!(
        vstructc::cond::internals::parse_statement_limited(
            text,
            &Extensions::none(),
            &Limits::default()
        )
        .is_ok()
    );
}

/// A network built in code (no reader involved) meets the same bounds in resolution, which
/// then leaves it untouched.
#[test]
fn resolution_refuses_a_network_beyond_its_bounds() {
    let registry = Registry::embedded();
    let build = || {
        let mut net = Network::new();
        let layer = net.add_node("layer", "PxrLayer");
        let mixer = net.add_node("mixer", "PxrLayerMixer");
        net.connect(mixer, "baselayer", layer, "pxrMaterialOut");
        net.set_param(layer, "diffuseGain", Value::Float(0.5));
        (net, mixer)
    };
    let (mut net, mixer) = build();
    let strict = ResolveOptions {
        limits: Limits {
            nodes: 1,
            ..Limits::default()
        },
        ..ResolveOptions::default()
    };
    let res = resolve(&mut net, &registry, &strict);
    let limit = res.limit.expect("refused");
    assert_eq!((limit.limit, limit.value, limit.max), (Limit::Nodes, 2, 1));
    assert!(res.diagnostics.iter().any(|d| d.code == "LM001"));
    // Untouched: the placeholder is still there, no member was connected.
    assert_eq!(net.connections(mixer, "baselayer").len(), 1);
    assert!(net.connections(mixer, "baselayer_diffuseGain").is_empty());

    let (mut net, mixer) = build();
    let res = resolve(&mut net, &registry, &ResolveOptions::default());
    assert!(res.limit.is_none());
    assert!(net.connections(mixer, "baselayer").is_empty());
}
