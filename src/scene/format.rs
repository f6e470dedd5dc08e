//! Serde mirror of the RON scene format. Values are validated while they are parsed, so a bad
//! value is reported at its own line and column by the RON parser, with the field it belongs to
//! and the entity or material it is part of ([`parse`]).

use std::collections::BTreeMap;
use std::path::Path;

use serde::Deserialize;
use serde::de::DeserializeOwned;

use crate::scene::error::SceneError;

mod camera;
mod light;
mod material;
mod number;
mod settings;
mod shape;
mod transform;

pub use camera::{CameraDesc, GltfCameraDesc, SceneCamera};
pub use light::{LightDesc, check_cone, checked_intensity};
pub use material::{MaterialDesc, NormalMapDesc, TextureDesc};
pub use number::{Color, Count, NonNegative, Positive, Real, UnitColor, UnitInterval, V3};
pub use settings::{
    EnvironmentDesc, MAX_COORDINATE, MAX_DEPTH, MAX_PIXELS, MAX_SIDE, MAX_SPP, Method,
    SettingsDesc, SunDesc,
};
pub use shape::ShapeDesc;
pub use transform::TransformDesc;
/// Parses the RON text `source` of the scene or prefab file `path`. RON's `implicit_some` is on,
/// so optional fields are written bare. An error names the field at fault and the entity or
/// material that holds it, from the path of the value being parsed when it failed.
pub fn parse<T: DeserializeOwned>(path: &Path, source: &str) -> Result<T, SceneError> {
    let options =
        ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
    let mut de = ron::Deserializer::from_str_with_options(source, &options)
        .map_err(|e| SceneError::from_ron(path, source, &e, &[]))?;
    match serde_path_to_error::deserialize(&mut de) {
        Ok(value) => {
            de.end()
                .map_err(|e| SceneError::from_ron(path, source, &de.span_error(e), &[]))?;
            Ok(value)
        }
        Err(e) => {
            let at: Vec<_> = e.path().iter().cloned().collect();
            let spanned = de.span_error(e.into_inner());
            Err(SceneError::from_ron(path, source, &spanned, &at))
        }
    }
}

/// The whole scene file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, rename = "Scene")]
pub struct SceneDesc {
    /// The camera: its own, or one of a placed glTF file.
    pub camera: SceneCamera,
    /// Image and sampling settings.
    #[serde(default)]
    pub settings: SettingsDesc,
    /// Point and spot lights, in world space.
    #[serde(default)]
    pub lights: Vec<LightDesc>,
    /// Named materials.
    #[serde(default)]
    pub materials: BTreeMap<String, MaterialDesc>,
    /// The objects.
    #[serde(default)]
    pub entities: Vec<EntityDesc>,
}

/// A prefab file: `Prefab(materials, entities)`, placed by scenes and other prefabs.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, rename = "Prefab")]
pub struct PrefabDesc {
    /// Default materials for the names the prefab uses; placements can map them to theirs.
    #[serde(default)]
    pub materials: BTreeMap<String, MaterialDesc>,
    /// The prefab's entities.
    #[serde(default)]
    pub entities: Vec<EntityDesc>,
}

/// `Entity(name, material, shape, transform)`, a prefab placement
/// `Entity(name, prefab, transform, materials)`, or a glTF placement
/// `Entity(name, gltf, transform, materials)`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, rename = "Entity")]
pub struct EntityDesc {
    /// Unique name among its siblings; defaults to `#<index>`.
    pub name: Option<String>,
    /// Name of a material (with `shape`).
    pub material: Option<String>,
    /// The shape (or `prefab`).
    pub shape: Option<ShapeDesc>,
    /// Path of a prefab file to place (or `shape`), relative to this file.
    pub prefab: Option<String>,
    /// Path of a glTF 2.0 file (`.gltf` or `.glb`) to place (or `shape`, or `prefab`),
    /// relative to this file: its default scene becomes entities named `<name>/<node>`.
    pub gltf: Option<String>,
    /// For a prefab or a glTF file: its material names mapped to names defined here.
    pub materials: Option<BTreeMap<String, String>>,
    /// Placement.
    pub transform: Option<TransformDesc>,
}
