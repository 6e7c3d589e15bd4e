//! No heap allocation in `prepare`, `eval` and `sample` (closures.md §6.1): a counting global
//! allocator around the hot calls, after a warm-up that sizes the scratch memory and decodes
//! the albedo tables. The counter counts per thread and only while a test asks for it, so the
//! other tests of this binary, running in parallel, do not interfere.

use glam::Vec3;
use std::alloc::{GlobalAlloc, Layout, System};
use vstructc::interp::{Material, Scratch, ShadingPoint};
use vstructc_testkit::reference::ref10_ir;
use vstructc_testkit::verify::Rng;

struct Counting;

thread_local! {
    /// Count only on threads that asked for it, and per thread: the test harness runs tests
    /// in parallel, and a shared counter would see the other test's allocations.
    static COUNTING: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    static ALLOCS: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

fn count() {
    if COUNTING.with(|c| c.get()) {
        ALLOCS.with(|a| a.set(a.get() + 1));
    }
}

/// Allocations counted on this thread so far.
fn allocations() -> usize {
    ALLOCS.with(|a| a.get())
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn prepare_eval_and_sample_do_not_allocate() {
    let m = Material::new(&ref10_ir()).unwrap();
    let mut scratch = Scratch::default();
    let mut rng = Rng::new(11);
    let points: Vec<(Vec3, Vec3, [f32; 3])> = (0..200)
        .map(|_| (rng.cosine(), rng.cosine(), rng.u3()))
        .collect();
    // Warm-up: the albedo tables (decoded once per process, on first use), the scratch, the
    // per-thread scratch of `prepare`.
    vstructc::interp::tables::init_all();
    let p0 = ShadingPoint::new(Vec3::Z, Vec3::X, Vec3::Z);
    let _ = m.prepare_with(&p0, &mut scratch);
    let _ = m.prepare(&p0);
    COUNTING.with(|c| c.set(true));
    let before = allocations();
    let mut acc = Vec3::ZERO;
    for (v, l, u) in &points {
        let p = m.prepare_with(&ShadingPoint::new(Vec3::Z, Vec3::X, *v), &mut scratch);
        acc += p.eval(*l).f_cos;
        if let Some(s) = p.sample(*u) {
            acc += s.weight;
        }
        acc += p.albedo().reflect;
        let q = m.prepare(&ShadingPoint::new(Vec3::Z, Vec3::X, *l));
        acc += q.eval(*v).f_cos;
    }
    let after = allocations();
    COUNTING.with(|c| c.set(false));
    assert!(acc.is_finite());
    assert_eq!(after - before, 0, "heap allocations in prepare/eval/sample");
}

#[test]
fn the_counter_counts() {
    // The check above must be able to fail.
    COUNTING.with(|c| c.set(true));
    let before = allocations();
    let v: Vec<u64> = std::hint::black_box(vec![1, 2, 3]);
    let after = allocations();
    COUNTING.with(|c| c.set(false));
    assert!(after > before);
    drop(v);
}
