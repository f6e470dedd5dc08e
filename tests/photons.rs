//! `Method::Photons` (caustics seen through mirrors and glass, gathered from photons) against
//! a closed form that only it reaches in a few samples.

mod common;

use std::f64::consts::PI;

use common::{mean_se, region_mean, render, temp_dir, write_scene};
use rondo::Overrides;
use rondo::scene::format::Method;

/// A sun of irradiance E = 3 from 45° (direction (1, 1, 0)) falls on a large perfect white
/// mirror at y = 0 (x from −6 to 2; the ceiling shades its part left of x = −2) and is
/// reflected onto a diffuse ceiling (albedo ρ = 0.5) at y = 2, lighting its underside evenly
/// over x from −4 to 0 with radiance ρ/π · E cos 45°.
/// The camera, at (−2, 1, 0) looking straight down, sees that underside only in a small
/// second mirror at y = 0.3: every pixel is camera → mirror → ceiling → mirror → sun, a caustic
/// seen in a mirror. The small mirror's shadow in the beam falls on the ceiling a metre to the
/// side of the part seen (the ceiling shades the small mirror from the sun); nothing else
/// lights it (black sky, paths of at most 4 rays, and the sun on the ceiling's upper side only).
fn mirrored_caustic() -> String {
    scene(
        "Camera(position: (-2, 1, 0), look_at: (-2, 0.3, 0), up: (0, 0, 1), fov: 20)",
        "spp: 128, max_depth: 4",
        "Entity(name: \"small mirror\", material: \"mirror\", shape: Quad(a: (-2.25, 0.3, -0.25), b: (-1.75, 0.3, -0.25), c: (-1.75, 0.3, 0.25), d: (-2.25, 0.3, 0.25))),",
    )
}

/// The sunlit mirror and the ceiling of these tests (see [`mirrored_caustic`]), seen by
/// `camera`, with `settings` and `more` entities.
fn scene(camera: &str, settings: &str, more: &str) -> String {
    format!(
        r#"Scene(
    camera: {camera},
    settings: Settings(width: 128, height: 128, {settings}, background: (0, 0, 0),
        sun: Sun(direction: (1, 1, 0), angular_diameter: 0.53, irradiance: 3.0, colour: (1, 1, 1))),
    materials: {{
        "ceiling": Diffuse(albedo: Constant((0.5, 0.5, 0.5))),
        "mirror": Metal(albedo: Constant((1, 1, 1)), roughness: 0),
    }},
    entities: [
        Entity(name: "ceiling", material: "ceiling", shape: Quad(a: (-8, 2, -4), b: (0, 2, -4), c: (0, 2, 4), d: (-8, 2, 4))),
        Entity(name: "mirror", material: "mirror", shape: Quad(a: (-6, 0, -4), b: (2, 0, -4), c: (2, 0, 4), d: (-6, 0, 4))),
        {more}
    ],
)"#
    )
}

/// Mean red value of the image of the scene `text` for each of `seeds`.
fn image_means(text: &str, method: Method, seeds: std::ops::Range<u64>) -> Vec<f64> {
    let dir = temp_dir("photons-closed-form");
    let scene = write_scene(dir.path(), "scene.ron", text);
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

#[test]
fn a_caustic_seen_in_a_mirror_has_the_closed_form_radiance() {
    let expected = 0.5 / PI * 3.0 * std::f64::consts::FRAC_1_SQRT_2;
    // Each render's photons are shared by all its pixels: the error is taken over seeds.
    let (mean, se) = mean_se(&image_means(&mirrored_caustic(), Method::Photons, 1..7));
    eprintln!("photons: {mean} ± {se}, expected {expected}");
    assert!(
        (mean - expected).abs() <= 4.0 * se && se < 0.01 * expected,
        "photons: {mean} ± {se}, expected {expected}"
    );
    // Without the photons, only the path tracer's rays from the ceiling that happen to hit
    // the 0.53° sun in the big mirror find this light: the same mean, far noisier.
    let (traced, traced_se) = mean_se(&image_means(&mirrored_caustic(), Method::Caustics, 1..7));
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

/// The big mirror's beam lights the ceiling's underside with L₁ = ρ/π · E cos 45°, evenly over
/// x from −4 to 0 (see [`mirrored_caustic`]). Seen from the ceiling, the mirror shows the ceiling again (its image 4 below
/// it, where the reflection point falls on the mirror): a second, indirect caustic
/// (ceiling → mirror → ceiling → mirror → sun), which `photons` gathers at the second ceiling
/// vertex. The camera looks straight up at the ceiling from just above the mirror (a 90° view
/// of the square |x + 2|, |z| ≤ 1.7, evenly); with paths of at most 5 rays its radiance is
/// L₁ (light-traced) + ρ/π · E₂, E₂ the irradiance from the lit ceiling's image, integrated
/// here on grids.
fn indirect_caustic() -> String {
    scene(
        "Camera(position: (-2, 0.3, 0), look_at: (-2, 2, 0), up: (0, 0, 1), fov: 90)",
        "spp: 64, max_depth: 5",
        "",
    )
}

/// Midpoints of `n` equal steps over `range`.
fn midpoints(range: std::ops::Range<f64>, n: usize) -> impl Iterator<Item = f64> + Clone {
    let step = (range.end - range.start) / n as f64;
    (0..n).map(move |i| range.start + (i as f64 + 0.5) * step)
}

#[test]
fn a_caustic_lighting_the_ceiling_again_through_the_mirror_is_gathered_after_the_bounce() {
    let (rho, l1) = (0.5, 0.5 / PI * 3.0 * std::f64::consts::FRAC_1_SQRT_2);
    // E₂ at the ceiling point (x0, 2, z0): L₁ cos² / d² over the image points (x, −2, z) of
    // the lit ceiling whose reflection point ((x0 + x) / 2, 0, (z0 + z) / 2) is on the mirror.
    let (n, cell) = (400, (4.0 / 400.0) * (8.0 / 400.0));
    let e2 = |x0: f64, z0: f64| {
        let mut sum = 0.0;
        for x in midpoints(-4.0..0.0, n) {
            if !(-6.0..=2.0).contains(&((x0 + x) / 2.0)) {
                continue;
            }
            for z in midpoints(-4.0..4.0, n) {
                if !(-4.0..=4.0).contains(&((z0 + z) / 2.0)) {
                    continue;
                }
                let d2 = (x - x0).powi(2) + 16.0 + (z - z0).powi(2);
                sum += l1 * 16.0 / (d2 * d2) * cell;
            }
        }
        sum
    };
    let view = 16;
    let mean_e2 = midpoints(-3.7..-0.3, view)
        .flat_map(|x0| midpoints(-1.7..1.7, view).map(move |z0| (x0, z0)))
        .map(|(x0, z0)| e2(x0, z0))
        .sum::<f64>()
        / (view * view) as f64;
    let expected = l1 + rho / PI * mean_e2;
    let means = image_means(&indirect_caustic(), Method::Photons, 1..7);
    let (mean, se) = mean_se(&means);
    eprintln!("indirect: {mean} ± {se}, expected {expected} (direct part {l1})");
    // Gathers near the lit ceiling's edges lose part of their kernel: allowed 1 % of the whole.
    assert!(
        (mean - expected).abs() <= 4.0 * se + 0.01 * expected && se < 0.01 * expected,
        "indirect: {mean} ± {se}, expected {expected} (direct part {l1})"
    );
}

/// [`region_mean`] of each seed's render of `scene` under `method` at `spp` and 96×64.
fn region_means(
    scene: &std::path::Path,
    (method, spp): (Method, u32),
    (rows, cols): (std::ops::Range<usize>, std::ops::Range<usize>),
    seeds: std::ops::Range<u64>,
) -> Vec<f64> {
    seeds
        .map(|seed| {
            let o = Overrides {
                method: Some(method),
                spp: Some(spp),
                seed: Some(seed),
                width: Some(96),
                height: Some(64),
                ..Overrides::default()
            };
            region_mean(scene, o, rows.clone(), cols.clone())
        })
        .collect()
}

#[test]
fn a_glossy_ball_s_caustic_is_gathered_from_photons_and_converges_to_the_path_tracer_s() {
    // scenes/sunlit.ron: the sun reflected by the gold ball (roughness 0.3, a narrow glossy
    // conductor) onto the ground. `photons` follows the ball along its light paths and drops
    // the path tracer's light samples there; `mis` finds the caustic by BSDF samples from the
    // ground that hit the ball's highlight. Both must agree on the caustic (the ground around
    // and in front of the ball) and on the whole image, within 4 combined standard errors over
    // 8 seeds; and the photons' estimate of the caustic must be far less noisy than the path
    // tracer's at 4 times the samples (without the glossy chains, `photons` is `mis` here).
    let scene = common::scenes_dir().join("sunlit.ron");
    for (what, rows, cols) in [("caustic", 40..60, 38..72), ("image", 0..64, 0..96)] {
        let region = (rows, cols);
        let (mis, mis_se) = mean_se(&region_means(
            &scene,
            (Method::Mis, 256),
            region.clone(),
            1..9,
        ));
        let (photons, photons_se) =
            mean_se(&region_means(&scene, (Method::Photons, 64), region, 1..9));
        eprintln!("{what}: mis {mis} ± {mis_se}, photons {photons} ± {photons_se}");
        let se = (mis_se * mis_se + photons_se * photons_se).sqrt();
        assert!(
            (mis - photons).abs() <= 4.0 * se,
            "{what}: mis {mis} ± {mis_se}, photons {photons} ± {photons_se}"
        );
        if what == "caustic" {
            assert!(
                photons_se < 0.5 * mis_se,
                "{what}: mis ± {mis_se}, photons ± {photons_se}"
            );
        }
    }
}
