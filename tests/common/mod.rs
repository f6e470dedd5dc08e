//! Helpers shared by the integration tests.
#![allow(
    dead_code,
    reason = "each test binary uses a different subset of the helpers"
)]

pub mod chi2;
pub mod furnace;
pub mod gltf_doc;
pub mod png_chunks;
pub mod sheen_brdf;
pub mod two_texel;
pub mod watch_diff;

use std::path::{Path, PathBuf};

use glam::Vec3;
use rondo::shading::rng::Rng;
use rondo::{Film, Overrides, PassPlan, Renderer};

/// A test's temporary directory: removed with its contents when dropped, unless the test is
/// panicking (failing), when it is kept and its path printed so that the files can be examined.
/// Derefs to its [`Path`].
pub struct TestDir(Option<tempfile::TempDir>);

impl TestDir {
    /// The directory's path.
    pub fn path(&self) -> &Path {
        self.0
            .as_ref()
            .map_or(Path::new(""), tempfile::TempDir::path)
    }
}

impl std::ops::Deref for TestDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        self.path()
    }
}

impl AsRef<Path> for TestDir {
    fn as_ref(&self) -> &Path {
        self.path()
    }
}

impl AsRef<std::ffi::OsStr> for TestDir {
    fn as_ref(&self) -> &std::ffi::OsStr {
        self.path().as_os_str()
    }
}

impl Drop for TestDir {
    fn drop(&mut self) {
        if std::thread::panicking()
            && let Some(dir) = self.0.take()
        {
            eprintln!("test files kept in {}", dir.keep().display());
        }
    }
}

/// A fresh, empty directory for one test in the system's temporary directory, named
/// `rondo-NAME-` and random characters; see [`TestDir`] for when it is removed.
pub fn temp_dir(name: &str) -> TestDir {
    let dir = tempfile::Builder::new()
        .prefix(&format!("rondo-{name}-"))
        .tempdir()
        .expect("create temp dir");
    TestDir(Some(dir))
}

/// Writes `source` to `dir/name` and returns the path.
pub fn write_scene(dir: &Path, name: &str, source: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, source).expect("write scene");
    path
}

/// Renders a scene file with overrides and a thread count; returns the renderer when done.
pub fn render(path: &Path, overrides: Overrides, threads: Option<usize>) -> Renderer {
    let mut r = Renderer::new(threads, PassPlan::Single).expect("thread pool");
    r.set_overrides(overrides);
    r.load(path).unwrap_or_else(|e| panic!("{e}"));
    r.render_to_completion();
    r
}

/// The mean red value of the pixels in rows `rows` and columns `cols` of a render.
pub fn region_mean(
    path: &Path,
    o: Overrides,
    rows: std::ops::Range<usize>,
    cols: std::ops::Range<usize>,
) -> f64 {
    let r = render(path, o, None);
    assert_eq!(r.stats().nonfinite, 0);
    let film = r.film();
    let px = film.mean();
    let w = film.width as usize;
    let n = (rows.len() * cols.len()) as f64;
    rows.flat_map(|y| cols.clone().map(move |x| (y, x)))
        .map(|(y, x)| f64::from(px[y * w + x].x))
        .sum::<f64>()
        / n
}

/// [`Material::pbr`] of constant `base`, `metallic` and `roughness`, with the layers `layers`.
pub fn layered_pbr(
    base: Vec3,
    metallic: f32,
    roughness: f32,
    layers: rondo::shading::layers::Layers,
) -> rondo::shading::material::Material {
    let mut m = rondo::shading::material::Material::pbr(base, metallic, roughness);
    if let rondo::shading::material::Material::Pbr { layers: l, .. } = &mut m {
        *l = layers;
    }
    m
}

/// Mean radiance per pixel of a film.
pub fn pixels(film: &Film) -> Vec<glam::Vec3> {
    film.mean()
}

/// The repository's `scenes/` directory.
pub fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

/// Mean and standard error of the red channel over all pixels (for the vanishing-fov cameras
/// that make every pixel an independent estimate of one radiance value).
pub fn point_estimate(r: &Renderer) -> (f64, f64) {
    let px: Vec<f64> = r.film().mean().iter().map(|p| f64::from(p.x)).collect();
    let n = px.len() as f64;
    let mean = px.iter().sum::<f64>() / n;
    let var = px.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// A uniformly distributed unit vector: a point drawn in the cube [-1, 1]³, kept if inside the
/// unit ball (and not too near its centre to normalise), projected onto the sphere.
pub fn random_unit(rng: &mut Rng) -> Vec3 {
    loop {
        let v = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - Vec3::ONE;
        let l = v.length_squared();
        if l > 1e-4 && l <= 1.0 {
            return v / l.sqrt();
        }
    }
}

/// Packs shapes placed by transforms exactly as the ECS does (`world_primitives`, one owner per
/// shape).
pub fn geometry_of(
    shapes: &[(rondo::Shape, rondo::Transform)],
) -> rondo::geometry::packed::Geometry {
    let prims: Vec<(u32, rondo::geometry::packed::Primitive)> = shapes
        .iter()
        .enumerate()
        .flat_map(|(i, (s, t))| {
            rondo::systems::world_primitives(s, t)
                .into_iter()
                .map(move |p| (i as u32, p))
        })
        .collect();
    rondo::geometry::packed::Geometry::build(&prims)
}

/// Waits for `child` to exit and returns its status, or `None` if it was still running after
/// `hang_guard` and was killed. The guard is a watchdog that only ends a hang: the wait itself is
/// for the exit event, not a comparison of elapsed times.
pub fn wait_or_kill(
    child: &mut std::process::Child,
    hang_guard: std::time::Duration,
) -> Option<std::process::ExitStatus> {
    use std::sync::mpsc::{RecvTimeoutError, channel};
    let pid = child.id().to_string();
    let (exited, watch) = channel::<()>();
    let watchdog = std::thread::spawn(move || {
        let hung = matches!(
            watch.recv_timeout(hang_guard),
            Err(RecvTimeoutError::Timeout)
        );
        if hung {
            let _ = std::process::Command::new("kill")
                .args(["-KILL", &pid])
                .status();
        }
        hung
    });
    let status = child.wait().expect("wait for the child");
    drop(exited);
    let hung = watchdog.join().expect("watchdog");
    (!hung).then_some(status)
}

/// Ends a test's watch session: its thread must end cleanly, unless the test already failed.
/// Call it before the session's [`TestDir`] is dropped, so that nothing writes there afterwards.
pub fn end_watch(session: Option<rondo::watch::WatchSession>) {
    if let Some(session) = session {
        let stopped = session.stop();
        if !std::thread::panicking() {
            stopped.expect("watch thread ends cleanly");
        }
    }
}

/// An OBJ UV sphere of unit radius, `nu` × `nv` quads (split into triangles), with vertex
/// normals (`vn`, the exact sphere normals) if `smooth`.
pub fn uv_sphere_obj(nu: usize, nv: usize, smooth: bool) -> String {
    let mut obj = String::new();
    for j in 0..=nv {
        for i in 0..nu {
            let (theta, phi) = (
                std::f32::consts::PI * j as f32 / nv as f32,
                2.0 * std::f32::consts::PI * i as f32 / nu as f32,
            );
            let p = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            obj += &format!("v {} {} {}\n", p.x, p.y, p.z);
            if smooth {
                obj += &format!("vn {} {} {}\n", p.x, p.y, p.z);
            }
        }
    }
    let idx = |i: usize, j: usize| j * nu + (i % nu) + 1;
    for j in 0..nv {
        for i in 0..nu {
            let (a, b, c, d) = (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1));
            if smooth {
                obj += &format!("f {a}//{a} {c}//{c} {b}//{b}\nf {a}//{a} {d}//{d} {c}//{c}\n");
            } else {
                obj += &format!("f {a} {c} {b}\nf {a} {d} {c}\n");
            }
        }
    }
    obj
}

/// The shared denoiser, or `None` when the Open Image Denoise library is not available (the
/// caller skips its test, saying why), unless `RONDO_REQUIRE_OIDN=1` (as in CI, after
/// `scripts/fetch-oidn.sh`): then a missing library fails the test.
pub fn denoiser() -> Option<&'static rondo::denoise::Denoiser> {
    match rondo::denoise::Denoiser::shared() {
        Ok(d) => Some(d),
        Err(e) if std::env::var("RONDO_REQUIRE_OIDN").is_ok_and(|v| v == "1") => {
            panic!("RONDO_REQUIRE_OIDN=1 but {e}")
        }
        Err(e) => {
            eprintln!("skipped: {e}");
            None
        }
    }
}

/// The channels of an EXR file's first layer and their values, by name.
pub fn exr_channels(path: &Path) -> std::collections::BTreeMap<String, Vec<f32>> {
    let image = exr::prelude::read_all_flat_layers_from_file(path).expect("an EXR");
    image.layer_data[0]
        .channel_data
        .list
        .iter()
        .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
        .collect()
}

/// Overrides of the method and sample count.
pub fn with(method: rondo::scene::format::Method, spp: u32) -> Overrides {
    Overrides {
        method: Some(method),
        spp: Some(spp),
        ..Overrides::default()
    }
}

/// A camera of vanishing field of view from `position` at `at` (RON vectors): every pixel an
/// independent estimate of the radiance leaving that one point.
pub fn point_camera(position: &str, at: &str, up: &str) -> String {
    format!("Camera(position: {position}, look_at: {at}, up: {up}, fov: 0.001)")
}

/// Mean and standard error of the mean of `xs` (at least two values).
pub fn mean_se(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    let mean = xs.iter().sum::<f64>() / n;
    let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// Whether `mean ± se` is within `k` standard errors of `expected`.
pub fn within(mean: f64, se: f64, expected: f64, k: f64) -> bool {
    (mean - expected).abs() <= k * se + 1e-6 * expected.abs()
}

/// The [`point_estimate`] of the scene at `path` under `naive`, `nee` and `mis`, `spp` samples
/// each, in that order, for [`assert_methods_agree`].
pub fn point_estimates_by_method(
    path: &Path,
    spp: u32,
) -> Vec<(rondo::scene::format::Method, f64, f64)> {
    use rondo::scene::format::Method;
    [Method::Naive, Method::Nee, Method::Mis]
        .into_iter()
        .map(|method| {
            let (mean, se) = point_estimate(&render(path, with(method, spp), None));
            (method, mean, se)
        })
        .collect()
}

/// The three methods' estimates agree pairwise within 3.5 combined standard errors.
pub fn assert_methods_agree(what: &str, estimates: &[(rondo::scene::format::Method, f64, f64)]) {
    for a in estimates {
        for b in estimates {
            let se = (a.2 * a.2 + b.2 * b.2).sqrt();
            assert!(
                within(a.1, se, b.1, 3.5),
                "{what}: {} {} ± {} vs {} {} ± {}",
                a.0,
                a.1,
                a.2,
                b.0,
                b.1,
                b.2
            );
        }
    }
}
