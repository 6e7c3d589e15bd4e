//! `lutgen`: generates the interpreter's albedo tables (see docs/albedo-tables.md).
//!
//! Usage: `cargo run --release --features testkit --example lutgen -- [--out DIR] [--only 2d|ggx|diel|diel-fwd|diel-inv|aniso|aniso-az|all]` (default: all groups, into
//! `src/interp/tables/` of this crate). Run it in release mode; the 3-D dielectric tables
//! take several CPU-minutes. Each group's tables (and the `Eavg` tables derived from them)
//! are written as soon as the group is done. `--entry NAME I J K` prints one entry.

use std::path::PathBuf;
use std::time::Instant;
use vstructc::interp::tables::{self, TableId};
use vstructc_testkit::lutgen::{self, GENERATOR_VERSION, Group};

fn main() {
    let mut out = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src/interp/tables");
    let mut only = String::from("all");
    let argv: Vec<String> = std::env::args().skip(1).collect();
    if argv.first().map(String::as_str) == Some("--entry") {
        print_entry(&argv[1..]);
        return;
    }
    let mut args = argv.into_iter();
    while let Some(a) = args.next() {
        match (a.as_str(), args.next()) {
            ("--out", Some(v)) => out = PathBuf::from(v),
            ("--only", Some(v)) => only = v,
            _ => {
                eprintln!(
                    "usage: lutgen [--out DIR] [--only 2d|ggx|diel|diel-fwd|diel-inv|aniso|aniso-az|all]"
                );
                std::process::exit(2);
            }
        }
    }
    if let Err(e) = std::fs::create_dir_all(&out) {
        eprintln!("error: cannot create {}: {e}", out.display());
        std::process::exit(1);
    }
    for group in Group::ALL {
        let selected = match only.as_str() {
            "all" => true,
            "2d" => matches!(group, Group::Single(_) | Group::Ggx(_)),
            "ggx" => matches!(group, Group::Ggx(_)),
            "diel" => matches!(group, Group::Dielectric(_)),
            "diel-fwd" => group == Group::Dielectric(false),
            "diel-inv" => group == Group::Dielectric(true),
            "aniso" => matches!(group, Group::Aniso(_)),
            // Only the tables with the view off azimuth 0 (22.5° and 45°).
            "aniso-az" => {
                matches!(group, Group::Aniso(t) if lutgen::aniso_azimuth(t) != Some(0.0))
            }
            _ => false,
        };
        if !selected {
            continue;
        }
        let start = Instant::now();
        for (id, data) in lutgen::generate(group) {
            write(&out, id, &data);
            if let Some(avg) = TableId::ALL.iter().find(|t| t.eavg_parent() == Some(id)) {
                write(&out, *avg, &lutgen::eavg_from(&data));
            }
        }
        eprintln!("{group:?}: {:.1} s", start.elapsed().as_secs_f64());
    }
}

/// `--entry NAME I J K`: computes and prints one entry (for checks).
fn print_entry(args: &[String]) {
    let id = TableId::ALL
        .iter()
        .find(|t| Some(t.name()) == args.first().map(String::as_str));
    let idx: Vec<usize> = args.iter().skip(1).filter_map(|a| a.parse().ok()).collect();
    match (id, idx.as_slice()) {
        (Some(id), [i, j, k]) => println!("{:.8}", lutgen::compute_entry(*id, [*i, *j, *k])),
        _ => {
            eprintln!("usage: lutgen --entry NAME I J K");
            std::process::exit(2);
        }
    }
}

fn write(dir: &std::path::Path, id: TableId, data: &[f32]) {
    let g = lutgen::grid(id);
    let bytes = tables::encode(id, GENERATOR_VERSION, (g * g) as u32, data);
    let path = dir.join(format!("{}.lut", id.name()));
    if let Err(e) = std::fs::write(&path, bytes) {
        eprintln!("error: cannot write {}: {e}", path.display());
        std::process::exit(1);
    }
    eprintln!("wrote {}", path.display());
}
