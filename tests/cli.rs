//! The command line: exit codes (1 for bad input, 2 for bad usage), output paths refused before
//! any work is done for them, errors that say their cause once.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::Duration;

use common::{exr_channels, scenes_dir, temp_dir, wait_or_kill, write_scene};

/// Longer than any command here needs by orders of magnitude: only guards against a hang (a
/// command that renders 10⁶ samples per pixel before looking at its output path).
const HANG_GUARD: Duration = Duration::from_secs(300);

/// Runs `rondo args…`, killing it (and failing) if it is still running after [`HANG_GUARD`].
fn rondo(args: &[&str]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_rondo"))
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start rondo");
    if wait_or_kill(&mut child, HANG_GUARD).is_none() {
        panic!("rondo {args:?} still running after {HANG_GUARD:?}: it started working");
    }
    child.wait_with_output().expect("rondo output")
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn text(p: &Path) -> &str {
    p.to_str().expect("UTF-8 temp path")
}

fn cornell() -> PathBuf {
    scenes_dir().join("cornell.ron")
}

/// A render that would take days on one thread: it must be refused before it starts.
fn endless_render(output: &str) -> Output {
    let scene = cornell();
    rondo(&[
        "render",
        text(&scene),
        "-o",
        output,
        "--spp",
        "1048576",
        "--threads",
        "1",
    ])
}

/// Asserts a refusal with exit status 1, the `expected` reason, and no render summary.
fn assert_refused(out: &Output, expected: &str) {
    let err = stderr(out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains(expected), "{err}");
    assert!(
        !err.contains("samples/s"),
        "rendered before refusing: {err}"
    );
}

#[test]
fn render_refuses_an_output_in_a_missing_directory_before_rendering() {
    let dir = temp_dir("cli-missing-dir");
    let output = dir.join("no/such/dir/out.png");
    let out = endless_render(text(&output));
    assert_refused(&out, "does not exist");
    assert!(
        stderr(&out).contains("no/such/dir/out.png"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn render_refuses_an_output_that_is_a_directory_before_rendering() {
    let dir = temp_dir("cli-output-is-dir");
    let output = dir.join("taken.png");
    std::fs::create_dir_all(&output).expect("mkdir");
    assert_refused(&endless_render(text(&output)), "is a directory");
    let file = dir.join("file");
    std::fs::write(&file, "").expect("write");
    assert_refused(
        &endless_render(text(&file.join("out.png"))),
        "is not a directory",
    );
}

/// Permission bits stop writes only for users other than root (CI may run as root): the render
/// must be refused exactly when creating a file in the directory fails.
#[test]
fn render_refuses_a_directory_that_does_not_accept_files_exactly_when_it_does_not() {
    use std::os::unix::fs::PermissionsExt;
    let dir = temp_dir("cli-read-only");
    let locked = dir.join("locked");
    std::fs::create_dir_all(&locked).expect("mkdir");
    std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o555)).expect("chmod");
    let writable = std::fs::write(locked.join("probe"), "").is_ok();
    std::fs::remove_file(locked.join("probe")).ok();
    let output = locked.join("out.png");
    if writable {
        let scene = cornell();
        let out = rondo(&[
            "render",
            text(&scene),
            "-o",
            text(&output),
            "--spp",
            "1",
            "--width",
            "4",
            "--height",
            "4",
        ]);
        assert!(out.status.success(), "{}", stderr(&out));
        assert!(output.exists());
    } else {
        assert_refused(&endless_render(text(&output)), "cannot create files in");
    }
    std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o755)).expect("chmod");
}

#[test]
fn watch_refuses_an_unwritable_output_instead_of_watching() {
    let dir = temp_dir("cli-watch");
    let scene = cornell();
    let output = dir.join("missing/live.png");
    let out = rondo(&["watch", text(&scene), "-o", text(&output)]);
    assert_refused(&out, "does not exist");
}

/// Writes a 2×1 PNG with the given red values.
fn png(dir: &Path, name: &str, red: [u8; 2]) -> PathBuf {
    let path = dir.join(name);
    image::RgbImage::from_raw(2, 1, vec![red[0], 0, 0, red[1], 0, 0])
        .expect("2x1 image")
        .save(&path)
        .expect("write png");
    path
}

#[test]
fn diff_refuses_an_unwritable_error_image_before_comparing() {
    let dir = temp_dir("cli-diff");
    let a = png(&dir, "a.png", [0, 255]);
    let b = png(&dir, "b.png", [255, 255]);
    let error_image = dir.join("missing/err.png");
    let out = rondo(&[
        "diff",
        text(&a),
        text(&b),
        "--error-image",
        text(&error_image),
    ]);
    assert_refused(&out, "does not exist");
    assert!(out.stdout.is_empty(), "compared anyway");
}

#[test]
fn benches_refuse_an_output_directory_that_is_a_file() {
    let dir = temp_dir("cli-bench-out");
    let file = dir.join("file");
    std::fs::write(&file, "").expect("write");
    let out = rondo(&["bench", "layout", "--smoke", "--out", text(&file)]);
    assert_refused(&out, "is not a directory");
    let out = rondo(&[
        "bench",
        "accuracy",
        text(&cornell()),
        "--reference",
        text(&dir.join("missing.exr")),
        "--out",
        text(&file.join("sub")),
    ]);
    assert_refused(&out, "cannot create it");
}

#[test]
fn bench_render_renders_every_run() {
    let scene = scenes_dir().join("cornell.ron");
    let out = rondo(&[
        "bench",
        "render",
        text(&scene),
        "--runs",
        "3",
        "--width",
        "48",
        "--height",
        "48",
        "--spp",
        "8",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let log = stderr(&out);
    // `run k: 48x48, 8 spp, T s, …`: every run traces (before, runs 2 and 3 reloaded the
    // unchanged scene into the finished film and reported 0.000 s).
    let seconds: Vec<f64> = log
        .lines()
        .filter(|l| l.starts_with("run "))
        .filter_map(|l| l.split(", ").nth(2)?.strip_suffix(" s")?.parse().ok())
        .collect();
    assert_eq!(seconds.len(), 3, "{log}");
    assert!(seconds.iter().all(|&t| t > 0.0), "{log}");
}

/// A scene with a mesh at a relative path, a small sphere, two materials: every kind of edit of
/// `rondo bench watch` has a target. (The red colour and the translation are those the bench
/// looked for before it found its targets itself.)
fn relative_mesh_scene(dir: &Path, mesh: &str) -> PathBuf {
    std::fs::create_dir_all(dir.join("meshes")).expect("mkdir");
    std::fs::write(
        dir.join("meshes/tri.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .expect("write mesh");
    write_scene(
        dir,
        "scene.ron",
        &format!(
            r#"Scene(
    camera: Camera(position: (0, 1, -5), look_at: (0, 0, 0), fov: 40),
    settings: Settings(width: 16, height: 16, spp: 2, max_depth: 2),
    materials: {{
        "red": Diffuse(albedo: Constant((0.65, 0.05, 0.05))),
        "lamp": Light(emit: Constant((1, 1, 1)), intensity: 4),
    }},
    entities: [
        Entity(name: "ball", material: "red", shape: Sphere(center: (0, 0.2, 0), radius: 0.2)),
        Entity(name: "tri", material: "red", shape: Mesh(path: "{mesh}"),
               transform: Transform(translate: (265, 0, 295))),
        Entity(name: "light", material: "lamp", shape: Quad(a: (-1, 3, -1), b: (1, 3, -1), c: (1, 3, 1), d: (-1, 3, 1))),
    ],
)
"#
        ),
    )
}

/// The names in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .expect("list")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn bench_watch_edits_a_scene_with_relative_paths_and_leaves_no_copy() {
    let dir = temp_dir("cli-bench-watch");
    let scene = relative_mesh_scene(&dir, "meshes/tri.obj");
    let original = std::fs::read_to_string(&scene).expect("read");
    let out = rondo(&[
        "bench",
        "watch",
        text(&scene),
        "--runs",
        "2",
        "--threads",
        "1",
    ]);
    // Before, the edited copy was in a temporary directory, where `meshes/tri.obj` is not.
    assert!(out.status.success(), "{}", stderr(&out));
    let table = String::from_utf8_lossy(&out.stdout);
    for kind in ["colour", "move-small", "move-mesh", "entity-material"] {
        assert!(
            table.lines().any(|l| l.trim_start().starts_with(kind)),
            "{kind}: {table}"
        );
    }
    assert!(table.contains("(sphere \"ball\")"), "{table}");
    assert!(table.contains("(mesh entity \"tri\")"), "{table}");
    assert_eq!(names(&dir), ["meshes", "scene.ron"], "a copy was left");
    assert_eq!(std::fs::read_to_string(&scene).expect("read"), original);

    // A scene that parses but does not load: the error, and the copy removed all the same.
    let broken = relative_mesh_scene(&dir, "meshes/missing.obj");
    let out = rondo(&[
        "bench",
        "watch",
        text(&broken),
        "--runs",
        "1",
        "--threads",
        "1",
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(stderr(&out).contains("missing.obj"), "{}", stderr(&out));
    assert_eq!(names(&dir), ["meshes", "scene.ron"], "a copy was left");
}

#[test]
fn bench_watch_stopped_by_ctrl_c_removes_its_copy() {
    use std::io::BufRead as _;
    let dir = temp_dir("cli-bench-watch-sigint");
    let scene = relative_mesh_scene(&dir, "meshes/tri.obj");
    let mut child = Command::new(env!("CARGO_BIN_EXE_rondo"))
        .args([
            "bench",
            "watch",
            text(&scene),
            "--runs",
            "100000",
            "--threads",
            "1",
        ])
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start rondo");
    // The first render's line: the copy exists and edits are being saved.
    let mut lines = std::io::BufReader::new(child.stderr.take().expect("stderr")).lines();
    let first = lines.next().and_then(Result::ok).unwrap_or_default();
    assert!(first.starts_with("loaded:"), "{first}");
    assert_eq!(names(&dir).len(), 3, "no copy beside the scene");
    let sent = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill");
    assert!(sent.success());
    let rest: Vec<String> = lines.map_while(Result::ok).collect();
    let status = wait_or_kill(&mut child, HANG_GUARD).expect("rondo did not stop on SIGINT");
    assert_eq!(status.code(), Some(1), "{rest:?}");
    assert!(
        rest.iter().any(|l| l.contains("stopped by a signal")),
        "{rest:?}"
    );
    assert_eq!(names(&dir), ["meshes", "scene.ron"], "a copy was left");
}

#[test]
fn bench_load_times_each_kind_of_edit_with_and_without_a_big_mesh() {
    // The old flags still work: the load table of one kind and size, and `--watch N`.
    let out = rondo(&[
        "bench", "load", "--kinds", "flat", "--sizes", "10", "--watch", "10", "--edits", "1",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let table = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(table.contains("| flat | 10 | 0.0 | 10 |"), "{table}");
    assert!(table.contains("| scene | entities | file MB | cold start ms | colour | move-small | move-mesh | entity-material |"), "{table}");

    let out = rondo(&[
        "bench",
        "load",
        "--no-load",
        "--watch-sizes",
        "10,100",
        "--big-mesh",
        "200",
        "--edits",
        "2",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let table = String::from_utf8_lossy(&out.stdout).into_owned();
    let rows: Vec<Vec<&str>> = table
        .lines()
        .filter(|l| l.starts_with("| flat"))
        .map(|l| l.split('|').map(str::trim).collect())
        .collect();
    // `| scene | entities | MB | cold | colour | move-small | move-mesh | entity-material |`:
    // every kind timed where the scene has its target, the mesh moved only where there is one,
    // and the growth given from 10 to 100 entities.
    assert_eq!(rows.len(), 4, "{table}");
    for row in &rows {
        let with_mesh = row[1].contains("OBJ");
        assert!(!with_mesh || row[1] == "flat + 200-triangle OBJ", "{table}");
        for (column, cell) in row[5..9].iter().enumerate() {
            assert_eq!(*cell == "–", column == 2 && !with_mesh, "{table}");
        }
        assert_eq!(row[2] == "100", row[4].contains('×'), "{table}");
    }
}

#[test]
fn bench_environment_runs_on_a_tiny_map_and_writes_its_table_only_when_asked() {
    let dir = temp_dir("cli-bench-environment");
    let args = [
        "bench",
        "environment",
        "--width",
        "16",
        "--height",
        "8",
        "--runs",
        "2",
    ];
    let out = rondo(&args);
    assert!(out.status.success(), "{}", stderr(&out));
    let table = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        table.contains("Environment map 16×8, median (min) of 2 runs"),
        "{table}"
    );
    // One row per format, each within the map's bound (sky/environment.rs): 16.5 bytes per
    // texel, at most 36 per row and 8 per column of small tables, 16 more.
    // The table rounds to two decimals.
    let bound = 16.5 + (36.0 * 8.0 + 8.0 * 16.0 + 16.0) / 128.0 + 0.005;
    for format in ["| exr |", "| hdr |"] {
        let row = table.lines().find(|l| l.starts_with(format));
        let per_texel = row.and_then(|r| r.split('|').nth(6)?.trim().parse::<f64>().ok());
        assert!(per_texel.is_some_and(|b| b <= bound), "{table}");
    }
    let out_dir = dir.join("out");
    let out = rondo(&[&args[..], &["--out", text(&out_dir)]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    let written = std::fs::read_to_string(out_dir.join("environment.md")).expect("table written");
    assert!(
        written.contains("| exr |") && written.contains("| hdr |"),
        "{written}"
    );
    assert_eq!(
        std::fs::read_dir(&dir).expect("list").count(),
        1,
        "wrote elsewhere"
    );
    let file = dir.join("file");
    std::fs::write(&file, "").expect("write");
    let out = rondo(&[&args[..], &["--out", text(&file)]].concat());
    assert_refused(&out, "is not a directory");
}

#[test]
fn a_missing_diff_input_says_its_cause_once() {
    let dir = temp_dir("cli-diff-missing");
    let b = png(&dir, "b.png", [0, 0]);
    let out = rondo(&["diff", text(&dir.join("nope.png")), text(&b)]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert_eq!(err.matches("No such file").count(), 1, "{err}");
    assert!(err.contains("nope.png"), "{err}");
}

#[test]
fn output_whose_reader_has_gone_ends_quietly() {
    // `rondo diff a b | head -0`: the pipe's read end is closed before rondo writes. `println!`
    // panicked there (status 101, a backtrace on stderr).
    let dir = temp_dir("cli-closed-pipe");
    let a = png(&dir, "a.png", [0, 0]);
    let b = png(&dir, "b.png", [10, 0]);
    for args in [
        vec!["diff", text(&a), text(&b)],
        vec!["check", text(&cornell())],
    ] {
        let (reader, writer) = std::io::pipe().expect("pipe");
        drop(reader);
        let mut child = Command::new(env!("CARGO_BIN_EXE_rondo"))
            .args(&args)
            .stdin(Stdio::null())
            .stdout(writer)
            .stderr(Stdio::piped())
            .spawn()
            .expect("start rondo");
        assert!(
            wait_or_kill(&mut child, HANG_GUARD).is_some(),
            "{args:?} hangs"
        );
        let out = child.wait_with_output().expect("rondo output");
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(0), "{args:?}: {err}");
        assert!(err.is_empty(), "{args:?}: {err}");
    }
}

#[test]
fn usage_errors_exit_with_status_2_and_input_errors_with_status_1() {
    let dir = temp_dir("cli-codes");
    let scene = cornell();
    let scene = text(&scene);
    let out_png = dir.join("out.png");
    let out_png = text(&out_png);
    let usage: [&[&str]; 12] = [
        &[],
        &["paint"],
        &["render", scene],
        &["render", scene, "-o", "out.txt"],
        // The README's table: an output that does not end in .png or .exr is a usage error for
        // every command that writes one.
        &["merge", "part.exr", "-o", "out.txt"],
        &["merge", "part.exr", "-o", out_png, "--spp", "0"],
        &["farm", "slurm", scene, "--tasks", "2", "-o", "out.txt"],
        &["render", scene, "-o", out_png, "--spp", "0"],
        &["render", scene, "-o", out_png, "--threads", "0"],
        &["render", scene, "-o", out_png, "--width", "many"],
        &["watch", scene, "-o", out_png, "--first-spp", "0"],
        &["bench", "layout", "--workload", "nope"],
    ];
    for args in usage {
        let out = rondo(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        assert!(!Path::new(out_png).exists(), "{args:?} wrote an image");
    }
    let bad = write_scene(
        &dir,
        "bad.ron",
        "Scene(camera: Camera(position: (0, 0, 0)))",
    );
    let missing = dir.join("missing.ron");
    let input: [&[&str]; 3] = [
        &["render", text(&bad), "-o", out_png],
        &["render", text(&missing), "-o", out_png],
        &["check", text(&missing)],
    ];
    for args in input {
        let out = rondo(args);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.starts_with("error: ") && !err.contains("panicked"),
            "{err}"
        );
    }
    let out = rondo(&["check", scene]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
}

/// The summary of a render of a sample range gives the samples it rendered,
/// and the rate from them. Every sample traces its camera ray, so rays/s ≥ samples/s holds for
/// a true count, and fails by far for 1024 spp claimed where 1 was rendered.
#[test]
fn a_range_render_reports_the_samples_it_rendered() {
    let dir = temp_dir("cli-range-summary");
    let part = dir.join("part.exr");
    let scene = cornell();
    let out = rondo(&[
        "render",
        text(&scene),
        "--samples",
        "1023..1024",
        "--width",
        "128",
        "--height",
        "128",
        "-o",
        text(&part),
    ]);
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    assert!(err.contains(", 1 spp (samples 1023..1024),"), "{err}");
    let rate = |unit: &str| -> f64 {
        let end = err
            .find(unit)
            .unwrap_or_else(|| panic!("no {unit} in {err}"));
        let start = err[..end].rfind(", ").expect("a number before the unit") + 2;
        err[start..end].trim().parse().expect("a rate")
    };
    let (samples, rays) = (rate(" M samples/s"), rate(" M rays/s"));
    // Both are printed to 0.01.
    assert!(rays + 0.01 >= samples, "{err}");
}

#[test]
fn render_denoise_writes_the_denoised_colour_beside_the_raw_one_and_the_features() {
    if common::denoiser().is_none() {
        return;
    }
    let dir = temp_dir("cli-denoise");
    let (plain, layered) = (dir.join("plain.exr"), dir.join("layered.exr"));
    let size = ["--spp", "2", "--width", "48", "--height", "48"];
    let scene = cornell();
    let out = rondo(&[&["render", text(&scene), "-o", text(&plain)], &size[..]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    let args = ["render", text(&scene), "-o", text(&layered), "--denoise"];
    let out = rondo(&[&args[..], &["--aov", "albedo,normal"], &size[..]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stderr(&out).contains("denoised in"), "{}", stderr(&out));
    let (plain, layered) = (exr_channels(&plain), exr_channels(&layered));
    let names: Vec<&str> = layered.keys().map(String::as_str).collect();
    assert_eq!(
        names,
        [
            "B", "G", "R", "albedo.B", "albedo.G", "albedo.R", "normal.B", "normal.G", "normal.R",
            "raw.B", "raw.G", "raw.R"
        ]
    );
    // The raw layer is the image a render without the denoiser writes, to the bit; the colour
    // is another (denoised) image.
    for c in ["R", "G", "B"] {
        assert_eq!(layered[&format!("raw.{c}")], plain[c]);
        assert_ne!(layered[c], plain[c]);
    }
}

#[test]
fn denoise_and_aov_are_refused_where_they_cannot_apply_before_rendering() {
    let dir = temp_dir("cli-denoise-refused");
    let png = dir.join("x.png");
    assert_refused(
        &rondo(&[
            "render",
            text(&cornell()),
            "-o",
            text(&png),
            "--aov",
            "albedo",
        ]),
        "only an .exr holds",
    );
    let partial = dir.join("p.exr");
    let out = rondo(&[
        "render",
        text(&cornell()),
        "-o",
        text(&partial),
        "--samples",
        "0..1",
        "--denoise",
    ]);
    assert_refused(&out, "a partial (--samples, --resume) holds the raw sums");
    // Without the library, `--denoise` is refused before any work, saying how to get it.
    let empty = temp_dir("cli-no-oidn");
    let out = Command::new(env!("CARGO_BIN_EXE_rondo"))
        .args(["render", text(&cornell()), "-o", text(&png), "--denoise"])
        .env("RONDO_OIDN_DIR", empty.path())
        .output()
        .expect("run rondo");
    assert_refused(&out, "scripts/fetch-oidn.sh");
    assert!(!png.exists(), "nothing written");
}

#[test]
fn merge_denoise_denoises_merged_partials_into_a_png_and_refuses_an_exr() {
    if common::denoiser().is_none() {
        return;
    }
    let dir = temp_dir("cli-merge-denoise");
    let scene = cornell();
    let size = ["--width", "32", "--height", "32"];
    let mut parts = Vec::new();
    for range in ["0..2", "2..4"] {
        let part = dir.join(format!("{}.exr", range.replace("..", "-")));
        let args = [
            "render",
            text(&scene),
            "-o",
            text(&part),
            "--samples",
            range,
        ];
        let out = rondo(&[&args[..], &size[..]].concat());
        assert!(out.status.success(), "{}", stderr(&out));
        parts.push(part);
    }
    let png = dir.join("merged.png");
    let out = rondo(&[
        "merge",
        text(&parts[0]),
        text(&parts[1]),
        "-o",
        text(&png),
        "--denoise",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let raw = dir.join("raw.png");
    let out = rondo(&["merge", text(&parts[0]), text(&parts[1]), "-o", text(&raw)]);
    assert!(out.status.success(), "{}", stderr(&out));
    let (a, b) = (
        image::open(&png).expect("png"),
        image::open(&raw).expect("png"),
    );
    assert_eq!(a.width(), 32);
    assert_ne!(a.to_rgb8().into_raw(), b.to_rgb8().into_raw(), "denoised");
    let exr = dir.join("merged.exr");
    let out = rondo(&[
        "merge",
        text(&parts[0]),
        text(&parts[1]),
        "-o",
        text(&exr),
        "--denoise",
    ]);
    assert_refused(&out, "an .exr merge is a partial of the raw sums");
}

#[test]
fn a_scenes_denoise_setting_asks_for_the_denoised_image_and_no_denoise_overrides_it() {
    if common::denoiser().is_none() {
        return;
    }
    let dir = temp_dir("cli-denoise-setting");
    let source = std::fs::read_to_string(cornell()).expect("cornell.ron");
    let source = source.replacen(
        "settings: Settings(",
        "settings: Settings(denoise: true, ",
        1,
    );
    assert!(source.contains("denoise: true"));
    let scene = write_scene(&dir, "scene.ron", &source);
    let size = ["--spp", "1", "--width", "24", "--height", "24"];
    let (on, off) = (dir.join("on.exr"), dir.join("off.exr"));
    let out = rondo(&[&["render", text(&scene), "-o", text(&on)], &size[..]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    let args = ["render", text(&scene), "-o", text(&off), "--no-denoise"];
    let out = rondo(&[&args[..], &size[..]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        exr_channels(&on).contains_key("raw.R"),
        "denoised, raw kept"
    );
    assert!(!exr_channels(&off).contains_key("raw.R"), "not denoised");
}

#[test]
fn check_command_lists_warnings_with_status_0_and_refuses_broken_scenes_with_status_1() {
    // `rondo check` on the stress scene: its two deliberate z-fighting pairs, status 0. On a
    // clean scene: no warnings, status 0. On a degenerate quad: the located load error, status 1.
    let run = |scene: &std::path::Path| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_rondo"))
            .arg("check")
            .arg(scene)
            .output()
            .expect("run rondo");
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stdout).into_owned(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let stress = common::scenes_dir().join("stress.ron");
    let (code, stdout, _) = run(&stress);
    assert_eq!(code, Some(0), "{stdout}");
    let warnings: Vec<&str> = stdout
        .lines()
        .filter(|l| l.starts_with("warning:"))
        .collect();
    assert_eq!(warnings.len(), 2, "{stdout}");
    assert!(
        warnings[0].contains("\"ground\" and \"case\" overlap in one plane"),
        "{stdout}"
    );
    assert!(
        warnings[1].contains("\"ground\" and \"diamond\""),
        "{stdout}"
    );
    assert!(stdout.ends_with("stress.ron: 2 warnings\n"), "{stdout}");

    let (code, stdout, _) = run(&common::scenes_dir().join("sphere.ron"));
    assert_eq!((code, stdout.lines().count()), (Some(0), 1), "{stdout}");
    assert!(stdout.contains("no warnings"), "{stdout}");

    let dir = temp_dir("check-cli");
    let bad = write_scene(
        &dir,
        "bad.ron",
        "Scene(\n    camera: Camera(position: (0, 0, -5), look_at: (0, 0, 0)),\n    materials: { \"w\": Diffuse(albedo: Constant((1, 1, 1))) },\n    entities: [ Entity(material: \"w\", shape: Quad(a: (0, 0, 0), b: (1, 0, 0), c: (2, 0, 0), d: (0, 1, 0))) ],\n)",
    );
    let (code, stdout, stderr) = run(&bad);
    assert_eq!(code, Some(1), "{stdout}{stderr}");
    assert!(
        stderr.contains("bad.ron:4:") && stderr.contains("quad: zero area"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
}
