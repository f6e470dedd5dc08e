//! The lights and cameras of a placed glTF file: `KHR_lights_punctual` points and spots become
//! the scene's punctual lights, a directional light its sun, and a camera the scene's camera
//! when `camera: Gltf(placement, camera)` asks for it; each placed by the placement's transform
//! times its node's.
//!
//! A directional light maps to rondo's `Sun` with the real sun's angular diameter (0.53°) and
//! the light's illuminance read as the irradiance on a plane facing it: a disk so small that it
//! lights as the spec's infinitely distant light does, and that mirrors and glossy surfaces
//! can reflect. A scene has one sun: a directional light is ignored with a warning when the
//! scene's settings give a sun or another directional light came first.

use std::path::Path;

use glam::{Affine3A, Vec3};

use super::{Anchor, Expander, SourceFile};
use crate::lights::punctual::PunctualLight;
use crate::scene::assets::GltfAsset;
use crate::scene::error::SceneError;
use crate::scene::format::{CameraDesc, GltfCameraDesc, SunDesc, checked_intensity};
use crate::scene::gltf_read::{GltfCamera, GltfLightKind, GltfProjection};

/// Angular diameter of the sun a directional light becomes, in degrees: the real sun's.
const DIRECTIONAL_SUN_DIAMETER: f32 = 0.53;

impl Expander<'_> {
    /// Adds the lights of the file at `full` placed by `world_from_file`: points and spots to
    /// the scene's lights, directional lights to the candidate suns.
    pub(super) fn place_gltf_lights(
        &mut self,
        full: &Path,
        asset: &GltfAsset,
        world_from_file: Affine3A,
    ) -> Result<(), String> {
        for light in &asset.scene.lights {
            let what = match &light.name {
                Some(name) => format!("light {} (\"{name}\")", light.index),
                None => format!("light {}", light.index),
            };
            let world = world_from_file * light.world_from_light;
            let position = world.transform_point3(Vec3::ZERO);
            // Along −z; the transform is invertible (checked with the nodes), so never zero.
            let axis = world.transform_vector3(Vec3::NEG_Z);
            let intensity = || checked_intensity(&what, position, light.colour, light.intensity);
            match light.kind {
                GltfLightKind::Point => self
                    .lights
                    .push(PunctualLight::point(position, intensity()?)),
                GltfLightKind::Spot { inner, outer } => self.lights.push(PunctualLight::spot(
                    position,
                    axis,
                    intensity()?,
                    inner,
                    outer,
                )),
                GltfLightKind::Directional => {
                    let irradiance = light.colour * light.intensity;
                    let radiance = crate::sky::Sun::radiance_for_irradiance(
                        irradiance,
                        DIRECTIONAL_SUN_DIAMETER.to_radians(),
                    );
                    if !radiance.is_finite() {
                        return Err(format!("{what}: the intensity is too large to represent"));
                    }
                    let sun = SunDesc {
                        direction: (-axis).normalize(),
                        angular_diameter: DIRECTIONAL_SUN_DIAMETER,
                        radiance,
                    };
                    self.suns
                        .push((sun, format!("{}: directional {what}", full.display())));
                }
            }
        }
        Ok(())
    }

    /// The scene's camera `desc` from the glTF placement it names, given the image size
    /// `width` × `height` (only to warn when the file's aspect ratio differs).
    pub(super) fn gltf_camera(
        &mut self,
        file: &SourceFile,
        desc: &GltfCameraDesc,
        width: u32,
        height: u32,
    ) -> Result<CameraDesc, SceneError> {
        let at = Anchor::Quoted(&desc.placement);
        let fail = |message: String| file.error(at, None, format!("camera: {message}"));
        let Some((asset, world_from_file, path)) = self.camera_source.take() else {
            let placed = if self.gltf_placements.is_empty() {
                "the scene places no glTF file".to_string()
            } else {
                format!("glTF placements: {}", self.gltf_placements.join(", "))
            };
            return Err(fail(format!(
                "no entity \"{}\" places a glTF file ({placed})",
                desc.placement
            )));
        };
        let cameras = &asset.scene.cameras;
        let named = |c: &&GltfCamera| {
            desc.camera.as_ref().is_none_or(|want| {
                c.node_name.as_ref() == Some(want) || c.name.as_ref() == Some(want)
            })
        };
        let found: Vec<&GltfCamera> = cameras.iter().filter(named).collect();
        let listed = || {
            let names: Vec<String> = cameras
                .iter()
                .map(|c| match (&c.node_name, &c.name) {
                    (Some(node), _) => format!("\"{node}\""),
                    (None, Some(camera)) => format!("\"{camera}\""),
                    (None, None) => format!("node {}", c.node),
                })
                .collect();
            if names.is_empty() {
                "it has none".to_string()
            } else {
                format!("its cameras: {}", names.join(", "))
            }
        };
        let camera = match (found.as_slice(), &desc.camera) {
            ([one], _) => *one,
            ([], Some(want)) => {
                return Err(fail(format!(
                    "{} has no camera named \"{want}\" in its default scene ({})",
                    path.display(),
                    listed()
                )));
            }
            ([], None) => {
                return Err(fail(format!(
                    "{} has no camera in its default scene",
                    path.display()
                )));
            }
            (_, _) => {
                return Err(fail(format!(
                    "{} has several cameras{}; name one with `camera` ({})",
                    path.display(),
                    desc.camera
                        .as_ref()
                        .map_or(String::new(), |w| format!(" named \"{w}\"")),
                    listed()
                )));
            }
        };
        let GltfProjection::Perspective { yfov, aspect_ratio } = camera.projection else {
            return Err(fail(format!(
                "{}: node {}'s camera is orthographic; rondo's camera is perspective only",
                path.display(),
                camera.node
            )));
        };
        let world = world_from_file * camera.world_from_camera;
        let made = CameraDesc::pinhole(
            world.transform_point3(Vec3::ZERO),
            world.transform_vector3(Vec3::NEG_Z),
            world.transform_vector3(Vec3::Y),
            yfov.to_degrees(),
        )
        .map_err(|m| {
            fail(format!(
                "{}: node {}'s camera: {m}",
                path.display(),
                camera.node
            ))
        })?;
        let image = width as f32 / height as f32;
        if let Some(ratio) = aspect_ratio
            && (ratio / image - 1.0).abs() > 0.01
        {
            self.warn(
                &path,
                &format!(
                    "camera of node {}: aspectRatio {ratio} differs from the image's {image} \
                     (width / height); the image's is used with the file's vertical field of view",
                    camera.node
                ),
            );
        }
        Ok(made)
    }
}
