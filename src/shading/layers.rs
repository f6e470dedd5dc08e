//! The optional parts of a `Pbr` material beyond glTF's core metallic–roughness model, as the
//! scene gives them: the dielectric specular lobe's strength and colour
//! (`KHR_materials_specular`, [`super::specular`]), a sheen (`KHR_materials_sheen`,
//! [`super::sheen`]) and a clear coat over it (`KHR_materials_clearcoat`, [`super::coat`]). The
//! default adds nothing: the plain material. No ECS here.

use glam::Vec3;

/// A `Pbr` material's specular strength and colour, its sheen and its clear coat.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Layers {
    /// `specularFactor` in [0, 1]: scales the dielectric specular lobe (1: glTF's default).
    pub specular: f32,
    /// `specularColorFactor`, each channel at least 0: tints the dielectric specular lobe's
    /// reflectance at normal incidence, `min(0.04 · colour, 1)` (white: glTF's default).
    pub specular_color: Vec3,
    /// `sheenColorFactor`, each channel in [0, 1]: colour of the sheen (black: none).
    pub sheen_color: Vec3,
    /// `sheenRoughnessFactor` in [0, 1]: the sheen's perceptual roughness (α = roughness²,
    /// at least [`super::sheen::ROUGHNESS_MIN`]).
    pub sheen_roughness: f32,
    /// `clearcoatFactor` in [0, 1]: strength of the clear coat (0: none).
    pub clearcoat: f32,
    /// `clearcoatRoughnessFactor` in [0, 1]: the coat's perceptual roughness (GGX α =
    /// roughness²; below [`super::microfacet::SPECULAR_ALPHA`] a perfect mirror).
    pub clearcoat_roughness: f32,
}

impl Default for Layers {
    fn default() -> Self {
        Self::NONE
    }
}

impl Layers {
    /// No specular change, no sheen and no coat.
    pub const NONE: Self = Self {
        specular: 1.0,
        specular_color: Vec3::ONE,
        sheen_color: Vec3::ZERO,
        sheen_roughness: 0.0,
        clearcoat: 0.0,
        clearcoat_roughness: 0.0,
    };
}
