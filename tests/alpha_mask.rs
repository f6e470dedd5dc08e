//! Alpha masks (`Pbr(alpha_cutoff: …)`, glTF's `alphaMode: MASK`): the camera sees through a
//! mask exactly where its alpha is below the cutoff, shadows pass through it in proportion to
//! its open area, light-traced caustics pass through it as the camera's paths do, a mask absent
//! everywhere changes no path, and a hostile stack of masked layers ends.

mod common;

use std::f64::consts::PI;
use std::path::Path;

use common::{point_camera, point_estimate, render, temp_dir, with, within, write_scene};
use glam::Vec3;
use rondo::render::MAX_PASS_THROUGHS;
use rondo::scene::format::Method;
use rondo::shading::sampler::SamplerKind;
use rondo::{Film, Overrides};

/// Writes a `width` × `height` RGBA8 PNG whose texel (x, y) (row 0 at the top) has colour
/// `rgb` and alpha `alpha(x, y)`.
fn write_rgba(
    dir: &Path,
    name: &str,
    size: (u32, u32),
    rgb: [u8; 3],
    alpha: impl Fn(u32, u32) -> u8,
) {
    let mut data = Vec::new();
    for y in 0..size.1 {
        for x in 0..size.0 {
            data.extend(rgb);
            data.push(alpha(x, y));
        }
    }
    let image = image::RgbaImage::from_raw(size.0, size.1, data).expect("buffer size");
    image.save(dir.join(name)).expect("write png");
}

#[test]
fn the_camera_sees_through_exactly_the_texels_below_the_cutoff() {
    let dir = temp_dir("alpha-camera");
    // Alphas 0 and 255 on the top row, 200 and 100 on the bottom: with cutoff 0.5 the top-left
    // and bottom-right texels are absent (100/255 < 0.5 ≤ 200/255).
    let alphas = [[0u8, 255], [200, 100]];
    write_rgba(&dir, "mask.png", (2, 2), [30, 60, 90], |x, y| {
        alphas[y as usize][x as usize]
    });
    // The masked quad spans x, y in [−1, 1] at z = 0 (u along +x, v along +y) and emits 3; the
    // camera on +z sees only it (its view is 0.8 wide at the quad). Behind it, a green lamp
    // covers x < 0; elsewhere the background is seen. One ray per path: only emission counts,
    // so every pixel is exact. The texel boundaries fall on the image's middle row and column,
    // which are pixel boundaries.
    let scene = write_scene(
        &dir,
        "mask.ron",
        "Scene(camera: Camera(position: (0, 0, 3), look_at: (0, 0, 0), up: (0, 1, 0), fov: 30), \
         settings: Settings(width: 8, height: 8, spp: 4, max_depth: 1, background: (0.2, 0.4, 0.6)), \
         materials: { \
           \"leaf\": Pbr(base_color: Image(path: \"mask.png\"), emissive: Constant((3, 3, 3)), alpha_cutoff: 0.5), \
           \"lamp\": Light(emit: Constant((0, 5, 0))) }, \
         entities: [ \
           Entity(material: \"leaf\", shape: Quad(a: (-1, -1, 0), b: (1, -1, 0), c: (1, 1, 0), d: (-1, 1, 0))), \
           Entity(material: \"lamp\", shape: Quad(a: (-2, -2, -1), b: (0, -2, -1), c: (0, 2, -1), d: (-2, 2, -1))) ])",
    );
    for method in [Method::Naive, Method::Nee, Method::Mis] {
        let r = render(&scene, with(method, 4), None);
        let film = r.film();
        let pixels = film.mean();
        for (k, p) in pixels.iter().enumerate() {
            let (x, y) = (k % 8, k / 8);
            // The pixel's texel: image column from the left, row from the top.
            let (i, j) = (x / 4, y / 4);
            let expected = if f32::from(alphas[j][i]) / 255.0 >= 0.5 {
                Vec3::splat(3.0)
            } else if i == 0 {
                Vec3::new(0.0, 5.0, 0.0)
            } else {
                Vec3::new(0.2, 0.4, 0.6)
            };
            assert!(
                (*p - expected).abs().max_element() < 1e-4,
                "{method}: pixel ({x}, {y}) is {p}, expected {expected}"
            );
        }
    }
}

#[test]
fn a_mask_between_a_plane_and_the_sun_lets_through_its_open_fraction() {
    let dir = temp_dir("alpha-shadow");
    // A 64 × 64 mask over the 2 × 2 quad at height 1 above the plane: texels of even column
    // and even row are open (alpha 0), the rest opaque: a pattern of period two texels, a
    // quarter open. The plane's point under a texel corner (the origin) sees the sun's disk
    // through the mask; reflecting the disk's directions at the two texel boundaries through
    // that corner keeps their cosine weight and maps each texel to one of each parity class, so
    // exactly a quarter of the sun's cosine-weighted solid angle is seen, whatever the disk's
    // size against the texels.
    write_rgba(&dir, "lattice.png", (64, 64), [0, 0, 0], |x, y| {
        if x % 2 == 0 && y % 2 == 0 { 0 } else { 255 }
    });
    let open = 0.25;
    // Two rays per path: the plane's direct light only, never light the mask reflects.
    for (diameter, methods, spp) in [
        (0.53f64, &[Method::Nee, Method::Mis][..], 64),
        (10.0, &[Method::Naive, Method::Nee, Method::Mis][..], 1024),
    ] {
        let radiance = 2000.0 / diameter;
        let half = (0.5 * diameter).to_radians();
        // Irradiance of a disk around the normal: L π sin²(half angle).
        let e = radiance * PI * half.sin().powi(2);
        let expected = 0.8 / PI * open * e;
        let scene = write_scene(
            &dir,
            "shadow.ron",
            &format!(
                "Scene(camera: {}, settings: Settings(width: 32, height: 32, max_depth: 2, \
                 sun: Sun(direction: (0, 1, 0), angular_diameter: {diameter}, radiance: {radiance})), \
                 materials: {{ \"ground\": Diffuse(albedo: Constant((0.8, 0.8, 0.8))), \
                   \"leaves\": Pbr(base_color: Image(path: \"lattice.png\"), alpha_cutoff: 0.5) }}, \
                 entities: [ \
                   Entity(material: \"ground\", shape: Plane(point: (0, 0, 0), normal: (0, 1, 0))), \
                   Entity(material: \"leaves\", shape: Quad(a: (-1, 1, -1), b: (1, 1, -1), c: (1, 1, 1), d: (-1, 1, 1))) ])",
                // Below the mask, so that the camera sees the plane's point directly.
                point_camera("(3, 0.5, 2)", "(0, 0, 0)", "(0, 1, 0)")
            ),
        );
        for &method in methods {
            let (mean, se) = point_estimate(&render(&scene, with(method, spp), None));
            assert!(
                within(mean, se, expected, 3.5) && (mean / expected - 1.0).abs() < 0.05,
                "{diameter}° {method}: {mean} ± {se}, expected {expected}"
            );
        }
    }
}

/// A scene of `tests/caustics.rs`'s mirrored-sun test, written to `dir`: a diffuse ceiling
/// (ρ = 0.5, y = 2, x ∈ [−4, −2]) seen from below, a perfect mirror at y = 0 (x ∈ [−2, 0]),
/// black background, paths of 3 rays; with `settings`, `materials` and `entities` added.
fn ceiling_over_a_mirror(
    dir: &Path,
    settings: &str,
    materials: &str,
    entities: &str,
) -> std::path::PathBuf {
    write_scene(
        dir,
        "mirror.ron",
        &format!(
            r#"Scene(
    camera: Camera(position: (-3, 0.2, 0), look_at: (-3, 2, 0), up: (0, 0, 1), fov: 30),
    settings: Settings(max_depth: 3, background: (0, 0, 0), {settings}),
    materials: {{
        "ceiling": Diffuse(albedo: Constant((0.5, 0.5, 0.5))),
        "mirror": Metal(albedo: Constant((1, 1, 1)), roughness: 0),
        {materials}
    }},
    entities: [
        Entity(material: "ceiling", shape: Quad(a: (-4, 2, -1), b: (-2, 2, -1), c: (-2, 2, 1), d: (-4, 2, 1))),
        Entity(material: "mirror", shape: Quad(a: (-2, 0, -1.5), b: (0, 0, -1.5), c: (0, 0, 1.5), d: (-2, 0, 1.5))),
        {entities}
    ],
)"#
        ),
    )
}

#[test]
fn a_mirrored_sun_reaches_a_ceiling_through_masks_by_light_tracing() {
    // The closed-form caustic of tests/caustics.rs: a sun of irradiance E = 3 from 45° falls on
    // a perfect mirror at y = 0 and is reflected onto a diffuse ceiling (ρ = 0.5) at y = 2,
    // seen from below, radiance ρ/π · E cos 45°. Only light tracing finds it (the path tracer's
    // BSDF samples nearly never hit the 0.53° sun), so without light paths through masks the
    // ceiling stays black. Two masked quads stand in the way:
    // - `pane`, horizontal at y = 1.5, open everywhere: the reflected light and the camera's
    //   view of the ceiling (the light paths' connections) both cross it, and it must change
    //   nothing;
    // - `grille`, vertical at x = −2 between the mirror and the part of the ceiling the camera
    //   sees, a 256 × 256 checkerboard of open and opaque texels: it must let through half the
    //   light, on average over the ceiling the camera sees (its shadow is the checkerboard,
    //   projected along the light).
    let dir = temp_dir("alpha-caustic");
    write_rgba(&dir, "open.png", (2, 2), [0, 0, 0], |_, _| 0);
    write_rgba(&dir, "checker.png", (256, 256), [0, 0, 0], |x, y| {
        if (x + y) % 2 == 0 { 0 } else { 255 }
    });
    let expected = 0.5 / PI * 3.0 * std::f64::consts::FRAC_1_SQRT_2;
    for (grille, open) in [(false, 1.0), (true, 0.5)] {
        let grille = if grille {
            "Entity(material: \"grille\", shape: Quad(a: (-2, 0, -1.5), b: (-2, 2, -1.5), c: (-2, 2, 1.5), d: (-2, 0, 1.5))),"
        } else {
            ""
        };
        let scene = ceiling_over_a_mirror(
            &dir,
            "width: 24, height: 24, spp: 1024, sun: Sun(direction: (1, 1, 0), angular_diameter: 0.53, irradiance: 3.0, \
             colour: (1, 1, 1))",
            r#""pane": Pbr(base_color: Image(path: "open.png"), alpha_cutoff: 0.5),
               "grille": Pbr(base_color: Image(path: "checker.png"), alpha_cutoff: 0.5),"#,
            &format!(
                "Entity(material: \"pane\", shape: Quad(a: (-4.5, 1.5, -1.5), b: (-1.5, 1.5, -1.5), \
                 c: (-1.5, 1.5, 1.5), d: (-4.5, 1.5, 1.5))), {grille}"
            ),
        );
        let (mean, se) = point_estimate(&render(&scene, with(Method::Caustics, 1024), None));
        let want = open * expected;
        assert!(
            (mean / want - 1.0).abs() < 0.05,
            "open {open}: ceiling {mean} ± {se}, expected {want}"
        );
    }
}

#[test]
fn a_masked_emitter_lights_only_from_its_present_points() {
    let dir = temp_dir("alpha-emitter");
    // The lattice of the shadow test on an emitter of radiance 2 (from both sides), a 2 × 2
    // square at height 1 over the plane: by the same symmetry, the plane's point under a
    // texel corner receives exactly the present three quarters of what the whole square
    // would send. Light sampling picks points on the whole square; those where the mask is
    // absent must send nothing.
    write_rgba(&dir, "lattice.png", (64, 64), [0, 0, 0], |x, y| {
        if x % 2 == 0 && y % 2 == 0 { 0 } else { 255 }
    });
    let present = 0.75;
    // Form factor from a point to a parallel rectangle X·h by Y·h with a corner above it, at
    // height h: (X/√(1+X²)·atan(Y/√(1+X²)) + Y/√(1+Y²)·atan(X/√(1+Y²))) / 2π; the square is
    // four such rectangles with X = Y = 1. Irradiance = L·π·F.
    let corner = 2.0 * (0.5f64.sqrt() * (0.5f64.sqrt()).atan()) / (2.0 * PI);
    let e = 2.0 * PI * 4.0 * corner;
    let expected = 0.8 / PI * present * e;
    let scene = write_scene(
        &dir,
        "emitter.ron",
        &format!(
            "Scene(camera: {}, settings: Settings(width: 32, height: 32, max_depth: 2), \
             materials: {{ \"ground\": Diffuse(albedo: Constant((0.8, 0.8, 0.8))), \
               \"panel\": Pbr(base_color: Image(path: \"lattice.png\"), emissive: Constant((2, 2, 2)), \
                 alpha_cutoff: 0.5) }}, \
             entities: [ \
               Entity(material: \"ground\", shape: Plane(point: (0, 0, 0), normal: (0, 1, 0))), \
               Entity(material: \"panel\", shape: Quad(a: (-1, 1, -1), b: (1, 1, -1), c: (1, 1, 1), d: (-1, 1, 1))) ])",
            point_camera("(3, 0.5, 2)", "(0, 0, 0)", "(0, 1, 0)")
        ),
    );
    for method in [Method::Naive, Method::Nee, Method::Mis] {
        let (mean, se) = point_estimate(&render(&scene, with(method, 256), None));
        assert!(
            within(mean, se, expected, 3.5) && (mean / expected - 1.0).abs() < 0.03,
            "{method}: {mean} ± {se}, expected {expected}"
        );
    }
}

#[test]
fn a_masked_emitter_seen_in_a_mirror_sends_light_paths_from_its_present_points() {
    // A 2 × 2 emitter at the ceiling's height lights the ceiling only through a mirror below
    // (it is edge-on to the ceiling), so under `caustics` light tracing carries all of it. A
    // 256 × 256 checkerboard mask, half present, on an emitter of radiance 2 must send what
    // the same emitter without a mask sends at radiance 1 (each ceiling point sees the
    // emitter's mirror image over thousands of texels); sending from absent points as well
    // would double it. A Z-test of the two ceilings' means over their pixels.
    let dir = temp_dir("alpha-emitter-mirror");
    write_rgba(&dir, "checker.png", (256, 256), [0, 0, 0], |x, y| {
        if (x + y) % 2 == 0 { 0 } else { 255 }
    });
    write_rgba(&dir, "solid.png", (2, 2), [0, 0, 0], |_, _| 255);
    let ceiling = |texture: &str, radiance: f64| {
        let scene = ceiling_over_a_mirror(
            &dir,
            "width: 48, height: 48",
            &format!(
                r#""panel": Pbr(base_color: Image(path: "{texture}"),
                   emissive: Constant(({radiance}, {radiance}, {radiance})), alpha_cutoff: 0.5),"#
            ),
            r#"Entity(material: "panel", shape: Quad(a: (0, 2, -1), b: (2, 2, -1), c: (2, 2, 1), d: (0, 2, 1))),"#,
        );
        point_estimate(&render(&scene, with(Method::Caustics, 512), None))
    };
    let (masked, se_masked) = ceiling("checker.png", 2.0);
    let (whole, se_whole) = ceiling("solid.png", 1.0);
    assert!(
        whole > 0.005 && se_whole < 0.1 * whole,
        "the ceiling is lit through the mirror: {whole} ± {se_whole}"
    );
    assert!(
        (masked - whole).abs() <= 3.5 * se_masked.hypot(se_whole),
        "masked at radiance 2: {masked} ± {se_masked}; whole at 1: {whole} ± {se_whole}"
    );
}

/// The Cornell box (scenes/cornell.ron) with a glass ball and, if `ghosts`, two masked quads
/// across it that are absent everywhere: one whose image has alpha 0 in every texel, one whose
/// cutoff is above any alpha.
fn cornell(dir: &Path, ghosts: bool) -> std::path::PathBuf {
    let source =
        std::fs::read_to_string(common::scenes_dir().join("cornell.ron")).expect("cornell.ron");
    let mut materials = String::from("\"glass\": Dielectric(ior: 1.5), ");
    let mut entities = String::from(
        "Entity(material: \"glass\", shape: Sphere(center: (150, 300, 200), radius: 60)), ",
    );
    if ghosts {
        materials += "\"clear\": Pbr(base_color: Image(path: \"clear.png\"), alpha_cutoff: 0.5), \
                      \"over\": Pbr(base_color: Constant((0.5, 0.5, 0.5)), alpha_cutoff: 1.5), ";
        // A slope from the floor's front to the ceiling's back, and a wall across the lamp's
        // light down the middle of the box. Neither meets another surface: where a ghost meets
        // a wall, the ray that passes through it starts a rounding error beyond the wall.
        entities += "Entity(material: \"clear\", shape: Quad(a: (5, 5, 20), b: (550, 5, 20), \
                         c: (550, 550, 540), d: (5, 550, 540))), \
                     Entity(material: \"over\", shape: Quad(a: (278, -10, -10), b: (278, -10, 565), \
                         c: (278, 565, 565), d: (278, 565, -10))), ";
    }
    let source = source
        .replacen("materials: {", &format!("materials: {{ {materials}"), 1)
        .replacen("entities: [", &format!("entities: [ {entities}"), 1);
    write_scene(
        dir,
        if ghosts { "ghosts.ron" } else { "plain.ron" },
        &source,
    )
}

#[test]
fn masks_absent_everywhere_change_no_path() {
    let dir = temp_dir("alpha-ghost");
    write_rgba(&dir, "clear.png", (2, 2), [255, 0, 0], |_, _| 0);
    let (plain, ghosts) = (cornell(&dir, false), cornell(&dir, true));
    let samplers = [SamplerKind::Independent, SamplerKind::Sobol];
    for (method, sampler) in [Method::Naive, Method::Nee, Method::Mis]
        .into_iter()
        .flat_map(|m| samplers.map(|s| (m, s)))
    {
        let overrides = Overrides {
            width: Some(24),
            height: Some(24),
            spp: Some(4),
            method: Some(method),
            sampler: Some(sampler),
            ..Overrides::default()
        };
        let film = |path: &Path| {
            let mut r = rondo::Renderer::new(None, rondo::PassPlan::Single).expect("thread pool");
            r.set_overrides(overrides);
            r.set_features(true);
            r.load(path).unwrap_or_else(|e| panic!("{e}"));
            r.render_to_completion();
            r.film().clone()
        };
        let (a, b) = (film(&plain), film(&ghosts));
        let features = |f: &Film| {
            let x = f.features.as_ref().expect("features");
            (x.albedo_mean(f.count()), x.normal_mean(f.count()))
        };
        let ((albedo_a, normal_a), (albedo_b, normal_b)) = (features(&a), features(&b));
        // The features use no random numbers and see through the ghosts.
        assert!(
            albedo_a == albedo_b && normal_a == normal_b,
            "{method} {sampler:?}: features"
        );
        if method == Method::Naive {
            // Radiance is a product of the constant albedos and emission: bit for bit.
            assert!(a == b, "{method} {sampler:?}: the film changed");
        } else {
            // Light sampling weighs by distances and cosines, which the shifted origins of
            // the rays that passed through change by a few ulps (the largest change seen is
            // 3·10⁻⁵ of a pixel); a sampler dimension drawn would change the pixels by their
            // noise, about 10 %.
            let worst = a
                .mean()
                .iter()
                .zip(b.mean())
                .map(|(p, q)| ((*p - q).abs() / q.abs().max(Vec3::splat(1e-3))).max_element())
                .fold(0.0, f32::max);
            assert!(
                worst < 1e-4,
                "{method} {sampler:?}: a pixel changed by {worst} of itself"
            );
        }
    }
}

/// Writes an OBJ of `count` unit-less squares spanning x, y in [−1, 1], the k-th at
/// z = −k · `spacing`.
fn write_stack(dir: &Path, name: &str, count: usize, spacing: f64) {
    let mut obj = String::new();
    for k in 0..count {
        let z = -(k as f64) * spacing;
        obj += &format!("v -1 -1 {z}\nv 1 -1 {z}\nv 1 1 {z}\nv -1 1 {z}\n");
        let v = 4 * k + 1;
        obj += &format!("f {} {} {} {}\n", v, v + 1, v + 2, v + 3);
    }
    std::fs::write(dir.join(name), obj).expect("write obj");
}

#[test]
fn a_hostile_stack_of_masked_layers_ends() {
    let dir = temp_dir("alpha-stack");
    // Layers absent everywhere (cutoff above any alpha) that would emit 2 if present, in front
    // of the background: 5000 coincident ones are passed at once; of spaced ones, at most
    // MAX_PASS_THROUGHS per ray, after which the next layer counts as present.
    let (few, many) = (1000, 5000);
    assert!(few < MAX_PASS_THROUGHS as usize && MAX_PASS_THROUGHS as usize + 1 < many);
    write_stack(&dir, "coincident.obj", many, 0.0);
    write_stack(&dir, "few.obj", few, 1e-4);
    write_stack(&dir, "many.obj", many, 1e-4);
    let background = Vec3::new(0.1, 0.2, 0.3);
    for (mesh, expected) in [
        ("coincident.obj", background),
        ("few.obj", background),
        ("many.obj", Vec3::splat(2.0)),
    ] {
        let scene = write_scene(
            &dir,
            "stack.ron",
            &format!(
                "Scene(camera: Camera(position: (0, 0, 3), look_at: (0, 0, 0), up: (0, 1, 0), fov: 30), \
                 settings: Settings(width: 8, height: 8, max_depth: 4, background: (0.1, 0.2, 0.3)), \
                 materials: {{ \"ghost\": Pbr(emissive: Constant((2, 2, 2)), alpha_cutoff: 2) }}, \
                 entities: [ Entity(material: \"ghost\", shape: Mesh(path: \"{mesh}\")) ])"
            ),
        );
        for method in [Method::Naive, Method::Mis] {
            let r = render(&scene, with(method, 1), None);
            for p in r.film().mean() {
                assert!(p.is_finite(), "{mesh} {method}: {p}");
                if mesh != "many.obj" {
                    assert!(
                        (p - expected).abs().max_element() < 1e-5,
                        "{mesh} {method}: {p}, expected the background {expected}"
                    );
                } else {
                    // The layer taken as present emits 2 and reflects what it sees.
                    assert!(p.min_element() >= 2.0 - 1e-5, "{mesh} {method}: {p}");
                }
            }
        }
    }
}
