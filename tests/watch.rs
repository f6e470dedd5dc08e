//! Live editing, end to end: a [`WatchSession`] on a scene in a temporary directory, edited the
//! ways editors save, observed through its reports and the image it writes. Waits are bounded
//! (a report or a timeout), never sleeps.

mod common;

use std::path::{Path, PathBuf};
use std::time::Duration;

use rondo::watch::{ReloadReport, Report, WatchOptions, WatchSession};

/// Upper bound of every wait; a passing run takes a small fraction of it.
const WAIT: Duration = Duration::from_secs(20);

const RED: &str = "Constant((1.0, 0.0, 0.0))";
const BLUE: &str = "Constant((0.0, 0.0, 1.0))";
const GREY: &str = "Constant((0.5, 0.5, 0.5))";

/// A scene whose centre pixel sees only the `wall` emitter (so its colour is exactly the wall's
/// emission whatever the sample count) and a small `ball` near the top edge. Line 5 holds the
/// wall material and line 9 the wall entity, for the error-location tests.
fn scene(wall: &str, ball: &str, ball_x: f32, spp: u32) -> String {
    format!(
        r#"Scene(
    camera: Camera(position: (0, 0, -5), look_at: (0, 0, 0), fov: 40.0),
    settings: Settings(width: 32, height: 32, spp: {spp}, max_depth: 3),
    materials: {{
        "wall": Light(emit: {wall}, intensity: 1.0, two_sided: true),
        "ball": Diffuse(albedo: {ball}),
    }},
    entities: [
        Entity(name: "wall", material: "wall", shape: Quad(a: (-10, -10, 5), b: (10, -10, 5), c: (10, 10, 5), d: (-10, 10, 5))),
        Entity(name: "ball", material: "ball", shape: Sphere(center: ({ball_x:.1}, 1.4, 0), radius: 0.3)),
    ],
)
"#
    )
}

fn simple(wall: &str) -> String {
    scene(wall, GREY, 0.0, 4)
}

/// A temporary directory with a scene and a running session, removed on drop.
struct Fixture {
    dir: common::TestDir,
    scene: PathBuf,
    out: PathBuf,
    session: Option<WatchSession>,
}

impl Fixture {
    /// [`Fixture::open`], then waits for the first complete render.
    fn start(name: &str, text: &str, files: &[(&str, [u8; 3])]) -> (Self, ReloadReport) {
        let f = Self::open(name, text, files);
        let first = f.rendered();
        (f, first)
    }

    /// Writes `files` (solid-colour PNGs) and `scene.ron`, and starts watching.
    fn open(name: &str, text: &str, files: &[(&str, [u8; 3])]) -> Self {
        Self::open_with(name, text, |dir| {
            for (file, rgb) in files {
                write_png(&dir.join(file), *rgb);
            }
        })
    }

    /// Lets `write` fill the directory, writes `scene.ron`, and starts watching.
    fn open_with(name: &str, text: &str, write: impl FnOnce(&Path)) -> Self {
        let dir = common::temp_dir(&format!("watch-{name}"));
        write(&dir);
        let scene = dir.join("scene.ron");
        std::fs::write(&scene, text).expect("write scene");
        let out = dir.join("out.png");
        let mut options = WatchOptions::new(&scene, &out);
        options.threads = Some(2);
        let session = WatchSession::start(options).expect("start watching");
        Self {
            dir,
            scene,
            out,
            session: Some(session),
        }
    }

    fn session(&self) -> &WatchSession {
        self.session.as_ref().expect("session running")
    }

    /// Waits for a report matching `predicate`.
    fn wait(&self, what: &str, predicate: impl FnMut(&Report) -> bool) -> Report {
        match self.session().wait_for(WAIT, predicate) {
            Ok(r) => r,
            Err(seen) => panic!("timed out waiting for {what}; reports meanwhile: {seen:#?}"),
        }
    }

    /// Waits for the next render to reach full quality.
    fn rendered(&self) -> ReloadReport {
        match self.wait(
            "a complete render",
            |r| matches!(r, Report::Rendered(r) if r.completed()),
        ) {
            Report::Rendered(r) => r,
            _ => unreachable!(),
        }
    }

    fn centre(&self) -> [u8; 3] {
        let image = image::open(&self.out).expect("output image").to_rgb8();
        image.get_pixel(16, 16).0
    }

    fn write_scene(&self, text: &str) {
        std::fs::write(&self.scene, text).expect("write scene");
    }
}

impl Drop for Fixture {
    fn drop(&mut self) {
        common::end_watch(self.session.take());
    }
}

fn write_png(path: &Path, rgb: [u8; 3]) {
    image::RgbImage::from_pixel(4, 4, image::Rgb(rgb))
        .save(path)
        .expect("write png");
}

#[test]
fn in_place_edit_rerenders_with_the_new_colour() {
    let (f, first) = Fixture::start("in-place", &simple(RED), &[]);
    assert_eq!(first.number, 0);
    assert_eq!(f.centre(), [255, 0, 0]);

    f.write_scene(&simple(BLUE));
    let r = f.rendered();
    assert_eq!(r.number, 1);
    assert!(r.changes.materials, "{r}");
    assert_eq!(f.centre(), [0, 0, 255]);
}

#[test]
fn rename_style_save_rerenders() {
    let (f, _) = Fixture::start("rename", &simple(RED), &[]);
    let tmp = f.dir.join(".scene.ron.swp-like");
    std::fs::write(&tmp, simple(BLUE)).expect("write temp");
    std::fs::rename(&tmp, &f.scene).expect("rename over the scene");
    f.rendered();
    assert_eq!(f.centre(), [0, 0, 255]);

    // And again: the directory watch survives the replaced file.
    std::fs::write(&tmp, simple(RED)).expect("write temp");
    std::fs::rename(&tmp, &f.scene).expect("rename over the scene");
    f.rendered();
    assert_eq!(f.centre(), [255, 0, 0]);
}

#[test]
fn delete_and_recreate_rerenders_and_keeps_the_image_meanwhile() {
    let (f, _) = Fixture::start("recreate", &simple(RED), &[]);
    let before = std::fs::read(&f.out).expect("image");

    std::fs::remove_file(&f.scene).expect("delete scene");
    f.wait("the scene reported missing", |r| {
        assert!(!matches!(r, Report::Wrote { .. }), "wrote while missing");
        matches!(r, Report::SceneMissing { .. })
    });
    assert_eq!(std::fs::read(&f.out).expect("image"), before);

    f.write_scene(&simple(BLUE));
    f.rendered();
    assert_eq!(f.centre(), [0, 0, 255]);
}

#[test]
fn broken_saves_report_line_and_column_and_keep_the_image() {
    let (f, _) = Fixture::start("broken", &simple(RED), &[]);
    let before = std::fs::read(&f.out).expect("image");
    // (what, scene, line, the text the column points at, the field at fault if the parser knows)
    let cases = [
        (
            "syntax error",
            simple("Constant((1.0, 0.0 0.0))"),
            5,
            "0.0))",
            Some("materials.wall.emit"),
        ),
        (
            "invalid value",
            simple("Constant((-1.0, 0.0, 0.0))"),
            5,
            "-1.0",
            Some("materials.wall.emit[0]"),
        ),
        (
            "missing texture",
            simple(r#"Image(path: "missing.png")"#),
            5,
            "",
            None,
        ),
        (
            "unknown material",
            simple(RED).replace(
                r#"Entity(name: "wall", material: "wall""#,
                r#"Entity(name: "wall", material: "nope""#,
            ),
            9,
            "",
            None,
        ),
    ];
    for (what, text, line, at, field) in cases {
        f.write_scene(&text);
        let Report::Failed(error) = f.wait(what, |r| {
            assert!(
                !matches!(r, Report::Wrote { .. } | Report::Rendered(_)),
                "{what}: rendered a broken scene: {r:?}"
            );
            matches!(r, Report::Failed { .. })
        }) else {
            unreachable!()
        };
        // The place is in fields of its own; the text shows it too.
        assert_eq!(error.path, f.scene, "{what}: the file");
        let location = error.location.expect("a location");
        assert_eq!(location.line, line, "{what}: the line");
        let source = text.lines().nth(line - 1).expect("the line");
        let from_column: String = source.chars().skip(location.col - 1).collect();
        assert!(
            from_column.starts_with(at),
            "{what}: column {} points at `{from_column}`, not `{at}`",
            location.col
        );
        assert_eq!(error.field.as_deref(), field, "{what}: the field");
        assert!(
            !error.message.contains("scene.ron"),
            "{what}: the message holds no place: {}",
            error.message
        );
        let located = format!("scene.ron:{line}:{}: {}", location.col, error.message);
        let message = error.to_string();
        assert!(
            message.ends_with(&located),
            "{what}: `{message}` lacks {located}"
        );
        // The report quotes the line of the scene (all of it: these lines are short).
        assert_eq!(
            error.source_line.as_deref(),
            Some(source),
            "{what}: the quoted line"
        );
        assert_eq!(
            std::fs::read(&f.out).expect("image"),
            before,
            "{what}: the image changed"
        );
    }

    f.write_scene(&simple(BLUE));
    f.rendered();
    assert_eq!(f.centre(), [0, 0, 255]);
}

/// A writer that pauses mid-save (here 400 ms, far beyond the debounce
/// window and the error's wait) is waited for until it closes the file: the half-written save
/// is never loaded, let alone reported, and the image comes from the complete file.
#[test]
fn a_save_split_by_a_pause_is_not_reported_as_an_error() {
    use std::io::Write;
    let (f, _) = Fixture::start("split-save", &simple(RED), &[]);
    let text = simple(BLUE);
    let (head, tail) = text.split_at(text.len() / 2);
    let mut file = std::fs::File::create(&f.scene).expect("truncate scene");
    file.write_all(head.as_bytes()).expect("write");
    file.flush().expect("flush");
    // The pause: nothing may happen while the writer holds the file open.
    let during = f.session().wait_for(Duration::from_millis(400), |r| {
        matches!(
            r,
            Report::Failed { .. } | Report::Deferred { .. } | Report::Started { .. }
        )
    });
    assert!(
        during.is_err(),
        "the half-written save was loaded: {during:?}"
    );
    file.write_all(tail.as_bytes()).expect("write");
    drop(file);
    match f.wait("the complete save to render", |r| {
        matches!(
            r,
            Report::Failed { .. } | Report::Deferred { .. } | Report::Rendered(_)
        )
    }) {
        Report::Rendered(r) => assert!(r.completed(), "{r}"),
        other => panic!("a half-written save was reported: {other:?}"),
    }
    assert_eq!(f.centre(), [0, 0, 255]);
}

#[test]
fn a_bad_save_during_a_render_resumes_the_old_scene_without_worse_images() {
    let (f, _) = Fixture::start("resume", &simple(RED), &[]);
    f.write_scene(&scene(RED, GREY, 0.0, 1 << 20));
    let track = |best: &mut u32, r: &Report| {
        if let Report::Wrote {
            reload: 1, samples, ..
        } = r
        {
            *best = (*best).max(*samples);
        }
    };
    let mut best = 0;
    f.wait("the long render under way", |r| {
        track(&mut best, r);
        best >= 16
    });
    f.write_scene(&simple("Constant((1.0, 0.0 0.0))"));
    f.wait("the error", |r| {
        track(&mut best, r);
        matches!(r, Report::Failed { .. })
    });
    let Report::Wrote { samples, .. } = f.wait("the old scene's next image", |r| {
        matches!(r, Report::Wrote { reload: 1, .. })
    }) else {
        unreachable!()
    };
    assert!(samples > best, "rewrote {samples} spp over {best} spp");
    assert_eq!(f.centre(), [255, 0, 0]);
}

#[test]
fn a_scene_broken_from_the_start_is_reported_then_rendered_once_fixed() {
    let f = Fixture::open("broken-start", &simple("Constant((1.0, 0.0 0.0))"), &[]);
    let Report::Failed(error) = f.wait("the error", |r| matches!(r, Report::Failed { .. })) else {
        unreachable!()
    };
    let message = error.to_string();
    assert!(message.contains("scene.ron:5:"), "{message}");
    assert!(!f.out.exists(), "no image from a broken scene");
    f.write_scene(&simple(BLUE));
    assert_eq!(f.rendered().number, 0);
    assert_eq!(f.centre(), [0, 0, 255]);
}

#[test]
fn a_missing_texture_renders_once_the_file_appears() {
    let (f, _) = Fixture::start("late-texture", &simple(RED), &[]);
    f.write_scene(&simple(r#"Image(path: "late.png")"#));
    f.wait("the missing texture error", |r| {
        matches!(r, Report::Failed { .. })
    });
    write_png(&f.dir.join("late.png"), [0, 255, 0]);
    f.rendered();
    assert_eq!(f.centre(), [0, 255, 0]);
}

#[test]
fn material_edit_skips_the_bvh_rebuild_and_moving_the_sphere_does_not() {
    let (f, first) = Fixture::start("bvh", &simple(RED), &[]);
    assert!(first.bvh_rebuilt);
    let builds = first.counters.bvh_builds;

    f.write_scene(&simple(BLUE));
    let r = f.rendered();
    assert!(!r.bvh_rebuilt, "{r}");
    assert_eq!(r.counters.bvh_builds, builds, "{r}");
    assert!(r.materials_synced, "{r}");
    assert_eq!(f.centre(), [0, 0, 255]);

    f.write_scene(&scene(BLUE, GREY, 0.5, 4));
    let r = f.rendered();
    assert!(r.bvh_rebuilt, "{r}");
    assert_eq!(r.counters.bvh_builds, builds + 1, "{r}");
    assert_eq!((r.changes.changed, r.changes.materials), (1, false), "{r}");
}

#[test]
fn texture_edit_rerenders_and_decodes_only_that_texture() {
    let text = scene(
        r#"Image(path: "wall.png")"#,
        r#"Image(path: "ball.png")"#,
        0.0,
        4,
    );
    let files = [("wall.png", [255, 0, 0]), ("ball.png", [128, 128, 128])];
    let (f, first) = Fixture::start("texture", &text, &files);
    assert_eq!(first.textures_decoded, 2);
    assert_eq!(f.centre(), [255, 0, 0]);

    write_png(&f.dir.join("wall.png"), [0, 0, 255]);
    let r = f.rendered();
    assert_eq!(r.textures_decoded, 1, "{r}");
    assert!(!r.bvh_rebuilt, "{r}");
    assert!(r.trigger.iter().any(|p| p.ends_with("wall.png")), "{r:?}");
    assert_eq!(f.centre(), [0, 0, 255]);
}

/// The buffer `quad.bin` of [`write_gltf_quad`]'s quad, moved by `dx` along x.
fn write_quad_buffer(dir: &Path, dx: f32) -> usize {
    let positions = [
        -2.0, -2.0, 5.0, 2.0, -2.0, 5.0, 2.0, 2.0, 5.0, -2.0, 2.0, 5.0f32,
    ];
    let mut bytes: Vec<u8> = positions
        .iter()
        .enumerate()
        .flat_map(|(k, p)| (if k % 3 == 0 { p + dx } else { *p }).to_le_bytes())
        .collect();
    let uvs = [0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0f32];
    bytes.extend(uvs.iter().flat_map(|v| v.to_le_bytes()));
    bytes.extend([0u16, 1, 2, 0, 2, 3].iter().flat_map(|v| v.to_le_bytes()));
    std::fs::write(dir.join("quad.bin"), &bytes).expect("write buffer");
    bytes.len()
}

/// A glTF quad over [−2, 2]² at z = 5, its buffer in `quad.bin`, emitting its emissive texture
/// `t.png` over a black conductor base, so a pixel seeing it shows the texel exactly.
fn write_gltf_quad(dir: &Path) {
    let length = write_quad_buffer(dir, 0.0);
    let gltf = format!(
        r#"{{"asset": {{"version": "2.0"}},
        "buffers": [{{"uri": "quad.bin", "byteLength": {}}}],
        "bufferViews": [{{"buffer": 0, "byteLength": 48}}, {{"buffer": 0, "byteOffset": 48, "byteLength": 32}},
                        {{"buffer": 0, "byteOffset": 80, "byteLength": 12}}],
        "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"}},
                      {{"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"}},
                      {{"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}}],
        "images": [{{"uri": "t.png"}}], "textures": [{{"source": 0}}],
        "materials": [{{"name": "screen", "emissiveFactor": [1, 1, 1], "emissiveTexture": {{"index": 0}},
                        "pbrMetallicRoughness": {{"baseColorFactor": [0, 0, 0, 1]}}}}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "TEXCOORD_0": 1}}, "indices": 2, "material": 0}}]}}],
        "nodes": [{{"name": "quad", "mesh": 0}}], "scenes": [{{"nodes": [0]}}]}}"#,
        length
    );
    std::fs::write(dir.join("quad.gltf"), gltf).expect("write glTF");
}

#[test]
fn gltf_texture_edit_skips_the_bvh_and_a_buffer_edit_rebuilds_it() {
    let text = r#"Scene(
    camera: Camera(position: (0, 0, -5), look_at: (0, 0, 0), fov: 40.0),
    settings: Settings(width: 32, height: 32, spp: 4, max_depth: 3),
    entities: [Entity(name: "model", gltf: "quad.gltf")],
)"#;
    let f = Fixture::open_with("gltf", text, |dir| {
        write_png(&dir.join("t.png"), [255, 0, 0]);
        write_gltf_quad(dir);
    });
    let first = f.rendered();
    assert!(first.bvh_rebuilt);
    assert_eq!(f.centre(), [255, 0, 0]);

    write_png(&f.dir.join("t.png"), [0, 0, 255]);
    let r = f.rendered();
    assert_eq!(r.textures_decoded, 1, "{r}");
    assert!(!r.bvh_rebuilt, "{r}");
    assert_eq!(f.centre(), [0, 0, 255]);

    // Moving the quad out of the centre's view through its buffer file.
    write_quad_buffer(&f.dir, 10.0);
    let r = f.rendered();
    assert!(r.bvh_rebuilt, "{r}");
    assert!(r.trigger.iter().any(|p| p.ends_with("quad.bin")), "{r:?}");
    assert_eq!(f.centre(), [0, 0, 0]);
}

#[test]
fn save_during_a_long_render_cancels_it_promptly() {
    let (f, _) = Fixture::start("cancel", &simple(RED), &[]);
    // About a billion samples: this render never finishes within the test.
    f.write_scene(&scene(RED, GREY, 0.0, 1 << 20));
    f.wait(
        "a first pass of the long render",
        |r| matches!(r, Report::Wrote { reload: 1, samples, .. } if *samples >= 4),
    );

    f.write_scene(&simple(BLUE));
    // A render that ignored the cancel would not be superseded within the wait.
    let Report::Rendered(old) = f.wait("the long render to be superseded", |r| {
        matches!(r, Report::Rendered(_))
    }) else {
        unreachable!()
    };
    assert_eq!(old.number, 1);
    assert!(!old.completed(), "{old}");
    let new = f.rendered();
    assert_eq!(new.number, 2);
    assert_eq!(f.centre(), [0, 0, 255]);
}

#[test]
fn stop_returns_promptly_during_a_long_render() {
    let (mut f, _) = Fixture::start("stop", &simple(RED), &[]);
    f.write_scene(&scene(RED, GREY, 0.0, 1 << 20));
    f.wait(
        "the long render under way",
        |r| matches!(r, Report::Wrote { reload: 1, samples, .. } if *samples >= 64),
    );
    // Stop on another thread and wait for it with a deadline: a stop that ignored the cancel
    // would hang until the billion samples were done.
    let session = f.session.take().expect("session running");
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(session.stop().is_ok());
    });
    assert_eq!(
        rx.recv_timeout(WAIT),
        Ok(true),
        "stop did not return cleanly"
    );
    let image = std::fs::read(&f.out).expect("image");
    assert!(
        image::load_from_memory(&image).is_ok(),
        "a complete image is left behind"
    );
    let leftovers: Vec<_> = std::fs::read_dir(&f.dir)
        .expect("dir")
        .filter_map(Result::ok)
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
}

// ------------------------------------------------------------------------------------------------
// Stale states, one test each: after the last edit, watch shows what a fresh render of the
// files on disk shows.

/// A fresh batch render of `scene`, as the 8-bit image `rondo render` writes.
fn fresh_render(scene: &Path) -> image::RgbImage {
    let mut r = rondo::Renderer::new(Some(2), rondo::PassPlan::Single).expect("thread pool");
    r.load(scene).unwrap_or_else(|e| panic!("{e}"));
    r.render_to_completion();
    r.film().to_srgb8()
}

/// A scene with the given materials and entities (RON fragments) and the camera of [`scene`].
fn custom(materials: &str, entities: &str, spp: u32) -> String {
    format!(
        r#"Scene(
    camera: Camera(position: (0, 0, -5), look_at: (0, 0, 0), fov: 40.0),
    settings: Settings(width: 32, height: 32, spp: {spp}, max_depth: 3),
    materials: {{ {materials} }},
    entities: [ {entities} ],
)
"#
    )
}

/// A prefab holding the wall emitter of [`scene`] in the given colour.
fn wall_prefab(colour: &str) -> String {
    format!(
        r#"Prefab(
    materials: {{ "wall": Light(emit: {colour}, intensity: 1.0, two_sided: true) }},
    entities: [ Entity(name: "w", material: "wall", shape: Quad(a: (-10, -10, 5), b: (10, -10, 5), c: (10, 10, 5), d: (-10, 10, 5))) ],
)
"#
    )
}

fn placed_wall(prefab: &str) -> String {
    custom(
        "",
        &format!(r#"Entity(name: "wall", prefab: "{prefab}")"#),
        4,
    )
}

fn failed(f: &Fixture, what: &str) -> String {
    match f.wait(what, |r| matches!(r, Report::Failed { .. })) {
        Report::Failed(error) => error.to_string(),
        _ => unreachable!(),
    }
}

#[test]
fn spp_one_leaves_the_real_pass_on_disk_not_the_preview() {
    // Noisy at 1 spp (a diffuse ball lit by the wall): the real pass differs from its 2×2-block
    // preview in almost every block.
    let (f, first) = Fixture::start("spp-one", &scene(RED, GREY, 0.0, 1), &[]);
    assert!(first.preview, "{first}");
    let line = first.to_string();
    assert!(
        line.contains("(preview)") && !line.contains("(1 spp),"),
        "{line}"
    );
    let on_disk = image::open(&f.out).expect("output image").to_rgb8();
    assert!(
        on_disk == fresh_render(&f.scene),
        "the image on disk is not the 1-spp render"
    );

    // And after an edit, through the overrides path too.
    f.write_scene(&scene(RED, GREY, 0.5, 1));
    f.rendered();
    let on_disk = image::open(&f.out).expect("output image").to_rgb8();
    assert!(
        on_disk == fresh_render(&f.scene),
        "the image on disk is not the 1-spp render"
    );
}

#[test]
fn a_texture_in_a_directory_created_later_is_picked_up() {
    let (f, _) = Fixture::start("late-dir", &simple(RED), &[]);
    f.write_scene(&simple(r#"Image(path: "newtex/wood.png")"#));
    failed(&f, "the missing texture error");
    std::fs::create_dir(f.dir.join("newtex")).expect("mkdir");
    write_png(&f.dir.join("newtex/wood.png"), [0, 255, 0]);
    f.rendered();
    assert_eq!(f.centre(), [0, 255, 0]);
    // The new directory is watched from now on.
    write_png(&f.dir.join("newtex/wood.png"), [0, 0, 255]);
    f.rendered();
    assert_eq!(f.centre(), [0, 0, 255]);
}

#[test]
fn a_prefab_in_a_new_subdirectory_fixing_a_cycle_is_picked_up() {
    let f = Fixture::open("late-prefab", &placed_wall("wall.ron"), &[]);
    // wall.ron places itself: a cycle.
    std::fs::write(
        f.dir.join("wall.ron"),
        r#"Prefab(entities: [ Entity(name: "again", prefab: "wall.ron") ])"#,
    )
    .expect("write prefab");
    let message = failed(&f, "the cycle");
    assert!(message.contains("cycle"), "{message}");
    // The fix names a prefab in a directory that does not exist yet…
    std::fs::write(
        f.dir.join("wall.ron"),
        r#"Prefab(entities: [ Entity(name: "real", prefab: "sub/wall.ron") ])"#,
    )
    .expect("write prefab");
    failed(&f, "the missing prefab");
    // …which then appears.
    std::fs::create_dir(f.dir.join("sub")).expect("mkdir");
    std::fs::write(f.dir.join("sub/wall.ron"), wall_prefab(BLUE)).expect("write prefab");
    f.rendered();
    assert_eq!(f.centre(), [0, 0, 255]);
}

#[test]
fn a_deleted_then_restored_directory_is_watched_again() {
    let f = Fixture::open("restored-dir", &placed_wall("prefabs/wall.ron"), &[]);
    std::fs::create_dir(f.dir.join("prefabs")).expect("mkdir");
    std::fs::write(f.dir.join("prefabs/wall.ron"), wall_prefab(RED)).expect("write prefab");
    f.rendered();
    assert_eq!(f.centre(), [255, 0, 0]);

    std::fs::remove_dir_all(f.dir.join("prefabs")).expect("rm -rf");
    failed(&f, "the missing prefab");
    std::fs::create_dir(f.dir.join("prefabs")).expect("mkdir");
    std::fs::write(f.dir.join("prefabs/wall.ron"), wall_prefab(RED)).expect("write prefab");
    f.rendered();
    assert_eq!(f.centre(), [255, 0, 0]);
    std::fs::write(f.dir.join("prefabs/wall.ron"), wall_prefab(BLUE)).expect("write prefab");
    f.rendered();
    assert_eq!(f.centre(), [0, 0, 255]);
}

/// The race behind the flaky `a_deleted_then_restored_directory_is_watched_again`
/// (BLUE expected, RED seen), made deterministic: a file written into a directory just
/// (re)created, whose writer is still at it when the loop arms the directory. Were the creation
/// of a directory a complete change, the loop would read at once (the data is there), render
/// it, and then load the file a second time on the writer's close, which arrives after that
/// render: two complete renders for one save, and a test that waits for "the next render"
/// after its next save takes the second, still red, for it. A directory's files follow it, so
/// it is read once they are quiet: once, after the close.
#[test]
fn a_file_written_into_a_recreated_directory_is_loaded_once() {
    use std::io::Write;
    let f = Fixture::open("restored-once", &placed_wall("prefabs/wall.ron"), &[]);
    std::fs::create_dir(f.dir.join("prefabs")).expect("mkdir");
    std::fs::write(f.dir.join("prefabs/wall.ron"), wall_prefab(BLUE)).expect("write prefab");
    f.rendered();
    std::fs::remove_dir_all(f.dir.join("prefabs")).expect("rm -rf");
    failed(&f, "the missing prefab");

    std::fs::create_dir(f.dir.join("prefabs")).expect("mkdir");
    let mut file = std::fs::File::create(f.dir.join("prefabs/wall.ron")).expect("create");
    file.write_all(wall_prefab(RED).as_bytes())
        .expect("write prefab");
    // The writer closes the file a little later: long enough for the loop to arm the new
    // directory, read the complete text and render it, were it to read at once.
    std::thread::sleep(Duration::from_millis(20));
    drop(file);
    f.rendered();
    assert_eq!(f.centre(), [255, 0, 0]);
    let again = f.session().wait_for(Duration::from_millis(300), |r| {
        matches!(r, Report::Started { .. } | Report::Rendered(_))
    });
    assert!(again.is_err(), "one save, loaded twice: {again:?}");
    std::fs::write(f.dir.join("prefabs/wall.ron"), wall_prefab(BLUE)).expect("write prefab");
    f.rendered();
    assert_eq!(f.centre(), [0, 0, 255]);
}

#[test]
fn a_directory_moved_away_and_copied_back_is_watched_again() {
    let f = Fixture::open("replaced-dir", &placed_wall("prefabs/wall.ron"), &[]);
    std::fs::create_dir(f.dir.join("prefabs")).expect("mkdir");
    std::fs::write(f.dir.join("prefabs/wall.ron"), wall_prefab(RED)).expect("write prefab");
    f.rendered();

    // mv prefabs prefabs.old && cp -r prefabs.old prefabs: the old watch follows prefabs.old.
    std::fs::rename(f.dir.join("prefabs"), f.dir.join("prefabs.old")).expect("mv");
    std::fs::create_dir(f.dir.join("prefabs")).expect("mkdir");
    std::fs::copy(
        f.dir.join("prefabs.old/wall.ron"),
        f.dir.join("prefabs/wall.ron"),
    )
    .expect("cp");
    f.rendered();
    std::fs::write(f.dir.join("prefabs/wall.ron"), wall_prefab(BLUE)).expect("write prefab");
    f.rendered();
    assert_eq!(f.centre(), [0, 0, 255]);
}

#[test]
fn a_mesh_replaced_with_the_same_size_and_mtime_is_reloaded() {
    // A light triangle in front of the wall covers the centre pixel, or (same byte count) not.
    let covering = "v -2 -2 0\nv 2 -2 0\nv 0 3 0\nf 1 2 3\n";
    let aside = "v -2 -2 0\nv 2 -2 0\nv 9 3 0\nf 1 2 3\n";
    assert_eq!(covering.len(), aside.len());
    let materials = format!(
        r#""wall": Light(emit: {RED}, intensity: 1.0, two_sided: true), "tri": Light(emit: {BLUE}, intensity: 1.0, two_sided: true)"#
    );
    let entities = r#"Entity(name: "wall", material: "wall", shape: Quad(a: (-10, -10, 5), b: (10, -10, 5), c: (10, 10, 5), d: (-10, 10, 5))),
        Entity(name: "tri", material: "tri", shape: Mesh(path: "tri.obj"))"#;
    let f = Fixture::open("same-stamp", &custom(&materials, entities, 4), &[]);
    let mesh = f.dir.join("tri.obj");
    std::fs::write(&mesh, covering).expect("write mesh");
    f.rendered();
    assert_eq!(f.centre(), [0, 0, 255]);

    let stamp = common::watch_diff::stamp(&mesh).1;
    std::fs::write(&mesh, aside).expect("write mesh");
    common::watch_diff::set_mtime(&mesh, stamp);
    let meta = std::fs::metadata(&mesh).expect("stat");
    assert_eq!(
        (meta.len(), meta.modified().ok()),
        (covering.len() as u64, Some(stamp))
    );
    f.rendered();
    assert_eq!(f.centre(), [255, 0, 0]);
}

#[test]
fn editing_the_target_of_a_symlinked_texture_rerenders() {
    let f = Fixture::open("symlink", &simple(RED), &[]);
    f.rendered();
    std::fs::create_dir(f.dir.join("elsewhere")).expect("mkdir");
    write_png(&f.dir.join("elsewhere/real.png"), [0, 255, 0]);
    std::os::unix::fs::symlink(f.dir.join("elsewhere/real.png"), f.dir.join("link.png"))
        .expect("symlink");
    f.write_scene(&simple(r#"Image(path: "link.png")"#));
    f.rendered();
    assert_eq!(f.centre(), [0, 255, 0]);
    write_png(&f.dir.join("elsewhere/real.png"), [0, 0, 255]);
    f.rendered();
    assert_eq!(f.centre(), [0, 0, 255]);
}

#[test]
fn a_reorder_says_so_and_an_unchanged_save_keeps_the_image() {
    let a = r#"Entity(name: "wall", material: "wall", shape: Quad(a: (-10, -10, 5), b: (10, -10, 5), c: (10, 10, 5), d: (-10, 10, 5)))"#;
    let b = r#"Entity(name: "ball", material: "ball", shape: Sphere(center: (0.0, 1.4, 0), radius: 0.3))"#;
    let materials = format!(
        r#""wall": Light(emit: {RED}, intensity: 1.0, two_sided: true), "ball": Diffuse(albedo: {GREY})"#
    );
    let (f, _) = Fixture::start("reorder", &custom(&materials, &format!("{a}, {b}"), 4), &[]);
    f.write_scene(&custom(&materials, &format!("{b}, {a}"), 4));
    let r = f.rendered();
    assert!(r.changes.reordered && r.bvh_rebuilt, "{r}");
    assert!(r.to_string().contains("entities reordered"), "{r}");
    let on_disk = image::open(&f.out).expect("output image").to_rgb8();
    assert!(on_disk == fresh_render(&f.scene));

    // The same text again: nothing to do, nothing rewritten.
    let before = std::fs::read(&f.out).expect("image");
    f.write_scene(&custom(&materials, &format!("{b}, {a}"), 4));
    let r = f.wait("the unchanged save", |r| {
        assert!(
            !matches!(r, Report::Wrote { .. }),
            "rewrote an unchanged image"
        );
        matches!(r, Report::Rendered(_))
    });
    let Report::Rendered(r) = r else {
        unreachable!()
    };
    assert!(r.completed() && r.changes.is_empty(), "{r}");
    assert!(r.to_string().contains("no changes"), "{r}");
    assert_eq!(std::fs::read(&f.out).expect("image"), before);
}

// ------------------------------------------------------------------------------------------------
// Environment maps.

/// Writes a 16 × 8 OpenEXR map whose texel (x, y) has radiance `f(x, y)`.
fn write_map(path: &Path, f: impl Fn(u32, u32) -> [f32; 3]) {
    let data: Vec<f32> = (0..8)
        .flat_map(|y| (0..16).map(move |x| (x, y)))
        .flat_map(|(x, y)| f(x, y))
        .collect();
    image::Rgb32FImage::from_raw(16, 8, data)
        .expect("buffer size")
        .save(path)
        .expect("write map");
}

/// A camera that sees the environment directly over the top of a diffuse ball it lights.
fn lit_by_map(strength: f32) -> String {
    format!(
        r#"Scene(
    camera: Camera(position: (0, 0, -5), look_at: (0, 0, 0), fov: 40.0),
    settings: Settings(width: 32, height: 32, spp: 4, max_depth: 3,
        environment: Environment(path: "sky.exr", strength: {strength:.1}, rotate: (0, 30, 0))),
    materials: {{ "ball": Diffuse(albedo: {GREY}) }},
    entities: [ Entity(name: "ball", material: "ball", shape: Sphere(center: (0, -1, 0), radius: 1)) ],
)
"#
    )
}

#[test]
fn editing_only_the_environment_map_rerenders_and_rebuilds_only_the_map() {
    let on_disk = |f: &Fixture| image::open(&f.out).expect("output image").to_rgb8();
    // The map is written before the session starts, so that no load sees half a file.
    let dir = common::temp_dir("watch-envmap");
    let map = dir.join("sky.exr");
    write_map(&map, |x, _| [0.2 + 0.1 * x as f32, 0.5, 0.3]);
    let scene = dir.join("scene.ron");
    std::fs::write(&scene, lit_by_map(1.0)).expect("write scene");
    let out = dir.join("out.png");
    let mut options = WatchOptions::new(&scene, &out);
    options.threads = Some(2);
    let session = WatchSession::start(options).expect("start watching");
    let f = Fixture {
        dir,
        scene,
        out,
        session: Some(session),
    };
    let first = f.rendered();
    assert_eq!(first.environments_built, 1, "{first}");
    let before = on_disk(&f);
    assert!(before == fresh_render(&f.scene));

    // The map alone: the watch follows its file and builds its distribution again.
    write_map(&map, |_, y| [0.1, 0.3, if y < 4 { 2.0 } else { 0.1 }]);
    let r = match f.wait(
        "the render after the map edit",
        |r| matches!(r, Report::Rendered(r) if r.completed()),
    ) {
        Report::Rendered(r) => r,
        _ => unreachable!(),
    };
    assert!(r.trigger.iter().any(|p| p.ends_with("sky.exr")), "{r:?}");
    assert_eq!(r.environments_built, 1, "{r}");
    assert!(r.changes.sky && !r.bvh_rebuilt, "{r}");
    assert!(r.to_string().contains("environment map"), "{r}");
    let after = on_disk(&f);
    assert!(after != before, "the map edit left the image as it was");
    assert!(after == fresh_render(&f.scene), "not the fresh render");

    // The strength alone: the same file, the distribution reused.
    f.write_scene(&lit_by_map(2.0));
    let r = f.rendered();
    assert_eq!(r.environments_built, 0, "{r}");
    assert!(r.changes.sky, "{r}");
    assert!(!r.to_string().contains("environment map"), "{r}");
    let brighter = on_disk(&f);
    assert!(
        brighter != after,
        "the strength edit left the image as it was"
    );
    assert!(brighter == fresh_render(&f.scene), "not the fresh render");
}

/// A reload reads only the asset files an event named (counted in bytes, the
/// sizes taken from the file system).
#[test]
fn a_scene_edit_reads_no_asset_and_an_asset_edit_reads_only_that_asset() {
    let size = |f: &Fixture, name: &str| std::fs::metadata(f.dir.join(name)).expect("stat").len();
    let text = |wall: &str| {
        custom(
            &format!(
                r#""wall": Light(emit: {wall}, intensity: 1.0, two_sided: true), "tex": Diffuse(albedo: Image(path: "ball.png")), "tri": Diffuse(albedo: {GREY})"#
            ),
            r#"Entity(name: "wall", material: "wall", shape: Quad(a: (-10, -10, 5), b: (10, -10, 5), c: (10, 10, 5), d: (-10, 10, 5))),
        Entity(name: "ball", material: "tex", shape: Sphere(center: (0, 1.4, 0), radius: 0.3)),
        Entity(name: "tri", material: "tri", shape: Mesh(path: "tri.obj")),
        Entity(name: "model", gltf: "quad.gltf", transform: Transform(translate: (0, 30, 0)))"#,
            4,
        )
    };
    let tri = "v -2 -2 -9\nv 2 -2 -9\nv 0 -3 -9\nf 1 2 3\n";
    let f = Fixture::open_with("asset-reads", &text(RED), |dir| {
        write_png(&dir.join("ball.png"), [128, 128, 128]);
        write_png(&dir.join("t.png"), [255, 0, 0]);
        write_gltf_quad(dir);
        std::fs::write(dir.join("tri.obj"), tri).expect("write mesh");
    });
    f.rendered();
    assert_eq!(f.centre(), [255, 0, 0]);

    // (a) The scene's text only: no asset is read.
    f.write_scene(&text(BLUE));
    let r = f.rendered();
    assert_eq!(f.centre(), [0, 0, 255]);
    assert_eq!(r.asset_bytes_read, 0, "{r:?}");

    // (b) One asset: that file only (a glTF buffer: it and the glTF file, parsed again).
    write_png(&f.dir.join("ball.png"), [0, 255, 0]);
    let r = f.rendered();
    assert_eq!(r.asset_bytes_read, size(&f, "ball.png"), "{r:?}");
    std::fs::write(f.dir.join("tri.obj"), tri.replace("-9", "-8")).expect("write mesh");
    let r = f.rendered();
    assert_eq!(r.asset_bytes_read, size(&f, "tri.obj"), "{r:?}");
    write_quad_buffer(&f.dir, 1.0);
    let r = f.rendered();
    assert!(r.bvh_rebuilt, "{r}");
    assert_eq!(
        r.asset_bytes_read,
        size(&f, "quad.bin") + size(&f, "quad.gltf"),
        "{r:?}"
    );
}

/// A mesh rewritten with the same size and mtime is read again because
/// its event names it.
#[test]
fn a_same_size_same_mtime_rewrite_with_an_event_is_read_again() {
    let covering = "v -2 -2 0\nv 2 -2 0\nv 0 3 0\nf 1 2 3\n";
    let aside = "v -2 -2 0\nv 2 -2 0\nv 9 3 0\nf 1 2 3\n";
    let materials = format!(
        r#""wall": Light(emit: {RED}, intensity: 1.0, two_sided: true), "tri": Light(emit: {BLUE}, intensity: 1.0, two_sided: true)"#
    );
    let entities = r#"Entity(name: "wall", material: "wall", shape: Quad(a: (-10, -10, 5), b: (10, -10, 5), c: (10, 10, 5), d: (-10, 10, 5))),
        Entity(name: "tri", material: "tri", shape: Mesh(path: "tri.obj"))"#;
    let f = Fixture::open_with(
        "asset-reads-stamp",
        &custom(&materials, entities, 4),
        |dir| {
            std::fs::write(dir.join("tri.obj"), covering).expect("write mesh");
        },
    );
    f.rendered();
    assert_eq!(f.centre(), [0, 0, 255]);
    let mesh = f.dir.join("tri.obj");
    let stamp = common::watch_diff::stamp(&mesh).1;
    std::fs::write(&mesh, aside).expect("write mesh");
    common::watch_diff::set_mtime(&mesh, stamp);
    let r = f.rendered();
    assert_eq!(r.asset_bytes_read, aside.len() as u64, "{r:?}");
    assert_eq!(f.centre(), [255, 0, 0]);
}

/// Each run of the schedule says what its systems did: the first frame of a load applies the
/// scene, builds the BVH over every primitive and assigns materials; a frame of an unchanged
/// scene only renders; a material edit assigns materials without touching the BVH; a move in
/// a progressive render refits for the preview and builds before the first real pass.
#[test]
fn each_frame_reports_what_its_systems_did() {
    use rondo::PassPlan;
    use rondo::ecs::frame_log::BvhWork;

    let dir = common::temp_dir("frame-log");
    let path = dir.join("scene.ron");
    std::fs::write(&path, simple(RED)).expect("write scene");
    let mut r =
        rondo::Renderer::new(Some(1), PassPlan::Progressive { first: 1 }).expect("renderer");
    r.load(&path).expect("loads");
    let frame = r.run_once();
    let changes = frame.applied.expect("the scene is applied");
    assert_eq!(changes.added, 2, "the wall and the ball");
    let geometry = frame.geometry.expect("geometry built");
    assert_eq!(geometry.bvh, BvhWork::Built);
    // A quad is two triangles, the ball one sphere.
    assert_eq!(geometry.primitives, 3);
    assert!(frame.materials);
    let pass = frame.pass.expect("the preview pass");
    assert!(pass.preview && pass.samples == 1, "{pass:?}");

    let frame = r.run_once();
    assert_eq!(frame.applied, None);
    assert_eq!(frame.geometry, None);
    assert!(!frame.materials);
    let pass = frame.pass.expect("the first real pass");
    assert!(!pass.preview && pass.samples == 1, "{pass:?}");

    std::fs::write(&path, simple(BLUE)).expect("write scene");
    r.load(&path).expect("loads");
    let frame = r.run_once();
    assert!(frame.applied.expect("applied").materials);
    assert_eq!(frame.geometry, None, "a material edit builds no BVH");
    assert!(frame.materials);

    std::fs::write(&path, scene(BLUE, GREY, 0.5, 4)).expect("write scene");
    r.load(&path).expect("loads");
    let frame = r.run_once();
    assert_eq!(frame.applied.expect("applied").changed, 1, "the ball moved");
    let geometry = frame.geometry.expect("geometry refitted");
    assert_eq!(geometry.bvh, BvhWork::Refitted);
    assert!(frame.pass.expect("the preview").preview);
    let frame = r.run_once();
    assert_eq!(frame.geometry.map(|g| g.bvh), Some(BvhWork::Built));
    assert!(!frame.pass.expect("a real pass").preview);
}
