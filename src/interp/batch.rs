//! Batched evaluation over `W` shading points (spec closures.md §1.5).
//!
//! A material's IR fixes the lobe structure; only parameter values differ between points. A
//! [`PreparedBatch`] therefore has one *slot* per leaf that is live in at least one lane,
//! in leaf order, and each slot stores its per-lane state side by side (structure of arrays
//! over lanes: `[PreparedLobe; W]`, `[Vec3; W]` weights, `[f32; W]` probabilities). A lobe
//! dropped in some lanes is masked there (weight 0), not removed; a leaf dropped in every
//! lane has no slot.
//!
//! `eval` is lobe-major: for each slot it runs the same leaf code over all `W` lanes, so one
//! dispatch serves `W` evaluations and the leaf's code and parameters stay hot. Per lane it
//! performs exactly the scalar operations in the scalar order, so results equal
//! [`Prepared::eval`] (the spec allows relative 1e-5; they are in fact identical).
//!
//! What this is not (yet): the leaves' arithmetic is still scalar per lane. Vectorising it
//! needs per-family SoA kernels like [`super::soa::DielectricRBatch`] for every leaf; the
//! batch layout (one slot per leaf, lanes contiguous) is the one those kernels need.

use super::frame::Frame;
use super::lobe::PreparedLobe;
use super::material::{Eval, Material, Prepared, Scratch, ShadingPoint};
use crate::ir::MAX_LOBES;
use glam::{Vec2, Vec3};

/// `W` shading points (§1.5). Every lane is a real point; pad a partial batch by repeating a
/// point.
#[derive(Debug, Clone, Copy)]
pub struct ShadingBatch<'a, const W: usize> {
    /// Shading normals.
    pub n: [Vec3; W],
    /// Surface tangents.
    pub t: [Vec3; W],
    /// Directions toward the viewer.
    pub v: [Vec3; W],
    /// Packed external inputs per lane (see [`Material::input_layout`]).
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
struct Slot<const W: usize> {
    lobes: [PreparedLobe; W],
    weight: [Vec3; W],
    prob: [f32; W],
    /// Lane is live (the lobe survived prepare there).
    live: [bool; W],
    /// Frame slot (the same for every lane: it is the leaf's).
    frame: u8,
}

/// A material prepared for `W` points (§1.5).
#[derive(Debug, Clone)]
pub struct PreparedBatch<const W: usize> {
    slots: [Slot<W>; MAX_LOBES],
    count: usize,
    frames: [[Frame; W]; MAX_LOBES],
    frame_count: usize,
    /// The scalar preparations, kept for `albedo`, `emission`, `sample` per lane.
    lanes: [Prepared; W],
}

impl Material {
    /// Prepare `W` points at once (§1.5).
    pub fn prepare_batch<const W: usize>(&self, p: &ShadingBatch<W>) -> PreparedBatch<W> {
        let mut s = Scratch::default();
        let lanes: [Prepared; W] = std::array::from_fn(|k| self.prepare_with(&p.lane(k), &mut s));
        PreparedBatch::from_lanes(lanes)
    }

    /// Prepare `W` points into an existing batch, reusing `scratch` (no heap allocation once
    /// the scratch is sized).
    pub fn prepare_batch_into<const W: usize>(
        &self,
        p: &ShadingBatch<W>,
        scratch: &mut Scratch,
        out: &mut PreparedBatch<W>,
    ) {
        for k in 0..W {
            self.prepare_into(&p.lane(k), scratch, &mut out.lanes[k]);
        }
        out.transpose();
    }
}

impl<const W: usize> PreparedBatch<W> {
    /// An empty batch (every lane without lobes), to be filled by
    /// [`Material::prepare_batch_into`]. Boxed: a batch of 16 lanes is about 120 KB.
    pub fn new_boxed() -> Box<PreparedBatch<W>> {
        Box::new(PreparedBatch::from_lanes(std::array::from_fn(|_| {
            Prepared::empty(Vec3::Z)
        })))
    }

    fn from_lanes(lanes: [Prepared; W]) -> PreparedBatch<W> {
        let first = lanes[0].lobes[0].lobe;
        let empty = Slot {
            lobes: [first; W],
            weight: [Vec3::ZERO; W],
            prob: [0.0; W],
            live: [false; W],
            frame: 0,
        };
        let mut b = PreparedBatch {
            slots: [empty; MAX_LOBES],
            count: 0,
            frames: [[Frame::default(); W]; MAX_LOBES],
            frame_count: 0,
            lanes,
        };
        b.transpose();
        b
    }

    /// Rebuild the slots from the per-lane preparations: slot order is leaf order, so lanes
    /// agree on it.
    fn transpose(&mut self) {
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
            slot.weight = [Vec3::ZERO; W];
            slot.prob = [0.0; W];
        }
        self.frame_count = 0;
        for (k, lane) in self.lanes.iter().enumerate() {
            for l in lane.lobes() {
                let slot = &mut self.slots[leaf_slot[l.leaf as usize] as usize];
                slot.lobes[k] = l.lobe;
                slot.weight[k] = l.weight;
                slot.prob[k] = l.prob;
                slot.live[k] = true;
                slot.frame = l.frame;
            }
            for f in 0..lane.frame_count {
                self.frames[f][k] = lane.frames[f];
            }
            self.frame_count = self.frame_count.max(lane.frame_count);
        }
        self.count = count;
    }

    /// `eval` per lane at world directions `l` (equal to the scalar [`Prepared::eval`]).
    pub fn eval(&self, l: &[Vec3; W]) -> [Eval; W] {
        let mut local = [[Vec3::ZERO; W]; MAX_LOBES];
        for (loc, frames) in local.iter_mut().zip(&self.frames[..self.frame_count]) {
            for k in 0..W {
                loc[k] = frames[k].to_local(l[k]);
            }
        }
        let mut f = [Vec3::ZERO; W];
        let mut pdf = [0.0f32; W];
        for slot in &self.slots[..self.count] {
            let loc = &local[slot.frame as usize];
            for k in 0..W {
                if slot.live[k] {
                    let e = slot.lobes[k].eval(loc[k]);
                    f[k] += slot.weight[k] * e.f_cos;
                    pdf[k] += slot.prob[k] * e.pdf;
                }
            }
        }
        std::array::from_fn(|k| Eval {
            f_cos: f[k],
            pdf: pdf[k],
        })
    }

    /// The scalar preparation of lane `k` (for `albedo`, `emission`, `sample`).
    pub fn lane(&self, k: usize) -> &Prepared {
        &self.lanes[k]
    }

    /// Number of leaf slots (leaves live in at least one lane).
    pub fn slot_count(&self) -> usize {
        self.count
    }
}
