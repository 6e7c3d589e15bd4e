//! Lobe packs: the scalar [`Prepared::eval`](super::Prepared::eval)'s lobes of one family evaluated together, one
//! lobe per SIMD lane.
//!
//! A whole lobe is the interpreter's instruction. When several
//! surviving lobes of a prepared point belong to one family that has a batched kernel
//! (`Kernel`, the kernels of the batched path), the end of `prepare` puts up to
//! [`PACK_LANES`] of them in one kernel with the lane axis running over lobes instead of
//! points, and `eval` runs that kernel once with the same L in every lane: ref10's three
//! Ward lobes become one instruction, its two GGX dielectrics another. The kernels compute
//! the scalar leaf's formula per lane with polynomial transcendentals, so a pack's sum
//! equals the lobes' own evaluations to relative 1e-5 (the batched path's tolerance;
//! `tests/interp/packs.rs`). [`super::PrepareOptions::pack_lobes`] turns packing off.
//!
//! Four lanes are one SSE register, the baseline x86-64 width; a family with more than four
//! lobes fills several packs. Lobes no kernel covers, and a family's only lobe, are
//! evaluated alone.

use super::record::ActiveLobe;
use crate::interp::lobe::PreparedLobe;
use crate::interp::soa::{Acc, KERNEL_KEYS, Kernel, LaneWeights, Vec3x, kernel_key};
use crate::ir::MAX_LOBES;
use glam::Vec3;

/// Lobes per pack.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(super) const PACK_LANES: usize = 4;

/// Packs per prepared point: a material has at most `MAX_LOBES` lobes, so four packs cover
/// every family that has two to four lobes; further lobes are evaluated alone.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
const MAX_PACKS: usize = 4;

/// Every lobe index, for an unplanned [`EvalPlan`] (every lobe alone).
const ALL_LOBES: [u8; MAX_LOBES] = {
    let mut all = [0u8; MAX_LOBES];
    let mut k = 0;
    while k < MAX_LOBES {
        all[k] = k as u8;
        k += 1;
    }
    all
};

/// Up to [`PACK_LANES`] lobes of one family in one kernel.
#[derive(Debug, Clone, Copy)]
struct LobePack {
    kernel: Kernel<PACK_LANES>,
    /// Lane weights, probabilities and flip signs (0 and 1 in unused lanes).
    lw: LaneWeights<PACK_LANES>,
    /// Each lane's frame (unused lanes repeat lane 0's).
    frame: [u8; PACK_LANES],
}

/// Which lobes run alone and which share packs: a function of the lobes' kernel keys
/// only, so a material whose leaves are all constants computes it once, at compile time,
/// for the case where every leaf survives ([`super::Material`]).
#[derive(Debug, Clone, Copy)]
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(super) struct Grouping {
    /// Indices (into the prepared lobes) of the lobes evaluated alone.
    solo: [u8; MAX_LOBES],
    solo_count: u8,
    /// Each pack's lobe indices (the first `pack_len[p]`).
    packs: [[u8; PACK_LANES]; MAX_PACKS],
    pack_len: [u8; MAX_PACKS],
    pack_count: u8,
}

impl Grouping {
    /// No lobes (what [`Grouping::of_keys`] fills in).
    fn empty() -> Grouping {
        Grouping {
            solo: [0; MAX_LOBES],
            solo_count: 0,
            packs: [[0; PACK_LANES]; MAX_PACKS],
            pack_len: [0; MAX_PACKS],
            pack_count: 0,
        }
    }

    /// Each pack's member lobe indices, in pack order.
    #[cfg_attr(feature = "testkit", visibility::make(pub))]
    fn members(&self) -> impl Iterator<Item = &[u8]> {
        self.packs
            .iter()
            .zip(&self.pack_len)
            .take(usize::from(self.pack_count))
            .map(|(members, &n)| &members[..usize::from(n)])
    }

    /// The lobes of each kernel key, in lobe order, fill packs of up to [`PACK_LANES`];
    /// a key's single remaining lobe, and lobes without a key, run alone.
    #[cfg_attr(feature = "testkit", visibility::make(pub))]
    pub(super) fn of_keys(keys: &[Option<u8>]) -> Grouping {
        // One pass sorts the lobes by key (no pairwise comparisons: this runs per prepare).
        let mut by_key = [[0u8; MAX_LOBES]; KERNEL_KEYS];
        let mut per_key = [0usize; KERNEL_KEYS];
        let mut g = Grouping::empty();
        let mut solo = 0;
        for (k, key) in keys.iter().enumerate().take(MAX_LOBES) {
            match key {
                Some(key) => {
                    let key = usize::from(*key);
                    by_key[key][per_key[key]] = k as u8;
                    per_key[key] += 1;
                }
                None => {
                    g.solo[solo] = k as u8;
                    solo += 1;
                }
            }
        }
        let mut packs = 0;
        for (members, &n) in by_key.iter().zip(&per_key) {
            for chunk in members[..n].chunks(PACK_LANES) {
                if chunk.len() >= 2 && packs < MAX_PACKS {
                    g.packs[packs][..chunk.len()].copy_from_slice(chunk);
                    g.pack_len[packs] = chunk.len() as u8;
                    packs += 1;
                } else {
                    g.solo[solo..solo + chunk.len()].copy_from_slice(chunk);
                    solo += chunk.len();
                }
            }
        }
        g.solo_count = solo as u8;
        g.pack_count = packs as u8;
        g
    }
}

/// What the crate's tests read of a grouping.
#[cfg(feature = "testkit")]
impl Grouping {
    /// The lobes evaluated alone, in plan order.
    pub fn solo_lobes(&self) -> &[u8] {
        &self.solo[..self.solo_count as usize]
    }

    /// The number of packs.
    pub fn pack_count(&self) -> usize {
        usize::from(self.pack_count)
    }
}

/// How [`super::Prepared::eval`] runs the surviving lobes: some alone, the others in packs.
#[derive(Debug, Clone, Copy)]
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(super) struct EvalPlan {
    grouping: Grouping,
    packs: [LobePack; MAX_PACKS],
    /// The plan describes the current lobes; when false every lobe is evaluated alone.
    valid: bool,
    /// The [`super::form::UniformPlan::stamp`] of the material whose leaves, all of
    /// them, in leaf order and none flipped, the packs' view-independent terms belong to
    /// (see [`EvalPlan::build_stamped`]); 0 when they may belong to anything else.
    stamp: u64,
}

/// What the crate's tests read of a plan.
#[cfg(feature = "testkit")]
impl EvalPlan {
    /// The plan's grouping of the lobes.
    pub fn grouping(&self) -> &Grouping {
        &self.grouping
    }

    /// The view direction in lane `k` of pack `p`, when that pack runs the Ward kernel.
    pub fn pack_ward_view(&self, p: usize, k: usize) -> Option<Vec3> {
        match &self.packs[p].kernel {
            Kernel::Ward(x) => Some(x.v.get(k)),
            _ => None,
        }
    }

    /// Pack `p`'s weight and selection probability in lane `k`.
    pub fn pack_lane(&self, p: usize, k: usize) -> (Vec3, f32) {
        let lw = &self.packs[p].lw;
        (lw.w.get(k), lw.p[k])
    }
}

impl EvalPlan {
    /// No plan (every lobe alone).
    #[cfg_attr(feature = "testkit", visibility::make(pub))]
    pub(super) fn empty() -> EvalPlan {
        let pack = LobePack {
            kernel: Kernel::Scalar,
            lw: LaneWeights {
                w: Vec3x::zero(),
                p: [0.0; PACK_LANES],
                sign: [1.0; PACK_LANES],
            },
            frame: [0; PACK_LANES],
        };
        EvalPlan {
            grouping: Grouping::empty(),
            packs: [pack; MAX_PACKS],
            valid: false,
            stamp: 0,
        }
    }

    /// Forgets the plan: `eval` runs every lobe alone until [`EvalPlan::build`].
    pub(super) fn clear(&mut self) {
        self.valid = false;
    }

    /// Plans `lobes` (weights and probabilities final) from their kernel keys.
    #[cfg_attr(feature = "testkit", visibility::make(pub))]
    pub(super) fn build(&mut self, lobes: &[ActiveLobe]) {
        let mut keys = [None; MAX_LOBES];
        for (key, a) in keys.iter_mut().zip(lobes) {
            *key = kernel_key(&a.lobe.state);
        }
        self.build_from(&Grouping::of_keys(&keys[..lobes.len()]), lobes);
    }

    /// Plans `lobes` with `grouping`, which must be [`Grouping::of_keys`] of their keys.
    pub(super) fn build_from(&mut self, grouping: &Grouping, lobes: &[ActiveLobe]) {
        self.stamp = 0;
        self.grouping = *grouping;
        for (pack, members) in self.packs.iter_mut().zip(grouping.members()) {
            pack.fill(lobes, members);
        }
        self.valid = true;
    }

    /// [`EvalPlan::build_from`] for the lobes of the fused prepare of the uniform material
    /// with `stamp` when every leaf survived (lobe `k` is leaf `k`, none flipped), and
    /// `grouping` is the material's grouping. The lobes' view-independent terms are then
    /// the same at every point, so when the packs already hold them (the previous plan was
    /// built here with the same stamp) only the view, weight and probability terms are
    /// written ([`Kernel::refresh_lanes`]); the packs end with the same bits either way.
    #[inline(always)]
    pub(super) fn build_stamped(&mut self, stamp: u64, grouping: &Grouping, lobes: &[ActiveLobe]) {
        if self.stamp != stamp {
            self.build_from(grouping, lobes);
            self.stamp = stamp;
            return;
        }
        for (pack, members) in self.packs.iter_mut().zip(grouping.members()) {
            pack.refresh(lobes, members);
        }
        self.valid = true;
    }

    /// The lobes `eval` runs alone, of `count` surviving lobes.
    #[inline(always)]
    pub(super) fn solo(&self, count: usize) -> &[u8] {
        if self.valid {
            &self.grouping.solo[..self.grouping.solo_count as usize]
        } else {
            &ALL_LOBES[..count]
        }
    }

    /// The packs' weighted sum `Σ w f·μ_i` and `Σ p pdf` at local direction `l` (every
    /// lobe in one frame); the density is 0 unless `PDF`.
    #[inline(always)]
    #[cfg_attr(feature = "testkit", visibility::make(pub))]
    pub(super) fn eval_one_frame<const PDF: bool>(&self, l: Vec3) -> (Vec3, f32) {
        let l = Vec3x {
            x: [l.x; PACK_LANES],
            y: [l.y; PACK_LANES],
            z: [l.z; PACK_LANES],
        };
        self.run::<PDF>(|_| l)
    }

    /// As [`EvalPlan::eval_one_frame`] with L given per frame (`local[f]`).
    #[inline(always)]
    pub(super) fn eval_frames<const PDF: bool>(&self, local: &[Vec3; MAX_LOBES]) -> (Vec3, f32) {
        self.run::<PDF>(|p: &LobePack| {
            let mut l = Vec3x::zero();
            for (k, &f) in p.frame.iter().enumerate() {
                l.set(k, local[f as usize]);
            }
            l
        })
    }

    #[inline(always)]
    fn run<const PDF: bool>(&self, l: impl Fn(&LobePack) -> Vec3x<PACK_LANES>) -> (Vec3, f32) {
        let count = self.grouping.pack_count as usize;
        if !self.valid || count == 0 {
            return (Vec3::ZERO, 0.0);
        }
        let mut acc = Acc {
            f: Vec3x::zero(),
            pdf: [0.0; PACK_LANES],
        };
        for p in &self.packs[..count] {
            // Packs only hold kernels (`LobePack::fill`), never `Kernel::Scalar`.
            p.kernel.accumulate::<PDF>(&l(p), &p.lw, &mut acc);
        }
        let sum = |x: &[f32; PACK_LANES]| (x[0] + x[1]) + (x[2] + x[3]);
        (
            Vec3::new(sum(&acc.f.x), sum(&acc.f.y), sum(&acc.f.z)),
            sum(&acc.pdf),
        )
    }
}

impl LobePack {
    /// Loads `members` (indices into `lobes`, two to [`PACK_LANES`] lobes of one kernel
    /// key) into the lanes.
    fn fill(&mut self, lobes: &[ActiveLobe], members: &[u8]) {
        for k in 0..PACK_LANES {
            let (w, p, sign, frame) = match members.get(k) {
                Some(&m) => {
                    let a = &lobes[m as usize];
                    let sign = if a.lobe.is_flipped() { -1.0 } else { 1.0 };
                    (a.weight, a.prob, sign, a.frame)
                }
                None => (Vec3::ZERO, 0.0, 1.0, self.frame[0]),
            };
            self.lw.w.set(k, w);
            self.lw.p[k] = p;
            self.lw.sign[k] = sign;
            self.frame[k] = frame;
        }
        debug_assert!(members.len() >= 2, "a pack has two lobes or more");
        debug_assert!(
            members.iter().all(|&m| {
                let key = kernel_key(&lobes[m as usize].lobe.state);
                key.is_some() && key == kernel_key(&lobes[members[0] as usize].lobe.state)
            }),
            "a pack's lobes share one kernel key"
        );
        // Unused lanes take the last lobe's terms (with weight and probability 0) and a
        // view straight up, which refreshes leave as it is.
        let last = members.len() - 1;
        let lanes: [&PreparedLobe; PACK_LANES] =
            std::array::from_fn(|k| &lobes[members[k.min(last)] as usize].lobe);
        self.kernel.fill_lanes(|k| lanes[k], &self.lw);
        self.kernel.park_lanes(members.len());
    }

    /// [`LobePack::fill`] of the same lobes, unflipped, as the fill before: the lanes'
    /// signs and frames, the kernel's view-independent terms and the unused lanes are
    /// already right, so only the members' view, weight and probability terms are written.
    #[inline(always)]
    fn refresh(&mut self, lobes: &[ActiveLobe], members: &[u8]) {
        let mut lanes: [&PreparedLobe; PACK_LANES] = [&lobes[members[0] as usize].lobe; PACK_LANES];
        for (k, &m) in members.iter().enumerate() {
            let a = &lobes[m as usize];
            debug_assert!(!a.lobe.is_flipped() && self.frame[k] == a.frame);
            self.lw.w.set(k, a.weight);
            self.lw.p[k] = a.prob;
            lanes[k] = &a.lobe;
        }
        self.kernel
            .refresh_lanes(|k| lanes[k], members.len(), &self.lw);
    }
}
