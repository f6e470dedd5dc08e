//! glTF's transmissive materials as rondo's glass: `KHR_materials_transmission` (its factor; the
//! roughness is the material's own roughness factor, as the extension says),
//! `KHR_materials_ior` and `KHR_materials_volume` (attenuation colour and distance) become a
//! [`Material::Dielectric`]; what rondo's glass cannot show comes back as notes for warnings.
//!
//! How this differs from the extensions:
//! - the spec mixes the transmissive lobe with the opaque one by `transmission × (1 −
//!   metallic)`; rondo has no such mix, so a material is glass where that weight is at least
//!   0.5 and opaque below (the nearer of the two), with a note when the weight is strictly
//!   between 0 and 1;
//! - transmission, thickness and metallic–roughness textures are not read (the factors are);
//! - the base colour does not tint the transmitted light (the volume's attenuation does);
//! - every glass surface is a volume boundary: a thin-walled material (`thicknessFactor` 0, the
//!   volume extension's default) refracts as solid glass and absorbs nothing; with a thickness
//!   above 0 the attenuation applies inside the closed mesh, whatever the thickness's value.

use glam::Vec3;

use crate::scene::gltf_read::GltfMaterial;
use crate::shading::material::{Material, absorption_coefficient};

/// What a glTF material's transmission makes of it.
#[derive(Debug, PartialEq)]
pub(super) enum Transmission {
    /// Opaque: the metallic–roughness material, with a note if transmission was dropped.
    Opaque(Option<String>),
    /// Glass, with notes on what of the file it does not show.
    Glass(Box<Material>, Vec<String>),
}

/// The transmission of glTF material `m`.
pub(super) fn transmission(m: &GltfMaterial) -> Transmission {
    let weight = m.transmission * (1.0 - m.metallic);
    if weight <= 0.0 {
        return Transmission::Opaque(None);
    }
    if weight < 0.5 {
        return Transmission::Opaque(Some(format!(
            "transmission {} × (1 − metallic {}) = {weight} is below 0.5: rendered opaque \
             (rondo does not mix glass with the opaque material)",
            m.transmission, m.metallic
        )));
    }
    let mut notes = Vec::new();
    if weight < 1.0 {
        notes.push(format!(
            "transmission {} × (1 − metallic {}) = {weight} is rendered as full transmission \
             (rondo does not mix glass with the opaque material)",
            m.transmission, m.metallic
        ));
    }
    if m.transmission_texture {
        notes.push("transmissionTexture is ignored".into());
    }
    if m.metallic_roughness_texture.is_some() {
        notes.push(format!(
            "metallicRoughnessTexture is ignored: the glass has roughness {}",
            m.roughness
        ));
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
        notes.push("normalTexture is ignored on glass".into());
    }
    let absorbs = m.attenuation_distance.is_finite() && m.attenuation_color != Vec3::ONE;
    let absorption = if m.thickness > 0.0 {
        absorption_coefficient(m.attenuation_color, m.attenuation_distance)
    } else {
        if absorbs {
            notes.push(
                "KHR_materials_volume with thicknessFactor 0 is thin-walled: no absorption \
                 (rondo renders it as solid glass)"
                    .into(),
            );
        }
        Vec3::ZERO
    };
    Transmission::Glass(
        Box::new(Material::Dielectric {
            ior: m.ior,
            roughness: m.roughness,
            absorption,
        }),
        notes,
    )
}
