//! The closure algebra: bottom-up throughput with tint modes and
//! top-down weights, producing the flat form — every lobe with its RGB weight.

use super::MaterialIr;
use super::closure::{Leaf, Node, NodeId, TintMode};
use super::program::lum;
use glam::Vec3;

/// Supplies a leaf's directional albedo `E(μ_o)`, without the leaf's `tint` (the
/// tint modes apply it) but with everything inside the lobe kind (Fresnel colours, ρ,
/// dielectric tints). The interpreter plugs in its tables; tests use constants.
pub trait AlbedoSource {
    /// `E(μ_o)` of `leaf` with its parameters read from `regs`.
    fn albedo(&self, leaf: &Leaf, regs: &[Vec3], mu_o: f32) -> Vec3;
}

impl<F: Fn(&Leaf, &[Vec3], f32) -> Vec3> AlbedoSource for F {
    fn albedo(&self, leaf: &Leaf, regs: &[Vec3], mu_o: f32) -> Vec3 {
        self(leaf, regs, mu_o)
    }
}

/// A table-free albedo estimate for tests of the algebra: diffuse kinds return their albedo ρ; microfacet
/// reflection its Fresnel term evaluated at `μ_o` (the smooth-surface limit); a dielectric
/// in `R` mode `F(μ_o, η) · T_r`; Ward its ρ_s; sheens 0.1·(1 − μ_o) + 0.05 (a rough
/// stand-in of the interpreter's tabulated values). Exact for smooth dielectrics and Lambert.
#[derive(Debug, Clone, Copy, Default)]
#[cfg(any(test, feature = "testkit"))]
pub struct SimpleAlbedo;

#[cfg(any(test, feature = "testkit"))]
impl AlbedoSource for SimpleAlbedo {
    fn albedo(&self, leaf: &Leaf, regs: &[Vec3], mu_o: f32) -> Vec3 {
        use super::Fresnel;
        use super::closure::LeafKind;
        use super::program::{fresnel_conductor, fresnel_dielectric};
        let r = |reg: super::Reg| regs.get(reg.index()).copied().unwrap_or(Vec3::ZERO);
        let mu = mu_o.clamp(0.0, 1.0);
        match leaf.kind {
            LeafKind::Lambert { albedo }
            | LeafKind::Translucent { albedo }
            | LeafKind::SubsurfaceProxy { albedo }
            | LeafKind::OrenNayarQ { albedo, .. }
            | LeafKind::OrenNayarE { albedo, .. }
            | LeafKind::Burley { albedo, .. } => r(albedo),
            LeafKind::MiaDiffuse { albedo, .. } => r(albedo) * (95.0 / 96.0),
            LeafKind::MicrofacetR { fresnel, .. } => match fresnel {
                Fresnel::One => Vec3::ONE,
                Fresnel::Schlick { f0, f90, q } | Fresnel::F82 { f0, f90, q, .. } => {
                    let x = (1.0 - mu).powf(r(q).x.max(0.0));
                    r(f0) + (r(f90) - r(f0)) * x
                }
                Fresnel::Dielectric { eta } => {
                    let e = r(eta);
                    Vec3::new(
                        fresnel_dielectric(mu, e.x),
                        fresnel_dielectric(mu, e.y),
                        fresnel_dielectric(mu, e.z),
                    )
                }
                Fresnel::Conductor { eta, kappa } => {
                    let (e, k) = (r(eta), r(kappa));
                    Vec3::new(
                        fresnel_conductor(mu, e.x, k.x),
                        fresnel_conductor(mu, e.y, k.y),
                        fresnel_conductor(mu, e.z, k.z),
                    )
                }
            },
            LeafKind::Dielectric { eta, refl_tint, .. } => {
                Vec3::splat(fresnel_dielectric(mu, r(eta).x)) * r(refl_tint)
            }
            LeafKind::Ward { rho_s, .. } => r(rho_s),
            LeafKind::MiaHighlight3 { .. } => Vec3::ONE,
            LeafKind::SheenCk { .. } | LeafKind::SheenLtc { .. } => {
                Vec3::splat(0.1 * (1.0 - mu) + 0.05)
            }
        }
    }
}

/// A constant albedo for every leaf (tests).
#[derive(Debug, Clone, Copy)]
#[cfg(any(test, feature = "testkit"))]
pub struct ConstAlbedo(pub Vec3);

#[cfg(any(test, feature = "testkit"))]
impl AlbedoSource for ConstAlbedo {
    fn albedo(&self, _leaf: &Leaf, _regs: &[Vec3], _mu_o: f32) -> Vec3 {
        self.0
    }
}

/// One lobe of the flat form.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlatLobe {
    /// The leaf node.
    pub node: NodeId,
    /// Its weight `w_k` (includes the leaf's tint), summed over all paths.
    pub weight: Vec3,
}

/// The flat form of a material for one point and view.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Flat {
    /// Every BSDF leaf reachable with a non-zero path weight, in node order.
    pub lobes: Vec<FlatLobe>,
    /// Accumulated emission `e`.
    pub emission: Vec3,
    /// Accumulated straight-through transparency `τ`.
    pub transparency: Vec3,
    /// Throughput of the whole closure (root), inherited mode `Rgb`.
    pub throughput: Vec3,
}

impl Flat {
    /// The weight of the lobe at `node`, or zero.
    pub fn weight_of(&self, node: NodeId) -> Vec3 {
        self.lobes
            .iter()
            .find(|l| l.node == node)
            .map_or(Vec3::ZERO, |l| l.weight)
    }
}

fn sat(v: Vec3) -> Vec3 {
    v.clamp(Vec3::ZERO, Vec3::ONE)
}

/// Throughput of a layerable leaf in `mode`, given `E` untinted.
#[inline(always)]
pub fn leaf_throughput(mode: TintMode, tint: Vec3, ttint: Vec3, e: Vec3) -> Vec3 {
    let tr_e = tint * e;
    let t = match mode {
        TintMode::Rgb => ttint * (Vec3::ONE - tr_e),
        TintMode::Gray => ttint * (1.0 - (e.x + e.y + e.z) / 3.0),
        TintMode::Luminance => ttint * (1.0 - lum(tr_e)),
        TintMode::MaxChannel => ttint * (1.0 - tr_e.max_element()).clamp(0.0, 1.0),
    };
    sat(t)
}

/// Throughput of `mix(a, b, m)` from its children's, `m` already saturated.
#[inline(always)]
pub(crate) fn mix_throughput(ta: Vec3, tb: Vec3, m: Vec3) -> Vec3 {
    (Vec3::ONE - m) * ta + m * tb
}

/// Throughput of `add(a, b)` from its children's.
#[inline(always)]
pub fn add_throughput(ta: Vec3, tb: Vec3) -> Vec3 {
    (ta + tb - Vec3::ONE).max(Vec3::ZERO)
}

/// Throughput of `mul(f, c)` from its child's, `c` already clamped at 0.
#[inline(always)]
pub fn mul_throughput(tf: Vec3, c: Vec3) -> Vec3 {
    sat(Vec3::ONE - c * (Vec3::ONE - tf))
}

/// Flatten the closure DAG of `ir` for one point: `regs` is the program's register file,
/// `mu_o` the view cosine per frame, `albedo` supplies `E(μ_o)` of leaves that lie in the
/// top of some layer (the only ones whose albedo matters).
pub fn flatten(ir: &MaterialIr, regs: &[Vec3], mu_o: &[f32], albedo: &dyn AlbedoSource) -> Flat {
    let n = ir.nodes.len();
    let mut flat = Flat {
        throughput: Vec3::ONE,
        ..Flat::default()
    };
    if n == 0 {
        return flat;
    }
    let reg = |r: super::Reg| regs.get(r.index()).copied().unwrap_or(Vec3::ZERO);
    let kappa_zero = |r: super::Reg| ir.program.constant(r) == Some(Vec3::ZERO);

    // Which nodes lie in the top subtree of some layer (parents precede children).
    // The root counts as a top so that `Flat::throughput` is exact.
    let mut in_top = vec![false; n];
    in_top[0] = true;
    for i in 0..n {
        let node = &ir.nodes[i];
        if let Node::Layer { top, .. } = node {
            in_top[top.index()] = true;
        }
        if in_top[i] {
            for c in node.children() {
                in_top[c.index()] = true;
            }
        }
    }

    // Bottom-up throughput per inherited mode (children have larger indices).
    let mut thr = vec![[Vec3::ONE; 4]; n];
    for i in (0..n).rev() {
        let t = match &ir.nodes[i] {
            Node::Leaf(leaf) => {
                // Leaves outside every top are never read; opaque is as good as any value.
                if !in_top[i] || !leaf.kind.is_layerable(kappa_zero) {
                    [Vec3::ZERO; 4]
                } else {
                    let mu = mu_o.get(leaf.frame as usize).copied().unwrap_or(1.0);
                    let e = albedo.albedo(leaf, regs, mu);
                    let (tint, ttint) = (reg(leaf.tint), reg(leaf.ttint));
                    TintMode::ALL.map(|m| leaf_throughput(m, tint, ttint, e))
                }
            }
            Node::Emission { .. } | Node::Transparent { .. } => [Vec3::ONE; 4],
            Node::Layer { top, base, mode } => {
                let tt = thr[top.index()][*mode as usize];
                let tb = thr[base.index()];
                tb.map(|b| tt * b)
            }
            Node::Mix { a, b, m } => {
                let m = sat(reg(*m));
                let (ta, tb) = (thr[a.index()], thr[b.index()]);
                std::array::from_fn(|k| mix_throughput(ta[k], tb[k], m))
            }
            Node::Add { a, b } => {
                let (ta, tb) = (thr[a.index()], thr[b.index()]);
                std::array::from_fn(|k| add_throughput(ta[k], tb[k]))
            }
            Node::Multiply { f, c } => {
                let c = reg(*c).max(Vec3::ZERO);
                let tf = thr[f.index()];
                std::array::from_fn(|k| mul_throughput(tf[k], c))
            }
        };
        thr[i] = t;
    }
    flat.throughput = thr[0][TintMode::Rgb as usize];

    // Top-down weights (parents precede children, so a node's W is complete when reached).
    let mut w = vec![Vec3::ZERO; n];
    w[0] = Vec3::ONE;
    for i in 0..n {
        let wi = w[i];
        if wi == Vec3::ZERO {
            continue;
        }
        match &ir.nodes[i] {
            Node::Leaf(leaf) => flat.lobes.push(FlatLobe {
                node: NodeId(i as u32),
                weight: reg(leaf.tint) * wi,
            }),
            Node::Emission { radiance } => flat.emission += wi * reg(*radiance),
            Node::Transparent { tint } => flat.transparency += wi * reg(*tint),
            Node::Layer { top, base, mode } => {
                w[top.index()] += wi;
                w[base.index()] += wi * thr[top.index()][*mode as usize];
            }
            Node::Mix { a, b, m } => {
                let m = sat(reg(*m));
                w[a.index()] += (Vec3::ONE - m) * wi;
                w[b.index()] += m * wi;
            }
            Node::Add { a, b } => {
                w[a.index()] += wi;
                w[b.index()] += wi;
            }
            Node::Multiply { f, c } => {
                w[f.index()] += reg(*c).max(Vec3::ZERO) * wi;
            }
        }
    }
    flat.lobes.retain(|l| l.weight != Vec3::ZERO);
    flat
}

/// Symbolic weight of every leaf: for each path from the root, the product of its factors
/// (`(1 − m)`, `m`, `c`, `T[mode](#top)` for the throughput of a layer's top), as text.
/// Paths are listed in depth-first order; a leaf reached on several paths shows a sum.
pub(crate) fn symbolic_weights(
    ir: &MaterialIr,
    operand: &dyn Fn(super::Reg) -> String,
) -> Vec<(NodeId, String)> {
    let mut out: Vec<(NodeId, Vec<String>)> = Vec::new();
    if ir.nodes.is_empty() {
        return Vec::new();
    }
    let mut stack: Vec<(NodeId, Vec<String>)> = vec![(NodeId(0), Vec::new())];
    while let Some((id, factors)) = stack.pop() {
        let with = |f: String| {
            let mut v = factors.clone();
            v.push(f);
            v
        };
        match &ir.nodes[id.index()] {
            Node::Leaf(leaf) => {
                let mut f = factors.clone();
                let t = operand(leaf.tint);
                if t != "1" {
                    f.push(t);
                }
                let term = if f.is_empty() {
                    "1".to_string()
                } else {
                    f.join(" ⊙ ")
                };
                match out.iter_mut().find(|(n, _)| *n == id) {
                    Some((_, terms)) => terms.push(term),
                    None => out.push((id, vec![term])),
                }
            }
            Node::Emission { .. } | Node::Transparent { .. } => {}
            Node::Layer { top, base, mode } => {
                // Push base first so that the top is visited first.
                stack.push((*base, with(format!("T[{}](#{})", mode.name(), top.0))));
                stack.push((*top, factors.clone()));
            }
            Node::Mix { a, b, m } => {
                let m = operand(*m);
                stack.push((*b, with(m.clone())));
                stack.push((*a, with(format!("(1 − {m})"))));
            }
            Node::Add { a, b } => {
                stack.push((*b, factors.clone()));
                stack.push((*a, factors.clone()));
            }
            Node::Multiply { f, c } => stack.push((*f, with(operand(*c)))),
        }
    }
    out.sort_by_key(|(n, _)| *n);
    out.into_iter()
        .map(|(n, terms)| (n, terms.join(" + ")))
        .collect()
}
