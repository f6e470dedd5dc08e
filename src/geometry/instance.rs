//! Instanced meshes: one BVH per distinct mesh in object space (a bottom-level BVH), shared by
//! every placement, and a top-level BVH over the placements' world bounds. A ray reaching an
//! instance is moved into its object space and tested against the shared triangles, so placing a
//! mesh N times costs N transforms, not N copies of its triangles.

use std::collections::HashMap;
use std::sync::Arc;

use std::ops::Range;

use glam::{Affine3A, Vec2, Vec3};

use super::aabb::RayQuery;
use super::bvh::{Bounds, Bvh, EMPTY, triangle_bounds, union};
use super::ray::{Ray, gamma};
use super::surface::{Surface, Tangent, uv_derivatives};
use super::triangle::intersect_triangle;
use crate::cpu::{Lanes, Sse};
use crate::model::MeshData;

/// A mesh's triangles in object space, in BVH order, with their BVH. Compared by identity: two
/// placements are of the same mesh when they share one `MeshBlas`.
#[derive(Clone, Default)]
pub struct MeshBlas {
    triangles: Vec<[Vec3; 3]>,
    /// Vertex normals per triangle (BVH order), when the mesh file has them.
    normals: Option<Vec<[Vec3; 3]>>,
    /// Texture coordinates per triangle vertex (BVH order), when the mesh file has them.
    uvs: Option<Vec<[Vec2; 3]>>,
    /// The second set of texture coordinates per triangle vertex (BVH order), when the mesh
    /// carries one.
    uvs1: Option<Vec<[Vec2; 3]>>,
    bvh: Bvh,
    bounds: Bounds,
}

impl PartialEq for MeshBlas {
    fn eq(&self, other: &Self) -> bool {
        std::ptr::eq(self, other)
    }
}

impl std::fmt::Debug for MeshBlas {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "MeshBlas({} triangles)", self.triangles.len())
    }
}

impl MeshBlas {
    /// Builds the BVH of a mesh. The gathers around the build are maps in parallel: the same
    /// result for any thread count. The triangles' corners are gathered once, in BVH order.
    pub fn build(mesh: &MeshData) -> Self {
        use rayon::prelude::*;
        let corners = |t: &[u32; 3]| t.map(|i| mesh.positions[i as usize]);
        let bounds: Vec<Bounds> = mesh
            .triangles
            .par_iter()
            .map(|t| triangle_bounds(corners(t)))
            .collect();
        let (bvh, order) = Bvh::build(&bounds);
        let all = bounds.iter().fold(EMPTY, |all, &b| union(all, b));
        let normals = mesh.normals.as_ref().map(|n| {
            order
                .par_iter()
                .map(|&k| mesh.triangles[k as usize].map(|v| n[v as usize]))
                .collect()
        });
        let corner_uvs = |t: &Vec<Vec2>| {
            order
                .par_iter()
                .map(|&k| mesh.triangles[k as usize].map(|v| t[v as usize]))
                .collect()
        };
        let uvs = mesh.uvs.as_ref().map(corner_uvs);
        let uvs1 = mesh.uvs1.as_ref().map(corner_uvs);
        Self {
            triangles: order
                .par_iter()
                .map(|&k| corners(&mesh.triangles[k as usize]))
                .collect(),
            normals,
            uvs,
            uvs1,
            bvh,
            bounds: all,
        }
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// Whether the mesh has no triangles.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }
}

/// Bottom-level BVHs by mesh, kept across geometry rebuilds: an unchanged mesh file keeps its
/// `Arc<MeshData>`, so its BVH is reused; only new or edited meshes are built.
#[derive(Default)]
pub struct BlasCache {
    entries: HashMap<usize, (Arc<MeshData>, Arc<MeshBlas>)>,
    builds: u64,
}

impl BlasCache {
    /// The BVH for `mesh`, built now if this exact mesh data has none yet.
    pub fn get(&mut self, mesh: &Arc<MeshData>) -> Arc<MeshBlas> {
        let key = Arc::as_ptr(mesh) as usize;
        if let Some((data, blas)) = self.entries.get(&key)
            && Arc::ptr_eq(data, mesh)
        {
            return blas.clone();
        }
        let blas = Arc::new(MeshBlas::build(mesh));
        self.builds += 1;
        self.entries.insert(key, (mesh.clone(), blas.clone()));
        blas
    }

    /// Drops the BVHs of meshes no longer used by `live`.
    pub fn retain(&mut self, live: &[Arc<MeshData>]) {
        let keep: std::collections::HashSet<usize> =
            live.iter().map(|m| Arc::as_ptr(m) as usize).collect();
        self.entries.retain(|k, _| keep.contains(k));
    }

    /// Bottom-level BVH builds so far.
    pub fn builds(&self) -> u64 {
        self.builds
    }
}

/// One placement of a mesh.
#[derive(Clone)]
pub struct Instance {
    /// The shared mesh BVH.
    pub blas: Arc<MeshBlas>,
    /// Object to world.
    pub world_from_object: Affine3A,
    /// World to object.
    pub object_from_world: Affine3A,
    /// Owner slot (scene entity).
    pub owner: u32,
}

/// A hit on an instanced triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InstanceHit {
    /// Distance along the world ray.
    pub t: f32,
    /// Instance slot (top-level BVH order).
    pub instance: u32,
    /// Triangle slot within the instance's mesh.
    pub triangle: u32,
    /// Barycentric weight of the triangle's second vertex.
    pub b1: f32,
    /// Barycentric weight of the triangle's third vertex.
    pub b2: f32,
}

/// All instances of a scene with their top-level BVH.
#[derive(Clone, Default)]
pub struct InstanceSet {
    instances: Vec<Instance>,
    tlas: Bvh,
}

/// World bounds of an object-space box under `m`: the box of its eight transformed corners.
fn transform_bounds(m: &Affine3A, (lo, hi): Bounds) -> Bounds {
    let mut out = EMPTY;
    for k in 0..8 {
        let c = Vec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        );
        let w = m.transform_point3(c);
        out = (out.0.min(w), out.1.max(w));
    }
    // Widen by the rounding of the transform so a grazing ray cannot miss the instance.
    let pad = gamma(4.0) * (out.0.abs().max(out.1.abs()));
    (out.0 - pad, out.1 + pad)
}

impl InstanceSet {
    /// Builds the top-level BVH over `(owner, mesh, world_from_object)` placements.
    pub fn build(placements: Vec<(u32, Arc<MeshBlas>, Affine3A)>) -> Self {
        let placements: Vec<_> = placements.into_iter().filter(|p| !p.1.is_empty()).collect();
        let bounds: Vec<Bounds> = placements
            .iter()
            .map(|(_, b, m)| transform_bounds(m, b.bounds))
            .collect();
        let (tlas, order) = Bvh::build(&bounds);
        let instances = order
            .iter()
            .map(|&i| {
                let (owner, blas, m) = &placements[i as usize];
                Instance {
                    blas: blas.clone(),
                    world_from_object: *m,
                    object_from_world: m.inverse(),
                    owner: *owner,
                }
            })
            .collect();
        Self { instances, tlas }
    }

    /// Number of instances.
    pub fn len(&self) -> usize {
        self.instances.len()
    }

    /// Whether there are no instances.
    pub fn is_empty(&self) -> bool {
        self.instances.is_empty()
    }

    /// The box around every instance, or `None` if there are none.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        self.tlas.bounds()
    }

    /// The instance in slot `i`.
    pub fn get(&self, i: usize) -> &Instance {
        &self.instances[i]
    }

    /// The vertices of `triangle` of instance `instance` in world space.
    #[inline]
    pub fn world_triangle(&self, instance: u32, triangle: u32) -> [Vec3; 3] {
        let inst = &self.instances[instance as usize];
        inst.blas.triangles[triangle as usize].map(|v| inst.world_from_object.transform_point3(v))
    }

    /// The world ray in an instance's object space, with a unit direction (the triangle test's
    /// error bound assumes one), and the factor `s` that turns world distances into object
    /// distances: `t_object = s · t_world`.
    #[inline]
    fn object_query(inst: &Instance, ray: &Ray) -> (RayQuery, f32) {
        let m = &inst.object_from_world;
        let d = m.transform_vector3(ray.direction);
        let s = d.length();
        let q = RayQuery::new(Ray {
            origin: m.transform_point3(ray.origin),
            direction: d / s,
        });
        (q, s)
    }

    /// The closest instanced triangle hit before `t_max` ([`InstanceSet::intersect_with`] with
    /// four lanes).
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<InstanceHit> {
        self.intersect_with(Sse, ray, t_max)
    }

    /// Whether any instance blocks `ray` before `t_max` ([`InstanceSet::occluded_with`] with
    /// four lanes).
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        self.occluded_with(Sse, ray, t_max)
    }

    /// The closest instanced triangle hit before `t_max`, with box tests as wide as `lanes`,
    /// out of line but compiled for the instruction set of `lanes` ([`Lanes::out_of_line`]): a
    /// scene without instances pays only for the emptiness test.
    #[inline(always)]
    pub fn intersect_with<W: Lanes>(&self, lanes: W, ray: &Ray, t_max: f32) -> Option<InstanceHit> {
        if self.instances.is_empty() {
            return None;
        }
        lanes.out_of_line(
            #[inline(always)]
            |lanes| self.intersect_instances(lanes, ray, t_max),
        )
    }

    /// [`InstanceSet::intersect`] for a non-empty set.
    #[inline(always)]
    fn intersect_instances<W: Lanes>(
        &self,
        lanes: W,
        ray: &Ray,
        t_max: f32,
    ) -> Option<InstanceHit> {
        let world = RayQuery::new(*ray);
        let mut best = None;
        let mut t_best = t_max;
        self.tlas.traverse_leaves(
            lanes,
            &world,
            &mut t_best,
            #[inline(always)]
            |range: Range<usize>, t_best: &mut f32| {
                for i in range {
                    let inst = &self.instances[i];
                    let (q, s) = Self::object_query(inst, ray);
                    let mut t_object = *t_best * s;
                    inst.blas.bvh.traverse_leaves(
                        lanes,
                        &q,
                        &mut t_object,
                        #[inline(always)]
                        |tris: Range<usize>, t_object: &mut f32| {
                            for k in tris {
                                let [a, b, c] = inst.blas.triangles[k];
                                if let Some(h) = intersect_triangle(&q, a, b, c, *t_object) {
                                    *t_object = h.t;
                                    let t = h.t / s;
                                    if t < *t_best {
                                        *t_best = t;
                                        best = Some(InstanceHit {
                                            t,
                                            instance: i as u32,
                                            triangle: k as u32,
                                            b1: h.b1,
                                            b2: h.b2,
                                        });
                                    }
                                }
                            }
                            true
                        },
                    );
                }
                true
            },
        );
        best
    }

    /// Whether any instance blocks `ray` before `t_max` (out of line, as
    /// [`InstanceSet::intersect_with`]).
    #[inline(always)]
    pub fn occluded_with<W: Lanes>(&self, lanes: W, ray: &Ray, t_max: f32) -> bool {
        if self.instances.is_empty() {
            return false;
        }
        lanes.out_of_line(
            #[inline(always)]
            |lanes| self.occluded_instances(lanes, ray, t_max),
        )
    }

    /// [`InstanceSet::occluded`] for a non-empty set.
    #[inline(always)]
    fn occluded_instances<W: Lanes>(&self, lanes: W, ray: &Ray, t_max: f32) -> bool {
        let world = RayQuery::new(*ray);
        let mut blocked = false;
        let mut t = t_max;
        self.tlas.traverse_any_leaves(
            lanes,
            &world,
            &mut t,
            #[inline(always)]
            |range: Range<usize>, t: &mut f32| {
                for i in range {
                    let inst = &self.instances[i];
                    let (q, s) = Self::object_query(inst, ray);
                    let mut t_object = *t * s;
                    inst.blas.bvh.traverse_any_leaves(
                        lanes,
                        &q,
                        &mut t_object,
                        #[inline(always)]
                        |tris: Range<usize>, t_object: &mut f32| {
                            // A loop, not `Iterator::any`, whose `try_fold` would stay out
                            // of line (see `simd::any_sphere`).
                            for k in tris {
                                let [a, b, c] = inst.blas.triangles[k];
                                if intersect_triangle(&q, a, b, c, *t_object).is_some() {
                                    blocked = true;
                                    return false;
                                }
                            }
                            true
                        },
                    );
                    if blocked {
                        return false;
                    }
                }
                true
            },
        );
        blocked
    }

    /// Local geometry of a hit on `triangle` of instance `instance` with barycentrics
    /// `(b1, b2)`. The point is interpolated in object space and transformed; normals go through
    /// the inverse transpose. The shading normal interpolates the mesh's vertex normals (when
    /// it has them), turned to the side of the geometric normal; texture coordinates interpolate
    /// the mesh's (0 when it has none).
    #[inline]
    pub fn surface(&self, instance: u32, triangle: u32, b1: f32, b2: f32) -> Surface {
        let inst = &self.instances[instance as usize];
        let k = triangle as usize;
        let [a, b, c] = inst.blas.triangles[k];
        let b0 = 1.0 - b1 - b2;
        let p_obj = b0 * a + b1 * b + b2 * c;
        let normal_to_world = |v: Vec3| -> Vec3 {
            (inst.object_from_world.matrix3.transpose() * glam::Vec3A::from(v))
                .normalize_or_zero()
                .into()
        };
        let n = normal_to_world((b - a).cross(c - a));
        let ns = inst
            .blas
            .normals
            .as_ref()
            .map(|normals| {
                let [na, nb, nc] = normals[k];
                normal_to_world(b0 * na + b1 * nb + b2 * nc)
            })
            .filter(|ns| *ns != Vec3::ZERO)
            .map_or(n, |ns| if ns.dot(n) < 0.0 { -ns } else { ns });
        let at = |uvs: &Vec<[Vec2; 3]>| {
            let [ta, tb, tc] = uvs[k];
            b0 * ta + b1 * tb + b2 * tc
        };
        let uv = inst.blas.uvs.as_ref().map_or(Vec2::ZERO, at);
        let uv1 = inst.blas.uvs1.as_ref().map_or(uv, at);
        Surface {
            p: inst.world_from_object.transform_point3(p_obj),
            n,
            ns,
            uv,
            uv1,
            owner: inst.owner,
        }
    }

    /// The texture-space tangent frame of `triangle` of instance `instance` (see
    /// [`Tangent`]): the object-space derivatives carried to world space by the placement's
    /// linear part (they are tangent vectors), the handedness taken against the world normal
    /// [`InstanceSet::surface`] reports, so a mirroring placement flips it. `None` for a mesh
    /// without texture coordinates or a degenerate triangle of them.
    pub fn uv_tangent(&self, instance: u32, triangle: u32) -> Option<Tangent> {
        let inst = &self.instances[instance as usize];
        let k = triangle as usize;
        let uv = inst.blas.uvs.as_ref()?[k];
        let [a, b, c] = inst.blas.triangles[k];
        let (dpdu, dpdv) = uv_derivatives([a, b, c], uv)?;
        let m = &inst.world_from_object;
        let n =
            inst.object_from_world.matrix3.transpose() * glam::Vec3A::from((b - a).cross(c - a));
        Tangent::from_derivatives(
            m.transform_vector3(dpdu),
            m.transform_vector3(dpdv),
            n.into(),
        )
    }

    /// Absolute error bound of the world-space point [`InstanceSet::surface`] returns: the
    /// interpolation's bound carried through the transform, plus the transform's own rounding
    /// (pbrt-v4, Section 6.8.6).
    #[inline]
    pub fn point_error(&self, instance: u32, triangle: u32, b1: f32, b2: f32) -> Vec3 {
        let inst = &self.instances[instance as usize];
        let [a, b, c] = inst.blas.triangles[triangle as usize];
        let b0 = 1.0 - b1 - b2;
        let p_obj = b0 * a + b1 * b + b2 * c;
        let err_obj = gamma(7.0) * ((b0 * a).abs() + (b1 * b).abs() + (b2 * c).abs());
        let m = &inst.world_from_object;
        let abs_m = glam::Mat3::from_cols(
            m.matrix3.x_axis.abs().into(),
            m.matrix3.y_axis.abs().into(),
            m.matrix3.z_axis.abs().into(),
        );
        abs_m * (err_obj + gamma(3.0) * p_obj.abs()) + gamma(3.0) * Vec3::from(m.translation).abs()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::rng::Rng;

    fn grid_mesh(n: usize) -> MeshData {
        // An n×n grid of quads in the unit square, z = 0.
        let mut mesh = MeshData::default();
        for j in 0..=n {
            for i in 0..=n {
                mesh.positions
                    .push(Vec3::new(i as f32 / n as f32, j as f32 / n as f32, 0.0));
            }
        }
        let idx = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        for j in 0..n {
            for i in 0..n {
                mesh.triangles
                    .push([idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)]);
                mesh.triangles
                    .push([idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)]);
            }
        }
        mesh
    }

    #[test]
    fn instanced_hits_match_world_space_triangles() {
        let mesh = Arc::new(grid_mesh(4));
        let mut cache = BlasCache::default();
        let blas = cache.get(&mesh);
        let placements: Vec<Affine3A> = (0..5)
            .map(|k| {
                Affine3A::from_scale_rotation_translation(
                    Vec3::splat(1.0 + k as f32 * 0.5),
                    glam::Quat::from_rotation_y(0.3 * k as f32),
                    Vec3::new(3.0 * k as f32, 0.0, 2.0),
                )
            })
            .collect();
        let set = InstanceSet::build(
            placements
                .iter()
                .enumerate()
                .map(|(k, m)| (k as u32, blas.clone(), *m))
                .collect(),
        );
        assert_eq!(cache.get(&mesh).len(), 32);
        assert_eq!(cache.builds(), 1, "one BVH for five placements");

        let mut world: Vec<(u32, [Vec3; 3])> = Vec::new();
        for (k, m) in placements.iter().enumerate() {
            for t in &mesh.triangles {
                world.push((
                    k as u32,
                    t.map(|i| m.transform_point3(mesh.positions[i as usize])),
                ));
            }
        }
        let mut rng = Rng::new(3, 3);
        let (mut hits, mut mismatches) = (0, 0);
        for _ in 0..4000 {
            let o = Vec3::new(
                rng.next_f32() * 16.0 - 2.0,
                rng.next_f32() * 4.0 - 2.0,
                -3.0,
            );
            let target = Vec3::new(
                rng.next_f32() * 16.0 - 2.0,
                rng.next_f32() * 4.0 - 2.0,
                2.0 + rng.next_f32(),
            );
            let ray = Ray::new(o, (target - o).normalize());
            let q = RayQuery::new(ray);
            let brute = world
                .iter()
                .filter_map(|(k, [a, b, c])| {
                    intersect_triangle(&q, *a, *b, *c, f32::INFINITY).map(|h| (h.t, *k))
                })
                .min_by(|x, y| x.0.total_cmp(&y.0));
            let fast = set.intersect(&ray, f32::INFINITY);
            match (brute, fast) {
                (None, None) => {}
                (Some((t, owner)), Some(h)) => {
                    hits += 1;
                    assert!((t - h.t).abs() <= 1e-4 * t, "{t} vs {}", h.t);
                    let s = set.surface(h.instance, h.triangle, h.b1, h.b2);
                    assert_eq!(owner, s.owner);
                    assert!((s.p - ray.at(t)).length() < 1e-3);
                    assert_eq!(s.ns, s.n, "a mesh without vertex normals shades flat");
                    assert!(
                        set.point_error(h.instance, h.triangle, h.b1, h.b2)
                            .max_element()
                            > 0.0
                    );
                    assert!(set.occluded(&ray, f32::INFINITY));
                }
                // A ray grazing an edge may round differently in object space; allow a few.
                _ => mismatches += 1,
            }
        }
        assert!(hits > 500, "{hits}");
        assert!(mismatches <= 4, "{mismatches} of 4000 rays disagree");
    }
}
