//! The stores of the packed primitives: the [`SphereStore`] and [`TriangleStore`] interfaces,
//! their SoA and AoS forms, and the scalar leaf loops every kernel must match. The layouts
//! ([`super::layout`]) and the SIMD kernels ([`super::simd`]) both read them.

use std::fmt;
use std::ops::Range;

use glam::Vec3;

use super::aabb::RayQuery;
use super::ray::Ray;
use super::sphere::intersect_sphere;
use super::triangle::{TriangleHit, intersect_triangle};

/// Sphere storage: centre and radius by slot.
pub trait SphereStore: Clone + Default + fmt::Debug + Send + Sync + 'static {
    /// Appends a sphere.
    fn push(&mut self, center: Vec3, radius: f32);
    /// Reserves room for `n` more spheres.
    fn reserve(&mut self, n: usize);
    /// Number of spheres.
    fn len(&self) -> usize;
    /// Whether there are no spheres.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Centre and radius of sphere `i`.
    fn get(&self, i: usize) -> (Vec3, f32);
    /// Centre and radius of the spheres in `slots`, in slot order.
    fn leaf(&self, slots: Range<usize>) -> impl Iterator<Item = (Vec3, f32)> + '_;
}

/// Triangle storage: vertices by slot.
pub trait TriangleStore: Clone + Default + fmt::Debug + Send + Sync + 'static {
    /// Appends a triangle.
    fn push(&mut self, p: [Vec3; 3]);
    /// Reserves room for `n` more triangles.
    fn reserve(&mut self, n: usize);
    /// Number of triangles.
    fn len(&self) -> usize;
    /// Whether there are no triangles.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Vertices of triangle `i`.
    fn get(&self, i: usize) -> [Vec3; 3];
    /// Vertices of the triangles in `slots`, in slot order.
    fn leaf(&self, slots: Range<usize>) -> impl Iterator<Item = [Vec3; 3]> + '_;
}

/// The scalar leaf loop over spheres: the reference every other sphere kernel must match.
#[inline(always)]
pub fn closest_sphere_scalar<S: SphereStore>(
    spheres: &S,
    ray: &Ray,
    slots: Range<usize>,
    t_max: &mut f32,
) -> Option<usize> {
    let mut best = None;
    let first = slots.start;
    for (k, (c, r)) in spheres.leaf(slots).enumerate() {
        if let Some(t) = intersect_sphere(ray, c, r, *t_max) {
            *t_max = t;
            best = Some(first + k);
        }
    }
    best
}

/// The scalar leaf loop over triangles: the reference every other triangle kernel must match.
#[inline(always)]
pub fn closest_triangle_scalar<T: TriangleStore>(
    triangles: &T,
    q: &RayQuery,
    slots: Range<usize>,
    t_max: &mut f32,
) -> Option<(usize, TriangleHit)> {
    let mut best = None;
    let first = slots.start;
    for (k, [a, b, c]) in triangles.leaf(slots).enumerate() {
        if let Some(h) = intersect_triangle(q, a, b, c, *t_max) {
            *t_max = h.t;
            best = Some((first + k, h));
        }
    }
    best
}

/// Entries each [`SphereSoa`] field holds past its last sphere (copies of that sphere's), so
/// that a lane kernel loads a leaf's last chunk as whole vectors however few of its lanes are
/// live: [`crate::geometry::simd`] tests four spheres at a time, so three suffice. Without them a
/// scene of a few spheres (Veach's five lamps) took an out-of-line, lane-by-lane load at nearly
/// every shadow ray.
pub const SOA_PADDING: usize = 3;

/// Spheres in SoA form: one array per field, 16 bytes per sphere over four arrays, each followed
/// by [`SOA_PADDING`] copies of its last entry once there is a sphere.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SphereSoa {
    /// Centre x per sphere, then the padding.
    pub cx: Vec<f32>,
    /// Centre y per sphere, then the padding.
    pub cy: Vec<f32>,
    /// Centre z per sphere, then the padding.
    pub cz: Vec<f32>,
    /// Radius per sphere, then the padding.
    pub r: Vec<f32>,
    /// Number of spheres: the fields' length without the padding.
    count: usize,
}

impl SphereSoa {
    /// Centre and radius of sphere `i`.
    #[inline(always)]
    pub fn get(&self, i: usize) -> (Vec3, f32) {
        (Vec3::new(self.cx[i], self.cy[i], self.cz[i]), self.r[i])
    }

    /// Number of spheres.
    pub fn len(&self) -> usize {
        self.count
    }

    /// Whether there are no spheres.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }
}

impl SphereStore for SphereSoa {
    fn push(&mut self, c: Vec3, r: f32) {
        let count = self.count;
        for (field, value) in [
            (&mut self.cx, c.x),
            (&mut self.cy, c.y),
            (&mut self.cz, c.z),
            (&mut self.r, r),
        ] {
            field.truncate(count);
            field.resize(count + 1 + SOA_PADDING, value);
        }
        self.count += 1;
    }

    fn reserve(&mut self, n: usize) {
        for field in [&mut self.cx, &mut self.cy, &mut self.cz, &mut self.r] {
            field.reserve(n + SOA_PADDING);
        }
    }

    fn len(&self) -> usize {
        self.count
    }

    #[inline(always)]
    fn get(&self, i: usize) -> (Vec3, f32) {
        SphereSoa::get(self, i)
    }

    #[inline(always)]
    fn leaf(&self, slots: Range<usize>) -> impl Iterator<Item = (Vec3, f32)> + '_ {
        // Slicing each field once lets the optimiser drop the per-element bounds checks.
        let cx = &self.cx[slots.clone()];
        let cy = &self.cy[slots.clone()];
        let cz = &self.cz[slots.clone()];
        let r = &self.r[slots];
        cx.iter()
            .zip(cy)
            .zip(cz)
            .zip(r)
            .map(|(((&x, &y), &z), &r)| (Vec3::new(x, y, z), r))
    }
}

/// Triangles in SoA form: one array per vertex coordinate, 36 bytes per triangle over nine
/// arrays.
#[derive(Clone, Debug, Default, PartialEq)]
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

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.v[0].len()
    }

    /// Whether there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl TriangleStore for TriangleSoa {
    fn push(&mut self, p: [Vec3; 3]) {
        for (k, vertex) in p.iter().enumerate() {
            for axis in 0..3 {
                self.v[3 * k + axis].push(vertex[axis]);
            }
        }
    }

    fn reserve(&mut self, n: usize) {
        for field in &mut self.v {
            field.reserve(n);
        }
    }

    fn len(&self) -> usize {
        TriangleSoa::len(self)
    }

    #[inline(always)]
    fn get(&self, i: usize) -> [Vec3; 3] {
        TriangleSoa::get(self, i)
    }

    #[inline(always)]
    fn leaf(&self, slots: Range<usize>) -> impl Iterator<Item = [Vec3; 3]> + '_ {
        let n = slots.len();
        let v: [&[f32]; 9] = std::array::from_fn(|k| &self.v[k][slots.clone()]);
        (0..n).map(move |j| {
            [
                Vec3::new(v[0][j], v[1][j], v[2][j]),
                Vec3::new(v[3][j], v[4][j], v[5][j]),
                Vec3::new(v[6][j], v[7][j], v[8][j]),
            ]
        })
    }
}

/// One sphere of [`SphereAos`]: 16 bytes, four to a 64-byte cache line.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct Sphere {
    /// Centre.
    pub center: Vec3,
    /// Radius.
    pub radius: f32,
}

/// One triangle of [`TriangleAos`]: 36 bytes (unpadded, so a triangle may straddle two cache
/// lines, exactly as the nine SoA arrays hold it in 36 bytes).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct Triangle {
    /// Vertices.
    pub p: [Vec3; 3],
}

const _: () = assert!(std::mem::size_of::<Sphere>() == 16);
const _: () = assert!(std::mem::size_of::<Triangle>() == 36);

/// Spheres in AoS form.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SphereAos(pub Vec<Sphere>);

impl SphereAos {
    /// Centre and radius of sphere `i`.
    #[inline(always)]
    pub fn get(&self, i: usize) -> (Vec3, f32) {
        let s = &self.0[i];
        (s.center, s.radius)
    }

    /// Number of spheres.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Whether there are no spheres.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

impl SphereStore for SphereAos {
    fn push(&mut self, center: Vec3, radius: f32) {
        self.0.push(Sphere { center, radius });
    }

    fn reserve(&mut self, n: usize) {
        self.0.reserve(n);
    }

    fn len(&self) -> usize {
        self.0.len()
    }

    #[inline(always)]
    fn get(&self, i: usize) -> (Vec3, f32) {
        SphereAos::get(self, i)
    }

    #[inline(always)]
    fn leaf(&self, slots: Range<usize>) -> impl Iterator<Item = (Vec3, f32)> + '_ {
        self.0[slots].iter().map(|s| (s.center, s.radius))
    }
}

/// Triangles in AoS form.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleAos(pub Vec<Triangle>);

impl TriangleAos {
    /// Vertices of triangle `i`.
    #[inline(always)]
    pub fn get(&self, i: usize) -> [Vec3; 3] {
        self.0[i].p
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Whether there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

impl TriangleStore for TriangleAos {
    fn push(&mut self, p: [Vec3; 3]) {
        self.0.push(Triangle { p });
    }

    fn reserve(&mut self, n: usize) {
        self.0.reserve(n);
    }

    fn len(&self) -> usize {
        self.0.len()
    }

    #[inline(always)]
    fn get(&self, i: usize) -> [Vec3; 3] {
        self.0[i].p
    }

    #[inline(always)]
    fn leaf(&self, slots: Range<usize>) -> impl Iterator<Item = [Vec3; 3]> + '_ {
        self.0[slots].iter().map(|t| t.p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stores_return_what_was_pushed_by_slot_and_by_leaf() {
        let spheres = [
            (Vec3::new(1.0, 2.0, 3.0), 0.5),
            (Vec3::new(-1.0, 0.0, 4.0), 2.0),
        ];
        let tris = [
            [Vec3::X, Vec3::Y, Vec3::Z],
            [Vec3::ZERO, Vec3::ONE, Vec3::NEG_ONE],
        ];
        let (mut s1, mut s2) = (SphereSoa::default(), SphereAos::default());
        let (mut t1, mut t2) = (TriangleSoa::default(), TriangleAos::default());
        for &(c, r) in &spheres {
            SphereStore::push(&mut s1, c, r);
            SphereStore::push(&mut s2, c, r);
        }
        for &p in &tris {
            TriangleStore::push(&mut t1, p);
            TriangleStore::push(&mut t2, p);
        }
        for i in 0..2 {
            assert_eq!(s1.get(i), spheres[i]);
            assert_eq!(s2.get(i), spheres[i]);
            assert_eq!(t1.get(i), tris[i]);
            assert_eq!(t2.get(i), tris[i]);
        }
        assert_eq!(s1.leaf(1..2).collect::<Vec<_>>(), vec![spheres[1]]);
        assert_eq!(s2.leaf(0..2).collect::<Vec<_>>(), spheres.to_vec());
        assert_eq!(t1.leaf(0..2).collect::<Vec<_>>(), tris.to_vec());
        assert_eq!(t2.leaf(1..2).collect::<Vec<_>>(), vec![tris[1]]);
    }

    /// Every chunk of four slots that starts at a sphere lies inside the SoA arrays, so the lane
    /// kernels never take the lane-by-lane load; the padding repeats the last sphere and is not
    /// counted.
    #[test]
    fn soa_spheres_are_padded_for_whole_lane_loads() {
        let mut s = SphereSoa::default();
        assert_eq!(s.len(), 0);
        assert!(s.cx.is_empty());
        for n in 1..=6usize {
            let c = Vec3::new(n as f32, -(n as f32), 0.5 * n as f32);
            SphereStore::push(&mut s, c, n as f32);
            assert_eq!(SphereStore::len(&s), n);
            for field in [&s.cx, &s.cy, &s.cz, &s.r] {
                assert!(
                    field.len() >= n + 3,
                    "{n} spheres in {} entries",
                    field.len()
                );
                for first in 0..n {
                    assert!(
                        field.get(first..first + 4).is_some(),
                        "chunk at {first} of {n}"
                    );
                }
            }
            assert_eq!(s.r[n..], [n as f32; 3], "padding repeats the last sphere");
            for i in 0..n {
                let want = Vec3::new(i as f32 + 1.0, -(i as f32 + 1.0), 0.5 * (i as f32 + 1.0));
                assert_eq!(s.get(i), (want, i as f32 + 1.0));
            }
            assert_eq!(s.leaf(0..n).count(), n);
        }
    }
}
