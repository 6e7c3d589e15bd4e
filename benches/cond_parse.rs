//! Parse every distinct real conditional expression from `../shared/fixtures` (args, oso and
//! the Laika OSL through `cpp`, scanned at start-up).
//!
//! Run: `cargo bench --bench cond_parse -- --quick`. The reported time is for one pass over
//! all distinct expressions; divide by the printed count for ns per expression.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;
use std::path::PathBuf;
use vstructc::cond;

#[path = "../tests/vectors/cond/scan.rs"]
mod scan;

fn fixture_exprs() -> Vec<String> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/fixtures");
    if !dir.is_dir() {
        eprintln!("notice: ../shared/fixtures not found; benchmarking the §11.1 examples only");
        return [
            "connect if enableDiffuse == 1 ",
            "set 1 if enableDiffuse == 1 else set 0 ",
            "connect if (baselayer_enableDiffuse == 1 or  layer1_enableDiffuse == 1) ",
        ]
        .map(String::from)
        .to_vec();
    }
    scan::distinct_fixture_exprs(&dir)
}

fn bench(c: &mut Criterion) {
    let exprs = fixture_exprs();
    let bytes: usize = exprs.iter().map(String::len).sum();
    for e in &exprs {
        assert!(cond::parse(e).is_ok(), "{e:?}");
    }
    eprintln!(
        "cond_parse: {} distinct expressions, {bytes} bytes in total",
        exprs.len()
    );
    let mut group = c.benchmark_group("cond_parse");
    group.throughput(Throughput::Elements(exprs.len() as u64));
    group.bench_function("all_distinct_fixture_exprs", |b| {
        b.iter(|| {
            for e in &exprs {
                black_box(cond::parse(black_box(e)).ok());
            }
        })
    });
    group.finish();

    let longest = exprs
        .iter()
        .max_by_key(|e| e.len())
        .cloned()
        .unwrap_or_default();
    c.bench_function("cond_parse/longest", |b| {
        b.iter(|| black_box(cond::parse(black_box(&longest)).ok()))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
