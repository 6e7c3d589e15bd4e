//! USD input against RIB input (target: a 1,000-material `.usdc` reads and resolves
//! in ≤ 2× the time of the same network in RIB).
//!
//! `usd/rib/1000` reads and resolves the generated layered scene from RIB; `usd/usdc/1000`
//! and `usd/usda/1000` the same network written by vstructc's USD writer in each encoding,
//! read back through `openusd` and resolved (nothing in these layers composes, so the reader
//! takes each root layer's specs as they are). Wall-clock time.

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use vstructc::Diagnostics;
use vstructc::back::usd::{UsdMode, write_usd};
use vstructc::front::rib::{RibOptions, parse_rib};
use vstructc::front::usd::parse_usd;
use vstructc::limits::Limits;
use vstructc::registry::Registry;
use vstructc::resolve::{ResolveOptions, resolve};
use vstructc_testkit::testgen::layered_scene;

// The same allocator as the `vstructc` binary, so the numbers are what the CLI sees.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn bench(c: &mut Criterion) {
    let reg = Registry::embedded();
    let materials = 1000usize;
    let rib = layered_scene(materials).into_bytes();
    let mut diags = Diagnostics::new();
    let net = parse_rib(&rib, "scene.rib", &reg, &RibOptions::default(), &mut diags).unwrap();
    let mut usda = Vec::new();
    write_usd(&net, &reg, UsdMode::Flatten, "usda", &mut usda).unwrap();
    let mut usdc = Vec::new();
    write_usd(&net, &reg, UsdMode::Flatten, "usdc", &mut usdc).unwrap();
    let mut group = c.benchmark_group("usd");
    group.sample_size(10);
    group.bench_with_input(BenchmarkId::new("rib", materials), &rib, |b, rib| {
        b.iter(|| {
            let mut diags = Diagnostics::new();
            let mut net =
                parse_rib(rib, "scene.rib", &reg, &RibOptions::default(), &mut diags).unwrap();
            let res = resolve(&mut net, &reg, &ResolveOptions::default());
            black_box((net, res))
        })
    });
    for (name, bytes) in [("usdc", &usdc), ("usda", &usda)] {
        let file = format!("scene.{name}");
        group.bench_with_input(BenchmarkId::new(name, materials), bytes, |b, bytes| {
            b.iter(|| {
                let mut diags = Diagnostics::new();
                let mut net =
                    parse_usd(bytes, &file, &reg, &Limits::default(), &mut diags).unwrap();
                let res = resolve(&mut net, &reg, &ResolveOptions::default());
                black_box((net, res))
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
