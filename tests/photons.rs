//! `Method::Photons` (caustics seen through mirrors and glass, gathered from photons) against
//! a closed form that only it reaches in a few samples.

mod common;

use std::f64::consts::PI;

use common::{render, temp_dir, write_scene};
use rondo::Overrides;
use rondo::scene::format::Method;

/// A sun of irradiance E = 3 from 45° (direction (1, 1, 0)) falls on a large perfect white
/// mirror at y = 0 (x from −6 to 2) and is reflected onto a diffuse ceiling (albedo ρ = 0.5)
/// at y = 2, lighting its underside evenly over x from −8 to 0 with radiance ρ/π · E cos 45°.
/// The camera, at (−2, 1, 0) looking straight down, sees that underside only in a small
/// second mirror at y = 0.3: every pixel is camera → mirror → ceiling → mirror → sun, a caustic
/// seen in a mirror. The small mirror's shadow and its own reflection of the sun fall on the
/// ceiling at least a metre to the side of the part seen; nothing else lights it (black sky,
/// paths of at most 4 rays, and the sun on the ceiling's upper side only).
const SCENE: &str = r#"Scene(
    camera: Camera(position: (-2, 1, 0), look_at: (-2, 0.3, 0), up: (0, 0, 1), fov: 20),
    settings: Settings(width: 128, height: 128, spp: 128, max_depth: 4, background: (0, 0, 0),
        sun: Sun(direction: (1, 1, 0), angular_diameter: 0.53, irradiance: 3.0, colour: (1, 1, 1))),
    materials: {
        "ceiling": Diffuse(albedo: Constant((0.5, 0.5, 0.5))),
        "mirror": Metal(albedo: Constant((1, 1, 1)), roughness: 0),
    },
    entities: [
        Entity(name: "ceiling", material: "ceiling", shape: Quad(a: (-8, 2, -4), b: (0, 2, -4), c: (0, 2, 4), d: (-8, 2, 4))),
        Entity(name: "mirror", material: "mirror", shape: Quad(a: (-6, 0, -4), b: (2, 0, -4), c: (2, 0, 4), d: (-6, 0, 4))),
        Entity(name: "small mirror", material: "mirror", shape: Quad(a: (-2.25, 0.3, -0.25), b: (-1.75, 0.3, -0.25), c: (-1.75, 0.3, 0.25), d: (-2.25, 0.3, 0.25))),
    ],
)"#;

/// Mean red value of the image for each of `seeds`.
fn image_means(method: Method, seeds: std::ops::Range<u64>) -> Vec<f64> {
    let dir = temp_dir("photons-mirrored-caustic");
    let scene = write_scene(dir.path(), "mirrors.ron", SCENE);
    seeds
        .map(|seed| {
            let o = Overrides {
                method: Some(method),
                seed: Some(seed),
                ..Overrides::default()
            };
            let r = render(&scene, o, None);
            assert_eq!(r.stats().nonfinite, 0);
            let px = r.film().mean();
            px.iter().map(|p| f64::from(p.x)).sum::<f64>() / px.len() as f64
        })
        .collect()
}

/// Mean and standard error of `values`.
fn mean_and_error(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

#[test]
fn a_caustic_seen_in_a_mirror_has_the_closed_form_radiance() {
    let expected = 0.5 / PI * 3.0 * std::f64::consts::FRAC_1_SQRT_2;
    // Each render's photons are shared by all its pixels: the error is taken over seeds.
    let (mean, se) = mean_and_error(&image_means(Method::Photons, 1..7));
    eprintln!("photons: {mean} ± {se}, expected {expected}");
    assert!(
        (mean - expected).abs() <= 4.0 * se && se < 0.01 * expected,
        "photons: {mean} ± {se}, expected {expected}"
    );
    // Without the photons, only the path tracer's rays from the ceiling that happen to hit
    // the 0.53° sun in the big mirror find this light: the same mean, far noisier.
    let (traced, traced_se) = mean_and_error(&image_means(Method::Caustics, 1..7));
    eprintln!("caustics: {traced} ± {traced_se}");
    assert!(traced_se > 5.0 * se, "caustics: {traced} ± {traced_se}");
}

#[test]
fn live_passes_gather_the_photons_a_batch_render_gathers() {
    // Watch's passes (a preview, then 1, 2, 4, 8, 16 and 20 samples in total) rebuild each
    // sample's photons from the scene and the seed: the image is the batch render's, bit for
    // bit, across the groups of 16 samples a pass traces at once.
    let scene = common::scenes_dir().join("caustic.ron");
    let o = Overrides {
        method: Some(Method::Photons),
        width: Some(40),
        height: Some(30),
        spp: Some(20),
        seed: Some(3),
        ..Overrides::default()
    };
    let batch = render(&scene, o, Some(2));
    let mut live =
        rondo::Renderer::new(Some(1), rondo::PassPlan::Progressive { first: 1 }).expect("pool");
    live.set_overrides(o);
    live.load(&scene).expect("loads");
    live.render_to_completion();
    assert_eq!(live.film().samples, 20);
    assert_eq!(live.film().sum, batch.film().sum);
    // Gathering changed the image: it is not the one `caustics` renders.
    let caustics = render(
        &scene,
        Overrides {
            method: Some(Method::Caustics),
            ..o
        },
        Some(2),
    );
    assert!(caustics.film().sum != batch.film().sum);
}
