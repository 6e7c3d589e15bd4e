//! Expansion plans and the decision cache of resolution.
//!
//! How the members of an input head match the members of an output head depends only on the
//! two node types and heads, so it is worked out once per pair of heads (a [`Plan`]). The
//! choices of the matched members' conditionals depend only on the plan and on what the
//! conditionals can read of the upstream node U: for each parameter they name, its authored
//! value and whether it is connected (declarations and defaults belong to U's definition,
//! which is part of the cache key). Scenes repeat a few upstream states thousands of times,
//! so the choices of one expansion ([`Decision`]) are computed once per (plan, state) and
//! shared by every expansion that finds U in the same state.

use super::KnownChoice;
use crate::cond::ComparisonReport;
use crate::network::{Network, NodeId, Param, Slot, name_hash};
use crate::registry::tables::{InputMember, OutputMember, VstructTables};
use crate::types::Value;
use hashbrown::HashTable;
use rustc_hash::{FxBuildHasher, FxHashMap as HashMap};
use std::hash::BuildHasher;
use std::io::Write;
use std::sync::Arc;

/// A list of parameter names to find in nodes, with their hashes and an index by hash.
#[derive(Default)]
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(super) struct NameSet {
    names: Vec<(Arc<str>, u64)>,
    /// Positions in `names` of the first occurrence of each name, by [`name_hash`].
    index: HashTable<u32>,
    /// True once a name was pushed twice (a scan would fill only the first occurrence).
    repeated: bool,
}

impl NameSet {
    /// Adds `name` unless it is in the set already.
    #[cfg_attr(feature = "testkit", visibility::make(pub))]
    fn insert(&mut self, name: Arc<str>) {
        if !self.contains(&name) {
            self.push(name);
        }
    }

    fn contains(&self, name: &str) -> bool {
        let names = &self.names;
        self.index
            .find(name_hash(name), |&i| &*names[i as usize].0 == name)
            .is_some()
    }

    /// Appends `name`, even if it is in the set already (positions must stay aligned with
    /// the caller's list); the index keeps the first occurrence.
    #[cfg_attr(feature = "testkit", visibility::make(pub))]
    fn push(&mut self, name: Arc<str>) {
        let hash = name_hash(&name);
        let seen = self.contains(&name);
        let i = u32::try_from(self.names.len()).expect("fewer than 2^32 names");
        self.names.push((name, hash));
        if seen {
            self.repeated = true;
        } else {
            let names = &self.names;
            self.index.insert_unique(hash, i, |&j| names[j as usize].1);
        }
    }

    /// The names and their hashes, in the set's order.
    #[cfg(feature = "testkit")]
    pub fn names(&self) -> impl Iterator<Item = &(Arc<str>, u64)> {
        self.names.iter()
    }

    /// Where each name is among `node`'s parameters, in the set's order. A node with fewer
    /// parameters than the set has names is scanned (one hash per parameter); otherwise
    /// each name is looked up in the node's own index. Both find the same positions, since
    /// parameter names are unique in a node.
    pub fn find_in(&self, net: &Network, node: NodeId, out: &mut Vec<Slot>) {
        out.clear();
        let params = net[node].all_params();
        if params.len() < self.names.len() && !self.repeated {
            out.extend(self.names.iter().map(|&(_, hash)| Slot::Missing { hash }));
            for (at, param) in params.iter().enumerate() {
                let name = param.name();
                let names = &self.names;
                if let Some(&i) = self
                    .index
                    .find(name_hash(name), |&i| &*names[i as usize].0 == name)
                {
                    out[i as usize] = Slot::At(at);
                }
            }
        } else {
            out.extend(
                self.names
                    .iter()
                    .map(|(name, hash)| net.slot_of(node, name, *hash)),
            );
        }
    }
}

/// How one input head's members meet one output head's members.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(super) struct Plan {
    /// Distinguishes plans in the decision cache.
    pub id: usize,
    /// One entry per member of the input head, in declaration order.
    pub members: Vec<PlannedMember>,
    /// The member properties, in the same order, to find them in each downstream node.
    pub properties: NameSet,
    /// Every parameter of U that a matched member's (parsed) conditional names: the upstream
    /// state a [`Decision`] depends on.
    pub reads: NameSet,
}

/// One member of the input head.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(super) struct PlannedMember {
    /// The index of the name it matched by and the upstream output member; `None` when the
    /// upstream head has no counterpart.
    pub matched: Option<(usize, OutputMember)>,
}

impl Plan {
    /// Match `down_members` against output head `up_head` of `up` (step 3f: by member name,
    /// then alias) and collect what the conditionals read.
    pub fn new(id: usize, down_members: &[InputMember], up: &VstructTables, up_head: &str) -> Plan {
        let members: Vec<PlannedMember> = down_members
            .iter()
            .map(|member| PlannedMember {
                matched: member.names.iter().enumerate().find_map(|(i, name)| {
                    up.reverse_out(up_head, name).map(|out| (i, out.clone()))
                }),
            })
            .collect();
        let mut properties = NameSet::default();
        for member in down_members {
            properties.push(member.property.clone());
        }
        let mut reads = NameSet::default();
        let statements = members
            .iter()
            .filter_map(|m| m.matched.as_ref()?.1.cond.as_ref()?.statement());
        for stmt in statements {
            for name in stmt.param_names() {
                reads.insert(Arc::from(name));
            }
        }
        Plan {
            id,
            members,
            properties,
            reads,
        }
    }
}

/// What expanding a member comes down to, when that is simple enough to do without the
/// general path (which builds the explain story and every diagnostic).
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(super) enum Verdict {
    /// Nothing happens: the conditional chose `ignore` and reported nothing.
    Ignore,
    /// Connect to the matched output: no conditional, or one that chose `connect` and
    /// reported nothing.
    Connect,
    /// Write this value: the conditional chose a `set` that applies to the member's type
    /// without saturating, and reported nothing.
    Write(Arc<Value>),
    /// Anything else (`copy`, VS015 reports, no counterpart, an unparsable or
    /// unevaluated conditional): the general path.
    General,
}

/// The conditionals' verdicts for one expansion.
#[derive(Default)]
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(super) struct Decision {
    /// Per member of the plan: the choice of its conditional when it was evaluated ahead.
    pub choices: Vec<Option<KnownChoice>>,
    /// Per member of the plan: what its expansion comes down to.
    pub verdicts: Vec<Verdict>,
    /// Per member of the plan: true if the member writes or connects something (so it adds a
    /// parameter to a node that does not have it yet).
    pub adds: Vec<bool>,
    /// The VS015 reports of each conditional that had some, by `memo_key`.
    pub reports: HashMap<usize, Vec<ComparisonReport>>,
}

/// At most this many decisions are kept: a scene whose upstream states never repeat would
/// otherwise keep one per expansion. Past the bound, decisions are computed and dropped.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
const MAX_CACHED: usize = 4096;

/// Decisions by (plan, upstream definition, upstream state).
#[derive(Default)]
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(super) struct DecisionCache {
    table: HashTable<Cached>,
    /// Scratch: the state being looked up.
    state: Vec<u8>,
    /// Scratch: where the plan's reads are in U.
    slots: Vec<Slot>,
}

struct Cached {
    hash: u64,
    plan: usize,
    def: usize,
    state: Box<[u8]>,
    decision: Arc<Decision>,
}

/// A look-up that missed: what [`DecisionCache::insert`] needs to store the decision.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(super) struct Miss {
    hash: u64,
    plan: usize,
    def: usize,
}

impl DecisionCache {
    /// The number of decisions kept.
    #[cfg(feature = "testkit")]
    pub fn cached(&self) -> usize {
        self.table.len()
    }

    /// The cached decision of `plan` for `upstream` in its current state, else what to
    /// insert it under. `def` identifies U's definition (its address; 0 for none).
    pub fn lookup(
        &mut self,
        plan: &Plan,
        def: usize,
        net: &Network,
        upstream: NodeId,
    ) -> Result<Arc<Decision>, Miss> {
        self.state.clear();
        plan.reads.find_in(net, upstream, &mut self.slots);
        for slot in &self.slots {
            let param = slot.position().map(|i| net.param_at(upstream, i));
            encode_param(&mut self.state, param);
        }
        let hash = FxBuildHasher.hash_one((plan.id, def, &self.state[..]));
        let state = &self.state[..];
        let found = self.table.find(hash, |c| {
            c.plan == plan.id && c.def == def && &*c.state == state
        });
        match found {
            Some(c) => Ok(c.decision.clone()),
            None => Err(Miss {
                hash,
                plan: plan.id,
                def,
            }),
        }
    }

    /// Keep `decision` for the state of the last [`DecisionCache::lookup`] (which missed).
    pub fn insert(&mut self, miss: Miss, decision: Arc<Decision>) {
        if self.table.len() >= MAX_CACHED {
            return;
        }
        let cached = Cached {
            hash: miss.hash,
            plan: miss.plan,
            def: miss.def,
            state: self.state.as_slice().into(),
            decision,
        };
        self.table.insert_unique(miss.hash, cached, |c| c.hash);
    }
}

/// Appends what a conditional can observe of one parameter of U: whether it exists, is
/// connected and has a value, and the value bit for bit (so `-0.0` and `0.0`, which compare
/// equal, are still different states).
#[cfg_attr(feature = "testkit", visibility::make(pub))]
fn encode_param(out: &mut Vec<u8>, param: Option<&Param>) {
    let Some(p) = param else {
        out.push(0);
        return;
    };
    out.push(1 | u8::from(p.is_connected()) << 1 | u8::from(p.value().is_some()) << 2);
    match p.value() {
        None => {}
        Some(Value::Int(i)) => {
            out.push(1);
            out.extend_from_slice(&i.to_le_bytes());
        }
        Some(Value::Float(f)) => {
            out.push(2);
            out.extend_from_slice(&f.to_bits().to_le_bytes());
        }
        // Rarer values: their debug text is exact (floats print as the shortest text that
        // reads back to the same bits), and the length prefix keeps the encoding unambiguous.
        Some(other) => {
            out.push(3);
            let start = out.len();
            out.extend_from_slice(&[0; 4]);
            // Writing to a Vec cannot fail.
            let _ = write!(out, "{other:?}");
            let len = u32::try_from(out.len() - start - 4).unwrap_or(u32::MAX);
            out[start..start + 4].copy_from_slice(&len.to_le_bytes());
        }
    }
}
