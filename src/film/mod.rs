//! The film: per-pixel sums of radiance samples in exact fixed point (`fixed.rs`), and the image
//! files made from them (`output.rs`, the one sink every image and layer is written through).
//!
//! Every sample is scaled by a power of two chosen for the scene ([`shift_for`]), rounded once to
//! an integer and added as one, so a pixel's sum does not depend on the order its samples were
//! added in: a render split by sample ranges (threads, passes, processes, machines) and merged in
//! any order gives the very same sums, hence the very same image, as one process rendering every
//! sample. The power of two (the film's `shift`) follows the scene's brightest radiance, so a
//! scene lit at 10⁻¹⁰ keeps its precision and one lit at 10⁹ its range; samples that still fall
//! outside are clamped and counted, never lost silently.

use std::path::Path;

use glam::Vec3;
use image::{Rgb32FImage, RgbImage};

mod fixed;
mod output;

pub use fixed::*;
pub use output::*;

/// The feature buffers (AOVs) a denoiser is guided by: per pixel, the exact sums of each
/// sample's albedo and shading normal at the first hit that is not a perfect mirror or glass
/// (see [`crate::render::trace_path`]). Summed like the colour, so they split, merge and resume
/// bit-exactly too. Each has a fixed point of its own, independent of the colour's: the normal
/// [`NORMAL_SHIFT`]'s, the albedo `albedo_shift`'s ([`ALBEDO_SHIFT`], but in a partial written
/// while the albedo took the colour's shift, see `docs/partial-format.md`).
#[derive(Clone, Debug, PartialEq)]
pub struct Features {
    /// Sums of the albedo samples, in units of 2⁻`albedo_shift`.
    pub albedo: Vec<Pixel>,
    /// Sums of the normal samples, in units of 2⁻[`NORMAL_SHIFT`].
    pub normal: Vec<Pixel>,
    /// The fixed-point shift of the albedo sums.
    pub albedo_shift: i32,
}

impl Default for Features {
    fn default() -> Self {
        Self::new(0)
    }
}

impl Features {
    /// Zero sums for `pixels` pixels, the albedo in [`ALBEDO_SHIFT`]'s fixed point.
    pub fn new(pixels: usize) -> Self {
        Self::with_albedo_shift(pixels, ALBEDO_SHIFT)
    }

    /// Zero sums for `pixels` pixels, the albedo in units of 2⁻`albedo_shift` (to read a
    /// partial whose albedo is in other units than [`ALBEDO_SHIFT`]'s).
    pub fn with_albedo_shift(pixels: usize, albedo_shift: i32) -> Self {
        Self {
            albedo: vec![Pixel::ZERO; pixels],
            normal: vec![Pixel::ZERO; pixels],
            albedo_shift,
        }
    }

    /// The fixed point the albedo is summed in.
    pub fn albedo_fixed(&self) -> FixedPoint {
        FixedPoint::new(self.albedo_shift)
    }

    /// Adds another film's feature sums (exact, so in any order), which must be in the same
    /// fixed point (callers check partials' `albedo_shift` before they merge). `None`, with
    /// `self` partly added to, if a sum leaves its words ([`Pixel::checked_merge`]).
    pub fn checked_merge(&mut self, other: &Self) -> Option<()> {
        debug_assert_eq!(self.albedo_shift, other.albedo_shift);
        let pairs = self.albedo.iter_mut().zip(&other.albedo);
        for (a, b) in pairs.chain(self.normal.iter_mut().zip(&other.normal)) {
            *a = a.checked_merge(b)?;
        }
        Some(())
    }

    /// The mean albedo of every pixel (`count` samples).
    pub fn albedo_mean(&self, count: u64) -> Vec<Vec3> {
        let fixed = self.albedo_fixed();
        self.albedo.iter().map(|s| fixed.mean(s, count)).collect()
    }

    /// The mean normal of every pixel (`count` samples): not renormalised, so shorter where a
    /// pixel's samples see surfaces facing different ways, and zero where they see the sky.
    pub fn normal_mean(&self, count: u64) -> Vec<Vec3> {
        self.normal
            .iter()
            .map(|s| NORMAL_FIXED.mean(s, count))
            .collect()
    }
}

/// One sample's feature values (see [`Features`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FeatureSample {
    /// Albedo (reflectance, or emitted radiance of an emitter).
    pub albedo: Vec3,
    /// Unit shading normal on the side the path arrived from; zero for the sky.
    pub normal: Vec3,
}

/// A band of rows of a film, for one worker: its colour sums and, if the film has them, its
/// feature sums.
pub struct FilmBand<'a> {
    /// Colour sums.
    pub sum: &'a mut [Pixel],
    /// Albedo and normal sums.
    pub features: Option<(&'a mut [Pixel], &'a mut [Pixel])>,
    /// The fixed point of the albedo sums ([`Features::albedo_fixed`]).
    albedo_fixed: FixedPoint,
}

impl FilmBand<'_> {
    /// Adds one sample to pixel `i` of the band: its radiance `l` in `fixed` point and its
    /// features (if the band has them and they are finite) in theirs. Returns `None` if `l` is not finite
    /// (the radiance is then dropped), else whether any value was clamped.
    #[inline]
    pub fn add(
        &mut self,
        i: usize,
        l: Vec3,
        features: &FeatureSample,
        fixed: FixedPoint,
    ) -> Option<bool> {
        let mut clamped = false;
        if let Some((albedo, normal)) = &mut self.features
            && features.albedo.is_finite()
            && features.normal.is_finite()
        {
            clamped |= albedo[i].add(features.albedo, self.albedo_fixed);
            clamped |= normal[i].add(features.normal, NORMAL_FIXED);
        }
        if !l.is_finite() {
            return None;
        }
        Some(self.sum[i].add(l, fixed) | clamped)
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
    /// Samples are rounded to multiples of 2⁻shift ([`shift_for`] of the scene).
    pub shift: i32,
    /// The feature buffers, if the film collects them ([`Film::with_features`]).
    pub features: Option<Features>,
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
            shift: DEFAULT_SHIFT,
            features: None,
        }
    }

    /// An empty film that also collects the feature buffers ([`Features`]).
    pub fn with_features(width: u32, height: u32) -> Self {
        let mut film = Self::new(width, height);
        film.features = Some(Features::new(film.sum.len()));
        film
    }

    /// The film's pixels in bands of `rows` rows, for the workers of a pass.
    pub fn bands(&mut self, rows: usize) -> Vec<FilmBand<'_>> {
        let n = (self.width as usize * rows).max(1);
        match &mut self.features {
            Some(f) => {
                let albedo_fixed = f.albedo_fixed();
                self.sum
                    .chunks_mut(n)
                    .zip(f.albedo.chunks_mut(n).zip(f.normal.chunks_mut(n)))
                    .map(|(sum, (a, b))| FilmBand {
                        sum,
                        features: Some((a, b)),
                        albedo_fixed,
                    })
                    .collect()
            }
            None => self
                .sum
                .chunks_mut(n)
                .map(|sum| FilmBand {
                    sum,
                    features: None,
                    albedo_fixed: FixedPoint::new(ALBEDO_SHIFT),
                })
                .collect(),
        }
    }

    /// Clears the sums, keeping the size and the shift; the film then starts at sample `start`.
    pub fn clear(&mut self, start: u32) {
        self.sum.fill(Pixel::ZERO);
        if let Some(f) = &mut self.features {
            f.albedo.fill(Pixel::ZERO);
            f.normal.fill(Pixel::ZERO);
        }
        self.start = start;
        self.samples = start;
    }

    /// The fixed-point scale samples are added in.
    pub fn fixed(&self) -> FixedPoint {
        FixedPoint::new(self.shift)
    }

    /// Samples per pixel held.
    pub fn count(&self) -> u64 {
        u64::from(self.samples.saturating_sub(self.start))
    }

    /// The mean radiance of every pixel.
    pub fn mean(&self) -> Vec<Vec3> {
        let (n, fixed) = (self.count(), self.fixed());
        self.sum.iter().map(|s| fixed.mean(s, n)).collect()
    }

    /// 8-bit sRGB image of the clamped mean.
    pub fn to_srgb8(&self) -> RgbImage {
        self.image().srgb8()
    }

    /// Linear float image of the mean, unclamped.
    pub fn to_linear(&self) -> Rgb32FImage {
        let (n, fixed) = (self.count(), self.fixed());
        let data = self
            .sum
            .iter()
            .flat_map(|s| fixed.mean(s, n).to_array())
            .collect();
        Rgb32FImage::from_raw(self.width, self.height, data).expect("film size matches its pixels")
    }

    /// The image of the film's means, as the output sink writes it.
    pub fn image(&self) -> OutputImage<'_> {
        OutputImage::of_sums(
            self.width,
            self.height,
            &self.sum,
            self.count(),
            self.fixed(),
        )
    }

    /// Writes the image to `path` and waits for the disk (see [`write_output`]).
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        write_output(path, &self.image(), Durability::Synced)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_clamps_and_exr_keeps_linear_values() {
        let mut film = Film::new(2, 1);
        let fixed = film.fixed();
        film.sum[0].add(Vec3::new(4.0, 0.5, -1.0), fixed);
        film.sum[1].add(Vec3::new(0.0, 2.0, 0.0), fixed);
        film.samples = 2;
        let png = film.to_srgb8();
        // Mean (2, 0.25, −0.5) clamps to (1, 0.25, 0); 0.25 linear is 0.5371 in sRGB → 137.
        assert_eq!(png.get_pixel(0, 0).0, [255, 137, 0]);
        let exr = film.to_linear();
        assert_eq!(exr.get_pixel(0, 0).0, [2.0, 0.25, -0.5]);
    }
}
