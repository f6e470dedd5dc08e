//! A glTF texture reference read into a [`GltfTexture`]: its image, sampler and
//! `KHR_texture_transform`.

use super::data::{GltfTexture, Wrap};
use super::texture_transform;

/// A texture reference with its sampler, and its `KHR_texture_transform` from the reference's
/// extension value `ext` (`slot` names the reference in errors).
pub(super) fn texture(
    tex: &gltf::Texture,
    texcoord: u32,
    ext: Option<&gltf::json::Value>,
    slot: &dyn Fn() -> String,
) -> Result<GltfTexture, String> {
    use gltf::texture::{MagFilter, WrappingMode};
    let wrap = |w| match w {
        WrappingMode::Repeat => Wrap::Repeat,
        WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        WrappingMode::ClampToEdge => Wrap::ClampToEdge,
    };
    let sampler = tex.sampler();
    let transform = texture_transform::read(ext, slot)?;
    Ok(GltfTexture {
        image: tex.source().index(),
        texcoord: transform.and_then(|t| t.texcoord).unwrap_or(texcoord),
        transform: transform.map(|t| texture_transform::to_rondo_space(t.matrix)),
        wrap_s: wrap(sampler.wrap_s()),
        wrap_t: wrap(sampler.wrap_t()),
        nearest: sampler.mag_filter() == Some(MagFilter::Nearest),
    })
}
