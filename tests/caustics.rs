//! `Method::Caustics` (light tracing of camera → diffuse → perfect specular → light paths)
//! against independent truth: a closed-form caustic, the plain path tracer that finds every
//! path, determinism over threads and sample splits (with and without alpha masks), and scenes
//! it must leave alone. Caustics through alpha masks: tests/alpha_mask.rs.

mod common;

use std::f64::consts::PI;
use std::path::Path;
use std::process::Command;

use common::{exr_channels, region_mean, render, scenes_dir, temp_dir, write_scene};
use rondo::Overrides;
use rondo::scene::format::Method;

fn overrides(method: Method, spp: u32, seed: u64, size: (u32, u32)) -> Overrides {
    Overrides {
        method: Some(method),
        spp: Some(spp),
        seed: Some(seed),
        width: Some(size.0),
        height: Some(size.1),
        ..Overrides::default()
    }
}

/// Mean and standard error of `f(seed)` over `seeds`.
fn over_seeds(seeds: u64, f: impl Fn(u64) -> f64) -> (f64, f64) {
    let v: Vec<f64> = (0..seeds).map(|s| f(100 + s)).collect();
    common::mean_se(&v)
}

#[test]
fn a_mirrored_sun_lights_a_ceiling_as_the_closed_form_says() {
    // A sun of irradiance E = 3 from 45° (direction (1, 1, 0)) falls on a perfect white mirror
    // at y = 0 and is reflected onto a diffuse ceiling (albedo ρ = 0.5) at y = 2, which the
    // camera sees from below. Nothing else lights it (black sky, paths of at most 3 rays), so
    // its radiance is ρ/π · E cos 45°, found only through the mirror: by light tracing, or by
    // BSDF samples hitting the 0.53° sun (the path tracer, nearly never).
    let dir = temp_dir("caustics-mirror");
    let scene = write_scene(
        dir.path(),
        "mirror.ron",
        r#"Scene(
    camera: Camera(position: (-3, 0.2, 0), look_at: (-3, 2, 0), up: (0, 0, 1), fov: 30),
    settings: Settings(width: 24, height: 24, spp: 2048, max_depth: 3, background: (0, 0, 0),
        sun: Sun(direction: (1, 1, 0), angular_diameter: 0.53, irradiance: 3.0, colour: (1, 1, 1))),
    materials: {
        "ceiling": Diffuse(albedo: Constant((0.5, 0.5, 0.5))),
        "mirror": Metal(albedo: Constant((1, 1, 1)), roughness: 0),
    },
    entities: [
        Entity(name: "ceiling", material: "ceiling", shape: Quad(a: (-4, 2, -1), b: (-2, 2, -1), c: (-2, 2, 1), d: (-4, 2, 1))),
        Entity(name: "mirror", material: "mirror", shape: Quad(a: (-2, 0, -1.5), b: (0, 0, -1.5), c: (0, 0, 1.5), d: (-2, 0, 1.5))),
    ],
)"#,
    );
    let expected = 0.5 / PI * 3.0 * std::f64::consts::FRAC_1_SQRT_2;
    let r = render(
        &scene,
        Overrides {
            method: Some(Method::Caustics),
            ..Overrides::default()
        },
        None,
    );
    let px: Vec<f64> = r.film().mean().iter().map(|p| f64::from(p.x)).collect();
    let n = px.len() as f64;
    let mean = px.iter().sum::<f64>() / n;
    let se = (px.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
    assert!(
        (mean - expected).abs() <= 3.5 * se && se < 0.02 * expected,
        "ceiling {mean} ± {se}, expected {expected}"
    );
}

#[test]
fn a_mirrored_spot_lights_a_ceiling_as_the_inverse_square_law_says() {
    // A spot of intensity I = 4 at height 1 shines down (full within 80° of straight down, none
    // beyond 85°) onto a small perfect white mirror at y = 0 (the part of it the camera's view
    // reflects from, |x|, |z| ≤ 0.09, and a margin), which reflects it onto a diffuse
    // ceiling (albedo ρ = 0.5) at y = 2; no light reaches the ceiling directly (it is above
    // the spot's cone). Seen from the mirror's image of the spot, (0, −1, 0), a ceiling point
    // (x, 2, z) is at distance d = √(x² + 9 + z²), its normal at cosine 3 / d: its radiance is
    // ρ/π · I · 3 / d³. The camera, at height 0.5 looking straight up with a 20° field of view,
    // sees the square |x|, |z| ≤ 1.5 tan 10° of the ceiling, evenly (a plane parallel to the
    // film). No path tracer's path reaches a punctual light through a mirror: `mis` is black.
    let dir = temp_dir("caustics-spot");
    let scene = write_scene(
        dir.path(),
        "spot.ron",
        r#"Scene(
    camera: Camera(position: (0, 0.5, 0), look_at: (0, 2, 0), up: (0, 0, 1), fov: 20),
    settings: Settings(width: 16, height: 16, spp: 1024, max_depth: 3, background: (0, 0, 0)),
    lights: [Spot(position: (0, 1, 0), direction: (0, -1, 0), intensity: 4, inner_angle: 80, outer_angle: 85)],
    materials: {
        "ceiling": Diffuse(albedo: Constant((0.5, 0.5, 0.5))),
        "mirror": Metal(albedo: Constant((1, 1, 1)), roughness: 0),
    },
    entities: [
        Entity(name: "ceiling", material: "ceiling", shape: Quad(a: (-3, 2, -3), b: (3, 2, -3), c: (3, 2, 3), d: (-3, 2, 3))),
        Entity(name: "mirror", material: "mirror", shape: Quad(a: (-0.2, 0, -0.2), b: (0.2, 0, -0.2), c: (0.2, 0, 0.2), d: (-0.2, 0, 0.2))),
    ],
)"#,
    );
    let half = 1.5 * (10.0f64).to_radians().tan();
    let n = 200;
    let expected = (0..n * n)
        .map(|i| {
            let x = half * (2.0 * ((i % n) as f64 + 0.5) / n as f64 - 1.0);
            let z = half * (2.0 * ((i / n) as f64 + 0.5) / n as f64 - 1.0);
            0.5 / PI * 4.0 * 3.0 / (x * x + 9.0 + z * z).powf(1.5)
        })
        .sum::<f64>()
        / (n * n) as f64;
    let mean_and_error = |method| {
        let r = render(
            &scene,
            Overrides {
                method: Some(method),
                ..Overrides::default()
            },
            None,
        );
        let px: Vec<f64> = r.film().mean().iter().map(|p| f64::from(p.x)).collect();
        let n = px.len() as f64;
        let mean = px.iter().sum::<f64>() / n;
        let se = (px.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
        (mean, se)
    };
    let (mean, se) = mean_and_error(Method::Caustics);
    assert!(
        (mean - expected).abs() <= 3.5 * se && se < 0.02 * expected,
        "ceiling {mean} ± {se}, expected {expected}"
    );
    assert_eq!(mean_and_error(Method::Mis).0, 0.0);
}

#[test]
fn the_caustic_scene_converges_to_what_the_plain_path_tracer_finds() {
    // scenes/caustic.ron at 64×48: a lamp focused by a glass ball onto the floor. The plain
    // path tracer (BSDF sampling only) finds every path, so its mean over independent seeds is
    // the truth; light tracing must agree on the caustic (a box around the focus) and the
    // whole image, within 4 combined standard errors (8 seeds each: Student's t, 7 degrees).
    let scene = scenes_dir().join("caustic.ron");
    let size = (64, 48);
    for (what, rows, cols) in [("caustic", 22..34, 28..42), ("image", 0..48, 0..64)] {
        let truth = over_seeds(8, |seed| {
            let o = overrides(Method::Naive, 1024, seed, size);
            region_mean(&scene, o, rows.clone(), cols.clone())
        });
        for method in [Method::Caustics, Method::Photons] {
            let light = over_seeds(8, |seed| {
                let o = overrides(method, 64, seed, size);
                region_mean(&scene, o, rows.clone(), cols.clone())
            });
            let se = (truth.1 * truth.1 + light.1 * light.1).sqrt();
            assert!(
                (truth.0 - light.0).abs() <= 4.0 * se,
                "{what}: naive {} ± {}, {method} {} ± {}",
                truth.0,
                truth.1,
                light.0,
                light.1
            );
            eprintln!("{what}: naive {truth:?}, {method} {light:?}");
        }
    }
}

#[test]
fn light_traced_images_are_the_same_on_any_thread_count() {
    // gltf.ron: light paths through alpha masks.
    for name in ["caustic.ron", "gltf.ron"] {
        let scene = scenes_dir().join(name);
        for method in [Method::Caustics, Method::Photons] {
            let o = overrides(method, 4, 7, (40, 30));
            let one = render(&scene, o, Some(1));
            let two = render(&scene, o, Some(2));
            assert_eq!(one.film().sum, two.film().sum, "{name} {method}");
        }
    }
}

fn rondo(args: &[&str]) {
    let out = Command::new(env!("CARGO_BIN_EXE_rondo"))
        .args(args)
        .output()
        .expect("run rondo");
    assert!(
        out.status.success(),
        "rondo {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn split_and_merged_light_tracing_is_bit_exact_and_partials_name_the_method() {
    split_and_merged_is_bit_exact("caustics", "caustic.ron");
    // Light paths through alpha masks (the glTF model's fence) draw from their own numbers.
    split_and_merged_is_bit_exact("caustics", "gltf.ron");
}

#[test]
fn split_and_merged_photons_are_bit_exact_and_partials_name_the_method() {
    // Each sample gathers its own photons with its own radius: a partial of samples 7..20
    // holds what the whole range's samples 7..20 hold.
    split_and_merged_is_bit_exact("photons", "caustic.ron");
}

fn split_and_merged_is_bit_exact(method: &str, scene: &str) {
    let dir = temp_dir("caustics-split");
    let scene = scenes_dir().join(scene);
    let s = |p: &Path| p.to_str().expect("utf-8 path").to_string();
    let scene = s(&scene);
    let common = [
        "--method", method, "--width", "40", "--height", "30", "--seed", "3",
    ];
    let whole = dir.path().join("whole.exr");
    let (a, b) = (dir.path().join("a.exr"), dir.path().join("b.exr"));
    let merged = dir.path().join("merged.exr");
    let mut args = vec!["render", scene.as_str()];
    args.extend(common);
    let run = |extra: &[&str]| {
        let mut v = args.clone();
        v.extend(extra);
        rondo(&v);
    };
    // 20 samples: `photons` traces them in groups of 16, and the split falls inside one.
    run(&["--samples", "0..20", "-o", &s(&whole)]);
    run(&["--samples", "0..7", "-o", &s(&a)]);
    run(&["--samples", "7..20", "-o", &s(&b)]);
    rondo(&["merge", &s(&b), &s(&a), "-o", &s(&merged)]);
    let (w, m) = (exr_channels(&whole), exr_channels(&merged));
    assert!(!w.is_empty());
    assert_eq!(w, m, "split and merged differ from the whole range");
    // A partial of `mis` does not merge with one of this method.
    let other = dir.path().join("other.exr");
    let mut v = vec!["render", scene.as_str(), "--method", "mis"];
    v.extend(&common[2..]);
    v.extend(["--samples", "20..22", "-o"]);
    let other_s = s(&other);
    v.push(&other_s);
    rondo(&v);
    let out = Command::new(env!("CARGO_BIN_EXE_rondo"))
        .args([
            "merge",
            &s(&whole),
            &other_s,
            "-o",
            &s(&dir.path().join("x.exr")),
        ])
        .output()
        .expect("run rondo");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("method"), "{err}");
}

#[test]
fn scenes_without_perfect_specular_surfaces_render_as_mis() {
    // sunlit.ron's gold ball is glossy (roughness 0.3), not a perfect mirror: nothing to light
    // trace, and the path tracer drops nothing, so the sums are `mis`'s exactly. The caustic
    // scene, with its glass ball, differs.
    let size = (48, 32);
    for (scene, same) in [("sunlit.ron", true), ("caustic.ron", false)] {
        let path = scenes_dir().join(scene);
        let mis = render(&path, overrides(Method::Mis, 2, 1, size), None);
        let light = render(&path, overrides(Method::Caustics, 2, 1, size), None);
        assert_eq!(mis.film().sum == light.film().sum, same, "{scene}");
    }
}

#[test]
fn a_scene_that_names_no_method_renders_with_caustics_and_one_that_says_mis_keeps_it() {
    // caustic.ron names no method: its render is `--method caustics`'s, bit for bit, not
    // `mis`'s (which differ there, above). The same scene saying `method: Mis` is `mis`'s.
    let size = (40, 30);
    let path = scenes_dir().join("caustic.ron");
    let text = std::fs::read_to_string(&path).expect("caustic.ron");
    assert!(!text.contains("method:"), "caustic.ron names no method");
    let plain = Overrides {
        method: None,
        ..overrides(Method::Mis, 2, 5, size)
    };
    let default = render(&path, plain, None);
    let caustics = render(&path, overrides(Method::Caustics, 2, 5, size), None);
    let mis = render(&path, overrides(Method::Mis, 2, 5, size), None);
    assert!(default.film().sum == caustics.film().sum);
    assert!(default.film().sum != mis.film().sum);

    let dir = temp_dir("caustics-default");
    let settings =
        text.find("settings: Settings(").expect("settings") + "settings: Settings(".len();
    let says_mis = format!("{}method: Mis, {}", &text[..settings], &text[settings..]);
    let written = write_scene(dir.path(), "mis.ron", &says_mis);
    let kept = render(&written, plain, None);
    assert!(kept.film().sum == mis.film().sum);
}
