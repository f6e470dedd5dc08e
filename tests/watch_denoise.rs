//! The denoised output of `watch --denoise` is exactly what `render --denoise` writes for the
//! files on disk, after the first load and after an edit: the watch-equals-render oracle of the
//! raw image, kept for the denoised one (Open Image Denoise is deterministic on one machine).
//! Skipped without the library unless `RONDO_REQUIRE_OIDN=1` (CI).

mod common;

use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use common::{denoiser, exr_channels, temp_dir, write_scene};
use rondo::denoise::FilmImages;
use rondo::denoise::Quality;
use rondo::film::{Durability, Layer, OutputImage, write_output};
use rondo::watch::{Report, WatchOptions, WatchSession};
use rondo::{PassPlan, Renderer};

const WAIT: Duration = Duration::from_secs(60);

fn scene_text(wall: &str) -> String {
    format!(
        r#"Scene(
            camera: Camera(position: (0, 1, 4), look_at: (0, 1, 0), fov: 50),
            settings: Settings(width: 48, height: 48, spp: 8, max_depth: 4),
            materials: {{
                "wall": Diffuse(albedo: Constant({wall})),
                "grey": Diffuse(albedo: Constant((0.5, 0.5, 0.5))),
                "lamp": Light(emit: Constant((1, 1, 1)), intensity: 6),
            }},
            entities: [
                Entity(name: "wall", material: "wall",
                    shape: Quad(a: (-3, -1, -1), b: (3, -1, -1), c: (3, 4, -1), d: (-3, 4, -1))),
                Entity(name: "ball", material: "grey", shape: Sphere(center: (0, 0.6, 0), radius: 0.6)),
                Entity(name: "lamp", material: "lamp",
                    shape: Quad(a: (-1, 3, -1), b: (1, 3, -1), c: (1, 3, 1), d: (-1, 3, 1))),
            ],
        )"#
    )
}

/// What `render --denoise -o x.exr` writes for `scene`, made here through the library.
fn fresh_denoised(scene: &Path, out: &Path) {
    let mut r = Renderer::new(None, PassPlan::Single).expect("thread pool");
    r.set_features(true);
    r.load(scene).unwrap_or_else(|e| panic!("{e}"));
    r.render_to_completion();
    let images = FilmImages::of(r.film());
    let d = denoiser().expect("checked");
    let denoised = images
        .denoise(d, Quality::High, &AtomicBool::new(false))
        .unwrap_or_else(|e| panic!("{e}"));
    let raw = [Layer {
        name: "raw",
        pixels: &images.colour,
    }];
    let image = OutputImage::of_linear(images.width, images.height, &denoised, &raw);
    write_output(out, &image, Durability::Synced).expect("written");
}

/// Waits for the denoised image of the full render of reload `reload`.
fn wait_for_full_denoise(session: &WatchSession, reload: u64) {
    let found = session.wait_for(WAIT, |r| {
        matches!(r, Report::Denoised(d) if d.reload == reload && d.samples == 8 && d.wrote.is_some())
    });
    if let Err(seen) = found {
        panic!("no full denoised image of reload {reload}: {seen:?}");
    }
}

#[test]
fn the_denoised_watch_output_equals_a_fresh_denoised_render_after_an_edit() {
    if denoiser().is_none() {
        return;
    }
    let dir = temp_dir("watch-denoise");
    let scene = write_scene(&dir, "scene.ron", &scene_text("(0.8, 0.2, 0.2)"));
    let (out, fresh) = (dir.join("out.exr"), dir.join("fresh.exr"));
    let mut options = WatchOptions::new(&scene, &out);
    options.denoise = Some(true);
    let session = WatchSession::start(options).expect("watch starts");
    wait_for_full_denoise(&session, 0);
    fresh_denoised(&scene, &fresh);
    let watched = exr_channels(&out);
    assert!(watched.contains_key("raw.R"));
    assert_eq!(watched, exr_channels(&fresh), "first load");

    write_scene(&dir, "scene.ron", &scene_text("(0.2, 0.3, 0.8)"));
    wait_for_full_denoise(&session, 1);
    fresh_denoised(&scene, &fresh);
    let edited = exr_channels(&out);
    assert_ne!(edited, watched, "the edit changed the image");
    assert_eq!(edited, exr_channels(&fresh), "after the edit");
    session.stop().expect("stops");
}
