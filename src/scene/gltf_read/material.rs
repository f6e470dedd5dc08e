//! glTF metallic–roughness materials and their textures, each factor checked to be in range.

use glam::Vec3;

use super::data::{AlphaMode, GltfMaterial, GltfTexture};
use super::field::check_field;
use super::layers::read_layers;
use super::texture_ref::texture;
use super::texture_transform;

/// A `textureInfo` (or the normal texture's) read by [`texture`]; `field` is its name in the
/// material.
fn info(
    what: &dyn Fn() -> String,
    field: &str,
    tex: &gltf::Texture,
    texcoord: u32,
    ext: Option<&gltf::json::Value>,
) -> Result<GltfTexture, String> {
    texture(tex, texcoord, ext, &|| format!("{}: {field}", what()))
}

/// Reads material `m` of `doc`, checking its factors against the spec's ranges.
pub(super) fn read_material(
    doc: &gltf::Document,
    m: &gltf::Material,
) -> Result<GltfMaterial, String> {
    let pbr = m.pbr_metallic_roughness();
    let name = m.name().map(str::to_owned);
    let what = || match (&name, m.index()) {
        (Some(n), Some(i)) => format!("material \"{n}\" (materials[{i}])"),
        (None, Some(i)) => format!("materials[{i}]"),
        (_, None) => "default material".into(),
    };
    let unit = 0.0..=1.0;
    let any = f32::NEG_INFINITY..=f32::INFINITY;
    let at_least_0 = 0.0..=f32::INFINITY;
    for (k, v) in pbr.base_color_factor().into_iter().enumerate() {
        let field = format!("pbrMetallicRoughness.baseColorFactor[{k}]");
        check_field(&what, &field, v, unit.clone())?;
    }
    let metallic = pbr.metallic_factor();
    check_field(
        &what,
        "pbrMetallicRoughness.metallicFactor",
        metallic,
        unit.clone(),
    )?;
    let roughness = pbr.roughness_factor();
    check_field(
        &what,
        "pbrMetallicRoughness.roughnessFactor",
        roughness,
        unit.clone(),
    )?;
    for (k, v) in m.emissive_factor().into_iter().enumerate() {
        check_field(&what, &format!("emissiveFactor[{k}]"), v, unit.clone())?;
    }
    let strength = m.emissive_strength().unwrap_or(1.0);
    let field = "extensions.KHR_materials_emissive_strength.emissiveStrength";
    check_field(&what, field, strength, at_least_0.clone())?;
    let emissive = Vec3::from(m.emissive_factor()) * strength;
    if !emissive.is_finite() {
        return Err(format!(
            "{}: emissiveFactor × emissiveStrength is not finite",
            what()
        ));
    }
    let transmission = m.transmission().map_or(0.0, |t| t.transmission_factor());
    let field = "extensions.KHR_materials_transmission.transmissionFactor";
    check_field(&what, field, transmission, unit.clone())?;
    let ior = m.ior().unwrap_or(1.5);
    if !(ior.is_finite() && ior > 0.0) {
        return Err(format!(
            "{}: extensions.KHR_materials_ior.ior is {ior}, must be finite and above 0",
            what()
        ));
    }
    let volume = m.volume();
    let thickness = volume.as_ref().map_or(0.0, |v| v.thickness_factor());
    let field = "extensions.KHR_materials_volume.thicknessFactor";
    check_field(&what, field, thickness, at_least_0.clone())?;
    let attenuation_color = volume.as_ref().map_or([1.0; 3], |v| v.attenuation_color());
    for (k, v) in attenuation_color.into_iter().enumerate() {
        let field = format!("extensions.KHR_materials_volume.attenuationColor[{k}]");
        check_field(&what, &field, v, unit.clone())?;
    }
    let attenuation_distance = volume
        .as_ref()
        .map_or(f32::INFINITY, |v| v.attenuation_distance());
    // The spec's default is +∞ (no absorption), which JSON cannot write: only that is infinite.
    if attenuation_distance.is_nan() || attenuation_distance <= 0.0 {
        return Err(format!(
            "{}: extensions.KHR_materials_volume.attenuationDistance is {attenuation_distance}, must be above 0",
            what()
        ));
    }
    if let Some(t) = m.normal_texture() {
        check_field(&what, "normalTexture.scale", t.scale(), any)?;
    }
    if let Some(cutoff) = m.alpha_cutoff() {
        check_field(&what, "alphaCutoff", cutoff, at_least_0)?;
    }
    let (layers, layer_textures, layer_notes) = read_layers(doc, m, &what)?;
    let alpha_mode = match m.alpha_mode() {
        gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
        gltf::material::AlphaMode::Mask => AlphaMode::Mask(m.alpha_cutoff().unwrap_or(0.5)),
        gltf::material::AlphaMode::Blend => AlphaMode::Blend,
    };
    let ext = texture_transform::NAME;
    let textured = |field: &str, t: Option<gltf::texture::Info>| {
        t.map(|t| {
            info(
                &what,
                field,
                &t.texture(),
                t.tex_coord(),
                t.extension_value(ext),
            )
        })
        .transpose()
    };
    Ok(GltfMaterial {
        base_color_factor: pbr.base_color_factor(),
        base_color_texture: textured(
            "pbrMetallicRoughness.baseColorTexture",
            pbr.base_color_texture(),
        )?,
        metallic,
        roughness,
        metallic_roughness_texture: textured(
            "pbrMetallicRoughness.metallicRoughnessTexture",
            pbr.metallic_roughness_texture(),
        )?,
        normal_texture: m
            .normal_texture()
            .map(|t| {
                let tex = info(
                    &what,
                    "normalTexture",
                    &t.texture(),
                    t.tex_coord(),
                    t.extension_value(ext),
                )?;
                Ok::<_, String>((tex, t.scale()))
            })
            .transpose()?,
        emissive,
        emissive_texture: textured("emissiveTexture", m.emissive_texture())?,
        alpha_mode,
        double_sided: m.double_sided(),
        transmission,
        transmission_texture: textured(
            "extensions.KHR_materials_transmission.transmissionTexture",
            m.transmission().and_then(|t| t.transmission_texture()),
        )?,
        ior,
        thickness,
        attenuation_color: Vec3::from(attenuation_color),
        attenuation_distance,
        layers,
        layer_textures,
        layer_notes,
        name,
    })
}
