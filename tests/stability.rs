//! Stability where naive methods fail: self-intersection, far-from-origin geometry.

mod common;

use common::{render, temp_dir, write_scene};
use rondo::Overrides;

/// A furnace view (sky of radiance 1) of a diffuse sphere of albedo 0.5 seen from `eye`,
/// looking at `target` on its surface. A convex sphere reflects exactly 0.5 of the sky, so any
/// pixel darker than that is a ray that re-hit the surface it left.
fn furnace_on_sphere(center: [f64; 3], radius: f64, eye: [f64; 3], target: [f64; 3]) -> String {
    format!(
        r#"Scene(
    camera: Camera(position: ({}, {}, {}), look_at: ({}, {}, {}), fov: 30),
    settings: Settings(width: 24, height: 24, spp: 4, max_depth: 6, background: (1, 1, 1)),
    materials: {{ "grey": Diffuse(albedo: Constant((0.5, 0.5, 0.5))) }},
    entities: [ Entity(name: "ground", material: "grey", shape: Sphere(center: ({}, {}, {}), radius: {radius})) ],
)"#,
        eye[0], eye[1], eye[2], target[0], target[1], target[2], center[0], center[1], center[2]
    )
}

#[test]
fn spawned_rays_never_reintersect_large_or_distant_spheres() {
    let dir = temp_dir("self-intersection");
    // (centre, radius, eye, target): a ground sphere touching the origin (its points near the
    // origin carry the error of coordinates ~1000), a huge one, and a unit sphere far away.
    let cases = [
        (
            [0.0, -1000.0, 0.0],
            1000.0,
            [0.0, 2.0, -3.0],
            [0.0, 0.0, 0.0],
        ),
        ([0.0, -1e5, 0.0], 1e5, [0.0, 2.0, -3.0], [0.0, 0.0, 0.0]),
        ([1e6, 0.0, 0.0], 1.0, [1e6, 0.5, -2.5], [1e6, 0.0, -0.5]),
        ([0.0, 0.0, 0.0], 1e-3, [0.0, 0.0, -3e-3], [0.0, 0.0, 0.0]),
    ];
    for (k, (c, r, eye, target)) in cases.into_iter().enumerate() {
        let path = write_scene(
            &dir,
            &format!("s{k}.ron"),
            &furnace_on_sphere(c, r, eye, target),
        );
        let film = render(&path, Overrides::default(), None);
        let px = common::pixels(film.film());
        // Pixels that see the sphere read exactly 0.5; sky pixels read 1.
        let dark = px.iter().filter(|p| p.x < 0.5 - 1e-4).count();
        let on_sphere = px.iter().filter(|p| (p.x - 0.5).abs() < 1e-4).count();
        assert_eq!(dark, 0, "case {k}: {dark} pixels darker than the albedo");
        assert!(
            on_sphere > 100,
            "case {k}: only {on_sphere} pixels see the sphere"
        );
    }
}
