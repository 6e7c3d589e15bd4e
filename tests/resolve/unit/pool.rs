//! The crate's helper that makes items on rayon's pool and hands them over in order.

use vstructc::schedule::make_in_order;

/// Every item is taken once, in order, whatever the piece size and however long each item
/// takes to make.
#[test]
fn items_made_on_the_pool_are_taken_in_order() {
    for count in [0, 1, 63, 64, 65, 1000] {
        for piece in [0, 1, 7, 64, 5000] {
            let mut taken = Vec::new();
            make_in_order(
                count,
                piece,
                |i| {
                    // Uneven work, so that pieces arrive out of order.
                    let spin = (i * 7919) % 257 * 50;
                    std::hint::black_box((0..spin).map(std::hint::black_box).count());
                    i
                },
                |v| taken.push(v),
            );
            let expected: Vec<usize> = (0..count).collect();
            assert_eq!(taken, expected, "count {count}, piece {piece}");
        }
    }
}

/// A panic while taking an item reaches the caller, and the pool stops after the pieces it
/// is making. Counted from the unwinding on: before it, the pool may have made every item
/// (while the calling thread waits for a core, or its panic hook prints a backtrace); after
/// it, only the pieces in the making may be finished (each item takes a while, so making the
/// rest would take far longer than the caller's unwinding).
#[test]
fn a_panic_while_taking_reaches_the_caller() {
    use std::sync::atomic::{AtomicUsize, Ordering};
    /// Notes how many items were made when it is dropped by an unwinding.
    struct AtUnwinding<'a> {
        made: &'a AtomicUsize,
        at: &'a AtomicUsize,
    }
    impl Drop for AtUnwinding<'_> {
        fn drop(&mut self) {
            if std::thread::panicking() {
                self.at
                    .store(self.made.load(Ordering::SeqCst), Ordering::SeqCst);
            }
        }
    }
    let made = AtomicUsize::new(0);
    let at_unwinding = AtomicUsize::new(usize::MAX);
    let caught = std::panic::catch_unwind(|| {
        make_in_order(
            10_000,
            8,
            |i| {
                made.fetch_add(1, Ordering::SeqCst);
                std::hint::black_box((0..20_000).map(std::hint::black_box).count());
                i
            },
            |i| {
                let _mark = AtUnwinding {
                    made: &made,
                    at: &at_unwinding,
                };
                if i == 100 {
                    std::panic::panic_any("stop");
                }
            },
        )
    });
    let payload = caught.expect_err("the panic reaches the caller");
    assert_eq!(payload.downcast_ref::<&str>(), Some(&"stop"));
    let at = at_unwinding.load(Ordering::SeqCst);
    assert!(at <= 10_000, "the unwinding was not noted");
    let after = made.load(Ordering::SeqCst) - at;
    assert!(after < 1_000, "{after} items made after the panic");
}
