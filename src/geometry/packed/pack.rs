//! Packing: world-space primitives laid out in BVH order, with the BVH over each kind.

use std::ops::Range;
use std::sync::Arc;

use glam::{Affine3A, Mat3, Vec2, Vec3};

use super::primitive::{Primitive, is_quad_pair, triangle_normal};
use crate::geometry::bvh::{Bounds, Bvh, EMPTY, sphere_bounds, triangle_bounds, union};
use crate::geometry::instance::{InstanceSet, MeshBlas};
use crate::geometry::layout::{DefaultLayout, Layout};
use crate::geometry::store::{SphereStore, TriangleStore};

/// An infinite plane with a frame for planar texture coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaneRecord {
    /// A point on the plane; texture coordinates are measured from it.
    pub point: Vec3,
    /// Unit normal.
    pub normal: Vec3,
    /// Unit tangent (texture u axis).
    pub tangent: Vec3,
    /// Unit bitangent (texture v axis).
    pub bitangent: Vec3,
    /// Owner slot.
    pub owner: u32,
}

/// The layout-independent half of packing: the BVH over each primitive kind and the slot order
/// it imposes. [`Geometry::pack_with`] lays the arrays out from it in any layout.
#[derive(Clone, Default)]
pub struct BvhPlan {
    sphere_bvh: Bvh,
    sphere_order: Vec<u32>,
    triangle_bvh: Bvh,
    triangle_order: Vec<u32>,
}

impl BvhPlan {
    /// Builds the sphere and triangle BVHs of `primitives` (planes need none).
    pub fn new(primitives: &[(u32, Primitive)]) -> Self {
        let mut spheres = Vec::new();
        let mut triangles = Vec::new();
        for (owner, prim) in primitives {
            match *prim {
                Primitive::Sphere { center, radius, .. } => {
                    spheres.push(sphere_bounds(center, radius));
                }
                Primitive::Triangle { p, .. } => triangles.push((*owner, p)),
                Primitive::Plane { .. } | Primitive::Instance { .. } => {}
            }
        }
        let (sphere_bvh, sphere_order) = Bvh::build(&spheres);
        // A quad's two triangles (a, b, c) and (a, c, d) are one group of the BVH, so they
        // always share a leaf: whatever enters the quad's box tests both, in one leaf visit.
        let mut groups: Vec<Range<u32>> = Vec::with_capacity(triangles.len());
        let mut bounds: Vec<Bounds> = Vec::with_capacity(triangles.len());
        let mut i = 0;
        while i < triangles.len() {
            let (owner, p) = triangles[i];
            let mut b = triangle_bounds(p);
            let mut end = i + 1;
            if let Some(&(o, q)) = triangles.get(i + 1)
                && o == owner
                && is_quad_pair(p, q)
            {
                b = (b.0.min(q[2]), b.1.max(q[2]));
                end += 1;
            }
            groups.push(i as u32..end as u32);
            bounds.push(b);
            i = end;
        }
        // A group is one triangle or a quad's two.
        let (triangle_bvh, group_order) =
            Bvh::build_groups(&bounds, |g| (groups[g].end - groups[g].start) as u8);
        let triangle_order = group_order
            .iter()
            .flat_map(|&g| groups[g as usize].clone())
            .collect();
        Self {
            sphere_bvh,
            sphere_order,
            triangle_bvh,
            triangle_order,
        }
    }
}

/// Primitives sorted by kind, in input order: spheres and triangles with their owners (to be laid
/// out in BVH order), planes and mesh placements ready.
struct Parts<'a> {
    spheres: Vec<(u32, &'a Primitive)>,
    triangles: Vec<(u32, &'a Primitive)>,
    planes: Vec<PlaneRecord>,
    placements: Vec<(u32, Arc<MeshBlas>, Affine3A)>,
}

impl<'a> Parts<'a> {
    fn of(primitives: &'a [(u32, Primitive)]) -> Self {
        let mut parts = Parts {
            spheres: Vec::new(),
            triangles: Vec::new(),
            planes: Vec::new(),
            placements: Vec::new(),
        };
        for (owner, prim) in primitives {
            match prim {
                Primitive::Instance {
                    blas,
                    world_from_object,
                } => {
                    parts
                        .placements
                        .push((*owner, blas.clone(), *world_from_object));
                }
                Primitive::Sphere { .. } => parts.spheres.push((*owner, prim)),
                Primitive::Triangle { .. } => parts.triangles.push((*owner, prim)),
                &Primitive::Plane { point, normal } => {
                    let (tangent, bitangent) = normal.any_orthonormal_pair();
                    parts.planes.push(PlaneRecord {
                        point,
                        normal,
                        tangent,
                        bitangent,
                        owner: *owner,
                    });
                }
            }
        }
        parts
    }

    /// The owners of the spheres and of the triangles, in input order.
    fn owners(&self) -> (Vec<u32>, Vec<u32>) {
        (
            self.spheres.iter().map(|s| s.0).collect(),
            self.triangles.iter().map(|t| t.0).collect(),
        )
    }
}

/// All geometry of a scene, packed for tracing in layout `L` (see [`crate::geometry::layout`]). Built from
/// [`Primitive`]s with their owners.
///
/// Slots are BVH order: a leaf's primitives are a contiguous slot range. Every layout holds the
/// same values in the same slots, so a slot, a [`Hit`](super::Hit) or an owner index means the same thing
/// whatever `L`. Read positions by slot with [`Geometry::sphere`] and [`Geometry::triangle`]
/// (any layout), or through the store fields.
#[derive(Clone, Default)]
pub struct Geometry<L: Layout = DefaultLayout> {
    /// Sphere centres and radii in BVH order.
    pub spheres: L::Spheres,
    /// Owner slot per sphere.
    pub sphere_owner: Vec<u32>,
    /// Object-to-world rotation per sphere (for texture coordinates).
    pub sphere_frame: Vec<Mat3>,
    /// BVH over the spheres.
    pub sphere_bvh: Bvh,
    /// The sphere in each slot, as its index among the spheres packed (see [`Geometry::refit`]).
    sphere_order: Vec<u32>,
    /// Triangle vertices in BVH order.
    pub triangles: L::Triangles,
    /// Owner slot per triangle.
    pub triangle_owner: Vec<u32>,
    /// Texture coordinates per triangle vertex.
    pub triangle_uv: Vec<[Vec2; 3]>,
    /// Unit geometric normal per triangle, [`triangle_normal`] of its vertices: computed once
    /// here rather than at every hit and every light sample.
    pub triangle_normal: Vec<Vec3>,
    /// BVH over the triangles.
    pub triangle_bvh: Bvh,
    /// The triangle in each slot, as its index among the triangles packed.
    triangle_order: Vec<u32>,
    /// Infinite planes.
    pub planes: Vec<PlaneRecord>,
    /// Mesh placements with their top-level BVH.
    pub instances: InstanceSet,
}

impl Geometry {
    /// Packs `(owner, primitive)` pairs in the default layout: builds the BVHs and lays out the
    /// arrays in BVH order. [`Geometry::pack`] does the same in any layout.
    pub fn build(primitives: &[(u32, Primitive)]) -> Self {
        Self::pack(primitives)
    }
}

impl<L: Layout> Geometry<L> {
    /// Packs `(owner, primitive)` pairs in layout `L`: builds the BVHs and lays out the arrays in
    /// BVH order.
    pub fn pack(primitives: &[(u32, Primitive)]) -> Self {
        Self::pack_with(primitives, BvhPlan::new(primitives))
    }

    /// Lays out `primitives` in the slot order of `plan`, which must have been built from the
    /// same primitives.
    pub fn pack_with(primitives: &[(u32, Primitive)], plan: BvhPlan) -> Self {
        let parts = Parts::of(primitives);
        let (sphere_owners, triangle_owners) = parts.owners();
        assert_eq!(
            (parts.spheres.len(), parts.triangles.len()),
            (plan.sphere_order.len(), plan.triangle_order.len()),
            "BvhPlan built from other primitives"
        );
        let mut g = Geometry::<L> {
            sphere_bvh: plan.sphere_bvh,
            sphere_order: plan.sphere_order,
            triangle_bvh: plan.triangle_bvh,
            triangle_order: plan.triangle_order,
            ..Default::default()
        };
        g.lay_out(parts);
        g.sphere_owner = g
            .sphere_order
            .iter()
            .map(|&i| sphere_owners[i as usize])
            .collect();
        g.triangle_owner = g
            .triangle_order
            .iter()
            .map(|&i| triangle_owners[i as usize])
            .collect();
        g
    }

    /// Moves the primitives to where `primitives` puts them, keeping the BVHs' trees and only
    /// refitting their boxes, if `primitives` is the same sequence as the one packed (the same
    /// owners, with the same number of spheres and of triangles each, in the same order);
    /// otherwise changes nothing and returns `false`. Planes and mesh placements are taken as
    /// given (they have no BVH of their own here; the instances' top level is rebuilt).
    ///
    /// A refitted tree finds the same hits as a fresh build, but may visit equally distant
    /// primitives in another order: use it where that cannot matter (a preview).
    pub fn refit(&mut self, primitives: &[(u32, Primitive)]) -> bool {
        let parts = Parts::of(primitives);
        let (sphere_owners, triangle_owners) = parts.owners();
        let same = |order: &[u32], owner: &[u32], new: &[u32]| {
            order.len() == new.len() && order.iter().zip(owner).all(|(&i, &o)| new[i as usize] == o)
        };
        if !same(&self.sphere_order, &self.sphere_owner, &sphere_owners)
            || !same(&self.triangle_order, &self.triangle_owner, &triangle_owners)
        {
            return false;
        }
        self.lay_out(parts);
        let spheres = &self.spheres;
        self.sphere_bvh.refit(|slots| {
            spheres
                .leaf(slots)
                .fold(EMPTY, |all, (c, r)| union(all, sphere_bounds(c, r)))
        });
        let triangles = &self.triangles;
        self.triangle_bvh.refit(|slots| {
            triangles
                .leaf(slots)
                .fold(EMPTY, |all, p| union(all, triangle_bounds(p)))
        });
        true
    }

    /// Fills the arrays from `parts` in the slot order of `sphere_order` and `triangle_order`
    /// (all but the owners), and the planes and instances.
    fn lay_out(&mut self, parts: Parts<'_>) {
        let Parts {
            spheres,
            triangles,
            planes,
            placements,
        } = parts;
        self.planes = planes;
        self.instances = InstanceSet::build(placements);
        self.spheres = L::Spheres::default();
        self.spheres.reserve(spheres.len());
        self.sphere_frame.clear();
        self.sphere_frame.reserve(spheres.len());
        for &i in &self.sphere_order {
            if let &Primitive::Sphere {
                center,
                radius,
                frame,
            } = spheres[i as usize].1
            {
                self.spheres.push(center, radius);
                self.sphere_frame.push(frame);
            }
        }
        self.triangles = L::Triangles::default();
        self.triangles.reserve(triangles.len());
        self.triangle_uv.clear();
        self.triangle_uv.reserve(triangles.len());
        self.triangle_normal.clear();
        self.triangle_normal.reserve(triangles.len());
        for &i in &self.triangle_order {
            if let &Primitive::Triangle { p, uv } = triangles[i as usize].1 {
                self.triangles.push(p);
                self.triangle_uv.push(uv);
                self.triangle_normal.push(triangle_normal(p));
            }
        }
    }

    /// The same geometry in layout `M`: slot for slot the same values and the same BVHs, so
    /// every hit and every image is bit-identical.
    pub fn relayout<M: Layout>(&self) -> Geometry<M> {
        let mut spheres = M::Spheres::default();
        spheres.reserve(self.spheres.len());
        for (c, r) in self.spheres.leaf(0..self.spheres.len()) {
            spheres.push(c, r);
        }
        let mut triangles = M::Triangles::default();
        triangles.reserve(self.triangles.len());
        for p in self.triangles.leaf(0..self.triangles.len()) {
            triangles.push(p);
        }
        Geometry {
            spheres,
            sphere_owner: self.sphere_owner.clone(),
            sphere_frame: self.sphere_frame.clone(),
            sphere_bvh: self.sphere_bvh.clone(),
            sphere_order: self.sphere_order.clone(),
            triangles,
            triangle_owner: self.triangle_owner.clone(),
            triangle_uv: self.triangle_uv.clone(),
            triangle_normal: self.triangle_normal.clone(),
            triangle_bvh: self.triangle_bvh.clone(),
            triangle_order: self.triangle_order.clone(),
            planes: self.planes.clone(),
            instances: self.instances.clone(),
        }
    }

    /// Number of primitives of every kind.
    pub fn primitive_count(&self) -> usize {
        self.sphere_owner.len()
            + self.triangle_owner.len()
            + self.planes.len()
            + self.instances.len()
    }

    /// Centre and radius of the sphere in `slot`.
    #[inline]
    pub fn sphere(&self, slot: usize) -> (Vec3, f32) {
        self.spheres.get(slot)
    }

    /// Vertices of the triangle in `slot`.
    #[inline]
    pub fn triangle(&self, slot: usize) -> [Vec3; 3] {
        self.triangles.get(slot)
    }

    /// The box around every finite primitive (spheres, triangles, instances; planes are
    /// infinite), or `None` if there is none.
    pub fn finite_bounds(&self) -> Option<(Vec3, Vec3)> {
        [
            self.sphere_bvh.bounds(),
            self.triangle_bvh.bounds(),
            self.instances.bounds(),
        ]
        .into_iter()
        .flatten()
        .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)))
    }
}
