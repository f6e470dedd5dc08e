//! Which `TEXCOORD_n` sets a primitive carries: those its material's textures read, at most
//! two. A mesh holds its first set in [`MeshData::uvs`](crate::model::MeshData::uvs) and a
//! second one in [`MeshData::uvs1`](crate::model::MeshData::uvs1) only when the material reads
//! two, so a file pays for the sets it uses: a material that reads only `TEXCOORD_1` costs what
//! one reading `TEXCOORD_0` does.

use super::data::{GltfMaterial, GltfTexture};

/// Most sets a primitive carries (the slots of [`crate::shading::texture::TexCoords`]).
pub const MAX_UV_SETS: usize = 2;

impl GltfMaterial {
    /// The textures rondo reads, with their names in the material.
    pub fn textures(&self) -> impl Iterator<Item = (&'static str, &GltfTexture)> {
        [
            ("baseColorTexture", self.base_color_texture.as_ref()),
            (
                "metallicRoughnessTexture",
                self.metallic_roughness_texture.as_ref(),
            ),
            (
                "normalTexture",
                self.normal_texture.as_ref().map(|(t, _)| t),
            ),
            ("emissiveTexture", self.emissive_texture.as_ref()),
            ("transmissionTexture", self.transmission_texture.as_ref()),
        ]
        .into_iter()
        .chain(self.layer_textures.slots())
        .filter_map(|(name, t)| t.map(|t| (name, t)))
    }

    /// The sets the material's textures read, ascending, each once: the first
    /// [`MAX_UV_SETS`] are what its primitives carry. Empty without textures (the primitive
    /// then carries `TEXCOORD_0`, as texture-less materials never read it).
    pub fn uv_sets(&self) -> Vec<u32> {
        let mut sets: Vec<u32> = self.textures().map(|(_, t)| t.texcoord).collect();
        sets.sort_unstable();
        sets.dedup();
        sets
    }

    /// The slot of the primitive's sets that texture `t` reads (its set's place in
    /// [`GltfMaterial::uv_sets`]); `None` for a set beyond the [`MAX_UV_SETS`] carried.
    pub fn uv_slot(&self, t: &GltfTexture) -> Option<usize> {
        self.uv_sets()
            .iter()
            .position(|&s| s == t.texcoord)
            .filter(|&k| k < MAX_UV_SETS)
    }
}
