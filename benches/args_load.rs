//! Parse `PxrLayerMixer.args` (129 KB, 409 inputs, 80 outputs) and build its vstruct tables.
//! The fixture is read once at start; the bench is skipped when it is missing.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::time::{Duration, Instant};
use vstructc::Diagnostics;
use vstructc::front::args::parse_args;
use vstructc::registry::VstructTables;

// The same allocator as the `vstructc` binary, so the numbers are what the CLI sees.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn bench_args_load(c: &mut Criterion) {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../shared/fixtures/args/pixar/PxrLayerMixer.args"
    );
    let Ok(bytes) = std::fs::read(path) else {
        eprintln!("notice: {path} not found; skipping args_load");
        return;
    };
    c.bench_function("parse PxrLayerMixer.args", |b| {
        b.iter(|| {
            let mut diags = Diagnostics::new();
            let def = parse_args(
                black_box(&bytes),
                "PxrLayerMixer.args",
                "PxrLayerMixer",
                &mut diags,
            );
            black_box(def.map(|d| d.inputs.len()).unwrap_or(0))
        })
    });
    // The machine is shared; on-CPU time of this thread (Linux schedstat) is robust to load.
    c.bench_function("parse PxrLayerMixer.args (thread CPU time)", |b| {
        b.iter_custom(|iters| {
            let start = cpu_time();
            let wall = Instant::now();
            for _ in 0..iters {
                let mut diags = Diagnostics::new();
                let def = parse_args(
                    black_box(&bytes),
                    "PxrLayerMixer.args",
                    "PxrLayerMixer",
                    &mut diags,
                );
                black_box(def.map(|d| d.inputs.len()).unwrap_or(0));
            }
            match (start, cpu_time()) {
                (Some(a), Some(b)) => b.saturating_sub(a),
                _ => wall.elapsed(),
            }
        })
    });
    let mut diags = Diagnostics::new();
    let Ok(def) = parse_args(&bytes, "PxrLayerMixer.args", "PxrLayerMixer", &mut diags) else {
        return;
    };
    c.bench_function("tables PxrLayerMixer", |b| {
        b.iter(|| {
            let mut d = Vec::new();
            black_box(VstructTables::build(black_box(&def), &mut d))
        })
    });
}

/// On-CPU time of the calling thread, from `/proc/thread-self/schedstat` (Linux).
fn cpu_time() -> Option<Duration> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: u64 = text.split_whitespace().next()?.parse().ok()?;
    Some(Duration::from_nanos(ns))
}

criterion_group!(benches, bench_args_load);
criterion_main!(benches);
