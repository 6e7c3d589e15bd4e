//! Optimisation passes over a [`MaterialIr`]: constant folding and common-subexpression
//! elimination (replaying the program through [`ProgramBuilder`]), dead-lobe elimination
//! (replaying the closure DAG through [`IrBuilder`], which drops statically zero closures),
//! dead-code elimination of unused ops and input slots, and the `MAX_LOBES` check (LW010).

use super::closure::{Node, NodeId};
use super::program::{OpCode, ProgramBuilder, Reg};
use super::{Cl, FrameSlot, IrBuilder, MAX_LOBES, MaterialIr};
use crate::diag::Diagnostic;
#[cfg(any(test, feature = "testkit"))]
use glam::Vec3;
use rustc_hash::FxHashMap as HashMap;

/// The nodes reachable from `root`, renumbered so that the root is node 0 and every node
/// precedes its children (reverse post-order of a depth-first walk).
pub fn topo_from_root(nodes: &[Node], root: NodeId) -> Vec<Node> {
    let mut post = Vec::new();
    let mut state = vec![0u8; nodes.len()]; // 0 new, 1 open, 2 done
    let mut stack = vec![(root, false)];
    while let Some((id, expanded)) = stack.pop() {
        let i = id.index();
        if expanded {
            if state[i] != 2 {
                state[i] = 2;
                post.push(id);
            }
            continue;
        }
        if state[i] != 0 {
            continue;
        }
        state[i] = 1;
        stack.push((id, true));
        for c in nodes[i].children().into_iter().rev() {
            if state[c.index()] == 0 {
                stack.push((c, false));
            }
        }
    }
    post.reverse();
    let index: HashMap<NodeId, NodeId> = post
        .iter()
        .enumerate()
        .map(|(k, &id)| (id, NodeId(k as u32)))
        .collect();
    post.iter()
        .map(|id| remap_children(&nodes[id.index()], |c| index[&c]))
        .collect()
}

fn remap_children(node: &Node, f: impl Fn(NodeId) -> NodeId) -> Node {
    match node.clone() {
        Node::Layer { top, base, mode } => Node::Layer {
            top: f(top),
            base: f(base),
            mode,
        },
        Node::Mix { a, b, m } => Node::Mix {
            a: f(a),
            b: f(b),
            m,
        },
        Node::Add { a, b } => Node::Add { a: f(a), b: f(b) },
        Node::Multiply { f: g, c } => Node::Multiply { f: f(g), c },
        other => other,
    }
}

fn remap_regs(node: &Node, f: &impl Fn(Reg) -> Reg) -> Node {
    match node.clone() {
        Node::Leaf(mut l) => {
            l.kind.map_regs(f);
            l.tint = f(l.tint);
            l.ttint = f(l.ttint);
            Node::Leaf(l)
        }
        Node::Emission { radiance } => Node::Emission {
            radiance: f(radiance),
        },
        Node::Transparent { tint } => Node::Transparent { tint: f(tint) },
        Node::Mix { a, b, m } => Node::Mix { a, b, m: f(m) },
        Node::Multiply { f: g, c } => Node::Multiply { f: g, c: f(c) },
        other => other,
    }
}

fn remap_frame(fr: &FrameSlot, f: &impl Fn(Reg) -> Reg) -> FrameSlot {
    FrameSlot {
        normal: fr.normal.map(f),
        tangent: fr.tangent.map(f),
        rotation: fr.rotation.map(f),
    }
}

/// Replay one node (children first) into `b`.
fn replay(
    ir: &MaterialIr,
    id: NodeId,
    b: &mut IrBuilder,
    regs: &impl Fn(Reg) -> Reg,
    frames: &[u32],
    memo: &mut HashMap<NodeId, Cl>,
) -> Cl {
    if let Some(&c) = memo.get(&id) {
        return c;
    }
    let node = remap_regs(&ir.nodes[id.index()], regs);
    let out = match node {
        Node::Leaf(mut l) => {
            l.frame = frames.get(l.frame as usize).copied().unwrap_or(0);
            b.leaf(l)
        }
        Node::Emission { radiance } => b.emission(radiance),
        Node::Transparent { tint } => b.transparent(tint),
        Node::Layer { top, base, mode } => {
            let t = replay(ir, top, b, regs, frames, memo);
            let u = replay(ir, base, b, regs, frames, memo);
            b.layer(t, u, mode)
        }
        Node::Mix { a, b: bb, m } => {
            let x = replay(ir, a, b, regs, frames, memo);
            let y = replay(ir, bb, b, regs, frames, memo);
            b.mix(x, y, m)
        }
        Node::Add { a, b: bb } => {
            let x = replay(ir, a, b, regs, frames, memo);
            let y = replay(ir, bb, b, regs, frames, memo);
            b.add(x, y)
        }
        Node::Multiply { f, c } => {
            let x = replay(ir, f, b, regs, frames, memo);
            b.mul(x, c)
        }
    };
    memo.insert(id, out);
    out
}

/// Fold constants, share subexpressions, drop dead lobes, unused ops and unused input slots,
/// order the nodes root-first, and check `MAX_LOBES` (LW010, error).
#[cfg(any(test, feature = "testkit"))]
pub fn optimize(ir: MaterialIr) -> Result<MaterialIr, Box<Diagnostic>> {
    optimize_with(ir, None)
}

/// [`optimize`], reusing `prog` as the already folded program builder of `ir` (the
/// [`IrBuilder::finish`] path, which need not fold twice).
pub(super) fn optimize_with(
    ir: MaterialIr,
    prog: Option<ProgramBuilder>,
) -> Result<MaterialIr, Box<Diagnostic>> {
    // 1. Fold + CSE: replay every op through a fresh builder (unless already folded).
    let folded = prog.is_some();
    let mut b = IrBuilder {
        prog: prog.unwrap_or_default(),
        inputs: ir.inputs.clone(),
        ..IrBuilder::default()
    };
    let mut map: Vec<u32> = Vec::with_capacity(ir.program.len());
    for (i, op) in ir.program.ops.iter().enumerate() {
        if folded {
            map.push(i as u32);
            continue;
        }
        let mut new = *op;
        for k in 0..op.code.arity() {
            new.args[k] = map[op.args[k] as usize];
        }
        map.push(b.prog.push(new).0);
    }
    let regs = |r: Reg| Reg(map[r.index()]);
    // Frames first (so that a frame that became the default maps to 0).
    b.frames = vec![FrameSlot::default()];
    let frames: Vec<u32> = ir
        .frames
        .iter()
        .map(|f| b.frame(remap_frame(f, &regs)))
        .collect();
    // 2. Dead lobes: replay the DAG from the root.
    let root = if ir.nodes.is_empty() {
        None
    } else {
        let mut memo = HashMap::default();
        replay(&ir, NodeId(0), &mut b, &regs, &frames, &mut memo)
    };
    let nodes = match root {
        Some(r) => topo_from_root(&b.nodes, r),
        None => Vec::new(),
    };
    // 3. Dead code: keep the ops that nodes and used frames read.
    let mut used_frames = vec![false; b.frames.len()];
    used_frames[0] = true;
    for n in &nodes {
        if let Node::Leaf(l) = n {
            used_frames[l.frame as usize] = true;
        }
    }
    let frame_index: Vec<Option<u32>> = {
        let mut k = 0;
        used_frames
            .iter()
            .map(|&u| {
                u.then(|| {
                    k += 1;
                    k - 1
                })
            })
            .collect()
    };
    let frames: Vec<FrameSlot> = b
        .frames
        .iter()
        .zip(&used_frames)
        .filter(|(_, u)| **u)
        .map(|(f, _)| *f)
        .collect();
    let mut roots: Vec<Reg> = nodes.iter().flat_map(Node::regs).collect();
    for f in &frames {
        roots.extend(f.normal.iter().chain(&f.tangent).chain(&f.rotation));
    }
    let program = b.prog.finish();
    let (mut program, rmap) = program.compact(&roots);
    let rr = |r: Reg| rmap.get(&r).copied().unwrap_or(r);
    let nodes: Vec<Node> = nodes
        .iter()
        .map(|n| {
            let mut n = remap_regs(n, &rr);
            if let Node::Leaf(l) = &mut n {
                l.frame = frame_index[l.frame as usize].unwrap_or(0);
            }
            n
        })
        .collect();
    let frames: Vec<FrameSlot> = frames.iter().map(|f| remap_frame(f, &rr)).collect();
    // 4. Unused input slots.
    let mut used_slots = vec![false; b.inputs.len()];
    for op in &program.ops {
        if op.code == OpCode::Input
            && let Some(u) = used_slots.get_mut(op.args[0] as usize) {
                *u = true;
            }
    }
    let mut slot_index = HashMap::default();
    let mut inputs = Vec::new();
    for (i, s) in b.inputs.into_iter().enumerate() {
        if used_slots[i] {
            slot_index.insert(i as u32, inputs.len() as u32);
            inputs.push(s);
        }
    }
    for op in &mut program.ops {
        if op.code == OpCode::Input {
            op.args[0] = slot_index.get(&op.args[0]).copied().unwrap_or(0);
        }
    }
    // 5. Lobe budget.
    let lobes = nodes.iter().filter(|n| n.is_lobe()).count();
    if lobes > MAX_LOBES {
        return Err(Box::new(
            Diagnostic::error(
                "LW010",
                format!(
                    "material `{}` has {lobes} BSDF lobes; at most {MAX_LOBES} are supported",
                    ir.name
                ),
            )
            .with_note("disable lobes (gains 0, enable flags off) or split the material"),
        ));
    }
    Ok(MaterialIr {
        name: ir.name,
        recipe: ir.recipe,
        inputs,
        program,
        nodes,
        frames,
        max_static_lobes: lobes as u8,
    })
}

/// Replace input slot `slot` by a constant and re-optimise (used to specialise a material
/// for a known input value).
#[cfg(any(test, feature = "testkit"))]
pub fn specialize(
    ir: &MaterialIr,
    slot: usize,
    value: Vec3,
) -> Result<MaterialIr, Box<Diagnostic>> {
    let mut ir = ir.clone();
    for op in &mut ir.program.ops {
        if op.code == OpCode::Input && op.args[0] as usize == slot {
            op.code = OpCode::Const;
            op.args = [0; 4];
            op.imm = value.to_array();
        }
    }
    optimize(ir)
}
