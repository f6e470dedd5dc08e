//! Render-side geometry: world-space primitives packed as structure-of-arrays in BVH order.
//!
//! Spheres and triangles each get their own BVH and their own arrays, so a scene pays only for the
//! primitive kinds it uses; infinite planes are tested linearly outside any BVH. Everything the
//! intersection loops read is in one `Vec<f32>` per field (SoA); what only shading needs (owner,
//! texture coordinates, frames) sits beside it and is touched once per closest hit.

use glam::{Mat3, Vec2, Vec3};

use super::aabb::RayQuery;
use super::bvh::{Bounds, Bvh};
use super::plane::{intersect_plane, plane_uv};
use super::ray::Ray;
use super::sphere::{intersect_sphere, sphere_uv};
use super::triangle::intersect_triangle;

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

/// Local geometry at a hit point, as shading needs it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface {
    /// The hit point, computed from the primitive (not from `o + t·d`) for accuracy.
    pub p: Vec3,
    /// Unit geometric normal as the primitive defines it (not flipped towards the ray).
    pub n: Vec3,
    /// Texture coordinates.
    pub uv: Vec2,
    /// Owner (scene entity slot) of the primitive.
    pub owner: u32,
}

/// Spheres in SoA form.
#[derive(Clone, Debug, Default)]
pub struct SphereSoa {
    /// Centre x per sphere.
    pub cx: Vec<f32>,
    /// Centre y per sphere.
    pub cy: Vec<f32>,
    /// Centre z per sphere.
    pub cz: Vec<f32>,
    /// Radius per sphere.
    pub r: Vec<f32>,
}

impl SphereSoa {
    /// Centre and radius of sphere `i`.
    #[inline(always)]
    pub fn get(&self, i: usize) -> (Vec3, f32) {
        (Vec3::new(self.cx[i], self.cy[i], self.cz[i]), self.r[i])
    }

    fn push(&mut self, c: Vec3, r: f32) {
        self.cx.push(c.x);
        self.cy.push(c.y);
        self.cz.push(c.z);
        self.r.push(r);
    }
}

/// Triangles in SoA form: one array per vertex coordinate.
#[derive(Clone, Debug, Default)]
pub struct TriangleSoa {
    /// `v[3 * k + axis]` holds coordinate `axis` of vertex `k` of every triangle.
    pub v: [Vec<f32>; 9],
}

impl TriangleSoa {
    /// Vertices of triangle `i`.
    #[inline(always)]
    pub fn get(&self, i: usize) -> [Vec3; 3] {
        let v = &self.v;
        [
            Vec3::new(v[0][i], v[1][i], v[2][i]),
            Vec3::new(v[3][i], v[4][i], v[5][i]),
            Vec3::new(v[6][i], v[7][i], v[8][i]),
        ]
    }

    fn push(&mut self, p: [Vec3; 3]) {
        for (k, vertex) in p.iter().enumerate() {
            for axis in 0..3 {
                self.v[3 * k + axis].push(vertex[axis]);
            }
        }
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.v[0].len()
    }

    /// Whether there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
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

/// All geometry of a scene, packed for tracing. Built from [`Primitive`]s with their owners.
#[derive(Clone, Default)]
pub struct Geometry {
    /// Sphere data in BVH order.
    pub spheres: SphereSoa,
    /// Owner slot per sphere.
    pub sphere_owner: Vec<u32>,
    /// Object-to-world rotation per sphere (for texture coordinates).
    pub sphere_frame: Vec<Mat3>,
    /// BVH over the spheres.
    pub sphere_bvh: Bvh,
    /// Triangle data in BVH order.
    pub triangles: TriangleSoa,
    /// Owner slot per triangle.
    pub triangle_owner: Vec<u32>,
    /// Texture coordinates per triangle vertex.
    pub triangle_uv: Vec<[Vec2; 3]>,
    /// BVH over the triangles.
    pub triangle_bvh: Bvh,
    /// Infinite planes.
    pub planes: Vec<PlaneRecord>,
}

impl Geometry {
    /// Packs `(owner, primitive)` pairs: builds the BVHs and lays out the arrays in BVH order.
    pub fn build(primitives: &[(u32, Primitive)]) -> Self {
        let mut spheres = Vec::new();
        let mut triangles = Vec::new();
        let mut planes = Vec::new();
        for (owner, prim) in primitives {
            match *prim {
                Primitive::Sphere {
                    center,
                    radius,
                    frame,
                } => {
                    spheres.push((*owner, center, radius, frame));
                }
                Primitive::Triangle { p, uv } => triangles.push((*owner, p, uv)),
                Primitive::Plane { point, normal } => {
                    let (tangent, bitangent) = normal.any_orthonormal_pair();
                    planes.push(PlaneRecord {
                        point,
                        normal,
                        tangent,
                        bitangent,
                        owner: *owner,
                    });
                }
            }
        }

        let bounds: Vec<Bounds> = spheres
            .iter()
            .map(|&(_, c, r, _)| (c - Vec3::splat(r), c + Vec3::splat(r)))
            .collect();
        let (sphere_bvh, order) = Bvh::build(&bounds);
        let mut geometry = Geometry {
            sphere_bvh,
            planes,
            ..Default::default()
        };
        for &i in &order {
            let (owner, c, r, frame) = spheres[i as usize];
            geometry.spheres.push(c, r);
            geometry.sphere_owner.push(owner);
            geometry.sphere_frame.push(frame);
        }

        let bounds: Vec<Bounds> = triangles
            .iter()
            .map(|(_, p, _)| (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2])))
            .collect();
        let (triangle_bvh, order) = Bvh::build(&bounds);
        geometry.triangle_bvh = triangle_bvh;
        for &i in &order {
            let (owner, p, uv) = triangles[i as usize];
            geometry.triangles.push(p);
            geometry.triangle_owner.push(owner);
            geometry.triangle_uv.push(uv);
        }
        geometry
    }

    /// Number of primitives of every kind.
    pub fn primitive_count(&self) -> usize {
        self.sphere_owner.len() + self.triangle_owner.len() + self.planes.len()
    }

    /// The closest hit along `ray` closer than `t_max`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        let q = RayQuery::new(*ray);
        let mut best: Option<Hit> = None;
        let mut t_best = t_max;
        if !self.sphere_owner.is_empty() {
            self.sphere_bvh.traverse(&q, &mut t_best, |range, t_best| {
                for i in range {
                    let (c, r) = self.spheres.get(i);
                    if let Some(t) = intersect_sphere(ray, c, r, *t_best) {
                        *t_best = t;
                        best = Some(Hit {
                            t,
                            kind: HitKind::Sphere,
                            index: i as u32,
                            b1: 0.0,
                            b2: 0.0,
                        });
                    }
                }
                true
            });
        }
        if !self.triangles.is_empty() {
            self.triangle_bvh
                .traverse(&q, &mut t_best, |range, t_best| {
                    for i in range {
                        let [p0, p1, p2] = self.triangles.get(i);
                        if let Some(h) = intersect_triangle(&q, p0, p1, p2, *t_best) {
                            *t_best = h.t;
                            best = Some(Hit {
                                t: h.t,
                                kind: HitKind::Triangle,
                                index: i as u32,
                                b1: h.b1,
                                b2: h.b2,
                            });
                        }
                    }
                    true
                });
        }
        for (i, plane) in self.planes.iter().enumerate() {
            if let Some(t) = intersect_plane(ray, plane.point, plane.normal, t_best) {
                t_best = t;
                best = Some(Hit {
                    t,
                    kind: HitKind::Plane,
                    index: i as u32,
                    b1: 0.0,
                    b2: 0.0,
                });
            }
        }
        best
    }

    /// Whether anything blocks `ray` before `t_max`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        let q = RayQuery::new(*ray);
        let mut blocked = false;
        let mut t = t_max;
        self.sphere_bvh.traverse(&q, &mut t, |range, t| {
            blocked = range.into_iter().any(|i| {
                let (c, r) = self.spheres.get(i);
                intersect_sphere(ray, c, r, *t).is_some()
            });
            !blocked
        });
        if blocked {
            return true;
        }
        self.triangle_bvh.traverse(&q, &mut t, |range, t| {
            blocked = range.into_iter().any(|i| {
                let [p0, p1, p2] = self.triangles.get(i);
                intersect_triangle(&q, p0, p1, p2, *t).is_some()
            });
            !blocked
        });
        blocked
            || self
                .planes
                .iter()
                .any(|pl| intersect_plane(ray, pl.point, pl.normal, t_max).is_some())
    }

    /// The closest hit by testing every primitive, without the BVHs: the oracle for tests.
    pub fn intersect_brute_force(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        let q = RayQuery::new(*ray);
        let mut best: Option<Hit> = None;
        let mut t_best = t_max;
        for i in 0..self.sphere_owner.len() {
            let (c, r) = self.spheres.get(i);
            if let Some(t) = intersect_sphere(ray, c, r, t_best) {
                t_best = t;
                best = Some(Hit {
                    t,
                    kind: HitKind::Sphere,
                    index: i as u32,
                    b1: 0.0,
                    b2: 0.0,
                });
            }
        }
        for i in 0..self.triangles.len() {
            let [p0, p1, p2] = self.triangles.get(i);
            if let Some(h) = intersect_triangle(&q, p0, p1, p2, t_best) {
                t_best = h.t;
                best = Some(Hit {
                    t: h.t,
                    kind: HitKind::Triangle,
                    index: i as u32,
                    b1: h.b1,
                    b2: h.b2,
                });
            }
        }
        for (i, plane) in self.planes.iter().enumerate() {
            if let Some(t) = intersect_plane(ray, plane.point, plane.normal, t_best) {
                t_best = t;
                best = Some(Hit {
                    t,
                    kind: HitKind::Plane,
                    index: i as u32,
                    b1: 0.0,
                    b2: 0.0,
                });
            }
        }
        best
    }

    /// Local geometry at `hit`.
    #[inline]
    pub fn surface(&self, ray: &Ray, hit: &Hit) -> Surface {
        let i = hit.index as usize;
        match hit.kind {
            HitKind::Sphere => {
                let (c, r) = self.spheres.get(i);
                // Re-project onto the sphere: removes most of the error of o + t·d.
                let n = (ray.at(hit.t) - c).normalize();
                let uv = sphere_uv(self.sphere_frame[i].transpose() * n);
                Surface {
                    p: c + r * n,
                    n,
                    uv,
                    owner: self.sphere_owner[i],
                }
            }
            HitKind::Triangle => {
                let [p0, p1, p2] = self.triangles.get(i);
                let b0 = 1.0 - hit.b1 - hit.b2;
                let [t0, t1, t2] = self.triangle_uv[i];
                Surface {
                    p: b0 * p0 + hit.b1 * p1 + hit.b2 * p2,
                    n: (p1 - p0).cross(p2 - p0).normalize(),
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
                    uv: plane_uv(p, pl.point, pl.tangent, pl.bitangent),
                    owner: pl.owner,
                }
            }
        }
    }
}
