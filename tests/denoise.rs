//! The denoiser (src/denoise/): Open Image Denoise loaded at run time.
//!
//! The tests that need the library find it the way rondo does (`RONDO_OIDN_DIR`, else
//! `.oidn/lib` in the repository, where scripts/fetch-oidn.sh puts it); without it they
//! print why and pass, unless `RONDO_REQUIRE_OIDN=1` (as in CI, after scripts/fetch-oidn.sh),
//! when they fail.

mod common;

use std::path::Path;
use std::process::Command;
use std::sync::atomic::AtomicBool;

use common::denoiser;
use rondo::denoise::{DenoiseError, DenoiseInput, Denoiser, Quality};

const WIDTH: u32 = 128;
const HEIGHT: u32 = 128;
/// Side of the albedo's constant blocks, in pixels.
const BLOCK: u32 = 16;

/// A small deterministic generator (SplitMix64), uniform in [0, 1).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        (z >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// A synthetic scene: smooth illumination times a piecewise-constant albedo (blocks of four
/// colours with sharp edges), a constant normal, and the clean colour with seeded Monte Carlo
/// like noise (each pixel scaled by a random factor of mean 1 and standard deviation 0.29).
struct Scene {
    clean: Vec<f32>,
    noisy: Vec<f32>,
    albedo: Vec<f32>,
    normal: Vec<f32>,
}

fn albedo_at(x: u32, y: u32) -> [f32; 3] {
    const COLOURS: [[f32; 3]; 4] = [
        [0.8, 0.2, 0.2],
        [0.2, 0.7, 0.3],
        [0.25, 0.3, 0.9],
        [0.9, 0.9, 0.85],
    ];
    COLOURS[((x / BLOCK + 2 * (y / BLOCK) + y / (2 * BLOCK)) % 4) as usize]
}

fn scene() -> Scene {
    let mut rng = Rng(21);
    let n = (WIDTH * HEIGHT * 3) as usize;
    let (mut clean, mut noisy, mut albedo) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let normal = [0.0, 0.0, 1.0].repeat((WIDTH * HEIGHT) as usize);
    for y in 0..HEIGHT {
        for x in 0..WIDTH {
            let (u, v) = (x as f32 / WIDTH as f32, y as f32 / HEIGHT as f32);
            let light = 0.6
                + 0.4 * (std::f32::consts::TAU * 0.7 * u).sin() * (std::f32::consts::PI * v).cos();
            let factor = (rng.next() + rng.next() + rng.next() + rng.next()) / 2.0;
            let a = albedo_at(x, y);
            let i = ((y * WIDTH + x) * 3) as usize;
            for c in 0..3 {
                albedo[i + c] = a[c];
                clean[i + c] = a[c] * light;
                noisy[i + c] = a[c] * light * factor;
            }
        }
    }
    Scene {
        clean,
        noisy,
        albedo,
        normal,
    }
}

impl Scene {
    fn input<'a>(&'a self, color: &'a [f32]) -> DenoiseInput<'a> {
        DenoiseInput {
            width: WIDTH,
            height: HEIGHT,
            color,
            albedo: Some(&self.albedo),
            normal: Some(&self.normal),
        }
    }
}

/// Root-mean-square difference of `a` and `b` over the pixels `keep` selects.
fn rmse(a: &[f32], b: &[f32], keep: impl Fn(u32, u32) -> bool) -> f64 {
    let (mut sum, mut count) = (0.0f64, 0usize);
    for y in 0..HEIGHT {
        for x in 0..WIDTH {
            if keep(x, y) {
                let i = ((y * WIDTH + x) * 3) as usize;
                for c in i..i + 3 {
                    sum += f64::from(a[c] - b[c]).powi(2);
                    count += 1;
                }
            }
        }
    }
    (sum / count as f64).sqrt()
}

/// Whether (x, y) is next to an albedo edge: one of its 4 neighbours has another albedo.
fn at_edge(x: u32, y: u32) -> bool {
    let a = albedo_at(x, y);
    [(1, 0), (-1, 0), (0, 1), (0, -1)].iter().any(|&(dx, dy)| {
        let (nx, ny) = (x as i64 + dx, y as i64 + dy);
        (0..WIDTH as i64).contains(&nx)
            && (0..HEIGHT as i64).contains(&ny)
            && albedo_at(nx as u32, ny as u32) != a
    })
}

/// A 5×5 box blur: a denoiser that does not keep edges, to show that the edge check tells.
fn box_blur(image: &[f32]) -> Vec<f32> {
    let mut out = vec![0.0; image.len()];
    for y in 0..HEIGHT as i64 {
        for x in 0..WIDTH as i64 {
            let mut sum = [0.0f32; 3];
            let mut count = 0.0;
            for (nx, ny) in (-2..=2).flat_map(|dy| (-2..=2).map(move |dx| (x + dx, y + dy))) {
                if (0..WIDTH as i64).contains(&nx) && (0..HEIGHT as i64).contains(&ny) {
                    let i = ((ny * WIDTH as i64 + nx) * 3) as usize;
                    for c in 0..3 {
                        sum[c] += image[i + c];
                    }
                    count += 1.0;
                }
            }
            let i = ((y * WIDTH as i64 + x) * 3) as usize;
            for c in 0..3 {
                out[i + c] = sum[c] / count;
            }
        }
    }
    out
}

#[test]
fn denoising_lowers_the_error_at_least_threefold_and_keeps_albedo_edges_sharp() {
    let Some(denoiser) = denoiser() else { return };
    let s = scene();
    let not_cancelled = AtomicBool::new(false);
    let all = |_, _| true;
    let noisy_error = rmse(&s.noisy, &s.clean, all);
    let noisy_edge_error = rmse(&s.noisy, &s.clean, at_edge);
    for quality in Quality::ALL {
        let denoised = denoiser
            .denoise(&s.input(&s.noisy), quality, &not_cancelled)
            .unwrap_or_else(|e| panic!("{quality}: {e}"));
        let error = rmse(&denoised, &s.clean, all);
        let edge_error = rmse(&denoised, &s.clean, at_edge);
        eprintln!(
            "{quality}: RMSE {noisy_error:.4} → {error:.4}, at edges {noisy_edge_error:.4} → \
             {edge_error:.4}"
        );
        assert!(
            error * 3.0 <= noisy_error,
            "{quality}: {error} vs {noisy_error}"
        );
        assert!(
            edge_error * 2.0 <= noisy_edge_error,
            "{quality}: edges blurred: {edge_error} vs {noisy_edge_error}"
        );
    }
    // The edge check tells a filter that blurs edges: a 5×5 box blur lowers the error overall,
    // but not at the edges (there it is worse than the noise).
    let blurred = box_blur(&s.noisy);
    assert!(rmse(&blurred, &s.clean, all) < noisy_error);
    assert!(rmse(&blurred, &s.clean, at_edge) * 2.0 > noisy_edge_error);
}

#[test]
fn a_clean_image_changes_by_less_than_one_percent() {
    let Some(denoiser) = denoiser() else { return };
    let s = scene();
    let denoised = denoiser
        .denoise(&s.input(&s.clean), Quality::High, &AtomicBool::new(false))
        .expect("denoise");
    let energy = rmse(&s.clean, &vec![0.0; s.clean.len()], |_, _| true).powi(2);
    let relative_mse = rmse(&denoised, &s.clean, |_, _| true).powi(2) / energy;
    eprintln!("relative MSE of the clean image: {relative_mse:.2e}");
    assert!(relative_mse < 0.01, "{relative_mse}");
}

#[test]
fn the_same_input_gives_the_same_output_bits() {
    let Some(denoiser) = denoiser() else { return };
    let s = scene();
    let flag = AtomicBool::new(false);
    for quality in Quality::ALL {
        let run = || -> Vec<u32> {
            let out = denoiser
                .denoise(&s.input(&s.noisy), quality, &flag)
                .expect("denoise");
            out.iter().map(|v| v.to_bits()).collect()
        };
        assert!(run() == run(), "{quality}: two runs differ");
    }
}

#[test]
fn colour_alone_and_colour_with_albedo_are_denoised_too() {
    let Some(denoiser) = denoiser() else { return };
    let s = scene();
    let flag = AtomicBool::new(false);
    let noisy_error = rmse(&s.noisy, &s.clean, |_, _| true);
    for (albedo, normal) in [(None, None), (Some(&s.albedo[..]), None)] {
        let input = DenoiseInput {
            albedo,
            normal,
            ..s.input(&s.noisy)
        };
        let denoised = denoiser
            .denoise(&input, Quality::High, &flag)
            .expect("denoise");
        assert!(rmse(&denoised, &s.clean, |_, _| true) * 2.0 < noisy_error);
    }
}

#[test]
fn non_finite_input_values_do_not_spread() {
    let Some(denoiser) = denoiser() else { return };
    let s = scene();
    let mut color = s.noisy.clone();
    color[3 * 500] = f32::NAN;
    color[3 * 900 + 1] = f32::INFINITY;
    let mut albedo = s.albedo.clone();
    albedo[3 * 700] = f32::NAN;
    let input = DenoiseInput {
        albedo: Some(&albedo),
        ..s.input(&color)
    };
    let denoised = denoiser
        .denoise(&input, Quality::Fast, &AtomicBool::new(false))
        .expect("denoise");
    assert!(denoised.iter().all(|v| v.is_finite()));
    assert!(rmse(&denoised, &s.clean, |_, _| true) * 3.0 < rmse(&s.noisy, &s.clean, |_, _| true));
}

#[test]
fn a_set_cancel_flag_cancels_and_the_denoiser_works_afterwards() {
    let Some(denoiser) = denoiser() else { return };
    let s = scene();
    let result = denoiser.denoise(&s.input(&s.noisy), Quality::High, &AtomicBool::new(true));
    assert!(
        matches!(result, Err(DenoiseError::Cancelled)),
        "{:?}",
        result.map(|d| format!("{} values", d.len()))
    );
    let again = denoiser.denoise(&s.input(&s.noisy), Quality::High, &AtomicBool::new(false));
    assert!(again.is_ok_and(|d| d.len() == s.noisy.len()));
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let Some(denoiser) = denoiser() else { return };
    let s = scene();
    let flag = AtomicBool::new(false);
    let good = s.input(&s.noisy);
    let short = &s.noisy[..s.noisy.len() - 3];
    let cases = [
        DenoiseInput { width: 0, ..good },
        DenoiseInput { height: 0, ..good },
        DenoiseInput {
            width: 0,
            height: 0,
            color: &[],
            albedo: None,
            normal: None,
        },
        DenoiseInput {
            color: short,
            ..good
        },
        DenoiseInput {
            albedo: Some(short),
            ..good
        },
        DenoiseInput {
            normal: Some(short),
            ..good
        },
        DenoiseInput {
            albedo: None,
            ..good
        },
        DenoiseInput {
            width: WIDTH + 1,
            ..good
        },
        DenoiseInput {
            width: u32::MAX,
            height: u32::MAX,
            ..good
        },
    ];
    for case in cases {
        let result = denoiser.denoise(&case, Quality::Fast, &flag);
        assert!(
            matches!(result, Err(DenoiseError::BadInput(_))),
            "{}×{}: {result:?}",
            case.width,
            case.height
        );
    }
}

#[test]
fn a_directory_without_the_library_is_unavailable_and_says_how_to_get_it() {
    let dir = common::temp_dir("oidn-empty");
    let err = Denoiser::load_from(&dir).expect_err("an empty directory has no library");
    let DenoiseError::Unavailable(message) = &err else {
        panic!("{err:?}")
    };
    assert!(message.contains(&*dir.to_string_lossy()), "{message}");
    assert!(message.contains("scripts/fetch-oidn.sh"), "{message}");
    assert!(message.contains("RONDO_OIDN_DIR"), "{message}");
}

#[test]
fn a_file_that_is_not_a_library_is_unavailable_with_the_loader_error() {
    let dir = common::temp_dir("oidn-bogus");
    std::fs::write(dir.join("libOpenImageDenoise.so.2"), "not a library").expect("write");
    let err = Denoiser::load_from(&dir).expect_err("not a library");
    let DenoiseError::Unavailable(message) = &err else {
        panic!("{err:?}")
    };
    assert!(
        message.contains("libOpenImageDenoise.so.2 could not be loaded"),
        "{message}"
    );
    // The loader's own reason (dlerror), which glibc gives for a file shorter than an ELF
    // header.
    assert!(message.contains("file too short"), "{message}");
}

/// A folder others can write, or one of its libraries, is refused before anything is loaded:
/// the refusal names the path and the reason, not a loader error.
#[test]
fn a_folder_or_library_others_can_write_is_refused() {
    use std::os::unix::fs::PermissionsExt;
    let set_mode = |path: &Path, mode: u32| {
        std::fs::set_permissions(path, std::fs::Permissions::from_mode(mode)).expect("chmod");
    };
    let refused = |dir: &Path, path: &Path, why: &str| {
        let err = Denoiser::load_from(dir).expect_err("refused");
        let message = err.to_string();
        assert!(
            message.contains(&format!("{}: refused: {why}", path.display())),
            "{message}"
        );
        assert!(!message.contains("could not be loaded"), "{message}");
    };
    let dir = common::temp_dir("oidn-writable");
    let lib = dir.join("libOpenImageDenoise.so.2");
    std::fs::write(&lib, "not a library").expect("write");
    let dir = dir.canonicalize().expect("canonical");
    let lib = dir.join("libOpenImageDenoise.so.2");
    set_mode(&lib, 0o755);
    for mode in [0o777, 0o775, 0o1777] {
        set_mode(&dir, mode);
        refused(&dir, &dir, "writable by others");
    }
    set_mode(&dir, 0o755);
    for mode in [0o757, 0o775] {
        set_mode(&lib, mode);
        refused(&dir, &lib, "writable by others");
    }
    // A library of the folder that OIDN loads itself (its CPU device) is checked too.
    set_mode(&lib, 0o755);
    let device = dir.join("libOpenImageDenoise_device_cpu.so.2.5.1");
    std::fs::write(&device, "not a library").expect("write");
    set_mode(&device, 0o777);
    refused(&dir, &device, "writable by others");
    set_mode(&device, 0o755);
    // Owned by another user (only root can make such a file here).
    if runs_as_root() {
        std::os::unix::fs::chown(&device, Some(65534), None).expect("chown");
        refused(&dir, &device, "owned by user 65534");
        std::os::unix::fs::chown(&device, Some(0), None).expect("chown");
    } else {
        eprintln!("skipped the owner check: only root can give a file to another user");
    }
    // A folder above the library's that others can write lets them swap it: refused, unless
    // it has the sticky bit (as the system's temporary folder).
    let parent = common::temp_dir("oidn-writable-parent");
    let inner = parent.join("lib");
    std::fs::create_dir(&inner).expect("mkdir");
    std::fs::write(inner.join("libOpenImageDenoise.so.2"), "not a library").expect("write");
    let parent_real = parent.canonicalize().expect("canonical");
    set_mode(&parent_real, 0o777);
    refused(&inner, &parent_real, "writable by others");
    set_mode(&parent_real, 0o1777);
    let err = Denoiser::load_from(&inner).expect_err("not a library");
    assert!(err.to_string().contains("could not be loaded"), "{err}");
    set_mode(&parent_real, 0o700);
}

/// Whether this process runs as root (the owner of a file this process creates).
fn runs_as_root() -> bool {
    use std::os::unix::fs::MetadataExt;
    let dir = common::temp_dir("oidn-whoami");
    std::fs::metadata(dir.path()).is_ok_and(|m| m.uid() == 0)
}

/// A rondo binary placed below the system's temporary folder, beside a planted
/// `.oidn/lib/libOpenImageDenoise.so.2` in a folder above it, does not look there: a denoised
/// render uses the project's library (or says where it looked), never the planted one.
#[test]
fn a_library_planted_above_the_executable_is_not_searched() {
    let root = common::temp_dir("oidn-planted");
    let planted = root.join(".oidn").join("lib");
    std::fs::create_dir_all(&planted).expect("mkdir");
    std::fs::write(planted.join("libOpenImageDenoise.so.2"), "planted").expect("write");
    let bin = root.join("bin");
    std::fs::create_dir(&bin).expect("mkdir");
    let rondo = bin.join("rondo");
    std::fs::copy(env!("CARGO_BIN_EXE_rondo"), &rondo).expect("copy rondo");
    let scene = common::scenes_dir().join("cornell.ron");
    let out = root.join("out.png");
    let ran = Command::new(&rondo)
        .arg("render")
        .arg(&scene)
        .arg("-o")
        .arg(&out)
        .args(["--spp", "1", "--width", "8", "--height", "8", "--denoise"])
        .env_remove("RONDO_OIDN_DIR")
        .output()
        .expect("run rondo");
    let stderr = String::from_utf8_lossy(&ran.stderr);
    assert!(!stderr.contains(&*root.to_string_lossy()), "{stderr}");
    if denoiser().is_some() {
        assert!(ran.status.success(), "{stderr}");
    } else {
        let fetched = Path::new(env!("CARGO_MANIFEST_DIR")).join(".oidn/lib");
        assert!(stderr.contains(&*fetched.to_string_lossy()), "{stderr}");
    }
}

/// Loads the denoiser as rondo does and denoises a small image with it; prints the outcome for
/// the parent test. Run only in a child process, with `RONDO_OIDN_DIR` set, by the tests below.
#[test]
#[ignore = "run in a child process by the RONDO_OIDN_DIR tests"]
fn child_loads_and_denoises() {
    match Denoiser::load() {
        Ok(denoiser) => {
            let color = vec![0.5; 16 * 16 * 3];
            let input = DenoiseInput {
                width: 16,
                height: 16,
                color: &color,
                albedo: None,
                normal: None,
            };
            let result = denoiser.denoise(&input, Quality::Fast, &AtomicBool::new(false));
            let values = result.map(|d| d.len());
            println!("child: loaded {}: {values:?}", denoiser.location());
        }
        Err(e) => println!("child: {e}"),
    }
}

/// Runs [`child_loads_and_denoises`] in a child process with `RONDO_OIDN_DIR=dir`; returns
/// its output.
fn child_with_variable(dir: &Path) -> String {
    let output = Command::new(std::env::current_exe().expect("test binary"))
        .args([
            "child_loads_and_denoises",
            "--exact",
            "--ignored",
            "--nocapture",
        ])
        .env("RONDO_OIDN_DIR", dir)
        .output()
        .expect("run the test binary");
    assert!(output.status.success(), "{output:?}");
    String::from_utf8_lossy(&output.stdout).into_owned()
}

#[test]
fn the_variable_is_the_only_place_looked_when_set() {
    let dir = common::temp_dir("oidn-variable-empty");
    let output = child_with_variable(&dir);
    assert!(
        output.contains(&format!("child: the denoiser (Open Image Denoise) is not available: libOpenImageDenoise.so.2 not found in {}; ", dir.display())),
        "{output}"
    );
}

/// The libraries in a directory not named `lib` (here: symbolic links to them), where their
/// `RPATH $ORIGIN/../lib` finds nothing: they load because TBB and the core are loaded first
/// by full path.
#[test]
fn the_variable_names_any_directory_holding_the_libraries() {
    let Some(denoiser) = denoiser() else { return };
    let Some(found) = Path::new(denoiser.location()).parent() else {
        eprintln!("skipped: loaded by the system loader, from an unknown directory");
        return;
    };
    let dir = common::temp_dir("oidn-variable-links");
    let links = dir.join("oidn-elsewhere");
    std::fs::create_dir(&links).expect("create dir");
    for entry in std::fs::read_dir(found).expect("read the library directory") {
        let path = entry.expect("directory entry").path();
        let name = path.file_name().expect("file name");
        std::os::unix::fs::symlink(&path, links.join(name)).expect("symlink");
    }
    let output = child_with_variable(&links);
    let expected = format!(
        "child: loaded {}: Ok(768)",
        links.join("libOpenImageDenoise.so.2").display()
    );
    assert!(output.contains(&expected), "{output}");
}
