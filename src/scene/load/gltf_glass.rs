//! glTF's transmissive materials as rondo's glass: `KHR_materials_transmission` (its factor; the
//! roughness is the material's own roughness factor, as the extension says),
//! `KHR_materials_ior` and `KHR_materials_volume` (attenuation colour and distance) become a
//! [`Material::Dielectric`], alone where the material is fully transmissive, mixed with the
//! opaque metallic–roughness material where it is partly so ([`Material::Transmissive`]); what
//! rondo's glass cannot show comes back as notes for warnings.
//!
//! The spec's BSDF is mix(dielectric, metal, m) with dielectric = fresnel_mix(specular_brdf,
//! mix(diffuse, specular_btdf, t)), t the transmission and m the metalness. It splits exactly
//! into w · glass + (1 − w) · base with w = t·(1 − m), the glass being the specular reflection
//! plus the transmission of the same Fresnel, and the base the metallic–roughness material of
//! metalness m / (1 − w): the metal's share m and the diffuse's (1 − m)(1 − t), each with its
//! own part of the specular reflection, in proportion. So a material whose w is strictly
//! between 0 and 1 is the mix; w = 1 is glass alone, w = 0 the opaque material alone.
//!
//! A `transmissionTexture` (its red channel r, linear, read through its own `texCoord` and
//! `KHR_texture_transform`) makes t vary over the surface: w(x) = t·r(x)·(1 − m). The
//! material is then the mix wherever w > 0, even at w = 1, and the glass's share is lowered
//! point by point ([`crate::shading::material::TransmissionTexture`]): where r < 1 the share it
//! takes from the glass goes to the metallic–roughness material of metalness 0 (the spec's
//! dielectric), so the metal's share m and the base stay as without the texture, exactly.
//!
//! How this differs from the extensions:
//! - the weight's metalness m is the `metallicFactor`: the metallic–roughness texture scales
//!   the metalness of the opaque parts where they shade, not the glass's share; thickness and
//!   metallic–roughness textures are not read by the glass;
//! - the base colour does not tint the transmitted light (the volume's attenuation does);
//! - the glass part reflects with the exact Fresnel of its ior, the base's specular lobe with
//!   Schlick's, so the mix's reflection is the spec's only up to that difference;
//! - every glass surface is a volume boundary: a thin-walled material (`thicknessFactor` 0, the
//!   volume extension's default) refracts as solid glass and absorbs nothing, with a warning:
//!   through a single open surface (a pane of one quad) the light is bent and passes on
//!   1/ior² of the radiance behind it, where the spec's thin wall lets it through unbent;
//!   with a thickness above 0 the attenuation applies inside the closed mesh, whatever the
//!   thickness's value.

use glam::Vec3;

use crate::scene::gltf_read::GltfMaterial;
use crate::shading::material::{Material, absorption_coefficient};

/// What a glTF material's transmission makes of it.
#[derive(Debug, PartialEq)]
pub(super) enum Transmission {
    /// Opaque: the metallic–roughness material alone (no transmission).
    Opaque,
    /// Partly transmissive: glass with probability `weight` (strictly between 0 and 1; up to 1
    /// with a transmission texture, which then lowers it point by point), else the
    /// metallic–roughness material with metalness `base_metallic`.
    Mix {
        /// The glass component's probability, transmission × (1 − metallic).
        weight: f32,
        /// The glass component.
        glass: Box<Material>,
        /// The metalness of the opaque component, metallic / (1 − weight).
        base_metallic: f32,
        /// What of the file the glass component does not show.
        notes: Vec<String>,
    },
    /// Glass alone, with notes on what of the file it does not show.
    Glass(Box<Material>, Vec<String>),
}

/// The transmission of glTF material `m`.
pub(super) fn transmission(m: &GltfMaterial) -> Transmission {
    let weight = m.transmission * (1.0 - m.metallic);
    if weight <= 0.0 {
        return Transmission::Opaque;
    }
    // A texture may lower the transmission anywhere: the mix, even at weight 1.
    let mixed = weight < 1.0 || m.transmission_texture.is_some();
    let (glass, notes) = glass(m, mixed);
    if mixed {
        return Transmission::Mix {
            weight,
            glass,
            // m ≤ 1 − w, as w = t·(1 − m) ≤ 1 − m: at most 1. w = 1 only where m = 0.
            base_metallic: if weight < 1.0 {
                (m.metallic / (1.0 - weight)).min(1.0)
            } else {
                0.0
            },
            notes,
        };
    }
    Transmission::Glass(glass, notes)
}

/// The glass of glTF material `m`, and notes on what of the file it does not show (`mixed`: as
/// the transmitted part of a mix, whose opaque part shows the rest).
fn glass(m: &GltfMaterial, mixed: bool) -> (Box<Material>, Vec<String>) {
    let mut notes = Vec::new();
    if m.metallic_roughness_texture.is_some() {
        let share = if m.transmission_texture.is_some() {
            "transmissionTexture's red × "
        } else {
            ""
        };
        notes.push(if mixed {
            format!(
                "metallicRoughnessTexture does not reach the transmitted part: it has \
                 roughness {} and a share of {share}transmission {} × (1 − metallic {}) \
                 everywhere",
                m.roughness, m.transmission, m.metallic
            )
        } else {
            format!(
                "metallicRoughnessTexture is ignored: the glass has roughness {}",
                m.roughness
            )
        });
    }
    let tinted = m.base_color_factor[..3].iter().any(|&c| c != 1.0);
    if tinted || m.base_color_texture.is_some() {
        notes.push(
            "the base colour does not tint the transmitted light (KHR_materials_volume's \
             attenuation does)"
                .into(),
        );
    }
    if m.normal_texture.is_some() {
        notes.push(if mixed {
            "normalTexture is ignored by the transmitted part".into()
        } else {
            "normalTexture is ignored on glass".into()
        });
    }
    let absorbs = m.attenuation_distance.is_finite() && m.attenuation_color != Vec3::ONE;
    let absorption = if m.thickness > 0.0 {
        absorption_coefficient(m.attenuation_color, m.attenuation_distance)
    } else {
        // The spec's thin wall lets light through unbent and undimmed by the crossing; rondo's
        // glass is a volume boundary, so an open surface (a pane of one quad) bends the light
        // into a medium it never leaves and passes on only 1/ior² of the radiance behind it.
        notes.push(format!(
            "thin-walled glass (KHR_materials_volume's thicknessFactor is 0 or absent) renders \
             as solid glass{}: through a single open surface the light is bent and dimmed to \
             1/ior² = {:.2} of the spec's; model panes as closed solids with a thickness",
            if absorbs { " and absorbs nothing" } else { "" },
            1.0 / (m.ior * m.ior)
        ));
        Vec3::ZERO
    };
    let glass = Material::Dielectric {
        ior: m.ior,
        roughness: m.roughness,
        absorption,
    };
    (Box::new(glass), notes)
}
