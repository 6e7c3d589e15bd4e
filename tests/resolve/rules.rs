//! Focused resolution cases: one per rule of spec vstruct.md §4 and per diagnostic of §8,
//! each as an insta snapshot of the resolved network and the diagnostics.

use vstructc::cond::{Extension, Extensions};
use vstructc::network::{Link, Network, NodeId};
use vstructc::registry::{Registry, RegistryOptions};
use vstructc::resolve::{Outcome, ResolveOptions, resolve};
use vstructc::{Diagnostics, Severity, Value};

/// Upstream type: inputs `enable` (int, default 1), `other` (int, default 0), `f` (float),
/// `s` (string), `c` (color), `arr` (float[2]); output head `out` with members.
const UP: &str = r#"<args format="1.0">
  <shaderType><tag value="pattern"/></shaderType>
  <param name="enable" type="int" default="1"/>
  <param name="other" type="int" default="0"/>
  <param name="f" type="float" default="0.25"/>
  <param name="s" type="string" default="abc"/>
  <param name="c" type="color" default="0.1 0.2 0.3"/>
  <param name="arr" type="float" arraySize="2" default="1 2"/>
  <param name="h" type="vstruct"><tags><tag value="vstruct"/></tags></param>
  <param name="h_flag" type="int" default="0" vstructmember="h.flag"/>
  <output name="out"><tags><tag value="vstruct"/></tags></output>
  <output name="out_a" vstructmember="out.a"><tags><tag value="float"/></tags></output>
  <output name="out_b" vstructmember="out.b"><tags><tag value="float"/></tags></output>
  <output name="out_c" vstructmember="out.c"><tags><tag value="float"/></tags></output>
  <output name="out_flag" vstructmember="out.flag"
          vstructConditionalExpr="set 1 if enable == 1 or h_flag == 1 else set 0"><tags><tag value="int"/></tags></output>
  <output name="out_bar" vstructmember="out.bar"><tags><tag value="float"/></tags></output>
  <output name="out_gated" vstructmember="out.gated" vstructConditionalExpr="connect if enable == 1"><tags><tag value="float"/></tags></output>
  <output name="out_ne" vstructmember="out.ne" vstructConditionalExpr="connect if c != 1"><tags><tag value="float"/></tags></output>
  <output name="out_seti" vstructmember="out.seti" vstructConditionalExpr="set 1.9"><tags><tag value="int"/></tags></output>
  <output name="out_big" vstructmember="out.big" vstructConditionalExpr="set 3e9"><tags><tag value="int"/></tags></output>
  <output name="out_setf" vstructmember="out.setf" vstructConditionalExpr="set 1.7"><tags><tag value="float"/></tags></output>
  <output name="out_setc" vstructmember="out.setc" vstructConditionalExpr="set 1.7"><tags><tag value="color"/></tags></output>
  <output name="out_sets" vstructmember="out.sets" vstructConditionalExpr="set 'xyz'"><tags><tag value="string"/></tags></output>
  <output name="out_copyf" vstructmember="out.copyf" vstructConditionalExpr="copy f"><tags><tag value="float"/></tags></output>
  <output name="out_copyint" vstructmember="out.copyint" vstructConditionalExpr="copy f"><tags><tag value="int"/></tags></output>
  <output name="out_ign" vstructmember="out.ign" vstructConditionalExpr="ignore if other == 1"><tags><tag value="float"/></tags></output>
  <output name="out_else" vstructmember="out.else" vstructConditionalExpr="if other == 1 else set 0"><tags><tag value="int"/></tags></output>
  <output name="out_isset" vstructmember="out.isset" vstructConditionalExpr="other is set"><tags><tag value="float"/></tags></output>
  <output name="out_headconn" vstructmember="out.headconn" vstructConditionalExpr="h is connected"><tags><tag value="float"/></tags></output>
  <output name="out_memconn" vstructmember="out.memconn" vstructConditionalExpr="h_flag is connected"><tags><tag value="float"/></tags></output>
  <output name="ClearCoat_CG" vstructmember="out.clearcoatEdgeColor"><tags><tag value="color"/></tags></output>
  <output name="out_nested" vstructmember="out.nested"><tags><tag value="float"/></tags></output>
  <output name="out_bad" vstructmember="out.bad" vstructConditionalExpr="connect if x = 1"><tags><tag value="float"/></tags></output>
</args>"#;

/// A downstream type declaring only the members a test names (`{members}` is replaced).
fn down(members: &[(&str, &str)]) -> String {
    let mut s = String::from(
        r#"<args format="1.0"><shaderType><tag value="bxdf"/></shaderType>
  <param name="inputMaterial" type="float" readOnly="true"><tags><tag value="vstruct"/></tags></param>
"#,
    );
    for (name, ty) in members {
        let (prop, member, alias) = match name.split_once('|') {
            Some((m, alias)) => (format!("p_{m}"), m.to_string(), Some(alias)),
            None => (format!("p_{name}"), name.to_string(), None),
        };
        let alias = alias
            .map(|a| format!(r#" vstructmemberaliases="{a}""#))
            .unwrap_or_default();
        s.push_str(&format!(
            r#"  <param name="{prop}" type="{ty}" vstructmember="inputMaterial.{member}"{alias}/>
"#
        ));
    }
    s.push_str("</args>");
    s
}

fn registry(down_members: &[(&str, &str)]) -> Registry {
    let mut reg = Registry::new(RegistryOptions {
        paths: vec![],
        use_env: false,
        use_embedded: false,
        ..RegistryOptions::default()
    });
    reg.add_args_text("Up", UP).expect("Up parses");
    reg.add_args_text("Down", &down(down_members))
        .expect("Down parses");
    reg
}

/// A stable text form of the network: per node (sorted), each parameter's connections or
/// value.
fn dump(net: &Network) -> String {
    let mut out = String::new();
    for id in net.nodes_sorted() {
        let node = &net[id];
        out.push_str(&format!("{} ({})\n", node.display_name(), node.shader()));
        for p in node.params_by_name() {
            if p.is_connected() {
                let links: Vec<String> = p.connections().iter().map(|l| link(net, l)).collect();
                out.push_str(&format!("  {} <- {}\n", p.name(), links.join(", ")));
            } else if let Some(v) = p.value() {
                out.push_str(&format!("  {} = {v}\n", p.name()));
            }
        }
    }
    out
}

fn link(net: &Network, l: &Link) -> String {
    let up = match l.upstream_node() {
        Some(n) => net[n].handle().to_string(),
        None => format!("<missing {}>", l.missing_handle().unwrap_or_default()),
    };
    match l.output() {
        Some(o) => format!("{up}.{o}"),
        None => up,
    }
}

fn diags(d: &Diagnostics) -> String {
    d.iter()
        .filter(|d| d.code != "VS020" || d.severity == Severity::Warning)
        .map(|d| format!("{}[{}]: {}", d.severity, d.code, d.message))
        .collect::<Vec<_>>()
        .join("\n")
}

/// Resolve and render network + diagnostics for a snapshot.
fn run(net: &mut Network, reg: &Registry, options: &ResolveOptions) -> String {
    let res = resolve(net, reg, options);
    format!("{}--\n{}\n", dump(net), diags(&res.diagnostics))
}

fn simple(members: &[(&str, &str)]) -> (Registry, Network, NodeId, NodeId) {
    let reg = registry(members);
    let mut net = Network::new();
    let u = net.add_node("U", "Up");
    let d = net.add_node("D", "Down");
    net.connect(d, "inputMaterial", u, "out");
    (reg, net, u, d)
}

fn abc() -> [(&'static str, &'static str); 3] {
    [("a", "float"), ("b", "float"), ("c", "float")]
}

#[test]
fn r1_members_connect_and_placeholder_is_deleted() {
    let (reg, mut net, _, d) = simple(&abc());
    let text = run(&mut net, &reg, &ResolveOptions::default());
    assert!(net.connections(d, "inputMaterial").is_empty());
    insta::assert_snapshot!(text);
}

#[test]
fn r2_direct_connection_wins() {
    let (reg, mut net, _, d) = simple(&abc());
    let x = net.add_node("X", "Up");
    net.connect(d, "p_a", x, "out_a");
    let text = run(&mut net, &reg, &ResolveOptions::default());
    assert_eq!(net.connections(d, "p_a")[0].upstream_node(), Some(x));
    insta::assert_snapshot!(text);
}

#[test]
fn r3_authored_value_is_overridden_by_connect() {
    let (reg, mut net, u, d) = simple(&abc());
    net.set_param(d, "p_b", Value::Float(0.5));
    let text = run(&mut net, &reg, &ResolveOptions::default());
    assert_eq!(net.connections(d, "p_b")[0].upstream_node(), Some(u));
    insta::assert_snapshot!(text);
}

#[test]
fn r4_missing_upstream_keeps_placeholder() {
    let reg = registry(&abc());
    let mut net = Network::new();
    let d = net.add_node("D", "Down");
    net.push_link(d, "inputMaterial", Link::missing("Missing", Some("out")));
    let text = run(&mut net, &reg, &ResolveOptions::default());
    assert_eq!(net.connections(d, "inputMaterial").len(), 1);
    insta::assert_snapshot!(text);
}

#[test]
fn r5_only_first_connection_of_a_head_is_expanded() {
    let (reg, mut net, _, d) = simple(&abc());
    let u2 = net.add_node("U2", "Up");
    net.connect(d, "inputMaterial", u2, "out");
    let text = run(&mut net, &reg, &ResolveOptions::default());
    assert!(net.connections(d, "inputMaterial").is_empty());
    insta::assert_snapshot!(text);
}

#[test]
fn r6_two_node_cycle_terminates_and_names_both_nodes() {
    // Up has an input head `h` and an output head `out` sharing the member `flag`.
    let reg = registry(&[]);
    let mut net = Network::new();
    let a = net.add_node("A", "Up");
    let b = net.add_node("B", "Up");
    net.connect(a, "h", b, "out");
    net.connect(b, "h", a, "out");
    let res = resolve(&mut net, &reg, &ResolveOptions::default());
    let cycles: Vec<_> = res.diagnostics.with_code("VS012").collect();
    assert_eq!(cycles.len(), 1);
    assert!(cycles[0].message.contains("A.") && cycles[0].message.contains("B."));
    insta::assert_snapshot!(format!("{}--\n{}\n", dump(&net), diags(&res.diagnostics)));
}

#[test]
fn r7_alias_matches_upstream_member() {
    let (reg, mut net, _, d) = simple(&[("foo|bar", "float")]);
    let text = run(&mut net, &reg, &ResolveOptions::default());
    assert_eq!(net.connections(d, "p_foo")[0].output(), Some("out_bar"));
    insta::assert_snapshot!(text);
}

#[test]
fn r8_member_without_counterpart_is_untouched_and_noted_when_verbose() {
    let (reg, mut net, _, d) = simple(&[("a", "float"), ("zzz", "float")]);
    net.set_param(d, "p_zzz", Value::Float(3.0));
    let options = ResolveOptions {
        verbose: true,
        ..ResolveOptions::default()
    };
    let text = run(&mut net, &reg, &options);
    assert_eq!(net.value(d, "p_zzz"), Some(&Value::Float(3.0)));
    insta::assert_snapshot!(text);
}

#[test]
fn r11_value_on_input_head_is_removed() {
    let (reg, mut net, _, d) = simple(&abc());
    net.set_param(d, "inputMaterial", Value::Float(0.0));
    let text = run(&mut net, &reg, &ResolveOptions::default());
    assert_eq!(net.value(d, "inputMaterial"), None);
    insta::assert_snapshot!(text);
}

#[test]
fn r13_and_e27_conditions_see_upstream_state_after_its_own_resolution() {
    // U0 -> U1.h: U1's member h_flag is set to 1 by U0's `set 1 if enable == 1 ...`, and
    // then D reads U1: `out.flag` = set 1 (h_flag == 1), `memconn`: h_flag is connected? no
    // (it was set, not connected) -> ignore; `headconn`: U1.h is not connected any more.
    let reg = registry(&[("flag", "int"), ("headconn", "float"), ("memconn", "float")]);
    let mut net = Network::new();
    let u0 = net.add_node("U0", "Up");
    let u1 = net.add_node("U1", "Up");
    let d = net.add_node("D", "Down");
    net.set_param(u1, "enable", Value::Int(0));
    net.connect(u1, "h", u0, "out");
    net.connect(d, "inputMaterial", u1, "out");
    let text = run(&mut net, &reg, &ResolveOptions::default());
    assert_eq!(net.value(u1, "h_flag"), Some(&Value::Int(1)));
    assert_eq!(net.value(d, "p_flag"), Some(&Value::Int(1)));
    assert!(net.connections(d, "p_headconn").is_empty());
    insta::assert_snapshot!(text);
}

#[test]
fn e27_member_connected_by_upstream_expansion_counts_as_connected() {
    // Same chain, but without conditions on the first hop U1.h_flag gets *connected*.
    let reg = registry(&[("memconn", "float")]);
    let mut net = Network::new();
    let u0 = net.add_node("U0", "Up");
    let u1 = net.add_node("U1", "Up");
    let d = net.add_node("D", "Down");
    net.connect(u1, "h", u0, "out");
    net.connect(d, "inputMaterial", u1, "out");
    // Connect h_flag directly so it is connected when D is evaluated.
    net.connect(u1, "h_flag", u0, "out_flag");
    resolve(&mut net, &reg, &ResolveOptions::default());
    assert_eq!(net.connections(d, "p_memconn").len(), 1);
}

#[test]
fn conditional_actions_set_copy_ignore() {
    let (reg, mut net, u, d) = simple(&[
        ("gated", "float"),
        ("seti", "int"),
        ("setf", "float"),
        ("sets", "string"),
        ("copyf", "float"),
        ("ign", "float"),
        ("else", "int"),
        ("isset", "float"),
    ]);
    net.set_param(u, "f", Value::Float(0.75));
    net.set_param(d, "p_ign", Value::Float(9.0));
    let text = run(&mut net, &reg, &ResolveOptions::default());
    assert_eq!(net.value(d, "p_seti"), Some(&Value::Int(1)));
    assert_eq!(net.value(d, "p_setf"), Some(&Value::Float(1.7)));
    assert_eq!(net.value(d, "p_sets"), Some(&Value::Str("xyz".into())));
    assert_eq!(net.value(d, "p_copyf"), Some(&Value::Float(0.75)));
    // `ignore if other == 1` with other = 0 → connect; `if other == 1 else set 0` → set 0.
    assert_eq!(net.connections(d, "p_ign").len(), 1);
    assert_eq!(net.value(d, "p_else"), Some(&Value::Int(0)));
    // `other is set`: only a default → ignore.
    assert!(net.connections(d, "p_isset").is_empty());
    insta::assert_snapshot!(text);
}

#[test]
fn conditional_reads_defaults_and_authored_values() {
    let (reg, mut net, u, d) = simple(&[("gated", "float"), ("isset", "float")]);
    net.set_param(u, "enable", Value::Int(0));
    net.set_param(u, "other", Value::Int(0));
    let text = run(&mut net, &reg, &ResolveOptions::default());
    assert!(net.connections(d, "p_gated").is_empty());
    assert_eq!(net.connections(d, "p_isset").len(), 1);
    insta::assert_snapshot!(text);
}

#[test]
fn vs013_vs014_vs015_vs023_type_problems() {
    let (reg, mut net, _, d) = simple(&[
        ("setc", "color"),
        ("sets", "float"),
        ("copyint", "int"),
        ("big", "int"),
        ("ne", "float"),
    ]);
    let res = resolve(&mut net, &reg, &ResolveOptions::default());
    for code in ["VS013", "VS014", "VS015", "VS023"] {
        assert!(res.diagnostics.count(code) > 0, "{code} missing");
    }
    assert_eq!(net.value(d, "p_big"), Some(&Value::Int(i32::MAX)));
    assert_eq!(net.value(d, "p_setc"), None);
    // `c != 1` on a colour is false (not the negation of ==): ignore.
    assert!(net.connections(d, "p_ne").is_empty());
    insta::assert_snapshot!(format!("{}--\n{}\n", dump(&net), diags(&res.diagnostics)));
}

#[test]
fn extensions_set_tuples_and_copy_convert() {
    let (reg, mut net, _, d) = simple(&[("setc", "color"), ("copyint", "int")]);
    let options = ResolveOptions {
        extensions: Extensions::none()
            .with(Extension::SetTuples)
            .with(Extension::CopyConvert),
        ..ResolveOptions::default()
    };
    let res = resolve(&mut net, &reg, &options);
    assert_eq!(
        net.value(d, "p_setc"),
        Some(&Value::Triple(vstructc::BaseType::Color, [1.7; 3]))
    );
    assert_eq!(net.value(d, "p_copyint"), Some(&Value::Int(0)));
    assert_eq!(res.diagnostics.count("VS013"), 0);
}

#[test]
fn vs016_unparsable_conditional_never_connects() {
    let (reg, mut net, _, d) = simple(&[("bad", "float")]);
    let text = run(&mut net, &reg, &ResolveOptions::default());
    assert!(net.connections(d, "p_bad").is_empty());
    insta::assert_snapshot!(text);
}

#[test]
fn vs022_no_conditions_connects_everything_matched() {
    let (reg, mut net, _, d) = simple(&[("bad", "float"), ("seti", "int"), ("a", "float")]);
    let options = ResolveOptions {
        conditions: false,
        ..ResolveOptions::default()
    };
    let text = run(&mut net, &reg, &options);
    for m in ["p_bad", "p_seti", "p_a"] {
        assert_eq!(net.connections(d, m).len(), 1, "{m}");
    }
    insta::assert_snapshot!(text);
}

#[test]
fn vs010_unknown_type_output_not_head_and_whole_node_reference() {
    let reg = registry(&abc());
    let mut net = Network::new();
    let x = net.add_node("X", "Mystery");
    let u = net.add_node("U", "Up");
    let d1 = net.add_node("D1", "Down");
    let d2 = net.add_node("D2", "Down");
    let d3 = net.add_node("D3", "Down");
    net.connect(d1, "inputMaterial", x, "out");
    net.connect(d2, "inputMaterial", u, "out_a");
    net.connect_node(d3, "inputMaterial", u);
    let text = run(&mut net, &reg, &ResolveOptions::default());
    for d in [d1, d2, d3] {
        assert_eq!(net.connections(d, "inputMaterial").len(), 1);
    }
    insta::assert_snapshot!(text);
}

#[test]
fn connection_into_a_non_head_is_not_a_vstruct_connection() {
    let (reg, mut net, u, d) = simple(&abc());
    net.clear_connections(d, "inputMaterial");
    net.connect(d, "p_a", u, "out");
    let res = resolve(&mut net, &reg, &ResolveOptions::default());
    assert_eq!(net.connections(d, "p_a").len(), 1);
    assert!(res.diagnostics.is_empty(), "{:?}", res.diagnostics);
}

#[test]
fn explain_events_record_reads_and_actions() {
    let (reg, mut net, u, _) = simple(&[("gated", "float"), ("flag", "int")]);
    net.set_param(u, "enable", Value::Int(1));
    let options = ResolveOptions {
        record_events: true,
        ..ResolveOptions::default()
    };
    let res = resolve(&mut net, &reg, &options);
    let gated = res.events.iter().find(|e| e.member == "p_gated").unwrap();
    assert_eq!(gated.outcome, Outcome::Connected);
    assert_eq!(gated.reads.len(), 1);
    assert_eq!(gated.reads[0].param, "enable");
    let flag = res.events.iter().find(|e| e.member == "p_flag").unwrap();
    assert_eq!(flag.outcome, Outcome::Written(Value::Int(1)));
    assert_eq!(flag.action.as_deref(), Some("set 1"));
}

#[test]
fn results_do_not_depend_on_insertion_order_on_acyclic_networks() {
    let build = |reverse: bool| {
        let reg = registry(&[("flag", "int"), ("gated", "float")]);
        let mut net = Network::new();
        let names = ["U0", "U1", "D"];
        let order: Vec<&str> = if reverse {
            names.iter().rev().copied().collect()
        } else {
            names.to_vec()
        };
        for n in &order {
            let shader = if *n == "D" { "Down" } else { "Up" };
            net.add_node(n, shader);
        }
        let (u0, u1, d) = (
            net.find("U0").unwrap(),
            net.find("U1").unwrap(),
            net.find("D").unwrap(),
        );
        net.set_param(u1, "enable", Value::Int(0));
        net.connect(u1, "h", u0, "out");
        net.connect(d, "inputMaterial", u1, "out");
        resolve(&mut net, &reg, &ResolveOptions::default());
        dump(&net)
    };
    assert_eq!(build(false), build(true));
}

#[test]
fn chain_of_100k_nodes_resolves_without_recursion() {
    // n000000.h ← n000001.out ← … : the first node in sorted order sits at the bottom of a
    // 100,000-deep dependency chain.
    let reg = registry(&[]);
    let mut net = Network::new();
    let n = 100_000;
    let ids: Vec<NodeId> = (0..n)
        .map(|i| net.add_node(&format!("n{i:06}"), "Up"))
        .collect();
    for i in 0..n - 1 {
        net.connect(ids[i], "h", ids[i + 1], "out");
    }
    net.set_param(ids[n - 1], "enable", Value::Int(0));
    let t = std::time::Instant::now();
    let res = resolve(&mut net, &reg, &ResolveOptions::default());
    eprintln!("resolve took {:?}", t.elapsed());
    assert_eq!(res.diagnostics.count("VS012"), 0);
    // `flag` propagates: the last node has enable 0 → its downstream gets h_flag 0 ... but
    // every other node has enable 1 (default), so h_flag = 1 from the second-to-last on.
    assert_eq!(net.value(ids[n - 2], "h_flag"), Some(&Value::Int(0)));
    assert_eq!(net.value(ids[0], "h_flag"), Some(&Value::Int(1)));
}

#[test]
fn r10_member_names_not_property_names_decide_the_match() {
    // Laika adapter style: the upstream output `ClearCoat_CG` carries the member
    // `clearcoatEdgeColor` and feeds the downstream `p_clearcoatEdgeColor`.
    let (reg, mut net, _, d) = simple(&[("clearcoatEdgeColor", "color")]);
    let text = run(&mut net, &reg, &ResolveOptions::default());
    assert_eq!(
        net.connections(d, "p_clearcoatEdgeColor")[0].output(),
        Some("ClearCoat_CG")
    );
    insta::assert_snapshot!(text);
}

#[test]
fn r12_nested_head_member_is_connected_but_not_expanded() {
    let mut reg = registry(&[]);
    reg.add_args_text(
        "Nest",
        r#"<args format="1.0"><shaderType><tag value="bxdf"/></shaderType>
  <param name="inputMaterial" type="float"><tags><tag value="vstruct"/></tags></param>
  <param name="p_nested" type="float" vstructmember="inputMaterial.nested"/>
  <param name="p_nested_x" type="float" vstructmember="p_nested.x"/>
</args>"#,
    )
    .expect("Nest parses");
    let mut net = Network::new();
    let u = net.add_node("U", "Up");
    let d = net.add_node("D", "Nest");
    net.connect(d, "inputMaterial", u, "out");
    let res = resolve(&mut net, &reg, &ResolveOptions::default());
    assert_eq!(
        net.connections(d, "p_nested")[0].output(),
        Some("out_nested")
    );
    assert!(net.connections(d, "p_nested_x").is_empty());
    let registry_diags = reg.diagnostics();
    assert_eq!(registry_diags.count("VS008"), 1);
    insta::assert_snapshot!(format!(
        "{}--\n{}\n{}\n",
        dump(&net),
        diags(&registry_diags),
        diags(&res.diagnostics)
    ));
}

#[test]
fn cycle_of_length_one_terminates() {
    let reg = registry(&[]);
    let mut net = Network::new();
    let a = net.add_node("A", "Up");
    net.connect(a, "h", a, "out");
    let text = run(&mut net, &reg, &ResolveOptions::default());
    assert!(net.connections(a, "h").is_empty());
    insta::assert_snapshot!(text);
}

#[test]
fn vs020_unknown_downstream_type_is_info_and_untouched() {
    let reg = registry(&[]);
    let mut net = Network::new();
    let u = net.add_node("U", "Up");
    let x = net.add_node("X", "Mystery");
    net.connect(x, "inputMaterial", u, "out");
    let res = resolve(&mut net, &reg, &ResolveOptions::default());
    assert_eq!(net.connections(x, "inputMaterial").len(), 1);
    let infos: Vec<_> = res.diagnostics.with_code("VS020").collect();
    assert_eq!(infos.len(), 1);
    assert_eq!(infos[0].severity, Severity::Info);
    insta::assert_snapshot!(infos[0].message.clone());
}

#[test]
fn vs017_head_value_without_connection_is_removed_too() {
    let reg = registry(&abc());
    let mut net = Network::new();
    let d = net.add_node("D", "Down");
    net.set_param(d, "inputMaterial", Value::Float(1.0));
    let text = run(&mut net, &reg, &ResolveOptions::default());
    assert_eq!(net.value(d, "inputMaterial"), None);
    insta::assert_snapshot!(text);
}

/// One upstream state for the decision-cache property below: values of `enable`, `other`,
/// `f` and `c` (absent, or one of a few values, `-0.0` included), and whether `h` and `h_flag`
/// are connected.
#[derive(Debug, Clone)]
struct UpState {
    enable: Option<i32>,
    other: Option<i32>,
    f: Option<f32>,
    c: Option<f32>,
    h_connected: bool,
    flag_connected: bool,
}

fn up_state() -> impl proptest::strategy::Strategy<Value = UpState> {
    use proptest::prelude::*;
    let int = prop::option::of(prop_oneof![Just(0), Just(1), Just(2)]);
    let float = prop::option::of(prop_oneof![Just(0.0f32), Just(-0.0), Just(0.75), Just(1.0)]);
    (
        int.clone(),
        int,
        float.clone(),
        float,
        any::<bool>(),
        any::<bool>(),
    )
        .prop_map(
            |(enable, other, f, c, h_connected, flag_connected)| UpState {
                enable,
                other,
                f,
                c,
                h_connected,
                flag_connected,
            },
        )
}

/// Adds `U{i}` in `state` and `D{i}` connected to it (plus the feeder `F{i}` of `h`).
fn add_pair(net: &mut Network, i: usize, state: &UpState) {
    let u = net.add_node(&format!("U{i}"), "Up");
    let d = net.add_node(&format!("D{i}"), "Down");
    let feeder = net.add_node(&format!("F{i}"), "PxrFractal");
    if let Some(v) = state.enable {
        net.set_param(u, "enable", Value::Int(v));
    }
    if let Some(v) = state.other {
        net.set_param(u, "other", Value::Int(v));
    }
    if let Some(v) = state.f {
        net.set_param(u, "f", Value::Float(v));
    }
    if let Some(v) = state.c {
        net.set_param(
            u,
            "c",
            Value::Triple(vstructc::types::BaseType::Color, [v; 3]),
        );
    }
    if state.h_connected {
        net.connect(u, "h", feeder, "resultRGB");
    }
    if state.flag_connected {
        net.connect(u, "h_flag", feeder, "resultF");
    }
    net.connect(d, "inputMaterial", u, "out");
}

/// The dump lines and diagnostics of pair `i` (names are single digits, so `D1` does not
/// match `D10`). VS020 is left out: it is one diagnostic per unknown type for the whole
/// network, naming the nodes of every pair.
fn pair_text(net: &Network, diagnostics: &Diagnostics, i: usize) -> String {
    let names = [format!("D{i}"), format!("U{i}"), format!("F{i}")];
    let mut out = String::new();
    let mut keep = false;
    for line in dump(net).lines() {
        if !line.starts_with(' ') {
            keep = names.iter().any(|n| line.starts_with(n.as_str()));
        }
        if keep {
            out.push_str(line);
            out.push('\n');
        }
    }
    for line in diags(diagnostics).lines() {
        if !line.contains("[VS020]") && names.iter().any(|n| line.contains(n.as_str())) {
            out.push_str(line);
            out.push('\n');
        }
    }
    out
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]

    /// Resolution shares the conditionals' verdicts between expansions that find the upstream
    /// node in the same state. Resolving many pairs in one network must therefore give each
    /// pair exactly what resolving it alone gives: results and diagnostics.
    #[test]
    fn shared_decisions_match_resolving_each_pair_alone(
        states in proptest::collection::vec(up_state(), 1..10),
        verbose in proptest::prelude::any::<bool>(),
    ) {
        let reg = registry(&[
            ("a", "float"), ("flag", "int"), ("gated", "float"), ("ne", "float"),
            ("seti", "int"), ("setc", "color"), ("copyf", "float"), ("copyint", "int"),
            ("ign", "float"), ("else", "int"), ("isset", "float"), ("headconn", "float"),
            ("memconn", "float"), ("bad", "float"), ("missing", "float"),
        ]);
        let options = ResolveOptions { verbose, ..ResolveOptions::default() };
        let mut together = Network::new();
        for (i, state) in states.iter().enumerate() {
            add_pair(&mut together, i, state);
        }
        let res = resolve(&mut together, &reg, &options);
        for (i, state) in states.iter().enumerate() {
            let mut alone = Network::new();
            add_pair(&mut alone, i, state);
            let res_alone = resolve(&mut alone, &reg, &options);
            proptest::prop_assert_eq!(
                pair_text(&together, &res.diagnostics, i),
                pair_text(&alone, &res_alone.diagnostics, i)
            );
        }
    }
}
