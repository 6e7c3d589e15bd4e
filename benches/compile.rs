//! Compile (lower) 10,000 layered materials: 3 PxrLayers → PxrLayerMixer → PxrLayerSurface
//! each. `network/*`: the generated RIB scene (`vstructc_testkit::testgen::layered_scene`), parsed and
//! resolved once outside the timing, lowered with the embedded definitions; `graph/*`: the
//! same shape built directly as a `SimpleGraph` without definitions. Each sequentially and
//! with rayon across materials.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use vstructc::Diagnostics;
use vstructc::front::rib::{RibOptions, parse_rib};
use vstructc::lower::network::terminals;
use vstructc::lower::{NoDefinitions, lower_many};
use vstructc::registry::Registry;
use vstructc::resolve::{ResolveOptions, resolve};
use vstructc_testkit::scene::layered_scene;

// The same allocator as the `vstructc` binary, so the numbers are what the CLI sees.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

const N: usize = 10_000;

fn bench(c: &mut Criterion) {
    let reg = Registry::embedded();
    let rib = vstructc_testkit::testgen::layered_scene(N);
    let mut diags = Diagnostics::new();
    let mut net = parse_rib(
        rib.as_bytes(),
        "scene.rib",
        &reg,
        &RibOptions::default(),
        &mut diags,
    )
    .expect("scene parses");
    resolve(&mut net, &reg, &ResolveOptions::default());
    let net_terminals = terminals(&net, None).expect("terminals");
    assert_eq!(net_terminals.len(), N);
    let (g, graph_terminals) = layered_scene(N);

    let mut group = c.benchmark_group("compile_10k");
    group.sample_size(10);
    group.bench_function("network/single_thread", |b| {
        b.iter(|| black_box(lower_many(&net, &reg, &net_terminals, false)))
    });
    group.bench_function("network/rayon", |b| {
        b.iter(|| black_box(lower_many(&net, &reg, &net_terminals, true)))
    });
    group.bench_function("graph/single_thread", |b| {
        b.iter(|| black_box(lower_many(&g, &NoDefinitions, &graph_terminals, false)))
    });
    group.bench_function("graph/rayon", |b| {
        b.iter(|| black_box(lower_many(&g, &NoDefinitions, &graph_terminals, true)))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
