//! Textures that vary a `Pbr`'s [`Layers`] over the surface, as the glTF extensions define them:
//! each reads one part of its texel and multiplies its factor. `KHR_materials_specular`'s
//! `specularTexture` (alpha) and `specularColorTexture` (RGB, sRGB); `KHR_materials_sheen`'s
//! `sheenColorTexture` (RGB, sRGB) and `sheenRoughnessTexture` (alpha);
//! `KHR_materials_clearcoat`'s `clearcoatTexture` (red) and `clearcoatRoughnessTexture` (green),
//! both linear. A material without any holds no [`LayerMaps`] and does no lookup. No ECS here.

use std::sync::Arc;

use super::layers::Layers;
use super::texture::{ImageTexture, Sampling, TexCoords, Texture, UvMap};

/// The alpha channel of an image, read at the coordinates a [`UvMap`] gives.
#[derive(Clone, Debug)]
pub struct AlphaChannel {
    /// The image (alpha 1 everywhere if it has no alpha channel).
    pub image: Arc<ImageTexture>,
    /// How it is filtered and wrapped.
    pub sampling: Sampling,
    /// Which coordinates it is read at.
    pub map: Box<UvMap>,
}

impl AlphaChannel {
    /// The alpha at `uv`.
    #[inline]
    pub fn eval(&self, uv: TexCoords) -> f32 {
        self.image.sample_alpha(self.map.apply(uv), self.sampling)
    }
}

impl PartialEq for AlphaChannel {
    /// Images compare by identity, as in [`Texture`].
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.image, &other.image)
            && self.sampling == other.sampling
            && self.map == other.map
    }
}

/// The textures of a `Pbr`'s layers; `None` where the factor holds everywhere.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LayerMaps {
    /// Alpha scales [`Layers::specular`].
    pub specular: Option<AlphaChannel>,
    /// RGB (decoded from sRGB) scales [`Layers::specular_color`].
    pub specular_color: Option<Texture>,
    /// RGB (decoded from sRGB) scales [`Layers::sheen_color`].
    pub sheen_color: Option<Texture>,
    /// Alpha scales [`Layers::sheen_roughness`].
    pub sheen_roughness: Option<AlphaChannel>,
    /// Red scales [`Layers::clearcoat`].
    pub clearcoat: Option<Texture>,
    /// Green scales [`Layers::clearcoat_roughness`].
    pub clearcoat_roughness: Option<Texture>,
}

impl LayerMaps {
    /// Whether no texture is set (such maps are left out of a material).
    pub fn is_empty(&self) -> bool {
        *self == Self::default()
    }

    /// The layers `factors` at `uv`: each factor times its texture's part there. Out of line:
    /// only materials with such textures get here.
    #[inline(never)]
    pub fn at(&self, factors: &Layers, uv: TexCoords) -> Layers {
        let mut l = *factors;
        if let Some(t) = &self.specular {
            l.specular *= t.eval(uv);
        }
        if let Some(t) = &self.specular_color {
            l.specular_color *= t.eval(uv);
        }
        if let Some(t) = &self.sheen_color {
            l.sheen_color *= t.eval(uv);
        }
        if let Some(t) = &self.sheen_roughness {
            l.sheen_roughness *= t.eval(uv);
        }
        if let Some(t) = &self.clearcoat {
            l.clearcoat *= t.eval(uv).x;
        }
        if let Some(t) = &self.clearcoat_roughness {
            l.clearcoat_roughness *= t.eval(uv).y;
        }
        l
    }

    /// Each texture set, for tools that list or describe them (export): the factor it scales,
    /// the part of its texel it reads (`"rgb"`, `"r"`, `"g"`, `"a"`) and the texture (an alpha
    /// channel as its image read through its map).
    pub fn channels(&self) -> Vec<(&'static str, &'static str, Texture)> {
        let alpha = |a: &AlphaChannel| {
            Texture::Mapped(
                Box::new(Texture::Image(a.image.clone(), a.sampling)),
                a.map.clone(),
            )
        };
        [
            ("specular", "a", self.specular.as_ref().map(alpha)),
            ("specular_color", "rgb", self.specular_color.clone()),
            ("sheen_color", "rgb", self.sheen_color.clone()),
            (
                "sheen_roughness",
                "a",
                self.sheen_roughness.as_ref().map(alpha),
            ),
            ("clearcoat", "r", self.clearcoat.clone()),
            ("clearcoat_roughness", "g", self.clearcoat_roughness.clone()),
        ]
        .into_iter()
        .filter_map(|(name, channel, t)| t.map(|t| (name, channel, t)))
        .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Vec2, Vec3};

    #[test]
    fn each_texture_scales_its_factor_by_its_channel() {
        // One texel: linear RGB (0.25, 0.5, 0.75), alpha 0.2 (51/255).
        let image = Arc::new(ImageTexture::from_rgba8(1, 1, &[64, 128, 191, 51], false));
        let rgb = Texture::Image(image.clone(), Sampling::default());
        let alpha = AlphaChannel {
            image,
            sampling: Sampling::default(),
            map: Box::default(),
        };
        let maps = LayerMaps {
            specular: Some(alpha.clone()),
            specular_color: Some(rgb.clone()),
            sheen_color: Some(rgb.clone()),
            sheen_roughness: Some(alpha),
            clearcoat: Some(rgb.clone()),
            clearcoat_roughness: Some(rgb.clone()),
        };
        let factors = Layers {
            specular: 0.5,
            specular_color: Vec3::new(2.0, 1.0, 1.0),
            sheen_color: Vec3::ONE,
            sheen_roughness: 1.0,
            clearcoat: 1.0,
            clearcoat_roughness: 0.5,
        };
        let texel = Vec3::new(64.0, 128.0, 191.0) / 255.0;
        let a = 51.0 / 255.0;
        let l = maps.at(&factors, Vec2::splat(0.5).into());
        let near = |x: f32, y: f32| (x - y).abs() < 1e-6;
        assert!(near(l.specular, 0.5 * a), "{l:?}");
        assert!((l.specular_color - Vec3::new(2.0, 1.0, 1.0) * texel).length() < 1e-6);
        assert!((l.sheen_color - texel).length() < 1e-6);
        assert!(near(l.sheen_roughness, a));
        assert!(near(l.clearcoat, texel.x));
        assert!(near(l.clearcoat_roughness, 0.5 * texel.y));
        assert!(LayerMaps::default().is_empty() && !maps.is_empty());
    }
}
