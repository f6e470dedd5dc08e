//! Denoising with Intel Open Image Denoise (OIDN) 2.x, loaded at run time.
//!
//! rondo does not link OIDN: the default build stays pure Rust, and the denoiser is available
//! when the library is found at run time, and loads it only when a denoised image is asked
//! for. `scripts/fetch-oidn.sh` fetches Intel's prebuilt CPU libraries (from the pinned,
//! checksummed PyPI wheel `pyoidn`) into `.oidn/lib` in the repository. [`Denoiser::load`]
//! looks in the directory named by the environment variable `RONDO_OIDN_DIR` if it is set, else
//! in that `.oidn/lib` of the project rondo was built from, and nowhere else; it refuses a
//! folder or library another user could change (`location.rs`).
//!
//! The filter is OIDN's `RT` (ray-traced images) on HDR colour, optionally guided by the first
//! hit's albedo and shading normal, on the CPU device. The raw image is never changed: the
//! denoised image is a new buffer.
//!
//! On one machine the same input gives the same output bits (`tests/denoise.rs` checks it);
//! other CPUs may run other kernels (AVX2, AVX-512) and differ in the last bits.
//!
//! A film's means become the denoiser's input in `input.rs` ([`FilmImages`]); the thread that
//! denoises passes beside a watch loop is in `worker.rs` ([`DenoiseWorker`]).

mod input;
mod location;
mod oidn;
mod worker;

use std::fmt;
use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::sync::{Mutex, OnceLock};

use crate::scene::format::MAX_PIXELS;

pub use input::FilmImages;
pub use worker::{
    DenoiseJob, DenoiseSink, DenoiseWorker, Denoised, DenoisedFrame, HIGH_QUALITY_FROM_SPP,
    WorkerNews,
};

/// The environment variable naming a directory that holds `libOpenImageDenoise.so.2`.
pub const DIR_VARIABLE: &str = "RONDO_OIDN_DIR";

/// How to get the library, for error messages.
const HOW_TO_GET: &str = "run scripts/fetch-oidn.sh in the rondo repository (it fetches the \
    library into .oidn/lib), or set RONDO_OIDN_DIR to a directory holding libOpenImageDenoise.so.2";

/// OIDN's speed–quality trade-off (the filter's `quality` parameter).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Quality {
    /// The fastest, for interactive previews.
    Fast,
    /// Between the two, for interactive rendering.
    Balanced,
    /// The best, for final frames (OIDN's default).
    #[default]
    High,
}

impl Quality {
    /// Every quality, fastest first.
    pub const ALL: [Quality; 3] = [Quality::Fast, Quality::Balanced, Quality::High];

    /// The lowercase name (`fast`, `balanced`, `high`).
    pub fn name(self) -> &'static str {
        match self {
            Quality::Fast => "fast",
            Quality::Balanced => "balanced",
            Quality::High => "high",
        }
    }

    /// The value of OIDN's `OIDNQuality` enum.
    fn oidn_value(self) -> i32 {
        match self {
            Quality::Fast => 4,
            Quality::Balanced => 5,
            Quality::High => 6,
        }
    }
}

impl fmt::Display for Quality {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The images to denoise: interleaved RGB `f32`, row by row, `width * height * 3` values each.
///
/// Values are made safe for OIDN before the call, on a copy: NaN and infinities become 0 in
/// every image, colour is clamped to at least 0, albedo to [0, 1] and normals to [-1, 1] (the
/// ranges OIDN's networks were trained on; a NaN would spread over the whole image). A colour
/// far from 1 overall (a scene lit at 10⁻¹⁰ or 10³⁰) is scaled by a power of two towards 1 for
/// OIDN and the result scaled back, so the denoised image is as bright as the input at any
/// scale; a colour whose brightest value is too far above its typical one for that is refused
/// ([`DenoiseError::BadInput`]).
#[derive(Debug, Clone, Copy)]
pub struct DenoiseInput<'a> {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The (HDR, linear) colour.
    pub color: &'a [f32],
    /// The albedo of the first non-specular hit, if available.
    pub albedo: Option<&'a [f32]>,
    /// The shading normal of the first non-specular hit, in any consistent space; OIDN uses it
    /// only together with `albedo`.
    pub normal: Option<&'a [f32]>,
}

/// Why denoising failed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DenoiseError {
    /// The library was not found, could not be loaded, or its CPU device could not be created.
    /// The message says where it looked and how to get the library.
    #[error("the denoiser (Open Image Denoise) is not available: {0}")]
    Unavailable(String),
    /// OIDN reported an error while denoising.
    #[error("Open Image Denoise failed: {0}")]
    Oidn(String),
    /// The cancel flag was set while denoising.
    #[error("denoising was cancelled")]
    Cancelled,
    /// The input does not describe a valid image.
    #[error("invalid input to the denoiser: {0}")]
    BadInput(String),
}

/// A loaded OIDN library with a committed CPU device. `Send + Sync`: calls from several threads
/// run one after another (OIDN's CPU device uses all cores for one image anyway).
pub struct Denoiser {
    device: Mutex<oidn::Device>,
    location: String,
    version: i32,
}

impl fmt::Debug for Denoiser {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Denoiser")
            .field("version", &self.version())
            .field("location", &self.location)
            .finish()
    }
}

impl Denoiser {
    /// The process's denoiser, loaded by the first call (see [`Denoiser::load`]); later calls
    /// return the same denoiser, or the same error.
    pub fn shared() -> Result<&'static Denoiser, DenoiseError> {
        static SHARED: OnceLock<Result<Denoiser, DenoiseError>> = OnceLock::new();
        SHARED
            .get_or_init(Denoiser::load)
            .as_ref()
            .map_err(Clone::clone)
    }

    /// Loads the library from the folder named by `RONDO_OIDN_DIR`, or else from `.oidn/lib`
    /// in the project rondo was built from (see the module documentation), and creates its CPU
    /// device.
    pub fn load() -> Result<Denoiser, DenoiseError> {
        let variable = std::env::var_os(DIR_VARIABLE);
        Denoiser::load_from(&location::search_path(variable.as_deref()))
    }

    /// Loads the library from `dir` only, which holds `libOpenImageDenoise.so.2` (and, for the
    /// wheel's libraries, the core, the CPU device module and TBB beside it). The folder, the
    /// folders above it and the libraries must be safe from other users (see the module
    /// documentation); a refusal or a load error says which path and why (the loader's
    /// message included).
    pub fn load_from(dir: &Path) -> Result<Denoiser, DenoiseError> {
        let file = dir.join(oidn::LIBRARY_NAME);
        if !file.is_file() {
            return Err(DenoiseError::Unavailable(format!(
                "{} not found in {}; {HOW_TO_GET}",
                oidn::LIBRARY_NAME,
                dir.display()
            )));
        }
        let real = location::trusted(dir).map_err(|why| {
            DenoiseError::Unavailable(format!("{} not loaded: {why}", file.display()))
        })?;
        let location = file.display().to_string();
        match oidn::Device::new(&real) {
            Ok(device) => Ok(Denoiser {
                version: device.version(),
                device: Mutex::new(device),
                location,
            }),
            Err(e) => Err(DenoiseError::Unavailable(format!(
                "{location} could not be loaded: {e}"
            ))),
        }
    }

    /// The OIDN version, as `major.minor.patch`.
    pub fn version(&self) -> String {
        let v = self.version;
        format!("{}.{}.{}", v / 10000, v / 100 % 100, v % 100)
    }

    /// The library file loaded (or its soname, when found by the system loader).
    pub fn location(&self) -> &str {
        &self.location
    }

    /// Denoises `input` with OIDN's `RT` filter and returns the denoised colour, in the layout
    /// of `input.color`. `cancel` is polled while OIDN runs; once it is true, the call returns
    /// [`DenoiseError::Cancelled`] as soon as OIDN stops. The input is checked first
    /// ([`DenoiseError::BadInput`]) and sanitised (see [`DenoiseInput`]). Calls from several
    /// threads wait for each other.
    pub fn denoise(
        &self,
        input: &DenoiseInput,
        quality: Quality,
        cancel: &AtomicBool,
    ) -> Result<Vec<f32>, DenoiseError> {
        let (width, height) = validate(input)?;
        let mut color = sanitized(input.color, 0.0, f32::MAX);
        let exposure = exposure(&color)?;
        if exposure != 1.0 {
            scale(&mut color, exposure);
        }
        let albedo = input.albedo.map(|a| sanitized(a, 0.0, 1.0));
        let normal = input.normal.map(|n| sanitized(n, -1.0, 1.0));
        let images = oidn::Images {
            width,
            height,
            color: &color,
            albedo: albedo.as_deref(),
            normal: normal.as_deref(),
        };
        let mut device = self
            .device
            .lock()
            .map_err(|_| DenoiseError::Oidn("an earlier call panicked".into()))?;
        let mut output =
            device
                .run(&images, quality.oidn_value(), cancel)
                .map_err(|e| match e {
                    oidn::RunError::Cancelled => DenoiseError::Cancelled,
                    oidn::RunError::Oidn(message) => DenoiseError::Oidn(message),
                })?;
        if exposure != 1.0 {
            scale(&mut output, 1.0 / exposure);
        }
        Ok(output)
    }
}

/// Checks the sizes: width and height at least 1, at most [`MAX_PIXELS`] pixels, every image
/// `width * height * 3` values, normals only with albedo. Returns the width and height.
fn validate(input: &DenoiseInput) -> Result<(usize, usize), DenoiseError> {
    let bad = |m: String| Err(DenoiseError::BadInput(m));
    let (w, h) = (input.width, input.height);
    let pixels = u64::from(w) * u64::from(h);
    if pixels == 0 {
        return bad(format!("the image is empty ({w}×{h})"));
    }
    if pixels > MAX_PIXELS {
        return bad(format!(
            "{w}×{h} = {pixels} pixels is more than the {MAX_PIXELS} allowed"
        ));
    }
    let expected = pixels * 3;
    let images = [
        ("colour", Some(input.color)),
        ("albedo", input.albedo),
        ("normal", input.normal),
    ];
    for (name, image) in images {
        if let Some(image) = image
            && image.len() as u64 != expected
        {
            return bad(format!(
                "the {name} image has {} values; {w}×{h} RGB needs {expected}",
                image.len()
            ));
        }
    }
    if input.normal.is_some() && input.albedo.is_none() {
        return bad(
            "a normal image needs an albedo image too (OIDN uses normals only with \
            albedo)"
                .into(),
        );
    }
    // Both fit: pixels ≤ MAX_PIXELS < 2^32.
    Ok((w as usize, h as usize))
}

/// The typical colours (log2 of their geometric mean) OIDN is given unscaled: its own exposure
/// maps them to its networks' range. Below about 2⁻²⁷ (1e-8, the luminance its exposure ignores)
/// it sees black and returns a floor of about 1.5·10⁻⁸, 150 times the mean of an image at
/// 10⁻¹⁰; near 10³⁸ its sums overflow and it returns zeros (both measured with OIDN 2.5.1).
const TYPICAL_LOG2: std::ops::RangeInclusive<f64> = -20.0..=20.0;

/// log2 of the largest colour OIDN is given, after [`exposure`]: OIDN sums colours in `f32`
/// (over 16×16 blocks, over the image's at most 2²⁶ pixels), which stays finite below 2¹²⁸
/// when every value is at most 2¹⁰⁰.
const MAX_LOG2: i32 = 100;

/// The power of two the colour is multiplied by before OIDN (and the output divided by after):
/// 1 when the geometric mean of the pixels' positive mean channels is within [`TYPICAL_LOG2`],
/// else the one that brings it to 1, so that a scene lit at 10⁻³⁰ or at 10³⁸ denoises as at 1
/// (a power of two scales `f32`s exactly). Refuses a colour whose brightest value would then
/// be beyond 2^[`MAX_LOG2`]. `color` is sanitised (finite, at least 0).
fn exposure(color: &[f32]) -> Result<f64, DenoiseError> {
    let (mut log_sum, mut count, mut brightest) = (0.0f64, 0u64, 0.0f32);
    for pixel in color.chunks_exact(3) {
        let mean = (f64::from(pixel[0]) + f64::from(pixel[1]) + f64::from(pixel[2])) / 3.0;
        if mean > 0.0 {
            log_sum += mean.log2();
            count += 1;
        }
        brightest = brightest.max(pixel[0]).max(pixel[1]).max(pixel[2]);
    }
    let typical = if count == 0 {
        0.0
    } else {
        log_sum / count as f64
    };
    let exponent = if TYPICAL_LOG2.contains(&typical) {
        0
    } else {
        -(typical.round() as i32)
    };
    let largest = f64::from(brightest).log2() + f64::from(exponent);
    if largest > f64::from(MAX_LOG2) {
        return Err(DenoiseError::BadInput(format!(
            "the colour's brightest value, {brightest:e}, is 2^{:.0} times its typical value \
            (the geometric mean of the pixels, {:e}): beyond the range the denoiser takes",
            f64::from(brightest).log2() - typical,
            2f64.powf(typical)
        )));
    }
    Ok(2f64.powi(exponent))
}

/// Multiplies every value by `factor` (a power of two), in `f64` so that factors beyond
/// `f32`'s range work; results beyond `f32::MAX` become `f32::MAX`.
fn scale(values: &mut [f32], factor: f64) {
    for v in values {
        *v = (f64::from(*v) * factor).min(f64::from(f32::MAX)) as f32;
    }
}

/// A copy of `values` with NaN and infinities replaced by 0 and the rest clamped to [lo, hi].
fn sanitized(values: &[f32], lo: f32, hi: f32) -> Vec<f32> {
    values
        .iter()
        .map(|&v| if v.is_finite() { v.clamp(lo, hi) } else { 0.0 })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn input(width: u32, height: u32, len: usize) -> (u32, u32, Vec<f32>) {
        (width, height, vec![0.5; len])
    }

    #[test]
    fn validate_accepts_matching_sizes_and_rejects_the_rest() {
        let (w, h, good) = input(4, 3, 36);
        let short = vec![0.5; 35];
        let ok = DenoiseInput {
            width: w,
            height: h,
            color: &good,
            albedo: Some(&good),
            normal: Some(&good),
        };
        assert_eq!(validate(&ok), Ok((4, 3)));
        let cases = [
            DenoiseInput { width: 0, ..ok },
            DenoiseInput { height: 0, ..ok },
            DenoiseInput {
                color: &short,
                ..ok
            },
            DenoiseInput {
                albedo: Some(&short),
                ..ok
            },
            DenoiseInput {
                normal: Some(&short),
                ..ok
            },
            DenoiseInput { albedo: None, ..ok },
            DenoiseInput {
                width: 1 << 16,
                height: 1 << 16,
                ..ok
            },
        ];
        for case in cases {
            assert!(
                matches!(validate(&case), Err(DenoiseError::BadInput(_))),
                "{case:?}"
            );
        }
    }

    #[test]
    fn sanitized_replaces_non_finite_values_and_clamps() {
        let values = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, -0.5, 0.25, 2.0];
        assert_eq!(
            sanitized(&values, 0.0, 1.0),
            [0.0, 0.0, 0.0, 0.0, 0.25, 1.0]
        );
        assert_eq!(sanitized(&values, -1.0, 1.0)[3], -0.5);
    }

    #[test]
    fn the_denoiser_can_be_shared_between_threads() {
        fn send_sync<T: Send + Sync>() {}
        send_sync::<Denoiser>();
    }
}
