//! The film: per-pixel sums of radiance samples in exact fixed point, and the image files made
//! from them.
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
use image::{ImageFormat, Rgb32FImage, RgbImage};

/// Bits of headroom above the scene's brightest radiance: a sample may reach 2²⁴ (1.7·10⁷)
/// times the brightest emitter or background before it is clamped.
pub const HEADROOM_BITS: i32 = 24;

/// Magnitude bound of one sample in fixed point: 2⁶², so rounding never overflows an `i64`, and
/// with at most 2³² samples per pixel a sum needs at most 94 bits and a sign
/// ([`Pixel::WORDS`] words).
const SAMPLE_LIMIT: f64 = (1u64 << 62) as f64;

/// The shift of a scene whose brightest radiance (emission or background, any channel) is
/// `max_radiance`: samples are rounded to multiples of 2⁻shift, and a sample may reach
/// 2^[`HEADROOM_BITS`] times the brightest radiance (rounded up to a power of two) before it is
/// clamped. A scene with nothing brighter than 1 uses the shift of 1 (38: a resolution of
/// 3.6·10⁻¹², a range to 1.7·10⁷). Deterministic in `max_radiance` alone, so every process
/// that renders part of a scene picks the same one.
pub fn shift_for(max_radiance: f32) -> i32 {
    let m = if max_radiance.is_finite() && max_radiance > 1.0 {
        max_radiance
    } else if max_radiance.is_finite() && max_radiance > 0.0 {
        max_radiance.max(f32::MIN_POSITIVE)
    } else {
        1.0
    };
    // ⌈log2 m⌉ from the bits: m is normal, so its exponent is exact.
    let bits = m.to_bits();
    let exponent = ((bits >> 23) & 0xff) as i32 - 127;
    let ceil_log2 = exponent + i32::from(bits & 0x7f_ffff != 0);
    62 - HEADROOM_BITS - ceil_log2
}

/// The shift a film starts with before a scene sets its own: that of radiance 1.
pub const DEFAULT_SHIFT: i32 = 62 - HEADROOM_BITS;

/// The fixed-point scale of a film: samples are multiplied by 2^shift and rounded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FixedPoint {
    scale: f64,
}

impl FixedPoint {
    /// The scale 2^`shift`.
    pub fn new(shift: i32) -> Self {
        Self {
            scale: 2f64.powi(shift),
        }
    }

    /// One channel of a sample in fixed point, rounded to nearest (ties away from zero), and
    /// whether it had to be clamped to the representable range. Exact and cheap: the scaled
    /// value fits an `i64`, and the truncation remainder is computed exactly.
    #[inline]
    fn fixed(self, c: f32) -> (i64, bool) {
        let x = f64::from(c) * self.scale;
        let (x, clamped) = if x.abs() < SAMPLE_LIMIT {
            (x, false)
        } else {
            (SAMPLE_LIMIT.copysign(x), true)
        };
        let t = x as i64;
        let r = x - t as f64;
        let v = if r >= 0.5 {
            t + 1
        } else if r <= -0.5 {
            t - 1
        } else {
            t
        };
        (v, clamped)
    }

    /// The fixed-point value of one sample (`l` must be finite), and whether any channel was
    /// clamped to the range.
    #[inline]
    pub fn pixel(self, l: Vec3) -> (Pixel, bool) {
        let (x, cx) = self.fixed(l.x);
        let (y, cy) = self.fixed(l.y);
        let (z, cz) = self.fixed(l.z);
        (
            Pixel([i128::from(x), i128::from(y), i128::from(z)]),
            cx | cy | cz,
        )
    }

    /// The mean of `count` samples whose sum is `sum` (zero for no samples).
    #[inline]
    pub fn mean(self, sum: &Pixel, count: u64) -> Vec3 {
        let scale = 1.0 / (self.scale * count.max(1) as f64);
        Vec3::new(
            (sum.0[0] as f64 * scale) as f32,
            (sum.0[1] as f64 * scale) as f32,
            (sum.0[2] as f64 * scale) as f32,
        )
    }
}

/// The exact sum of a pixel's samples, per channel, in units of 2⁻shift of its film.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Pixel(pub [i128; 3]);

impl Pixel {
    /// A zero sum.
    pub const ZERO: Self = Self([0; 3]);

    /// 32-bit words a channel's sum is stored in (two's complement, least significant first).
    pub const WORDS: usize = 3;

    /// Adds one sample (`l` must be finite) in `fixed` point; true if a channel was clamped.
    #[inline]
    pub fn add(&mut self, l: Vec3, fixed: FixedPoint) -> bool {
        let (p, clamped) = fixed.pixel(l);
        self.merge(&p);
        clamped
    }

    /// Adds another sum (exact, so in any order).
    #[inline]
    pub fn merge(&mut self, other: &Self) {
        for (a, b) in self.0.iter_mut().zip(other.0) {
            *a += b;
        }
    }

    /// The sum of this and `other`, or `None` if a channel's leaves the [`Pixel::WORDS`] words
    /// it is stored in (sums read from files, which anyone may have written).
    pub fn checked_merge(&self, other: &Self) -> Option<Self> {
        const BOUND: i128 = 1 << (32 * Pixel::WORDS - 1);
        let mut sum = Self::ZERO;
        for ((s, a), b) in sum.0.iter_mut().zip(self.0).zip(other.0) {
            *s = a.checked_add(b).filter(|v| (-BOUND..BOUND).contains(v))?;
        }
        Some(sum)
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

/// The 8-bit sRGB value of a linear channel, clamped to [0, 1] (what a `.png` stores).
#[inline]
pub fn srgb8_channel(c: f32) -> u8 {
    (linear_to_srgb(c.clamp(0.0, 1.0)) * 255.0 + 0.5) as u8
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

/// The fixed-point shift of the normal feature buffer: normals are unit vectors, so the shift of
/// radiance 1.
pub const NORMAL_SHIFT: i32 = DEFAULT_SHIFT;

/// The fixed-point shift of the albedo feature buffer: albedos are reflectances, at most 1 (an
/// emitter's or the sky's may be more, up to 2^[`HEADROOM_BITS`] before it is clamped), so the
/// shift of radiance 1, whatever the colour's: the colour's shift of a scene lit at 10⁻¹⁰ leaves
/// a range of about 10⁻³, which would clamp every albedo, and that of a scene lit at 10³⁸ a
/// resolution of about 10³¹, which would round every albedo to zero.
pub const ALBEDO_SHIFT: i32 = DEFAULT_SHIFT;

/// The fixed point of [`NORMAL_SHIFT`], made once rather than per sample.
const NORMAL_FIXED: FixedPoint = FixedPoint {
    scale: (1u64 << NORMAL_SHIFT) as f64,
};

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
        srgb8(
            self.width,
            self.height,
            &self.sum,
            self.count(),
            self.fixed(),
        )
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

    /// Writes the image atomically (see [`write_atomically`]); the mean of each pixel is made
    /// as it is encoded, never kept as a second full-size image.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        let sums = (&self.sum[..], self.count(), self.fixed());
        encode_image(path, self.width, self.height, sums, true)
    }

    /// As [`Film::write`], but without waiting for the data to reach the disk (no fsync): for
    /// live images replaced within moments, where the fsync (5–20 ms on ext4 here) would delay
    /// the first image of an edit. Readers still never see a half-written file.
    pub fn write_live(&self, path: &Path) -> std::io::Result<()> {
        let sums = (&self.sum[..], self.count(), self.fixed());
        encode_image(path, self.width, self.height, sums, false)
    }
}

/// 8-bit sRGB image of the clamped means of `sum` (`count` samples per pixel, in `fixed` point).
pub fn srgb8(width: u32, height: u32, sum: &[Pixel], count: u64, fixed: FixedPoint) -> RgbImage {
    let data = sum
        .iter()
        .flat_map(|s| fixed.mean(s, count).to_array())
        .map(srgb8_channel)
        .collect();
    RgbImage::from_raw(width, height, data).expect("film size matches its pixels")
}

/// Writes the means of `sum` (`count` samples per pixel, in `fixed` point) as a `.png` (8-bit
/// sRGB, clamped) or `.exr` (linear f32 R, G, B) image, chosen by `path`'s extension, atomically.
pub fn write_image(
    path: &Path,
    width: u32,
    height: u32,
    sum: &[Pixel],
    count: u64,
    fixed: FixedPoint,
) -> std::io::Result<()> {
    encode_image(path, width, height, (sum, count, fixed), true)
}

fn encode_image(
    path: &Path,
    width: u32,
    height: u32,
    (sum, count, fixed): (&[Pixel], u64, FixedPoint),
    sync: bool,
) -> std::io::Result<()> {
    let kind = OutputKind::from_path(path).ok_or_else(|| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("{}: output must end in .png or .exr", path.display()),
        )
    })?;
    crate::output_file::write_file(path, sync, |out| match kind {
        OutputKind::Png => srgb8(width, height, sum, count, fixed)
            .write_to(out, ImageFormat::Png)
            .map_err(std::io::Error::other),
        OutputKind::Exr => {
            use exr::prelude::*;
            let w = width as usize;
            let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
                let m = fixed.mean(&sum[p.y() * w + p.x()], count);
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
    fn checked_merges_stop_at_the_96_bits_a_sum_is_stored_in() {
        let top = (1i128 << 95) - 1;
        let at = |v: i128| Pixel([v, 0, 0]);
        assert_eq!(at(top - 1).checked_merge(&at(1)), Some(at(top)));
        assert_eq!(at(top).checked_merge(&at(1)), None);
        assert_eq!(at(-top).checked_merge(&at(-1)), Some(at(-top - 1)));
        assert_eq!(at(-top - 1).checked_merge(&at(-1)), None);
        assert_eq!(Pixel([0, top, 0]).checked_merge(&Pixel([0, top, 0])), None);
        // What fits reads back from its words.
        let mut back = Pixel::ZERO;
        back.set_words(0, at(-top - 1).words(0));
        assert_eq!(back, at(-top - 1));
    }

    #[test]
    fn srgb_encoding_matches_the_standard() {
        assert_eq!(linear_to_srgb(0.0), 0.0);
        assert!((linear_to_srgb(1.0) - 1.0).abs() < 1e-6);
        assert!((linear_to_srgb(0.214_04) - 0.5).abs() < 1e-4);
    }

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

    #[test]
    fn fixed_point_rounds_to_nearest_and_sums_in_any_order() {
        let fixed = FixedPoint::new(32);
        let unit = 2f32.powi(-32);
        let one = |c: f32| fixed.fixed(c);
        assert_eq!(one(1.0), (1 << 32, false));
        assert_eq!(one(-0.25), (-(1 << 30), false));
        assert_eq!(one(unit * 0.49), (0, false));
        assert_eq!(one(unit * 0.5), (1, false));
        assert_eq!(one(-unit * 0.5), (-1, false));
        // Beyond 2^62 units (2^30 at shift 32) a channel is clamped, and says so.
        assert_eq!(one(f32::MAX), (1 << 62, true));
        assert_eq!(one(-f32::MAX), (-(1 << 62), true));
        assert_eq!(
            one(2f32.powi(30) * 0.999),
            (
                (f64::from(2f32.powi(30) * 0.999) * 2f64.powi(32)) as i64,
                false
            )
        );
        // Values that do not add associatively in floating point.
        let samples = [1e8f32, 1e-3, -1e8, 3.7e-5, 0.1, 12345.678];
        let mut forward = Pixel::ZERO;
        samples.iter().for_each(|&s| {
            forward.add(Vec3::splat(s), fixed);
        });
        let mut backward = Pixel::ZERO;
        samples.iter().rev().for_each(|&s| {
            backward.add(Vec3::splat(s), fixed);
        });
        assert_eq!(forward, backward);
        let f: f32 = samples.iter().sum();
        let b: f32 = samples.iter().rev().sum();
        assert_ne!(f, b, "the samples must not be associative in f32");
    }

    #[test]
    fn the_shift_gives_every_brightness_its_headroom_and_precision() {
        assert_eq!(shift_for(1.0), DEFAULT_SHIFT);
        assert_eq!(
            shift_for(0.0),
            DEFAULT_SHIFT,
            "a black scene keeps the default"
        );
        assert_eq!(shift_for(f32::NAN), DEFAULT_SHIFT);
        assert_eq!(shift_for(2.0), DEFAULT_SHIFT - 1);
        assert_eq!(
            shift_for(2.5),
            DEFAULT_SHIFT - 2,
            "rounded up to a power of two"
        );
        assert_eq!(shift_for(0.5), DEFAULT_SHIFT + 1);
        for m in [
            1e-30f32,
            1e-10,
            3e-10,
            0.7,
            17.0,
            1.6e9,
            5e9,
            1e30,
            f32::MAX,
        ] {
            let fixed = FixedPoint::new(shift_for(m));
            // The brightest radiance, and 2^HEADROOM_BITS times it less an ulp, are not clamped;
            // four times beyond the headroom is.
            let headroom = 2f32.powi(HEADROOM_BITS);
            assert!(!fixed.pixel(Vec3::splat(m)).1, "{m}");
            if (m * headroom).is_finite() {
                assert!(!fixed.pixel(Vec3::splat(m * headroom * 0.999)).1, "{m}");
            }
            if (m * headroom * 4.0).is_finite() {
                assert!(fixed.pixel(Vec3::splat(m * headroom * 4.0)).1, "{m}");
            }
            // One sample at 10⁻⁶ of the brightest value is kept to 2⁻³⁸ of the brightest
            // (rounded up to a power of two): a relative error below 10⁻⁵.
            let small = m * 1e-6;
            let mean = fixed.mean(&fixed.pixel(Vec3::splat(small)).0, 1);
            let rel = ((mean.x - small) / small).abs();
            assert!(rel < 1e-5, "{m}: {rel}");
        }
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
