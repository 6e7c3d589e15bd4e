//! What a reader remembers of texts it read before: a scene repeats the same declarations
//! and parameters on thousands of nodes, and reading one again costs a hash and a comparison
//! of bytes. The RIB reader remembers per shader (types come from its definition), the JSON
//! reader per parameter name.
//!
//! Entries are never changed or removed, and a reader remembers only what reading the text
//! again would give without a diagnostic, so a hit is exactly what reading would have given.

use hashbrown::HashTable;
use rustc_hash::FxHasher;
use std::hash::Hasher;

/// At most this many distinct parameters are remembered by one of a reader's tables while
/// a file is read: an entry keeps its text, and a file of distinct values must not make a
/// reader keep a copy of it.
pub(crate) const MAX_REMEMBERED_PARAMS: usize = 1 << 16;

/// The hash of a text alone: the part of an entry's hash that needs no key (the RIB reader
/// computes it on the tokenizer's thread).
pub(crate) fn text_hash(text: &[u8]) -> u64 {
    let mut h = FxHasher::default();
    h.write(text);
    h.finish()
}

/// Texts read before, each under a key of the reader's (a shader's number), with what was
/// read from them.
pub(crate) struct Remembered<T> {
    table: HashTable<Entry<T>>,
}

/// One text remembered.
struct Entry<T> {
    key: usize,
    text: Box<[u8]>,
    /// Its [`entry_hash`], kept for the table's growth.
    hash: u64,
    read: T,
}

impl<T> Default for Remembered<T> {
    fn default() -> Self {
        Remembered {
            table: HashTable::new(),
        }
    }
}

/// The hash of a key and a text (given by its [`text_hash`]).
fn entry_hash(key: usize, text_hash: u64) -> u64 {
    let mut h = FxHasher::default();
    h.write_usize(key);
    h.write_u64(text_hash);
    h.finish()
}

impl<T> Remembered<T> {
    /// How many texts are remembered.
    pub(crate) fn len(&self) -> usize {
        self.table.len()
    }

    /// What was read from `text` (of hash `hash`, [`text_hash`]) under `key`, if remembered.
    pub(crate) fn recall(&self, key: usize, text: &[u8], hash: u64) -> Option<&T> {
        self.table
            .find(entry_hash(key, hash), |e| e.key == key && *e.text == *text)
            .map(|e| &e.read)
    }

    /// Remember `read` for `text` (of hash `hash`, [`text_hash`]) under `key`; not
    /// remembered yet.
    pub(crate) fn remember(&mut self, key: usize, text: &[u8], hash: u64, read: T) {
        let hash = entry_hash(key, hash);
        let entry = Entry {
            key,
            text: Box::from(text),
            hash,
            read,
        };
        self.table.insert_unique(hash, entry, |e| e.hash);
    }
}
