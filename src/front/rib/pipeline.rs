//! The RIB reader on two threads: one tokenizes (finds the shading requests, reads their
//! arguments, [`Scanner`], and splits them into parameter occurrences, source items and
//! comments, [`split_request`]), the calling thread interprets the parameters and assembles
//! the network in file order ([`Assembler`]), as the one-thread reader does in turn.
//!
//! Requests travel in batches through a bounded channel, with the diagnostics the tokenizer
//! reported while reading each one, so the calling thread pushes every diagnostic at the
//! place the one-thread reader does: the network, the diagnostics (codes, order, positions)
//! and the error are the same. The tokenizer stops at its first error, which ends its last
//! batch; the assembler stops at its own first error (the batches still in the channel are
//! dropped, and the tokenizer stops at its next send). Emptied batches go back to the
//! tokenizer, so their room is reused.
//!
//! A batch's parameters are read ([`ParamReader`]) by whichever thread has time: the
//! tokenizer reads them before sending the batch when the assembler is behind (batches
//! wait in the channel), the assembler otherwise: the thread that would wait does that work
//! instead, and both stay busy.

use super::{
    Args, Assembler, Occurrence, ParamReader, Piece, Read, RibOptions, Scanner, Split, Token,
    split_request,
};
use crate::diag::{Diagnostic, Diagnostics, Error};
use crate::network::{ParamTypes, RequestKind};
use std::ops::Range;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc::{Receiver, Sender, SyncSender, channel, sync_channel};

/// Shading requests per batch at most (the bench scene's take about 60 kB of tokens).
pub(super) const MAX_BATCH_REQUESTS: usize = 256;

/// Array elements and arguments per batch at most: a batch of very long requests is sent
/// early, so the batches in flight stay small whatever the requests.
const MAX_BATCH_TOKENS: usize = 16 * 1024;

/// Batches filled ahead of the assembler at most.
const IN_FLIGHT: usize = 4;

/// With this many batches waiting for the assembler, the tokenizer reads the parameters of
/// the next one itself ([`Reading::WhenBehind`]).
const BEHIND: usize = 2;

/// Which thread reads a batch's parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Reading {
    /// The tokenizer when [`BEHIND`] batches wait, the assembler otherwise.
    WhenBehind,
    /// The tokenizer every other batch (tests: both threads read, whatever their speed).
    #[cfg(feature = "testkit")]
    Alternate,
}

impl Reading {
    /// Whether the tokenizer reads the parameters of its batch number `sent` (from 0), with
    /// `waiting` batches waiting for the assembler.
    #[cfg_attr(not(feature = "testkit"), allow(unused_variables))]
    fn by_tokenizer(self, sent: usize, waiting: usize) -> bool {
        match self {
            Reading::WhenBehind => waiting >= BEHIND,
            #[cfg(feature = "testkit")]
            Reading::Alternate => sent % 2 == 1,
        }
    }
}

/// One shading request of a batch.
struct Request<'a> {
    kind: RequestKind,
    keyword: Token,
    /// Its parts, split on the tokenizer's thread.
    split: Split<'a>,
    /// Its arguments in [`Batch::args`]' pieces.
    pieces: Range<usize>,
    /// How many of the batch's diagnostics were reported before the request was assembled
    /// (while reading it or earlier).
    diags: usize,
    /// How many of the batch's [`Batch::reads`] are its own, once they are read.
    reads: usize,
}

/// Consecutive shading requests, their arguments, and what ended the input if it ended.
#[derive(Default)]
struct Batch<'a> {
    args: Args,
    /// The parameter occurrences of all its requests ([`Split::params`]).
    occurrences: Vec<Occurrence>,
    requests: Vec<Request<'a>>,
    diags: Vec<Diagnostic>,
    /// The parameter occurrences of its requests as read, in order, once `read` is set.
    reads: Vec<Read>,
    /// Whether its parameters were read (by the tokenizer).
    read: bool,
    /// The end of the input (`Ok`) or the tokenizer's error, after the requests.
    end: Option<Result<(), Error>>,
}

/// Reads the requests of `bytes` into `asm` on two threads, in batches of at most `batch`
/// requests. `None` when no thread could be started (nothing was read then).
#[allow(clippy::too_many_arguments)]
pub(super) fn read(
    bytes: &[u8],
    file: &Arc<str>,
    options: &RibOptions,
    types: &(dyn ParamTypes + Sync),
    asm: &mut Assembler<'_, '_>,
    diags: &mut Diagnostics,
    batch: usize,
    reading: Reading,
) -> Option<Result<(), Error>> {
    let (full_tx, full_rx) = sync_channel::<Batch<'_>>(IN_FLIGHT);
    let (free_tx, free_rx) = channel::<Batch<'_>>();
    let strict = options.strict;
    let waiting = AtomicUsize::new(0);
    std::thread::scope(|s| {
        let scanner = Scanner::new(bytes, file.clone(), strict);
        let tokenizer_file = file.clone();
        let waiting = &waiting;
        let tokenizer = std::thread::Builder::new()
            .name("rib-tokenizer".into())
            .spawn_scoped(s, move || {
                // Built here: what it remembers is this thread's alone.
                let reader = ParamReader::new(bytes, tokenizer_file, types);
                let tokenizer = Tokenizer {
                    scanner,
                    reader,
                    max_requests: batch,
                    reading,
                    waiting,
                };
                tokenizer.run(&full_tx, &free_rx)
            })
            .ok()?;
        let reader = ParamReader::new(bytes, file.clone(), types);
        let result = assemble(
            reader, file, options, asm, diags, full_rx, &free_tx, waiting,
        );
        if let Err(panic) = tokenizer.join() {
            std::panic::resume_unwind(panic);
        }
        Some(result)
    })
}

/// The tokenizer's thread and what it reads with.
struct Tokenizer<'a, 't, 'w> {
    scanner: Scanner<'a>,
    reader: ParamReader<'a, 't>,
    max_requests: usize,
    reading: Reading,
    /// Batches sent and not yet taken by the assembler.
    waiting: &'w AtomicUsize,
}

impl<'a> Tokenizer<'a, '_, '_> {
    /// Fills batches until the end of the input or an error, or until the assembler stops.
    fn run(mut self, full: &SyncSender<Batch<'a>>, free: &Receiver<Batch<'a>>) {
        for sent in 0usize.. {
            let mut batch = free.try_recv().unwrap_or_default();
            self.fill(&mut batch);
            let waiting = self.waiting.load(Ordering::Relaxed);
            if self.reading.by_tokenizer(sent, waiting) {
                read_batch(&mut self.reader, &mut batch);
            }
            let last = batch.end.is_some();
            self.waiting.fetch_add(1, Ordering::Relaxed);
            if full.send(batch).is_err() || last {
                return;
            }
        }
    }

    /// Fills `batch` with requests up to its bounds, the end of the input or an error.
    fn fill(&mut self, batch: &mut Batch<'a>) {
        let scanner = &mut self.scanner;
        let mut diags = Diagnostics::new();
        while batch.end.is_none()
            && batch.requests.len() < self.max_requests
            && batch.args.pieces.len() + batch.args.items.len() < MAX_BATCH_TOKENS
        {
            let from = batch.args.pieces.len();
            match scanner.next_request(&mut batch.args, &mut diags) {
                Ok(Some((kind, keyword))) => {
                    let pieces = from..batch.args.pieces.len();
                    let split = split_request(
                        scanner.src,
                        &scanner.lx,
                        kind,
                        &keyword,
                        &batch.args.pieces[pieces.clone()],
                        &mut batch.occurrences,
                    );
                    batch.requests.push(Request {
                        kind,
                        keyword,
                        split,
                        pieces,
                        diags: diags.len(),
                        reads: 0,
                    });
                }
                Ok(None) => batch.end = Some(Ok(())),
                Err(e) => batch.end = Some(Err(e)),
            }
        }
        batch.diags = diags.into_vec();
    }
}

/// Reads the parameters of every request of `batch` with `reader`.
fn read_batch(reader: &mut ParamReader<'_, '_>, batch: &mut Batch<'_>) {
    for r in &mut batch.requests {
        r.reads = reader.read_request(
            &r.split,
            &batch.args.pieces[r.pieces.clone()],
            &batch.args.items,
            &batch.occurrences,
            &mut batch.reads,
        );
    }
    batch.read = true;
}

/// The calling thread: assembles the requests of each batch in turn, pushing the
/// tokenizer's diagnostics where the one-thread reader does.
#[allow(clippy::too_many_arguments)]
fn assemble<'a>(
    mut reader: ParamReader<'a, '_>,
    file: &Arc<str>,
    options: &RibOptions,
    asm: &mut Assembler<'_, '_>,
    diags: &mut Diagnostics,
    full: Receiver<Batch<'a>>,
    free: &Sender<Batch<'a>>,
    waiting: &AtomicUsize,
) -> Result<(), Error> {
    // Only for positions: the tokens were read by the tokenizer's own.
    let positions = Scanner::new(asm.src, file.clone(), options.strict).lx;
    for mut batch in full {
        waiting.fetch_sub(1, Ordering::Relaxed);
        if !batch.read {
            read_batch(&mut reader, &mut batch);
        }
        let mut lexed = std::mem::take(&mut batch.diags).into_iter();
        let mut pushed = 0;
        let mut reads = batch.reads.drain(..);
        for r in batch.requests.drain(..) {
            diags.extend(lexed.by_ref().take(r.diags - pushed));
            pushed = r.diags;
            let pieces: &[Piece] = &batch.args.pieces[r.pieces];
            asm.shading_request(
                &positions,
                r.kind,
                &r.keyword,
                pieces,
                &batch.args.items,
                r.split,
                &batch.occurrences,
                reads.by_ref().take(r.reads),
                diags,
            )?;
            asm.check_nodes(&positions, &r.keyword, &options.limits)?;
        }
        drop(reads);
        diags.extend(lexed);
        if let Some(end) = batch.end.take() {
            return end;
        }
        batch.args.pieces.clear();
        batch.args.items.clear();
        batch.occurrences.clear();
        batch.read = false;
        // The tokenizer may have stopped already: then the batch is dropped.
        let _ = free.send(batch);
    }
    // The tokenizer stopped without ending a batch: it panicked (its join reports it).
    Ok(())
}
