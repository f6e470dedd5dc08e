//! The warning for an extension a file uses that rondo does not read: one sentence naming the
//! extension and what will look wrong without it.

/// What is missing from the render when extension `ext` is ignored.
fn consequence(ext: &str) -> &'static str {
    match ext {
        "KHR_materials_clearcoat" => {
            "the clear coat is ignored: coated surfaces lose their sharp top reflection and show the base alone"
        }
        "KHR_materials_specular" => {
            "specular strength and colour are ignored: dielectric highlights keep the default 4 % white reflectance"
        }
        "KHR_materials_volume" => {
            "volume absorption is ignored: transmissive materials look clear instead of tinted by their thickness"
        }
        "KHR_materials_iridescence" => {
            "iridescence is ignored: thin-film colour shifts are missing"
        }
        "KHR_materials_anisotropy" => {
            "anisotropy is ignored: brushed highlights are round instead of stretched"
        }
        "KHR_materials_dispersion" => "dispersion is ignored: refractions show no colour fringes",
        "KHR_materials_diffuse_transmission" => {
            "diffuse transmission is ignored: thin translucent surfaces (leaves, paper) let no light through"
        }
        "KHR_materials_unlit" => {
            "unlit materials are shaded as lit metallic–roughness ones: they look darker and shaded"
        }
        "KHR_materials_pbrSpecularGlossiness" => {
            "specular–glossiness parameters are ignored: those materials show only their metallic–roughness fallback"
        }
        "KHR_materials_variants" => {
            "material variants are ignored: the default materials are shown"
        }
        "KHR_texture_basisu" | "EXT_texture_webp" | "EXT_texture_avif" | "MSFT_texture_dds" => {
            "textures only available in that format are not read: those materials lose them"
        }
        "KHR_draco_mesh_compression" | "EXT_meshopt_compression" => {
            "compressed geometry is not decoded: meshes that rely on it are missing or wrong"
        }
        "KHR_animation_pointer" => "animations are ignored: the rest pose is shown",
        "KHR_xmp_json_ld" | "KHR_xmp" => "metadata is ignored (nothing visible changes)",
        _ => "what it adds to the file is missing from the render",
    }
}

/// The warning for an ignored extension `ext`: its name, then what will look wrong.
pub(super) fn warning(ext: &str) -> String {
    format!("extension {ext} is ignored; {}", consequence(ext))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_warning_names_its_extension_and_a_consequence() {
        for ext in [
            "KHR_materials_clearcoat",
            "KHR_materials_anisotropy",
            "EXT_unknown",
        ] {
            let w = warning(ext);
            assert!(
                w.starts_with(&format!("extension {ext} is ignored; ")),
                "{w}"
            );
            assert!(w.len() > format!("extension {ext} is ignored; ").len() + 10);
        }
        assert!(warning("KHR_materials_anisotropy").contains("brushed"));
    }
}
