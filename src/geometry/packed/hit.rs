//! What a ray query on packed geometry finds.

use crate::geometry::triangle::TriangleHit;

/// Which kind of primitive a [`Hit`] refers to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HitKind {
    /// An index into the packed spheres.
    Sphere,
    /// An index into the packed triangles.
    Triangle,
    /// An index into the planes.
    Plane,
    /// An index into the instances, and the triangle within the instance's mesh.
    Instance {
        /// Triangle slot in the mesh's BVH order.
        triangle: u32,
    },
}

/// The closest intersection found along a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the ray.
    pub t: f32,
    /// Kind of the primitive hit.
    pub kind: HitKind,
    /// Slot of the primitive within its kind (BVH order).
    pub index: u32,
    /// Barycentric weight of the second triangle vertex (0 for other kinds).
    pub b1: f32,
    /// Barycentric weight of the third triangle vertex (0 for other kinds).
    pub b2: f32,
}

impl Hit {
    /// A hit at distance `t` of slot `index` of a kind without barycentrics (sphere, plane).
    #[inline(always)]
    pub(super) fn at(kind: HitKind, index: usize, t: f32) -> Self {
        Self {
            t,
            kind,
            index: index as u32,
            b1: 0.0,
            b2: 0.0,
        }
    }

    /// The hit `h` of triangle slot `index`.
    #[inline(always)]
    pub(super) fn triangle(index: usize, h: TriangleHit) -> Self {
        Self {
            t: h.t,
            kind: HitKind::Triangle,
            index: index as u32,
            b1: h.b1,
            b2: h.b2,
        }
    }
}
