//! Image error metrics against a reference, and a false-colour picture of the error. No ECS here.
//!
//! All three metrics average over every pixel and every channel (R, G, B) of linear values:
//!
//! - RMSE: `sqrt(mean((a − r)²))`;
//! - relative MSE: `mean((a − r)² / (r² + ε))` with [`REL_EPSILON`] `ε = 0.01`, so that dark
//!   pixels neither divide by zero nor dominate (the choice of Rousselle et al., "Robust
//!   denoising using feature and color information", 2013, and of most denoising papers);
//! - mean absolute error: `mean(|a − r|)`.
//!
//! Sums are taken in `f64`, so a million pixels add up without drift.

use std::path::{Path, PathBuf};

use image::RgbImage;

use crate::film::Film;
use crate::scene::bounded_read::open_regular;
use crate::scene::format::{MAX_PIXELS, MAX_SIDE};

/// The ε added to `r²` in the denominator of the relative MSE.
pub const REL_EPSILON: f64 = 0.01;

/// A linear RGB image in memory, row-major from the top-left, three `f32` per pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `3 · width · height` channel values.
    pub data: Vec<f32>,
}

/// Error metrics of an image against a reference.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ErrorMetrics {
    /// Root mean squared error.
    pub rmse: f64,
    /// Mean of `(a − r)² / (r² + REL_EPSILON)`.
    pub rel_mse: f64,
    /// Mean absolute error.
    pub mae: f64,
}

/// What can go wrong reading, comparing or writing images.
#[derive(Debug, thiserror::Error)]
pub enum MetricsError {
    /// An image file could not be opened or decoded.
    #[error("{}: cannot read image: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: image::ImageError,
    },
    /// An image is larger than a render can be: refused from its header.
    #[error(
        "{}: the image is {}×{}; at most {MAX_SIDE} on a side and {MAX_PIXELS} pixels are accepted",
        path.display(), size.0, size.1
    )]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Its size in its header.
        size: (u32, u32),
    },
    /// The two images differ in size.
    #[error(
        "{}: image is {}×{}, but the reference {} is {}×{}",
        path.display(), size.0, size.1, reference.display(), reference_size.0, reference_size.1
    )]
    SizeMismatch {
        /// The image compared.
        path: PathBuf,
        /// Its size.
        size: (u32, u32),
        /// The reference.
        reference: PathBuf,
        /// The reference's size.
        reference_size: (u32, u32),
    },
    /// An image holds NaN or infinite values, which no metric can average.
    #[error("{}: {count} channel values are NaN or infinite", path.display())]
    NonFinite {
        /// The file.
        path: PathBuf,
        /// How many values.
        count: usize,
    },
    /// The error image could not be written.
    #[error("{}: cannot write error image: {source}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        source: image::ImageError,
    },
}

impl Image {
    /// Reads an image file (any format the build decodes: OpenEXR, PNG). EXR values are linear
    /// radiance; 8-bit formats are taken as stored values / 255, without undoing the sRGB curve.
    /// Non-finite values are an error, and so is an image larger than a render can be
    /// ([`MAX_SIDE`], [`MAX_PIXELS`]): refused from its header, before its pixels are allocated.
    pub fn read(path: &Path) -> Result<Self, MetricsError> {
        use image::ImageDecoder;
        let read_error = |source| MetricsError::Read {
            path: path.to_path_buf(),
            source,
        };
        let (file, _) = open_regular(path)
            .map_err(|e| read_error(image::ImageError::IoError(std::io::Error::other(e))))?;
        let mut reader = image::ImageReader::new(std::io::BufReader::new(file));
        if let Ok(format) = image::ImageFormat::from_path(path) {
            reader.set_format(format);
        }
        let mut reader = reader
            .with_guessed_format()
            .map_err(|e| read_error(image::ImageError::IoError(e)))?;
        let mut limits = image::Limits::default();
        // RGBA f32, the widest decoded texel.
        limits.max_alloc = Some(MAX_PIXELS * 16);
        reader.limits(limits);
        let decoder = reader.into_decoder().map_err(read_error)?;
        let (width, height) = decoder.dimensions();
        if width > MAX_SIDE
            || height > MAX_SIDE
            || u64::from(width) * u64::from(height) > MAX_PIXELS
        {
            return Err(MetricsError::TooLarge {
                path: path.to_path_buf(),
                size: (width, height),
            });
        }
        let decoded = image::DynamicImage::from_decoder(decoder).map_err(read_error)?;
        let rgb = decoded.to_rgb32f();
        let image = Self {
            width: rgb.width(),
            height: rgb.height(),
            data: rgb.into_raw(),
        };
        let count = image.data.iter().filter(|v| !v.is_finite()).count();
        if count > 0 {
            return Err(MetricsError::NonFinite {
                path: path.to_path_buf(),
                count,
            });
        }
        Ok(image)
    }

    /// The mean radiance of a film's pixels.
    pub fn from_film(film: &Film) -> Self {
        Self {
            width: film.width,
            height: film.height,
            data: film.mean().iter().flat_map(|c| c.to_array()).collect(),
        }
    }
}

/// The metrics of `a` against reference `r`; `None` if their sizes differ.
pub fn compare(a: &Image, r: &Image) -> Option<ErrorMetrics> {
    if (a.width, a.height) != (r.width, r.height) || a.data.len() != r.data.len() {
        return None;
    }
    let (mut se, mut rel, mut ae) = (0.0f64, 0.0f64, 0.0f64);
    for (&x, &y) in a.data.iter().zip(&r.data) {
        let (x, y) = (f64::from(x), f64::from(y));
        let d = x - y;
        se += d * d;
        rel += d * d / (y * y + REL_EPSILON);
        ae += d.abs();
    }
    let n = a.data.len().max(1) as f64;
    Some(ErrorMetrics {
        rmse: (se / n).sqrt(),
        rel_mse: rel / n,
        mae: ae / n,
    })
}

/// The lamp-out clamped RMSE of `a` against reference `r`, the error of the peer-renderer
/// benches (`benches/common/image_metrics.py`): pixels whose reference exceeds 1 in some channel
/// (a visible lamp and its antialiased edge) are left out, and both images are clamped to
/// [0, 1], so it judges what a display shows. `None` if the sizes differ; NaN if every pixel is
/// left out.
pub fn lamp_out_rmse(a: &Image, r: &Image) -> Option<f64> {
    if (a.width, a.height) != (r.width, r.height) || a.data.len() != r.data.len() {
        return None;
    }
    let (mut se, mut n) = (0.0f64, 0usize);
    for (x, y) in a.data.chunks_exact(3).zip(r.data.chunks_exact(3)) {
        if y.iter().any(|&c| c > 1.0) {
            continue;
        }
        for (&x, &y) in x.iter().zip(y) {
            let d = f64::from(x.clamp(0.0, 1.0)) - f64::from(y.clamp(0.0, 1.0));
            se += d * d;
        }
        n += 3;
    }
    Some((se / n as f64).sqrt())
}

/// Brightness above which a pixel is a firefly: [`FIREFLY_FACTOR`] times its reference's.
pub const FIREFLY_FACTOR: f32 = 4.0;

/// Least excess over the reference, in the channel mean, for a firefly: a dark pixel a
/// little brighter than its near-black reference is noise, not a speckle.
pub const FIREFLY_EXCESS: f32 = 0.1;

/// Fireflies of `a` against `r`: pixels whose channel mean exceeds [`FIREFLY_FACTOR`] times
/// the reference's and the reference's by more than [`FIREFLY_EXCESS`] (the bright speckles
/// rare paths leave, which the "pixels more than 4× their reference" counts). `None`
/// if the sizes differ.
pub fn fireflies(a: &Image, r: &Image) -> Option<usize> {
    if (a.width, a.height) != (r.width, r.height) || a.data.len() != r.data.len() {
        return None;
    }
    let mean = |p: &[f32]| (p[0] + p[1] + p[2]) / 3.0;
    Some(
        a.data
            .chunks_exact(3)
            .zip(r.data.chunks_exact(3))
            .filter(|(x, y)| {
                let (x, y) = (mean(x), mean(y));
                x > FIREFLY_FACTOR * y && x - y > FIREFLY_EXCESS
            })
            .count(),
    )
}

/// What [`diff_files`] found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Diff {
    /// The metrics.
    pub metrics: ErrorMetrics,
    /// Per-pixel error shown as the top colour of the error image, if one was written.
    pub error_scale: Option<f32>,
}

/// Reads `path` and `reference`, compares them, and if `error_out` is given writes the
/// false-colour error image there (see [`write_error_image`]).
pub fn diff_files(
    path: &Path,
    reference: &Path,
    error_out: Option<&Path>,
) -> Result<Diff, MetricsError> {
    let (a, r) = (Image::read(path)?, Image::read(reference)?);
    let metrics = compare(&a, &r).ok_or_else(|| MetricsError::SizeMismatch {
        path: path.to_path_buf(),
        size: (a.width, a.height),
        reference: reference.to_path_buf(),
        reference_size: (r.width, r.height),
    })?;
    let error_scale = match error_out {
        Some(out) => Some(write_error_image(&a, &r, out)?),
        None => None,
    };
    Ok(Diff {
        metrics,
        error_scale,
    })
}

/// Control points of the false-colour scale, from 0 to 1: dark blue, through teal and green, to
/// yellow (sampled from matplotlib's "viridis", which is perceptually uniform and reads in
/// grey-scale print).
const VIRIDIS: [[f32; 3]; 9] = [
    [0.267, 0.005, 0.329],
    [0.279, 0.175, 0.483],
    [0.230, 0.322, 0.546],
    [0.173, 0.449, 0.558],
    [0.128, 0.567, 0.551],
    [0.158, 0.684, 0.502],
    [0.369, 0.789, 0.383],
    [0.678, 0.864, 0.190],
    [0.993, 0.906, 0.144],
];

/// The false colour of `t` in [0, 1] (clamped), as 8-bit sRGB-encoded values.
pub fn false_colour(t: f32) -> [u8; 3] {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let x = t * (VIRIDIS.len() - 1) as f32;
    let i = (x as usize).min(VIRIDIS.len() - 2);
    let f = x - i as f32;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    std::array::from_fn(|k| ((a[k] + (b[k] - a[k]) * f) * 255.0 + 0.5) as u8)
}

/// A false-colour picture of the per-pixel absolute error `|a − r|` averaged over the channels,
/// scaled so that `scale` (and above) is the top colour. Returns the image; `None` if the sizes
/// differ.
pub fn error_image(a: &Image, r: &Image, scale: f32) -> Option<RgbImage> {
    let errors = pixel_errors(a, r)?;
    let inv = if scale > 0.0 { 1.0 / scale } else { 0.0 };
    let data = errors.iter().flat_map(|&e| false_colour(e * inv)).collect();
    RgbImage::from_raw(a.width, a.height, data)
}

/// Per-pixel absolute error averaged over channels; `None` if the sizes differ.
pub fn pixel_errors(a: &Image, r: &Image) -> Option<Vec<f32>> {
    if (a.width, a.height) != (r.width, r.height) || a.data.len() != r.data.len() {
        return None;
    }
    Some(
        a.data
            .chunks_exact(3)
            .zip(r.data.chunks_exact(3))
            .map(|(x, y)| ((x[0] - y[0]).abs() + (x[1] - y[1]).abs() + (x[2] - y[2]).abs()) / 3.0)
            .collect(),
    )
}

/// The `q`-quantile (0 ≤ q ≤ 1) of `values` (nearest rank); 0 for no values.
pub fn quantile(values: &[f32], q: f64) -> f32 {
    if values.is_empty() {
        return 0.0;
    }
    let mut sorted: Vec<f32> = values.to_vec();
    sorted.sort_by(f32::total_cmp);
    let k = ((sorted.len() - 1) as f64 * q.clamp(0.0, 1.0)).round() as usize;
    sorted[k]
}

/// Writes the false-colour error image of `a` against `r` (which must have the same size) to
/// `path`, scaled to the 99th percentile of the per-pixel error, so that a few outliers do not
/// darken the rest. Returns that scale. The format follows the extension (use `.png`).
pub fn write_error_image(a: &Image, r: &Image, path: &Path) -> Result<f32, MetricsError> {
    debug_assert_eq!((a.width, a.height), (r.width, r.height));
    let errors = pixel_errors(a, r).unwrap_or_default();
    let scale = quantile(&errors, 0.99);
    let picture = error_image(a, r, scale).unwrap_or_default();
    let fail = |source| MetricsError::Write {
        path: path.to_path_buf(),
        source,
    };
    let format = image::ImageFormat::from_path(path).map_err(fail)?;
    crate::output_file::write_atomically(path, |out| {
        picture.write_to(out, format).map_err(std::io::Error::other)
    })
    .map_err(|e| fail(image::ImageError::IoError(e)))?;
    Ok(scale)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_image_has_zero_error_against_itself() {
        let a = Image {
            width: 2,
            height: 1,
            data: vec![0.1, 2.0, 0.0, 5.0, 0.3, 0.7],
        };
        assert_eq!(compare(&a, &a), Some(ErrorMetrics::default()));
    }

    #[test]
    fn fireflies_are_pixels_far_above_their_reference() {
        // Reference 0.1 grey everywhere; pixels at 0.5 (5×, +0.4: a firefly), 0.3 (3×: not),
        // 0.41 in one channel only (mean 0.17: not), and against a black reference 0.05 (+0.05:
        // not) and 0.2 (a firefly).
        let grey = |v: f32, n: u32| Image {
            width: n,
            height: 1,
            data: vec![v; 3 * n as usize],
        };
        let r = grey(0.1, 4);
        let a = Image {
            data: vec![
                0.5, 0.5, 0.5, 0.3, 0.3, 0.3, 0.41, 0.05, 0.05, 0.1, 0.1, 0.1,
            ],
            ..r.clone()
        };
        assert_eq!(fireflies(&a, &r), Some(1));
        let black = grey(0.0, 2);
        let b = Image {
            data: vec![0.05, 0.05, 0.05, 0.2, 0.2, 0.2],
            ..black.clone()
        };
        assert_eq!(fireflies(&b, &black), Some(1));
        assert_eq!(fireflies(&a, &black), None);
    }

    #[test]
    fn false_colour_runs_from_dark_blue_to_yellow() {
        assert_eq!(false_colour(0.0), [68, 1, 84]);
        assert_eq!(false_colour(1.0), [253, 231, 37]);
        assert_eq!(false_colour(7.0), false_colour(1.0));
        assert_eq!(false_colour(f32::NAN), false_colour(0.0));
    }

    #[test]
    fn quantile_picks_by_rank() {
        let v: Vec<f32> = (0..=100).rev().map(|i| i as f32).collect();
        assert_eq!(quantile(&v, 0.99), 99.0);
        assert_eq!(quantile(&v, 0.0), 0.0);
        assert_eq!(quantile(&[], 0.5), 0.0);
    }
}
