//! The denoiser on rendered images (the `--denoise` path: a film with its feature buffers, its
//! means handed to Open Image Denoise), judged against references rendered here at many more
//! samples: it must cut the low-sample error, leave a converged image alone and keep texture
//! edges sharp, and give the same bits for the same input. Skipped without the library unless
//! `RONDO_REQUIRE_OIDN=1` (CI).

mod common;

use std::sync::atomic::AtomicBool;

use common::{denoiser, temp_dir, write_scene};
use glam::Vec3;
use rondo::denoise::FilmImages;
use rondo::denoise::Quality;
use rondo::{Overrides, PassPlan, Renderer};

/// Renders `scene` at `size`² and `spp` with `seed`, collecting the features.
fn render(scene: &std::path::Path, size: u32, spp: u32, seed: u64) -> FilmImages {
    let mut r = Renderer::new(None, PassPlan::Single).expect("thread pool");
    r.set_features(true);
    r.set_overrides(Overrides {
        width: Some(size),
        height: Some(size),
        spp: Some(spp),
        seed: Some(seed),
        ..Overrides::default()
    });
    r.load(scene).unwrap_or_else(|e| panic!("{e}"));
    r.render_to_completion();
    FilmImages::of(r.film())
}

fn denoised(images: &FilmImages) -> Vec<Vec3> {
    let d = denoiser().expect("checked by the caller");
    images
        .denoise(d, Quality::High, &AtomicBool::new(false))
        .unwrap_or_else(|e| panic!("{e}"))
}

/// RMSE over the pixels whose reference is at most 1 in every channel (the lamp and its edge
/// left out), both images clamped to [0, 1]: the error measure of the Cornell benchmarks.
fn lamp_out_rmse(a: &[Vec3], reference: &[Vec3]) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for (a, r) in a.iter().zip(reference) {
        if r.max_element() > 1.0 {
            continue;
        }
        let d = a.clamp(Vec3::ZERO, Vec3::ONE) - r.clamp(Vec3::ZERO, Vec3::ONE);
        sum += f64::from(d.length_squared());
        n += 3;
    }
    (sum / n.max(1) as f64).sqrt()
}

#[test]
fn the_denoiser_cuts_the_cornell_boxs_4_spp_error_threefold_and_leaves_a_converged_image_alone() {
    if denoiser().is_none() {
        return;
    }
    let scene = common::scenes_dir().join("cornell.ron");
    // Seed 0 for the reference, another for the test image: their noise is independent.
    let reference = render(&scene, 128, 512, 0).colour;
    let noisy = render(&scene, 128, 4, 7);
    let raw = lamp_out_rmse(&noisy.colour, &reference);
    let clean = lamp_out_rmse(&denoised(&noisy), &reference);
    eprintln!(
        "Cornell 128², 4 spp: raw {raw:.5}, denoised {clean:.5} ({:.1}×)",
        raw / clean
    );
    assert!(clean * 3.0 <= raw, "raw {raw}, denoised {clean}");

    // The reference itself, denoised: relative MSE (Σ(d − r)² / Σr²) below 1 %.
    let converged = render(&scene, 128, 512, 0);
    let d = denoised(&converged);
    let (num, den) = d
        .iter()
        .zip(&converged.colour)
        .map(|(d, r)| {
            let (d, r) = (d.as_dvec3(), r.as_dvec3());
            ((d - r).length_squared(), r.length_squared())
        })
        .fold((0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
    eprintln!(
        "converged image changed by {:.4} % relative MSE",
        100.0 * num / den
    );
    assert!(num < 0.01 * den, "relative MSE {}", num / den);
}

#[test]
fn a_denoised_4_spp_checker_is_sharper_than_the_raw_64_spp_one() {
    if denoiser().is_none() {
        return;
    }
    let dir = temp_dir("denoise-checker");
    // A checker floor filling the view, lit by a large lamp overhead: its edges are the detail a
    // blurring denoiser would lose.
    let scene = write_scene(
        &dir,
        "checker.ron",
        r#"Scene(
            camera: Camera(position: (0, 3, 3), look_at: (0, 0, 0), fov: 40),
            settings: Settings(max_depth: 4),
            materials: {
                "board": Diffuse(albedo: Checker(scale: 3,
                    even: Constant((0.8, 0.8, 0.8)), odd: Constant((0.1, 0.1, 0.1)))),
                "lamp": Light(emit: Constant((1, 1, 1)), intensity: 4),
            },
            entities: [
                Entity(name: "floor", material: "board",
                    shape: Quad(a: (-4, 0, -4), b: (-4, 0, 4), c: (4, 0, 4), d: (4, 0, -4))),
                Entity(name: "lamp", material: "lamp",
                    shape: Quad(a: (-2, 5, -2), b: (2, 5, -2), c: (2, 5, 2), d: (-2, 5, 2))),
            ],
        )"#,
    );
    let reference = render(&scene, 128, 1024, 0).colour;
    let raw64 = lamp_out_rmse(&render(&scene, 128, 64, 3).colour, &reference);
    let noisy = render(&scene, 128, 4, 5);
    let clean = lamp_out_rmse(&denoised(&noisy), &reference);
    eprintln!("checker 128²: raw 64 spp {raw64:.5}, denoised 4 spp {clean:.5}");
    assert!(clean < raw64, "denoised 4 spp {clean}, raw 64 spp {raw64}");
}

#[test]
fn the_same_render_denoises_to_the_same_bits() {
    if denoiser().is_none() {
        return;
    }
    let scene = common::scenes_dir().join("cornell.ron");
    let a = render(&scene, 64, 2, 1);
    let b = render(&scene, 64, 2, 1);
    assert_eq!(a, b, "renders are deterministic");
    let (da, db) = (denoised(&a), denoised(&b));
    assert!(
        da.iter()
            .zip(&db)
            .all(|(x, y)| x.to_array().map(f32::to_bits) == y.to_array().map(f32::to_bits))
    );
    assert_ne!(da, a.colour, "the denoiser changed the image");
}

/// A floor and a back wall lit by a lamp of `intensity`, written to `dir`.
fn lamp_scene(dir: &std::path::Path, intensity: f32) -> std::path::PathBuf {
    write_scene(
        dir,
        &format!("lamp-{intensity:e}.ron"),
        &format!(
            r#"Scene(
            camera: Camera(position: (0, 2, 4), look_at: (0, 0.5, 0), fov: 50),
            settings: Settings(max_depth: 4),
            materials: {{
                "white": Diffuse(albedo: Constant((0.7, 0.7, 0.7))),
                "red": Diffuse(albedo: Constant((0.6, 0.1, 0.1))),
                "lamp": Light(emit: Constant((1, 1, 1)), intensity: {intensity:e}),
            }},
            entities: [
                Entity(name: "floor", material: "white",
                    shape: Quad(a: (-3, 0, -3), b: (-3, 0, 3), c: (3, 0, 3), d: (3, 0, -3))),
                Entity(name: "wall", material: "red",
                    shape: Quad(a: (-3, 0, -2), b: (3, 0, -2), c: (3, 3, -2), d: (-3, 3, -2))),
                Entity(name: "lamp", material: "lamp",
                    shape: Quad(a: (-0.5, 2.5, -0.5), b: (0.5, 2.5, -0.5), c: (0.5, 2.5, 0.5),
                        d: (-0.5, 2.5, 0.5))),
            ],
        )"#
        ),
    )
}

fn mean(pixels: &[Vec3]) -> f64 {
    pixels
        .iter()
        .map(|p| p.as_dvec3().element_sum())
        .sum::<f64>()
        / (3 * pixels.len()) as f64
}

/// Light is linear: a scene whose lamp is `f` times as bright renders `f` times as bright, so
/// its denoised image must be `f` times the denoised image of the lamp at 1, at any `f` a
/// lamp may have, from 10⁻³⁰ to 3·10³⁸. The albedo, which does not depend on the lamp, is the
/// same at every `f` (none clamped to the film's range).
#[test]
fn a_dimmed_or_brightened_lamp_denoises_to_the_scaled_image() {
    if denoiser().is_none() {
        return;
    }
    let dir = temp_dir("denoise-scaled-lamp");
    let reference = render(&lamp_scene(&dir, 1.0), 48, 4, 3);
    let (raw_mean, denoised_mean) = (mean(&reference.colour), mean(&denoised(&reference)));
    assert!(denoised_mean > 0.01, "{denoised_mean}");
    for factor in [1e-10f32, 1e-20, 1e-30, 3e38] {
        let scaled = render(&lamp_scene(&dir, factor), 48, 4, 3);
        let f = f64::from(factor);
        let raw = mean(&scaled.colour) / f;
        let clean = mean(&denoised(&scaled)) / f;
        eprintln!(
            "lamp ×{factor:e}: raw mean / f {raw:.6} (at 1: {raw_mean:.6}), denoised mean / f \
            {clean:.6} (at 1: {denoised_mean:.6})"
        );
        assert!((raw / raw_mean - 1.0).abs() < 1e-3, "the render is linear");
        assert_eq!(scaled.albedo, reference.albedo, "lamp ×{factor:e}: albedo");
        assert!(
            (clean / denoised_mean - 1.0).abs() < 0.01,
            "lamp ×{factor:e}: denoised mean / f {clean}, at 1 {denoised_mean}"
        );
    }
}
