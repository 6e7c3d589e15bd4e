//! Linear scaling guard: every shape of `vstructc_testkit::testgen::Shape` goes through the whole
//! pipeline (registry, RIB read, resolution, RIB and JSON write, JSON read, RIB write of the
//! JSON network) at size `n` and `4n`, and the `4n` run may cost at most 8× the `n` run
//! (linear work is 4×; a quadratic path is 16×).
//!
//! The cost is counted, not timed, so the test means the same on every machine:
//!
//! * heap allocations, by a counting global allocator (per thread, so tests running in
//!   parallel do not disturb each other);
//! * instructions retired in user space, by the CPU's counter (`perf_event_open`), which also
//!   sees quadratic paths that do not allocate (scans, linked-list walks). Where the kernel
//!   does not allow it (containers and virtual machines often refuse hardware counters),
//!   this count is reported as not available and the thread's CPU time stands in for it:
//!   the best of three runs at each size, against the same bound (a quadratic path that does
//!   not allocate, such as counting the characters from a line's start for every position of
//!   a file written on one line, is 16× and fails it; linear work is 4×, so the bound leaves
//!   a factor of 2 for the noise of a shared machine).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use vstructc::Diagnostics;
use vstructc::back::json::write_json;
use vstructc::back::rib::write_rib_to_vec;
use vstructc::front::json::parse_json;
use vstructc::front::rib::{RibOptions, parse_rib};
use vstructc::registry::Registry;
use vstructc::resolve::{ResolveOptions, resolve};
use vstructc_testkit::testgen::{Shape, ShapeScene};

struct Counting;

thread_local! {
    /// (allocations, bytes requested) by this thread.
    static ALLOCATIONS: Cell<(u64, u64)> = const { Cell::new((0, 0)) };
}

fn count(bytes: usize) {
    let _ = ALLOCATIONS.try_with(|c| {
        let (n, b) = c.get();
        c.set((n + 1, b + bytes as u64));
    });
}

// SAFETY: every call is forwarded to `System` unchanged; the counter is a const-initialised
// thread-local, which does not allocate.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count(layout.size());
        // SAFETY: forwarded with the caller's layout.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from `System.alloc` with this layout.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count(layout.size());
        // SAFETY: forwarded with the caller's layout.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // A reallocation may copy the whole block: count its new size.
        count(new_size);
        // SAFETY: `ptr` came from `System` with `layout`; forwarded unchanged.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

fn allocations() -> (u64, u64) {
    ALLOCATIONS.with(Cell::get)
}

/// The user-space instructions retired by the calling thread, via `perf_event_open`.
#[cfg(target_os = "linux")]
mod instructions {
    /// `struct perf_event_attr` up to `config2` (the size the kernel is told).
    #[repr(C)]
    #[derive(Default)]
    struct Attr {
        kind: u32,
        size: u32,
        config: u64,
        sample_period: u64,
        sample_type: u64,
        read_format: u64,
        flags: u64,
        wakeup_events: u32,
        bp_type: u32,
        config1: u64,
        config2: u64,
    }

    const PERF_TYPE_HARDWARE: u32 = 0;
    const PERF_COUNT_HW_INSTRUCTIONS: u64 = 1;
    /// `disabled` is bit 0, `exclude_kernel` bit 5, `exclude_hv` bit 6.
    const FLAGS: u64 = 1 | 1 << 5 | 1 << 6;
    const ENABLE: libc::c_ulong = 0x2400;
    const DISABLE: libc::c_ulong = 0x2401;
    const RESET: libc::c_ulong = 0x2403;

    /// A counter of this thread's instructions, if the kernel allows one.
    pub struct Counter(libc::c_int);

    impl Counter {
        pub fn new() -> Option<Counter> {
            let attr = Attr {
                kind: PERF_TYPE_HARDWARE,
                size: std::mem::size_of::<Attr>() as u32,
                config: PERF_COUNT_HW_INSTRUCTIONS,
                flags: FLAGS,
                ..Attr::default()
            };
            // SAFETY: `attr` is a valid perf_event_attr prefix of the size given; pid 0 and
            // cpu -1 measure the calling thread on any CPU.
            let fd = unsafe {
                libc::syscall(
                    libc::SYS_perf_event_open,
                    &attr as *const Attr,
                    0,
                    -1,
                    -1,
                    0,
                )
            };
            (fd >= 0).then(|| Counter(fd as libc::c_int))
        }

        /// The instructions `f` retires.
        pub fn count(&self, f: impl FnOnce()) -> Option<u64> {
            // SAFETY: plain ioctls on the counter's own descriptor.
            unsafe {
                libc::ioctl(self.0, RESET, 0);
                libc::ioctl(self.0, ENABLE, 0);
            }
            f();
            let mut value = 0u64;
            // SAFETY: reads 8 bytes into `value` from the counter's own descriptor.
            let read = unsafe {
                libc::ioctl(self.0, DISABLE, 0);
                libc::read(self.0, (&mut value as *mut u64).cast(), 8)
            };
            (read == 8 && value > 0).then_some(value)
        }
    }

    impl Drop for Counter {
        fn drop(&mut self) {
            // SAFETY: closes the descriptor this counter owns.
            unsafe { libc::close(self.0) };
        }
    }
}

/// Elsewhere there is no instruction counter.
#[cfg(not(target_os = "linux"))]
mod instructions {
    pub struct Counter;

    impl Counter {
        pub fn new() -> Option<Counter> {
            None
        }

        pub fn count(&self, f: impl FnOnce()) -> Option<u64> {
            f();
            None
        }
    }
}

/// The whole pipeline on one scene.
fn pipeline(scene: &ShapeScene) {
    let mut registry = Registry::embedded();
    if let Some((id, text)) = &scene.args {
        registry
            .add_args_text(id, text)
            .expect("generated .args parses");
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
    let res = resolve(&mut net, &registry, &ResolveOptions::default());
    std::hint::black_box(&res);
    let written = write_rib_to_vec(rib, &net, &registry).expect("RIB written");
    // A scene without material has no JSON form (the writer says so): nothing to read back.
    let rewritten = match write_json(&net) {
        Ok(json) => {
            let from_json = parse_json(json.as_bytes(), "scene.json", &registry, &mut diags)
                .expect("JSON reads");
            write_rib_to_vec(b"", &from_json, &registry).expect("RIB written")
        }
        Err(_) => Vec::new(),
    };
    std::hint::black_box((written, rewritten, diags));
}

/// The base size of each shape: large enough that fixed costs (the embedded registry) do
/// not hide the growth, small enough for a debug-build test.
fn base_size(shape: Shape) -> usize {
    match shape {
        Shape::SharedLayer | Shape::SharedMixer => 250,
        Shape::FanIn => 500,
        Shape::RedefinedBxdf => 1000,
        Shape::ArgsParams => 2000,
        Shape::ArgsHeads => 500,
        Shape::ArgsParamsOneLine => 2000,
        Shape::ArgsHeadsOneLine => 500,
    }
}

/// The largest `4n` / `n` cost ratio allowed.
const MAX_RATIO: f64 = 8.0;

/// What one run cost.
struct Cost {
    allocations: u64,
    /// Bytes requested by allocations and reallocations (a reallocation may copy its block,
    /// so growing a vector one element at a time shows here as quadratic).
    bytes: u64,
    instructions: Option<u64>,
    /// The calling thread's CPU time in nanoseconds, best of [`TIMED_RUNS`], when there is no
    /// instruction count.
    cpu_nanos: Option<u64>,
}

/// Runs timed when the CPU time stands in for the instruction count.
const TIMED_RUNS: usize = 3;

/// The CPU time the calling thread has used, in nanoseconds.
fn thread_cpu_nanos() -> Option<u64> {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid timespec the call writes into.
    let ok = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) } == 0;
    ok.then(|| t.tv_sec as u64 * 1_000_000_000 + t.tv_nsec as u64)
}

/// The cost of the pipeline on `shape` at size `n`.
fn cost(shape: Shape, n: usize, counter: Option<&instructions::Counter>) -> Cost {
    let scene = shape.scene(n);
    // A warm-up run, so one-off costs (lazy statics) fall outside the measurement.
    pipeline(&shape.scene(1));
    let before = allocations();
    let start = std::time::Instant::now();
    let instructions = match counter {
        Some(c) => c.count(|| pipeline(&scene)),
        None => {
            pipeline(&scene);
            None
        }
    };
    // Shown for information only: time depends on the machine and its load.
    eprintln!("{}: n = {n}: {:?}", shape.name(), start.elapsed());
    let after = allocations();
    let cpu_nanos = if instructions.is_some() {
        None
    } else {
        (0..TIMED_RUNS)
            .map(|_| {
                let t0 = thread_cpu_nanos()?;
                pipeline(&scene);
                Some(thread_cpu_nanos()?.saturating_sub(t0))
            })
            .min()
            .flatten()
    };
    Cost {
        allocations: after.0 - before.0,
        bytes: after.1 - before.1,
        instructions,
        cpu_nanos,
    }
}

/// Fails if the `4n` run cost more than [`MAX_RATIO`] times the `n` run in `what`.
fn assert_linear(shape: Shape, what: &str, at_n: u64, at_4n: u64) {
    let ratio = at_4n as f64 / at_n.max(1) as f64;
    eprintln!("{}: {what} {at_n} → {at_4n} ({ratio:.2}×)", shape.name());
    assert!(
        ratio <= MAX_RATIO,
        "{}: 4× the size costs {ratio:.2}× the {what} ({at_n} → {at_4n}); at most \
         {MAX_RATIO}× is linear",
        shape.name()
    );
}

fn check(shape: Shape) {
    let counter = instructions::Counter::new();
    let n = base_size(shape);
    let one = cost(shape, n, counter.as_ref());
    let four = cost(shape, 4 * n, counter.as_ref());
    assert_linear(shape, "allocations", one.allocations, four.allocations);
    assert_linear(shape, "bytes allocated", one.bytes, four.bytes);
    match (one.instructions, four.instructions) {
        (Some(at_n), Some(at_4n)) => assert_linear(shape, "instructions", at_n, at_4n),
        _ => match (one.cpu_nanos, four.cpu_nanos) {
            (Some(at_n), Some(at_4n)) => {
                assert_linear(shape, "thread CPU nanoseconds", at_n, at_4n);
            }
            _ => crate::common::not_run(
                "neither an instruction count nor the thread's CPU time is available here: \
                 growth checked by allocations only",
            ),
        },
    }
}

#[test]
fn one_layer_read_by_many_mixers_is_linear() {
    check(Shape::SharedLayer);
}

#[test]
fn one_mixer_read_by_many_surfaces_is_linear() {
    check(Shape::SharedMixer);
}

#[test]
fn one_input_with_many_connections_is_linear() {
    check(Shape::FanIn);
}

#[test]
fn one_bxdf_handle_redefined_many_times_is_linear() {
    check(Shape::RedefinedBxdf);
}

#[test]
fn an_args_definition_with_many_parameters_is_linear() {
    check(Shape::ArgsParams);
}

#[test]
fn an_args_definition_with_many_heads_is_linear() {
    check(Shape::ArgsHeads);
}

#[test]
fn an_args_definition_with_many_parameters_on_one_line_is_linear() {
    check(Shape::ArgsParamsOneLine);
}

#[test]
fn an_args_definition_with_many_heads_on_one_line_is_linear() {
    check(Shape::ArgsHeadsOneLine);
}
