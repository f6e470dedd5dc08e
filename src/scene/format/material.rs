//! Materials and textures as written.

use glam::Vec3;
use serde::Deserialize;

use super::number::{Color, NonNegative, Positive, Real, UnitColor, UnitInterval};
use crate::shading::texture::{Filter, Wrap};

/// A texture: wherever a colour is expected.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum TextureDesc {
    /// `Constant((r, g, b))`.
    Constant(Color),
    /// `Checker(scale, even, odd)`: `even` where `sin(scale·u)·sin(scale·v) > 0`.
    Checker {
        /// Frequency k.
        scale: Real,
        /// Texture of the positive cells.
        even: Box<TextureDesc>,
        /// Texture of the other cells.
        odd: Box<TextureDesc>,
    },
    /// `Image(path: "file.png", filter: Nearest, wrap: Clamp)`, relative to the scene file.
    Image {
        /// Path to a PNG file.
        path: String,
        /// `Nearest` (the default) or `Bilinear`.
        #[serde(default)]
        filter: Filter,
        /// `Clamp` (the default), `Repeat` or `MirroredRepeat`.
        #[serde(default)]
        wrap: Wrap,
    },
}

/// A material.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum MaterialDesc {
    /// `Diffuse(albedo)`.
    Diffuse {
        /// Reflectance.
        albedo: TextureDesc,
    },
    /// `Metal(albedo, roughness)`; roughness is clamped to [0, 1].
    Metal {
        /// Reflectance.
        albedo: TextureDesc,
        /// Fuzz.
        #[serde(default = "zero")]
        roughness: Real,
    },
    /// `Glossy(albedo, roughness)`: GGX microfacet reflection; roughness is clamped to
    /// [0.01, 1].
    Glossy {
        /// Reflectance at normal incidence.
        albedo: TextureDesc,
        /// Roughness; GGX α = roughness².
        roughness: Real,
    },
    /// `Dielectric(ior, roughness, attenuation_color, attenuation_distance)`: glass, smooth by
    /// default; with both attenuation fields, tinted through its thickness (white light turns
    /// `attenuation_color` after `attenuation_distance` inside, as `KHR_materials_volume`).
    Dielectric {
        /// Index of refraction.
        ior: Positive,
        /// Perceptual roughness in [0, 1]; GGX α = roughness² (default 0: smooth).
        #[serde(default = "unit_zero")]
        roughness: UnitInterval,
        /// The colour white light turns into after `attenuation_distance` inside, each channel
        /// in [0, 1] (default white: no absorption).
        #[serde(default)]
        attenuation_color: Option<UnitColor>,
        /// The distance at which light inside has `attenuation_color` (default: infinite, no
        /// absorption).
        #[serde(default)]
        attenuation_distance: Option<Positive>,
    },
    /// `Light(emit, intensity, two_sided)`.
    Light {
        /// Emitted colour.
        emit: TextureDesc,
        /// Scale of `emit`.
        #[serde(default = "one")]
        intensity: NonNegative,
        /// Emit on both sides.
        #[serde(default)]
        two_sided: bool,
    },
    /// `Pbr(base_color, metallic, roughness, emissive, emissive_strength, normal_map,
    /// alpha_cutoff, specular, specular_color, sheen_color, sheen_roughness, clearcoat,
    /// clearcoat_roughness)`: the glTF 2.0 metallic–roughness material, with glTF's defaults
    /// (base colour 1, metallic 1, roughness 1, no emission, strength 1, no normal map, no mask,
    /// specular 1 and white, no sheen, no clear coat).
    Pbr {
        /// Base colour.
        #[serde(default = "white")]
        base_color: TextureDesc,
        /// Metalness in [0, 1].
        #[serde(default = "unit_one")]
        metallic: UnitInterval,
        /// Perceptual roughness in [0, 1]; GGX α = roughness² (at least 0.01²).
        #[serde(default = "unit_one")]
        roughness: UnitInterval,
        /// Emitted colour.
        #[serde(default = "black")]
        emissive: TextureDesc,
        /// Scale of `emissive`.
        #[serde(default = "one")]
        emissive_strength: NonNegative,
        /// Tangent-space normal map (none by default).
        #[serde(default)]
        normal_map: Option<NormalMapDesc>,
        /// Alpha mask (glTF's `alphaMode: MASK`): where the alpha of the `base_color` image is
        /// below this cutoff the surface is absent and rays pass through it. No mask by default.
        #[serde(default)]
        alpha_cutoff: Option<NonNegative>,
        /// Strength of the dielectric specular lobe in [0, 1] (`KHR_materials_specular`'s
        /// `specularFactor`; default 1).
        #[serde(default = "unit_one")]
        specular: UnitInterval,
        /// Colour of the dielectric specular lobe: its reflectance at normal incidence is
        /// `min(0.04 · colour, 1)` (`specularColorFactor`; default white).
        #[serde(default = "white_color")]
        specular_color: Color,
        /// Colour of a sheen layer over the material, each channel in [0, 1]
        /// (`KHR_materials_sheen`'s `sheenColorFactor`; default black: none).
        #[serde(default = "black_color")]
        sheen_color: UnitColor,
        /// Perceptual roughness of the sheen in [0, 1] (`sheenRoughnessFactor`; default 0, taken
        /// as the lobe's smallest, 0.05).
        #[serde(default = "unit_zero")]
        sheen_roughness: UnitInterval,
        /// Strength of a clear coat in [0, 1] (`KHR_materials_clearcoat`'s `clearcoatFactor`;
        /// default 0: none).
        #[serde(default = "unit_zero")]
        clearcoat: UnitInterval,
        /// Perceptual roughness of the clear coat in [0, 1] (default 0: a mirror).
        #[serde(default = "unit_zero")]
        clearcoat_roughness: UnitInterval,
    },
}

/// `NormalMap(path: "n.png", scale: 1.0, filter: Nearest, wrap: Clamp)`: a tangent-space normal
/// map, relative to the scene file, decoded as linear data; the texel's RGB encodes the normal
/// `2·rgb − 1` in the frame (tangent ∂p/∂u, bitangent, shading normal), x and y scaled by
/// `scale`; green points towards the image's top (OpenGL's convention, glTF's). Tangents come
/// from the triangles' texture coordinates, so it acts on triangles, quads, boxes and meshes
/// with texture coordinates, not on spheres and planes.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, rename = "NormalMap")]
pub struct NormalMapDesc {
    /// Path to an image file.
    pub path: String,
    /// Scale of the map's x and y (1, the default, as drawn; 0 flattens it).
    #[serde(default = "one_real")]
    pub scale: Real,
    /// `Nearest` (the default) or `Bilinear`.
    #[serde(default)]
    pub filter: Filter,
    /// `Clamp` (the default), `Repeat` or `MirroredRepeat`.
    #[serde(default)]
    pub wrap: Wrap,
}

fn one_real() -> Real {
    Real(1.0)
}

fn white() -> TextureDesc {
    TextureDesc::Constant(Color(Vec3::ONE))
}

fn white_color() -> Color {
    Color(Vec3::ONE)
}

fn black_color() -> UnitColor {
    UnitColor(Vec3::ZERO)
}

fn black() -> TextureDesc {
    TextureDesc::Constant(Color(Vec3::ZERO))
}

fn unit_one() -> UnitInterval {
    UnitInterval(1.0)
}

fn unit_zero() -> UnitInterval {
    UnitInterval(0.0)
}

fn zero() -> Real {
    Real(0.0)
}

fn one() -> NonNegative {
    NonNegative(1.0)
}
