//! Textures: a colour as a function of texture coordinates.

use std::sync::Arc;

use glam::{Affine2, Vec2, Vec3};
use serde::Deserialize;

/// The texture coordinates of a hit: set 0 and set 1 of its mesh (set 1 is set 0 where the
/// mesh carries no second set). A single `Vec2` converts to both sets.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TexCoords(pub [Vec2; 2]);

impl From<Vec2> for TexCoords {
    #[inline(always)]
    fn from(uv: Vec2) -> Self {
        Self([uv, uv])
    }
}

/// Which texture coordinates a texture reads: one of the hit's sets, through an optional
/// affine transform (glTF's `texCoord` and `KHR_texture_transform`, in rondo's texture space:
/// v pointing up the image).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct UvMap {
    /// The set read: 0 or 1 ([`TexCoords`]); anything above 1 reads set 1.
    pub set: usize,
    /// The transform applied to the set's coordinates, if any.
    pub transform: Option<Affine2>,
}

impl UvMap {
    /// The coordinates this map reads from `uv`.
    #[inline]
    pub fn apply(&self, uv: TexCoords) -> Vec2 {
        let t = uv.0[self.set.min(1)];
        match &self.transform {
            None => t,
            Some(m) => m.transform_point2(t),
        }
    }
}

/// How an image texture is read between texel centres.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum Filter {
    /// The texel the point falls in (the default).
    #[default]
    Nearest,
    /// Bilinear interpolation of the four texels around the point, between texel centres.
    Bilinear,
}

/// How an image texture is read outside [0, 1] (glTF's sampler wrap modes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum Wrap {
    /// The edge texels extend outwards (the default).
    #[default]
    Clamp,
    /// The image tiles.
    Repeat,
    /// The image tiles, every other copy mirrored.
    MirroredRepeat,
}

/// How an image texture is sampled: its filter and its wrap modes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Sampling {
    /// Between texel centres.
    pub filter: Filter,
    /// Outside [0, 1], along u then along v (glTF's `wrapS`, `wrapT`).
    pub wrap: [Wrap; 2],
}

impl Wrap {
    /// Texel index `i` (any integer) of a row or column of `n` texels, wrapped into `0..n`.
    #[inline]
    fn index(self, i: i64, n: usize) -> usize {
        let n = n as i64;
        let k = match self {
            Self::Clamp => i.clamp(0, n - 1),
            Self::Repeat => i.rem_euclid(n),
            Self::MirroredRepeat => {
                let k = i.rem_euclid(2 * n);
                if k < n { k } else { 2 * n - 1 - k }
            }
        };
        k as usize
    }
}

/// An image decoded to linear RGB, with its alpha channel if it has one that is not opaque.
#[derive(Debug)]
pub struct ImageTexture {
    width: u32,
    height: u32,
    texels: Vec<Vec3>,
    /// Alpha per texel, in [0, 1]; `None` when every texel is opaque.
    alpha: Option<Vec<f32>>,
    /// The largest channel magnitude of any texel.
    max: f32,
}

/// The sRGB electro-optical transfer function: encoded value in `[0, 1]` → linear.
#[inline]
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

impl ImageTexture {
    /// Decodes 8-bit sRGB pixels (row-major, top row first) to linear RGB.
    /// `pixels.len()` must be `3 · width · height`.
    pub fn from_srgb8(width: u32, height: u32, pixels: &[u8]) -> Self {
        debug_assert_eq!(pixels.len(), 3 * width as usize * height as usize);
        let lut = srgb_table();
        let texels = pixels
            .chunks_exact(3)
            .map(|p| Vec3::new(lut[p[0] as usize], lut[p[1] as usize], lut[p[2] as usize]))
            .collect();
        Self::new(width, height, texels, None)
    }

    /// Decodes 8-bit RGBA pixels (row-major, top row first): RGB sRGB-encoded if `srgb`, else
    /// linear values `v / 255`; alpha always linear, kept only if some texel is not opaque.
    /// `pixels.len()` must be `4 · width · height`.
    pub fn from_rgba8(width: u32, height: u32, pixels: &[u8], srgb: bool) -> Self {
        debug_assert_eq!(pixels.len(), 4 * width as usize * height as usize);
        let lut = if srgb {
            srgb_table()
        } else {
            (0..=255u8).map(|v| f32::from(v) / 255.0).collect()
        };
        let texels = pixels
            .chunks_exact(4)
            .map(|p| Vec3::new(lut[p[0] as usize], lut[p[1] as usize], lut[p[2] as usize]))
            .collect();
        let alpha = pixels.chunks_exact(4).any(|p| p[3] != 255).then(|| {
            pixels
                .chunks_exact(4)
                .map(|p| f32::from(p[3]) / 255.0)
                .collect()
        });
        Self::new(width, height, texels, alpha)
    }

    /// Wraps linear RGB floats (row-major, top row first); `pixels.len()` must be
    /// `3 · width · height`.
    pub fn from_linear(width: u32, height: u32, pixels: &[f32]) -> Self {
        debug_assert_eq!(pixels.len(), 3 * width as usize * height as usize);
        let texels = pixels.chunks_exact(3).map(Vec3::from_slice).collect();
        Self::new(width, height, texels, None)
    }

    fn new(width: u32, height: u32, texels: Vec<Vec3>, alpha: Option<Vec<f32>>) -> Self {
        let max = texels
            .iter()
            .map(|t| t.abs().max_element())
            .fold(0.0, f32::max);
        Self {
            width,
            height,
            texels,
            alpha,
            max,
        }
    }

    /// Whether the image has an alpha channel that is not opaque everywhere.
    pub fn has_alpha(&self) -> bool {
        self.alpha.is_some()
    }

    /// Index of the texel at `uv`: `i = min(⌊u·W⌋, W−1)`, `j = min(⌊(1−v)·H⌋, H−1)` (v = 0 is
    /// the bottom row), with u and v clamped to [0, 1], so every texel covers an equal square of
    /// texture space (`⌊u(W−1)⌋` would never reach the last column and row).
    #[inline]
    fn nearest_clamped(&self, uv: Vec2) -> usize {
        let u = uv.x.clamp(0.0, 1.0);
        let v = uv.y.clamp(0.0, 1.0);
        let i = ((u * self.width as f32) as usize).min(self.width as usize - 1);
        let j = (((1.0 - v) * self.height as f32) as usize).min(self.height as usize - 1);
        j * self.width as usize + i
    }

    /// The texel at `uv`, nearest and clamped (see [`ImageTexture::sample`]).
    #[inline]
    pub fn lookup(&self, uv: Vec2) -> Vec3 {
        self.texels[self.nearest_clamped(uv)]
    }

    /// The colour at `uv` sampled as `sampling` says; nearest and clamped is
    /// [`ImageTexture::lookup`]. Texel `(i, j)` covers `u` in `[i, i + 1) / W` and `v` in
    /// `(H − j − 1, H − j] / H` (v = 0 is the bottom row); bilinear weights are taken between
    /// texel centres.
    #[inline]
    pub fn sample(&self, uv: Vec2, sampling: Sampling) -> Vec3 {
        self.filtered(uv, sampling, |k| self.texels[k], Vec3::lerp)
    }

    /// The alpha at `uv`, sampled as the colour is; 1 for an image without alpha.
    #[inline]
    pub fn sample_alpha(&self, uv: Vec2, sampling: Sampling) -> f32 {
        match &self.alpha {
            None => 1.0,
            Some(alpha) => self.filtered(uv, sampling, |k| alpha[k], |a, b, t| a + (b - a) * t),
        }
    }

    /// A channel read by `texel(index)` at `uv`, filtered and wrapped as `sampling` says.
    #[inline]
    fn filtered<T: Copy>(
        &self,
        uv: Vec2,
        sampling: Sampling,
        texel: impl Fn(usize) -> T,
        lerp: impl Fn(T, T, f32) -> T,
    ) -> T {
        let (w, h) = (self.width as usize, self.height as usize);
        let at = |i: i64, j: i64| {
            let (i, j) = (sampling.wrap[0].index(i, w), sampling.wrap[1].index(j, h));
            texel(j * w + i)
        };
        // Continuous texel coordinates, rows from the top; non-finite reads as 0.
        let finite = |x: f32| if x.is_finite() { x } else { 0.0 };
        let x = finite(uv.x) * w as f32;
        let y = (1.0 - finite(uv.y)) * h as f32;
        match (sampling.filter, sampling.wrap) {
            (Filter::Nearest, [Wrap::Clamp, Wrap::Clamp]) => texel(self.nearest_clamped(uv)),
            (Filter::Nearest, _) => at(x.floor() as i64, y.floor() as i64),
            (Filter::Bilinear, _) => {
                let (x, y) = (x - 0.5, y - 0.5);
                let (i, j) = (x.floor(), y.floor());
                let (tx, ty) = (x - i, y - j);
                let (i, j) = (i as i64, j as i64);
                let top = lerp(at(i, j), at(i + 1, j), tx);
                let bottom = lerp(at(i, j + 1), at(i + 1, j + 1), tx);
                lerp(top, bottom, ty)
            }
        }
    }
}

/// sRGB decoding of every 8-bit value.
fn srgb_table() -> Vec<f32> {
    (0..=255u8)
        .map(|v| srgb_to_linear(f32::from(v) / 255.0))
        .collect()
}

/// Whether `sin(a) · sin(b) > 0`, without evaluating a sine: `sin x` is positive on the
/// half-periods `[2kπ, (2k + 1)π)` and negative on the others, so the product is positive
/// when neither factor is zero and `⌊a/π⌋` and `⌊b/π⌋` have the same parity. The same answer
/// as the product of sines except where `a/π` or `b/π` rounds across an integer other than 0
/// (within an ulp of a cell's edge); NaN and infinite arguments (whose sine is NaN) give false.
#[inline]
fn sines_agree(a: f32, b: f32) -> bool {
    a != 0.0
        && b != 0.0
        && matches!((half_period_parity(a), half_period_parity(b)), (Some(p), Some(q)) if p == q)
}

/// The parity of `⌊x/π⌋` (`None` for a NaN or infinite `x`, whose sine is NaN), exact for every
/// finite quotient, by integer arithmetic: no `floor`, which the out-of-line texture lookup,
/// compiled for baseline x86-64 (SSE2 has no rounding instruction), calls in the C library.
/// From 2²⁴ up a quotient's ulp is at least 2, so it is an even integer; below, the truncation
/// to an integer is exact and is moved down by one where it rounded a negative quotient up.
#[inline]
fn half_period_parity(x: f32) -> Option<u32> {
    let q = x * std::f32::consts::FRAC_1_PI;
    if !q.is_finite() {
        return None;
    }
    if q.abs() >= (1u32 << 24) as f32 {
        return Some(0);
    }
    let truncated = q as i32;
    let floor = truncated - i32::from(q < truncated as f32);
    Some((floor & 1) as u32)
}

/// A colour source.
#[derive(Clone, Debug)]
pub enum Texture {
    /// The same colour everywhere.
    Constant(Vec3),
    /// A checker: `even` where `sin(k·u)·sin(k·v) > 0`, else `odd`.
    Checker {
        /// The frequency `k`.
        scale: f32,
        /// Texture of the "positive" cells.
        even: Box<Texture>,
        /// Texture of the other cells.
        odd: Box<Texture>,
    },
    /// An image, shared between materials that use the same file, and how it is sampled.
    Image(Arc<ImageTexture>, Sampling),
    /// A texture times a factor per channel (glTF's texture × factor).
    Scaled(Box<Texture>, Vec3),
    /// A texture read at the coordinates a [`UvMap`] gives (another set, a transform); boxed, as
    /// the map is larger than every other variant.
    Mapped(Box<Texture>, Box<UvMap>),
}

impl PartialEq for Texture {
    /// Images compare by identity: a reloaded file is a new texture.
    fn eq(&self, other: &Self) -> bool {
        match (self, other) {
            (Self::Constant(a), Self::Constant(b)) => a == b,
            (
                Self::Checker {
                    scale: s,
                    even: e,
                    odd: o,
                },
                Self::Checker {
                    scale: s2,
                    even: e2,
                    odd: o2,
                },
            ) => s == s2 && e == e2 && o == o2,
            (Self::Image(a, s), Self::Image(b, s2)) => Arc::ptr_eq(a, b) && s == s2,
            (Self::Scaled(a, f), Self::Scaled(b, f2)) => a == b && f == f2,
            (Self::Mapped(a, m), Self::Mapped(b, m2)) => a == b && m == m2,
            _ => false,
        }
    }
}

impl Texture {
    /// The colour at `uv` (a single set, or a hit's [`TexCoords`]; textures other than
    /// [`Texture::Mapped`] read set 0).
    #[inline(always)]
    pub fn eval(&self, uv: impl Into<TexCoords>) -> Vec3 {
        // A constant, the most common texture, is read here: `eval_at` recurses, so it is
        // never inlined, and a call per lookup would cost more than the lookup.
        match self {
            Self::Constant(c) => *c,
            _ => self.eval_at(uv.into()),
        }
    }

    #[inline]
    fn eval_at(&self, tc: TexCoords) -> Vec3 {
        let uv = tc.0[0];
        match self {
            Self::Constant(c) => *c,
            Self::Checker { scale, even, odd } => {
                if sines_agree(scale * uv.x, scale * uv.y) {
                    even.eval_at(tc)
                } else {
                    odd.eval_at(tc)
                }
            }
            Self::Image(image, sampling) => image.sample(uv, *sampling),
            Self::Scaled(texture, factor) => texture.eval_at(tc) * *factor,
            Self::Mapped(texture, map) => texture.eval(map.apply(tc)),
        }
    }

    /// Whether the colour depends on the texture coordinates: false for a constant colour
    /// (scaled or mapped), whose lookups need no coordinates computed.
    pub fn reads_uv(&self) -> bool {
        match self {
            Self::Constant(_) => false,
            Self::Checker { .. } | Self::Image(..) => true,
            Self::Scaled(texture, _) | Self::Mapped(texture, _) => texture.reads_uv(),
        }
    }

    /// The largest channel magnitude the texture takes anywhere.
    pub fn max_channel(&self) -> f32 {
        match self {
            Self::Constant(c) => c.abs().max_element(),
            Self::Checker { even, odd, .. } => even.max_channel().max(odd.max_channel()),
            Self::Image(image, _) => image.max,
            Self::Scaled(texture, factor) => texture.max_channel() * factor.abs().max_element(),
            Self::Mapped(texture, _) => texture.max_channel(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_decoding_matches_the_standard_at_known_points() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        // 0.5 encoded is 0.21404 linear (IEC 61966-2-1).
        assert!((srgb_to_linear(0.5) - 0.214_04).abs() < 1e-4);
    }

    #[test]
    fn image_lookup_flips_v_and_clamps() {
        // 2×2 image: top row red, green; bottom row blue, white.
        let px = [255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255];
        let img = ImageTexture::from_srgb8(2, 2, &px);
        assert_eq!(img.lookup(Vec2::new(0.0, 1.0)), Vec3::X); // top-left
        assert_eq!(img.lookup(Vec2::new(0.0, 0.0)), Vec3::Z); // bottom-left
        assert_eq!(img.lookup(Vec2::new(1.0, 1.0)), Vec3::Y); // top-right
        assert_eq!(img.lookup(Vec2::new(7.0, -3.0)), Vec3::ONE); // clamped bottom-right
    }

    #[test]
    fn every_texel_of_a_2x2_image_covers_a_quarter_of_texture_space() {
        // Top row red, green; bottom row blue, white. The centre of each quarter of the unit
        // square, and points just inside its corners, read that quarter's texel.
        let px = [255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255];
        let img = ImageTexture::from_srgb8(2, 2, &px);
        let quarters = [
            (Vec2::new(0.25, 0.75), Vec3::X),
            (Vec2::new(0.75, 0.75), Vec3::Y),
            (Vec2::new(0.25, 0.25), Vec3::Z),
            (Vec2::new(0.75, 0.25), Vec3::ONE),
        ];
        for (centre, texel) in quarters {
            for offset in [Vec2::ZERO, Vec2::splat(0.24), Vec2::splat(-0.24)] {
                let uv = centre + offset;
                assert_eq!(img.lookup(uv), texel, "uv {uv}");
            }
        }
    }

    /// A 2×2 image of grey values: top row 0, 1; bottom row 2, 3 (linear).
    fn grey_2x2() -> ImageTexture {
        let px: Vec<f32> = [0.0f32, 1.0, 2.0, 3.0]
            .iter()
            .flat_map(|&g| [g; 3])
            .collect();
        ImageTexture::from_linear(2, 2, &px)
    }

    #[test]
    fn bilinear_filtering_interpolates_between_texel_centres() {
        let img = grey_2x2();
        let bilinear = |wrap| Sampling {
            filter: Filter::Bilinear,
            wrap: [wrap; 2],
        };
        let at = |u: f32, v: f32, wrap| img.sample(Vec2::new(u, v), bilinear(wrap)).x;
        // Texel centres are exact: (0.25, 0.75) is the top-left texel.
        assert_eq!(at(0.25, 0.75, Wrap::Clamp), 0.0);
        assert_eq!(at(0.75, 0.25, Wrap::Clamp), 3.0);
        // Midway between all four: their mean; between two in a row: their mean.
        assert!((at(0.5, 0.5, Wrap::Clamp) - 1.5).abs() < 1e-6);
        assert!((at(0.5, 0.75, Wrap::Clamp) - 0.5).abs() < 1e-6);
        // At the left edge, clamped: the edge texel; repeated: halfway to the right column.
        assert!((at(0.0, 0.75, Wrap::Clamp) - 0.0).abs() < 1e-6);
        assert!((at(0.0, 0.75, Wrap::Repeat) - 0.5).abs() < 1e-6);
        assert!((at(0.0, 0.75, Wrap::MirroredRepeat) - 0.0).abs() < 1e-6);
        // The default sampling is the nearest texel, clamped: `lookup`.
        for uv in [
            Vec2::new(0.3, 0.9),
            Vec2::new(-2.0, 5.0),
            Vec2::new(0.75, 0.1),
        ] {
            assert_eq!(img.sample(uv, Sampling::default()), img.lookup(uv));
        }
    }

    #[test]
    fn wrap_modes_tile_and_mirror_outside_the_unit_square() {
        let img = grey_2x2();
        let nearest = |wrap| Sampling {
            filter: Filter::Nearest,
            wrap: [wrap; 2],
        };
        let at = |u: f32, v: f32, wrap| img.sample(Vec2::new(u, v), nearest(wrap)).x;
        // Repeat: u + 1 reads the same texel; negative u wraps from the right.
        assert_eq!(at(1.25, 0.75, Wrap::Repeat), 0.0);
        assert_eq!(at(-0.25, 0.75, Wrap::Repeat), 1.0);
        // Mirrored: just past 1 reads the last column again, then the first.
        assert_eq!(at(1.25, 0.75, Wrap::MirroredRepeat), 1.0);
        assert_eq!(at(1.75, 0.75, Wrap::MirroredRepeat), 0.0);
        assert_eq!(at(-0.25, 0.75, Wrap::MirroredRepeat), 0.0);
        // Clamp: the edge texel.
        assert_eq!(at(3.0, 0.75, Wrap::Clamp), 1.0);
        // Rows: v = 1.25 is a quarter above the top; repeat reads the bottom row's texel there.
        assert_eq!(at(0.25, 1.25, Wrap::Repeat), 2.0);
        // Non-finite coordinates read as 0: v = 0 is the bottom edge, which repeat wraps to the top.
        assert_eq!(at(f32::NAN, f32::INFINITY, Wrap::Repeat), 0.0);
    }

    #[test]
    fn rgba_pixels_keep_a_linear_alpha_and_decode_rgb_as_asked() {
        // Top row: opaque white, transparent black; bottom row: half alpha, opaque grey 128.
        let px = [
            255, 255, 255, 255, 0, 0, 0, 0, 10, 20, 30, 128, 128, 128, 128, 255,
        ];
        let srgb = ImageTexture::from_rgba8(2, 2, &px, true);
        let linear = ImageTexture::from_rgba8(2, 2, &px, false);
        let bottom_right = Vec2::new(0.75, 0.25);
        assert!((srgb.lookup(bottom_right).x - srgb_to_linear(128.0 / 255.0)).abs() < 1e-6);
        assert_eq!(linear.lookup(bottom_right).x, 128.0 / 255.0);
        let nearest = Sampling::default();
        assert_eq!(srgb.sample_alpha(Vec2::new(0.75, 0.75), nearest), 0.0);
        assert_eq!(
            srgb.sample_alpha(Vec2::new(0.25, 0.25), nearest),
            128.0 / 255.0
        );
        // Bilinear halfway along the top row: the mean of 1 and 0.
        let bilinear = Sampling {
            filter: Filter::Bilinear,
            wrap: [Wrap::Clamp; 2],
        };
        assert!((srgb.sample_alpha(Vec2::new(0.5, 0.75), bilinear) - 0.5).abs() < 1e-6);
        // An opaque image keeps no alpha and reads 1 everywhere.
        let opaque = ImageTexture::from_rgba8(1, 1, &[1, 2, 3, 255], true);
        assert!(!opaque.has_alpha() && srgb.has_alpha());
        assert_eq!(opaque.sample_alpha(Vec2::ZERO, nearest), 1.0);
    }

    #[test]
    fn a_mapped_texture_reads_its_set_through_its_transform() {
        // Grey 0, 1 / 2, 3 (top row first), nearest and clamped.
        let image = Texture::Image(Arc::new(grey_2x2()), Sampling::default());
        let uv = TexCoords([Vec2::new(0.25, 0.75), Vec2::new(0.75, 0.25)]);
        let set = |set| {
            Texture::Mapped(
                Box::new(image.clone()),
                Box::new(UvMap {
                    set,
                    transform: None,
                }),
            )
        };
        // Unmapped and set 0 read the first set (top left, 0); set 1 the second (bottom right, 3).
        assert_eq!(image.eval(uv).x, 0.0);
        assert_eq!(set(0).eval(uv).x, 0.0);
        assert_eq!(set(1).eval(uv).x, 3.0);
        // A shift by +0.5 in u moves the first set's point to the top right texel (1).
        let shifted = Texture::Mapped(
            Box::new(image.clone()),
            Box::new(UvMap {
                set: 0,
                transform: Some(glam::Affine2::from_translation(Vec2::new(0.5, 0.0))),
            }),
        );
        assert_eq!(shifted.eval(uv).x, 1.0);
        // A single set stands for both.
        assert_eq!(set(1).eval(Vec2::new(0.25, 0.25)).x, 2.0);
    }

    #[test]
    fn checker_alternates_by_the_sign_of_the_sine_product() {
        let t = Texture::Checker {
            scale: std::f32::consts::PI,
            even: Box::new(Texture::Constant(Vec3::ONE)),
            odd: Box::new(Texture::Constant(Vec3::ZERO)),
        };
        assert_eq!(t.eval(Vec2::new(0.5, 0.5)), Vec3::ONE);
        assert_eq!(t.eval(Vec2::new(1.5, 0.5)), Vec3::ZERO);
        assert_eq!(t.eval(Vec2::new(1.5, 1.5)), Vec3::ONE);
    }

    /// The integer parity equals `⌊x/π⌋ mod 2` computed in f64 from the same f32 quotient, at
    /// every magnitude: around each power of two from 2⁻²⁰ to 2¹²⁷ (where the quotient stops
    /// having a fractional part at 2²³ and an odd one at 2²⁴), both signs, an ulp either side.
    #[test]
    fn half_period_parity_is_the_floor_s_parity_at_every_magnitude() {
        let mut checked = 0;
        for e in -20..=127 {
            let p = 2f32.powi(e);
            for q in [p, p.next_up(), p.next_down(), 1.5 * p, 3.0 * p] {
                for q in [q, -q] {
                    let x = q * std::f32::consts::PI;
                    let quotient = x * std::f32::consts::FRAC_1_PI;
                    if !quotient.is_finite() || !x.is_finite() {
                        continue;
                    }
                    let want = f64::from(quotient).floor().rem_euclid(2.0) as u32;
                    assert_eq!(half_period_parity(x), Some(want), "{x}");
                    checked += 1;
                }
            }
        }
        assert!(checked > 1400, "{checked}");
        assert_eq!(half_period_parity(f32::NAN), None);
        assert_eq!(half_period_parity(f32::NEG_INFINITY), None);
    }

    /// The parity form agrees with the sign of the product of sines (computed in f64, the
    /// independent truth) everywhere but within a relative 1e-5 of a cell's edge, over
    /// thousands of cells each way, negative arguments, zeros and non-finite values included.
    #[test]
    fn checker_parity_equals_the_sign_of_the_sine_product() {
        let mut rng = crate::shading::rng::Rng::new(34, 7);
        let mut checked = 0;
        for _ in 0..200_000 {
            let a = (rng.next_f32() - 0.5) * 2.0e4;
            let b = (rng.next_f32() - 0.5) * 20.0;
            let near_edge = |x: f32| {
                let q = f64::from(x) / std::f64::consts::PI;
                (q - q.round()).abs() < 1e-5 * q.abs().max(1.0)
            };
            if near_edge(a) || near_edge(b) {
                continue;
            }
            let want = f64::from(a).sin() * f64::from(b).sin() > 0.0;
            assert_eq!(sines_agree(a, b), want, "{a} {b}");
            assert_eq!(sines_agree(b, a), want, "{b} {a}");
            checked += 1;
        }
        assert!(checked > 190_000);
        for x in [0.0, -0.0, f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            assert!(!sines_agree(x, 1.0) && !sines_agree(1.0, x), "{x}");
        }
        // Both factors negative: the product is positive.
        assert!(sines_agree(-1.0, 4.0));
        assert!(!sines_agree(-1.0, 1.0));
    }
}
