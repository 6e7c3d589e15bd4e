//! Closure-algebra properties (closures.md §2.5, §5.6): random trees against an independent
//! recursive implementation of the (response, throughput) table of §2.2, and the nine listed
//! properties.

use glam::Vec3;
use proptest::prelude::*;
use vstructc::ir::algebra::{flatten, leaf_throughput};
use vstructc::ir::passes::topo_from_root;
use vstructc::ir::{
    FrameSlot, Fresnel, IrBuilder, Leaf, LeafKind, Masking, MaterialIr, Node, NodeId,
    ProgramBuilder, RecipeId, TintMode,
};

/// A tree description. Leaves carry their tint, their (pretend) untinted albedo E, and a
/// pretend response value f_k|μ_i| for one fixed L.
#[derive(Debug, Clone)]
enum T {
    Leaf {
        layerable: bool,
        tint: Vec3,
        e: Vec3,
        resp: Vec3,
    },
    Layer(Box<T>, Box<T>, TintMode),
    Mix(Box<T>, Box<T>, Vec3),
    Add(Box<T>, Box<T>),
    Mul(Box<T>, Vec3),
}

fn unit3() -> impl Strategy<Value = Vec3> {
    (0.0f32..=1.0, 0.0f32..=1.0, 0.0f32..=1.0).prop_map(|(a, b, c)| Vec3::new(a, b, c))
}

fn mode() -> impl Strategy<Value = TintMode> {
    prop_oneof![
        Just(TintMode::Rgb),
        Just(TintMode::Gray),
        Just(TintMode::Luminance),
        Just(TintMode::MaxChannel)
    ]
}

fn leaf() -> impl Strategy<Value = T> {
    (any::<bool>(), unit3(), unit3(), unit3()).prop_map(|(layerable, tint, e, resp)| T::Leaf {
        layerable,
        tint,
        e,
        resp,
    })
}

fn tree() -> impl Strategy<Value = T> {
    leaf().prop_recursive(5, 24, 2, |inner| {
        prop_oneof![
            (inner.clone(), inner.clone(), mode()).prop_map(|(a, b, m)| T::Layer(
                Box::new(a),
                Box::new(b),
                m
            )),
            (inner.clone(), inner.clone(), unit3()).prop_map(|(a, b, m)| T::Mix(
                Box::new(a),
                Box::new(b),
                m
            )),
            (inner.clone(), inner.clone()).prop_map(|(a, b)| T::Add(Box::new(a), Box::new(b))),
            (inner, unit3()).prop_map(|(a, c)| T::Mul(Box::new(a), c)),
        ]
    })
}

/// Per-leaf data addressed by the leaf label.
struct Built {
    ir: MaterialIr,
    e: Vec<Vec3>,
    resp: Vec<Vec3>,
}

/// Build a raw IR (no builder simplification) from a tree.
fn build(t: &T) -> Built {
    let mut p = ProgramBuilder::new();
    let mut nodes = Vec::new();
    let mut e = Vec::new();
    let mut resp = Vec::new();
    fn go(
        t: &T,
        p: &mut ProgramBuilder,
        nodes: &mut Vec<Node>,
        e: &mut Vec<Vec3>,
        resp: &mut Vec<Vec3>,
    ) -> NodeId {
        let n = match t {
            T::Leaf {
                layerable,
                tint,
                e: ee,
                resp: rr,
            } => {
                let one = p.constf(1.0);
                let kind = if *layerable {
                    LeafKind::MicrofacetR {
                        alpha_x: one,
                        alpha_y: one,
                        fresnel: Fresnel::One,
                        masking: Masking::HeightCorrelated,
                        comp: one,
                    }
                } else {
                    LeafKind::Lambert { albedo: one }
                };
                let label = e.len().to_string();
                e.push(*ee);
                resp.push(*rr);
                Node::Leaf(Leaf {
                    kind,
                    tint: p.constant3(*tint),
                    ttint: one,
                    frame: 0,
                    label,
                })
            }
            T::Layer(a, b, m) => {
                let a = go(a, p, nodes, e, resp);
                let b = go(b, p, nodes, e, resp);
                Node::Layer {
                    top: a,
                    base: b,
                    mode: *m,
                }
            }
            T::Mix(a, b, m) => {
                let a = go(a, p, nodes, e, resp);
                let b = go(b, p, nodes, e, resp);
                Node::Mix {
                    a,
                    b,
                    m: p.constant3(*m),
                }
            }
            T::Add(a, b) => {
                let a = go(a, p, nodes, e, resp);
                let b = go(b, p, nodes, e, resp);
                Node::Add { a, b }
            }
            T::Mul(a, c) => {
                let a = go(a, p, nodes, e, resp);
                Node::Multiply {
                    f: a,
                    c: p.constant3(*c),
                }
            }
        };
        nodes.push(n);
        NodeId(nodes.len() as u32 - 1)
    }
    let root = go(t, &mut p, &mut nodes, &mut e, &mut resp);
    let ir = MaterialIr {
        name: "t".into(),
        recipe: RecipeId::Custom,
        inputs: vec![],
        program: p.finish(),
        nodes: topo_from_root(&nodes, root),
        frames: vec![FrameSlot::default()],
        max_static_lobes: 0,
    };
    Built { ir, e, resp }
}

/// Independent recursive (response, throughput) of §2.2 for inherited `mode`.
fn rt(t: &T, mode: TintMode) -> (Vec3, Vec3) {
    match t {
        T::Leaf {
            layerable,
            tint,
            e,
            resp,
        } => {
            let thr = if *layerable {
                leaf_throughput(mode, *tint, Vec3::ONE, *e)
            } else {
                Vec3::ZERO
            };
            (*tint * *resp, thr)
        }
        T::Layer(a, b, m) => {
            let (ra, ta) = rt(a, *m);
            let (rb, tb) = rt(b, mode);
            (ra + ta * rb, ta * tb)
        }
        T::Mix(a, b, m) => {
            let (ra, ta) = rt(a, mode);
            let (rb, tb) = rt(b, mode);
            let m = m.clamp(Vec3::ZERO, Vec3::ONE);
            ((1.0 - m) * ra + m * rb, (1.0 - m) * ta + m * tb)
        }
        T::Add(a, b) => {
            let (ra, ta) = rt(a, mode);
            let (rb, tb) = rt(b, mode);
            (ra + rb, (ta + tb - Vec3::ONE).max(Vec3::ZERO))
        }
        T::Mul(a, c) => {
            let (ra, ta) = rt(a, mode);
            (
                *c * ra,
                (Vec3::ONE - *c * (Vec3::ONE - ta)).clamp(Vec3::ZERO, Vec3::ONE),
            )
        }
    }
}

/// Flat-form response Σ w_k ⊙ resp_k and root throughput.
fn flat_rt(b: &Built) -> (Vec3, Vec3, Vec<(String, Vec3)>) {
    let regs = b.ir.run_program(None, 1.0);
    let e = b.e.clone();
    let albedo = move |leaf: &Leaf, _: &[Vec3], _: f32| e[leaf.label.parse::<usize>().unwrap()];
    let flat = flatten(&b.ir, &regs, &[1.0], &albedo);
    let mut r = Vec3::ZERO;
    let mut ws = Vec::new();
    for l in &flat.lobes {
        let Node::Leaf(leaf) = &b.ir.nodes[l.node.index()] else {
            panic!()
        };
        let k: usize = leaf.label.parse().unwrap();
        r += l.weight * b.resp[k];
        ws.push((leaf.label.clone(), l.weight));
    }
    ws.sort_by(|a, b| a.0.cmp(&b.0));
    (r, flat.throughput, ws)
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() <= 1e-5 * (1.0 + a.abs().max_element().max(b.abs().max_element()))
}

fn lf(layerable: bool, tint: Vec3, e: Vec3, resp: Vec3) -> T {
    T::Leaf {
        layerable,
        tint,
        e,
        resp,
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Top-down weights equal the bottom-up response; throughput equals the recursive one
    /// and lies in [0, 1] (§5.6).
    #[test]
    fn top_down_equals_bottom_up(t in tree()) {
        let b = build(&t);
        let (r, thr, _) = flat_rt(&b);
        let (r0, t0) = rt(&t, TintMode::Rgb);
        prop_assert!(close(r, r0), "{r} vs {r0}");
        prop_assert!(close(thr, t0), "{thr} vs {t0}");
        prop_assert!(thr.min_element() >= 0.0 && thr.max_element() <= 1.0);
    }

    /// §2.5.1 layer associativity in response and throughput, equal modes.
    #[test]
    fn layer_associativity(a in leaf(), bb in leaf(), c in tree(), m in mode()) {
        let left = T::Layer(Box::new(a.clone()), Box::new(T::Layer(Box::new(bb.clone()), Box::new(c.clone()), m)), m);
        let right = T::Layer(Box::new(T::Layer(Box::new(a), Box::new(bb), m)), Box::new(c), m);
        let (rl, tl, wl) = flat_rt(&build(&left));
        let (rr, tr, wr) = flat_rt(&build(&right));
        prop_assert!(close(rl, rr) && close(tl, tr));
        prop_assert_eq!(wl.len(), wr.len());
        for ((na, wa), (nb, wb)) in wl.iter().zip(&wr) {
            prop_assert_eq!(na, nb);
            prop_assert!(close(*wa, *wb));
        }
    }

    /// §2.5.2 mix(a, a, m) = a.
    #[test]
    fn mix_of_equal_is_identity(a in tree(), m in unit3()) {
        let (ra, ta, _) = flat_rt(&build(&a));
        let (rm, tm, _) = flat_rt(&build(&T::Mix(Box::new(a.clone()), Box::new(a), m)));
        prop_assert!(close(ra, rm) && close(ta, tm));
    }

    /// §2.5.8 mix ≡ add(mul(a, 1 − m), mul(b, m)).
    #[test]
    fn mix_is_add_of_multiplies(a in tree(), bb in tree(), m in unit3()) {
        let mix = T::Mix(Box::new(a.clone()), Box::new(bb.clone()), m);
        let add = T::Add(Box::new(T::Mul(Box::new(a), Vec3::ONE - m)), Box::new(T::Mul(Box::new(bb), m)));
        let (r1, t1, _) = flat_rt(&build(&mix));
        let (r2, t2, _) = flat_rt(&build(&add));
        prop_assert!(close(r1, r2) && close(t1, t2), "{t1} {t2}");
    }

    /// §2.5.4 add throughput.
    #[test]
    fn add_throughput(a in leaf(), bb in leaf()) {
        let (_, ta) = rt(&a, TintMode::Rgb);
        let (_, tb) = rt(&bb, TintMode::Rgb);
        let (_, t, _) = flat_rt(&build(&T::Add(Box::new(a), Box::new(bb))));
        prop_assert!(close(t, (ta + tb - Vec3::ONE).max(Vec3::ZERO)));
    }

    /// §2.5.5 a top with zero albedo: layer(top, base) = top + base.
    #[test]
    fn zero_albedo_top_is_add(tint in unit3(), resp in unit3(), base in tree(), m in mode()) {
        let top = lf(true, tint, Vec3::ZERO, resp);
        let (r1, _, w1) = flat_rt(&build(&T::Layer(Box::new(top.clone()), Box::new(base.clone()), m)));
        let (r2, _, w2) = flat_rt(&build(&T::Add(Box::new(top), Box::new(base))));
        prop_assert!(close(r1, r2));
        prop_assert_eq!(w1.len(), w2.len());
    }

    /// §2.5.6 an opaque top leaves the base weight 0.
    #[test]
    fn opaque_top_hides_base(tint in unit3(), resp in unit3(), base in tree(), m in mode()) {
        let top = lf(false, tint, Vec3::ONE, resp);
        let (_, _, w) = flat_rt(&build(&T::Layer(Box::new(top), Box::new(base), m)));
        prop_assert_eq!(w.len() as u32, u32::from(tint != Vec3::ZERO), "only the top keeps a weight: {:?}", w);
    }

    /// §2.5.7 coverage: layer(multiply(top, c), base) = c·top + (1 − c ⊙ E_top) ⊙ base.
    #[test]
    fn coverage(c in unit3(), e in unit3(), resp in unit3(), base_resp in unit3()) {
        let top = lf(true, Vec3::ONE, e, resp);
        let base = lf(false, Vec3::ONE, Vec3::ONE, base_resp);
        let (r, _, _) = flat_rt(&build(&T::Layer(Box::new(T::Mul(Box::new(top), c)), Box::new(base), TintMode::Rgb)));
        prop_assert!(close(r, c * resp + (Vec3::ONE - c * e) * base_resp));
    }
}

/// §2.5.3 multiply by 0 contributes nothing, and the builder removes the lobe.
#[test]
fn multiply_by_zero_removes_the_lobe() {
    let t = T::Add(
        Box::new(T::Mul(
            Box::new(lf(false, Vec3::ONE, Vec3::ONE, Vec3::ONE)),
            Vec3::ZERO,
        )),
        Box::new(lf(false, Vec3::splat(0.5), Vec3::ONE, Vec3::ONE)),
    );
    let (_, _, w) = flat_rt(&build(&t));
    assert_eq!(w.len(), 1, "the multiplied lobe has no weight");

    let mut b = IrBuilder::new();
    let a = b.prog.constf(0.5);
    let l = b.simple_leaf(LeafKind::Lambert { albedo: a }, "d");
    let zero = b.prog.constf(0.0);
    let m = b.mul(l, zero);
    assert!(m.is_none());
    let ir = b.finish("z", RecipeId::Custom, m).unwrap();
    assert_eq!(ir.lobe_count(), 0);
}

/// §2.5.9 a shared subtree reached on two paths is one lobe with the summed weight.
#[test]
fn shared_leaf_sums_weights() {
    let mut b = IrBuilder::new();
    let a = b.prog.constf(0.5);
    let l = b.simple_leaf(LeafKind::Lambert { albedo: a }, "d");
    let c1 = b.prog.constf(0.25);
    let c2 = b.prog.constf(0.5);
    let m1 = b.mul(l, c1);
    let m2 = b.mul(l, c2);
    let root = b.add(m1, m2);
    let ir = b.finish("s", RecipeId::Custom, root).unwrap();
    assert_eq!(ir.lobe_count(), 1);
    let f = ir.weights(None, 1.0, &vstructc::ir::SimpleAlbedo);
    assert_eq!(f.lobes.len(), 1);
    assert_eq!(f.lobes[0].weight, Vec3::splat(0.75));
}

/// The tint modes of §2.4 on one value.
#[test]
fn tint_modes() {
    let tint = Vec3::new(1.0, 0.5, 0.0);
    let e = Vec3::new(0.5, 0.5, 0.5);
    let tt = Vec3::ONE;
    assert_eq!(
        leaf_throughput(TintMode::Rgb, tint, tt, e),
        Vec3::new(0.5, 0.75, 1.0)
    );
    assert_eq!(
        leaf_throughput(TintMode::Gray, tint, tt, e),
        Vec3::splat(0.5)
    );
    let l = 1.0 - (0.2126 * 0.5 + 0.7152 * 0.25);
    assert!(
        (leaf_throughput(TintMode::Luminance, tint, tt, e) - Vec3::splat(l))
            .abs()
            .max_element()
            < 1e-6
    );
    assert_eq!(
        leaf_throughput(TintMode::MaxChannel, tint, tt, e),
        Vec3::splat(0.5)
    );
    // Transmission tint filters everything below.
    let coat = Vec3::new(1.0, 0.5, 0.25);
    assert_eq!(leaf_throughput(TintMode::Gray, tint, coat, e), coat * 0.5);
}

/// MaterialIr::MAX_LOBES: 17 lobes is LW010.
#[test]
fn too_many_lobes_is_lw010() {
    let mut b = IrBuilder::new();
    let mut root = None;
    for k in 0..17 {
        let a = b.prog.constf(0.01 * (k + 1) as f32);
        let l = b.simple_leaf(LeafKind::Lambert { albedo: a }, "d");
        root = b.add(root, l);
    }
    let err = b.finish("many", RecipeId::Custom, root).unwrap_err();
    assert_eq!(err.code, "LW010");
    let mut b = IrBuilder::new();
    let mut root = None;
    for k in 0..16 {
        let a = b.prog.constf(0.01 * (k + 1) as f32);
        let l = b.simple_leaf(LeafKind::Lambert { albedo: a }, "d");
        root = b.add(root, l);
    }
    assert_eq!(
        b.finish("ok", RecipeId::Custom, root)
            .unwrap()
            .max_static_lobes,
        16
    );
}
