//! Intersection kernels through the packed geometry, checked against exact values and against a
//! brute-force scan of every primitive.

mod common;

use common::{geometry_of, random_unit};
use glam::{Vec2, Vec3};
use rondo::geometry::packed::{Geometry, HitKind, Primitive};
use rondo::geometry::ray::Ray;
use rondo::shading::rng::Rng;
use rondo::{Shape, Transform};

#[test]
fn box_hit_reports_exact_distance_point_normal_and_uv() {
    let g = geometry_of(&[(
        Shape::Box {
            min: Vec3::ZERO,
            max: Vec3::new(2.0, 2.0, 2.0),
        },
        Transform::default(),
    )]);
    // Straight down onto the top face at (0.5, 2, 1.5).
    let ray = Ray::new(Vec3::new(0.5, 5.0, 1.5), -Vec3::Y);
    let hit = g.intersect(&ray, f32::INFINITY).expect("hit");
    assert_eq!(hit.t, 3.0);
    let s = g.surface(&ray, &hit);
    assert_eq!(s.p, Vec3::new(0.5, 2.0, 1.5));
    assert_eq!(s.n, Vec3::Y);
    // The top face spans the box's [0,2]² in (z, x); uv is a corner-relative fraction.
    assert!(s.uv.x >= 0.0 && s.uv.x <= 1.0 && s.uv.y >= 0.0 && s.uv.y <= 1.0);
    let frac = [s.uv.x, s.uv.y];
    assert!(frac.contains(&0.25) && frac.contains(&0.75), "uv {}", s.uv);
}

#[test]
fn quad_uv_follows_its_own_edges_in_any_orientation() {
    // A quad in a tilted plane: uv must be the fraction along a→b and a→d.
    let a = Vec3::new(1.0, 2.0, 3.0);
    let ab = Vec3::new(2.0, 1.0, 0.0);
    let ad = Vec3::new(0.0, 1.0, -2.0) - ab * (Vec3::new(0.0, 1.0, -2.0).dot(ab) / ab.dot(ab));
    let quad = Shape::Quad {
        a,
        b: a + ab,
        c: a + ab + ad,
        d: a + ad,
    };
    let g = geometry_of(&[(quad, Transform::default())]);
    let normal = ab.cross(ad).normalize();
    for (fu, fv) in [(0.25f32, 0.5f32), (0.8, 0.1), (0.1, 0.9)] {
        let target = a + fu * ab + fv * ad;
        let ray = Ray::new(target + 3.0 * normal, -normal);
        let hit = g.intersect(&ray, f32::INFINITY).expect("hit");
        let s = g.surface(&ray, &hit);
        assert!(
            (s.uv - Vec2::new(fu, fv)).length() < 1e-5,
            "({fu},{fv}) -> {}",
            s.uv
        );
        assert!((s.n - normal).length() < 1e-6);
        assert!((hit.t - 3.0).abs() < 1e-5);
    }
}

#[test]
fn quad_diagonal_is_never_missed() {
    let quad = Shape::Quad {
        a: Vec3::new(0.0, 0.0, 0.0),
        b: Vec3::new(1.0, 0.0, 0.0),
        c: Vec3::new(1.0, 1.0, 0.0),
        d: Vec3::new(0.0, 1.0, 0.0),
    };
    let g = geometry_of(&[(quad, Transform::default())]);
    let mut rng = Rng::new(4, 4);
    for _ in 0..10_000 {
        let s = rng.next_f32();
        let target = Vec3::new(s, s, 0.0);
        let origin = Vec3::new(rng.next_f32() * 4.0 - 2.0, rng.next_f32() * 4.0 - 2.0, 2.0);
        let ray = Ray::new(origin, (target - origin).normalize());
        assert!(
            g.intersect(&ray, f32::INFINITY).is_some(),
            "{origin} → {target}"
        );
    }
}

/// Random scene: `n` spheres and `n` triangles; `clump` puts every centroid at the origin.
fn random_scene(n: usize, clump: bool, seed: u64) -> Geometry {
    let mut rng = Rng::new(seed, 1);
    let mut prims = Vec::new();
    for i in 0..n {
        let c = if clump {
            Vec3::ZERO
        } else {
            Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 20.0 - Vec3::splat(10.0)
        };
        let r = 0.05 + rng.next_f32() * 0.5;
        prims.push((
            i as u32,
            Primitive::Sphere {
                center: c,
                radius: r,
                frame: glam::Mat3::IDENTITY,
            },
        ));
        let p = [0, 1, 2].map(|_| c + random_unit(&mut rng) * (0.2 + rng.next_f32()));
        prims.push((
            i as u32,
            Primitive::Triangle {
                p,
                uv: [Vec2::ZERO; 3],
            },
        ));
    }
    Geometry::build(&prims)
}

#[test]
fn bvh_closest_hit_equals_brute_force() {
    for (n, clump) in [
        (0, false),
        (1, false),
        (2, false),
        (500, false),
        (200, true),
    ] {
        let g = random_scene(n, clump, n as u64 + 7);
        let mut rng = Rng::new(99, n as u64);
        for _ in 0..3_000 {
            let origin = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 30.0
                - Vec3::splat(15.0);
            let ray = Ray::new(origin, random_unit(&mut rng));
            let fast = g.intersect(&ray, f32::INFINITY);
            let slow = g.intersect_brute_force(&ray, f32::INFINITY);
            match (fast, slow) {
                (None, None) => {}
                (Some(a), Some(b)) => {
                    assert_eq!(a.t, b.t, "n={n} clump={clump}: {ray:?}");
                    assert_eq!(a.kind, b.kind);
                    if !clump {
                        assert_eq!(a.index, b.index);
                    }
                }
                other => panic!(
                    "n={n} clump={clump}: BVH and brute force disagree: {other:?} for {ray:?}"
                ),
            }
            let blocked = g.occluded(&ray, f32::INFINITY);
            assert_eq!(blocked, slow.is_some());
        }
    }
}

#[test]
fn coincident_triangles_and_concentric_spheres_hit_as_brute_force() {
    // Boxes that coincide or nest are where clustering builds degenerate; the tree over them must
    // still hold every primitive where a ray finds it.
    let mut prims = Vec::new();
    for i in 0..3_000u32 {
        let p = [
            Vec3::new(-2.0, 0.0, 1.0),
            Vec3::new(2.0, 0.5, 1.0),
            Vec3::new(0.0, 3.0, 1.5),
        ];
        let uv = [Vec2::ZERO; 3];
        prims.push((i, Primitive::Triangle { p, uv }));
        let (center, radius) = (Vec3::new(0.5, 1.0, -4.0), 0.5 + i as f32 * 1e-3);
        let frame = glam::Mat3::IDENTITY;
        prims.push((
            i,
            Primitive::Sphere {
                center,
                radius,
                frame,
            },
        ));
    }
    let g = Geometry::build(&prims);
    let mut rng = Rng::new(31, 3);
    let mut hits = 0;
    for _ in 0..2_000 {
        let origin =
            Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 20.0 - Vec3::splat(10.0);
        let ray = Ray::new(origin, random_unit(&mut rng));
        let (fast, slow) = (
            g.intersect(&ray, f32::INFINITY),
            g.intersect_brute_force(&ray, f32::INFINITY),
        );
        assert_eq!(
            fast.map(|h| (h.t, h.kind)),
            slow.map(|h| (h.t, h.kind)),
            "{ray:?}"
        );
        assert_eq!(g.occluded(&ray, f32::INFINITY), slow.is_some());
        hits += usize::from(slow.is_some());
    }
    assert!(hits > 100, "{hits} rays of 2,000 hit anything");
}

#[test]
fn axis_aligned_rays_agree_with_brute_force() {
    let g = random_scene(300, false, 3);
    let mut rng = Rng::new(5, 6);
    let axes = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
    for i in 0..6_000 {
        let origin =
            Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 24.0 - Vec3::splat(12.0);
        let ray = Ray::new(origin, axes[i % 6]);
        let fast = g
            .intersect(&ray, f32::INFINITY)
            .map(|h| (h.t, h.kind, h.index));
        let slow = g
            .intersect_brute_force(&ray, f32::INFINITY)
            .map(|h| (h.t, h.kind, h.index));
        assert_eq!(fast, slow, "{ray:?}");
    }
}

#[test]
fn planes_are_found_outside_the_bvh() {
    let g = geometry_of(&[
        (
            Shape::Plane {
                point: Vec3::ZERO,
                normal: Vec3::Y,
            },
            Transform::default(),
        ),
        (
            Shape::Sphere {
                center: Vec3::new(0.0, 1.0, 0.0),
                radius: 1.0,
            },
            Transform::default(),
        ),
    ]);
    let down = Ray::new(Vec3::new(5.0, 3.0, 0.0), -Vec3::Y);
    let hit = g.intersect(&down, f32::INFINITY).expect("plane");
    assert_eq!((hit.kind, hit.t), (HitKind::Plane, 3.0));
    let onto_sphere = Ray::new(Vec3::new(0.0, 3.0, 0.0), -Vec3::Y);
    let hit = g.intersect(&onto_sphere, f32::INFINITY).expect("sphere");
    assert_eq!((hit.kind, hit.t), (HitKind::Sphere, 1.0));
}
