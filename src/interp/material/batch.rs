//! Batched evaluation over `W` shading points.
//!
//! A material's IR fixes the lobe structure; only parameter values differ between points. A
//! [`PreparedBatch`] therefore has one *slot* per leaf that is live in at least one lane,
//! in leaf order, and each slot stores its per-lane state side by side (structure of arrays
//! over lanes). A lobe dropped in some lanes is masked there (weight 0), not removed; a leaf
//! dropped in every lane has no slot.
//!
//! `eval` is lobe-major: L is transformed into each frame once for all lanes, then each
//! slot runs its family's SoA kernel ([`crate::interp::soa`]: Lambert, Oren–Nayar, GGX conductor,
//! GGX dielectric R, Ward, both sheens) over all `W` lanes in straight-line code the
//! compiler vectorises. Slots whose lanes mix families or use a configuration no kernel
//! covers (transmission, Kulla–Conty compensation, mia leaves, ...) run the scalar leaf per
//! lane. Per lane the result equals [`Prepared::eval`] to relative 1e-5 (the kernels use
//! polynomial `exp`/`pow`/`acos`; everything else is the scalar formula in the same order).

use super::prepared::Prepared;
use super::record::{Eval, ShadingPoint};
use crate::interp::frame::Frame;
use crate::interp::math::Rgb;
use crate::interp::simd::{Level, call_widest, widest_versions};
use crate::interp::soa::{Acc, Kernel, LaneWeights, Vec3x};
use crate::ir::MAX_LOBES;
use glam::{Vec2, Vec3};

/// `W` shading points. Every lane is a real point; pad a partial batch by repeating a
/// point.
#[derive(Debug, Clone, Copy)]
pub struct ShadingBatch<'a, const W: usize> {
    /// Shading normals.
    pub n: [Vec3; W],
    /// Surface tangents.
    pub t: [Vec3; W],
    /// Directions toward the viewer.
    pub v: [Vec3; W],
    /// Packed external inputs per lane (see
    /// [`Material::input_layout`](super::Material::input_layout)).
    pub inputs: [&'a [f32]; W],
    /// Surface positions.
    pub p: [Vec3; W],
    /// Surface parameters.
    pub uv: [Vec2; W],
}

impl<'a, const W: usize> ShadingBatch<'a, W> {
    /// A batch of points without inputs, `P = 0`, `uv = 0`.
    pub fn new(n: [Vec3; W], t: [Vec3; W], v: [Vec3; W]) -> ShadingBatch<'static, W> {
        ShadingBatch {
            n,
            t,
            v,
            inputs: [&[]; W],
            p: [Vec3::ZERO; W],
            uv: [Vec2::ZERO; W],
        }
    }

    /// Sets lane `k` to point `p`.
    pub fn set_lane(&mut self, k: usize, p: &ShadingPoint<'a>) {
        self.n[k] = p.n;
        self.t[k] = p.t;
        self.v[k] = p.v;
        self.inputs[k] = p.inputs;
        self.p[k] = p.p;
        self.uv[k] = p.uv;
    }

    /// Lane `k` as a scalar point.
    pub fn lane(&self, k: usize) -> ShadingPoint<'a> {
        ShadingPoint {
            n: self.n[k],
            t: self.t[k],
            v: self.v[k],
            inputs: self.inputs[k],
            p: self.p[k],
            uv: self.uv[k],
        }
    }
}

/// One leaf across the lanes.
#[derive(Debug, Clone, Copy)]
pub(super) struct Slot<const W: usize> {
    /// Where lane `k`'s lobe is in that lane's [`Prepared::lobes`] (meaningful where live).
    pub(super) index: [u8; W],
    /// Weights and probabilities (0 where not live) and flip signs, SoA.
    pub(super) lw: LaneWeights<W>,
    /// Lane is live (the lobe survived prepare there).
    pub(super) live: [bool; W],
    /// Frame slot (the same for every lane: it is the leaf's).
    pub(super) frame: u8,
    /// The family's SoA kernel ([`Kernel::Scalar`]: lane by lane).
    pub(super) kernel: Kernel<W>,
}

/// `W` frames, structure of arrays.
#[derive(Debug, Clone, Copy)]
pub(super) struct FrameX<const W: usize> {
    pub(super) x: Vec3x<W>,
    pub(super) y: Vec3x<W>,
    pub(super) z: Vec3x<W>,
}

impl<const W: usize> FrameX<W> {
    fn identity() -> Self {
        let f = Frame::default();
        let mut out = FrameX {
            x: Vec3x::zero(),
            y: Vec3x::zero(),
            z: Vec3x::zero(),
        };
        for k in 0..W {
            out.set(k, &f);
        }
        out
    }

    #[inline(always)]
    pub(super) fn set(&mut self, k: usize, f: &Frame) {
        self.x.set(k, f.x);
        self.y.set(k, f.y);
        self.z.set(k, f.z);
    }

    /// World → local for every lane (the same arithmetic as [`Frame::to_local`]).
    #[allow(clippy::needless_range_loop)] // index loops over lanes vectorise best
    #[inline(always)]
    fn local(&self, w: &Vec3x<W>) -> Vec3x<W> {
        let mut out = Vec3x::zero();
        let dot = |a: &Vec3x<W>, k: usize| w.x[k] * a.x[k] + w.y[k] * a.y[k] + w.z[k] * a.z[k];
        for k in 0..W {
            out.x[k] = dot(&self.x, k);
            out.y[k] = dot(&self.y, k);
            out.z[k] = dot(&self.z, k);
        }
        out
    }
}

/// A material prepared for `W` points.
#[derive(Debug, Clone)]
pub struct PreparedBatch<const W: usize> {
    pub(super) slots: [Slot<W>; MAX_LOBES],
    pub(super) count: usize,
    pub(super) frames: [FrameX<W>; MAX_LOBES],
    pub(super) frame_count: usize,
    /// The scalar preparations, kept for `sample` and inspection per lane (valid only when
    /// `lanes_valid`).
    pub(super) lanes: [Prepared; W],
    /// `lanes` holds this batch's points
    /// ([`Material::prepare_batch_into`](super::Material::prepare_batch_into)), not only the
    /// kernels
    /// ([`Material::prepare_batch_eval_into`](super::Material::prepare_batch_eval_into)).
    pub(super) lanes_valid: bool,
    /// The slots carry the selection probabilities, so [`PreparedBatch::eval`] has its
    /// densities (false after
    /// [`Material::prepare_batch_f_cos_into`](super::Material::prepare_batch_f_cos_into)'s
    /// lane-parallel path).
    pub(super) densities: bool,
    /// Per lane: `albedo().total()`, `emission()`, `transparency()` of the lane's
    /// preparation.
    pub(super) albedo: Vec3x<W>,
    pub(super) emission: Vec3x<W>,
    pub(super) transparency: Vec3x<W>,
    /// Working memory of the lane-parallel prepare (throughputs, scope products, weight
    /// sums), kept to avoid allocating per batch.
    pub(super) work: Vec<Vec3x<W>>,
}

/// The widest batch whose eval skips kernel slots lit from below in every lane.
const SKIP_BELOW_MAX_LANES: usize = 4;

impl<const W: usize> PreparedBatch<W> {
    /// An empty batch (every lane without lobes), to be filled by
    /// [`Material::prepare_batch_into`](super::Material::prepare_batch_into). Boxed: a batch of
    /// 16 lanes is about 120 KB.
    pub fn new_boxed() -> Box<PreparedBatch<W>> {
        Box::new(PreparedBatch::from_lanes(std::array::from_fn(|_| {
            Prepared::empty(Vec3::Z)
        })))
    }

    pub(super) fn from_lanes(lanes: [Prepared; W]) -> PreparedBatch<W> {
        let empty = Slot {
            index: [0; W],
            lw: LaneWeights {
                w: Vec3x::zero(),
                p: [0.0; W],
                sign: [1.0; W],
            },
            live: [false; W],
            frame: 0,
            kernel: Kernel::Scalar,
        };
        let mut b = PreparedBatch {
            slots: [empty; MAX_LOBES],
            count: 0,
            frames: [FrameX::identity(); MAX_LOBES],
            frame_count: 0,
            lanes,
            lanes_valid: true,
            densities: true,
            albedo: Vec3x::zero(),
            emission: Vec3x::zero(),
            transparency: Vec3x::zero(),
            work: Vec::new(),
        };
        b.transpose();
        b
    }

    /// Rebuild the slots from the per-lane preparations: slot order is leaf order, so lanes
    /// agree on it.
    pub(super) fn transpose(&mut self) {
        let mut leaf_slot = [u8::MAX; MAX_LOBES];
        let mut leaves: [u8; MAX_LOBES] = [0; MAX_LOBES];
        let mut count = 0;
        // Which leaves are live anywhere, in leaf order.
        let mut live_any = [false; MAX_LOBES];
        for lane in &self.lanes {
            for l in lane.lobes() {
                live_any[l.leaf as usize] = true;
            }
        }
        for (leaf, &live) in live_any.iter().enumerate() {
            if live {
                leaf_slot[leaf] = count as u8;
                leaves[count] = leaf as u8;
                count += 1;
            }
        }
        for slot in &mut self.slots[..count] {
            slot.live = [false; W];
            slot.lw.w = Vec3x::zero();
            slot.lw.p = [0.0; W];
            slot.lw.sign = [1.0; W];
        }
        self.frame_count = 0;
        for (k, lane) in self.lanes.iter().enumerate() {
            for (j, l) in lane.lobes().iter().enumerate() {
                let slot = &mut self.slots[leaf_slot[l.leaf as usize] as usize];
                slot.index[k] = j as u8;
                // An inactive lobe evaluates to zero: it stays masked.
                if l.lobe.is_inactive() {
                    continue;
                }
                slot.lw.w.set(k, l.weight);
                slot.lw.p[k] = l.prob;
                slot.lw.sign[k] = if l.lobe.is_flipped() { -1.0 } else { 1.0 };
                slot.live[k] = true;
                slot.frame = l.frame;
            }
            for f in 0..lane.frame_count {
                self.frames[f].set(k, &lane.frames[f]);
            }
            self.frame_count = self.frame_count.max(lane.frame_count);
            self.albedo.set(k, lane.albedo().total());
            self.emission.set(k, lane.emission());
            self.transparency.set(k, lane.transparency());
        }
        self.lanes_valid = true;
        self.densities = true;
        for slot in &mut self.slots[..count] {
            let lanes = &self.lanes;
            let lobe = |k: usize| &lanes[k].lobes[slot.index[k] as usize].lobe;
            slot.kernel.rebuild(lobe, &slot.live, &slot.lw);
        }
        self.count = count;
    }

    /// `eval` per lane at world directions `l` (equal to the scalar [`Prepared::eval`] to
    /// relative 1e-5; the pdf is NaN after the eval-only prepare of the preview, which
    /// computes no selection probabilities). The kernels run in the widest vector extension
    /// the CPU has (module `simd`); the results do not depend on which.
    pub fn eval(&self, l: &[Vec3; W]) -> [Eval; W] {
        self.eval_at(Level::Avx512, l)
    }

    testkit_pub! {
        /// [`PreparedBatch::eval`] with the kernels compiled for at most `level` (for tests and
        /// benchmarks: every level gives the same bits).
        fn eval_at(&self, level: Level, l: &[Vec3; W]) -> [Eval; W] {
            call_widest!(level, self.eval_lanes(l), eval_avx512, eval_avx2)
        }
    }

    testkit_pub! {
        /// [`PreparedBatch::eval`]'s `f_cos` alone, for callers that need no density (the
        /// batched material preview): the kernels leave their pdf arithmetic out, as
        /// [`Prepared::eval_f_cos`] does.
        fn eval_f_cos(&self, l: &[Vec3; W]) -> [Rgb; W] {
            self.eval_f_cos_at(Level::Avx512, l)
        }
    }

    testkit_pub! {
        /// [`PreparedBatch::eval_f_cos`] with the kernels compiled for at most `level`.
        fn eval_f_cos_at(&self, level: Level, l: &[Vec3; W]) -> [Rgb; W] {
            call_widest!(
                level,
                self.f_cos_lanes(l),
                eval_f_cos_avx512,
                eval_f_cos_avx2
            )
        }
    }

    widest_versions!(eval_lanes(l: &[Vec3; W]) -> [Eval; W], eval_avx512, eval_avx2);

    widest_versions!(f_cos_lanes(l: &[Vec3; W]) -> [Rgb; W], eval_f_cos_avx512, eval_f_cos_avx2);

    #[inline(always)]
    fn eval_lanes(&self, l: &[Vec3; W]) -> [Eval; W] {
        let acc = self.accumulate::<true>(l);
        std::array::from_fn(|k| Eval {
            f_cos: acc.f.get(k),
            pdf: if self.densities { acc.pdf[k] } else { f32::NAN },
        })
    }

    #[inline(always)]
    fn f_cos_lanes(&self, l: &[Vec3; W]) -> [Rgb; W] {
        let acc = self.accumulate::<false>(l);
        std::array::from_fn(|k| acc.f.get(k))
    }

    /// The slots' sums at world directions `l`; `acc.pdf` is the mixture density only
    /// when `PDF` (else the kernels leave it out, and callers ignore it).
    #[inline(always)]
    fn accumulate<const PDF: bool>(&self, l: &[Vec3; W]) -> Acc<W> {
        let world = Vec3x::from_vecs(l);
        let mut acc = Acc {
            f: Vec3x::zero(),
            pdf: [0.0f32; W],
        };
        // L in the current slot's frame, transformed when the frame changes. Slots are in
        // leaf order and leaves share few frames (ref10 has one), so this transforms about
        // once per frame; an array of every frame's local L would have to be zeroed first
        // (3 KB for 16 lanes, a third of the instructions of a ref10 batch).
        let mut frame = usize::MAX;
        let mut loc = Vec3x::zero();
        for slot in &self.slots[..self.count] {
            if slot.frame as usize != frame {
                frame = slot.frame as usize;
                loc = self.frames[frame].local(&world);
            }
            // Every kernel family reflects only: a lane adds exact zeros unless L lies above
            // its (possibly flipped) surface, so a slot whose lanes all see L from below is
            // skipped; the sums are unchanged. Only narrow batches test it (with one lane, the
            // preview's unlit pixels): across 16 lanes it almost never holds, and the test
            // cost 16-lane evals 4 % more instructions.
            let narrow = W <= SKIP_BELOW_MAX_LANES;
            let kernel = !matches!(slot.kernel, Kernel::Scalar);
            if narrow && kernel && !(0..W).any(|k| slot.lw.sign[k] * loc.z[k] > 0.0) {
                continue;
            }
            if !slot.kernel.accumulate::<PDF>(&loc, &slot.lw, &mut acc) {
                self.scalar_slot(slot, &loc, &mut acc);
            }
        }
        acc
    }

    /// A slot without a kernel: the scalar leaf lane by lane. Kept out of line so that the
    /// scalar leaves (with their library calls) do not bloat `eval`'s kernel loops.
    #[inline(never)]
    fn scalar_slot(&self, slot: &Slot<W>, loc: &Vec3x<W>, acc: &mut Acc<W>) {
        for k in 0..W {
            if slot.live[k] {
                let e = self.lanes[k].lobes[slot.index[k] as usize]
                    .lobe
                    .eval(loc.get(k));
                let f = slot.lw.w.get(k) * e.f_cos;
                acc.f.set(k, acc.f.get(k) + f);
                acc.pdf[k] += slot.lw.p[k] * e.pdf;
            }
        }
    }

    /// Number of slots that run a vectorised kernel (the others run the scalar leaf per
    /// lane).
    #[cfg(feature = "testkit")]
    pub fn kernel_count(&self) -> usize {
        self.slots[..self.count]
            .iter()
            .filter(|s| !matches!(s.kernel, Kernel::Scalar))
            .count()
    }

    /// The scalar preparation of lane `k` (for `sample` and inspection); `None` when the batch
    /// was prepared lane-parallel by
    /// [`Material::prepare_batch_eval_into`](super::Material::prepare_batch_eval_into) or its
    /// preview variant.
    pub fn lane(&self, k: usize) -> Option<&Prepared> {
        self.lanes_valid.then(|| &self.lanes[k])
    }

    /// Lane `k`'s directional albedo `albedo().total()` (reflection plus transmission as
    /// energy, [`Prepared::albedo`]).
    pub fn albedo(&self, k: usize) -> Vec3 {
        self.albedo.get(k)
    }

    /// Lane `k`'s emission ([`Prepared::emission`]).
    pub fn emission(&self, k: usize) -> Vec3 {
        self.emission.get(k)
    }

    /// Lane `k`'s straight-through transmittance ([`Prepared::transparency`]).
    pub fn transparency(&self, k: usize) -> Vec3 {
        self.transparency.get(k)
    }

    /// Number of leaf slots (leaves live in at least one lane).
    pub fn slot_count(&self) -> usize {
        self.count
    }
}
