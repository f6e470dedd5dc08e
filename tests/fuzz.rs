//! Hostile input: a seeded mutation fuzzer over the shipped scenes, and broken texture, mesh and
//! prefab files. The loader must answer `Ok` or `Err` and never panic, hang or allocate without
//! bound; a scene that loads must also check and render without panicking.
//!
//! Unbounded allocation is caught by the test binary's own global allocator, which records the
//! largest single request: sizes must be checked before anything is allocated for them.

mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

use common::png_chunks::png_header;
use common::temp_dir;
use rondo::scene::assets::AssetCache;
use rondo::scene::check::check_scene;
use rondo::scene::format::MAX_PIXELS;
use rondo::scene::load::{LoadedScene, load_scene};
use rondo::shading::rng::Rng;
use rondo::{Overrides, PassPlan, Renderer};

/// The system allocator, recording the largest single allocation of the process.
struct LargestAllocation;

static LARGEST: AtomicUsize = AtomicUsize::new(0);

#[expect(
    unsafe_code,
    reason = "a global allocator is an unsafe trait; this one forwards every call to System unchanged and only records sizes"
)]
unsafe impl GlobalAlloc for LargestAllocation {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        LARGEST.fetch_max(layout.size(), Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        LARGEST.fetch_max(layout.size(), Ordering::Relaxed);
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        LARGEST.fetch_max(new_size, Ordering::Relaxed);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: LargestAllocation = LargestAllocation;

/// Largest single allocation any test here may cause. Loading the shipped scenes needs well
/// under 1 MiB per allocation; a film or texture sized by hostile numbers would need gigabytes.
const ALLOCATION_CAP: usize = 64 << 20;

/// A scratch copy of `scenes/` (textures, meshes, prefabs and the scenes), so that mutated
/// scenes resolve their relative paths as the originals do. Returns it with the scene texts.
fn scratch_scenes(name: &str) -> (common::TestDir, Vec<(String, Vec<u8>)>) {
    let dir = temp_dir(name);
    let src = common::scenes_dir();
    let mut scenes = Vec::new();
    for entry in std::fs::read_dir(&src).expect("scenes dir") {
        let path = entry.expect("entry").path();
        let file = path.file_name().expect("name").to_owned();
        if path.is_dir() {
            std::fs::create_dir_all(dir.join(&file)).expect("mkdir");
            for inner in std::fs::read_dir(&path).expect("subdir") {
                let inner = inner.expect("entry").path();
                std::fs::copy(
                    &inner,
                    dir.join(&file).join(inner.file_name().expect("name")),
                )
                .expect("copy");
            }
        } else if path.extension().is_some_and(|e| e == "ron") {
            let text = std::fs::read(&path).expect("read scene");
            std::fs::write(dir.join(&file), &text).expect("copy");
            scenes.push((file.to_string_lossy().into_owned(), text));
        }
    }
    scenes.sort();
    assert!(scenes.len() >= 8, "only {} scenes", scenes.len());
    (dir, scenes)
}

/// Fragments a hostile or careless author might type: numbers at and past every limit,
/// unbalanced brackets, comments, fields with absurd values, entities with broken references.
const TOKENS: &[&str] = &[
    "1e30",
    "-1e30",
    "1e12",
    "1000000000000",
    "4294967296",
    "18446744073709551616",
    "1e39",
    "-1e39",
    "3.4e38",
    "1e-45",
    "1e-30",
    "0",
    "-0",
    "-0.0",
    "NaN",
    "inf",
    "-inf",
    "0x7f",
    "1_000",
    "(",
    ")",
    "[",
    "]",
    "{",
    "}",
    ",",
    ":",
    "\"",
    "//",
    "/*",
    "*/",
    "Some(",
    "None",
    "#",
    "r#\"",
    "'\\u{0}'",
    "\u{feff}",
    "\0",
    "width: 1000000, height: 1000000,",
    "width: 16384, height: 16384,",
    "spp: 1000000000000,",
    "spp: 1048576,",
    "max_depth: 4294967295,",
    "radius: 0,",
    "normal: (0, 0, 0),",
    "scale: (1e30, 1e30, 1e30),",
    "scale: (1e-30, 1, 1),",
    "translate: (1e9, 1e9, 1e9),",
    "fov: 180,",
    "up: (0, 0, 0),",
    "intensity: 3e38,",
    "Entity(material: \"nope\", shape: Sphere(center: (0, 0, 0), radius: 1)),",
    "Entity(prefab: \"prefabs/box.ron\"),",
    "Entity(prefab: \"prefabs/box.ron\", transform: Transform(scale: (1e30, 1, 1))),",
    "Entity(prefab: \"cornell.ron\"),",
    "Entity(prefab: \"prefabs\"),",
    "Entity(prefab: \"/dev/zero\"),",
    "Entity(material: \"white\", shape: Mesh(path: \"meshes/bunny.obj\")),",
    "Entity(material: \"white\", shape: Mesh(path: \"textures\")),",
    "Entity(material: \"white\", shape: Mesh(path: \"/dev/zero\")),",
    "Entity(material: \"white\", shape: Mesh(path: \"textures/grid.png\")),",
    "Image(path: \"textures/grid.png\")",
    "Image(path: \"textures\")",
    "Image(path: \"meshes/bunny.obj\")",
    "Image(path: \"/dev/zero\")",
    "Checker(scale: 1e30, even: Constant((1e30, 0, 0)), odd: Constant((0, 0, 0)))",
];

/// Numbers that replace a number of the scene.
const NUMBERS: &[&str] = &[
    "1e30",
    "-1e30",
    "1e12",
    "1e9",
    "-1e9",
    "1e-30",
    "0",
    "-0",
    "3.4e38",
    "1e39",
    "4294967296",
    "1000000",
    "NaN",
    "inf",
    "-1",
];

/// One random edit of `text`: flip a byte, truncate, insert a token, replace a number, delete
/// or duplicate a span.
fn mutate(text: &mut Vec<u8>, rng: &mut Rng) {
    let mut below = |n: usize| (rng.next_u32() as usize) % n.max(1);
    let len = text.len();
    // Numbers are replaced most often: such mutants still parse, and reach the checks of values
    // and the renderer.
    match below(10) {
        0 => {
            let i = below(len);
            if i < len {
                text[i] = below(256) as u8;
            }
        }
        1 => text.truncate(below(len + 1)),
        2 | 3 => {
            let token = TOKENS[below(TOKENS.len())].as_bytes();
            let i = below(len + 1);
            text.splice(i..i, token.iter().copied());
        }
        4..=7 => {
            // Replace the number that starts at or after a random place.
            let start = below(len);
            let Some(k) = text[start.min(len)..].iter().position(u8::is_ascii_digit) else {
                return;
            };
            let i = start + k;
            let j = i + text[i..]
                .iter()
                .position(|c| !(c.is_ascii_digit() || *c == b'.' || *c == b'e' || *c == b'-'))
                .unwrap_or(len - i);
            let number = NUMBERS[below(NUMBERS.len())].as_bytes();
            text.splice(i..j, number.iter().copied());
        }
        8 => {
            let i = below(len);
            let j = (i + 1 + below(40)).min(len);
            text.drain(i..j);
        }
        _ => {
            let i = below(len);
            let j = (i + 1 + below(200)).min(len);
            let span: Vec<u8> = text[i..j].to_vec();
            text.splice(j..j, span);
        }
    }
}

/// Loads `path`; on success also checks it and renders a 4×4, 1 spp image of it. Any panic
/// fails the test with the offending text.
fn load_check_render(
    path: &Path,
    text: &[u8],
    assets: &mut AssetCache,
    renderer: &mut Renderer,
) -> bool {
    let result = catch_unwind(AssertUnwindSafe(|| load_scene(path, assets)));
    let loaded: LoadedScene = match result {
        Ok(Ok(scene)) => scene,
        Ok(Err(e)) => {
            // The scene, or a prefab it places (errors inside a prefab name the prefab).
            let message = e.to_string();
            let dir = path.parent().expect("scratch dir").display().to_string();
            assert!(
                message.starts_with(&dir),
                "error without its file: {message}"
            );
            return false;
        }
        Err(_) => panic!("the loader panicked on:\n{}", String::from_utf8_lossy(text)),
    };
    let s = &loaded.settings;
    assert!(
        s.validate().is_ok() && u64::from(s.width) * u64::from(s.height) <= MAX_PIXELS,
        "limits not enforced: {s:?}"
    );
    let checked = catch_unwind(AssertUnwindSafe(|| check_scene(&loaded)));
    assert!(
        checked.is_ok(),
        "check panicked on:\n{}",
        String::from_utf8_lossy(text)
    );
    let rendered = catch_unwind(AssertUnwindSafe(|| {
        renderer.load(path).map(|_| renderer.render_to_completion())
    }));
    match rendered {
        Ok(Ok(_)) => {}
        Ok(Err(e)) => panic!("loaded once, then failed: {e}"),
        Err(_) => panic!("rendering panicked on:\n{}", String::from_utf8_lossy(text)),
    }
    true
}

#[test]
fn mutated_scenes_load_or_fail_cleanly_and_never_panic_or_allocate_without_bound() {
    // 2500 mutants of the shipped scenes, each one to three edits deep, seeded: byte flips,
    // truncations, inserted tokens (limits, NaN, brackets, broken references, device files),
    // numbers replaced by huge or tiny ones, deleted and duplicated spans. Expected: every
    // mutant loads or fails with an error naming its file (or the prefab at fault); no panic in loading, checking or a
    // 4×4 render of those that load; no allocation above 64 MiB (a 10⁶×10⁶ film would be 24 TB,
    // 10¹² spp are refused before a pass is planned). Both outcomes must occur.
    let (dir, scenes) = scratch_scenes("fuzz-scenes");
    let mut assets = AssetCache::default();
    let mut renderer = Renderer::new(Some(1), PassPlan::Single).expect("pool");
    renderer.set_overrides(Overrides {
        width: Some(4),
        height: Some(4),
        spp: Some(1),
        max_depth: Some(4),
        ..Default::default()
    });
    let mut rng = Rng::new(0xf022, 1);
    let (mut loaded, mut failed) = (0, 0);
    for i in 0..2500 {
        let (name, original) = &scenes[i % scenes.len()];
        let mut text = original.clone();
        for _ in 0..1 + rng.next_u32() % 3 {
            mutate(&mut text, &mut rng);
        }
        let path = dir.join(format!("mutant-{name}"));
        std::fs::write(&path, &text).expect("write mutant");
        if load_check_render(&path, &text, &mut assets, &mut renderer) {
            loaded += 1;
        } else {
            failed += 1;
        }
        let largest = LARGEST.load(Ordering::Relaxed);
        assert!(
            largest <= ALLOCATION_CAP,
            "a {largest}-byte allocation for:\n{}",
            String::from_utf8_lossy(&text)
        );
    }
    eprintln!("{loaded} mutants loaded, {failed} refused");
    assert!(
        loaded > 250 && failed > 1000,
        "{loaded} loaded, {failed} refused"
    );
}

#[test]
fn deeply_nested_or_huge_input_is_refused_without_overflowing_the_stack() {
    // 100 000 nested brackets or checkers would overflow the parser's stack without its
    // recursion limit. Expected: an error, no crash.
    let dir = temp_dir("fuzz-nesting");
    let deep = |open: &str, close: &str| {
        format!(
            "Scene(camera: Camera(position: (0, 0, 0), direction: (0, 0, 1)), materials: {{ \"m\": Diffuse(albedo: {}Constant((1, 1, 1)){}) }})",
            open.repeat(100_000),
            close.repeat(100_000)
        )
    };
    for (k, text) in [
        deep("(", ")"),
        deep("[", "]"),
        deep("Checker(scale: 1, odd: Constant((0, 0, 0)), even: ", ")"),
    ]
    .into_iter()
    .enumerate()
    {
        let path = dir.join(format!("deep{k}.ron"));
        std::fs::write(&path, &text).expect("write");
        let e = load_scene(&path, &mut AssetCache::default()).expect_err("nesting refused");
        assert!(
            e.to_string().starts_with(&path.display().to_string()),
            "{e}"
        );
    }
}

/// A minimal scene using `texture` as an image texture and `mesh` as a mesh (either may be
/// empty to leave it out); the path literals stand on line 3 and line 5.
fn scene_with(texture: &str, mesh: &str) -> String {
    let material = if texture.is_empty() {
        "Constant((0.5, 0.5, 0.5))".to_string()
    } else {
        format!("Image(path: \"{texture}\")")
    };
    let entity = if mesh.is_empty() {
        "Sphere(center: (0, 0, 0), radius: 1)".to_string()
    } else {
        format!("Mesh(path: \"{mesh}\")")
    };
    format!(
        "Scene(\n    camera: Camera(position: (0, 0, -5), look_at: (0, 0, 0)),\n    materials: {{ \"m\": Diffuse(albedo: {material}) }},\n    entities: [\n        Entity(material: \"m\", shape: {entity}),\n    ],\n)"
    )
}

/// Loads `scene` (written as `dir/scene.ron`) and returns its error text, or `None` if it loaded.
fn load_error(dir: &Path, scene: &str) -> Option<String> {
    let path = dir.join("scene.ron");
    std::fs::write(&path, scene).expect("write scene");
    let result = catch_unwind(|| load_scene(&path, &mut AssetCache::default()));
    match result {
        Ok(Ok(_)) => None,
        Ok(Err(e)) => Some(e.to_string()),
        Err(_) => panic!("the loader panicked on {scene}"),
    }
}

#[test]
fn broken_textures_are_errors_located_at_their_path() {
    // The shipped 64×64 grid.png cut at every length, with each byte flipped in turn, and
    // headers announcing 10⁵ × 10⁵ and 2³¹ × 1 pixels; a directory; a device; a missing file.
    // Expected: an error pointing at the texture's path in the scene (line 3, column 51) for
    // every cut that loses pixel data, every header whose image cannot be decoded, the
    // directory, the device and the missing file; never a panic, never an allocation for the
    // announced size.
    let dir = temp_dir("fuzz-png");
    let good = std::fs::read(common::scenes_dir().join("textures/grid.png")).expect("grid.png");
    let at_path = |e: &str| e.contains("scene.ron:3:51:") && e.contains("t.png");
    // The last 12 bytes are the empty IEND chunk, after all pixel data: the decoder may
    // accept a file cut inside it.
    let iend = good.len() - 12;
    for cut in 0..good.len() {
        std::fs::write(dir.join("t.png"), &good[..cut]).expect("write");
        match load_error(&dir, &scene_with("t.png", "")) {
            Some(e) => assert!(at_path(&e), "cut at {cut}: {e}"),
            None => assert!(cut >= iend, "cut at {cut} of {} loaded", good.len()),
        }
    }
    let mut flipped_errors = 0;
    for i in 0..good.len() {
        let mut bad = good.clone();
        bad[i] ^= 0x5a;
        std::fs::write(dir.join("t.png"), &bad).expect("write");
        if let Some(e) = load_error(&dir, &scene_with("t.png", "")) {
            assert!(at_path(&e), "flip at {i}: {e}");
            flipped_errors += 1;
        }
    }
    assert!(
        flipped_errors > good.len() / 2,
        "{flipped_errors} of {} flips refused",
        good.len()
    );
    for (w, h) in [(100_000, 100_000), (1 << 31, 1), (16_384, 16_384)] {
        std::fs::write(
            dir.join("t.png"),
            png_header(w, h, b"\0\0\0\0IEND\xae\x42\x60\x82"),
        )
        .expect("write");
        let e =
            load_error(&dir, &scene_with("t.png", "")).unwrap_or_else(|| panic!("{w}×{h} loaded"));
        assert!(at_path(&e), "{w}×{h}: {e}");
    }
    std::fs::create_dir_all(dir.join("folder.png")).expect("mkdir");
    let e = load_error(&dir, &scene_with("folder.png", "")).expect("a directory is refused");
    assert!(
        e.contains("scene.ron:3:51:") && e.contains("directory"),
        "{e}"
    );
    let e = load_error(&dir, &scene_with("/dev/zero", "")).expect("a device is refused");
    assert!(e.contains("scene.ron:3:51:"), "{e}");
    let e = load_error(&dir, &scene_with("missing.png", "")).expect("a missing file is refused");
    assert!(
        e.contains("scene.ron:3:51:") && e.contains("missing.png"),
        "{e}"
    );
    let largest = LARGEST.load(Ordering::Relaxed);
    assert!(largest <= ALLOCATION_CAP, "a {largest}-byte allocation");
}

#[test]
fn broken_meshes_are_errors_located_at_their_path() {
    // OBJ files cut short, with indices out of range, with non-finite coordinates, with no
    // faces, binary garbage, a directory, a device (an endless stream of zeros) and a missing
    // file. Expected: an error pointing at the mesh's path (line 5, column 49); never a panic,
    // a hang or an unbounded read.
    let dir = temp_dir("fuzz-obj");
    let good = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\n";
    let at_path = |e: &str| e.contains("scene.ron:5:49:");
    let cases: Vec<(&str, Vec<u8>)> = vec![
        ("out of range", b"v 0 0 0\nv 1 0 0\nf 1 2 3\n".to_vec()),
        (
            "huge index",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4294967297\n".to_vec(),
        ),
        (
            "negative index",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -9 2 3\n".to_vec(),
        ),
        (
            "zero index",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n".to_vec(),
        ),
        (
            "NaN vertex",
            b"v 0 NaN 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_vec(),
        ),
        (
            "infinite vertex",
            b"v 0 1e39 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_vec(),
        ),
        ("no faces", b"v 0 0 0\nv 1 0 0\nv 0 1 0\n".to_vec()),
        ("empty", Vec::new()),
        (
            "garbage",
            (0..4096u32)
                .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
                .collect(),
        ),
    ];
    for (name, bytes) in cases {
        std::fs::write(dir.join("m.obj"), &bytes).expect("write");
        let e =
            load_error(&dir, &scene_with("", "m.obj")).unwrap_or_else(|| panic!("{name} loaded"));
        assert!(at_path(&e), "{name}: {e}");
    }
    // Finite but beyond the world-space limit: refused at the entity (line 5, column 9).
    std::fs::write(
        dir.join("m.obj"),
        b"v 0 1e30 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .expect("write");
    let e = load_error(&dir, &scene_with("", "m.obj")).expect("a 1e30 vertex is refused");
    assert!(
        e.contains("scene.ron:5:9:") && e.contains("world space"),
        "{e}"
    );
    for cut in 0..good.len() {
        std::fs::write(dir.join("m.obj"), &good.as_bytes()[..cut]).expect("write");
        if let Some(e) = load_error(&dir, &scene_with("", "m.obj")) {
            assert!(at_path(&e), "cut at {cut}: {e}");
        }
    }
    std::fs::create_dir_all(dir.join("folder.obj")).expect("mkdir");
    for path in ["folder.obj", "/dev/zero", "missing.obj"] {
        let e = load_error(&dir, &scene_with("", path)).unwrap_or_else(|| panic!("{path} loaded"));
        assert!(at_path(&e), "{path}: {e}");
    }
    let largest = LARGEST.load(Ordering::Relaxed);
    assert!(largest <= ALLOCATION_CAP, "a {largest}-byte allocation");
}

#[test]
fn prefab_paths_that_are_not_prefab_files_are_errors() {
    // A prefab that is a directory, a device, missing, or the scene itself. Expected: an error
    // at the placement's path (line 3, column 32); the device is not read (reading /dev/zero to
    // the end never ends: no allocation above the cap).
    let dir = temp_dir("fuzz-prefab");
    std::fs::create_dir_all(dir.join("folder.ron")).expect("mkdir");
    for prefab in ["folder.ron", "/dev/zero", "missing.ron", "scene.ron"] {
        let scene = format!(
            "Scene(\n    camera: Camera(position: (0, 0, -5), look_at: (0, 0, 0)),\n    entities: [ Entity(prefab: \"{prefab}\") ],\n)"
        );
        let e = load_error(&dir, &scene).unwrap_or_else(|| panic!("{prefab} loaded"));
        assert!(e.contains("scene.ron:3:32:"), "{prefab}: {e}");
    }
    let largest = LARGEST.load(Ordering::Relaxed);
    assert!(largest <= ALLOCATION_CAP, "a {largest}-byte allocation");
}

#[test]
fn scene_and_prefab_files_over_the_size_bound_are_refused_before_they_are_read() {
    // Sparse files one byte over the 1 GiB bound of scene text: the size is there, the disk
    // blocks are not. Expected: an error naming the size, for the scene itself and at the
    // placement of the prefab (line 3, column 32), and no allocation above the cap — reading
    // either into memory would take 1 GiB.
    let dir = temp_dir("fuzz-huge");
    let huge = |name: &str| {
        let file = std::fs::File::create(dir.join(name)).expect("create");
        file.set_len((1 << 30) + 1).expect("sparse length");
    };
    huge("huge.ron");
    let scene = "Scene(\n    camera: Camera(position: (0, 0, -5), look_at: (0, 0, 0)),\n    entities: [ Entity(prefab: \"huge.ron\") ],\n)";
    let e = load_error(&dir, scene).expect("a huge prefab loaded");
    assert!(e.contains("scene.ron:3:32:"), "{e}");
    assert!(e.contains("is 1073741825 bytes"), "{e}");
    huge("scene.ron");
    let path = dir.join("scene.ron");
    let e = match catch_unwind(|| load_scene(&path, &mut AssetCache::default())) {
        Ok(Err(e)) => e.to_string(),
        Ok(Ok(_)) => panic!("a huge scene loaded"),
        Err(_) => panic!("the loader panicked on a huge scene"),
    };
    assert!(e.contains("is 1073741825 bytes"), "{e}");
    let largest = LARGEST.load(Ordering::Relaxed);
    assert!(largest <= ALLOCATION_CAP, "a {largest}-byte allocation");
}

#[test]
fn pipes_devices_and_directories_given_as_partials_or_images_are_refused_without_waiting() {
    // A FIFO opened for reading waits for a writer, and a device is read forever: a partial
    // (`rondo merge`) or an image (`rondo diff`) named by such a path must be refused from the
    // opened file's type, at once. Each read runs on its own thread, so a reader that waits
    // fails this test after 20 s instead of hanging it.
    let dir = temp_dir("fuzz-pipes");
    let fifo = dir.join("pipe.exr");
    let _ = std::fs::remove_file(&fifo);
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .expect("mkfifo");
    assert!(made.success());
    let within = |what: &str, read: Box<dyn FnOnce() -> String + Send>| {
        let (send, answer) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let _ = send.send(read());
        });
        let e = answer
            .recv_timeout(std::time::Duration::from_secs(20))
            .unwrap_or_else(|_| panic!("reading {what} did not return"));
        assert!(
            e.contains("not a regular file") || e.contains("directory"),
            "{what}: {e}"
        );
    };
    for path in [fifo.clone(), "/dev/zero".into(), dir.to_path_buf()] {
        let p = path.clone();
        within(
            &format!("{} as a partial", path.display()),
            Box::new(move || match rondo::farm::partial::read_meta(&p) {
                Ok(_) => "read".into(),
                Err(e) => e.0,
            }),
        );
        let p = path.clone();
        within(
            &format!("{} as an image", path.display()),
            Box::new(move || match rondo::metrics::Image::read(&p) {
                Ok(_) => "read".into(),
                Err(e) => e.to_string(),
            }),
        );
    }
}
