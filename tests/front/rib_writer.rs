//! RIB writer (formats.md §3.7): re-serialisation of modified nodes, pass-through, fresh
//! nodes, determinism, re-parsability.

use crate::common::network as network_common;

use network_common::{Table, summary};
use vstructc::back::rib::write_rib_to_vec;
use vstructc::front::rib::{RibOptions, parse_rib};
use vstructc::network::{Link, Network, NoDefinitions, ParamTypes, RequestKind};
use vstructc::{BaseType, Diagnostics, Value};

fn defs() -> Table {
    Table::new()
        .shader(
            "PxrSurface",
            &[
                ("diffuseGain", "float"),
                ("diffuseColor", "color"),
                ("diffuseRoughness", "float"),
                ("specularFaceColor", "color"),
                ("specularRoughness", "float"),
                ("presence", "float"),
                ("bumpNormal", "normal"),
            ],
            &[],
        )
        .shader(
            "PxrFractal",
            &[("layers", "int")],
            &[("resultF", "float"), ("resultRGB", "color")],
        )
        .shader(
            "PxrTexture",
            &[("filename", "string")],
            &[("resultRGB", "color"), ("resultA", "float")],
        )
}

fn read(src: &str, types: &(dyn ParamTypes + Sync)) -> Network {
    let mut d = Diagnostics::new();
    parse_rib(
        src.as_bytes(),
        "in.rib",
        types,
        &RibOptions::default(),
        &mut d,
    )
    .unwrap()
}

fn write(src: &str, net: &Network, types: &(dyn ParamTypes + Sync)) -> String {
    String::from_utf8(write_rib_to_vec(src.as_bytes(), net, types).unwrap()).unwrap()
}

const SCENE: &str = r#"##RenderMan RIB
# A material
AttributeBegin
	Pattern "PxrFractal" "noise"
		"int layers" [6] # octaves
		"float frequency"  [2]
	Pattern "PxrTexture" "tex" "string filename" ["wood.tex"]
	Bxdf "PxrSurface" "surf"
		# base colour
		"color diffuseColor" [0.5 0.5 0.5]
		# will be removed
		"float diffuseGain" [1] # gain comment
		"float specularRoughness" [0.2]
		"reference float presence" ["tex:resultA"]
		"string __materialid" ["SurfSG"] # id
	Sphere 1 -1 1 360
AttributeEnd
"#;

#[test]
fn modified_node_is_reserialised_in_place() {
    let types = defs();
    let mut net = read(SCENE, &types);
    let noise = net.find("noise").unwrap();
    let tex = net.find("tex").unwrap();
    let surf = net.find("surf").unwrap();
    net.set_param(noise, "layers", Value::Int(3));
    net.connect(surf, "diffuseColor", tex, "resultRGB");
    net.remove_param(surf, "diffuseGain");
    net.set_param(surf, "specularRoughness", Value::Float(0.35));
    net.clear_connections(surf, "presence");
    // Added in reverse declaration order: written in declaration order.
    net.set_param(
        surf,
        "specularFaceColor",
        Value::Triple(BaseType::Color, [0.04, 0.04, 0.04]),
    );
    net.connect(surf, "diffuseRoughness", noise, "resultF");
    assert!(!net.is_modified(tex));

    let out = write(SCENE, &net, &types);
    insta::assert_snapshot!("modified_node", out);

    // Re-parsable, and the re-read network is the modified network.
    let again = read(&out, &types);
    assert_eq!(summary(&again), summary(&net));
    // Deterministic.
    assert_eq!(write(SCENE, &net, &types), out);
}

#[test]
fn connected_parameter_keeps_value_but_writes_only_the_connection() {
    let mut net = read(SCENE, &NoDefinitions);
    let noise = net.find("noise").unwrap();
    let surf = net.find("surf").unwrap();
    net.connect(surf, "specularRoughness", noise, "resultF");
    assert_eq!(
        net.value(surf, "specularRoughness"),
        Some(&Value::Float(0.2))
    );
    let out = write(SCENE, &net, &NoDefinitions);
    // No definitions: the type comes from the source decl (float).
    assert!(out.contains("\t\t\"reference float specularRoughness\" [\"noise:resultF\"]\n"));
    assert!(!out.contains("[0.2]"));
}

#[test]
fn new_connection_type_falls_back_to_upstream_output_type() {
    let types = Table::new().shader("PxrFractal", &[], &[("resultRGB", "color")]);
    let mut net = read(SCENE, &types);
    let noise = net.find("noise").unwrap();
    let surf = net.find("surf").unwrap();
    net.connect(surf, "emission", noise, "resultRGB");
    net.push_link(surf, "ghost", Link::missing("Nowhere", None));
    let out = write(SCENE, &net, &types);
    assert!(
        out.contains("\"reference color emission\" [\"noise:resultRGB\"]"),
        "{out}"
    );
    assert!(
        out.contains("\"reference float ghost\" [\"Nowhere\"]"),
        "{out}"
    );
}

#[test]
fn replaced_value_of_other_type_gets_a_new_decl() {
    let mut net = read(SCENE, &NoDefinitions);
    let surf = net.find("surf").unwrap();
    net.set_param(surf, "diffuseGain", Value::Int(2));
    net.set_param(
        surf,
        "diffuseColor",
        Value::Triple(BaseType::Color, [1.0, 0.25, 0.0]),
    );
    let out = write(SCENE, &net, &NoDefinitions);
    assert!(
        out.contains("\t\t\"int diffuseGain\" [2] # gain comment\n"),
        "{out}"
    );
    assert!(
        out.contains("\t\t\"color diffuseColor\" [1 0.25 0]\n"),
        "{out}"
    );
    // A source connection replaced by a value.
    net.clear_connections(surf, "presence");
    net.set_param(surf, "presence", Value::Float(0.5));
    let out = write(SCENE, &net, &NoDefinitions);
    assert!(out.contains("\t\t\"float presence\" [0.5]\n"), "{out}");
}

#[test]
fn network_built_in_code_is_written_upstream_first() {
    let mut net = Network::new();
    let surf = net.add_node_of_kind("surf", "PxrSurface", RequestKind::Bxdf);
    let noise = net.add_node("noise", "PxrFractal");
    net.set_param(noise, "layers", Value::Int(4));
    net.connect(surf, "diffuseGain", noise, "resultF");
    net.set_param(
        surf,
        "diffuseColor",
        Value::Triple(BaseType::Color, [1.0, 0.5, 0.0]),
    );
    net.set_param(surf, "label", Value::Str("say \"hi\"\n".into()));
    let m = net.add_material("MySG");
    net.set_terminal(m, "surface", surf, None);
    let out = String::from_utf8(write_rib_to_vec(b"", &net, &NoDefinitions).unwrap()).unwrap();
    insta::assert_snapshot!("built_in_code", out);
    let again = read(&out, &NoDefinitions);
    let s = again.find("surf").unwrap();
    assert_eq!(again[s].material_id(), Some("MySG"));
    assert_eq!(
        again.value(s, "label"),
        Some(&Value::Str("say \"hi\"\n".into()))
    );
    assert_eq!(
        again.connections(s, "diffuseGain")[0].upstream_node(),
        again.find("noise")
    );
}

#[test]
fn new_node_in_a_read_network_goes_before_its_first_user() {
    let src = "Pattern \"PxrFractal\" \"noise\"\n\tBxdf \"PxrSurface\" \"surf\"\n\t\t\"float diffuseGain\" [1]\nWorldBegin\n";
    let mut net = read(src, &NoDefinitions);
    let noise = net.find("noise").unwrap();
    let surf = net.find("surf").unwrap();
    let remap = net.add_node("remap", "PxrRemap");
    net.connect(remap, "inputF", noise, "resultF");
    net.connect(surf, "diffuseGain", remap, "resultF");
    let out = write(src, &net, &NoDefinitions);
    insta::assert_snapshot!("inserted_node", out);
    let again = read(&out, &NoDefinitions);
    let s = again.find("surf").unwrap();
    assert_eq!(
        again.connections(s, "diffuseGain")[0].upstream_node(),
        again.find("remap")
    );
}

#[test]
fn unused_new_node_goes_at_the_end() {
    let src = "Pattern \"PxrFractal\" \"noise\"";
    let mut net = read(src, &NoDefinitions);
    let extra = net.add_node("extra", "PxrFractal");
    net.set_param(extra, "layers", Value::Int(1));
    let out = write(src, &net, &NoDefinitions);
    assert_eq!(
        out,
        "Pattern \"PxrFractal\" \"noise\"\nPattern \"PxrFractal\" \"extra\"\n\t\"int layers\" [1]\n"
    );
}

#[test]
fn duplicate_parameters_keep_the_winner_and_move_comments() {
    let src = "Pattern \"P\" \"p\"\n\t# first\n\t\"int x\" [1]\n\t\"int y\" [0]\n\t\"int x\" [2]\n";
    let mut net = read(src, &NoDefinitions);
    let p = net.find("p").unwrap();
    net.set_param(p, "y", Value::Int(5));
    let out = write(src, &net, &NoDefinitions);
    assert_eq!(
        out,
        "Pattern \"P\" \"p\"\n\t# first\n\t\"int y\" [5]\n\t\"int x\" [2]\n"
    );
    let again = read(&out, &NoDefinitions);
    assert_eq!(summary(&again), summary(&net));
}

#[test]
fn header_comments_without_parameters() {
    let src = "Pattern # odd place\n \"P\" \"p\" \"int x\" [1]\nPattern \"Q\" # c\n \"q\"\n";
    let mut net = read(src, &NoDefinitions);
    let p = net.find("p").unwrap();
    let q = net.find("q").unwrap();
    net.set_param(p, "x", Value::Int(2));
    net.set_param(q, "y", Value::Int(3));
    let out = write(src, &net, &NoDefinitions);
    assert_eq!(
        out,
        "Pattern \"P\" \"p\"\n\t# odd place\n\t\"int x\" [2]\nPattern \"Q\" \"q\"\n\t# c\n\t\"int y\" [3]\n"
    );
}

#[test]
fn writer_rejects_mismatched_source() {
    let net = read(SCENE, &NoDefinitions);
    let err = write_rib_to_vec(b"short", &net, &NoDefinitions).unwrap_err();
    assert_eq!(err.kind(), std::io::ErrorKind::InvalidInput);
}

/// `net` written over `source` in pieces of each size, on one thread and on rayon's pool:
/// every way gives the bytes of `write_rib_to_vec`.
fn assert_pieces_agree(source: &[u8], net: &Network, types: &(dyn ParamTypes + Sync)) {
    use vstructc::back::rib::write_rib_chunked;
    let mut whole = Vec::new();
    write_rib_chunked(source, net, types, &mut whole, usize::MAX, false).unwrap();
    assert!(write_rib_to_vec(source, net, types).unwrap() == whole);
    for nodes in [1, 2, 7, 32, 100_000] {
        for parallel in [false, true] {
            let mut out = Vec::new();
            write_rib_chunked(source, net, types, &mut out, nodes, parallel).unwrap();
            assert!(
                out == whole,
                "pieces of {nodes} nodes, parallel {parallel}: {} bytes, not the {} of one pass",
                out.len(),
                whole.len()
            );
        }
    }
}

#[test]
fn pieces_in_parallel_give_the_bytes_of_one_pass() {
    use vstructc::registry::Registry;
    use vstructc::resolve::{ResolveOptions, resolve};
    use vstructc_testkit::testgen::layered_scene;
    let reg = Registry::embedded();
    // Long runs of pass-through bytes before the first request and after the last one.
    let geometry =
        "AttributeBegin\n  PointsPolygons [3] [0 1 2] \"P\" [0 0 0 1 0 0 0 1 0]\nAttributeEnd\n"
            .repeat(500);
    let rib = format!("{geometry}{}{geometry}", layered_scene(40));
    let mut net = read(&rib, &reg);
    resolve(&mut net, &reg, &ResolveOptions::default());
    assert!(net.node_ids().all(|id| net[id].source().is_some()));
    assert_pieces_agree(rib.as_bytes(), &net, &reg);
    // Every node fresh (no source): the block at the end, in pieces.
    let fresh = vstructc::back::json::write_json(&net).unwrap();
    let mut d = Diagnostics::new();
    let from_json =
        vstructc::front::json::parse_json(fresh.as_bytes(), "in.json", &reg, &mut d).unwrap();
    assert!(
        from_json
            .node_ids()
            .all(|id| from_json[id].source().is_none())
    );
    assert_pieces_agree(b"", &from_json, &reg);
}

#[test]
fn pieces_keep_a_fresh_block_before_its_reader_and_source_after_the_last_node() {
    let src = "# head\nPattern \"PxrFractal\" \"a\" \"int layers\" [1]\n\
               Pattern \"PxrFractal\" \"b\" \"int layers\" [2]\n\
               Bxdf \"PxrSurface\" \"s\" \"float diffuseGain\" [1]\nWorldEnd # tail";
    let types = defs();
    let mut net = read(src, &types);
    let s = net.find("s").unwrap();
    let t = net.add_node("t", "PxrTexture");
    net.set_param(t, "filename", Value::Str("x.tex".into()));
    net.connect(s, "diffuseColor", t, "resultRGB");
    let out = write(src, &net, &types);
    assert!(
        out.find("\"t\"").unwrap() < out.find("\"s\"").unwrap(),
        "{out}"
    );
    assert!(out.ends_with("WorldEnd # tail"), "{out}");
    assert_pieces_agree(src.as_bytes(), &net, &types);
    // Without a reader the fresh block follows the source.
    let mut alone = read(src, &types);
    let t = alone.add_node("t", "PxrTexture");
    alone.set_param(t, "filename", Value::Str("x.tex".into()));
    assert!(
        write(src, &alone, &types)
            .ends_with("# tail\nPattern \"PxrTexture\" \"t\"\n\t\"string filename\" [\"x.tex\"]\n")
    );
    assert_pieces_agree(src.as_bytes(), &alone, &types);
}

#[test]
fn pieces_stop_at_the_first_error_in_output_order() {
    use vstructc::back::rib::write_rib_chunked;
    let net = read(SCENE, &NoDefinitions);
    for parallel in [false, true] {
        let mut out = Vec::new();
        let err =
            write_rib_chunked(b"short", &net, &NoDefinitions, &mut out, 1, parallel).unwrap_err();
        assert_eq!(err.kind(), std::io::ErrorKind::InvalidInput);
    }
}

/// A connection written anew is declared with the definition's type: `[n]` for several
/// connections to a scalar input, and an array input's own size or the count of its
/// connections, also after the same input was written with one connection.
#[test]
fn new_connections_are_declared_by_count_and_array_type() {
    let types = defs().shader(
        "Mix",
        &[("colors", "color[2]"), ("gain", "float")],
        &[("out", "color")],
    );
    let mut net = Network::new();
    let f = net.add_node("f", "PxrFractal");
    net.set_param(f, "layers", Value::Int(1));
    let one = net.add_node("one", "Mix");
    net.connect(one, "gain", f, "resultF");
    net.connect(one, "colors", f, "resultRGB");
    let two = net.add_node("two", "Mix");
    net.connect(two, "gain", f, "resultF");
    net.connect(two, "gain", f, "resultF");
    net.connect(two, "colors", f, "resultRGB");
    net.connect(two, "colors", f, "resultRGB");
    let three = net.add_node("three", "Mix");
    net.connect(three, "colors", f, "resultRGB");
    let out = write("", &net, &types);
    let request = |handle: &str| {
        let at = out.find(&format!("\"{handle}\"\n")).unwrap();
        out[at..].split("\n\n").next().unwrap().to_string()
    };
    let (one, two, three) = (request("one"), request("two"), request("three"));
    assert!(
        one.contains("\t\"reference float gain\" [\"f:resultF\"]"),
        "{out}"
    );
    assert!(
        one.contains("\t\"reference color[1] colors\" [\"f:resultRGB\"]"),
        "{out}"
    );
    assert!(
        two.contains("\t\"reference float[2] gain\" [\"f:resultF\" \"f:resultF\"]"),
        "{out}"
    );
    assert!(
        two.contains("\t\"reference color[2] colors\" [\"f:resultRGB\" \"f:resultRGB\"]"),
        "{out}"
    );
    assert!(
        three.contains("\t\"reference color[1] colors\" [\"f:resultRGB\"]"),
        "{out}"
    );
}
