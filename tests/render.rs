//! Whole renders checked against analytic values, determinism and the shipped scenes.

mod common;

use common::{render, scenes_dir, temp_dir, write_scene};
use rondo::Overrides;

fn furnace_scene(albedo: f32, fov: f32, distance: f32) -> String {
    format!(
        r#"Scene(
    camera: Camera(position: (0, 0, -{distance}), look_at: (0, 0, 0), up: (0, 1, 0), fov: {fov}),
    settings: Settings(width: 64, height: 64, spp: 16, max_depth: 32, background: (1, 1, 1), seed: 3),
    materials: {{ "grey": Diffuse(albedo: Constant(({albedo}, {albedo}, {albedo}))) }},
    entities: [ Entity(name: "ball", material: "grey", shape: Sphere(center: (0, 0, 0), radius: 1)) ],
)"#
    )
}

#[test]
fn white_furnace_sphere_matches_the_analytic_value() {
    // A convex diffuse sphere of albedo ρ under a uniform sky of radiance 1 reflects exactly ρ:
    // every scattered ray escapes. Pixels wholly on the sphere must read ρ, wholly off it 1.
    let dir = temp_dir("furnace");
    let (albedo, fov, distance) = (0.5f32, 40.0f32, 4.0f32);
    let path = write_scene(&dir, "furnace.ron", &furnace_scene(albedo, fov, distance));
    let r = render(&path, Overrides::default(), None);
    let px = common::pixels(r.film());
    assert_eq!(r.stats().nonfinite, 0);

    // Projected disc radius on the image plane at distance 1: tan(asin(r/d)).
    let disc = (1.0f32 / distance).asin().tan();
    let half = (0.5 * fov.to_radians()).tan();
    let n = 64.0f32;
    let (mut inside, mut outside) = (0, 0);
    for y in 0..64 {
        for x in 0..64 {
            // Pixel corners in image-plane units.
            let corners = [(x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1)].map(|(cx, cy)| {
                let sx = (2.0 * cx as f32 / n - 1.0) * half;
                let sy = (1.0 - 2.0 * cy as f32 / n) * half;
                (sx * sx + sy * sy).sqrt()
            });
            let v = px[y * 64 + x];
            if corners.iter().all(|&c| c < disc * 0.999) {
                inside += 1;
                assert!(
                    (v - glam::Vec3::splat(albedo)).abs().max_element() < 0.01 * albedo,
                    "({x},{y}) = {v}"
                );
            } else if corners.iter().all(|&c| c > disc * 1.001) {
                outside += 1;
                assert!(
                    (v - glam::Vec3::ONE).abs().max_element() < 0.01,
                    "({x},{y}) = {v}"
                );
            }
        }
    }
    assert!(
        inside > 1000 && outside > 1000,
        "{inside} inside, {outside} outside"
    );

    // Image mean: 1 − (1 − ρ) · (disc area / image area).
    let covered = std::f32::consts::PI * disc * disc / (4.0 * half * half);
    let expected = 1.0 - (1.0 - albedo) * covered;
    let mean: f32 = px.iter().map(|p| p.x).sum::<f32>() / px.len() as f32;
    assert!(
        (mean - expected).abs() < 0.005 * expected,
        "mean {mean}, expected {expected}"
    );
}

#[test]
fn same_seed_gives_identical_images_with_one_or_two_threads() {
    let cornell = scenes_dir().join("cornell.ron");
    let small = Overrides {
        width: Some(40),
        height: Some(40),
        spp: Some(4),
        ..Default::default()
    };
    let one = render(&cornell, small, Some(1));
    let two = render(&cornell, small, Some(2));
    assert_eq!(one.film().sum, two.film().sum);
    let other_seed = render(
        &cornell,
        Overrides {
            seed: Some(1),
            ..small
        },
        Some(2),
    );
    assert_ne!(one.film().sum, other_seed.film().sum);
}

#[test]
fn cornell_box_has_red_on_the_left_and_green_on_the_right() {
    let cornell = scenes_dir().join("cornell.ron");
    let o = Overrides {
        width: Some(32),
        height: Some(32),
        spp: Some(32),
        ..Default::default()
    };
    let r = render(&cornell, o, None);
    let px = common::pixels(r.film());
    let band = |x0: usize, x1: usize| {
        let mut sum = glam::Vec3::ZERO;
        for y in 10..22 {
            for x in x0..x1 {
                sum += px[y * 32 + x];
            }
        }
        sum
    };
    let (left, right) = (band(2, 5), band(27, 30));
    assert!(left.x > 2.0 * left.y, "left wall {left}");
    assert!(right.y > 2.0 * right.x, "right wall {right}");
}

#[test]
fn every_shipped_scene_renders_without_a_nonfinite_sample() {
    let mut count = 0;
    for entry in std::fs::read_dir(scenes_dir()).expect("scenes dir") {
        let path = entry.expect("entry").path();
        if path.extension().is_some_and(|e| e == "ron") {
            let o = Overrides {
                width: Some(24),
                height: Some(24),
                spp: Some(4),
                ..Default::default()
            };
            let r = render(&path, o, None);
            assert_eq!(r.stats().nonfinite, 0, "{}", path.display());
            assert!(r.stats().rays > 0);
            count += 1;
        }
    }
    assert!(count >= 1);
}

#[test]
fn cli_writes_clamped_srgb_png_and_linear_unclamped_exr() {
    let dir = temp_dir("cli-out");
    let cornell = scenes_dir().join("cornell.ron");
    let run = |out: &str| {
        let status = std::process::Command::new(env!("CARGO_BIN_EXE_rondo"))
            .args(["render", cornell.to_str().expect("utf-8"), "-o"])
            .arg(dir.join(out))
            .args([
                "--width",
                "16",
                "--height",
                "16",
                "--spp",
                "2",
                "--threads",
                "1",
            ])
            .output()
            .expect("run rondo");
        assert!(
            status.status.success(),
            "{}",
            String::from_utf8_lossy(&status.stderr)
        );
        String::from_utf8_lossy(&status.stderr).into_owned()
    };
    let summary = run("a.exr");
    assert!(
        summary.contains("16x16, 2 spp") && summary.contains("rays/s"),
        "{summary}"
    );
    run("a.png");
    let exr = image::open(dir.join("a.exr")).expect("exr").into_rgb32f();
    let png = image::open(dir.join("a.png")).expect("png").into_rgb8();
    assert_eq!((exr.width(), png.width()), (16, 16));
    // The lamp (radiance 15) is visible in the top-centre pixels: unclamped in EXR, 255 in PNG.
    let max = exr.pixels().map(|p| p.0[0]).fold(0.0f32, f32::max);
    assert!(max > 1.5, "brightest EXR value {max}");
    for (e, p) in exr.pixels().zip(png.pixels()) {
        for c in 0..3 {
            let v = e.0[c].clamp(0.0, 1.0);
            let srgb = if v <= 0.003_130_8 {
                12.92 * v
            } else {
                1.055 * v.powf(1.0 / 2.4) - 0.055
            };
            assert!((f32::from(p.0[c]) - srgb * 255.0).abs() <= 1.0);
        }
    }
}

#[test]
fn live_preview_and_progressive_passes_end_in_the_batch_image() {
    // The watcher's plan: a 2×2-block preview, then passes of 1, 2, 4… samples. The preview is
    // discarded and the passes add samples in order, so the final film equals a batch render.
    let cornell = scenes_dir().join("cornell.ron");
    let o = Overrides {
        width: Some(30),
        height: Some(20),
        spp: Some(8),
        ..Default::default()
    };
    let batch = render(&cornell, o, Some(2));
    let mut live =
        rondo::Renderer::new(Some(2), rondo::PassPlan::Progressive { first: 1 }).expect("pool");
    live.set_overrides(o);
    live.load(&cornell).expect("loads");
    live.run_once();
    // The preview: one sample per pixel, equal within each 2×2 block.
    let preview = live.film().mean();
    assert_eq!(live.film().samples, 1);
    for y in (0..20).step_by(2) {
        for x in (0..30).step_by(2) {
            let p = preview[y * 30 + x];
            assert!(
                [(1, 0), (0, 1), (1, 1)]
                    .iter()
                    .all(|(dx, dy)| preview[(y + dy) * 30 + x + dx] == p)
            );
        }
    }
    live.render_to_completion();
    assert_eq!(live.film().sum, batch.film().sum);
    assert_eq!(
        live.counters().passes,
        5,
        "the preview, then passes of 1, 2, 4 and 8 samples in total"
    );
}

/// The linear RGB of an EXR file (the `R`, `G`, `B` layer a partial also carries).
fn read_exr(path: &std::path::Path) -> Vec<f32> {
    image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .into_rgb32f()
        .into_raw()
}

fn rondo(args: &[&std::ffi::OsStr]) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_rondo"))
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
fn the_film_keeps_very_dim_and_very_bright_scenes() {
    // A uniform background seen by every pixel is the exact value of every pixel. With a fixed
    // film range, 1e-10 rounded to 0 and 3e-10 to -22 %, and 5e9 was clamped to 2.1e9.
    let dir = temp_dir("film-range");
    for background in [1e-10f32, 3e-10, 1.6e9, 5e9, 3e30] {
        let scene = write_scene(
            &dir,
            "sky.ron",
            &format!(
                r#"Scene(
    camera: Camera(position: (0, 0, 0), look_at: (0, 0, 1), fov: 40),
    settings: Settings(width: 8, height: 8, spp: 4, background: ({background:e}, {background:e}, {background:e})),
    materials: {{}},
    entities: [],
)"#
            ),
        );
        let whole = dir.join("whole.exr");
        rondo(&[
            "render".as_ref(),
            scene.as_os_str(),
            "-o".as_ref(),
            whole.as_os_str(),
        ]);
        let pixels = read_exr(&whole);
        eprintln!("background {background:e}: first pixel {:e}", pixels[0]);
        for v in pixels {
            assert!(
                ((v - background) / background).abs() < 1e-3,
                "background {background:e}: pixel {v:e}"
            );
        }
        // Partials of such a scene merge to the very same image.
        let parts = [dir.join("a.exr"), dir.join("b.exr")];
        for (part, range) in parts.iter().zip(["0..1", "1..4"]) {
            rondo(&[
                "render".as_ref(),
                scene.as_os_str(),
                "--samples".as_ref(),
                range.as_ref(),
                "-o".as_ref(),
                part.as_os_str(),
            ]);
        }
        let merged = dir.join("merged.exr");
        rondo(&[
            "merge".as_ref(),
            parts[1].as_os_str(),
            parts[0].as_os_str(),
            "-o".as_ref(),
            merged.as_os_str(),
        ]);
        assert_eq!(
            read_exr(&merged),
            read_exr(&whole),
            "background {background:e}"
        );
    }
}
