//! The film: per-pixel sums of radiance samples in exact fixed point, and the image files made
//! from them.
//!
//! Every sample is rounded once to a multiple of 2⁻³² ([`FRACTION_BITS`]) and added as an
//! integer, so a pixel's sum does not depend on the order its samples were added in: a render
//! split by sample ranges (threads, passes, processes, machines) and merged in any order gives
//! the very same sums, hence the very same image, as one process rendering every sample.

use std::path::Path;

use glam::Vec3;
use image::{ImageFormat, Rgb32FImage, RgbImage};

/// Fractional bits of the fixed-point sums: samples are rounded to multiples of 2⁻³² (2.3e-10).
pub const FRACTION_BITS: u32 = 32;

/// Largest magnitude a sample's channel may have; larger values are clamped to it. With at most
/// 2³² samples per pixel a sum then needs at most 95 bits and a sign ([`Pixel::WORDS`] words).
pub const MAX_SAMPLE: f32 = 2_147_483_520.0;

const SCALE: f64 = (1u64 << FRACTION_BITS) as f64;

/// The exact sum of a pixel's samples, per channel, in units of 2⁻[`FRACTION_BITS`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Pixel(pub [i128; 3]);

/// One channel of a sample in fixed point, rounded to nearest (ties away from zero). Exact and
/// cheap: the scaled value fits an `i64`, and the truncation remainder is computed exactly.
#[inline]
fn fixed(c: f32) -> i64 {
    let x = f64::from(c.clamp(-MAX_SAMPLE, MAX_SAMPLE)) * SCALE;
    let t = x as i64;
    let r = x - t as f64;
    if r >= 0.5 {
        t + 1
    } else if r <= -0.5 {
        t - 1
    } else {
        t
    }
}

impl Pixel {
    /// A zero sum.
    pub const ZERO: Self = Self([0; 3]);

    /// 32-bit words a channel's sum is stored in (two's complement, least significant first).
    pub const WORDS: usize = 3;

    /// The fixed-point value of one sample (`l` must be finite).
    #[inline]
    pub fn from_radiance(l: Vec3) -> Self {
        Self([
            i128::from(fixed(l.x)),
            i128::from(fixed(l.y)),
            i128::from(fixed(l.z)),
        ])
    }

    /// Adds one sample (`l` must be finite).
    #[inline]
    pub fn add(&mut self, l: Vec3) {
        self.merge(&Self::from_radiance(l));
    }

    /// Adds another sum (exact, so in any order).
    #[inline]
    pub fn merge(&mut self, other: &Self) {
        for (a, b) in self.0.iter_mut().zip(other.0) {
            *a += b;
        }
    }

    /// The mean of `count` samples whose sum this is (zero for no samples).
    #[inline]
    pub fn mean(&self, count: u64) -> Vec3 {
        let scale = 1.0 / (SCALE * count.max(1) as f64);
        Vec3::new(
            (self.0[0] as f64 * scale) as f32,
            (self.0[1] as f64 * scale) as f32,
            (self.0[2] as f64 * scale) as f32,
        )
    }

    /// Channel `c`'s sum as [`Pixel::WORDS`] 32-bit words, least significant first.
    #[inline]
    pub fn words(&self, c: usize) -> [u32; Self::WORDS] {
        let v = self.0[c];
        [v as u32, (v >> 32) as u32, (v >> 64) as u32]
    }

    /// Channel `c`'s sum from its words (the inverse of [`Pixel::words`]).
    #[inline]
    pub fn set_words(&mut self, c: usize, w: [u32; Self::WORDS]) {
        let raw = u128::from(w[0]) | (u128::from(w[1]) << 32) | (u128::from(w[2]) << 64);
        // Sign-extend from 96 bits.
        self.0[c] = ((raw << 32) as i128) >> 32;
    }
}

/// The sRGB opto-electronic transfer function: linear in `[0, 1]` → encoded.
#[inline]
pub fn linear_to_srgb(c: f32) -> f32 {
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// Output file kinds, chosen by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputKind {
    /// 8-bit sRGB PNG (clamped).
    Png,
    /// Linear 32-bit float OpenEXR (unclamped).
    Exr,
}

impl OutputKind {
    /// The kind for a path's extension (`.png` or `.exr`, any case).
    pub fn from_path(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "png" => Some(Self::Png),
            "exr" => Some(Self::Exr),
            _ => None,
        }
    }
}

/// Accumulated radiance per pixel, row-major from the top-left: the sums of samples
/// `start..samples` of every pixel.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Film {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Exact sum of the samples of each pixel.
    pub sum: Vec<Pixel>,
    /// One past the last sample index accumulated (the samples per pixel, for `start` 0).
    pub samples: u32,
    /// First sample index accumulated (0 but for a render of a sample range).
    pub start: u32,
}

impl Film {
    /// An empty film.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            sum: vec![Pixel::ZERO; width as usize * height as usize],
            samples: 0,
            start: 0,
        }
    }

    /// Clears the sums, keeping the size; the film then starts at sample `start`.
    pub fn clear(&mut self, start: u32) {
        self.sum.fill(Pixel::ZERO);
        self.start = start;
        self.samples = start;
    }

    /// Samples per pixel held.
    pub fn count(&self) -> u64 {
        u64::from(self.samples.saturating_sub(self.start))
    }

    /// The mean radiance of every pixel.
    pub fn mean(&self) -> Vec<Vec3> {
        let n = self.count();
        self.sum.iter().map(|s| s.mean(n)).collect()
    }

    /// 8-bit sRGB image of the clamped mean.
    pub fn to_srgb8(&self) -> RgbImage {
        srgb8(self.width, self.height, &self.sum, self.count())
    }

    /// Linear float image of the mean, unclamped.
    pub fn to_linear(&self) -> Rgb32FImage {
        let n = self.count();
        let data = self.sum.iter().flat_map(|s| s.mean(n).to_array()).collect();
        Rgb32FImage::from_raw(self.width, self.height, data).expect("film size matches its pixels")
    }

    /// Writes the image atomically (see [`write_atomically`]); the mean of each pixel is made
    /// as it is encoded, never kept as a second full-size image.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        encode_image(path, self.width, self.height, &self.sum, self.count(), true)
    }

    /// As [`Film::write`], but without waiting for the data to reach the disk (no fsync): for
    /// live images replaced within moments, where the fsync (5–20 ms on ext4 here) would delay
    /// the first image of an edit. Readers still never see a half-written file.
    pub fn write_live(&self, path: &Path) -> std::io::Result<()> {
        encode_image(
            path,
            self.width,
            self.height,
            &self.sum,
            self.count(),
            false,
        )
    }
}

/// 8-bit sRGB image of the clamped means of `sum` (`count` samples per pixel).
pub fn srgb8(width: u32, height: u32, sum: &[Pixel], count: u64) -> RgbImage {
    let data = sum
        .iter()
        .flat_map(|s| s.mean(count).to_array())
        .map(|c| (linear_to_srgb(c.clamp(0.0, 1.0)) * 255.0 + 0.5) as u8)
        .collect();
    RgbImage::from_raw(width, height, data).expect("film size matches its pixels")
}

/// Writes the means of `sum` (`count` samples per pixel) as a `.png` (8-bit sRGB, clamped) or
/// `.exr` (linear f32 R, G, B) image, chosen by `path`'s extension, atomically.
pub fn write_image(
    path: &Path,
    width: u32,
    height: u32,
    sum: &[Pixel],
    count: u64,
) -> std::io::Result<()> {
    encode_image(path, width, height, sum, count, true)
}

fn encode_image(
    path: &Path,
    width: u32,
    height: u32,
    sum: &[Pixel],
    count: u64,
    sync: bool,
) -> std::io::Result<()> {
    let kind = OutputKind::from_path(path).ok_or_else(|| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("{}: output must end in .png or .exr", path.display()),
        )
    })?;
    crate::output_file::write_file(path, sync, |out| match kind {
        OutputKind::Png => srgb8(width, height, sum, count)
            .write_to(out, ImageFormat::Png)
            .map_err(std::io::Error::other),
        OutputKind::Exr => {
            use exr::prelude::*;
            let w = width as usize;
            let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
                let m = sum[p.y() * w + p.x()].mean(count);
                (m.x, m.y, m.z)
            });
            Image::from_channels((w, height as usize), channels)
                .write()
                .to_buffered(out)
                .map_err(std::io::Error::other)
        }
    })
}

/// Writes a file atomically (moved to [`crate::output_file`]; kept here for its callers).
pub use crate::output_file::write_atomically;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_encoding_matches_the_standard() {
        assert_eq!(linear_to_srgb(0.0), 0.0);
        assert!((linear_to_srgb(1.0) - 1.0).abs() < 1e-6);
        assert!((linear_to_srgb(0.214_04) - 0.5).abs() < 1e-4);
    }

    #[test]
    fn png_clamps_and_exr_keeps_linear_values() {
        let mut film = Film::new(2, 1);
        film.sum[0].add(Vec3::new(4.0, 0.5, -1.0));
        film.sum[1].add(Vec3::new(0.0, 2.0, 0.0));
        film.samples = 2;
        let png = film.to_srgb8();
        // Mean (2, 0.25, −0.5) clamps to (1, 0.25, 0); 0.25 linear is 0.5371 in sRGB → 137.
        assert_eq!(png.get_pixel(0, 0).0, [255, 137, 0]);
        let exr = film.to_linear();
        assert_eq!(exr.get_pixel(0, 0).0, [2.0, 0.25, -0.5]);
    }

    #[test]
    fn fixed_point_rounds_to_nearest_and_sums_in_any_order() {
        let unit = (1.0 / SCALE) as f32;
        assert_eq!(fixed(1.0), 1 << 32);
        assert_eq!(fixed(-0.25), -(1 << 30));
        assert_eq!(fixed(unit * 0.49), 0);
        assert_eq!(fixed(unit * 0.5), 1);
        assert_eq!(fixed(-unit * 0.5), -1);
        assert_eq!(fixed(f32::MAX), fixed(MAX_SAMPLE));
        assert!(fixed(MAX_SAMPLE) < i64::MAX);
        // Values that do not add associatively in floating point.
        let samples = [1e8f32, 1e-3, -1e8, 3.7e-5, 0.1, 12345.678];
        let mut forward = Pixel::ZERO;
        samples.iter().for_each(|&s| forward.add(Vec3::splat(s)));
        let mut backward = Pixel::ZERO;
        samples
            .iter()
            .rev()
            .for_each(|&s| backward.add(Vec3::splat(s)));
        assert_eq!(forward, backward);
        let f: f32 = samples.iter().sum();
        let b: f32 = samples.iter().rev().sum();
        assert_ne!(f, b, "the samples must not be associative in f32");
    }

    #[test]
    fn words_round_trip_negative_and_large_sums() {
        for v in [
            0i128,
            1,
            -1,
            i128::from(i64::MAX) * 3,
            -(1i128 << 94),
            (1 << 94) - 1,
        ] {
            let p = Pixel([v, -v, v / 7]);
            let mut q = Pixel::ZERO;
            for c in 0..3 {
                q.set_words(c, p.words(c));
            }
            assert_eq!(p, q);
        }
    }
}
