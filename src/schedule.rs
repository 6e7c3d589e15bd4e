//! How the readers and writers share rayon's pool: whether handing work to it can help,
//! two independent pieces side by side, and items made on the pool but taken in order on
//! the calling thread. Without the `parallel` feature the work runs on the calling thread.

/// Whether handing work to rayon's pool and waiting for it can help: the pool has more
/// than one thread, and the caller is not one of them (waiting there for the work could
/// hold the very thread that would do it). The readers and writers that split their work
/// into pieces ask this first.
#[cfg(feature = "parallel")]
pub(crate) fn pool_can_help() -> bool {
    rayon::current_num_threads() > 1 && rayon::current_thread_index().is_none()
}

/// Items `0..count` made by `make` in pieces of `piece` consecutive items, and handed to
/// `take` on the calling thread in order, so that the calling thread uses each item while
/// rayon's pool makes the next ones. All but one of the pool's threads take the next piece
/// in turn; the calling thread, when the piece it wants next is not there yet, makes the
/// next piece nobody has taken itself (so that the two kinds of work share the cores)
/// before it waits. A piece made early waits for the ones before it. When `take` panics,
/// the pool stops after the pieces it is making.
#[cfg(all(feature = "parallel", feature = "usd"))]
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) fn make_in_order<T: Send>(
    count: usize,
    piece: usize,
    make: impl Fn(usize) -> T + Sync,
    mut take: impl FnMut(T),
) {
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::sync::mpsc::TryRecvError;
    let piece = piece.max(1);
    let pieces = count.div_ceil(piece);
    let next = AtomicUsize::new(0);
    let make_piece =
        |i: usize| -> Vec<T> { (i * piece..count.min((i + 1) * piece)).map(&make).collect() };
    let (tx, rx) = std::sync::mpsc::channel::<(usize, Vec<T>)>();
    rayon::in_place_scope(|scope| {
        let helpers = rayon::current_num_threads().saturating_sub(1).max(1);
        for _ in 0..helpers.min(pieces) {
            let (tx, next, make_piece) = (tx.clone(), &next, &make_piece);
            scope.spawn(move |_| {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    if i >= pieces || tx.send((i, make_piece(i))).is_err() {
                        return;
                    }
                }
            });
        }
        drop(tx);
        // Owned here, so that a panic of `take` drops it before the scope waits for the
        // helpers: their next send fails and they stop.
        let rx = rx;
        let mut early: Vec<Option<Vec<T>>> = Vec::new();
        let mut want = 0;
        while want < pieces {
            if let Some(items) = early.get_mut(want).and_then(Option::take) {
                items.into_iter().for_each(&mut take);
                want += 1;
                continue;
            }
            let arrived = match rx.try_recv() {
                Ok(arrived) => Some(arrived),
                Err(TryRecvError::Empty | TryRecvError::Disconnected) => {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    if i < pieces {
                        Some((i, make_piece(i)))
                    } else {
                        rx.recv().ok()
                    }
                }
            };
            let Some((i, items)) = arrived else {
                // Every helper has stopped and the wanted piece never came: cannot happen
                // while each piece is made once, but never wait for nothing.
                break;
            };
            if i >= early.len() {
                early.resize_with(i + 1, || None);
            }
            early[i] = Some(items);
        }
    });
}

/// `a` and `b`, on two of rayon's threads when the pool has more than one (feature
/// `parallel`), else one after the other: for two independent pieces of one reading.
#[cfg(feature = "usd")]
pub(crate) fn both<A: Send, B: Send>(a: impl FnOnce() -> A + Send, b: impl FnOnce() -> B + Send) -> (A, B) {
    #[cfg(feature = "parallel")]
    if rayon::current_num_threads() > 1 {
        return rayon::join(a, b);
    }
    (a(), b())
}
