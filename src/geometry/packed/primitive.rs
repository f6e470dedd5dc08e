//! The world-space primitives that geometry is packed from.

use std::sync::Arc;

use glam::{Affine3A, Mat3, Vec2, Vec3};

use crate::geometry::instance::MeshBlas;

/// A world-space primitive, as produced from a scene shape and its transform.
#[derive(Clone, Debug, PartialEq)]
pub enum Primitive {
    /// A sphere; `frame` rotates object space (where texture coordinates are defined) to world.
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius (> 0).
        radius: f32,
        /// Rotation from object to world space.
        frame: Mat3,
    },
    /// A triangle with per-vertex texture coordinates; geometric normal `(b − a) × (c − a)`.
    Triangle {
        /// Vertices.
        p: [Vec3; 3],
        /// Texture coordinates at the vertices.
        uv: [Vec2; 3],
    },
    /// An infinite plane through `point` with unit `normal`.
    Plane {
        /// A point on the plane.
        point: Vec3,
        /// Unit normal.
        normal: Vec3,
    },
    /// A placement of a mesh: its shared bottom-level BVH and `world_from_object`.
    Instance {
        /// The mesh's BVH in object space, shared by all its placements.
        blas: Arc<MeshBlas>,
        /// Object to world.
        world_from_object: Affine3A,
    },
}

/// Whether triangles `p` and `q` are the halves `(a, b, c)` and `(a, c, d)` of a quad: `q`
/// starts with `p`'s first and last vertex, bit for bit.
#[inline]
pub(super) fn is_quad_pair(p: [Vec3; 3], q: [Vec3; 3]) -> bool {
    let bits = |v: Vec3| v.to_array().map(f32::to_bits);
    bits(q[0]) == bits(p[0]) && bits(q[1]) == bits(p[2])
}

/// The unit geometric normal of triangle `[a, b, c]`: `(b − a) × (c − a)`, normalised.
#[inline]
pub fn triangle_normal([a, b, c]: [Vec3; 3]) -> Vec3 {
    (b - a).cross(c - a).normalize()
}
