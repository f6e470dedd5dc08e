//! Texture maps that change a surface's shape or presence rather than its colour: normal maps
//! and alpha masks (glTF's `normalTexture` and `alphaMode: MASK`). Both are read as linear data.

use std::sync::Arc;

use super::texture::{ImageTexture, Sampling, Texture};

/// A tangent-space normal map: the texel's RGB in [0, 1] encodes a normal `2·rgb − 1` in the
/// frame (tangent, bitangent, shading normal); x and y are multiplied by `scale`.
#[derive(Clone, Debug, PartialEq)]
pub struct NormalMap {
    /// The map, decoded as linear values.
    pub texture: Texture,
    /// Scale of the map's x and y (glTF's `normalTexture.scale`).
    pub scale: f32,
}

/// An alpha mask: the surface is present where `factor · alpha(uv) ≥ cutoff`; rays pass
/// through it elsewhere.
#[derive(Clone, Debug)]
pub struct AlphaMask {
    /// Alpha below which the surface is absent.
    pub cutoff: f32,
    /// Alpha factor (the base colour factor's fourth component).
    pub factor: f32,
    /// The image whose alpha channel is read (the base colour texture's), and how.
    pub image: Option<(Arc<ImageTexture>, Sampling)>,
}

impl PartialEq for AlphaMask {
    /// Images compare by identity, as in [`Texture`].
    fn eq(&self, other: &Self) -> bool {
        self.cutoff == other.cutoff
            && self.factor == other.factor
            && match (&self.image, &other.image) {
                (None, None) => true,
                (Some((a, s)), Some((b, s2))) => Arc::ptr_eq(a, b) && s == s2,
                _ => false,
            }
    }
}
