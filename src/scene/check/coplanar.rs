//! The coplanar-overlap rule of `rondo check` ([`super::WarningKind::CoplanarOverlap`]): which
//! planar pieces of different entities lie in one plane and overlap, found through a multi-level
//! grid.

use std::collections::{BTreeSet, HashMap};
use std::hash::{BuildHasherDefault, Hasher};

use glam::{Vec2, Vec3};

use crate::geometry::packed::Primitive;
use crate::geometry::world::world_primitives;
use crate::model::Shape;
use crate::scene::load::LoadedScene;
use crate::shading::material::Material;

/// Tolerance of [`WarningKind::CoplanarOverlap`](super::WarningKind::CoplanarOverlap), relative
/// to the larger surface's size.
pub const COPLANAR_TOLERANCE: f32 = 1e-5;
/// Mesh triangles, summed over placements, that
/// [`WarningKind::CoplanarOverlap`](super::WarningKind::CoplanarOverlap) compares.
pub const MESH_TRIANGLE_BUDGET: usize = 1 << 20;

/// A planar piece of an entity: a triangle, or an infinite plane (`None` vertices).
pub(super) struct Flat {
    pub(super) entity: usize,
    pub(super) normal: Vec3,
    pub(super) point: Vec3,
    pub(super) vertices: Option<[Vec3; 3]>,
}

impl Flat {
    /// Longest edge (0 for a plane).
    fn size(&self) -> f32 {
        self.vertices.map_or(0.0, |[a, b, c]| {
            (a - b).length().max((b - c).length()).max((c - a).length())
        })
    }

    /// Largest coordinate magnitude.
    fn magnitude(&self) -> f32 {
        match self.vertices {
            Some([a, b, c]) => a.abs().max(b.abs()).max(c.abs()).max_element(),
            None => self.point.abs().max_element(),
        }
    }

    /// Distance within which another surface counts as lying in this one's plane.
    pub(super) fn tolerance(&self, other: &Flat) -> f32 {
        let step = 8.0 * f32::EPSILON * self.magnitude().max(other.magnitude());
        (COPLANAR_TOLERANCE * self.size().max(other.size())).max(step)
    }

    /// A triangle's bounding box grown by its own share of [`Self::tolerance`]: the pair's
    /// tolerance is at most the larger share, so two pieces that overlap within it have
    /// intersecting grown boxes.
    fn grown_box(&self) -> Option<(Vec3, Vec3)> {
        let [a, b, c] = self.vertices?;
        let own = (COPLANAR_TOLERANCE * self.size()).max(8.0 * f32::EPSILON * self.magnitude());
        Some((a.min(b).min(c) - own, a.max(b).max(c) + own))
    }

    /// Whether every vertex of `other` (its point, for a plane) lies within `tol` of this plane.
    pub(super) fn holds(&self, other: &Flat, tol: f32) -> bool {
        let off = |p: Vec3| (p - self.point).dot(self.normal).abs() <= tol;
        match other.vertices {
            Some(v) => v.iter().all(|&p| off(p)),
            None => off(other.point),
        }
    }
}

/// Whether two coplanar triangles overlap with positive area: no edge direction of either
/// separates their projections onto the plane (the separating axis theorem), with a margin of
/// `tol` so that triangles that only share an edge or a corner do not count.
pub(super) fn triangles_overlap(a: [Vec3; 3], b: [Vec3; 3], normal: Vec3, tol: f32) -> bool {
    let (s, t) = normal.any_orthonormal_pair();
    let flat = |p: [Vec3; 3]| p.map(|v| Vec2::new(v.dot(s), v.dot(t)));
    let (a, b) = (flat(a), flat(b));
    let separated_by = |edge: Vec2| {
        let axis = edge.perp().normalize_or_zero();
        if axis == Vec2::ZERO {
            return false;
        }
        let range = |p: &[Vec2; 3]| {
            let d = p.map(|v| v.dot(axis));
            (d[0].min(d[1]).min(d[2]), d[0].max(d[1]).max(d[2]))
        };
        let ((a0, a1), (b0, b1)) = (range(&a), range(&b));
        a1 <= b0 + tol || b1 <= a0 + tol
    };
    let edges = |p: &[Vec2; 3]| [p[1] - p[0], p[2] - p[1], p[0] - p[2]];
    !edges(&a).into_iter().chain(edges(&b)).any(separated_by)
}

/// The entity pairs of [`WarningKind::CoplanarOverlap`](super::WarningKind::CoplanarOverlap).
/// Triangles are found through a multi-level grid (a "loose" grid: each grown box is filed once,
/// by its centre, at the level whose cells are at least 1.25 times its extent), so a triangle is
/// compared only with triangles in the 27 cells around it on its own and coarser levels: linear
/// in the scene for pieces of any sizes. Infinite planes are compared with every piece of a
/// near-parallel normal (planes are few). Returns the pairs of entities `(a, b)`, `a < b`, and
/// the number of pairs compared.
pub(super) fn coplanar_pairs(scene: &LoadedScene) -> (BTreeSet<(usize, usize)>, u64) {
    let mut flats = Vec::new();
    let mut budget = MESH_TRIANGLE_BUDGET;
    for (entity, e) in scene.entities.iter().enumerate() {
        if let Shape::Mesh(m) = &e.shape {
            if m.data.triangles.len() > budget {
                continue;
            }
            budget -= m.data.triangles.len();
        }
        for prim in world_primitives(&e.shape, &e.transform) {
            match prim {
                Primitive::Triangle { p, .. } => {
                    let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
                    if n != Vec3::ZERO {
                        flats.push(Flat {
                            entity,
                            normal: n,
                            point: p[0],
                            vertices: Some(p),
                        });
                    }
                }
                Primitive::Plane { point, normal } => {
                    flats.push(Flat {
                        entity,
                        normal,
                        point,
                        vertices: None,
                    });
                }
                Primitive::Sphere { .. } | Primitive::Instance { .. } => {}
            }
        }
    }
    let see_through = |entity: usize| {
        matches!(
            scene.materials.get(&scene.entities[entity].material),
            Some(Material::Dielectric { .. } | Material::Transmissive { .. })
        )
    };
    let mut pairs = BTreeSet::new();
    let mut comparisons = 0u64;
    let mut compare = |f: &Flat, g: &Flat| {
        if g.entity == f.entity {
            return;
        }
        let pair = (f.entity.min(g.entity), f.entity.max(g.entity));
        if pairs.contains(&pair) || f.normal.dot(g.normal).abs() < 1.0 - 1e-6 {
            return;
        }
        let seen = f.normal.dot(g.normal) > 0.0 || see_through(f.entity) || see_through(g.entity);
        if !seen {
            return;
        }
        let tol = f.tolerance(g);
        if !(f.holds(g, tol) && g.holds(f, tol)) {
            return;
        }
        let overlap = match (f.vertices, g.vertices) {
            (Some(a), Some(b)) => triangles_overlap(a, b, f.normal, tol),
            _ => true,
        };
        if overlap {
            pairs.insert(pair);
        }
    };

    // Planes against everything of a near-parallel normal: pieces are bucketed by their
    // quantised normal, a normal and its opposite folded together (27 neighbouring buckets).
    let key = |n: Vec3| {
        let n = if n.x < 0.0 || (n.x == 0.0 && (n.y < 0.0 || (n.y == 0.0 && n.z < 0.0))) {
            -n
        } else {
            n
        };
        (n * 1000.0).round().as_ivec3()
    };
    if flats.iter().any(|f| f.vertices.is_none()) {
        let mut buckets: HashMap<glam::IVec3, Vec<usize>> = HashMap::new();
        for (i, f) in flats.iter().enumerate() {
            buckets.entry(key(f.normal)).or_default().push(i);
        }
        for (i, f) in flats
            .iter()
            .enumerate()
            .filter(|(_, f)| f.vertices.is_none())
        {
            for k in [key(f.normal), key(-f.normal)] {
                for d in NEIGHBOURS {
                    for &j in buckets
                        .get(&(k + glam::IVec3::from(d)))
                        .into_iter()
                        .flatten()
                    {
                        // A plane pair is met from both planes: compare it once.
                        if flats[j].vertices.is_some() || j > i {
                            comparisons += 1;
                            compare(&flats[i.min(j)], &flats[i.max(j)]);
                        }
                    }
                }
            }
        }
    }

    // Triangles against triangles, through the grid. Cells are at least 2.5 times the
    // extent of what they hold, so the centres of two overlapping boxes are less than 0.4 cell
    // apart on every axis: 2 cells per axis (the centre's and the nearer neighbour) hold every
    // candidate.
    let boxes: Vec<Option<(Vec3, Vec3)>> = flats.iter().map(Flat::grown_box).collect();
    let level_of =
        |(lo, hi): (Vec3, Vec3)| (2.5 * f64::from((hi - lo).max_element())).log2().ceil() as i32;
    let centre_in =
        |(lo, hi): (Vec3, Vec3), level: i32| (lo + hi).as_dvec3() * 0.5 / f64::from(level).exp2();
    let mut grid: HashMap<(i32, [i64; 3]), Vec<usize>, BuildHasherDefault<CellHasher>> =
        HashMap::default();
    let mut levels = BTreeSet::new();
    for (i, b) in boxes.iter().enumerate() {
        if let Some(b) = *b {
            let level = level_of(b);
            levels.insert(level);
            let c = centre_in(b, level).floor().as_i64vec3().to_array();
            grid.entry((level, c)).or_default().push(i);
        }
    }
    for (i, b) in boxes.iter().enumerate() {
        let Some(b) = *b else { continue };
        let own = level_of(b);
        for &level in levels.range(own..) {
            let c = centre_in(b, level);
            let cell = c.floor();
            let side = (c - cell).cmpge(glam::DVec3::splat(0.5));
            let cell = cell.as_i64vec3();
            let near = glam::I64Vec3::select(side, cell + 1, cell - 1);
            for k in 0..8 {
                let pick = glam::BVec3::new(k & 1 != 0, k & 2 != 0, k & 4 != 0);
                let key = (level, glam::I64Vec3::select(pick, near, cell).to_array());
                for &j in grid.get(&key).into_iter().flatten() {
                    // A pair on one level is met from both sides: compare it once.
                    if level == own && j <= i {
                        continue;
                    }
                    comparisons += 1;
                    let Some((lo, hi)) = boxes[j] else { continue };
                    if lo.cmple(b.1).all() && b.0.cmple(hi).all() {
                        compare(&flats[i.min(j)], &flats[i.max(j)]);
                    }
                }
            }
        }
    }
    (pairs, comparisons)
}

/// A multiply-rotate hash (as rustc's FxHash) for the grid's integer cell keys: SipHash took
/// most of the coplanar rule's time.
#[derive(Default)]
struct CellHasher(u64);

impl Hasher for CellHasher {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }

    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(5) ^ v).wrapping_mul(0x517c_c1b7_2722_0a95);
    }

    fn write_i64(&mut self, v: i64) {
        self.write_u64(v as u64);
    }

    fn write_i32(&mut self, v: i32) {
        self.write_u64(u64::from(v as u32));
    }

    fn write_usize(&mut self, v: usize) {
        self.write_u64(v as u64);
    }

    fn finish(&self) -> u64 {
        self.0
    }
}

/// The 27 offsets of a cell and its neighbours.
const NEIGHBOURS: [[i32; 3]; 27] = {
    let mut n = [[0; 3]; 27];
    let mut k = 0;
    while k < 27 {
        n[k] = [
            (k % 3) as i32 - 1,
            ((k / 3) % 3) as i32 - 1,
            (k / 9) as i32 - 1,
        ];
        k += 1;
    }
    n
};
