//! Every layout and leaf kernel gives the scalar reference kernel's answer, bit for bit; renders
//! are bit-identical in every layout; `bench layout` runs (smoke mode) and writes its outputs.

mod common;

use std::ops::Range;
use std::path::Path;
use std::process::Command;

use glam::{Mat3, Vec2, Vec3};
use rondo::geometry::aabb::RayQuery;
use rondo::geometry::layout::{Aos, Hybrid, Layout, LayoutKind, Soa, SoaSimd};
use rondo::geometry::packed::{Geometry, Hit, Primitive};
use rondo::geometry::ray::Ray;
use rondo::geometry::simd::LANES;
use rondo::geometry::store::{
    SphereStore, TriangleStore, closest_sphere_scalar, closest_triangle_scalar,
};
use rondo::geometry::triangle::TriangleHit;
use rondo::shading::rng::Rng;
use rondo::{Overrides, PassPlan, Renderer};

use common::{random_unit, scenes_dir, temp_dir};

fn random_vec(rng: &mut Rng, scale: f32) -> Vec3 {
    (Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - Vec3::ONE) * scale
}

/// Spheres and triangles with the awkward cases mixed in: exact duplicates (ties), axis-aligned
/// triangles on a grid (edge functions of exactly zero for axis-aligned rays through a grid
/// point), nested spheres (rays starting inside).
fn awkward_primitives(n: usize, seed: u64) -> (Vec<(Vec3, f32)>, Vec<[Vec3; 3]>) {
    let mut rng = Rng::new(seed, 7);
    let mut spheres = Vec::new();
    let mut tris = Vec::new();
    for i in 0..n {
        match i % 5 {
            0 if i > 0 => {
                spheres.push(spheres[i - 1]);
                tris.push(tris[i - 1]);
            }
            1 => {
                let c = random_vec(&mut rng, 2.0).round();
                spheres.push((c, 1.0));
                tris.push([c, c + Vec3::X, c + Vec3::Y]);
            }
            2 if i > 1 => {
                let (c, r) = spheres[i - 1];
                spheres.push((c, 0.5 * r));
                let [a, b, c] = tris[i - 1];
                tris.push([a, c, b + Vec3::Z]);
            }
            _ => {
                spheres.push((random_vec(&mut rng, 3.0), 0.05 + rng.next_f32()));
                let c = random_vec(&mut rng, 3.0);
                tris.push([
                    c,
                    c + random_vec(&mut rng, 1.0),
                    c + random_vec(&mut rng, 1.0),
                ]);
            }
        }
    }
    (spheres, tris)
}

/// Rays aimed at the primitives (so most hit), axis-aligned rays through grid points, and
/// random rays.
fn awkward_rays(count: usize, targets: &[Vec3], seed: u64) -> Vec<(Ray, f32)> {
    let mut rng = Rng::new(seed, 11);
    (0..count)
        .map(|i| {
            let target = targets[i % targets.len()] + random_vec(&mut rng, 0.3);
            let ray = match i % 4 {
                0 => {
                    let axis = Vec3::AXES[i / 4 % 3];
                    let target = target.round();
                    Ray::new(target - 6.0 * axis, axis)
                }
                1 => Ray::new(random_vec(&mut rng, 4.0), random_unit(&mut rng)),
                _ => {
                    let origin = random_vec(&mut rng, 8.0);
                    let d = target - origin;
                    if d.length_squared() > 1e-6 {
                        Ray::new(origin, d.normalize())
                    } else {
                        Ray::new(origin, Vec3::Z)
                    }
                }
            };
            let t_max = if i % 3 == 0 {
                f32::INFINITY
            } else {
                1.0 + 10.0 * rng.next_f32()
            };
            (ray, t_max)
        })
        .collect()
}

/// Every leaf range `start..start + len`, with `len` from 1 to past two lane vectors (and at
/// least to 11, past the BVH's largest leaf of 8), so that leaves fill 1..LANES lanes, span
/// chunks, and read padded lanes at the end of the arrays.
fn leaf_ranges(n: usize) -> Vec<Range<usize>> {
    let mut ranges = Vec::new();
    for start in 0..n {
        for len in 1..=(2 * LANES + 3).max(11).min(n - start) {
            ranges.push(start..start + len);
        }
    }
    ranges
}

fn sphere_kernel<L: Layout>(
    store: &L::Spheres,
    ray: &Ray,
    slots: Range<usize>,
    t_max: f32,
) -> (Option<usize>, u32, bool) {
    let mut t = t_max;
    let hit = L::closest_sphere(store, ray, slots.clone(), &mut t);
    (hit, t.to_bits(), L::any_sphere(store, ray, slots, t_max))
}

fn triangle_kernel<L: Layout>(
    store: &L::Triangles,
    q: &RayQuery,
    slots: Range<usize>,
    t_max: f32,
) -> (Option<(usize, [u32; 3])>, u32, bool) {
    let mut t = t_max;
    let hit = L::closest_triangle(store, q, slots.clone(), &mut t);
    let bits = hit
        .map(|(i, h): (usize, TriangleHit)| (i, [h.t.to_bits(), h.b1.to_bits(), h.b2.to_bits()]));
    (bits, t.to_bits(), L::any_triangle(store, q, slots, t_max))
}

#[test]
fn every_leaf_kernel_matches_the_scalar_reference_bit_for_bit() {
    let n = 24;
    let (spheres, tris) = awkward_primitives(n, 3);
    let mut soa_s = <Soa as Layout>::Spheres::default();
    let mut aos_s = <Aos as Layout>::Spheres::default();
    let mut soa_t = <Soa as Layout>::Triangles::default();
    let mut aos_t = <Aos as Layout>::Triangles::default();
    for (&(c, r), &p) in spheres.iter().zip(&tris) {
        soa_s.push(c, r);
        aos_s.push(c, r);
        soa_t.push(p);
        aos_t.push(p);
    }
    let targets: Vec<Vec3> = spheres.iter().map(|s| s.0).collect();
    let rays = awkward_rays(160, &targets, 5);
    let ranges = leaf_ranges(n);
    let (mut sphere_hits, mut triangle_hits, mut ties) = (0, 0, 0);
    for (ray, t_max) in &rays {
        let q = RayQuery::new(*ray);
        for slots in &ranges {
            // The reference: the scalar loop over the scalar kernel.
            let mut t = *t_max;
            let reference = closest_sphere_scalar(&soa_s, ray, slots.clone(), &mut t);
            let expected = (reference, t.to_bits(), reference.is_some());
            sphere_hits += usize::from(reference.is_some());
            assert_eq!(
                sphere_kernel::<Soa>(&soa_s, ray, slots.clone(), *t_max),
                expected
            );
            assert_eq!(
                sphere_kernel::<Aos>(&aos_s, ray, slots.clone(), *t_max),
                expected
            );
            assert_eq!(
                sphere_kernel::<SoaSimd>(&soa_s, ray, slots.clone(), *t_max),
                expected,
                "SIMD spheres, slots {slots:?}, {ray:?}"
            );
            assert_eq!(
                sphere_kernel::<Hybrid>(&soa_s, ray, slots.clone(), *t_max),
                expected
            );

            let mut t = *t_max;
            let reference = closest_triangle_scalar(&soa_t, &q, slots.clone(), &mut t);
            let bits = reference.map(|(i, h)| (i, [h.t.to_bits(), h.b1.to_bits(), h.b2.to_bits()]));
            let expected = (bits, t.to_bits(), reference.is_some());
            triangle_hits += usize::from(reference.is_some());
            if let Some((i, _)) = reference {
                ties += usize::from(i > 0 && slots.start < i && tris[i] == tris[i - 1]);
            }
            assert_eq!(
                triangle_kernel::<Soa>(&soa_t, &q, slots.clone(), *t_max),
                expected
            );
            assert_eq!(
                triangle_kernel::<Aos>(&aos_t, &q, slots.clone(), *t_max),
                expected
            );
            assert_eq!(
                triangle_kernel::<SoaSimd>(&soa_t, &q, slots.clone(), *t_max),
                expected,
                "SIMD triangles, slots {slots:?}, {ray:?}"
            );
            assert_eq!(
                triangle_kernel::<Hybrid>(&aos_t, &q, slots.clone(), *t_max),
                expected
            );
        }
    }
    // The cases must actually occur, or the test proves little.
    assert!(sphere_hits > 1000, "{sphere_hits} sphere hits");
    assert!(triangle_hits > 1000, "{triangle_hits} triangle hits");
    assert!(ties > 0, "no tie between duplicate triangles was exercised");
}

#[test]
fn lanes_at_the_end_of_the_arrays_are_padded_and_ignored() {
    // Fewer primitives than one lane vector: every load runs past the end of the arrays.
    for n in 1..LANES {
        let (spheres, tris) = awkward_primitives(n, 17 + n as u64);
        let mut s = <SoaSimd as Layout>::Spheres::default();
        let mut t = <SoaSimd as Layout>::Triangles::default();
        for (&(c, r), &p) in spheres.iter().zip(&tris) {
            s.push(c, r);
            t.push(p);
        }
        let targets: Vec<Vec3> = spheres.iter().map(|s| s.0).collect();
        for (ray, t_max) in awkward_rays(200, &targets, n as u64) {
            let q = RayQuery::new(ray);
            for slots in leaf_ranges(n) {
                assert_eq!(
                    sphere_kernel::<SoaSimd>(&s, &ray, slots.clone(), t_max),
                    sphere_kernel::<Soa>(&s, &ray, slots.clone(), t_max)
                );
                assert_eq!(
                    triangle_kernel::<SoaSimd>(&t, &q, slots.clone(), t_max),
                    triangle_kernel::<Soa>(&t, &q, slots.clone(), t_max)
                );
            }
        }
    }
}

#[test]
fn an_edge_function_that_rounds_to_zero_is_decided_in_double_precision_by_every_kernel() {
    // Seen from the origin along +z, edge ab has e = 3·(1 + 2⁻²³) − (3 + 2⁻²¹): both products
    // round to 3 + 2⁻²¹ in f32, so e = 0 there, but e = 2⁻²³ > 0 exactly. The other two edge
    // functions are negative, so f32 alone says hit, and the watertight test (which recomputes
    // zero edges in f64) says miss. Its neighbour across ab is hit instead.
    let a = Vec3::new(3.0, 1.0, 0.0);
    let b = Vec3::new(-(3.0 + 2f32.powi(-21)), -(1.0 + 2f32.powi(-23)), 0.0);
    let (c, d) = (Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, -1.0, 0.0));
    let q = RayQuery::new(Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z));
    let mut soa = <Soa as Layout>::Triangles::default();
    let mut aos = <Aos as Layout>::Triangles::default();
    let far = Vec3::new(50.0, 50.0, 50.0);
    for p in [[a, b, c], [far, far + Vec3::X, far + Vec3::Y], [b, a, d]] {
        soa.push(p);
        aos.push(p);
    }
    let mut t = f32::INFINITY;
    assert_eq!(closest_triangle_scalar(&soa, &q, 0..2, &mut t), None);
    let mut t = f32::INFINITY;
    assert_eq!(
        closest_triangle_scalar(&soa, &q, 0..3, &mut t).map(|h| h.0),
        Some(2)
    );
    for slots in [0..1, 0..2, 0..3, 2..3] {
        let expected = triangle_kernel::<Soa>(&soa, &q, slots.clone(), f32::INFINITY);
        assert_eq!(
            triangle_kernel::<Aos>(&aos, &q, slots.clone(), f32::INFINITY),
            expected
        );
        assert_eq!(
            triangle_kernel::<SoaSimd>(&soa, &q, slots.clone(), f32::INFINITY),
            expected,
            "{slots:?}"
        );
    }
}

/// A random scene of spheres, triangles and a plane, as `(owner, primitive)` pairs.
fn random_scene(n: usize, seed: u64) -> Vec<(u32, Primitive)> {
    let (spheres, tris) = awkward_primitives(n, seed);
    let mut prims = Vec::new();
    for (i, ((c, r), p)) in spheres.into_iter().zip(tris).enumerate() {
        prims.push((
            i as u32,
            Primitive::Sphere {
                center: c * 3.0,
                radius: r,
                frame: Mat3::IDENTITY,
            },
        ));
        prims.push((
            i as u32,
            Primitive::Triangle {
                p: p.map(|v| v * 3.0),
                uv: [Vec2::ZERO, Vec2::X, Vec2::Y],
            },
        ));
    }
    prims.push((
        n as u32,
        Primitive::Plane {
            point: Vec3::new(0.0, -12.0, 0.0),
            normal: Vec3::Y,
        },
    ));
    prims
}

fn hit_bits(h: Option<Hit>) -> Option<(u32, u32, u32, u32, String)> {
    h.map(|h| {
        (
            h.t.to_bits(),
            h.index,
            h.b1.to_bits(),
            h.b2.to_bits(),
            format!("{:?}", h.kind),
        )
    })
}

fn check_layout<L: Layout>(reference: &Geometry<Soa>, rays: &[(Ray, f32)]) -> usize {
    let g: Geometry<L> = reference.relayout();
    let packed: Geometry<L> = Geometry::pack(&random_scene(300, 9));
    assert_eq!(packed.primitive_count(), reference.primitive_count());
    let mut hits = 0;
    for (ray, t_max) in rays {
        let expected = reference.intersect(ray, *t_max);
        let got = g.intersect(ray, *t_max);
        assert_eq!(hit_bits(got), hit_bits(expected), "{:?}: {ray:?}", L::KIND);
        assert_eq!(hit_bits(packed.intersect(ray, *t_max)), hit_bits(expected));
        assert_eq!(g.occluded(ray, *t_max), reference.occluded(ray, *t_max));
        if let (Some(a), Some(b)) = (got, expected) {
            hits += 1;
            let (sa, sb) = (g.surface(ray, &a), reference.surface(ray, &b));
            assert_eq!(
                sa.n.to_array().map(f32::to_bits),
                sb.n.to_array().map(f32::to_bits)
            );
            assert_eq!(
                sa.p.to_array().map(f32::to_bits),
                sb.p.to_array().map(f32::to_bits)
            );
            assert_eq!(sa.owner, sb.owner);
        }
    }
    for i in 0..g.spheres.len() {
        assert_eq!(g.sphere(i), reference.sphere(i));
    }
    for i in 0..g.triangles.len() {
        assert_eq!(g.triangle(i), reference.triangle(i));
    }
    hits
}

#[test]
fn every_layout_finds_the_same_closest_hit_through_the_bvh() {
    // The reference is the scalar kernel through the same BVH; the brute-force scan checks the
    // reference itself (up to the order in which exact ties are met).
    let prims = random_scene(300, 9);
    let reference: Geometry<Soa> = Geometry::pack(&prims);
    let targets: Vec<Vec3> = (0..reference.spheres.len())
        .map(|i| reference.sphere(i).0)
        .collect();
    let rays = awkward_rays(4000, &targets, 21);
    for (ray, t_max) in &rays {
        let bvh = reference.intersect(ray, *t_max).map(|h| h.t);
        let brute = reference.intersect_brute_force(ray, *t_max).map(|h| h.t);
        match (bvh, brute) {
            (Some(a), Some(b)) => assert!((a - b).abs() <= 1e-5 * b.max(1.0), "{a} vs {b}"),
            (a, b) => assert_eq!(a.is_some(), b.is_some(), "{ray:?}"),
        }
    }
    let hits = [
        check_layout::<Soa>(&reference, &rays),
        check_layout::<Aos>(&reference, &rays),
        check_layout::<SoaSimd>(&reference, &rays),
        check_layout::<Hybrid>(&reference, &rays),
    ];
    assert!(hits.iter().all(|&h| h > 1000), "{hits:?}");
}

/// Asserts that the render's one pass ran the code monomorphised for `layout` (the pass
/// records its layout type's `KIND`), so comparing images compares layouts.
fn assert_traced_in(r: &Renderer, layout: LayoutKind) {
    let expected: Vec<u64> = LayoutKind::ALL
        .iter()
        .map(|&k| u64::from(k == layout))
        .collect();
    assert_eq!(
        r.stats().layout_passes.to_vec(),
        expected,
        "passes per layout {:?}, asked for {layout}",
        LayoutKind::ALL
    );
}

fn render_film(scene: &Path, layout: LayoutKind) -> Vec<rondo::film::Pixel> {
    let mut r = Renderer::new(Some(2), PassPlan::Single).expect("thread pool");
    r.set_overrides(Overrides {
        width: Some(24),
        height: Some(24),
        spp: Some(2),
        ..Default::default()
    });
    r.set_layout(layout);
    r.load(scene).unwrap_or_else(|e| panic!("{e}"));
    r.render_to_completion();
    assert!(r.is_complete());
    assert_traced_in(&r, layout);
    r.film().sum.clone()
}

#[test]
fn renders_are_bit_identical_in_every_layout_for_every_shipped_scene() {
    let mut scenes: Vec<_> = std::fs::read_dir(scenes_dir())
        .expect("scenes dir")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "ron"))
        .collect();
    scenes.sort();
    assert!(!scenes.is_empty());
    for scene in &scenes {
        let reference = render_film(scene, LayoutKind::Soa);
        assert!(reference.iter().any(|p| *p != rondo::film::Pixel::ZERO));
        for layout in [LayoutKind::Aos, LayoutKind::SoaSimd, LayoutKind::Hybrid] {
            assert!(
                render_film(scene, layout) == reference,
                "{}: {layout} differs from soa",
                scene.display()
            );
        }
    }
}

#[test]
fn switching_layout_between_renders_keeps_the_image() {
    // One renderer, the layout changed between renders of the same scene. The sample count
    // alternates between 1 and 2, so every render is a fresh one even if a layout change did
    // not restart it (an unchanged reload keeps a complete film); each pass is checked to run
    // in the layout asked for, and each layout renders both counts.
    let scene = scenes_dir().join("cornell.ron");
    let mut r = Renderer::new(Some(1), PassPlan::Single).expect("thread pool");
    let mut films: [Vec<_>; 2] = Default::default();
    let (aos, soa, simd, hybrid) = (
        LayoutKind::Aos,
        LayoutKind::Soa,
        LayoutKind::SoaSimd,
        LayoutKind::Hybrid,
    );
    // Odd positions render 2 spp; each layout comes once at an even and once at an odd one.
    let order = [aos, soa, simd, hybrid, soa, aos, hybrid, simd];
    for (k, layout) in order.iter().enumerate() {
        let spp = 1 + k % 2;
        r.set_overrides(Overrides {
            width: Some(16),
            height: Some(16),
            spp: Some(spp as u32),
            ..Default::default()
        });
        r.set_layout(*layout);
        r.load(&scene).unwrap_or_else(|e| panic!("{e}"));
        r.render_to_completion();
        assert_traced_in(&r, *layout);
        films[spp - 1].push(r.film().sum.clone());
    }
    for same_spp in &films {
        assert_eq!(same_spp.len(), 4);
        assert!(same_spp.iter().all(|f| f == &same_spp[0]));
    }
    assert_ne!(films[0][0], films[1][0]);
    assert_eq!(r.counters().bvh_builds, 1);
}

fn rondo() -> Command {
    Command::new(env!("CARGO_BIN_EXE_rondo"))
}

#[test]
fn cli_layout_flag_gives_byte_identical_images() {
    let dir = temp_dir("layout-cli");
    let scene = scenes_dir().join("cornell.ron");
    let mut images = Vec::new();
    for layout in ["soa", "aos", "soa-simd", "hybrid"] {
        let out = dir.join(format!("{layout}.png"));
        let status = rondo()
            .args(["render", "--spp", "2", "--width", "20", "--height", "20"])
            .args(["--layout", layout, "-o"])
            .arg(&out)
            .arg(&scene)
            .output()
            .expect("run rondo");
        assert!(status.status.success(), "{status:?}");
        images.push(std::fs::read(&out).expect("image written"));
    }
    assert_eq!(images[0], images[1]);
    assert_eq!(images[0], images[2]);
    assert_eq!(images[0], images[3]);
    let bad = rondo()
        .args(["render", "--layout", "soaa", "-o"])
        .arg(dir.join("x.png"))
        .arg(&scene)
        .output()
        .expect("run rondo");
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("soa-simd"));
}

#[test]
fn bench_layout_smoke_run_writes_a_consistent_csv_and_a_chart() {
    let dir = temp_dir("bench-layout");
    let out = rondo()
        .args(["bench", "layout", "--smoke", "--out"])
        .arg(&dir)
        .output()
        .expect("run rondo");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let csv = std::fs::read_to_string(dir.join("layout.csv")).expect("layout.csv");
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .unwrap_or_else(|| panic!("no column {name} in {header:?}"))
    };
    let (workload, kind, layout, count) =
        (col("workload"), col("kind"), col("layout"), col("count"));
    let (median, ratio) = (col("median"), col("ratio_vs_aos_median"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    for w in ["kernel", "traverse", "render", "extract"] {
        for k in ["sphere", "triangle"] {
            for l in ["soa", "aos", "soa-simd", "hybrid"] {
                let n = rows
                    .iter()
                    .filter(|r| r[workload] == w && r[kind] == k && r[layout] == l)
                    .count();
                assert!(n >= 2, "{w}/{k}/{l}: {n} sizes");
            }
        }
    }
    for r in &rows {
        let m: f64 = r[median].parse().expect("median");
        let q: f64 = r[ratio].parse().expect("ratio");
        assert!(m > 0.0 && m.is_finite(), "{r:?}");
        assert!(q > 0.0 && q.is_finite(), "{r:?}");
        if r[layout] == "aos" {
            assert_eq!(q, 1.0);
        }
        assert!(r[count].parse::<u64>().expect("count") > 0);
    }
    let svg = std::fs::read_to_string(dir.join("layout.svg")).expect("layout.svg");
    assert!(svg.starts_with("<svg") && svg.contains("</svg>"));
    let table = std::fs::read_to_string(dir.join("layout.md")).expect("layout.md");
    assert!(table.contains("| workload"));
}
