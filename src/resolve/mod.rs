//! vstruct resolution: expand every placeholder connection between an
//! output head and an input head into member connections and values, upstream first, exactly
//! as OpenUSD hdPrman does, and report what the reference does silently. The user-facing
//! description of the algorithm and of the VS codes is `docs/resolution.md`.
//!
//! The reference recurses; this implementation runs the same algorithm on an explicit work
//! stack, so that a chain of 100,000 nodes cannot overflow the thread's stack. Each stack frame
//! is one node being resolved, with the snapshot of its connected input heads and the position
//! reached in it.

use crate::cond::{
    self, Action, ActionKind, Choice, ComparisonReport, CopyOutcome, Extension, Extensions,
    Statement,
};
use crate::diag::{Diagnostic, Diagnostics, LIST_ENDS, Location, join_bounded};
use crate::limits::{LimitExceeded, Limits};
use crate::network::{Link, Network, NodeId, Slot, Sym};
use crate::registry::tables::{CondEntry, InputMember, OutputMember, VstructTables};
use crate::registry::{IndexedDefinition, Registry};
use crate::types::Value;
use rustc_hash::FxHashMap as HashMap;
use std::sync::Arc;

// Definition checks and decision plans: public under `testkit` for their unit tests.
testkit_mods!(check, plan);
mod story;
pub use check::check_definitions;
use plan::{Decision, DecisionCache, Plan, Verdict};
pub use story::{Story, StoryEvent, StoryRead};

/// Options of one resolution run.
#[derive(Debug, Clone)]
pub struct ResolveOptions {
    /// Evaluate conditionals (the default). `false` is the reference's
    /// `enableConditions = false`: every matched member connects.
    pub conditions: bool,
    /// Opt-in extensions. Without them, results are exactly the reference's.
    pub extensions: Extensions,
    /// Also report `note` diagnostics (VS021: a downstream member without counterpart).
    pub verbose: bool,
    /// Record one [`MemberEvent`] per member decision (for [`Resolution::story`]).
    pub record_events: bool,
    /// Delete every connection still on an input head after resolution (the VS010
    /// placeholders) instead of keeping it.
    pub drop_unresolved: bool,
    /// Bounds the network must meet before it is resolved ([`Network::check_limits`]: nodes,
    /// parameters per node, connections per input). A network beyond them is not resolved:
    /// [`Resolution::limit`] says which bound, and an LM001 error is among the diagnostics.
    pub limits: Limits,
}

impl Default for ResolveOptions {
    fn default() -> Self {
        ResolveOptions {
            conditions: true,
            extensions: Extensions::none(),
            verbose: false,
            record_events: false,
            drop_unresolved: false,
            limits: Limits::default(),
        }
    }
}

/// What resolution did, besides editing the network.
#[derive(Debug, Clone, Default)]
pub struct Resolution {
    /// Every diagnostic, in the order the algorithm produced them.
    pub diagnostics: Diagnostics,
    /// Member decisions, when [`ResolveOptions::record_events`] is set.
    pub events: Vec<MemberEvent>,
    /// The bound of [`ResolveOptions::limits`] the network exceeded, when it was not
    /// resolved for that reason.
    pub limit: Option<LimitExceeded>,
}

/// One value an expression read on the upstream node.
#[derive(Debug, Clone, PartialEq)]
pub struct ValueRead {
    /// The parameter name on the upstream node.
    pub param: String,
    /// Where the value came from.
    pub source: ReadSource,
    /// Whether the input had a connection at evaluation time.
    pub connected: bool,
}

/// The origin of a value read by a conditional.
#[derive(Debug, Clone, PartialEq)]
pub enum ReadSource {
    /// An authored value (including one written by `set`/`copy` earlier in the run).
    Authored(Value),
    /// The definition default of a declared input.
    Default(Value),
    /// A declared input without value or default.
    NoValue,
    /// The upstream definition declares no such input.
    Undeclared,
}

/// What happened to one downstream member.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// Connected to the upstream member output.
    Connected,
    /// Left alone by `ignore` (keeps its value or default).
    Ignored,
    /// A value was written by `set` or `copy`.
    Written(Value),
    /// `set` or `copy` could not be applied (VS013 / VS014); nothing changed.
    NotApplied(String),
    /// Already connected: the direct connection wins (VS019).
    DirectConnectionWins,
    /// The conditional failed to parse: never connected (VS016).
    Unparsable,
    /// No upstream member matches any of the member's names.
    NoCounterpart,
}

impl Outcome {
    /// The outcome as one word: `connected`, `ignored`, `written`, `not-applied`,
    /// `direct-connection-wins`, `unparsable` or `no-counterpart`.
    pub fn word(&self) -> &'static str {
        match self {
            Outcome::Connected => "connected",
            Outcome::Ignored => "ignored",
            Outcome::Written(_) => "written",
            Outcome::NotApplied(_) => "not-applied",
            Outcome::DirectConnectionWins => "direct-connection-wins",
            Outcome::Unparsable => "unparsable",
            Outcome::NoCounterpart => "no-counterpart",
        }
    }
}

/// One member decision during resolution ([`Resolution::story`] tells stories from them).
#[derive(Debug, Clone, PartialEq)]
pub struct MemberEvent {
    /// Downstream node.
    pub node: NodeId,
    /// Downstream member input.
    pub member: String,
    /// The input head it was expanded from.
    pub head: String,
    /// Upstream node and output head.
    pub upstream: NodeId,
    /// The upstream output head.
    pub upstream_head: String,
    /// The upstream member output that matched, and by which name.
    pub matched: Option<(String, String)>,
    /// The conditional text, if the matched output has one and conditions are enabled.
    pub expression: Option<String>,
    /// The chosen action as written (`connect`, `set 1`, …), if a conditional was evaluated.
    pub action: Option<String>,
    /// Every parameter the conditional names, with the value it had on the upstream node.
    pub reads: Vec<ValueRead>,
    /// What happened.
    pub outcome: Outcome,
}

/// Resolve every vstruct connection of `net` against `registry`.
///
/// The network is first checked against its definitions ([`check_definitions`]: undeclared
/// parameters and outputs, VS024; unknown node types, VS020). Nodes are visited in sorted
/// order; each node's input heads are expanded after the upstream node has been resolved
/// completely. Afterwards authored values on input heads are
/// removed (VS017).
pub fn resolve(net: &mut Network, registry: &Registry, options: &ResolveOptions) -> Resolution {
    if let Err(e) = net.check_limits(&options.limits) {
        let mut out = Resolution::default();
        out.diagnostics.push(e.to_diagnostic());
        out.limit = Some(e);
        return out;
    }
    let order = net.nodes_sorted();
    let checked = check::check_in_order(net, registry, &order);
    // Resolution edits connections only; the graph's edges are rebuilt once at the end
    // (removing them one by one is quadratic for nodes with many connections).
    net.suspend_edges();
    // Resolution adds no nodes, so every node index stays below this bound.
    let bound = petgraph::visit::NodeIndexable::node_bound(net.graph());
    let mut r = Resolver {
        net,
        registry,
        options,
        out: Resolution {
            diagnostics: checked,
            ..Resolution::default()
        },
        visited: NodeSet::new(bound),
        on_stack: NodeSet::new(bound),
        types: HashMap::default(),
        unconditioned: None,
        memo: HashMap::default(),
        plans: HashMap::default(),
        decisions: DecisionCache::default(),
        decision: Arc::default(),
        order,
        slots: Vec::new(),
    };
    r.run();
    r.report_unconditioned();
    r.remove_head_values();
    let out = r.out;
    net.restore_edges();
    if options.drop_unresolved {
        drop_unresolved(net, registry);
    }
    out
}

/// Delete every connection still on an input head (the VS010 placeholders).
fn drop_unresolved(net: &mut Network, registry: &Registry) {
    for node in net.nodes_sorted() {
        let Some(tables) = registry.tables(net[node].shader()) else {
            continue;
        };
        for input in net.connected_inputs(node) {
            if tables.is_input_head(&input) {
                net.clear_connections(node, &input);
            }
        }
    }
}

/// One node under resolution on the work stack.
struct Frame {
    node: NodeId,
    /// Connected input heads of the node, snapshot taken when the node was entered (step 3).
    heads: Vec<String>,
    /// Position in `heads`.
    next: usize,
    /// True when the upstream of `heads[next]` has already been entered (step 3d done).
    upstream_done: bool,
}

/// The checked upstream end of a head connection.
struct HeadSource {
    upstream: NodeId,
    head: String,
}

struct Resolver<'a> {
    net: &'a mut Network,
    registry: &'a Registry,
    options: &'a ResolveOptions,
    out: Resolution,
    visited: NodeSet,
    /// Nodes of the frames on the work stack (step 1's "on stack"), for O(1) cycle checks.
    on_stack: NodeSet,
    /// Per shader id: its definition and tables, looked up in the registry once per run.
    types: HashMap<String, TypeInfo>,
    /// `--no-conditions`: how many members were connected without evaluating a conditional
    /// that does not always connect, and the first one (VS022 reports them once).
    unconditioned: Option<(usize, String)>,
    /// Scratch while a [`Decision`] is computed: the choice of each conditional evaluated so
    /// far, keyed by the shared parse result, so members with the same expression text share
    /// one evaluation (exact because expanding D never changes U; when D is U nothing is
    /// decided ahead). The choice is kept rather than the action: it is `Copy`.
    memo: HashMap<usize, KnownChoice>,
    /// Plans per (downstream tables, input head, upstream tables, output head).
    plans: HashMap<(usize, String, usize, String), Arc<Plan>>,
    /// Decisions already computed, by plan and upstream state.
    decisions: DecisionCache,
    /// The decision of the head being expanded.
    decision: Arc<Decision>,
    /// Every node in handle order (resolution adds no nodes): the order of the walk and of
    /// the final head-value clean-up.
    order: Vec<NodeId>,
    /// Scratch: where each member of the head being expanded is in the downstream node.
    slots: Vec<Slot>,
}

/// A set of nodes as one flag per node index: resolution asks for every node and every head
/// whether it was visited, and a dense table answers that without hashing or scattered reads.
struct NodeSet(Vec<bool>);

impl NodeSet {
    /// An empty set for node indices below `bound`.
    fn new(bound: usize) -> NodeSet {
        NodeSet(vec![false; bound])
    }

    /// Adds `node`; false if it was in the set already.
    fn insert(&mut self, node: NodeId) -> bool {
        !std::mem::replace(&mut self.0[node.index()], true)
    }

    fn remove(&mut self, node: NodeId) {
        self.0[node.index()] = false;
    }

    fn contains(&self, node: NodeId) -> bool {
        self.0[node.index()]
    }
}

/// A conditional's choice, and whether its evaluation reported anything (VS015).
type KnownChoice = (Choice, bool);

/// The definitions of D and U, when known.
type Defs<'d> = (Option<&'d IndexedDefinition>, Option<&'d IndexedDefinition>);

#[derive(Clone)]
struct TypeInfo {
    def: Option<Arc<IndexedDefinition>>,
    tables: Option<Arc<VstructTables>>,
}

impl Resolver<'_> {
    fn type_info(&mut self, shader: &str) -> TypeInfo {
        if let Some(info) = self.types.get(shader) {
            return info.clone();
        }
        let info = TypeInfo {
            def: self.registry.indexed(shader),
            tables: self.registry.tables(shader),
        };
        self.types.insert(shader.to_string(), info.clone());
        info
    }

    fn tables(&mut self, shader: &str) -> Option<Arc<VstructTables>> {
        self.type_info(shader).tables
    }

    fn definition(&mut self, shader: &str) -> Option<Arc<IndexedDefinition>> {
        self.type_info(shader).def
    }

    fn run(&mut self) {
        let mut stack: Vec<Frame> = Vec::new();
        let order = std::mem::take(&mut self.order);
        for &start in &order {
            if let Some(frame) = self.enter(start) {
                self.on_stack.insert(frame.node);
                stack.push(frame);
            }
            while let Some(top) = stack.len().checked_sub(1) {
                if stack[top].next >= stack[top].heads.len() {
                    self.on_stack.remove(stack[top].node);
                    stack.pop();
                    continue;
                }
                if let Some(upstream) = self.step(&mut stack, top)
                    && let Some(frame) = self.enter(upstream)
                {
                    self.on_stack.insert(frame.node);
                    stack.push(frame);
                }
            }
        }
        self.order = order;
    }

    /// Step 1–3 entry: mark visited and snapshot the connected input heads. `None` if the
    /// node was visited before or has nothing to expand.
    fn enter(&mut self, node: NodeId) -> Option<Frame> {
        if !self.visited.insert(node) {
            return None;
        }
        let shader = self.net[node].shader().to_string();
        // An unknown type was reported by the definition check (VS020).
        let tables = self.tables(&shader)?;
        // The connected input heads in byte-wise order. A type has a few heads and a node
        // many parameters, so the heads are checked rather than the parameters scanned.
        let mut heads: Vec<String> = tables
            .input_heads()
            .filter(|h| !self.net.connections(node, h).is_empty())
            .map(str::to_string)
            .collect();
        heads.sort_unstable();
        heads.dedup();
        if heads.is_empty() {
            return None;
        }
        Some(Frame {
            node,
            heads,
            next: 0,
            upstream_done: false,
        })
    }

    /// Advance the top frame by one head. Returns an upstream node to enter first, if the
    /// current head's upstream has not been resolved yet.
    fn step(&mut self, stack: &mut [Frame], top: usize) -> Option<NodeId> {
        let (node, head, upstream_done) = {
            let f = &stack[top];
            (f.node, f.heads[f.next].clone(), f.upstream_done)
        };
        let Some(source) = self.check_head(node, &head, !upstream_done) else {
            stack[top].next += 1;
            stack[top].upstream_done = false;
            return None;
        };
        if !upstream_done {
            stack[top].upstream_done = true;
            if self.on_stack.contains(source.upstream) {
                let pos = stack
                    .iter()
                    .position(|f| f.node == source.upstream)
                    .unwrap_or(0);
                self.report_cycle(&stack[pos..], &head, &source);
            } else if !self.visited.contains(source.upstream) {
                return Some(source.upstream);
            }
        }
        self.expand(node, &head, &source);
        stack[top].next += 1;
        stack[top].upstream_done = false;
        None
    }

    /// Steps 3b–3c: the first connection of the head must come from an output head of a known
    /// upstream type. Diagnostics are produced on the first visit only.
    fn check_head(&mut self, node: NodeId, head: &str, report: bool) -> Option<HeadSource> {
        let links = self.net.connections(node, head);
        let first = links.first()?.clone();
        if report && links.len() > 1 {
            let links = links.to_vec();
            self.report_extra_connections(node, head, &links);
        }
        let problem = match (&first.upstream_node(), first.output()) {
            (None, _) => format!(
                "upstream node `{}` does not exist",
                first.missing_handle().unwrap_or_default()
            ),
            (Some(_), None) => "it is a whole-node reference (no output name)".to_string(),
            (Some(up), Some(out)) => {
                let shader = self.net[*up].shader().to_string();
                match self.tables(&shader) {
                    None => {
                        format!("the type `{shader}` of `{}` is unknown", self.name(*up))
                    }
                    Some(t) if !t.is_output_head(out) => {
                        format!("`{out}` is not an output head of `{shader}`")
                    }
                    Some(_) => {
                        return Some(HeadSource {
                            upstream: *up,
                            head: out.to_string(),
                        });
                    }
                }
            }
        };
        if report {
            let d = Diagnostic::warning(
                "VS010",
                format!(
                    "placeholder {} ← {} cannot be resolved: {problem}; it is kept",
                    self.plug(node, head),
                    self.link_text(&first)
                ),
            );
            self.push(d, node, Some(head));
        }
        None
    }

    /// Steps 3e–3f: delete the placeholder(s) and expand each member of the head.
    fn expand(&mut self, node: NodeId, head: &str, source: &HeadSource) {
        let down_shader = self.net[node].shader().to_string();
        let up_shader = self.net[source.upstream].shader().to_string();
        let (Some(down_tables), Some(up_tables)) =
            (self.tables(&down_shader), self.tables(&up_shader))
        else {
            return;
        };
        let down_def = self.definition(&down_shader);
        let up_def = self.definition(&up_shader);
        self.net.clear_connections(node, head);
        let plan = self.plan(&down_tables, head, &up_tables, &source.head);
        let members = down_tables.members_in(head);
        // One look-up per member; connecting or writing then works by position.
        let mut slots = std::mem::take(&mut self.slots);
        plan.properties.find_in(self.net, node, &mut slots);
        let defs = (down_def.as_deref(), up_def.as_deref());
        self.decision = self.decide(node, source, defs, members, &plan);
        // Make room for exactly the parameters this head will add: growing by doubling, or
        // reserving a slot for every member, left most of a resolved scene's memory unused.
        let added = slots
            .iter()
            .zip(&self.decision.adds)
            .filter(|(slot, adds)| **adds && matches!(slot, Slot::Missing { .. }))
            .count();
        self.net.reserve_params(node, added);
        let decision = self.decision.clone();
        for (i, (member, planned)) in members.iter().zip(&plan.members).enumerate() {
            let slot = slots[i];
            let connected = match slot {
                Slot::At(at) => self.net.param_at(node, at).is_connected(),
                Slot::Missing { .. } => false,
            };
            // Most members are ignored or simply connected; the general path would come to
            // the same result through the explain story and the diagnostics checks.
            let verdict = match &planned.matched {
                Some(_) if self.options.record_events => &Verdict::General,
                _ => &decision.verdicts[i],
            };
            if !connected && *verdict == Verdict::Ignore {
                continue;
            }
            let ctx = MemberCtx {
                known: decision.choices[i],
                node,
                head,
                member: &member.property,
                member_sym: member.sym,
                slot,
                source,
                down_def: down_def.as_deref(),
                up_def: up_def.as_deref(),
            };
            if connected {
                self.direct_connection_wins(&ctx);
                continue;
            }
            match (verdict, &planned.matched) {
                (Verdict::Ignore, _) => {}
                (Verdict::Connect, Some((_, output))) => self.connect(&ctx, output.sym),
                // A new parameter has no value to replace (VS018), so writing is all there is.
                (Verdict::Write(value), Some(_)) if matches!(slot, Slot::Missing { .. }) => {
                    self.net.add_shared_value(node, member.sym, value);
                }
                (_, Some((name, output))) => self.apply_member(&ctx, &member.names[*name], output),
                (_, None) => self.no_counterpart(&ctx, &member.names),
            }
        }
        self.slots = slots;
    }

    /// The members' verdicts for this expansion: from the cache when U is in a state seen
    /// before with the same plan, else computed (and cached). U does not change while D is
    /// expanded, so deciding first gives the same results as deciding member by member; when
    /// D is U nothing is decided ahead and every matched member counts as adding.
    fn decide(
        &mut self,
        node: NodeId,
        source: &HeadSource,
        defs: Defs<'_>,
        members: &[InputMember],
        plan: &Plan,
    ) -> Arc<Decision> {
        let evaluates = self.options.conditions && node != source.upstream;
        // `array-index` reads elements through names the plan does not list.
        let cacheable = evaluates && !self.options.extensions.contains(Extension::ArrayIndex);
        let compute = |r: &mut Self, evaluates| {
            Arc::new(r.compute_decision(evaluates, source.upstream, defs, members, plan))
        };
        if !cacheable {
            return compute(self, evaluates);
        }
        // The plan fixes D's type; U's definition is part of the key.
        let def = defs.1.map_or(0, |d| d as *const IndexedDefinition as usize);
        match self.decisions.lookup(plan, def, self.net, source.upstream) {
            Ok(decision) => decision,
            Err(miss) => {
                let decision = compute(self, true);
                self.decisions.insert(miss, decision.clone());
                decision
            }
        }
    }

    /// Evaluates the plan's conditionals on U (when `evaluates`), each distinct one once.
    fn compute_decision(
        &mut self,
        evaluates: bool,
        upstream: NodeId,
        (down_def, up_def): Defs<'_>,
        members: &[InputMember],
        plan: &Plan,
    ) -> Decision {
        self.memo.clear();
        let mut decision = Decision::default();
        for (member, planned) in members.iter().zip(&plan.members) {
            let mut known = None;
            let (adds, verdict) = match &planned.matched {
                None => (false, Verdict::General),
                Some((_, output)) => match (&output.cond, self.options.conditions) {
                    (None, _) => (true, Verdict::Connect),
                    (Some(_), false) => (true, Verdict::General),
                    (Some(entry), true) => match entry.statement() {
                        None => (false, Verdict::General),
                        Some(_) if !evaluates => (true, Verdict::General),
                        Some(stmt) => {
                            let choice =
                                self.memo_choice(entry, stmt, upstream, up_def, &mut decision);
                            known = Some(choice);
                            let kind = &cond::chosen_action(stmt, choice.0).kind;
                            let verdict = match (kind, choice.1) {
                                (ActionKind::Ignore, false) => Verdict::Ignore,
                                (ActionKind::Connect, false) => Verdict::Connect,
                                (ActionKind::Set { literal }, false) => {
                                    let dest = down_def
                                        .and_then(|d| d.input(&member.property))
                                        .map(|p| &p.ty);
                                    match cond::set_value(literal, dest, &self.options.extensions) {
                                        Ok(set) if !set.saturated => {
                                            Verdict::Write(Arc::new(set.value))
                                        }
                                        _ => Verdict::General,
                                    }
                                }
                                _ => Verdict::General,
                            };
                            (!matches!(kind, ActionKind::Ignore), verdict)
                        }
                    },
                },
            };
            decision.choices.push(known);
            decision.adds.push(adds);
            decision.verdicts.push(verdict);
        }
        decision
    }

    /// The choice of `entry` on U, evaluating it the first time it is met while `decision`
    /// is computed (its VS015 reports go into the decision).
    fn memo_choice(
        &mut self,
        entry: &CondEntry,
        stmt: &Statement,
        upstream: NodeId,
        up_def: Option<&IndexedDefinition>,
        decision: &mut Decision,
    ) -> KnownChoice {
        let key = memo_key(entry);
        if let Some(known) = self.memo.get(&key) {
            return *known;
        }
        let view = NodeView {
            net: self.net,
            node: upstream,
            def: up_def,
        };
        let evaluation = cond::evaluate(stmt, &view, &self.options.extensions);
        let known = (evaluation.choice, !evaluation.reports.is_empty());
        if known.1 {
            decision.reports.insert(key, evaluation.reports);
        }
        self.memo.insert(key, known);
        known
    }

    /// The plan of a pair of heads, worked out on first use.
    fn plan(
        &mut self,
        down: &Arc<VstructTables>,
        head: &str,
        up: &Arc<VstructTables>,
        up_head: &str,
    ) -> Arc<Plan> {
        let key = (
            Arc::as_ptr(down) as usize,
            head.to_string(),
            Arc::as_ptr(up) as usize,
            up_head.to_string(),
        );
        if let Some(plan) = self.plans.get(&key) {
            return plan.clone();
        }
        let plan = Arc::new(Plan::new(
            self.plans.len(),
            down.members_in(head),
            up,
            up_head,
        ));
        self.plans.insert(key, plan.clone());
        plan
    }

    fn apply_member(&mut self, ctx: &MemberCtx<'_>, name: &str, output: &OutputMember) {
        // The explain story is built only when asked for: it costs several strings per member.
        let mut event = self
            .options
            .record_events
            .then(|| self.event(ctx, Some((output.property.to_string(), name.to_string()))));
        let outcome = match (&output.cond, self.options.conditions) {
            (None, _) => {
                self.connect(ctx, output.sym);
                Outcome::Connected
            }
            (Some(entry), false) => {
                self.connect(ctx, output.sym);
                if !always_connects(entry) {
                    self.no_conditions_info(ctx, &output.property, entry);
                }
                Outcome::Connected
            }
            (Some(entry), true) => {
                if let Some(e) = event.as_mut() {
                    e.expression = Some(entry.source.text.clone());
                }
                match entry.statement() {
                    Some(stmt) => self.evaluate(ctx, output.sym, entry, stmt, event.as_mut()),
                    None => {
                        self.unparsable(ctx, &output.property, entry);
                        Outcome::Unparsable
                    }
                }
            }
        };
        if let Some(mut e) = event {
            e.outcome = outcome;
            self.out.events.push(e);
        }
    }

    /// Evaluate the conditional against U and apply the chosen action to D.M.
    fn evaluate(
        &mut self,
        ctx: &MemberCtx<'_>,
        output: Sym,
        entry: &CondEntry,
        stmt: &Statement,
        event: Option<&mut MemberEvent>,
    ) -> Outcome {
        let view = NodeView {
            net: self.net,
            node: ctx.source.upstream,
            def: ctx.up_def,
        };
        let (choice, reports) = match ctx.known {
            // Reports are rare: look them up only when there are some.
            Some((choice, true)) => (
                choice,
                self.decision
                    .reports
                    .get(&memo_key(entry))
                    .cloned()
                    .unwrap_or_default(),
            ),
            Some((choice, false)) => (choice, Vec::new()),
            None => {
                let evaluation = cond::evaluate(stmt, &view, &self.options.extensions);
                (evaluation.choice, evaluation.reports)
            }
        };
        let action = cond::chosen_action(stmt, choice);
        if let Some(event) = event {
            event.reads = stmt
                .param_names()
                .into_iter()
                .map(|p| view.read(p))
                .collect();
            event.action = Some(action.to_string());
        }
        for report in &reports {
            self.comparison_warning(ctx, &output, entry, report);
        }
        match &action.kind {
            ActionKind::Connect => {
                self.connect(ctx, output);
                Outcome::Connected
            }
            ActionKind::Ignore => Outcome::Ignored,
            ActionKind::Set { literal } => {
                let dest = ctx
                    .down_def
                    .and_then(|d| d.input(ctx.member))
                    .map(|p| &p.ty);
                match cond::set_value(literal, dest, &self.options.extensions) {
                    Ok(set) => {
                        if set.saturated {
                            self.saturated_warning(ctx, action, &set.value);
                        }
                        self.write(ctx, set.value.clone(), action);
                        Outcome::Written(set.value)
                    }
                    Err(why) => {
                        let msg = why.to_string();
                        self.not_applied(ctx, cond::SetRejection::CODE, &msg, action);
                        Outcome::NotApplied(msg)
                    }
                }
            }
            ActionKind::Copy { param } => self.copy(ctx, &param.name, action),
        }
    }

    fn copy(&mut self, ctx: &MemberCtx<'_>, param: &str, action: &Action) -> Outcome {
        let up = ctx.source.upstream;
        let source_prop = ctx.up_def.and_then(|d| d.input(param));
        let value = self
            .net
            .value(up, param)
            .or_else(|| source_prop.and_then(|p| p.default.as_ref()))
            .cloned();
        let dest = ctx
            .down_def
            .and_then(|d| d.input(ctx.member))
            .map(|p| &p.ty);
        match cond::copy_value(
            value.as_ref(),
            source_prop.map(|p| &p.ty),
            dest,
            &self.options.extensions,
        ) {
            Ok(CopyOutcome::Write {
                value,
                shape_mismatch,
                saturated,
                ..
            }) => {
                if saturated {
                    self.saturated_warning(ctx, action, &value);
                }
                if shape_mismatch {
                    let msg = format!(
                        "`copy {param}` copies between an array and a non-array (or arrays of \
                         different sizes), as the reference does"
                    );
                    self.not_applied(ctx, cond::CopyRejection::CODE, &msg, action);
                }
                self.write(ctx, value.clone(), action);
                Outcome::Written(value)
            }
            Ok(CopyOutcome::NoValue) => Outcome::Ignored,
            Err(why) => {
                let msg = why.to_string();
                self.not_applied(ctx, cond::CopyRejection::CODE, &msg, action);
                Outcome::NotApplied(msg)
            }
        }
    }

    fn connect(&mut self, ctx: &MemberCtx<'_>, output: Sym) {
        let authored = ctx
            .slot
            .position()
            .is_some_and(|i| self.net.param_at(ctx.node, i).value().is_some());
        if authored {
            let d = Diagnostic::info(
                "VS018",
                format!(
                    "authored value on {} is overridden by the connection from {}",
                    self.plug(ctx.node, ctx.member),
                    self.plug(ctx.source.upstream, &output)
                ),
            );
            self.push(d, ctx.node, Some(ctx.member));
        }
        self.net.connect_slot(
            ctx.node,
            ctx.slot,
            ctx.member_sym,
            ctx.source.upstream,
            output,
        );
    }

    fn write(&mut self, ctx: &MemberCtx<'_>, value: Value, action: &Action) {
        let previous = self.net.set_slot(ctx.node, ctx.slot, ctx.member_sym, value);
        if let Some(old) = previous {
            let d = Diagnostic::info(
                "VS018",
                format!(
                    "authored value {old} on {} is replaced by `{action}`",
                    self.plug(ctx.node, ctx.member)
                ),
            );
            self.push(d, ctx.node, Some(ctx.member));
        }
    }

    /// Authored values on input heads are never meaningful; remove them (VS017).
    fn remove_head_values(&mut self) {
        for node in std::mem::take(&mut self.order) {
            let shader = self.net[node].shader().to_string();
            let Some(tables) = self.tables(&shader) else {
                continue;
            };
            let heads: Vec<String> = tables.input_heads().map(str::to_string).collect();
            for head in heads {
                if self.net.value(node, &head).is_none() {
                    continue;
                }
                let d = Diagnostic::warning(
                    "VS017",
                    format!(
                        "authored value on input head {} removed (a vstruct head carries no value)",
                        self.plug(node, &head)
                    ),
                );
                self.push(d, node, Some(&head));
                self.net.remove_value(node, &head);
            }
        }
    }

    // ----- diagnostics ---------------------------------------------------------------------

    fn direct_connection_wins(&mut self, ctx: &MemberCtx<'_>) {
        let links = self.net.connections(ctx.node, ctx.member).to_vec();
        let from = join_bounded(links.len(), |i| self.link_text(&links[i]));
        let d = Diagnostic::info(
            "VS019",
            format!(
                "{} is already connected to {from}; the direct connection wins over the \
                 expansion of `{}`",
                self.plug(ctx.node, ctx.member),
                ctx.head
            ),
        );
        self.push(d, ctx.node, Some(ctx.member));
        self.record_unexpanded(ctx, Outcome::DirectConnectionWins);
    }

    fn no_counterpart(&mut self, ctx: &MemberCtx<'_>, names: &[String]) {
        if self.options.verbose {
            let d = Diagnostic::note(
                "VS021",
                format!(
                    "{} has no counterpart named {} in `{}` of {}",
                    self.plug(ctx.node, ctx.member),
                    names
                        .iter()
                        .map(|n| format!("`{n}`"))
                        .collect::<Vec<_>>()
                        .join(" or "),
                    ctx.source.head,
                    self.name(ctx.source.upstream)
                ),
            );
            self.push(d, ctx.node, Some(ctx.member));
        }
        self.record_unexpanded(ctx, Outcome::NoCounterpart);
    }

    fn unparsable(&mut self, ctx: &MemberCtx<'_>, output: &str, entry: &CondEntry) {
        let why = match entry.parsed.as_ref() {
            Err(e) => e.message.clone(),
            Ok(_) => String::new(),
        };
        let d = Diagnostic::warning(
            "VS016",
            format!(
                "{} ← {} not expanded: the conditional {:?} failed to parse ({why})",
                self.plug(ctx.node, ctx.member),
                self.plug(ctx.source.upstream, output),
                entry.source.text
            ),
        )
        .with_related("conditional", entry.source.location.clone());
        self.push(d, ctx.node, Some(ctx.member));
    }

    /// VS022: a note per member with `--verbose`, and one info for the whole run
    /// ([`Resolver::report_unconditioned`]).
    fn no_conditions_info(&mut self, ctx: &MemberCtx<'_>, output: &str, entry: &CondEntry) {
        if let Some((count, ..)) = self.unconditioned.as_mut() {
            *count += 1;
            if !self.options.verbose {
                return;
            }
        }
        let hop = format!(
            "{} ← {}",
            self.plug(ctx.node, ctx.member),
            self.plug(ctx.source.upstream, output)
        );
        let d = Diagnostic::note(
            "VS022",
            format!(
                "{hop} connected without evaluating its conditional {:?} (--no-conditions)",
                entry.source.text
            ),
        );
        let d = self.located(d, ctx.node, Some(ctx.member));
        if self.unconditioned.is_none() {
            self.unconditioned = Some((1, hop));
        }
        if self.options.verbose {
            self.out.diagnostics.push(d);
        }
    }

    /// VS022 once: how many members `--no-conditions` connected without evaluating their
    /// conditional, naming the first. It is about the whole run, so it has no location (a
    /// source snippet under it would point at one member of many).
    fn report_unconditioned(&mut self) {
        let Some((count, first)) = self.unconditioned.take() else {
            return;
        };
        let d = Diagnostic::info(
            "VS022",
            format!(
                "--no-conditions: {count} member{} connected without evaluating a conditional \
                 that does not always connect (the first: {first}){}",
                if count == 1 { " was" } else { "s were" },
                if self.options.verbose {
                    ""
                } else {
                    "; --verbose lists them"
                }
            ),
        );
        self.out.diagnostics.push(d);
    }

    fn comparison_warning(
        &mut self,
        ctx: &MemberCtx<'_>,
        output: &str,
        entry: &CondEntry,
        report: &ComparisonReport,
    ) {
        let d = report
            .to_diagnostic(&entry.source.text)
            .with_note(format!(
                "evaluated on {} for {} ← {}",
                self.name(ctx.source.upstream),
                self.plug(ctx.node, ctx.member),
                self.plug(ctx.source.upstream, output)
            ))
            .with_related("conditional", entry.source.location.clone());
        self.push(d, ctx.node, Some(ctx.member));
    }

    /// VS023: `value` was written saturated, an int to the `i32` range, a float (or float
    /// components) to the finite `f32` range, which is all the writers and readers carry.
    fn saturated_warning(&mut self, ctx: &MemberCtx<'_>, action: &Action, value: &Value) {
        // The value is named by its rule, not written out: f32::MAX prints with 39 digits.
        let plug = self.plug(ctx.node, ctx.member);
        let message = match value {
            Value::Int(_) => format!("`{action}` is outside the int range; {plug} is saturated"),
            _ => format!(
                "`{action}` gives a float outside the finite f32 range (an infinity or NaN); \
                 {plug} is saturated to the largest finite float of its sign (±3.4028235e38), \
                 NaN to 0"
            ),
        };
        let d = Diagnostic::warning("VS023", message);
        self.push(d, ctx.node, Some(ctx.member));
    }

    fn not_applied(&mut self, ctx: &MemberCtx<'_>, code: &'static str, msg: &str, action: &Action) {
        let d = Diagnostic::warning(
            code,
            format!("{}: `{action}`: {msg}", self.plug(ctx.node, ctx.member)),
        );
        self.push(d, ctx.node, Some(ctx.member));
    }

    fn report_extra_connections(&mut self, node: NodeId, head: &str, links: &[Link]) {
        let dropped = join_bounded(links.len() - 1, |i| self.link_text(&links[i + 1]));
        let d = Diagnostic::warning(
            "VS011",
            format!(
                "{} has {} connections; only the first ({}) is expanded and all are deleted; \
                 dropped: {dropped}",
                self.plug(node, head),
                links.len(),
                self.link_text(&links[0])
            ),
        );
        self.push(d, node, Some(head));
    }

    /// VS012. A long cycle is named by its first and last hops and their count
    /// ([`join_bounded`]), so the message stays short whatever the cycle's length.
    fn report_cycle(&mut self, cycle: &[Frame], head: &str, source: &HeadSource) {
        // One hop per frame on the cycle: `node.head ← upstream.output`.
        let hop = |f: &Frame| {
            let input = f.heads.get(f.next).map(String::as_str).unwrap_or(head);
            let from = self
                .net
                .connections(f.node, input)
                .first()
                .map(|l| self.link_text(l))
                .unwrap_or_default();
            format!("{} ← {from}", self.plug(f.node, input))
        };
        let hops = join_bounded(cycle.len(), |i| hop(&cycle[i]));
        let Some(last) = cycle.last() else { return };
        let d = Diagnostic::warning(
            "VS012",
            format!(
                "{}: {} is still being resolved and is used as it is now: {hops}",
                if cycle.len() > 2 * LIST_ENDS + 1 {
                    format!("cycle of {} nodes", cycle.len())
                } else {
                    "cycle".to_string()
                },
                self.name(source.upstream),
            ),
        );
        self.push(d, last.node, Some(head));
    }

    // ----- helpers -------------------------------------------------------------------------

    fn name(&self, node: NodeId) -> String {
        self.net[node].display_name()
    }

    fn plug(&self, node: NodeId, param: &str) -> String {
        format!("{}.{param}", self.name(node))
    }

    fn link_text(&self, link: &Link) -> String {
        let up = match link.upstream_node() {
            Some(n) => self.name(n),
            None => link.missing_handle().unwrap_or_default().to_string(),
        };
        match link.output() {
            Some(o) => format!("{up}.{o}"),
            None => up,
        }
    }

    /// Attach the most precise location known (the parameter's, else the node's) and push.
    fn push(&mut self, d: Diagnostic, node: NodeId, param: Option<&str>) {
        let d = self.located(d, node, param);
        self.out.diagnostics.push(d);
    }

    /// `d` with the most precise location known (the parameter's, else the node's), the
    /// node and the parameter.
    fn located(&self, d: Diagnostic, node: NodeId, param: Option<&str>) -> Diagnostic {
        let n = &self.net[node];
        let loc: Option<Location> = param
            .and_then(|p| n.param(p))
            .and_then(|p| n.param_location(p))
            .or_else(|| n.location().cloned());
        let mut d = match loc {
            Some(l) => d.at(l),
            None => d,
        }
        .with_node(n.handle());
        if let Some(p) = param {
            d = d.with_param(p);
        }
        d
    }

    fn event(&self, ctx: &MemberCtx<'_>, matched: Option<(String, String)>) -> MemberEvent {
        MemberEvent {
            node: ctx.node,
            member: ctx.member.to_string(),
            head: ctx.head.to_string(),
            upstream: ctx.source.upstream,
            upstream_head: ctx.source.head.clone(),
            matched,
            expression: None,
            action: None,
            reads: Vec::new(),
            outcome: Outcome::NoCounterpart,
        }
    }

    /// Records the story of a member that was not expanded (explain), if asked for.
    fn record_unexpanded(&mut self, ctx: &MemberCtx<'_>, outcome: Outcome) {
        if self.options.record_events {
            let mut event = self.event(ctx, None);
            event.outcome = outcome;
            self.out.events.push(event);
        }
    }
}

/// The member being expanded and everything needed to apply an action to it.
struct MemberCtx<'c> {
    node: NodeId,
    head: &'c str,
    member: &'c str,
    /// The member's interned name.
    member_sym: Sym,
    /// Where the member is among the node's parameters.
    slot: Slot,
    /// The conditional's choice when it was evaluated ahead.
    known: Option<KnownChoice>,
    source: &'c HeadSource,
    down_def: Option<&'c IndexedDefinition>,
    up_def: Option<&'c IndexedDefinition>,
}

/// The memo key of a conditional: its shared parse result, so members with the same
/// expression text share one entry.
fn memo_key(entry: &CondEntry) -> usize {
    Arc::as_ptr(&entry.parsed) as usize
}

/// True if every branch of the conditional connects (so `--no-conditions` changes nothing
/// for it and VS022 is not reported).
fn always_connects(entry: &CondEntry) -> bool {
    match entry.statement() {
        None => false,
        Some(stmt) => {
            let connects = |a: &Action| matches!(a.kind, ActionKind::Connect);
            connects(&stmt.action)
                && stmt.fallback.as_ref().is_none_or(connects)
                && (stmt.condition.is_none() || stmt.fallback.is_some())
                && stmt.else_ifs.iter().all(|l| connects(&l.action))
        }
    }
}

/// The upstream node as the conditional evaluator sees it: the network's current state plus
/// the node's definition.
struct NodeView<'v> {
    net: &'v Network,
    node: NodeId,
    def: Option<&'v IndexedDefinition>,
}

impl NodeView<'_> {
    fn read(&self, param: &str) -> ValueRead {
        let connected = !self.net.connections(self.node, param).is_empty();
        let declared = self.def.and_then(|d| d.input(param));
        let source = match (self.net.value(self.node, param), declared) {
            (Some(v), _) => ReadSource::Authored(v.clone()),
            (None, Some(p)) => match &p.default {
                Some(v) => ReadSource::Default(v.clone()),
                None => ReadSource::NoValue,
            },
            (None, None) => ReadSource::Undeclared,
        };
        ValueRead {
            param: param.to_string(),
            source,
            connected,
        }
    }
}

impl cond::Upstream for NodeView<'_> {
    fn authored(&self, param: &str) -> Option<&Value> {
        self.net.value(self.node, param)
    }
    fn declares_input(&self, param: &str) -> bool {
        self.def.is_some_and(|d| d.input(param).is_some())
    }
    fn default_value(&self, param: &str) -> Option<&Value> {
        self.def?.input(param)?.default.as_ref()
    }
    fn is_connected(&self, param: &str) -> bool {
        !self.net.connections(self.node, param).is_empty()
    }
    /// One look-up in the node and at most one in the definition.
    fn operand(&self, param: &str) -> Option<&Value> {
        self.net
            .value(self.node, param)
            .or_else(|| self.def?.input(param)?.default.as_ref())
    }
}

impl Extensions {
    /// The names of the extensions in this set that act in the resolver and are not
    /// implemented yet: a caller asking for them gets an error instead of silently unchanged
    /// results.
    pub fn unsupported_by_resolver(&self) -> Vec<&'static str> {
        [Extension::ArrayHeads, Extension::Nested]
            .into_iter()
            .filter(|e| self.contains(*e))
            .map(Extension::name)
            .collect()
    }
}
