//! No lost data: resolving a full scene RIB keeps every byte outside the shading-node
//! requests (every non-network request, comment and value) and every comment inside them.
//!
//! Method: read both the input and `vstructc resolve`'s output with the RIB reader, cut each
//! text at the node source spans (`NodeSource::span`), and require the pieces between spans to
//! be equal, in order. Inside each node request, every comment of the input must still be in
//! the output's request.

use crate::common;

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::process::Command;
use vstructc::Diagnostics;
use vstructc::front::rib::{RibOptions, parse_rib};
use vstructc::network::{Network, NoDefinitions};

fn parse(bytes: &[u8], name: &str) -> Network {
    let mut diags = Diagnostics::new();
    parse_rib(
        bytes,
        name,
        &NoDefinitions,
        &RibOptions::default(),
        &mut diags,
    )
    .unwrap_or_else(|e| panic!("{name} does not parse: {e}"))
}

/// Node request spans in source order.
fn spans(net: &Network) -> Vec<Range<usize>> {
    let mut out: Vec<Range<usize>> = net
        .nodes_sorted()
        .into_iter()
        .filter_map(|id| net[id].source().map(|s| s.span.clone()))
        .collect();
    out.sort_by_key(|r| r.start);
    out
}

/// The bytes between (and before and after) the spans.
fn outside<'a>(bytes: &'a [u8], spans: &[Range<usize>]) -> Vec<&'a [u8]> {
    let mut out = Vec::new();
    let mut at = 0;
    for s in spans {
        out.push(&bytes[at..s.start]);
        at = s.end;
    }
    out.push(&bytes[at..]);
    out
}

/// Every comment (`#` to end of line) inside each node request, per request in source order.
fn inside_comments(bytes: &[u8], net: &Network) -> Vec<Vec<Vec<u8>>> {
    let mut nodes: Vec<_> = net
        .nodes_sorted()
        .into_iter()
        .filter_map(|id| net[id].source())
        .collect();
    nodes.sort_by_key(|s| s.span.start);
    nodes
        .into_iter()
        .map(|s| {
            let mut ranges: Vec<Range<usize>> = s.end_comments().to_vec();
            for k in 0..s.items.len() {
                ranges.extend(s.leading_comments(k).iter().cloned());
                ranges.extend(s.trailing_comment(k).cloned());
            }
            ranges.iter().map(|r| bytes[r.clone()].to_vec()).collect()
        })
        .collect()
}

fn resolve(path: &Path) -> Vec<u8> {
    let out = Command::new(env!("CARGO_BIN_EXE_vstructc"))
        .arg("resolve")
        .arg(path)
        .output()
        .expect("the vstructc binary runs");
    assert!(
        matches!(out.status.code(), Some(0)),
        "{}: {}",
        path.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    out.stdout
}

fn check_file(path: &Path) {
    let name = path.display().to_string();
    let input = std::fs::read(path).expect("readable");
    let output = resolve(path);
    let net_in = parse(&input, &name);
    let net_out = parse(&output, "output");
    let (s_in, s_out) = (spans(&net_in), spans(&net_out));
    assert!(!s_in.is_empty(), "{name}: no shading nodes found");
    assert_eq!(
        s_in.len(),
        s_out.len(),
        "{name}: node request count changed"
    );
    let (o_in, o_out) = (outside(&input, &s_in), outside(&output, &s_out));
    for (i, (a, b)) in o_in.iter().zip(&o_out).enumerate() {
        assert!(
            a == b,
            "{name}: text outside the network differs in gap {i}:\n--- input\n{}\n--- output\n{}",
            String::from_utf8_lossy(a),
            String::from_utf8_lossy(b)
        );
    }
    let c_out = inside_comments(&output, &net_out);
    for (i, comments) in inside_comments(&input, &net_in).iter().enumerate() {
        let request = &output[s_out[i].clone()];
        for c in comments {
            assert!(
                request.windows(c.len()).any(|w| w == c.as_slice()),
                "{name}: comment {:?} lost from node request {i}",
                String::from_utf8_lossy(c)
            );
        }
        assert!(
            c_out[i].len() >= comments.len(),
            "{name}: request {i} lost comments"
        );
    }
}

fn rib_files_under(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).expect("readable dir") {
            let p = e.expect("dir entry").path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rib") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

#[test]
fn fixture_scenes_keep_everything_outside_the_network() {
    let dir = fixtures_or_skip!();
    let files = rib_files_under(&dir.join("rib"));
    assert!(
        files
            .iter()
            .any(|f| f.ends_with("ldd/pxrLayerSurface.0001.rib")),
        "the full-scene fixture is missing"
    );
    for f in files {
        check_file(&f);
    }
}

#[test]
fn examples_and_generated_scene_keep_everything_outside_the_network() {
    let root = common::repo_dir();
    for f in rib_files_under(&root.join("examples")) {
        check_file(&f);
    }
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("no_lost_data");
    std::fs::create_dir_all(&dir).expect("scratch dir");
    let scene = dir.join("layered30.rib");
    std::fs::write(&scene, vstructc_testkit::testgen::layered_scene(30)).expect("scene");
    check_file(&scene);
}

/// The check itself must notice a change outside the network: drop one pass-through line.
#[test]
fn the_outside_comparison_detects_a_dropped_request() {
    let text = vstructc_testkit::testgen::layered_scene(2);
    let net = parse(text.as_bytes(), "scene");
    let s = spans(&net);
    let gaps = outside(text.as_bytes(), &s);
    let damaged = text.replacen("WorldBegin\n", "", 1);
    let net2 = parse(damaged.as_bytes(), "damaged");
    let s2 = spans(&net2);
    assert_ne!(gaps, outside(damaged.as_bytes(), &s2));
}
