//! Parse every distinct real conditional expression from `../shared/fixtures` (args, oso and
//! the Laika OSL through `cpp`, scanned at start-up).
//!
//! Run: `cargo bench --bench cond_parse -- --quick`. The reported time is for one pass over
//! all distinct expressions; divide by the printed count for ns per expression. The
//! `cond_chain` group parses and evaluates one 100,000-term `and` chain.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;
use std::path::PathBuf;
use vstructc::cond;

#[path = "../tests/vectors/cond/scan.rs"]
mod scan;

fn fixture_exprs() -> Vec<String> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/fixtures");
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

/// A 100,000-term `and` chain (about 1.1 MB of text): parse, and evaluate to the end. Both
/// are linear in the terms (n-ary chain nodes, no token list).
fn long_chain(c: &mut Criterion) {
    let terms = 100_000;
    let preds = ["a == 1", "b == 2", "c >= 3"];
    let text = format!(
        "connect if {}",
        (0..terms)
            .map(|i| preds[i % 3])
            .collect::<Vec<_>>()
            .join(" and ")
    );
    let up = cond::MapUpstream::new()
        .input("a", Some(vstructc::Value::Int(1)))
        .input("b", Some(vstructc::Value::Int(2)))
        .input("c", Some(vstructc::Value::Int(3)));
    let stmt = cond::parse(&text).expect("the chain parses");
    let mut group = c.benchmark_group("cond_chain");
    group.throughput(Throughput::Elements(terms as u64));
    group.sample_size(20);
    group.bench_function("parse_100k_terms", |b| {
        b.iter(|| black_box(cond::parse(black_box(&text)).ok()))
    });
    group.bench_function("evaluate_100k_terms", |b| {
        b.iter(|| black_box(cond::evaluate(&stmt, &up, &cond::Extensions::none()).choice))
    });
    group.finish();
}

criterion_group!(benches, bench, long_chain);
criterion_main!(benches);
