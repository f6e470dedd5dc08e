//! Texture maps that change a surface's shape or presence rather than its colour: normal maps
//! and alpha masks (glTF's `normalTexture` and `alphaMode: MASK` or `BLEND`). Both are read as
//! linear data.

use std::sync::Arc;

use glam::Vec3;

use super::texture::{ImageTexture, Sampling, TexCoords, Texture, UvMap};

/// A tangent-space normal map: the texel's RGB in [0, 1] encodes a normal `2·rgb − 1` in the
/// frame (tangent, bitangent, shading normal); x and y are multiplied by `scale`.
#[derive(Clone, Debug, PartialEq)]
pub struct NormalMap {
    /// The map, decoded as linear values.
    pub texture: Texture,
    /// Scale of the map's x and y (glTF's `normalTexture.scale`).
    pub scale: f32,
}

impl NormalMap {
    /// The shading normal at `uv` perturbed by the map: `normalize(T·x·scale + B·y·scale + N·z)`
    /// with `(x, y, z) = 2·texel − 1`, in the frame of `N` = the unit shading normal `ns`, `T` =
    /// the unit texture tangent `tangent` (∂p/∂u) orthogonalised against `ns` (Gram–Schmidt)
    /// and `B = sign · N × T` (`sign` = −1 where the texture is mirrored). A result below the
    /// surface of unit geometric normal `n` is mirrored at it, to stay on `n`'s side as shading
    /// normals do; `ns` itself comes back when the frame or the result is degenerate (zero, or
    /// in the surface's plane) or not finite.
    #[inline]
    pub fn perturb(
        &self,
        uv: impl Into<TexCoords>,
        n: Vec3,
        ns: Vec3,
        tangent: Vec3,
        sign: f32,
    ) -> Vec3 {
        let Some(t) = (tangent - ns * ns.dot(tangent)).try_normalize() else {
            return ns;
        };
        let b = sign * ns.cross(t);
        let m = 2.0 * self.texture.eval(uv) - Vec3::ONE;
        let Some(p) = (t * (m.x * self.scale) + b * (m.y * self.scale) + ns * m.z).try_normalize()
        else {
            return ns;
        };
        let p = if p.dot(n) < 0.0 {
            p - 2.0 * p.dot(n) * n
        } else {
            p
        };
        if p.dot(n) > 0.0 { p } else { ns }
    }
}

/// An alpha mask: where the surface is there. With a cutoff (glTF's `MASK`) it is present
/// where `factor · alpha(uv) ≥ cutoff` and absent elsewhere; without one (glTF's `BLEND`) it is
/// present with probability `factor · alpha(uv)` ([`AlphaMask::coverage`]). The integrator
/// passes rays through with probability 1 − coverage: stochastic transparency, which in
/// expectation is the spec's "over" blend of the surface and what lies behind it, with no
/// sorting and no bias.
#[derive(Clone, Debug)]
pub struct AlphaMask {
    /// Alpha below which the surface is absent; `None`: blended.
    pub cutoff: Option<f32>,
    /// Alpha factor (the base colour factor's fourth component).
    pub factor: f32,
    /// The image whose alpha channel is read (the base colour texture's), and how.
    pub image: Option<(Arc<ImageTexture>, Sampling)>,
    /// Which coordinates the image is read at (the base colour texture's).
    pub map: Box<UvMap>,
}

impl AlphaMask {
    /// The probability that the surface is there at `uv`. With a cutoff: 1 where
    /// `factor · alpha(uv) ≥ cutoff`, else 0; blended: `factor · alpha(uv)` clamped to [0, 1].
    /// Alpha is 1 without an image (or for an image without an alpha channel); a NaN alpha
    /// reads as absent.
    #[inline]
    pub fn coverage(&self, uv: impl Into<TexCoords>) -> f32 {
        let alpha = match &self.image {
            None => 1.0,
            Some((image, sampling)) => image.sample_alpha(self.map.apply(uv.into()), *sampling),
        };
        let a = self.factor * alpha;
        match self.cutoff {
            Some(cutoff) => {
                if a >= cutoff {
                    1.0
                } else {
                    0.0
                }
            }
            // NaN fails `a > 0`: absent.
            None => {
                if a > 0.0 {
                    a.min(1.0)
                } else {
                    0.0
                }
            }
        }
    }

    /// The mask of cutoff `cutoff` and factor 1 that reads the alpha of a base colour texture:
    /// of its image, sampled as the colour is, when it is an [`Texture::Image`] (perhaps
    /// [`Texture::Mapped`]); any other texture has alpha 1 (the surface is then present
    /// everywhere if `cutoff` ≤ 1).
    pub fn of_base_color(cutoff: f32, base_color: &Texture) -> Self {
        let (texture, map) = match base_color {
            Texture::Mapped(inner, map) => (&**inner, map.clone()),
            other => (other, Box::default()),
        };
        Self {
            cutoff: Some(cutoff),
            factor: 1.0,
            image: match texture {
                Texture::Image(image, sampling) => Some((image.clone(), *sampling)),
                _ => None,
            },
            map,
        }
    }
}

impl PartialEq for AlphaMask {
    /// Images compare by identity, as in [`Texture`].
    fn eq(&self, other: &Self) -> bool {
        self.cutoff == other.cutoff
            && self.factor == other.factor
            && self.map == other.map
            && match (&self.image, &other.image) {
                (None, None) => true,
                (Some((a, s)), Some((b, s2))) => Arc::ptr_eq(a, b) && s == s2,
                _ => false,
            }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec2;

    #[test]
    fn a_mask_is_present_where_factor_times_alpha_reaches_the_cutoff() {
        // Top row: alpha 1, 0; bottom row: 128/255, 127/255.
        let px = [0, 0, 0, 255, 0, 0, 0, 0, 0, 0, 0, 128, 0, 0, 0, 127];
        let image = Arc::new(ImageTexture::from_rgba8(2, 2, &px, true));
        let mask = |factor, cutoff| AlphaMask {
            cutoff: Some(cutoff),
            factor,
            image: Some((image.clone(), Sampling::default())),
            map: Box::default(),
        };
        let texels = [
            Vec2::new(0.25, 0.75),
            Vec2::new(0.75, 0.75),
            Vec2::new(0.25, 0.25),
            Vec2::new(0.75, 0.25),
        ];
        let present = |m: &AlphaMask| texels.map(|uv| m.coverage(uv) == 1.0);
        assert_eq!(present(&mask(1.0, 0.5)), [true, false, true, false]);
        // Equal to the cutoff is present.
        assert_eq!(
            present(&mask(1.0, 128.0 / 255.0)),
            [true, false, true, false]
        );
        assert_eq!(present(&mask(0.5, 0.5)), [true, false, false, false]);
        assert_eq!(present(&mask(0.0, 0.5)), [false; 4]);
        assert_eq!(present(&mask(1.0, 0.0)), [true; 4]);
        // Without an image, alpha is 1: the factor alone decides.
        let flat = |factor| AlphaMask {
            cutoff: Some(0.5),
            factor,
            image: None,
            map: Box::default(),
        };
        assert!(flat(1.0).coverage(Vec2::ZERO) == 1.0 && flat(0.4).coverage(Vec2::ZERO) == 0.0);
    }
}
