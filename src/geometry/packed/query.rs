//! Ray queries on packed geometry: the closest hit, any hit (occlusion), the brute-force
//! oracle, and the local surface at a hit.

use std::ops::Range;

use glam::Vec2;

use super::hit::{Hit, HitKind};
use super::pack::Geometry;
use crate::cpu::{Lanes, Sse};
use crate::geometry::aabb::RayQuery;
use crate::geometry::bvh::Leaf;
use crate::geometry::layout::Layout;
use crate::geometry::plane::{intersect_plane, plane_uv};
use crate::geometry::ray::Ray;
use crate::geometry::sphere::{intersect_sphere, sphere_uv};
use crate::geometry::store::{SphereStore, TriangleStore};
use crate::geometry::surface::{Surface, Tangent, uv_derivatives};
use crate::geometry::triangle::{TriangleHit, intersect_triangle};

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

/// The closest-hit leaf test over spheres, as a [`Leaf`] (a struct, not a closure, so that it is
/// inlined into the traversal as the triangles' is): records the closest sphere hit in `best`.
struct ClosestSphere<'a, L: Layout> {
    spheres: &'a L::Spheres,
    ray: &'a Ray,
    best: &'a mut Option<Hit>,
}

impl<L: Layout> Leaf for ClosestSphere<'_, L> {
    #[inline(always)]
    fn visit(&mut self, slots: Range<usize>, t_max: &mut f32) -> bool {
        if let Some(i) = L::closest_sphere(self.spheres, self.ray, slots, t_max) {
            *self.best = Some(Hit::at(HitKind::Sphere, i, *t_max));
        }
        true
    }
}

/// The any-hit leaf test over spheres, as a [`Leaf`]: sets `blocked` and stops the traversal at
/// the first sphere hit.
struct AnySphere<'a, L: Layout> {
    spheres: &'a L::Spheres,
    ray: &'a Ray,
    blocked: &'a mut bool,
}

impl<L: Layout> Leaf for AnySphere<'_, L> {
    #[inline(always)]
    fn visit(&mut self, slots: Range<usize>, t_max: &mut f32) -> bool {
        *self.blocked = L::any_sphere(self.spheres, self.ray, slots, *t_max);
        !*self.blocked
    }
}

impl<L: Layout> Geometry<L> {
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
            self.sphere_bvh.traverse_leaves(
                lanes,
                &q,
                &mut t_best,
                ClosestSphere::<L> {
                    spheres: &self.spheres,
                    ray,
                    best: &mut best,
                },
            );
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
        self.intersect_outside_bvhs(lanes, ray, t_best, best)
    }

    /// The part of every closest-hit query outside the sphere and triangle BVHs: infinite
    /// planes, tested linearly, then mesh instances, through their own BVHs. Returns the closest
    /// of those and `best` (found before `t_best`).
    #[inline(always)]
    fn intersect_outside_bvhs<W: Lanes>(
        &self,
        lanes: W,
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
        if let Some(h) = self.instances.intersect_with(lanes, ray, t_best) {
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
        self.sphere_bvh.traverse_any_leaves(
            lanes,
            &q,
            &mut t,
            AnySphere::<L> {
                spheres: &self.spheres,
                ray,
                blocked: &mut blocked,
            },
        );
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
            || self.instances.occluded_with(lanes, ray, t_max)
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
        self.intersect_outside_bvhs(Sse, ray, t_best, best)
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
        self.surface_reading(ray, hit, |_| true)
    }

    /// [`Geometry::surface`], where a sphere's texture coordinates (an `atan2` and an `acos`)
    /// are computed only if `reads_uv(owner)` says its owner's material reads them, and are
    /// zero otherwise. Every other primitive's are interpolated as always (a few products).
    #[inline(always)]
    pub fn surface_reading(
        &self,
        ray: &Ray,
        hit: &Hit,
        reads_uv: impl FnOnce(u32) -> bool,
    ) -> Surface {
        let i = hit.index as usize;
        match hit.kind {
            HitKind::Sphere => {
                let (c, r) = self.spheres.get(i);
                // (o − c) + t·d keeps the digits o + t·d − c would cancel far from the origin;
                // the point is then re-projected onto the sphere.
                let n = ((ray.origin - c) + hit.t * ray.direction).normalize();
                let owner = self.sphere_owner[i];
                let uv = if reads_uv(owner) {
                    sphere_uv(self.sphere_frame[i].transpose() * n)
                } else {
                    Vec2::ZERO
                };
                Surface {
                    p: c + r * n,
                    n,
                    ns: n,
                    uv,
                    uv1: uv,
                    owner,
                }
            }
            HitKind::Triangle => {
                let [p0, p1, p2] = self.triangles.get(i);
                let b0 = 1.0 - hit.b1 - hit.b2;
                let [t0, t1, t2] = self.triangle_uv[i];
                let n = self.triangle_normal[i];
                let uv = b0 * t0 + hit.b1 * t1 + hit.b2 * t2;
                Surface {
                    p: b0 * p0 + hit.b1 * p1 + hit.b2 * p2,
                    n,
                    ns: n,
                    uv,
                    uv1: uv,
                    owner: self.triangle_owner[i],
                }
            }
            HitKind::Plane => {
                let pl = &self.planes[i];
                let p = ray.at(hit.t);
                let p = p - pl.normal * (p - pl.point).dot(pl.normal);
                let uv = plane_uv(p, pl.point, pl.tangent, pl.bitangent);
                Surface {
                    p,
                    n: pl.normal,
                    ns: pl.normal,
                    uv,
                    uv1: uv,
                    owner: pl.owner,
                }
            }
            HitKind::Instance { triangle } => {
                self.instances.surface(hit.index, triangle, hit.b1, hit.b2)
            }
        }
    }
}
