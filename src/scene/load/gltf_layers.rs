//! The textures of a glTF material's layers (`KHR_materials_specular`, `KHR_materials_sheen`,
//! `KHR_materials_clearcoat`) loaded into [`LayerMaps`]: colours decoded from sRGB, the other
//! channels read as linear data, each through its sampler, set and transform as the core
//! material's textures are.

use std::path::Path;

use super::Expander;
use super::gltf_place::{mapped, uv_map};
use crate::scene::assets::{Encoding, GltfAsset};
use crate::scene::gltf_read::{GltfMaterial, GltfTexture};
use crate::shading::layer_maps::{AlphaChannel, LayerMaps};
use crate::shading::texture::Texture;

impl Expander<'_> {
    /// The layer textures of glTF material `m` of the file at `path` (`what` names the
    /// material in errors); `None` when it names none, so that its hits look nothing up.
    pub(super) fn gltf_layer_maps(
        &mut self,
        asset: &GltfAsset,
        path: &Path,
        m: &GltfMaterial,
        what: &str,
    ) -> Result<Option<Box<LayerMaps>>, String> {
        let t = &m.layer_textures;
        let colour = |x: &mut Self, t: &Option<GltfTexture>, encoding: Encoding| {
            t.as_ref()
                .map(|t| {
                    let (image, sampling) = x
                        .gltf_image(asset, path, t, encoding)
                        .map_err(|e| format!("{what}: {e}"))?;
                    Ok::<_, String>(mapped(Texture::Image(image, sampling), uv_map(m, t)))
                })
                .transpose()
        };
        let specular_color = colour(self, &t.specular_color, Encoding::Srgb)?;
        let sheen_color = colour(self, &t.sheen_color, Encoding::Srgb)?;
        let clearcoat = colour(self, &t.clearcoat, Encoding::Linear)?;
        let clearcoat_roughness = colour(self, &t.clearcoat_roughness, Encoding::Linear)?;
        // Alpha is linear whatever the encoding of the colour beside it.
        let alpha = |x: &mut Self, t: &Option<GltfTexture>| {
            t.as_ref()
                .map(|t| {
                    let (image, sampling) = x
                        .gltf_image(asset, path, t, Encoding::Linear)
                        .map_err(|e| format!("{what}: {e}"))?;
                    Ok::<_, String>(AlphaChannel {
                        image,
                        sampling,
                        map: uv_map(m, t),
                    })
                })
                .transpose()
        };
        let maps = LayerMaps {
            specular: alpha(self, &t.specular)?,
            specular_color,
            sheen_color,
            sheen_roughness: alpha(self, &t.sheen_roughness)?,
            clearcoat,
            clearcoat_roughness,
        };
        Ok((!maps.is_empty()).then(|| Box::new(maps)))
    }
}
