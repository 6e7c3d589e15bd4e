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

use super::{Args, Assembler, Occurrence, Piece, RibOptions, Scanner, Split, Token, split_request};
use crate::diag::{Diagnostic, Diagnostics, Error};
use crate::network::RequestKind;
use std::ops::Range;
use std::sync::Arc;
use std::sync::mpsc::{Receiver, Sender, SyncSender, channel, sync_channel};

/// Shading requests per batch at most (the bench scene's take about 60 kB of tokens).
pub(super) const MAX_BATCH_REQUESTS: usize = 256;

/// Array elements and arguments per batch at most: a batch of very long requests is sent
/// early, so the batches in flight stay small whatever the requests.
const MAX_BATCH_TOKENS: usize = 16 * 1024;

/// Batches filled ahead of the assembler at most.
const IN_FLIGHT: usize = 4;

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
}

/// Consecutive shading requests, their arguments, and what ended the input if it ended.
#[derive(Default)]
struct Batch<'a> {
    args: Args,
    /// The parameter occurrences of all its requests ([`Split::params`]).
    occurrences: Vec<Occurrence>,
    requests: Vec<Request<'a>>,
    diags: Vec<Diagnostic>,
    /// The end of the input (`Ok`) or the tokenizer's error, after the requests.
    end: Option<Result<(), Error>>,
}

/// Reads the requests of `bytes` into `asm` on two threads, in batches of at most `batch`
/// requests. `None` when no thread could be started (nothing was read then).
pub(super) fn read(
    bytes: &[u8],
    file: &Arc<str>,
    options: &RibOptions,
    asm: &mut Assembler<'_, '_>,
    diags: &mut Diagnostics,
    batch: usize,
) -> Option<Result<(), Error>> {
    let (full_tx, full_rx) = sync_channel::<Batch<'_>>(IN_FLIGHT);
    let (free_tx, free_rx) = channel::<Batch<'_>>();
    let strict = options.strict;
    std::thread::scope(|s| {
        let scanner = Scanner::new(bytes, file.clone(), strict);
        let tokenizer = std::thread::Builder::new()
            .name("rib-tokenizer".into())
            .spawn_scoped(s, move || tokenize(scanner, batch, &full_tx, &free_rx))
            .ok()?;
        let result = assemble(bytes, file, options, asm, diags, full_rx, &free_tx);
        if let Err(panic) = tokenizer.join() {
            std::panic::resume_unwind(panic);
        }
        Some(result)
    })
}

/// The tokenizer's thread: fills batches until the end of the input or an error, or until
/// the assembler stops.
fn tokenize<'a>(
    mut scanner: Scanner<'a>,
    max_requests: usize,
    full: &SyncSender<Batch<'a>>,
    free: &Receiver<Batch<'a>>,
) {
    loop {
        let mut batch = free.try_recv().unwrap_or_default();
        let mut diags = Diagnostics::new();
        while batch.end.is_none()
            && batch.requests.len() < max_requests
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
                    });
                }
                Ok(None) => batch.end = Some(Ok(())),
                Err(e) => batch.end = Some(Err(e)),
            }
        }
        batch.diags = diags.into_vec();
        let last = batch.end.is_some();
        if full.send(batch).is_err() || last {
            return;
        }
    }
}

/// The calling thread: assembles the requests of each batch in turn, pushing the
/// tokenizer's diagnostics where the one-thread reader does.
fn assemble<'a>(
    bytes: &'a [u8],
    file: &Arc<str>,
    options: &RibOptions,
    asm: &mut Assembler<'_, '_>,
    diags: &mut Diagnostics,
    full: Receiver<Batch<'a>>,
    free: &Sender<Batch<'a>>,
) -> Result<(), Error> {
    // Only for positions: the tokens were read by the tokenizer's own.
    let positions = Scanner::new(bytes, file.clone(), options.strict).lx;
    for mut batch in full {
        let mut lexed = std::mem::take(&mut batch.diags).into_iter();
        let mut pushed = 0;
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
                diags,
            )?;
            asm.check_nodes(&positions, &r.keyword, &options.limits)?;
        }
        diags.extend(lexed);
        if let Some(end) = batch.end.take() {
            return end;
        }
        batch.args.pieces.clear();
        batch.args.items.clear();
        batch.occurrences.clear();
        // The tokenizer may have stopped already: then the batch is dropped.
        let _ = free.send(batch);
    }
    // The tokenizer stopped without ending a batch: it panicked (its join reports it).
    Ok(())
}
