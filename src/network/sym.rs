//! Interned parameter and output names.
//!
//! A resolved scene has millions of member parameters and connections but a few thousand
//! distinct names, so a parameter or a connection keeps a [`Sym`]: one pointer to the one
//! copy of its name, with the name's [`name_hash`](super::name_hash) computed once. Equal
//! names are the same `Sym`, so comparing two is comparing two pointers.
//!
//! The table is process-wide and never shrinks: a name, once read, stays for the life of
//! the process. Names are a bounded vocabulary (the parameters and outputs of the shader
//! types in use), unlike handles or values, which are never interned. Each thread keeps the
//! names it met in a table of its own, looked up without the process-wide table's lock: the
//! threads of a parallel reader would otherwise take turns at it for every name.

use hashbrown::HashTable;
use std::cell::RefCell;
use std::cmp::Ordering;
use std::fmt;
use std::hash::{Hash, Hasher};
use std::ops::Deref;
use std::sync::{LazyLock, Mutex, PoisonError};

/// One interned name and its hash.
struct SymData {
    text: Box<str>,
    hash: u64,
}

/// An interned name: a pointer to its one copy (8 bytes, `Copy`, compared by address).
#[derive(Clone, Copy)]
pub struct Sym(&'static SymData);

/// Every name interned so far, by hash.
static TABLE: LazyLock<Mutex<HashTable<&'static SymData>>> =
    LazyLock::new(|| Mutex::new(HashTable::new()));

/// At most this many names are kept in a thread's own table (a bound on its memory for a
/// file of distinct names; the names beyond are found in the process-wide table).
const MAX_SEEN: usize = 1 << 16;

thread_local! {
    /// The names this thread interned or found, by hash.
    static SEEN: RefCell<HashTable<&'static SymData>> = const { RefCell::new(HashTable::new()) };
}

impl Sym {
    /// The one `Sym` of `name` (interned on first use).
    pub fn new(name: &str) -> Sym {
        Sym::with_hash(name, super::name_hash(name))
    }

    /// [`Sym::new`] with the name's [`name_hash`](super::name_hash) already known.
    pub fn with_hash(name: &str, hash: u64) -> Sym {
        SEEN.with_borrow_mut(|seen| {
            if let Some(&data) = seen.find(hash, |d| &*d.text == name) {
                return Sym(data);
            }
            let sym = Sym::intern(name, hash);
            if seen.len() < MAX_SEEN {
                seen.insert_unique(hash, sym.0, |d| d.hash);
            }
            sym
        })
    }

    /// The `Sym` of `name` from the process-wide table (interned on first use).
    fn intern(name: &str, hash: u64) -> Sym {
        // A poisoned lock leaves a consistent table (insertion is the only change).
        let mut table = TABLE.lock().unwrap_or_else(PoisonError::into_inner);
        if let Some(&data) = table.find(hash, |d| &*d.text == name) {
            return Sym(data);
        }
        let data: &'static SymData = Box::leak(Box::new(SymData {
            text: Box::from(name),
            hash,
        }));
        table.insert_unique(hash, data, |d| d.hash);
        Sym(data)
    }

    /// The name.
    pub fn as_str(self) -> &'static str {
        &self.0.text
    }

    /// The name's [`name_hash`](super::name_hash).
    pub fn name_hash(self) -> u64 {
        self.0.hash
    }
}

impl Deref for Sym {
    type Target = str;
    fn deref(&self) -> &str {
        self.as_str()
    }
}

impl PartialEq for Sym {
    /// Interned: equal names are the same block.
    fn eq(&self, other: &Sym) -> bool {
        std::ptr::eq(self.0, other.0)
    }
}

impl Eq for Sym {}

impl Hash for Sym {
    fn hash<H: Hasher>(&self, state: &mut H) {
        state.write_u64(self.0.hash);
    }
}

impl PartialOrd for Sym {
    fn partial_cmp(&self, other: &Sym) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Sym {
    /// Byte-wise order of the names.
    fn cmp(&self, other: &Sym) -> Ordering {
        self.as_str().cmp(other.as_str())
    }
}

impl fmt::Debug for Sym {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(self.as_str(), f)
    }
}

impl fmt::Display for Sym {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}
