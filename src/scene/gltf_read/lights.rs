//! The nodes' cameras and `KHR_lights_punctual` lights: read from the JSON once per file (the
//! lights' values checked there, so a bad light is an error naming its field), then listed
//! once per node instance with the node's composed transform.

use glam::Vec3;
use gltf::json::camera::Type as CameraType;
use gltf::json::extensions::scene::khr_lights_punctual::Type as LightType;
use gltf::json::validation::Checked;

use super::data::{GltfCamera, GltfLight, GltfLightKind, GltfProjection, GltfScene};

/// A camera of the file: its name and projection.
pub(super) type CameraEntry = (Option<String>, GltfProjection);

/// A light of the file: its name, colour, intensity and kind.
pub(super) type LightEntry = (Option<String>, Vec3, f32, GltfLightKind);

/// The file's cameras by index. The field of view is checked where a camera is used.
pub(super) fn read_cameras(doc: &gltf::Document) -> Result<Vec<CameraEntry>, String> {
    doc.as_json()
        .cameras
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let projection = match (&c.type_, &c.perspective) {
                (Checked::Valid(CameraType::Perspective), Some(p)) => GltfProjection::Perspective {
                    yfov: p.yfov,
                    aspect_ratio: p.aspect_ratio,
                },
                (Checked::Valid(CameraType::Orthographic), _) => GltfProjection::Orthographic,
                _ => {
                    return Err(format!(
                        "camera {i}: a perspective camera without `perspective` values"
                    ));
                }
            };
            Ok((c.name.clone(), projection))
        })
        .collect()
}

/// The file's `KHR_lights_punctual` lights by index, checked: colour and intensity finite and
/// ≥ 0, a spot's cone `0 ≤ innerConeAngle ≤ outerConeAngle ≤ π/2` (the spec asks for
/// `inner < outer`; equal angles are read as a hard edge).
pub(super) fn read_lights(doc: &gltf::Document) -> Result<Vec<LightEntry>, String> {
    let Some(lights) = doc
        .as_json()
        .extensions
        .as_ref()
        .and_then(|e| e.khr_lights_punctual.as_ref())
    else {
        return Ok(Vec::new());
    };
    lights
        .lights
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let what = match &l.name {
                Some(name) => format!("light {i} (\"{name}\")"),
                None => format!("light {i}"),
            };
            let colour = Vec3::from(l.color);
            if !(colour.is_finite() && colour.min_element() >= 0.0) {
                return Err(format!(
                    "{what}: color {:?} must be finite and >= 0",
                    l.color
                ));
            }
            if !(l.intensity.is_finite() && l.intensity >= 0.0) {
                return Err(format!(
                    "{what}: intensity {} must be finite and >= 0",
                    l.intensity
                ));
            }
            let kind = match (&l.type_, &l.spot) {
                (Checked::Valid(LightType::Directional), _) => GltfLightKind::Directional,
                (Checked::Valid(LightType::Point), _) => GltfLightKind::Point,
                (Checked::Valid(LightType::Spot), Some(spot)) => {
                    let (inner, outer) = (spot.inner_cone_angle, spot.outer_cone_angle);
                    crate::scene::format::check_cone(
                        &what,
                        ["spot.innerConeAngle", "spot.outerConeAngle"],
                        inner,
                        outer,
                        std::f32::consts::FRAC_PI_2,
                    )?;
                    GltfLightKind::Spot { inner, outer }
                }
                _ => return Err(format!("{what}: a spot light without `spot` values")),
            };
            Ok((l.name.clone(), colour, l.intensity, kind))
        })
        .collect()
}

/// Lists the cameras and lights of the scene's nodes, in node order, with their transforms.
pub(super) fn place_cameras_and_lights(
    scene: &mut GltfScene,
    cameras: &[CameraEntry],
    lights: &[LightEntry],
) {
    for node in &scene.nodes {
        if let Some((name, projection)) = node.camera.and_then(|c| cameras.get(c)) {
            scene.cameras.push(GltfCamera {
                node: node.index,
                node_name: node.name.clone(),
                name: name.clone(),
                world_from_camera: node.world_from_node,
                projection: *projection,
            });
        }
        if let Some((index, (name, colour, intensity, kind))) =
            node.light.and_then(|l| Some((l, lights.get(l)?)))
        {
            scene.lights.push(GltfLight {
                index,
                name: name.clone(),
                world_from_light: node.world_from_node,
                colour: *colour,
                intensity: *intensity,
                kind: *kind,
            });
        }
    }
}
