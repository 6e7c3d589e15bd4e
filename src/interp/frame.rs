//! Local shading frames: tangent `x`, bitangent `y`, normal `z`.

use super::vmath::select3;
use glam::Vec3;

/// An orthonormal frame; leaves work in its local coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Tangent (anisotropy direction).
    pub x: Vec3,
    /// Bitangent, `z × x`.
    pub y: Vec3,
    /// Normal.
    pub z: Vec3,
}

impl Frame {
    /// The frame of normal `n` and tangent `t` (Gram–Schmidt). A zero or degenerate normal
    /// gives `+z`; a tangent parallel to the normal (or zero) is replaced by an arbitrary
    /// perpendicular one.
    // Both alternatives are computed and blended without a branch (the values equal those of
    // `normalize_or` and an `if`): the lane-parallel prepare builds a frame per lane in a
    // loop the compiler vectorises only when it has no branch.
    #[inline(always)]
    pub fn new(n: Vec3, t: Vec3) -> Frame {
        let rcp = n.length_recip();
        let z = select3(rcp.is_finite() & (rcp > 0.0), n * rcp, Vec3::Z);
        let tt = t - z * z.dot(t);
        let x = select3(
            tt.length_squared() > 1e-12,
            tt.normalize(),
            z.any_orthonormal_vector(),
        );
        Frame {
            x,
            y: z.cross(x),
            z,
        }
    }

    /// A frame with an arbitrary tangent around normal `n`.
    pub fn from_normal(n: Vec3) -> Frame {
        let z = n.normalize_or(Vec3::Z);
        let (x, y) = z.any_orthonormal_pair();
        Frame { x, y, z }
    }

    /// The same frame with its tangent rotated by `angle` radians about the normal.
    pub fn rotated(&self, angle: f32) -> Frame {
        let (s, c) = angle.sin_cos();
        let x = self.x * c + self.y * s;
        Frame {
            x,
            y: self.z.cross(x),
            z: self.z,
        }
    }

    /// World → local.
    #[inline]
    pub fn to_local(&self, w: Vec3) -> Vec3 {
        Vec3::new(w.dot(self.x), w.dot(self.y), w.dot(self.z))
    }

    /// Local → world.
    #[inline]
    pub fn to_world(&self, w: Vec3) -> Vec3 {
        self.x * w.x + self.y * w.y + self.z * w.z
    }
}

impl Default for Frame {
    fn default() -> Self {
        Frame {
            x: Vec3::X,
            y: Vec3::Y,
            z: Vec3::Z,
        }
    }
}
