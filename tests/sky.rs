//! Environment maps and the sun against independent truth: a white furnace, closed-form
//! irradiance of a band and of a single texel, a sun's irradiance L·Ω and the penumbra its
//! angular diameter makes; and the map as a dependency built once per load of its file.

mod common;

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use common::{
    assert_methods_agree, point_camera, point_estimate, render, temp_dir, with, within, write_scene,
};
use rondo::scene::format::Method;

/// Writes a `width` × `height` OpenEXR map whose texel (x, y) has grey radiance `f(x, y)`.
fn write_map(
    dir: &Path,
    name: &str,
    width: u32,
    height: u32,
    f: impl Fn(u32, u32) -> f32,
) -> PathBuf {
    let mut data = Vec::new();
    for y in 0..height {
        for x in 0..width {
            data.extend([f(x, y); 3]);
        }
    }
    let image = image::Rgb32FImage::from_raw(width, height, data).expect("buffer size");
    let path = dir.join(name);
    image.save(&path).expect("write map");
    path
}

#[test]
fn a_constant_environment_is_a_white_furnace_for_every_method() {
    let dir = temp_dir("sky-furnace");
    write_map(&dir, "one.exr", 16, 8, |_, _| 1.0);
    for (material, exact) in [
        ("Diffuse(albedo: Constant((1, 1, 1)))", true),
        ("Dielectric(ior: 1.5)", false),
        ("Glossy(albedo: Constant((1, 1, 1)), roughness: 0.3)", false),
    ] {
        let scene = write_scene(
            &dir,
            "furnace.ron",
            &format!(
                "Scene(camera: {}, settings: Settings(width: 32, height: 32, max_depth: 64, \
                 environment: Environment(path: \"one.exr\")), materials: {{ \"m\": {material} }}, \
                 entities: [Entity(material: \"m\", shape: Sphere(center: (0, 0, 0), radius: 1))])",
                point_camera("(0.6, 0.3, -4)", "(0, 0, 0)", "(0, 1, 0)")
            ),
        );
        let mut estimates = Vec::new();
        for method in [Method::Naive, Method::Nee, Method::Mis] {
            let r = render(&scene, with(method, 64), None);
            let (mean, se) = point_estimate(&r);
            if exact && method == Method::Naive {
                // Every path is one diffuse bounce of weight 1 into radiance 1.
                for p in r.film().mean() {
                    assert!((p.x - 1.0).abs() < 1e-6, "{material}: naive pixel {}", p.x);
                }
            }
            if material.starts_with("Glossy") {
                // Single-scattering GGX loses energy: never more than the sky, at most.
                assert!(
                    mean <= 1.0 + 3.0 * se,
                    "{material} {method}: {mean} ± {se} gains"
                );
            } else {
                assert!(
                    within(mean, se, 1.0, 3.5),
                    "{material} {method}: {mean} ± {se}, expected 1"
                );
            }
            estimates.push((method, mean, se));
        }
        // The three methods estimate the same radiance.
        assert_methods_agree(material, &estimates);
    }
}

/// Radiance leaving a horizontal diffuse plane of albedo `albedo` at the origin under a map
/// of `width` × `height` texels, by each method, as (mean, standard error).
fn plane_under(dir: &Path, map: &str, albedo: f64, spp: u32, method: Method) -> (f64, f64) {
    let scene = write_scene(
        dir,
        "plane.ron",
        &format!(
            "Scene(camera: {}, settings: Settings(width: 32, height: 32, \
             environment: Environment(path: \"{map}\")), \
             materials: {{ \"ground\": Diffuse(albedo: Constant(({albedo}, {albedo}, {albedo}))) }}, \
             entities: [Entity(material: \"ground\", shape: Plane(point: (0, 0, 0), normal: (0, 1, 0)))])",
            point_camera("(0, 5, 0)", "(0, 0, 0)", "(0, 0, 1)")
        ),
    );
    point_estimate(&render(&scene, with(method, spp), None))
}

#[test]
fn a_band_and_a_single_texel_light_a_plane_as_the_closed_form_says() {
    let dir = temp_dir("sky-band");
    let (w, h) = (32u32, 16u32);
    // Rows 3 and 4 (θ from 3π/16 to 5π/16) at radiance 4, the rest black.
    write_map(&dir, "band.exr", w, h, |_, y| {
        if (3..5).contains(&y) { 4.0 } else { 0.0 }
    });
    // One texel (column 9, row 5) at radiance 300.
    write_map(&dir, "texel.exr", w, h, |x, y| {
        if (x, y) == (9, 5) { 300.0 } else { 0.0 }
    });
    let theta = |row: u32| PI * f64::from(row) / f64::from(h);
    let sin2 = |t: f64| t.sin().powi(2);
    let albedo = 0.5;
    // E = ∫ L cos θ dω: over a band of full azimuth L π (sin²θ₂ − sin²θ₁); over one texel
    // L Δφ (sin²θ₂ − sin²θ₁) / 2. The plane sends (albedo / π) E.
    let band = albedo / PI * 4.0 * PI * (sin2(theta(5)) - sin2(theta(3)));
    let texel =
        albedo / PI * 300.0 * (2.0 * PI / f64::from(w)) * (sin2(theta(6)) - sin2(theta(5))) / 2.0;
    for (map, expected) in [("band.exr", band), ("texel.exr", texel)] {
        for method in [Method::Naive, Method::Nee, Method::Mis] {
            let (mean, se) = plane_under(&dir, map, albedo, 256, method);
            assert!(
                within(mean, se, expected, 3.5),
                "{map} {method}: {mean} ± {se}, closed form {expected}"
            );
            if method != Method::Naive {
                // Importance sampling concentrates on the lit texels.
                let (_, naive_se) = plane_under(&dir, map, albedo, 256, Method::Naive);
                assert!(
                    se < naive_se,
                    "{map} {method}: se {se} not below naive's {naive_se}"
                );
            }
        }
    }
}

/// A scene under a sun of radiance `radiance` and angular diameter `diameter` degrees towards
/// `direction`, with `entities` and a camera.
fn sun_scene(camera: &str, size: (u32, u32), sun: &str, materials: &str, entities: &str) -> String {
    format!(
        "Scene(camera: {camera}, settings: Settings(width: {}, height: {}, sun: {sun}), \
         materials: {{ {materials} }}, entities: [{entities}])",
        size.0, size.1
    )
}

#[test]
fn a_sun_gives_a_plane_facing_it_the_irradiance_l_times_omega() {
    let dir = temp_dir("sky-sun");
    let n = "(0.3, 1.0, 0.2)";
    // The real sun's size for next-event estimation; a 10° one that BSDF sampling can find.
    for (diameter, methods) in [
        (0.53f64, &[Method::Nee, Method::Mis][..]),
        (10.0, &[Method::Naive, Method::Nee, Method::Mis][..]),
    ] {
        let radiance = 2000.0 / diameter;
        let half = (0.5 * diameter).to_radians();
        let omega = 2.0 * PI * (1.0 - half.cos());
        // The disk's cosine-weighted solid angle π sin², not L Ω: they differ by Ω·θ²/4,
        // 5·10⁻⁶ at 0.53°, more than the tolerance of a noiseless estimate (every light
        // sample of a plane facing the sun carries the same value).
        let e = radiance * PI * half.sin().powi(2);
        assert!((e / (radiance * omega) - 1.0).abs() < 1e-2);
        let expected = 0.8 / PI * e;
        let scene = write_scene(
            &dir,
            "sun.ron",
            &sun_scene(
                &point_camera("(1.5, 5, 1)", "(0, 0, 0)", "(0, 1, 0)"),
                (32, 32),
                &format!("Sun(direction: {n}, angular_diameter: {diameter}, radiance: {radiance})"),
                "\"ground\": Diffuse(albedo: Constant((0.8, 0.8, 0.8)))",
                &format!(
                    "Entity(material: \"ground\", shape: Plane(point: (0, 0, 0), normal: {n}))"
                ),
            ),
        );
        for &method in methods {
            let (mean, se) = point_estimate(&render(&scene, with(method, 256), None));
            assert!(
                within(mean, se, expected, 3.5) && (mean / expected - 1.0).abs() < 0.03,
                "{diameter}° {method}: {mean} ± {se}, expected {expected}"
            );
        }
    }
}

/// Fraction of a disk left of a line at signed distance `t` radii from its centre.
fn disk_fraction_below(t: f64) -> f64 {
    let t = t.clamp(-1.0, 1.0);
    1.0 - (t.acos() - t * (1.0 - t * t).sqrt()) / PI
}

#[test]
fn the_penumbra_of_an_edge_is_as_wide_as_the_sun_is_seen() {
    // A black slab 1 to 1.01 high over x < 0; the sun 30° from the zenith towards −x, 5° across.
    // A ground point x sees the part of the disk whose direction (angle β + δ from the zenith)
    // clears the slab's upper edge, h tan(β + δ) < x: the disk left of δ₀ = atan(x / h) − β. The
    // penumbra runs from h tan(β − a) to h tan(β + a), a the half-angle: 0.118 wide.
    let dir = temp_dir("sky-penumbra");
    let (beta, diameter) = (30f64.to_radians(), 5.0f64);
    let a = (0.5 * diameter).to_radians();
    let radiance = 1000.0;
    // The slab's top face, 1.01 high, holds the edge that casts the shadow.
    let top = 1.01;
    let x0 = top * beta.tan();
    // Camera straight down over the shadow's edge: 128 × 8 pixels over x0 ± 0.16 by ± 0.01.
    let camera = format!(
        "Camera(position: ({x0}, 3, 0), look_at: ({x0}, 0, 0), up: (0, 0, -1), fov: {})",
        2.0 * (0.01f64 / 3.0).atan().to_degrees()
    );
    let scene = write_scene(
        &dir,
        "penumbra.ron",
        &sun_scene(
            &camera,
            (128, 8),
            &format!(
                "Sun(direction: ({}, {}, 0), angular_diameter: {diameter}, radiance: {radiance})",
                -beta.sin(),
                beta.cos()
            ),
            "\"ground\": Diffuse(albedo: Constant((1, 1, 1))), \"black\": Diffuse(albedo: Constant((0, 0, 0)))",
            "Entity(material: \"ground\", shape: Plane(point: (0, 0, 0), normal: (0, 1, 0))), \
             Entity(material: \"black\", shape: Box(min: (-20, 1, -20), max: (0, 1.01, 20)))",
        ),
    );
    let r = render(&scene, with(Method::Mis, 256), None);
    let pixels = r.film().mean();
    let full = radiance * PI * a.sin().powi(2) * beta.cos() / PI;
    let pitch = 2.0 * 0.16 / 128.0;
    let column = |c: usize| -> f64 {
        (0..8)
            .map(|row| f64::from(pixels[row * 128 + c].x))
            .sum::<f64>()
            / 8.0
            / full
    };
    let mut worst = 0.0f64;
    let profile: Vec<(f64, f64)> = (0..128)
        .map(|c| {
            let x = x0 - 0.16 + (c as f64 + 0.5) * pitch;
            let expected = disk_fraction_below(((x / top).atan() - beta) / a);
            worst = worst.max((column(c) - expected).abs());
            (x, column(c))
        })
        .collect();
    assert!(
        worst < 0.05,
        "profile departs from the disk's by {worst} of full sun"
    );
    // The 10–90 % width, read off the rendered profile, against the disk's.
    let crossing = |level: f64| {
        let k = profile
            .iter()
            .position(|p| p.1 >= level)
            .expect("the profile rises");
        let (a, b) = (profile[k - 1], profile[k]);
        a.0 + (level - a.1) / (b.1 - a.1) * (b.0 - a.0)
    };
    let measured = crossing(0.9) - crossing(0.1);
    // The disk's 10–90 % points in δ₀ / a, solved by bisection.
    let solve = |level: f64| {
        let (mut lo, mut hi) = (-1.0, 1.0);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if disk_fraction_below(mid) < level {
                lo = mid
            } else {
                hi = mid
            }
        }
        top * (beta + 0.5 * (lo + hi) * a).tan()
    };
    let predicted = solve(0.9) - solve(0.1);
    assert!(
        (measured / predicted - 1.0).abs() < 0.05,
        "10–90 % penumbra {measured:.4} vs {predicted:.4} for a {diameter}° sun"
    );
}

#[test]
fn the_map_is_a_dependency_built_once_per_content_of_its_file() {
    let dir = temp_dir("sky-cache");
    let map = write_map(&dir, "sky.exr", 8, 4, |x, _| 1.0 + x as f32);
    let source = |strength: f32| {
        format!(
            "Scene(camera: Camera(position: (0, 0, -3), look_at: (0, 0, 0)), \
             settings: Settings(width: 8, height: 8, spp: 1, environment: Environment(path: \"sky.exr\", strength: {strength})))"
        )
    };
    let scene = write_scene(&dir, "scene.ron", &source(1.0));
    let mut r = rondo::Renderer::new(Some(1), rondo::PassPlan::Single).expect("pool");
    let info = r.load(&scene).expect("loads");
    assert!(info.dependencies.contains(&map), "{:?}", info.dependencies);
    assert_eq!(r.environment_builds(), 1);
    // A scene edit that keeps the map reuses its distribution.
    write_scene(&dir, "scene.ron", &source(2.0));
    r.load(&scene).expect("loads");
    assert_eq!(r.environment_builds(), 1);
    // A new map is built again.
    write_map(&dir, "sky.exr", 8, 4, |x, _| 2.0 + x as f32);
    r.load(&scene).expect("loads");
    assert_eq!(r.environment_builds(), 2);
    // A broken map is an error naming the file, the line and the field; nothing panics.
    std::fs::write(&map, b"not an image").expect("write");
    let e = r.load(&scene).expect_err("broken map").to_string();
    assert!(
        e.contains("sky.exr") && e.contains("settings.environment") && e.contains(":1:"),
        "{e}"
    );
}

#[test]
fn background_and_environment_are_exclusive_and_bad_suns_are_refused() {
    let dir = temp_dir("sky-errors");
    write_map(&dir, "sky.exr", 4, 2, |_, _| 1.0);
    let cases = [
        (
            "background: (1, 1, 1), environment: Environment(path: \"sky.exr\")",
            "not both",
        ),
        ("sun: Sun(direction: (0, 0, 0), radiance: 1)", "direction"),
        ("sun: Sun(direction: (0, 1, 0))", "irradiance"),
        (
            "sun: Sun(direction: (0, 1, 0), radiance: 1, irradiance: 1)",
            "not both",
        ),
        (
            "sun: Sun(direction: (0, 1, 0), radiance: 1, angular_diameter: 120)",
            "angular_diameter",
        ),
        (
            "environment: Environment(path: \"missing.exr\")",
            "missing.exr",
        ),
    ];
    for (settings, expected) in cases {
        let scene = write_scene(
            &dir,
            "bad.ron",
            &format!(
                "Scene(camera: Camera(position: (0, 0, -3), look_at: (0, 0, 0)), settings: Settings({settings}))"
            ),
        );
        let mut r = rondo::Renderer::new(Some(1), rondo::PassPlan::Single).expect("pool");
        let e = r.load(&scene).expect_err(settings).to_string();
        assert!(
            e.contains(expected) && e.contains("bad.ron:1:"),
            "{settings}: {e}"
        );
    }
}

#[test]
fn an_environment_strength_that_overflows_its_texels_is_refused() {
    // A texel of 1.7e38 is finite; 1e38 times it is not, and every sample would be dropped.
    let dir = temp_dir("sky-overflow");
    write_map(&dir, "hot.exr", 4, 2, |x, y| {
        if (x, y) == (1, 0) { 1.7e38 } else { 1.0 }
    });
    let load = |strength: &str| {
        let scene = write_scene(
            &dir,
            "hot.ron",
            &format!(
                "Scene(camera: Camera(position: (0, 0, -3), look_at: (0, 0, 0)), settings: Settings(environment: Environment(path: \"hot.exr\", strength: {strength})))"
            ),
        );
        let mut r = rondo::Renderer::new(Some(1), rondo::PassPlan::Single).expect("pool");
        r.load(&scene).map_err(|e| e.to_string())
    };
    let e = load("1e38").expect_err("overflowing strength refused");
    assert!(
        e.contains("hot.ron:1:")
            && e.contains("settings.environment")
            && e.contains("hot.exr")
            && e.contains("too large to represent"),
        "{e}"
    );
    load("1").expect("the map itself is finite");
}
