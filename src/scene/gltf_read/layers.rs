//! The material extensions that add to the metallic–roughness model: `KHR_materials_specular`,
//! `KHR_materials_sheen` and `KHR_materials_clearcoat` read into [`Layers`] (their factors) and
//! [`GltfLayerTextures`] (their textures, each a `textureInfo` read as the core material's are:
//! `texCoord` and `KHR_texture_transform` included), each value checked against the spec's
//! range, a value of the wrong type an error naming its field. The coat's normal texture is not
//! read: a note says what will look wrong.

use std::ops::RangeInclusive;

use glam::Vec3;
use gltf::json::Value;

use super::data::{GltfLayerTextures, GltfTexture};
use super::field::check_field;
use super::texture_ref::texture;
use super::texture_transform;
use crate::shading::layers::Layers;

/// `KHR_materials_specular`.
pub(super) const SPECULAR: &str = "KHR_materials_specular";
/// `KHR_materials_sheen`.
pub(super) const SHEEN: &str = "KHR_materials_sheen";
/// `KHR_materials_clearcoat`.
pub(super) const CLEARCOAT: &str = "KHR_materials_clearcoat";

/// One extension's object in a material: its name and value.
struct Extension<'a> {
    name: &'static str,
    value: &'a serde_json::Map<String, Value>,
}

impl Extension<'_> {
    /// The number `key` (`default` when absent), within `range`.
    fn number(
        &self,
        what: &dyn Fn() -> String,
        key: &str,
        default: f32,
        range: RangeInclusive<f32>,
    ) -> Result<f32, String> {
        let field = format!("extensions.{}.{key}", self.name);
        let v = match self.value.get(key) {
            None => return Ok(default),
            Some(v) => v
                .as_f64()
                .ok_or_else(|| format!("{}: {field} is not a number", what()))?,
        };
        check_field(what, &field, v as f32, range)?;
        Ok(v as f32)
    }

    /// The three numbers `key` (`default` when absent), each within `range`.
    fn vec3(
        &self,
        what: &dyn Fn() -> String,
        key: &str,
        default: Vec3,
        range: RangeInclusive<f32>,
    ) -> Result<Vec3, String> {
        let field = format!("extensions.{}.{key}", self.name);
        let Some(v) = self.value.get(key) else {
            return Ok(default);
        };
        let not_three = || format!("{}: {field} is not an array of 3 numbers", what());
        let items = v
            .as_array()
            .filter(|a| a.len() == 3)
            .ok_or_else(not_three)?;
        let mut out = [0.0f32; 3];
        for (k, (o, item)) in out.iter_mut().zip(items).enumerate() {
            let x = item.as_f64().ok_or_else(not_three)? as f32;
            check_field(what, &format!("{field}[{k}]"), x, range.clone())?;
            *o = x;
        }
        Ok(Vec3::from(out))
    }

    /// The `textureInfo` `key` of the extension, if it names one: its texture (an index into
    /// `doc`'s), `texCoord` and transform.
    fn texture(
        &self,
        doc: &gltf::Document,
        what: &dyn Fn() -> String,
        key: &str,
    ) -> Result<Option<GltfTexture>, String> {
        let Some(v) = self.value.get(key) else {
            return Ok(None);
        };
        let field = format!("extensions.{}.{key}", self.name);
        let info = v
            .as_object()
            .ok_or_else(|| format!("{}: {field} is not an object", what()))?;
        let count = doc.textures().len();
        let index = info.get("index").and_then(Value::as_u64);
        let tex = index
            .and_then(|i| usize::try_from(i).ok())
            .and_then(|i| doc.textures().nth(i))
            .ok_or_else(|| {
                format!(
                    "{}: {field}.index is {}, must name one of the file's {count} textures",
                    what(),
                    info.get("index").map_or("missing".into(), Value::to_string),
                )
            })?;
        let texcoord = match info.get("texCoord") {
            None => 0,
            Some(v) => v
                .as_u64()
                .and_then(|n| u32::try_from(n).ok())
                .ok_or_else(|| {
                    format!(
                        "{}: {field}.texCoord is {v}, must be an integer ≥ 0",
                        what()
                    )
                })?,
        };
        let ext = info
            .get("extensions")
            .and_then(|e| e.get(texture_transform::NAME));
        texture(&tex, texcoord, ext, &|| format!("{}: {field}", what())).map(Some)
    }

    /// A note for texture `key` if the extension names one: not read, and what that changes.
    fn unread_texture(&self, key: &str, consequence: &str, notes: &mut Vec<String>) {
        if self.value.contains_key(key) {
            notes.push(format!(
                "extensions.{}.{key} is ignored: {consequence}",
                self.name
            ));
        }
    }
}

/// The extension `name` of material `m`, if it has it; an error if it is not a JSON object.
fn extension<'a>(
    m: &'a gltf::Material,
    what: &dyn Fn() -> String,
    name: &'static str,
) -> Result<Option<Extension<'a>>, String> {
    m.extension_value(name)
        .map(|v| {
            v.as_object()
                .map(|value| Extension { name, value })
                .ok_or_else(|| format!("{}: extensions.{name} is not an object", what()))
        })
        .transpose()
}

/// The specular, sheen and clear coat layers of material `m` of `doc` (`what` names it in
/// errors), their textures, and a note for what of them is not read.
pub(super) fn read_layers(
    doc: &gltf::Document,
    m: &gltf::Material,
    what: &dyn Fn() -> String,
) -> Result<(Layers, GltfLayerTextures, Vec<String>), String> {
    let mut layers = Layers::NONE;
    let mut textures = GltfLayerTextures::default();
    let mut notes = Vec::new();
    let unit = 0.0..=1.0;
    if let Some(ext) = extension(m, what, SPECULAR)? {
        layers.specular = ext.number(what, "specularFactor", 1.0, unit.clone())?;
        layers.specular_color =
            ext.vec3(what, "specularColorFactor", Vec3::ONE, 0.0..=f32::INFINITY)?;
        textures.specular = ext.texture(doc, what, "specularTexture")?;
        textures.specular_color = ext.texture(doc, what, "specularColorTexture")?;
    }
    if let Some(ext) = extension(m, what, SHEEN)? {
        layers.sheen_color = ext.vec3(what, "sheenColorFactor", Vec3::ZERO, unit.clone())?;
        layers.sheen_roughness = ext.number(what, "sheenRoughnessFactor", 0.0, unit.clone())?;
        textures.sheen_color = ext.texture(doc, what, "sheenColorTexture")?;
        textures.sheen_roughness = ext.texture(doc, what, "sheenRoughnessTexture")?;
    }
    if let Some(ext) = extension(m, what, CLEARCOAT)? {
        layers.clearcoat = ext.number(what, "clearcoatFactor", 0.0, unit.clone())?;
        layers.clearcoat_roughness = ext.number(what, "clearcoatRoughnessFactor", 0.0, unit)?;
        textures.clearcoat = ext.texture(doc, what, "clearcoatTexture")?;
        textures.clearcoat_roughness = ext.texture(doc, what, "clearcoatRoughnessTexture")?;
        ext.unread_texture(
            "clearcoatNormalTexture",
            "the coat follows the base's normal (and its normal map)",
            &mut notes,
        );
        if layers.clearcoat > 0.0 && m.normal_texture().is_some() {
            notes.push(format!(
                "extensions.{CLEARCOAT}: the coat follows the base's normal map, where the spec keeps it smooth"
            ));
        }
    }
    Ok((layers, textures, notes))
}
