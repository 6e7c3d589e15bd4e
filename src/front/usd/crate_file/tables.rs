//! A crate file's (`.usdc`) tables — TOC, tokens, strings, fields, field sets, paths and
//! specs — and its value representations, decoded from the bytes when the file is laid out
//! as USD's writers lay it out; anything else is refused here and left to `openusd`. The
//! sections are LZ4 blocks (after a chunk-count byte, zero for one block); the integer
//! tables are in USD's integer coding: a common delta, two bits of code per value, then the
//! deltas of 8, 16 or 32 bits that are not the common one.

use openusd::sdf;
use rustc_hash::FxHashMap;

/// A crate file's tables, decoded here when the file is laid out as the USD writer and
/// Pixar's library write it (see [`CrateTables::decode`]); anything else is left to
/// `openusd`, which reads it (or refuses it) as before.
pub(super) struct CrateTables {
    /// Major, minor and patch version.
    pub(super) version: [u8; 3],
    pub(super) tokens: Vec<openusd::tf::Token>,
    /// The token index of each string.
    pub(super) strings: Vec<usize>,
    /// Each field: its name's token index and its value representation.
    pub(super) fields: Vec<(usize, u64)>,
    /// Field indices, each field set ended by nothing.
    pub(super) fieldsets: Vec<Option<usize>>,
    pub(super) paths: Vec<sdf::Path>,
    /// The path tree by path index, when decoded here and no two paths are the same.
    pub(super) tree: Option<PathTree>,
    /// Each spec: its path index, its field set's start and its type.
    pub(super) specs: Vec<Spec>,
}

/// A spec in a crate file's SPECS table: its path index, its field set's start and its type.
pub(super) type Spec = (usize, usize, sdf::SpecType);

/// The strings, fields, field sets and specs of [`CrateTables`], decoded together.
type OtherTables = (Vec<usize>, Vec<(usize, u64)>, Vec<Option<usize>>, Vec<Spec>);

/// A crate file's paths as a tree of path indices: each path's element token (negative
/// for a property), first child and next sibling (`NO_PATH` for none), and the root's
/// index. Made only when no parent has two children of the same name and kind, so that
/// every path is told apart by its index: then finding a child by name among its
/// parent's children finds the spec a look-up by the path's text would.
pub(super) struct PathTree {
    pub(super) root: usize,
    pub(super) element: Vec<i32>,
    pub(super) first_child: Vec<u32>,
    pub(super) next_sibling: Vec<u32>,
}

/// No path (in [`PathTree`]).
pub(super) const NO_PATH: u32 = u32::MAX;

impl PathTree {
    /// The children of path `parent`, in file order.
    pub(super) fn children(&self, parent: usize) -> impl Iterator<Item = usize> + '_ {
        let first = self.first_child.get(parent).copied().unwrap_or(NO_PATH);
        std::iter::successors(
            (first != NO_PATH).then_some(first as usize),
            |&c| match self.next_sibling.get(c).copied() {
                Some(NO_PATH) | None => None,
                Some(n) => Some(n as usize),
            },
        )
    }
}

/// A little-endian `u64` at `at`, if the bytes are there.
fn le_u64(bytes: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(
        bytes.get(at..at.checked_add(8)?)?.try_into().ok()?,
    ))
}

/// A little-endian `u64` at `at` as a size, if the bytes are there.
pub(super) fn le_size(bytes: &[u8], at: usize) -> Option<usize> {
    usize::try_from(le_u64(bytes, at)?).ok()
}

/// More bytes than one byte of an LZ4 block may stand for (a match grows by at most 255
/// bytes a length byte), so that a size a file claims for decompressed data is believed
/// only as far as its compressed data could fill it.
const LZ4_MAX_RATIO: usize = 256;

impl CrateTables {
    /// The tables of crate file `bytes`, or nothing when anything in them is not as the
    /// writers lay it out: a version before 0.4.0 or after what `openusd` reads, a section
    /// missing or given twice, chunked compression, sizes that do not agree, indices out of
    /// range, a path element that is not an identifier (variant selections, relational
    /// targets), a path given twice or never, or what `openusd`'s validation refuses.
    pub(super) fn decode(bytes: &[u8]) -> Option<Self> {
        if bytes.get(..8)? != b"PXR-USDC" {
            return None;
        }
        let version = [*bytes.get(8)?, *bytes.get(9)?, *bytes.get(10)?];
        // 0.4.0 (compressed tables) up to what `openusd` reads (0.12).
        if version[0] != 0 || !(4..=12).contains(&version[1]) {
            return None;
        }
        let toc = le_size(bytes, 16)?;
        if toc == 0 {
            return None;
        }
        let count = le_size(bytes, toc)?;
        if count == 0 || count >= 64 {
            return None;
        }
        let mut sections: FxHashMap<&[u8], usize> = FxHashMap::default();
        for i in 0..count {
            // Each entry: a name (16 bytes, ended by a NUL), a start and a size.
            let at = toc.checked_add(8)?.checked_add(i.checked_mul(32)?)?;
            bytes.get(at..at.checked_add(32)?)?;
            let name = &bytes[at..at + 16];
            let name = &name[..name.iter().position(|&b| b == 0)?];
            let start = le_size(bytes, at + 16)?;
            if sections.insert(name, start).is_some() {
                return None;
            }
        }
        let section = |name: &[u8]| sections.get(name).copied();

        // TOKENS: count, decompressed size, then the compressed text, each token ended by
        // a NUL.
        let at = section(b"TOKENS")?;
        let count = le_size(bytes, at)?;
        let size = le_size(bytes, at + 8)?;
        let (text, _) = Self::compressed(bytes, at.checked_add(16)?, size)?;
        if text.len() != size {
            return None;
        }
        let tokens: Vec<openusd::tf::Token> = match text.split_last() {
            None if count == 0 => Vec::new(),
            Some((0, text)) => {
                let tokens = text
                    .split(|&b| b == 0)
                    .map(|t| std::str::from_utf8(t).ok().map(openusd::tf::Token::from))
                    .collect::<Option<Vec<_>>>()?;
                if tokens.len() != count {
                    return None;
                }
                tokens
            }
            _ => return None,
        };

        // The paths (the largest table) are decoded beside the others.
        let (paths, rest) = crate::schedule::both(
            || Self::paths(bytes, section(b"PATHS")?, &tokens),
            || Self::other_tables(bytes, &section, tokens.len()),
        );
        let (paths, tree) = paths?;
        let (strings, fields, fieldsets, specs) = rest?;
        // As `openusd` validates: each spec's path exists.
        if specs.iter().any(|&(path, ..)| path >= paths.len()) {
            return None;
        }
        Some(CrateTables {
            version,
            tokens,
            strings,
            fields,
            fieldsets,
            paths,
            tree,
            specs,
        })
    }

    /// The STRINGS, FIELDS, FIELDSETS and SPECS tables (see [`CrateTables::decode`]), given
    /// where each section starts and how many tokens there are; the specs' path indices are
    /// checked against the paths by the caller.
    fn other_tables(
        bytes: &[u8],
        section: &(impl Fn(&[u8]) -> Option<usize> + Sync),
        tokens: usize,
    ) -> Option<OtherTables> {
        // STRINGS: count (as `openusd` bounds it), then each string's token index.
        let at = section(b"STRINGS")?;
        let count = le_size(bytes, at)?;
        if count >= 128 * 1024 * 1024 {
            return None;
        }
        let start = at.checked_add(8)?;
        let strings = bytes
            .get(start..start.checked_add(count * 4)?)?
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as usize)
            .collect();

        // FIELDS: count, the name tokens (integer coded), the value representations.
        let at = section(b"FIELDS")?;
        let count = le_size(bytes, at)?;
        let (names, at) = Self::ints(bytes, at + 8, count)?;
        let (reps, _) = Self::compressed(bytes, at, count.checked_mul(8)?)?;
        if reps.len() != count * 8 {
            return None;
        }
        let fields: Vec<(usize, u64)> = names
            .iter()
            .zip(reps.chunks_exact(8))
            .map(|(&t, r)| {
                let t = t as u32 as usize;
                let rep = u64::from_le_bytes(r.try_into().ok()?);
                (t < tokens).then_some((t, rep))
            })
            .collect::<Option<_>>()?;

        // FIELDSETS: count, the field indices (integer coded; all ones ends a set).
        let at = section(b"FIELDSETS")?;
        let count = le_size(bytes, at)?;
        let (sets, _) = Self::ints(bytes, at + 8, count)?;
        let fieldsets: Vec<Option<usize>> = sets
            .iter()
            .map(|&i| match i as u32 {
                u32::MAX => Some(None),
                i => ((i as usize) < fields.len()).then_some(Some(i as usize)),
            })
            .collect::<Option<_>>()?;

        // SPECS: count, then path indices, field set starts and types (integer coded).
        let at = section(b"SPECS")?;
        let count = le_size(bytes, at)?;
        let (path_of, at) = Self::ints(bytes, at + 8, count)?;
        let (set_of, at) = Self::ints(bytes, at, count)?;
        let (type_of, _) = Self::ints(bytes, at, count)?;
        let mut specs = Vec::with_capacity(count);
        for i in 0..count {
            let path = path_of[i] as u32 as usize;
            let set = set_of[i] as u32 as usize;
            let ty = sdf::SpecType::from_repr(type_of[i] as u32)?;
            // As `openusd` validates: the set exists, a set starts after the end of
            // another, and the type is known.
            if set >= fieldsets.len()
                || (set > 0 && fieldsets[set - 1].is_some())
                || ty == sdf::SpecType::Unknown
            {
                return None;
            }
            specs.push((path, set, ty));
        }
        Some((strings, fields, fieldsets, specs))
    }

    /// The compressed block at `at` (its compressed size, then the data: a chunk count of
    /// zero and one LZ4 block) decompressed into at most `max` bytes, and where the block
    /// ends.
    fn compressed(bytes: &[u8], at: usize, max: usize) -> Option<(Vec<u8>, usize)> {
        let end = Self::block_end(bytes, at)?;
        let block = bytes.get(at.checked_add(8)?..end)?;
        let (&chunks, block) = block.split_first()?;
        if chunks != 0 {
            return None;
        }
        // No more room than the block could fill: a size the file claims is not believed.
        let room = max.min(block.len().saturating_mul(LZ4_MAX_RATIO).saturating_add(64));
        let mut out = vec![0u8; room];
        let n = lz4_flex::block::decompress_into(block, &mut out).ok()?;
        out.truncate(n);
        Some((out, end))
    }

    /// Where the compressed block at `at` (its compressed size, then the data) ends.
    fn block_end(bytes: &[u8], at: usize) -> Option<usize> {
        at.checked_add(8)?.checked_add(le_size(bytes, at)?)
    }

    /// `count` 32-bit integers coded as USD codes them (a common value; two bits a value
    /// saying whether it is that common value or a delta of 8, 16 or 32 bits; the deltas)
    /// in the compressed block at `at`, and where the block ends.
    fn ints(bytes: &[u8], at: usize, count: usize) -> Option<(Vec<i32>, usize)> {
        if count == 0 {
            // Nothing is coded, but the block is there.
            let (_, end) = Self::compressed(bytes, at, 0)?;
            return Some((Vec::new(), end));
        }
        let code_bytes = count.checked_mul(2)?.div_ceil(8);
        let max = 4usize
            .checked_add(code_bytes)?
            .checked_add(count.checked_mul(4)?)?;
        let (data, end) = Self::compressed(bytes, at, max)?;
        let common = i32::from_le_bytes(data.get(..4)?.try_into().ok()?);
        let codes = data.get(4..4 + code_bytes)?;
        let deltas = data.get(4 + code_bytes..)?;
        // The codes after the last value must say "common", so that nothing is read for
        // them.
        let used = count - (code_bytes - 1) * 4;
        if used < 4 && codes.last().is_some_and(|&last| last >> (2 * used) != 0) {
            return None;
        }
        let mut out = Vec::with_capacity(count);
        let mut prev = 0i32;
        let mut pos = 0usize;
        for (k, &byte) in codes.iter().enumerate() {
            let n = if k + 1 == code_bytes { used } else { 4 };
            for j in 0..n {
                let delta = match (byte >> (2 * j)) & 3 {
                    0 => common,
                    1 => {
                        pos += 1;
                        i32::from(*deltas.get(pos - 1)? as i8)
                    }
                    2 => {
                        pos += 2;
                        let b = deltas.get(pos - 2..pos)?;
                        i32::from(i16::from_le_bytes([b[0], b[1]]))
                    }
                    _ => {
                        pos += 4;
                        let b = deltas.get(pos - 4..pos)?;
                        i32::from_le_bytes([b[0], b[1], b[2], b[3]])
                    }
                };
                prev = prev.wrapping_add(delta);
                out.push(prev);
            }
        }
        Some((out, end))
    }

    /// The PATHS section at `at`: the number of paths, the number of entries, then each
    /// entry's path index, element token (negative for a property) and jump (to its next
    /// sibling: 0 when the next entry is its sibling, -1 when it is its child, -2 when it
    /// has neither), integer coded. Every path must be given once.
    /// With the paths, their tree ([`PathTree`]) when no two are the same.
    fn paths(
        bytes: &[u8],
        at: usize,
        tokens: &[openusd::tf::Token],
    ) -> Option<(Vec<sdf::Path>, Option<PathTree>)> {
        let count = le_size(bytes, at)?;
        let entries = le_size(bytes, at + 8)?;
        // The three integer tables, each a compressed block after its size, decoded side
        // by side (a thread of the pool that is done with the other tables joins in).
        let at_index = at.checked_add(16)?;
        let at_element = Self::block_end(bytes, at_index)?;
        let at_jump = Self::block_end(bytes, at_element)?;
        let (index, (element, jump)) = crate::schedule::both(
            || Self::ints(bytes, at_index, entries),
            || {
                crate::schedule::both(
                    || Self::ints(bytes, at_element, entries),
                    || Self::ints(bytes, at_jump, entries),
                )
            },
        );
        let ((index, _), (element, _), (jump, _)) = (index?, element?, jump?);
        if count != entries {
            return None;
        }
        let mut paths: Vec<Option<(sdf::Path, bool)>> = vec![None; count];
        if entries == 0 {
            return Some((Vec::new(), None));
        }
        let mut elements = vec![0i32; count];
        let mut first_child = vec![NO_PATH; count];
        let mut last_child = vec![NO_PATH; count];
        let mut next_sibling = vec![NO_PATH; count];
        let root = index[0] as u32 as usize;
        // (entry, its parent's path index, or nothing for the root).
        let mut pending: Vec<(usize, Option<usize>)> = vec![(0, None)];
        let mut visited = vec![false; entries];
        // Whether each token is a prim name and a property name, checked once.
        let mut names: Vec<Option<(bool, bool)>> = vec![None; tokens.len()];
        while let Some((mut entry, mut parent)) = pending.pop() {
            loop {
                if std::mem::replace(visited.get_mut(entry)?, true) {
                    return None;
                }
                let this = index[entry] as u32 as usize;
                let made = match parent {
                    None => (sdf::Path::abs_root(), false),
                    Some(p) => {
                        let (parent_path, parent_is_property) = paths.get(p)?.as_ref()?;
                        if *parent_is_property {
                            return None;
                        }
                        let e = element[entry];
                        let t = e.unsigned_abs() as usize;
                        let name = tokens.get(t)?.as_str();
                        let property = e < 0;
                        let (prim_name, property_name) =
                            *names.get_mut(t)?.get_or_insert_with(|| {
                                (
                                    sdf::Path::is_valid_identifier(name),
                                    sdf::Path::is_valid_namespace_identifier(name),
                                )
                            });
                        if !(if property { property_name } else { prim_name }) {
                            return None;
                        }
                        let parent = parent_path.as_str();
                        let mut p = String::with_capacity(parent.len() + 1 + name.len());
                        p.push_str(parent);
                        if property {
                            p.push('.');
                        } else if parent != "/" {
                            p.push('/');
                        }
                        p.push_str(name);
                        (sdf::Path::from(p), property)
                    }
                };
                let slot = paths.get_mut(this)?;
                if slot.is_some() {
                    return None;
                }
                *slot = Some(made);
                if let Some(p) = parent {
                    elements[this] = element[entry];
                    match last_child[p] {
                        NO_PATH => first_child[p] = this as u32,
                        last => next_sibling[last as usize] = this as u32,
                    }
                    last_child[p] = this as u32;
                }
                let j = jump[entry];
                let has_child = j > 0 || j == -1;
                let has_sibling = j >= 0;
                // The root has no siblings.
                if parent.is_none() && has_sibling {
                    return None;
                }
                if has_child && has_sibling {
                    pending.push((entry.checked_add(usize::try_from(j).ok()?)?, parent));
                }
                if has_child {
                    parent = Some(this);
                }
                if !has_child && !has_sibling {
                    break;
                }
                entry += 1;
            }
        }
        let paths: Vec<sdf::Path> = paths
            .into_iter()
            .map(|p| p.map(|(p, _)| p))
            .collect::<Option<_>>()?;
        let tree = PathTree {
            root,
            element: elements,
            first_child,
            next_sibling,
        };
        // Whether some parent has two children of the same element (a token and its
        // sign): each parent's children are checked together, each token marked with
        // the parent's index.
        let mut marks = vec![[NO_PATH; 2]; tokens.len()];
        for parent in 0..count {
            for child in tree.children(parent) {
                let e = tree.element[child];
                let mark = &mut marks.get_mut(e.unsigned_abs() as usize)?[usize::from(e < 0)];
                if *mark == parent as u32 {
                    return Some((paths, None));
                }
                *mark = parent as u32;
            }
        }
        Some((paths, Some(tree)))
    }
}

/// The value types in a crate file's value representations (bits 48 to 55) that
/// [`super::CrateLayer`] decodes itself.
pub(super) const CRATE_BOOL: u64 = 1;
pub(super) const CRATE_INT: u64 = 3;
pub(super) const CRATE_FLOAT: u64 = 8;
pub(super) const CRATE_DOUBLE: u64 = 9;
pub(super) const CRATE_STRING: u64 = 10;
pub(super) const CRATE_TOKEN: u64 = 11;
pub(super) const CRATE_VEC3F: u64 = 24;
pub(super) const CRATE_PATH_LIST_OP: u64 = 34;
pub(super) const CRATE_TOKEN_VECTOR: u64 = 41;
pub(super) const CRATE_SPECIFIER: u64 = 42;

/// The parts of a crate file's value representation: its type, whether it is an array,
/// inlined or compressed, and its payload (the value itself when inlined, else where it
/// lies in the file).
#[derive(Clone, Copy)]
pub(super) struct Rep(pub(super) u64);

impl Rep {
    pub(super) fn ty(self) -> u64 {
        (self.0 >> 48) & 0xff
    }
    pub(super) fn is_array(self) -> bool {
        self.0 & (1 << 63) != 0
    }
    pub(super) fn is_inlined(self) -> bool {
        self.0 & (1 << 62) != 0
    }
    pub(super) fn is_compressed(self) -> bool {
        self.0 & (1 << 61) != 0
    }
    pub(super) fn payload(self) -> u64 {
        self.0 & ((1 << 48) - 1)
    }
    /// An inlined value's 32 bits.
    pub(super) fn low(self) -> u32 {
        (self.0 & 0xffff_ffff) as u32
    }
    /// Its type, whether it is an array and whether it is inlined: what decides how an
    /// uncompressed value is decoded.
    pub(super) fn layout(self) -> (u64, bool, bool) {
        (self.ty(), self.is_array(), self.is_inlined())
    }
}
