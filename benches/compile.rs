//! Compile (lower) the generated layered scene: 3 PxrLayers → PxrLayerMixer →
//! PxrLayerSurface per material, sequentially and with rayon across materials.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use vstructc::lower::{NoDefinitions, lower_many, scene::layered_scene};

fn bench(c: &mut Criterion) {
    let (g, terminals) = layered_scene(10_000);
    let mut group = c.benchmark_group("compile_10k");
    group.sample_size(10);
    group.bench_function("single_thread", |b| {
        b.iter(|| black_box(lower_many(&g, &NoDefinitions, &terminals, false)))
    });
    group.bench_function("rayon", |b| {
        b.iter(|| black_box(lower_many(&g, &NoDefinitions, &terminals, true)))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
