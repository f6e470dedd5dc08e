//! The optional parts of a `Pbr` material beyond glTF's core metallic–roughness model, as the
//! scene gives them: the dielectric specular lobe's strength and colour
//! (`KHR_materials_specular`, [`super::specular`]) and a clear coat (`KHR_materials_clearcoat`,
//! [`super::coat`]). The default adds nothing: the plain material. No ECS here.

use glam::Vec3;

/// A `Pbr` material's specular strength and colour and its clear coat.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Layers {
    /// `specularFactor` in [0, 1]: scales the dielectric specular lobe (1: glTF's default).
    pub specular: f32,
    /// `specularColorFactor`, each channel at least 0: tints the dielectric specular lobe's
    /// reflectance at normal incidence, `min(0.04 · colour, 1)` (white: glTF's default).
    pub specular_color: Vec3,
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
    /// No specular change and no coat.
    pub const NONE: Self = Self {
        specular: 1.0,
        specular_color: Vec3::ONE,
        clearcoat: 0.0,
        clearcoat_roughness: 0.0,
    };
}
