//! Textures: a colour as a function of texture coordinates.

use std::sync::Arc;

use glam::{Vec2, Vec3};

/// An image decoded to linear RGB, looked up by nearest texel.
#[derive(Debug)]
pub struct ImageTexture {
    width: u32,
    height: u32,
    texels: Vec<Vec3>,
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
        let lut: Vec<f32> = (0..=255u8)
            .map(|v| srgb_to_linear(f32::from(v) / 255.0))
            .collect();
        let texels = pixels
            .chunks_exact(3)
            .map(|p| Vec3::new(lut[p[0] as usize], lut[p[1] as usize], lut[p[2] as usize]))
            .collect();
        Self::new(width, height, texels)
    }

    /// Wraps linear RGB floats (row-major, top row first); `pixels.len()` must be
    /// `3 · width · height`.
    pub fn from_linear(width: u32, height: u32, pixels: &[f32]) -> Self {
        debug_assert_eq!(pixels.len(), 3 * width as usize * height as usize);
        let texels = pixels.chunks_exact(3).map(Vec3::from_slice).collect();
        Self::new(width, height, texels)
    }

    fn new(width: u32, height: u32, texels: Vec<Vec3>) -> Self {
        let max = texels
            .iter()
            .map(|t| t.abs().max_element())
            .fold(0.0, f32::max);
        Self {
            width,
            height,
            texels,
            max,
        }
    }

    /// The texel at `uv`: `i = min(⌊u·W⌋, W−1)`, `j = min(⌊(1−v)·H⌋, H−1)` (v = 0 is the
    /// bottom row), with u and v clamped to [0, 1], so every texel covers an equal square of
    /// texture space (the thesis's `⌊u(W−1)⌋` never reaches the last column and row).
    #[inline]
    pub fn lookup(&self, uv: Vec2) -> Vec3 {
        let u = uv.x.clamp(0.0, 1.0);
        let v = uv.y.clamp(0.0, 1.0);
        let i = ((u * self.width as f32) as usize).min(self.width as usize - 1);
        let j = (((1.0 - v) * self.height as f32) as usize).min(self.height as usize - 1);
        self.texels[j * self.width as usize + i]
    }
}

/// A colour source.
#[derive(Clone, Debug)]
pub enum Texture {
    /// The same colour everywhere.
    Constant(Vec3),
    /// The thesis's checker: `even` where `sin(k·u)·sin(k·v) > 0`, else `odd`.
    Checker {
        /// The frequency `k`.
        scale: f32,
        /// Texture of the "positive" cells.
        even: Box<Texture>,
        /// Texture of the other cells.
        odd: Box<Texture>,
    },
    /// An image, shared between materials that use the same file.
    Image(Arc<ImageTexture>),
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
            (Self::Image(a), Self::Image(b)) => Arc::ptr_eq(a, b),
            _ => false,
        }
    }
}

impl Texture {
    /// The colour at `uv`.
    #[inline]
    pub fn eval(&self, uv: Vec2) -> Vec3 {
        match self {
            Self::Constant(c) => *c,
            Self::Checker { scale, even, odd } => {
                if (scale * uv.x).sin() * (scale * uv.y).sin() > 0.0 {
                    even.eval(uv)
                } else {
                    odd.eval(uv)
                }
            }
            Self::Image(image) => image.lookup(uv),
        }
    }

    /// The largest channel magnitude the texture takes anywhere.
    pub fn max_channel(&self) -> f32 {
        match self {
            Self::Constant(c) => c.abs().max_element(),
            Self::Checker { even, odd, .. } => even.max_channel().max(odd.max_channel()),
            Self::Image(image) => image.max,
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
}
