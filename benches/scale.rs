//! Scaling shapes (target: the 4N run ≤ 5× the N run, BENCHMARKS.md): each shape of
//! `vstructc_testkit::testgen::Shape` through read, resolution and write, at sizes N and 4N, with
//! the measured 4N / N ratio printed after each pair.
//!
//! `cargo bench --bench scale`. The pipeline is the one `vstructc resolve` runs (registry with
//! the shape's definition, RIB read, resolution, RIB write), at a quarter of the sizes of the
//! whole-process figures to keep the bench short. `scale_info` reads the `.args` shapes at
//! the sizes of their `info` targets (100,000 parameters, 20,000 heads; ≤ 1 s each) as
//! `vstructc info` does.

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::time::{Duration, Instant};
use vstructc::Diagnostics;
use vstructc::back::rib::write_rib_to_vec;
use vstructc::front::rib::{RibOptions, parse_rib};
use vstructc::registry::Registry;
use vstructc::resolve::{ResolveOptions, resolve};
use vstructc_testkit::testgen::{Shape, ShapeScene};

// The same allocator as the `vstructc` binary, so the numbers are what the CLI sees.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn pipeline(scene: &ShapeScene) -> Vec<u8> {
    let mut registry = Registry::embedded();
    if let Some((id, text)) = &scene.args {
        registry.add_args_text(id, text).expect("generated .args");
    }
    let mut diags = Diagnostics::new();
    let rib = scene.rib.as_bytes();
    let mut net = parse_rib(
        rib,
        "scene.rib",
        &registry,
        &RibOptions::default(),
        &mut diags,
    )
    .expect("generated scene parses");
    black_box(resolve(&mut net, &registry, &ResolveOptions::default()));
    write_rib_to_vec(rib, &net, &registry).expect("written")
}

/// N for each shape (a quarter of the whole-process figure's).
fn size(shape: Shape) -> usize {
    match shape {
        Shape::SharedLayer | Shape::SharedMixer => 1250,
        Shape::FanIn | Shape::ArgsParams | Shape::ArgsParamsOneLine => 2500,
        Shape::RedefinedBxdf => 625,
        Shape::ArgsHeads | Shape::ArgsHeadsOneLine => 1250,
    }
}

/// The mean time of `runs` pipelines on `scene`.
fn mean(scene: &ShapeScene, runs: u32) -> Duration {
    let start = Instant::now();
    for _ in 0..runs {
        black_box(pipeline(scene));
    }
    start.elapsed() / runs
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("scale");
    group.sample_size(10);
    for shape in Shape::ALL {
        let n = size(shape);
        let scenes = [shape.scene(n), shape.scene(4 * n)];
        for (scene, k) in scenes.iter().zip([n, 4 * n]) {
            group.bench_with_input(BenchmarkId::new(shape.name(), k), scene, |b, s| {
                b.iter(|| pipeline(s))
            });
        }
        // Criterion reports each size on its own; the ratio is what the target is about.
        let ratio = mean(&scenes[1], 3).as_secs_f64() / mean(&scenes[0], 3).as_secs_f64();
        println!("scale/{}: 4N / N = {ratio:.2}× (target ≤ 5×)", shape.name());
    }
    group.finish();
}

/// What `vstructc info` asks of the library for the shape's definition: the file read into
/// a registry, its definition and its vstruct tables (the printing is the command's).
fn info(scene: &ShapeScene) -> usize {
    let (id, text) = scene.args.as_ref().expect("an .args shape");
    let mut registry = Registry::embedded();
    registry.add_args_text(id, text).expect("generated .args");
    let def = registry.definition(id).expect("defined");
    let tables = registry.tables(id).expect("tables");
    black_box(&tables);
    def.inputs.len()
}

/// The `.args` shapes at the sizes of the `info` targets: 100,000 parameters and 20,000 heads
/// with a member each, each file on one line and as one declaration per line.
fn bench_info(c: &mut Criterion) {
    let mut group = c.benchmark_group("scale_info");
    group.sample_size(10);
    for (shape, n) in [
        (Shape::ArgsParams, 100_000),
        (Shape::ArgsParamsOneLine, 100_000),
        (Shape::ArgsHeads, 20_000),
        (Shape::ArgsHeadsOneLine, 20_000),
    ] {
        let scene = shape.scene(n);
        group.bench_with_input(BenchmarkId::new(shape.name(), n), &scene, |b, s| {
            b.iter(|| info(s))
        });
    }
    group.finish();
}

criterion_group!(benches, bench, bench_info);
criterion_main!(benches);
