//! Stable text forms of the IR (`--emit ir`) and of the flat lobe list (`--emit lobes`).
//!
//! Constant operands are printed inline as literals (a scalar when all lanes are equal,
//! else `(r, g, b)`), so `const` ops do not appear in the op listing.

use super::MaterialIr;
use super::algebra::{self, AlbedoSource};
use super::closure::{DielectricMode, Leaf, LeafKind, Node, NodeId};
use super::program::{Global, OpCode, Program, Reg};
use glam::Vec3;
use std::fmt::Write;

/// Format a float stably: the shortest text that reads back to the same `f32`, `0` for ±0.
pub(crate) fn fmt_f32(x: f32) -> String {
    if x == 0.0 { "0".into() } else { format!("{x}") }
}

/// Format a register value: a scalar when all lanes are equal.
pub(crate) fn fmt_vec3(v: Vec3) -> String {
    if v.x == v.y && v.y == v.z {
        fmt_f32(v.x)
    } else {
        format!("({}, {}, {})", fmt_f32(v.x), fmt_f32(v.y), fmt_f32(v.z))
    }
}

/// An operand: the literal for a constant register, else `rN`.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) fn operand(p: &Program, r: Reg) -> String {
    match p.constant(r) {
        Some(v) => fmt_vec3(v),
        None => format!("r{}", r.0),
    }
}

fn global_name(i: u32) -> &'static str {
    [
        Global::P,
        Global::N,
        Global::T,
        Global::I,
        Global::U,
        Global::V,
    ]
    .get(i as usize)
    .map_or("?", |g| g.name())
}

/// The text of one op (without the destination).
pub(crate) fn op_text(ir: &MaterialIr, i: usize) -> String {
    let p = &ir.program;
    let op = &p.ops[i];
    let args: Vec<String> = op.operands().map(|r| operand(p, r)).collect();
    match op.code {
        OpCode::Const => fmt_vec3(Vec3::from_array(op.imm)),
        OpCode::Input => {
            let k = op.args[0] as usize;
            let name = ir.inputs.get(k).map_or("?", |s| s.name.as_str());
            format!("input ${k} ({name})")
        }
        OpCode::ViewMu => format!("view_mu f{}", op.args[0]),
        OpCode::Global => format!("global {}", global_name(op.args[0])),
        OpCode::Clamp => format!(
            "clamp {}, {}, {}",
            args[0],
            fmt_f32(op.imm[0]),
            fmt_f32(op.imm[1])
        ),
        OpCode::Splat => format!(
            "splat {}, {}",
            args[0],
            ["r", "g", "b"][op.args[1].min(2) as usize]
        ),
        c => format!("{} {}", c.mnemonic(), args.join(", ")),
    }
}

fn leaf_text(ir: &MaterialIr, leaf: &Leaf) -> String {
    let p = &ir.program;
    let mut s = format!("{} \"{}\"", leaf.kind.name(), leaf.label);
    let extra = match leaf.kind {
        LeafKind::MicrofacetR {
            fresnel, masking, ..
        } => {
            let f = match fresnel {
                super::Fresnel::One => "one",
                super::Fresnel::Schlick { .. } => "schlick",
                super::Fresnel::F82 { .. } => "f82",
                super::Fresnel::Dielectric { .. } => "dielectric",
                super::Fresnel::Conductor { .. } => "conductor",
            };
            format!(" fresnel={f} masking={masking:?}")
        }
        LeafKind::Dielectric {
            mode,
            t_fresnel,
            masking,
            ..
        } => {
            let m = match mode {
                DielectricMode::R => "R",
                DielectricMode::T => "T",
                DielectricMode::Rt => "RT",
            };
            format!(" mode={m} t_fresnel={t_fresnel} masking={masking:?}")
        }
        LeafKind::Ward { variant, .. } | LeafKind::MiaHighlight3 { variant, .. } => {
            format!(" variant={variant:?}")
        }
        LeafKind::SheenCk { masking, .. } => format!(" masking={masking:?}"),
        _ => String::new(),
    };
    s.push_str(&extra);
    for (name, r) in leaf.kind.params() {
        let _ = write!(s, " {name}={}", operand(p, r));
    }
    let _ = write!(
        s,
        " tint={} ttint={} frame=f{}",
        operand(p, leaf.tint),
        operand(p, leaf.ttint),
        leaf.frame
    );
    s
}

/// One line describing node `id`.
pub(crate) fn node_text(ir: &MaterialIr, id: NodeId) -> String {
    let p = &ir.program;
    match &ir.nodes[id.index()] {
        Node::Leaf(l) => format!("leaf {}", leaf_text(ir, l)),
        Node::Emission { radiance } => format!("emission radiance={}", operand(p, *radiance)),
        Node::Transparent { tint } => format!("transparent tint={}", operand(p, *tint)),
        Node::Layer { top, base, mode } => {
            format!("layer[{}] top=#{} base=#{}", mode.name(), top.0, base.0)
        }
        Node::Mix { a, b, m } => format!("mix a=#{} b=#{} m={}", a.0, b.0, operand(p, *m)),
        Node::Add { a, b } => format!("add #{} #{}", a.0, b.0),
        Node::Multiply { f, c } => format!("mul #{} c={}", f.0, operand(p, *c)),
    }
}

/// The IR as text (`--emit ir`).
pub(crate) fn ir_text(ir: &MaterialIr) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "material {} (recipe {})", ir.name, ir.recipe.name());
    let _ = writeln!(s, "inputs:");
    if ir.inputs.is_empty() {
        let _ = writeln!(s, "  (none)");
    }
    for (k, slot) in ir.inputs.iter().enumerate() {
        let _ = writeln!(
            s,
            "  ${k} {} : {} fallback {}",
            slot.name, slot.ty, slot.fallback
        );
    }
    let _ = writeln!(s, "frames:");
    for (k, f) in ir.frames.iter().enumerate() {
        let show =
            |r: Option<Reg>, dflt: &str| r.map_or(dflt.to_string(), |r| operand(&ir.program, r));
        let _ = writeln!(
            s,
            "  f{k} normal={} tangent={} rotation={}",
            show(f.normal, "N"),
            show(f.tangent, "T"),
            show(f.rotation, "0")
        );
    }
    let _ = writeln!(s, "program:");
    let mut any = false;
    for (i, op) in ir.program.ops.iter().enumerate() {
        if op.code == OpCode::Const {
            continue;
        }
        any = true;
        let _ = writeln!(s, "  r{i} = {}", op_text(ir, i));
    }
    if !any {
        let _ = writeln!(s, "  (constants only)");
    }
    let _ = writeln!(s, "nodes:");
    if ir.nodes.is_empty() {
        let _ = writeln!(s, "  (none: the material is black)");
    }
    for i in 0..ir.nodes.len() {
        let _ = writeln!(s, "  #{i} {}", node_text(ir, NodeId(i as u32)));
    }
    let _ = writeln!(s, "lobes: {}", ir.max_static_lobes);
    s
}

/// The flat lobe list as text (`--emit lobes`): each lobe with its symbolic weight, then
/// numeric weights at `μ_o = 1` and `0.5` with the inputs' fallbacks and `albedo`.
pub(crate) fn lobes_text(ir: &MaterialIr, albedo: &dyn AlbedoSource) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "material {} (recipe {})", ir.name, ir.recipe.name());
    let op = |r: Reg| operand(&ir.program, r);
    let sym = algebra::symbolic_weights(ir, &op);
    let flats = [1.0f32, 0.5].map(|mu| (mu, ir.weights(None, mu, albedo)));
    for (id, w) in &sym {
        let leaf = match &ir.nodes[id.index()] {
            Node::Leaf(l) => l,
            _ => continue,
        };
        let _ = writeln!(s, "lobe #{} {} \"{}\"", id.0, leaf.kind.name(), leaf.label);
        let _ = writeln!(s, "  weight = {w}");
        for (mu, flat) in &flats {
            let _ = writeln!(
                s,
                "  at mu_o={}: {}",
                fmt_f32(*mu),
                fmt_vec3(flat.weight_of(*id))
            );
        }
    }
    if sym.is_empty() {
        let _ = writeln!(s, "(no lobes)");
    }
    for (mu, flat) in &flats {
        if flat.emission != Vec3::ZERO || flat.transparency != Vec3::ZERO {
            let _ = writeln!(
                s,
                "at mu_o={}: emission {} transparency {}",
                fmt_f32(*mu),
                fmt_vec3(flat.emission),
                fmt_vec3(flat.transparency)
            );
        }
    }
    s
}
