//! Resolution throughput on a generated scene of layered materials (targets: resolve
//! 10,000 materials ≤ 300 ms single-threaded; doubling the scene ≤ 2.2× the time).
//!
//! `scene/*` is wall-clock time (`parse`, `parse_json` and `write` also as MB/s of the text read
//! or written; the readers' rows leave the dropping of the network out); `scene/parse_json`
//! reads the same network from its JSON form (target: ≤ 1.5× `scene/parse`). `scene_cpu/resolve` is the same resolution measured as the
//! thread's CPU time (ns): resolution is single-threaded, and on the shared development
//! machine wall-clock time mostly measures the other processes. `scene_cpu/parse` is the RIB
//! reader's CPU time on the calling thread, for the same reason: with the `parallel` feature a
//! large input is tokenized on a second thread, whose time this row leaves out (the calling
//! thread assembles the network, the longer of the two halves).

use criterion::measurement::Measurement;
use criterion::{
    BenchmarkGroup, BenchmarkId, Criterion, Throughput, criterion_group, criterion_main,
};

#[path = "common/cpu_time.rs"]
mod cpu_time;
use cpu_time::CpuTime;
use std::hint::black_box;
use vstructc::Diagnostics;
use vstructc::back::json::write_json;
use vstructc::back::rib::{write_rib, write_rib_to_vec};
use vstructc::front::json::parse_json;
use vstructc::front::rib::{RibOptions, parse_rib};
use vstructc::network::Network;
use vstructc::registry::Registry;
use vstructc::resolve::{ResolveOptions, resolve};
use vstructc_testkit::testgen::layered_scene;

// The same allocator as the `vstructc` binary, so the numbers are what the CLI sees.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// `resolve/{materials}`: resolution of a fresh copy of `parsed` (the copy is not timed).
fn bench_resolve<M: Measurement>(
    group: &mut BenchmarkGroup<'_, M>,
    reg: &Registry,
    parsed: &Network,
    materials: usize,
) {
    group.bench_with_input(
        BenchmarkId::new("resolve", materials),
        &materials,
        |b, _| {
            b.iter_batched(
                || parsed.clone(),
                |mut net| {
                    let res = resolve(&mut net, reg, &ResolveOptions::default());
                    black_box((net, res))
                },
                criterion::BatchSize::LargeInput,
            )
        },
    );
}

fn bench(c: &mut Criterion) {
    let reg = Registry::embedded();
    let mut group = c.benchmark_group("scene");
    group.sample_size(10);
    for materials in [10_000usize, 20_000] {
        let rib = layered_scene(materials).into_bytes();
        let parse = || {
            let mut diags = Diagnostics::new();
            parse_rib(&rib, "scene.rib", &reg, &RibOptions::default(), &mut diags).unwrap()
        };
        let parsed = parse();
        group.throughput(Throughput::Bytes(rib.len() as u64));
        // The network is dropped outside the timing (as the command line, which leaves it
        // to the operating system at exit): the rows measure reading.
        group.bench_with_input(BenchmarkId::new("parse", materials), &materials, |b, _| {
            b.iter_with_large_drop(parse)
        });
        let json = write_json(&parsed).unwrap().into_bytes();
        group.throughput(Throughput::Bytes(json.len() as u64));
        group.bench_with_input(
            BenchmarkId::new("parse_json", materials),
            &materials,
            |b, _| {
                b.iter_with_large_drop(|| {
                    let mut diags = Diagnostics::new();
                    parse_json(&json, "scene.json", &reg, &mut diags).unwrap()
                })
            },
        );
        drop(json);
        group.throughput(Throughput::Elements(materials as u64));
        bench_resolve(&mut group, &reg, &parsed, materials);
        let mut resolved = parsed.clone();
        resolve(&mut resolved, &reg, &ResolveOptions::default());
        // Bytes written per second.
        let written = write_rib_to_vec(&rib, &resolved, &reg).unwrap().len();
        group.throughput(Throughput::Bytes(written as u64));
        // Into one buffer kept across iterations, as the CLI streams into a buffered file: the
        // row measures the writer, not the growth of a 74 MB vector.
        let mut out = Vec::with_capacity(written);
        group.bench_with_input(BenchmarkId::new("write", materials), &materials, |b, _| {
            b.iter(|| {
                out.clear();
                write_rib(&rib, &resolved, &reg, &mut out).unwrap();
                black_box(out.len())
            })
        });
    }
    group.finish();
}

fn bench_cpu(c: &mut Criterion<CpuTime>) {
    let reg = Registry::embedded();
    let mut group = c.benchmark_group("scene_cpu");
    group.sample_size(10);
    for materials in [10_000usize, 20_000] {
        let rib = layered_scene(materials).into_bytes();
        let parse = || {
            let mut diags = Diagnostics::new();
            parse_rib(&rib, "scene.rib", &reg, &RibOptions::default(), &mut diags).unwrap()
        };
        let parsed = parse();
        group.bench_with_input(BenchmarkId::new("parse", materials), &materials, |b, _| {
            b.iter_with_large_drop(parse)
        });
        bench_resolve(&mut group, &reg, &parsed, materials);
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_group! {
    name = cpu;
    config = Criterion::default().with_measurement(CpuTime);
    targets = bench_cpu
}
criterion_main!(benches, cpu);
