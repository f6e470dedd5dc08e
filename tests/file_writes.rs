//! Output files: a planted symlink never redirects a write, a signal in the middle of a write
//! leaves no temporary behind, and the tests' temporary directories remove themselves.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

use common::{temp_dir, wait_or_kill, write_scene};
use rondo::farm::partial::read_partial;
use rondo::watch::{Report, WatchOptions, WatchSession};
use rondo::{PassPlan, Renderer};

/// Ends a child that hangs; not a measure of anything.
const HANG_GUARD: Duration = Duration::from_secs(120);

fn scene(width: u32, height: u32, spp: u32) -> String {
    format!(
        r#"Scene(
    camera: Camera(position: (0, 0, -4), look_at: (0, 0, 0), fov: 40.0),
    settings: Settings(width: {width}, height: {height}, spp: {spp}, max_depth: 2, background: (0.3, 0.5, 0.7)),
    materials: {{ "grey": Diffuse(albedo: Constant((0.5, 0.5, 0.5))) }},
    entities: [ Entity(material: "grey", shape: Sphere(center: (0, 0, 0), radius: 1)) ],
)"#
    )
}

/// Names of the entries of `dir` that look like temporaries.
fn temporaries(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .expect("read dir")
        .filter_map(Result::ok)
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".tmp"))
        .collect()
}

/// A file outside the output's directory, and symlinks to it at every name the temporary of
/// each output in `outputs` would have in this process under a predictable scheme
/// (`.NAME.PID.tmp`), and at a few other
/// guessable ones.
#[cfg(unix)]
struct Trap {
    _outside: common::TestDir,
    victim: PathBuf,
}

#[cfg(unix)]
impl Trap {
    const CONTENT: &'static [u8] = b"not to be overwritten";

    fn plant(dir: &Path, outputs: &[&str], pids: &[u32]) -> Self {
        let outside = temp_dir("victim");
        let victim = outside.join("victim");
        std::fs::write(&victim, Self::CONTENT).expect("write victim");
        for name in outputs {
            let mut links: Vec<String> = pids.iter().map(|p| format!(".{name}.{p}.tmp")).collect();
            links.extend([format!(".{name}.tmp"), format!("{name}.tmp")]);
            for link in links {
                std::os::unix::fs::symlink(&victim, dir.join(link)).expect("plant symlink");
            }
        }
        Self {
            _outside: outside,
            victim,
        }
    }

    fn assert_untouched(&self) {
        let now = std::fs::read(&self.victim).expect("victim");
        assert!(
            now == Self::CONTENT,
            "a write went through a planted symlink: the victim now holds {} bytes",
            now.len()
        );
    }
}

#[cfg(unix)]
#[test]
fn item11_a_render_write_does_not_follow_a_symlink_planted_at_a_temporary_name() {
    let dir = temp_dir("symlink-render");
    let path = write_scene(&dir, "scene.ron", &scene(16, 16, 2));
    let trap = Trap::plant(&dir, &["out.png", "out.exr"], &[std::process::id()]);
    for out in ["out.png", "out.exr"] {
        let out = dir.join(out);
        let mut r = Renderer::new(Some(2), PassPlan::Single).expect("thread pool");
        r.set_output(Some(&out), false);
        r.load(&path).unwrap_or_else(|e| panic!("{e}"));
        r.render_to_completion();
        assert_eq!(r.output().last_error, None);
        trap.assert_untouched();
        let image = image::open(&out).expect("the output is a complete image");
        assert_eq!((image.width(), image.height()), (16, 16));
    }
}

#[cfg(unix)]
#[test]
fn item11_a_watch_write_does_not_follow_a_symlink_planted_at_a_temporary_name() {
    let dir = temp_dir("symlink-watch");
    let path = write_scene(&dir, "scene.ron", &scene(16, 16, 8));
    let out = dir.join("live.png");
    let trap = Trap::plant(&dir, &["live.png"], &[std::process::id()]);
    // And a symlink at the output itself: the rename replaces the link, not its target.
    std::os::unix::fs::symlink(&trap.victim, &out).expect("symlink at the output");
    let mut options = WatchOptions::new(&path, &out);
    options.threads = Some(2);
    let session = WatchSession::start(options).expect("start watching");
    let rendered = session.wait_for(
        HANG_GUARD,
        |r| matches!(r, Report::Rendered(r) if r.completed()),
    );
    common::end_watch(Some(session));
    assert!(rendered.is_ok(), "no complete render: {rendered:?}");
    trap.assert_untouched();
    let meta = std::fs::symlink_metadata(&out).expect("output");
    assert!(meta.is_file(), "the output link is replaced by the image");
    image::open(&out).expect("the output is a complete image");
}

/// Starts `rondo ARGS` in `dir`, sends `signal` as soon as a temporary appears there, and waits
/// for it to end. Returns whether a temporary was seen before the signal, and the exit status.
fn signal_mid_write(dir: &Path, args: &[&str], signal: &str) -> (bool, std::process::ExitStatus) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_rondo"))
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("start rondo");
    let seen = loop {
        if !temporaries(dir).is_empty() {
            break true;
        }
        if child.try_wait().expect("poll the child").is_some() {
            break false;
        }
        std::thread::yield_now();
    };
    if seen {
        let sent = Command::new("kill")
            .args([&format!("-{signal}"), &child.id().to_string()])
            .status()
            .expect("run kill");
        assert!(sent.success(), "kill -{signal}");
    }
    let status = wait_or_kill(&mut child, HANG_GUARD).expect("rondo ends after the signal");
    (seen, status)
}

#[test]
fn item12_sigterm_or_sigint_during_a_render_write_leaves_no_temporary() {
    // A large EXR takes long enough to encode and write for the signal to land during it.
    let dir = temp_dir("signal-render");
    write_scene(&dir, "scene.ron", &scene(2048, 2048, 1));
    let mut caught = 0;
    for signal in ["TERM", "INT", "TERM", "INT"] {
        let (seen, status) = signal_mid_write(
            &dir,
            &["render", "scene.ron", "-o", "out.exr", "--threads", "2"],
            signal,
        );
        let left = temporaries(&dir);
        assert!(
            left.is_empty(),
            "SIG{signal} left {left:?} (seen mid-write: {seen}, {status})"
        );
        if seen {
            caught += 1;
            assert!(!status.success(), "SIG{signal} during the write: {status}");
        }
    }
    assert!(caught > 0, "no run was caught in the middle of a write");
}

#[test]
fn item12_sigterm_during_a_watch_write_leaves_no_temporary() {
    let dir = temp_dir("signal-watch");
    write_scene(&dir, "scene.ron", &scene(2048, 2048, 64));
    let (seen, status) = signal_mid_write(
        &dir,
        &["watch", "scene.ron", "-o", "out.exr", "--threads", "2"],
        "TERM",
    );
    assert!(seen, "the watch wrote no image ({status})");
    let left = temporaries(&dir);
    assert!(left.is_empty(), "SIGTERM left {left:?} ({status})");
}

#[test]
fn item18_a_test_directory_is_removed_on_drop_and_kept_when_the_test_fails() {
    let dir = temp_dir("guard removed");
    std::fs::create_dir(dir.join("sub")).expect("mkdir");
    std::fs::write(dir.join("sub/file"), b"x").expect("write");
    let path = dir.to_path_buf();
    assert!(
        path.file_name()
            .is_some_and(|n| n.to_string_lossy().starts_with("rondo-guard removed-")),
        "{}",
        path.display()
    );
    drop(dir);
    assert!(!path.exists(), "{} is left behind", path.display());

    let kept = std::thread::spawn(|| {
        let dir = temp_dir("guard-kept");
        std::fs::write(dir.join("evidence"), b"x").expect("write");
        let path = dir.to_path_buf();
        // A failing test: the directory must outlive the panic.
        std::panic::panic_any(path);
    })
    .join()
    .expect_err("the thread panics");
    let kept = kept
        .downcast::<PathBuf>()
        .expect("the panic carries the path");
    assert!(
        kept.join("evidence").is_file(),
        "{} was removed",
        kept.display()
    );
    std::fs::remove_dir_all(&*kept).expect("remove the kept directory");
}

/// Every EXR rondo writes (an image, one with feature layers, a partial) stores its tiles in
/// increasing order, so the same image is the same bytes: with the order left unspecified the
/// tiles went out as the compression threads finished them, and a loaded machine gave different
/// files for one render. (A partial's bytes may still differ: the exr crate writes a layer's
/// own attributes in its hash map's order, so its sums are compared instead.)
#[test]
fn exr_files_store_their_tiles_in_order_and_are_the_same_bytes_for_any_thread_count() {
    let dir = temp_dir("exr-order");
    // Wider than one 64-pixel tile, so that there is an order to keep.
    std::fs::write(dir.join("s.ron"), scene(200, 130, 2)).expect("scene");
    let outputs = [
        ("plain", vec![]),
        ("layers", vec!["--aov", "albedo,normal"]),
        ("partial", vec!["--samples", "0..2"]),
    ];
    for (name, extra) in outputs {
        let mut bytes = Vec::new();
        for threads in ["1", "2"] {
            let out = dir.join(format!("{name}-{threads}.exr"));
            let status = Command::new(env!("CARGO_BIN_EXE_rondo"))
                .args(["render", "--threads", threads, "-o"])
                .arg(&out)
                .args(&extra)
                .arg(dir.join("s.ron"))
                .stderr(Stdio::null())
                .status()
                .expect("run rondo");
            assert!(status.success(), "{name}");
            let meta = exr::meta::MetaData::read_from_file(&out, false).expect("read header");
            for header in &meta.headers {
                assert_eq!(
                    header.line_order,
                    exr::meta::attribute::LineOrder::Increasing,
                    "{name}"
                );
            }
            bytes.push(std::fs::read(&out).expect("read"));
        }
        if name == "partial" {
            let read = |t: &str| read_partial(&dir.join(format!("partial-{t}.exr"))).expect("read");
            assert!(read("1") == read("2"), "the sums depend on the threads");
        } else {
            assert!(
                bytes[0] == bytes[1],
                "{name}: the bytes depend on the threads"
            );
        }
    }
}
