//! The feature buffers (AOVs) a denoiser is guided by: albedo and shading normal of the first
//! hit that is not a perfect mirror or glass, checked against values computed here by hand
//! (texture bytes decoded with the sRGB standard's formula, ray–sphere intersections), and
//! their exact sums: the same bits whatever the thread count or the pass split.

mod common;

use common::{temp_dir, write_scene};
use glam::{DVec3, Vec3};
use rondo::{Overrides, PassPlan, Renderer};

/// The sRGB decoding of an 8-bit value (IEC 61966-2-1), written out here rather than taken from
/// rondo.
fn srgb_byte_to_linear(b: u8) -> f64 {
    let c = f64::from(b) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Renders `source` with features collected; returns the renderer.
fn render_features(source: &str, spp: u32, threads: Option<usize>, plan: PassPlan) -> Renderer {
    let dir = temp_dir("aov");
    let path = write_scene(&dir, "scene.ron", source);
    render_file(&path, spp, threads, plan)
}

fn render_file(
    path: &std::path::Path,
    spp: u32,
    threads: Option<usize>,
    plan: PassPlan,
) -> Renderer {
    let mut r = Renderer::new(threads, plan).expect("thread pool");
    r.set_features(true);
    r.set_overrides(Overrides {
        spp: Some(spp),
        ..Overrides::default()
    });
    r.load(path).unwrap_or_else(|e| panic!("{e}"));
    r.render_to_completion();
    r
}

fn albedo_of(r: &Renderer) -> Vec<Vec3> {
    let film = r.film();
    let f = film.features.as_ref().expect("features were collected");
    f.albedo_mean(film.count())
}

fn normal_of(r: &Renderer) -> Vec<Vec3> {
    let film = r.film();
    let f = film.features.as_ref().expect("features were collected");
    f.normal_mean(film.count())
}

#[test]
fn a_textured_quads_albedo_buffer_equals_its_texture() {
    let dir = temp_dir("aov-texture");
    // A 2×2 texture: its top-left texel is red, top-right green, bottom-left blue, bottom-right
    // grey.
    let bytes: [[u8; 3]; 4] = [[255, 0, 0], [0, 255, 0], [0, 0, 255], [128, 64, 32]];
    let texture = image::RgbImage::from_fn(2, 2, |x, y| image::Rgb(bytes[(y * 2 + x) as usize]));
    texture.save(dir.join("t.png")).expect("texture written");
    // The quad spans [-1, 1]² at z = 0 (u along x, v along y) and fills the view (half-height
    // 2·tan 20° = 0.73 < 1), so the texels' quadrants meet at the image's centre lines.
    let scene = write_scene(
        &dir,
        "scene.ron",
        r#"Scene(
            camera: Camera(position: (0, 0, 2), look_at: (0, 0, 0), fov: 40),
            settings: Settings(width: 32, height: 32, spp: 4, max_depth: 2, method: Naive),
            materials: { "t": Diffuse(albedo: Image(path: "t.png")) },
            entities: [Entity(name: "q", material: "t",
                shape: Quad(a: (-1, -1, 0), b: (1, -1, 0), c: (1, 1, 0), d: (-1, 1, 0)))],
        )"#,
    );
    let r = render_file(&scene, 4, None, PassPlan::Single);
    let albedo = albedo_of(&r);
    let mut checked = 0;
    for y in 0..32 {
        for x in 0..32 {
            if (15..=16).contains(&x) || (15..=16).contains(&y) {
                continue; // pixels on a texel edge average two texels
            }
            let texel = usize::from(y >= 16) * 2 + usize::from(x >= 16);
            let expected = bytes[texel].map(srgb_byte_to_linear);
            let got = albedo[y * 32 + x];
            for c in 0..3 {
                assert!(
                    (f64::from(got[c]) - expected[c]).abs() < 1e-5,
                    "pixel ({x}, {y}) channel {c}: {got} against {expected:?}"
                );
            }
            checked += 1;
        }
    }
    assert_eq!(checked, 30 * 30);
}

/// The mean, over a 16 × 16 grid of points of pixel (x, y), of the outward normal of the unit
/// sphere at the origin where the camera ray through the point hits it (`None` if a point
/// misses). The camera: at (0, 0, 4) looking down −z, vertical fov 40°, square image of `size`.
fn analytic_mean_normal(x: usize, y: usize, size: usize) -> Option<DVec3> {
    let half = (20f64).to_radians().tan();
    let origin = DVec3::new(0.0, 0.0, 4.0);
    let mut sum = DVec3::ZERO;
    for i in 0..16 {
        for j in 0..16 {
            let px = x as f64 + (f64::from(i) + 0.5) / 16.0;
            let py = y as f64 + (f64::from(j) + 0.5) / 16.0;
            let sx = (2.0 * px / size as f64 - 1.0) * half;
            let sy = (1.0 - 2.0 * py / size as f64) * half;
            let d = DVec3::new(sx, sy, -1.0).normalize();
            // |o + t d|² = 1.
            let b = origin.dot(d);
            let disc = b * b - (origin.length_squared() - 1.0);
            if disc < 0.0 {
                return None;
            }
            let t = -b - disc.sqrt();
            sum += (origin + t * d).normalize();
        }
    }
    Some(sum / 256.0)
}

#[test]
fn a_spheres_normal_buffer_equals_its_analytic_normals() {
    let size = 48;
    let r = render_features(
        r#"Scene(
            camera: Camera(position: (0, 0, 4), look_at: (0, 0, 0), fov: 40),
            settings: Settings(width: 48, height: 48, spp: 64, max_depth: 2, method: Naive),
            materials: { "m": Diffuse(albedo: Constant((0.5, 0.5, 0.5))) },
            entities: [Entity(name: "s", material: "m", shape: Sphere(center: (0, 0, 0), radius: 1))],
        )"#,
        64,
        None,
        PassPlan::Single,
    );
    let normals = normal_of(&r);
    let (mut inside, mut sky) = (0, 0);
    for y in 0..size {
        for x in 0..size {
            let got = normals[y * size + x].as_dvec3();
            match analytic_mean_normal(x, y, size) {
                Some(n) => {
                    assert!(
                        (got - n).length() < 0.01,
                        "pixel ({x}, {y}): {got} against {n}"
                    );
                    inside += 1;
                }
                None => {
                    // Pixels that the sphere's edge crosses hold a mix; only those wholly
                    // outside it (all four corners miss by a margin) must see the sky.
                    let centre = (
                        (x as f64 + 0.5) / size as f64 - 0.5,
                        (y as f64 + 0.5) / size as f64 - 0.5,
                    );
                    if (centre.0 * centre.0 + centre.1 * centre.1).sqrt() > 0.45 {
                        assert_eq!(got, DVec3::ZERO, "pixel ({x}, {y}) sees the sky");
                        sky += 1;
                    }
                }
            }
        }
    }
    assert!(inside > 500, "{inside} pixels inside the sphere");
    assert!(sky > 100, "{sky} sky pixels");
}

/// The camera looks at a mirror (z = 0) of material `mirror` and sees, reflected, a diffuse wall
/// behind itself (z = 4, wider than the view), rendered by `method`.
fn mirror_scene(mirror: &str, method: &str) -> String {
    format!(
        r#"Scene(
        camera: Camera(position: (0, 0, 2), look_at: (0, 0, 0), fov: 30),
        settings: Settings(width: 16, height: 16, spp: 4, max_depth: 4, method: {method}),
        materials: {{
            "mirror": {mirror},
            "wall": Diffuse(albedo: Constant((0.2, 0.4, 0.6))),
        }},
        entities: [
            Entity(name: "m", material: "mirror",
                shape: Quad(a: (-5, -5, 0), b: (5, -5, 0), c: (5, 5, 0), d: (-5, 5, 0))),
            Entity(name: "w", material: "wall",
                shape: Quad(a: (-20, -20, 4), b: (20, -20, 4), c: (20, 20, 4), d: (-20, 20, 4))),
        ],
    )"#
    )
}

#[test]
fn through_a_mirror_the_buffers_hold_the_mirrored_object_tinted_by_the_mirror() {
    let scene = |tint: &str| {
        mirror_scene(
            &format!("Metal(albedo: Constant({tint}), roughness: 0)"),
            "Naive",
        )
    };
    for (tint, expected) in [
        ("(1, 1, 1)", Vec3::new(0.2, 0.4, 0.6)),
        ("(0.5, 1, 0.25)", Vec3::new(0.1, 0.4, 0.15)),
    ] {
        let r = render_features(&scene(tint), 4, None, PassPlan::Single);
        for (a, n) in albedo_of(&r).iter().zip(normal_of(&r)) {
            assert!((*a - expected).abs().max_element() < 1e-6, "{a}");
            // The wall's normal on the side the reflected rays arrive from.
            assert!((n - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-6, "{n}");
        }
    }
}

#[test]
fn an_emitters_albedo_is_its_emission_clamped_to_one_per_channel() {
    // Open Image Denoise takes albedos in [0, 1]: a lamp of (2, 3, 4) · 5 records white, a dim
    // one of (0.1, 0.2, 0.05) · 5 its emission (0.5, 1, 0.25).
    let lamp = |emit: &str| {
        format!(
            r#"Scene(
            camera: Camera(position: (0, 0, 2), look_at: (0, 0, 0), fov: 30),
            settings: Settings(width: 8, height: 8, spp: 2, max_depth: 3, method: Mis),
            materials: {{ "lamp": Light(emit: Constant({emit}), intensity: 5) }},
            entities: [Entity(name: "l", material: "lamp",
                shape: Quad(a: (-5, -5, 0), b: (5, -5, 0), c: (5, 5, 0), d: (-5, 5, 0)))],
        )"#
        )
    };
    for (emit, expected) in [
        ("(2, 3, 4)", Vec3::ONE),
        ("(0.1, 0.2, 0.05)", Vec3::new(0.5, 1.0, 0.25)),
    ] {
        let r = render_features(&lamp(emit), 2, None, PassPlan::Single);
        for a in albedo_of(&r) {
            assert!((a - expected).abs().max_element() < 1e-6, "{emit}: {a}");
        }
    }
}

#[test]
fn a_pixel_half_covering_the_sun_records_half_its_albedo() {
    // A 5 × 5 image of 0.05° whose centre column is centred on the edge of a sun of 20° (radius
    // 10°, radiance 10⁴) in a black sky: across the image the edge is straight to within 10⁻³ of
    // a pixel, so the two columns on one side see only sun (albedo 1, clamped per sample), the
    // two on the other only sky (0), and the centre column half of each: 0.5.
    let r = 10f32.to_radians();
    let sun = format!("({}, 0, {})", -r.sin(), r.cos());
    let scene = format!(
        r#"Scene(
        camera: Camera(position: (0, 0, 0), look_at: (0, 0, 1), fov: 0.05),
        settings: Settings(width: 5, height: 5, max_depth: 2,
            sun: Sun(direction: {sun}, angular_diameter: 20, radiance: 10000)),
        materials: {{ "m": Diffuse(albedo: Constant((0.5, 0.5, 0.5))) }},
        entities: [Entity(name: "s", material: "m",
            shape: Sphere(center: (0, 0, -10), radius: 1))],
    )"#
    );
    let r = render_features(&scene, 256, None, PassPlan::Single);
    let albedo = albedo_of(&r);
    let column = |x: usize| (0..5).map(|y| f64::from(albedo[y * 5 + x].x)).sum::<f64>() / 5.0;
    let (left, right) = (column(0) + column(1), column(3) + column(4));
    let (sun_side, sky_side) = if left > right {
        (left, right)
    } else {
        (right, left)
    };
    assert!(
        (sun_side - 2.0).abs() < 1e-6,
        "columns in the sun: {sun_side} / 2"
    );
    assert!(sky_side.abs() < 1e-6, "columns in the sky: {sky_side} / 2");
    assert!(
        (column(2) - 0.5).abs() < 0.01,
        "the edge column: {}",
        column(2)
    );
}

#[test]
fn a_mirror_like_pbr_or_glossy_records_what_it_reflects_as_a_smooth_metal_does() {
    // As the mirror test above (`mirror_scene`), with the mirror a roughness-0 `Metal`, a `Pbr`
    // conductor of roughness 0 and a roughness-0 `Glossy`, each of the same colour: seen within
    // 21° of the normal, Schlick's Fresnel of the last two is their colour to within 2·10⁻⁶, so
    // all three record the wall times the tint and the wall's normal.
    let tint = "(0.5, 1, 0.25)";
    let expected = Vec3::new(0.1, 0.4, 0.15);
    for mirror in [
        format!("Metal(albedo: Constant({tint}), roughness: 0)"),
        format!("Pbr(base_color: Constant({tint}), metallic: 1, roughness: 0)"),
        format!("Glossy(albedo: Constant({tint}), roughness: 0)"),
    ] {
        let r = render_features(&mirror_scene(&mirror, "Mis"), 4, None, PassPlan::Single);
        for (a, n) in albedo_of(&r).iter().zip(normal_of(&r)) {
            assert!((*a - expected).abs().max_element() < 1e-5, "{mirror}: {a}");
            assert!(
                (n - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-6,
                "{mirror}: {n}"
            );
        }
    }
}

#[test]
fn features_are_the_same_bits_for_any_thread_count_and_pass_split_and_leave_the_image_alone() {
    let cornell = common::scenes_dir().join("cornell.ron");
    let size = Overrides {
        width: Some(40),
        height: Some(40),
        spp: Some(8),
        ..Overrides::default()
    };
    let run = |threads, plan, features| {
        let mut r = Renderer::new(threads, plan).expect("thread pool");
        r.set_features(features);
        r.set_overrides(size);
        r.load(&cornell).unwrap_or_else(|e| panic!("{e}"));
        r.render_to_completion();
        r
    };
    let one = run(Some(1), PassPlan::Single, true);
    let many = run(Some(4), PassPlan::Single, true);
    let passes = run(Some(2), PassPlan::Progressive { first: 1 }, true);
    let plain = run(Some(2), PassPlan::Single, false);
    let features = one.film().features.as_ref().expect("features");
    assert!(features.albedo.iter().any(|p| p.0 != [0; 3]));
    assert_eq!(Some(features), many.film().features.as_ref());
    assert_eq!(Some(features), passes.film().features.as_ref());
    assert_eq!(one.film().sum, plain.film().sum, "features change no pixel");
    assert!(plain.film().features.is_none());
}

/// A partial whose albedo layer is in the colour's fixed point (as rondo wrote them before the
/// albedo had a scale of its own) is still read, its albedo mean is the albedo summed, and it
/// does not merge with a partial whose albedo is in the albedo's own scale.
#[test]
fn a_partial_with_the_albedo_in_the_colours_fixed_point_is_read_and_kept_apart() {
    use rondo::farm::partial::{PartialMeta, plan_merge, read_partial, write_partial};
    use rondo::film::{ALBEDO_SHIFT, Features, FixedPoint, Pixel};
    let dir = temp_dir("aov-old-partial");
    let (width, height, count) = (4u32, 2u32, 3u32);
    let pixels = (width * height) as usize;
    // A colour shift other than the albedo's, as a scene lit at 10⁻⁶ has (one of 10⁻¹⁰ would
    // have clamped such an albedo).
    let shift = ALBEDO_SHIFT + 20;
    let meta = |albedo_shift| PartialMeta {
        width,
        height,
        seed: 0,
        hash: 1,
        ranges: std::slice::from_ref(&(0..count)).to_vec(),
        scene: "s.ron".into(),
        shift,
        settings: "max_depth=8 method=mis sampler=sobol background=0,0,0 roulette=on instancing=on"
            .into(),
        features: true,
        albedo_shift,
    };
    // Every sample's albedo is 0.25 (exact in any fixed point), its normal +z.
    let sums = |albedo_shift: i32| {
        let mut f = Features::with_albedo_shift(pixels, albedo_shift);
        let sample = |v: Vec3, shift: i32| {
            let mut p = Pixel::ZERO;
            for _ in 0..count {
                p.add(v, FixedPoint::new(shift));
            }
            p
        };
        f.albedo.fill(sample(Vec3::splat(0.25), albedo_shift));
        f.normal.fill(sample(Vec3::Z, rondo::film::NORMAL_SHIFT));
        f
    };
    let colour = vec![Pixel::ZERO; pixels];
    let old = dir.join("old.exr");
    write_partial(&old, &meta(shift), &colour, Some(&sums(shift))).expect("write");
    let (read, held) = read_partial(&old).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(read.albedo_shift, shift);
    let features = held.features.expect("features");
    assert_eq!(
        features.albedo_mean(u64::from(count)),
        vec![Vec3::splat(0.25); pixels]
    );
    let new = dir.join("new.exr");
    let later = PartialMeta {
        ranges: std::slice::from_ref(&(count..2 * count)).to_vec(),
        ..meta(ALBEDO_SHIFT)
    };
    write_partial(&new, &later, &colour, Some(&sums(ALBEDO_SHIFT))).expect("write");
    let refused = plan_merge(&[old, new], None).expect_err("albedo sums in other units");
    assert!(refused.0.contains("albedo fraction bits"), "{refused}");
}
