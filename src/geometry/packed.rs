//! Render-side geometry: world-space primitives packed in BVH order, in a choice of layouts.
//!
//! Spheres and triangles each get their own BVH and their own arrays, so a scene pays only for the
//! primitive kinds it uses; infinite planes are tested linearly outside any BVH. What the
//! intersection loops read is stored as the layout `L` says (see [`super::layout`]: one
//! `Vec<f32>` per field, or one struct per primitive); what only shading needs (owner, texture
//! coordinates, frames) sits beside it and is touched once per closest hit.

use std::any::Any;

use std::ops::Range;
use std::sync::Arc;

use glam::{Affine3A, Mat3, Vec2, Vec3};

use super::aabb::RayQuery;
use super::bvh::{Bounds, Bvh, EMPTY, Leaf, sphere_bounds, triangle_bounds, union};
use super::instance::{InstanceSet, MeshBlas};
pub use super::layout::{Aos, DefaultLayout, Hybrid, Layout, LayoutKind, Soa, SoaSimd};
use super::plane::{intersect_plane, plane_uv};
use super::ray::Ray;
use super::sphere::{intersect_sphere, sphere_uv};
pub use super::store::{
    Sphere, SphereAos, SphereSoa, SphereStore, Triangle, TriangleAos, TriangleSoa, TriangleStore,
};
use super::surface::{Surface, Tangent, uv_derivatives};
use super::triangle::{TriangleHit, intersect_triangle};
use crate::cpu::{Lanes, Sse};

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
fn is_quad_pair(p: [Vec3; 3], q: [Vec3; 3]) -> bool {
    let bits = |v: Vec3| v.to_array().map(f32::to_bits);
    bits(q[0]) == bits(p[0]) && bits(q[1]) == bits(p[2])
}

/// The unit geometric normal of triangle `[a, b, c]`: `(b − a) × (c − a)`, normalised.
#[inline]
pub fn triangle_normal([a, b, c]: [Vec3; 3]) -> Vec3 {
    (b - a).cross(c - a).normalize()
}

/// The closest-hit leaf test over triangles, as a [`Leaf`] whose test is compiled into the
/// traversal loop: records the closest triangle hit (slot and hit) in `closest`.
struct ClosestTriangle<'a, L: Layout> {
    triangles: &'a L::Triangles,
    q: &'a RayQuery,
    closest: &'a mut Option<(usize, TriangleHit)>,
}

impl<L: Layout> Leaf for ClosestTriangle<'_, L> {
    #[inline(always)]
    fn visit(&mut self, slots: Range<usize>, t_max: &mut f32) -> bool {
        if let Some(hit) = L::closest_triangle(self.triangles, self.q, slots, t_max) {
            *self.closest = Some(hit);
        }
        true
    }
}

/// The any-hit leaf test over triangles, as a [`Leaf`]: sets `blocked` and stops the traversal
/// at the first triangle hit.
struct AnyTriangle<'a, L: Layout> {
    triangles: &'a L::Triangles,
    q: &'a RayQuery,
    blocked: &'a mut bool,
}

impl<L: Layout> Leaf for AnyTriangle<'_, L> {
    #[inline(always)]
    fn visit(&mut self, slots: Range<usize>, t_max: &mut f32) -> bool {
        *self.blocked = L::any_triangle(self.triangles, self.q, slots, *t_max);
        !*self.blocked
    }
}

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
    fn at(kind: HitKind, index: usize, t: f32) -> Self {
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
    fn triangle(index: usize, h: TriangleHit) -> Self {
        Self {
            t: h.t,
            kind: HitKind::Triangle,
            index: index as u32,
            b1: h.b1,
            b2: h.b2,
        }
    }
}

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
        let (triangle_bvh, group_order) =
            Bvh::build_groups(&bounds, |g| groups[g].end - groups[g].start);
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

/// All geometry of a scene, packed for tracing in layout `L` (see [`super::layout`]). Built from
/// [`Primitive`]s with their owners.
///
/// Slots are BVH order: a leaf's primitives are a contiguous slot range. Every layout holds the
/// same values in the same slots, so a slot, a [`Hit`] or an owner index means the same thing
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

    /// Owner slot (scene entity) of the primitive `hit` refers to.
    #[inline]
    pub fn owner(&self, hit: &Hit) -> u32 {
        let i = hit.index as usize;
        match hit.kind {
            HitKind::Sphere => self.sphere_owner[i],
            HitKind::Triangle => self.triangle_owner[i],
            HitKind::Plane => self.planes[i].owner,
            HitKind::Instance { .. } => self.instances.get(i).owner,
        }
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

    /// The closest hit along `ray` closer than `t_max`.
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        self.intersect_with(Sse, ray, t_max)
    }

    /// [`Geometry::intersect`] with the sphere and triangle BVHs' box tests as wide as `lanes`.
    #[inline(always)]
    pub fn intersect_with<W: Lanes>(&self, lanes: W, ray: &Ray, t_max: f32) -> Option<Hit> {
        let q = RayQuery::new(*ray);
        let mut best: Option<Hit> = None;
        let mut t_best = t_max;
        if !self.sphere_owner.is_empty() {
            self.sphere_bvh
                .traverse_leaves(lanes, &q, &mut t_best, |slots, t_best: &mut f32| {
                    if let Some(i) = L::closest_sphere(&self.spheres, ray, slots, t_best) {
                        best = Some(Hit::at(HitKind::Sphere, i, *t_best));
                    }
                    true
                });
        }
        if !self.triangle_owner.is_empty() {
            let mut closest = None;
            self.triangle_bvh.traverse_leaves(
                lanes,
                &q,
                &mut t_best,
                ClosestTriangle::<L> {
                    triangles: &self.triangles,
                    q: &q,
                    closest: &mut closest,
                },
            );
            if let Some((i, h)) = closest {
                best = Some(Hit::triangle(i, h));
            }
        }
        self.intersect_outside_bvhs(ray, t_best, best)
    }

    /// The part of every closest-hit query outside the sphere and triangle BVHs: infinite
    /// planes, tested linearly, then mesh instances, through their own BVHs. Returns the closest
    /// of those and `best` (found before `t_best`).
    #[inline]
    fn intersect_outside_bvhs(
        &self,
        ray: &Ray,
        mut t_best: f32,
        mut best: Option<Hit>,
    ) -> Option<Hit> {
        for (i, plane) in self.planes.iter().enumerate() {
            if let Some(t) = intersect_plane(ray, plane.point, plane.normal, t_best) {
                t_best = t;
                best = Some(Hit::at(HitKind::Plane, i, t));
            }
        }
        if let Some(h) = self.instances.intersect(ray, t_best) {
            best = Some(Hit {
                t: h.t,
                kind: HitKind::Instance {
                    triangle: h.triangle,
                },
                index: h.instance,
                b1: h.b1,
                b2: h.b2,
            });
        }
        best
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

    /// Whether anything blocks `ray` before `t_max`.
    #[inline(always)]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        self.occluded_with(Sse, ray, t_max)
    }

    /// [`Geometry::occluded`] with the sphere and triangle BVHs' box tests as wide as `lanes`.
    #[inline(always)]
    pub fn occluded_with<W: Lanes>(&self, lanes: W, ray: &Ray, t_max: f32) -> bool {
        let q = RayQuery::new(*ray);
        let mut blocked = false;
        let mut t = t_max;
        self.sphere_bvh
            .traverse_any_leaves(lanes, &q, &mut t, |slots, t: &mut f32| {
                blocked = L::any_sphere(&self.spheres, ray, slots, *t);
                !blocked
            });
        if blocked {
            return true;
        }
        self.triangle_bvh.traverse_any_leaves(
            lanes,
            &q,
            &mut t,
            AnyTriangle::<L> {
                triangles: &self.triangles,
                q: &q,
                blocked: &mut blocked,
            },
        );
        blocked
            || self
                .planes
                .iter()
                .any(|pl| intersect_plane(ray, pl.point, pl.normal, t_max).is_some())
            || self.instances.occluded(ray, t_max)
    }

    /// The closest hit by testing every primitive with the scalar reference kernels, without
    /// the BVHs and without the layout's leaf kernels: the oracle for tests.
    pub fn intersect_brute_force(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        let q = RayQuery::new(*ray);
        let mut best: Option<Hit> = None;
        let mut t_best = t_max;
        for i in 0..self.spheres.len() {
            let (c, r) = self.spheres.get(i);
            if let Some(t) = intersect_sphere(ray, c, r, t_best) {
                t_best = t;
                best = Some(Hit::at(HitKind::Sphere, i, t));
            }
        }
        for i in 0..self.triangles.len() {
            let [p0, p1, p2] = self.triangles.get(i);
            if let Some(h) = intersect_triangle(&q, p0, p1, p2, t_best) {
                t_best = h.t;
                best = Some(Hit::triangle(i, h));
            }
        }
        self.intersect_outside_bvhs(ray, t_best, best)
    }

    /// The texture-space tangent frame at `hit` (see [`Tangent`]), for normal mapping: for
    /// triangles (packed or instanced) with non-degenerate texture coordinates; `None` for
    /// spheres, planes, meshes without texture coordinates and degenerate ones. Computed on
    /// demand from the triangle's vertices, so scenes without normal maps never pay for it.
    pub fn uv_tangent(&self, hit: &Hit) -> Option<Tangent> {
        let i = hit.index as usize;
        match hit.kind {
            HitKind::Sphere | HitKind::Plane => None,
            HitKind::Triangle => {
                let (dpdu, dpdv) = uv_derivatives(self.triangles.get(i), self.triangle_uv[i])?;
                Tangent::from_derivatives(dpdu, dpdv, self.triangle_normal[i])
            }
            HitKind::Instance { triangle } => self.instances.uv_tangent(hit.index, triangle),
        }
    }

    /// Local geometry at `hit`.
    #[inline(always)]
    pub fn surface(&self, ray: &Ray, hit: &Hit) -> Surface {
        let i = hit.index as usize;
        match hit.kind {
            HitKind::Sphere => {
                let (c, r) = self.spheres.get(i);
                // (o − c) + t·d keeps the digits o + t·d − c would cancel far from the origin;
                // the point is then re-projected onto the sphere.
                let n = ((ray.origin - c) + hit.t * ray.direction).normalize();
                let uv = sphere_uv(self.sphere_frame[i].transpose() * n);
                Surface {
                    p: c + r * n,
                    n,
                    ns: n,
                    uv,
                    owner: self.sphere_owner[i],
                }
            }
            HitKind::Triangle => {
                let [p0, p1, p2] = self.triangles.get(i);
                let b0 = 1.0 - hit.b1 - hit.b2;
                let [t0, t1, t2] = self.triangle_uv[i];
                let n = self.triangle_normal[i];
                Surface {
                    p: b0 * p0 + hit.b1 * p1 + hit.b2 * p2,
                    n,
                    ns: n,
                    uv: b0 * t0 + hit.b1 * t1 + hit.b2 * t2,
                    owner: self.triangle_owner[i],
                }
            }
            HitKind::Plane => {
                let pl = &self.planes[i];
                let p = ray.at(hit.t);
                let p = p - pl.normal * (p - pl.point).dot(pl.normal);
                Surface {
                    p,
                    n: pl.normal,
                    ns: pl.normal,
                    uv: plane_uv(p, pl.point, pl.tangent, pl.bitangent),
                    owner: pl.owner,
                }
            }
            HitKind::Instance { triangle } => {
                self.instances.surface(hit.index, triangle, hit.b1, hit.b2)
            }
        }
    }
}

/// Geometry in the layouts other than the default, made on demand from the default-layout
/// geometry and kept until that geometry is rebuilt. The render system holds one, so a
/// `--layout` other than the default costs one [`Geometry::relayout`] per BVH build (a copy of
/// the arrays and BVHs, linear in the primitives), not one per pass.
#[derive(Default)]
pub struct LayoutCache {
    source: u64,
    soa: Option<Geometry<Soa>>,
    aos: Option<Geometry<Aos>>,
    soa_simd: Option<Geometry<SoaSimd>>,
    hybrid: Option<Geometry<Hybrid>>,
}

/// Layouts that have a slot in [`LayoutCache`].
pub trait Cached: Layout {
    /// This layout's slot.
    fn slot(cache: &mut LayoutCache) -> &mut Option<Geometry<Self>>;
}

impl Cached for Soa {
    fn slot(cache: &mut LayoutCache) -> &mut Option<Geometry<Self>> {
        &mut cache.soa
    }
}

impl Cached for Aos {
    fn slot(cache: &mut LayoutCache) -> &mut Option<Geometry<Self>> {
        &mut cache.aos
    }
}

impl Cached for SoaSimd {
    fn slot(cache: &mut LayoutCache) -> &mut Option<Geometry<Self>> {
        &mut cache.soa_simd
    }
}

impl Cached for Hybrid {
    fn slot(cache: &mut LayoutCache) -> &mut Option<Geometry<Self>> {
        &mut cache.hybrid
    }
}

impl LayoutCache {
    /// `geometry` in layout `L`: itself if `L` is its layout, else a copy made now or kept from
    /// an earlier call with the same `version` (any number that changes whenever `geometry` is
    /// rebuilt; a new version drops every copy).
    pub fn get<'a, L: Cached>(
        &'a mut self,
        geometry: &'a Geometry,
        version: u64,
    ) -> &'a Geometry<L> {
        // A type check once per pass, never per ray.
        if let Some(same) = (geometry as &dyn Any).downcast_ref::<Geometry<L>>() {
            return same;
        }
        if self.source != version {
            *self = Self {
                source: version,
                ..Self::default()
            };
        }
        L::slot(self).get_or_insert_with(|| geometry.relayout())
    }
}
