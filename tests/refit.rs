//! Moves shown by refitting the BVH: the refitted geometry finds the hits a fresh build finds,
//! a live reload that only moves entities refits for its preview and builds before any real
//! sample, and the converged image equals a cold render of the same file.

mod common;

use common::{temp_dir, write_scene};
use glam::{Mat3, Vec2, Vec3};
use rondo::app::Renderer;
use rondo::ecs::resources::PassPlan;
use rondo::geometry::packed::{Geometry, Primitive};
use rondo::geometry::ray::Ray;
use rondo::shading::rng::Rng;

fn sphere(center: Vec3, radius: f32) -> Primitive {
    Primitive::Sphere {
        center,
        radius,
        frame: Mat3::IDENTITY,
    }
}

fn triangle(p: [Vec3; 3]) -> Primitive {
    Primitive::Triangle {
        p,
        uv: [Vec2::ZERO, Vec2::X, Vec2::Y],
    }
}

fn point(rng: &mut Rng, scale: f32) -> Vec3 {
    Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * scale
}

/// 400 spheres and 400 triangles (two per owner, a quad's halves) scattered in a 20-wide cube.
fn scattered(rng: &mut Rng) -> Vec<(u32, Primitive)> {
    let mut out = Vec::new();
    for owner in 0..400u32 {
        out.push((owner, sphere(point(rng, 20.0), 0.1 + 0.3 * rng.next_f32())));
    }
    for owner in 400..600u32 {
        let a = point(rng, 20.0);
        let (u, v) = (point(rng, 1.0), point(rng, 1.0));
        out.push((owner, triangle([a, a + u, a + u + v])));
        out.push((owner, triangle([a, a + u + v, a + v])));
    }
    out
}

/// The closest hit of each of 20,000 random rays through the cube: distance bits and owner.
fn hits(g: &Geometry, seed: u64) -> Vec<Option<(u32, u32)>> {
    let mut rng = Rng::new(seed, 3);
    (0..20_000)
        .map(|_| {
            let origin = point(&mut rng, 30.0) - Vec3::splat(5.0);
            let target = point(&mut rng, 20.0);
            let ray = Ray::new(origin, (target - origin).normalize());
            g.intersect(&ray, f32::INFINITY)
                .map(|h| (h.t.to_bits(), g.owner(&h)))
        })
        .collect()
}

#[test]
fn a_refitted_geometry_finds_the_hits_of_a_fresh_build() {
    let mut rng = Rng::new(5, 1);
    let before = scattered(&mut rng);
    let mut g = Geometry::build(&before);
    // A tenth of the owners move far (out of their leaves' boxes) and change size.
    let mut after = before.clone();
    for (owner, prim) in after.iter_mut() {
        if *owner % 10 != 3 {
            continue;
        }
        let shift = point(&mut rng, 10.0) - Vec3::splat(5.0);
        match prim {
            Primitive::Sphere { center, radius, .. } => {
                *center += shift;
                *radius *= 1.5;
            }
            Primitive::Triangle { p, .. } => {
                // Both halves of a quad move together.
                let shift = Vec3::splat(*owner as f32 * 0.01) + Vec3::Y * 3.0;
                for v in p.iter_mut() {
                    *v += shift;
                }
            }
            _ => {}
        }
    }
    let stale = hits(&g, 9);
    assert!(g.refit(&after), "same owners and counts: refitted");
    let fresh = Geometry::build(&after);
    let (refitted, built) = (hits(&g, 9), hits(&fresh, 9));
    let hit = built.iter().filter(|h| h.is_some()).count();
    assert!(hit > 5_000, "the rays hit something: {hit}");
    assert_eq!(
        refitted, built,
        "the refitted geometry finds the fresh build's hits"
    );
    assert_ne!(stale, built, "the moves change what the rays hit");
    assert_eq!(g.finite_bounds(), fresh.finite_bounds());
}

#[test]
fn a_refit_refuses_other_primitives_and_changes_nothing() {
    let mut rng = Rng::new(6, 1);
    let before = scattered(&mut rng);
    let mut g = Geometry::build(&before);
    let reference = hits(&g, 4);
    // One owner more, one fewer, a sphere given to another owner, a quad made a triangle.
    let mut more = before.clone();
    more.push((600, sphere(Vec3::ONE, 1.0)));
    let fewer = before[1..].to_vec();
    let mut swapped = before.clone();
    swapped[7].0 = 8;
    let mut halved = before.clone();
    halved.pop();
    for other in [more, fewer, swapped, halved] {
        assert!(!g.refit(&other));
        assert_eq!(
            hits(&g, 4),
            reference,
            "a refused refit leaves the geometry as it was"
        );
    }
}

const SCENE_HEAD: &str = r#"Scene(
    camera: Camera(position: (10, 8, -22), look_at: (10, 2, 10), fov: 50),
    settings: Settings(width: 48, height: 32, spp: 8, max_depth: 3, seed: 5),
    materials: {
        "clay": Diffuse(albedo: Constant((0.7, 0.6, 0.5))),
        "lamp": Light(emit: Constant((4, 4, 4))),
    },
    entities: [
        Entity(name: "lamp", material: "lamp", shape: Quad(a: (0, 12, 0), b: (20, 12, 0), c: (20, 12, 20), d: (0, 12, 20))),
        Entity(name: "floor", material: "clay", shape: Quad(a: (-5, 0, -5), b: (-5, 0, 25), c: (25, 0, 25), d: (25, 0, -5))),
"#;

/// A scene of 300 spheres on a grid; sphere 150 at height `y` (grown to radius 2 above the
/// others), and one more entity if `extra`.
fn scene(y: f32, extra: bool) -> String {
    let mut s = String::from(SCENE_HEAD);
    for k in 0..300 {
        let (x, z) = ((k % 20) as f32, (k / 20) as f32 * 1.3);
        let (y, r) = match k {
            150 if y > 0.4 => (y, 2.0),
            _ => (0.4, 0.4),
        };
        s += &format!(
            "        Entity(name: \"s{k}\", material: \"clay\", shape: Sphere(center: ({x}, {y}, {z}), radius: {r})),\n"
        );
    }
    if extra {
        s += "        Entity(name: \"new\", material: \"clay\", shape: Sphere(center: (3, 3, 3), radius: 1)),\n";
    }
    s + "    ],\n)\n"
}

/// A cold render of the file at `path` with the live plan: its preview, then its final film.
fn cold(path: &std::path::Path) -> (Vec<Vec3>, Vec<Vec3>) {
    let mut r = Renderer::new(Some(2), PassPlan::Progressive { first: 1 }).expect("pool");
    r.load(path).unwrap_or_else(|e| panic!("{e}"));
    r.run_once();
    assert!(r.film_is_preview());
    let preview = r.film().mean();
    r.render_to_completion();
    (preview, r.film().mean())
}

#[test]
fn a_live_move_refits_for_the_preview_and_builds_before_real_samples() {
    let dir = temp_dir("refit-live");
    let path = write_scene(&dir, "scene.ron", &scene(0.4, false));
    let mut r = Renderer::new(Some(2), PassPlan::Progressive { first: 1 }).expect("pool");
    r.load(&path).unwrap_or_else(|e| panic!("{e}"));
    r.render_to_completion();
    let start = r.counters();
    assert_eq!(start.bvh_refits, 0, "a first load builds");

    // One sphere moves up: the preview comes from a refit, with no build.
    write_scene(&dir, "scene.ron", &scene(3.0, false));
    r.load(&path).unwrap_or_else(|e| panic!("{e}"));
    r.run_once();
    let previewed = r.counters();
    assert!(r.film_is_preview());
    assert_eq!(previewed.bvh_refits, start.bvh_refits + 1, "refitted");
    assert_eq!(
        previewed.bvh_builds, start.bvh_builds,
        "not built for the preview"
    );
    let preview = r.film().mean();
    r.render_to_completion();
    let done = r.counters();
    assert_eq!(
        done.bvh_builds,
        start.bvh_builds + 1,
        "built before real samples"
    );
    let (cold_preview, cold_final) = cold(&path);
    assert_eq!(preview, cold_preview, "the refitted preview shows the move");
    assert_eq!(
        r.film().mean(),
        cold_final,
        "the image equals a cold render"
    );

    // A new entity changes the owners: built at once, never refitted.
    write_scene(&dir, "scene.ron", &scene(3.0, true));
    r.load(&path).unwrap_or_else(|e| panic!("{e}"));
    r.run_once();
    assert_eq!(r.counters().bvh_refits, done.bvh_refits);
    assert_eq!(r.counters().bvh_builds, done.bvh_builds + 1);
    r.render_to_completion();
    assert_eq!(r.film().mean(), cold(&path).1);
}

#[test]
fn a_batch_render_never_refits() {
    let dir = temp_dir("refit-batch");
    let path = write_scene(&dir, "scene.ron", &scene(0.4, false));
    let mut r = Renderer::new(Some(2), PassPlan::Single).expect("pool");
    r.load(&path).unwrap_or_else(|e| panic!("{e}"));
    r.render_to_completion();
    write_scene(&dir, "scene.ron", &scene(3.0, false));
    r.load(&path).unwrap_or_else(|e| panic!("{e}"));
    r.render_to_completion();
    assert_eq!(r.counters().bvh_refits, 0);
    assert_eq!(r.counters().bvh_builds, 2);
}
