//! RIB reader and writer on a generated scene of layered materials (3 PxrLayers → PxrLayerMixer
//! → PxrLayerSurface each, placeholder connections as in formats.md §3.5).
//!
//! `cargo bench --bench rib -- --quick`

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;
use vstructc::Diagnostics;
use vstructc::Value;
use vstructc::back::rib::write_rib_to_vec;
use vstructc::front::rib::{RibOptions, parse_rib};
use vstructc::network::NoDefinitions;
use vstructc_testkit::testgen;

// The same allocator as the `vstructc` binary, so the numbers are what the CLI sees.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn parse(scene: &[u8]) -> vstructc::network::Network {
    let mut d = Diagnostics::new();
    parse_rib(
        scene,
        "scene.rib",
        &NoDefinitions,
        &RibOptions::default(),
        &mut d,
    )
    .expect("generated scene parses")
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("rib");
    group.sample_size(10);
    for materials in [10_000usize, 20_000] {
        let scene = testgen::layered_scene(materials);
        group.throughput(Throughput::Bytes(scene.len() as u64));
        group.bench_with_input(BenchmarkId::new("parse", materials), &scene, |b, s| {
            b.iter(|| parse(black_box(s.as_bytes())))
        });
        let net = parse(scene.as_bytes());
        group.bench_with_input(
            BenchmarkId::new("write_unmodified", materials),
            &net,
            |b, n| {
                b.iter(|| {
                    write_rib_to_vec(scene.as_bytes(), black_box(n), &NoDefinitions).expect("write")
                })
            },
        );
        // Every mixer and surface modified (as resolution would): all re-serialised.
        let mut edited = net.clone();
        let ids: Vec<_> = edited.node_ids().collect();
        for id in ids {
            if edited[id].shader() == "PxrLayerMixer" {
                edited.set_param(id, "layer2Mask", Value::Float(0.75));
            } else if edited[id].shader() == "PxrLayerSurface" {
                edited.clear_connections(id, "inputMaterial");
            }
        }
        group.bench_with_input(
            BenchmarkId::new("write_modified", materials),
            &edited,
            |b, n| {
                b.iter(|| {
                    write_rib_to_vec(scene.as_bytes(), black_box(n), &NoDefinitions).expect("write")
                })
            },
        );
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
