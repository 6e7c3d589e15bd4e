//! The repository's example networks (`examples/*.rib`) read cleanly and write back unchanged.

use crate::common::network as network_common;

use network_common::{codes, summary};
use vstructc::back::rib::write_rib_to_vec;
use vstructc::front::rib::{RibOptions, parse_rib};
use vstructc::network::NoDefinitions;
use vstructc::{Diagnostics, Value};

#[test]
fn examples_round_trip() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let mut paths: Vec<_> = std::fs::read_dir(&dir)
        .map(|rd| rd.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    paths.retain(|p| p.extension().is_some_and(|x| x == "rib"));
    paths.sort();
    for path in paths {
        let bytes = std::fs::read(&path).unwrap();
        let mut d = Diagnostics::new();
        let name = path.display().to_string();
        let mut net = parse_rib(
            &bytes,
            &name,
            &NoDefinitions,
            &RibOptions::default(),
            &mut d,
        )
        .unwrap();
        assert!(d.is_empty(), "{name}: {:?}", codes(&d));
        assert!(!net.materials().is_empty(), "{name}: no material");
        assert_eq!(
            write_rib_to_vec(&bytes, &net, &NoDefinitions).unwrap(),
            bytes,
            "{name}"
        );
        // Re-serialise every node and read it back.
        let before = summary(&net);
        let ids: Vec<_> = net.node_ids().collect();
        for id in ids {
            net.set_param(id, "__probe", Value::Int(1));
        }
        let out = write_rib_to_vec(&bytes, &net, &NoDefinitions).unwrap();
        let mut again =
            parse_rib(&out, &name, &NoDefinitions, &RibOptions::default(), &mut d).unwrap();
        let ids: Vec<_> = again.node_ids().collect();
        for id in ids {
            assert_eq!(again.remove_value(id, "__probe"), Some(Value::Int(1)));
        }
        let mut after = summary(&again);
        after.retain(|l| !l.contains("__probe"));
        assert_eq!(after, before, "{name}");
    }
}
