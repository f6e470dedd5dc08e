//! The camera as written: `Camera(position, look_at | direction, …)`, or a camera of a glTF
//! file the scene places, `Gltf(placement, camera)`:
//!
//! ```ron
//! camera: Gltf(placement: "helmet", camera: "Camera"),
//! ```
//!
//! `placement` names an entity that places a glTF file (`Entity(name: "helmet", gltf: …)`,
//! qualified as `outer/inner` inside a prefab); `camera` names a node of the file's default
//! scene that holds a camera, or the camera itself (optional when the scene holds exactly one
//! camera). The camera is put where the node and the placement put it, looking along its −z
//! with +y up, with the file's vertical field of view (`yfov`); the image's aspect ratio is the
//! settings' `width / height`, whatever the file's `aspectRatio` says, and it is a pinhole.
//! Orthographic cameras are refused (rondo's camera is perspective).

use std::fmt;
use std::marker::PhantomData;

use glam::Vec3;
use serde::de::value::MapAccessDeserializer;
use serde::de::{EnumAccess, MapAccess, VariantAccess, Visitor};
use serde::{Deserialize, Deserializer};

use super::number::{NonNegative, Positive, Real, V3, or_default};
use super::settings::MAX_COORDINATE;
use crate::scene::error::{number, vector};

/// The scene's camera as written: its own, or one of a placed glTF file.
#[derive(Clone, Debug, PartialEq)]
pub enum SceneCamera {
    /// `Camera(…)`.
    Camera(CameraDesc),
    /// `Gltf(placement, camera)`, resolved by the loader.
    Gltf(GltfCameraDesc),
}

/// `Gltf(placement, camera)`: a camera of a glTF file the scene places (see the module's doc).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, rename = "Gltf")]
pub struct GltfCameraDesc {
    /// Qualified name of the entity that places the glTF file.
    pub placement: String,
    /// Name of the node holding the camera, or of the camera; optional when there is one.
    pub camera: Option<String>,
}

/// The variants of [`SceneCamera`] as written.
#[derive(Deserialize)]
#[serde(variant_identifier)]
enum CameraKind {
    Camera,
    Gltf,
}

impl<'de> Deserialize<'de> for SceneCamera {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_enum("SceneCamera", &["Camera", "Gltf"], SceneCameraVisitor)
    }
}

/// Reads `Camera(…)` or `Gltf(…)`, each with its own fields and checks: written as RON's
/// struct-like variants, so `Camera(position: …)` reads as it always has.
struct SceneCameraVisitor;

impl<'de> Visitor<'de> for SceneCameraVisitor {
    type Value = SceneCamera;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("`Camera(…)` or `Gltf(placement, camera)`")
    }

    fn visit_enum<A: EnumAccess<'de>>(self, data: A) -> Result<SceneCamera, A::Error> {
        let (kind, variant) = data.variant::<CameraKind>()?;
        match kind {
            CameraKind::Camera => variant
                .struct_variant(CAMERA_FIELDS, Fields(PhantomData))
                .map(SceneCamera::Camera),
            CameraKind::Gltf => variant
                .struct_variant(&["placement", "camera"], Fields(PhantomData))
                .map(SceneCamera::Gltf),
        }
    }
}

/// The fields of `Camera(…)`.
const CAMERA_FIELDS: &[&str] = &[
    "position",
    "look_at",
    "direction",
    "up",
    "fov",
    "aperture",
    "focus_distance",
    "focus_on",
];

/// A struct-like variant's fields read as the struct `T` (with its own checks).
struct Fields<T>(PhantomData<T>);

impl<'de, T: Deserialize<'de>> Visitor<'de> for Fields<T> {
    type Value = T;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("named fields")
    }

    fn visit_map<M: MapAccess<'de>>(self, map: M) -> Result<T, M::Error> {
        T::deserialize(MapAccessDeserializer::new(map))
    }
}

/// `Camera(position, look_at | direction, up, fov, aperture, focus_distance | focus_on)`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, rename = "Camera", try_from = "RawCamera")]
pub struct CameraDesc {
    /// Eye position.
    pub position: Vec3,
    /// View direction (from `look_at − position` or `direction`), non-zero.
    pub direction: Vec3,
    /// Up vector, not parallel to `direction`.
    pub up: Vec3,
    /// Vertical field of view in degrees, in (0, 180).
    pub fov: f32,
    /// Radius of the thin lens in scene units; 0 (the default) is a pinhole.
    pub aperture: f32,
    /// Distance of the plane of focus along the view direction, > 0: `focus_distance`, or the
    /// depth of `focus_on`, or by default that of `look_at` (1 for a pinhole given a
    /// `direction`, where it does not matter).
    pub focus_distance: f32,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Camera")]
struct RawCamera {
    position: V3,
    look_at: Option<V3>,
    direction: Option<V3>,
    #[serde(default = "default_up")]
    up: V3,
    #[serde(default = "default_fov")]
    fov: Real,
    aperture: Option<NonNegative>,
    focus_distance: Option<Positive>,
    focus_on: Option<V3>,
}

fn default_up() -> V3 {
    V3(Vec3::Y)
}

fn default_fov() -> Real {
    Real(40.0)
}

impl TryFrom<RawCamera> for CameraDesc {
    type Error = String;
    fn try_from(raw: RawCamera) -> Result<Self, String> {
        let direction = match (raw.look_at, raw.direction) {
            (Some(at), None) => at.0 - raw.position.0,
            (None, Some(d)) => d.0,
            (Some(_), Some(_)) => {
                return Err("give `look_at` or `direction`, not both".into());
            }
            (None, None) => return Err("`look_at` or `direction` is required".into()),
        };
        // Only the directions of `direction` and `up` matter. Scaling each by its largest
        // component makes any non-zero length safe to square: `up: (3e38, 0, -3e38)` made the
        // camera's right vector ∞ · 0 = NaN, and a tiny direction's square underflowed to 0.
        let unit_max = |v: Vec3| {
            let m = v.abs().max_element();
            if m > 0.0 { v / m } else { v }
        };
        let direction = unit_max(direction);
        if direction == Vec3::ZERO || !direction.is_finite() {
            return Err("the view direction is zero (`look_at` equals `position`?)".into());
        }
        if raw.position.0.abs().max_element() > MAX_COORDINATE {
            return Err(format!(
                "position must be within ±{MAX_COORDINATE:e} on every axis (got {})",
                vector(raw.position.0)
            ));
        }
        let up = unit_max(raw.up.0);
        if direction.normalize().cross(up).length_squared() < 1e-12 {
            return Err("`up` must be non-zero and not parallel to the view direction".into());
        }
        let fov = raw.fov.0;
        if !(fov > 0.0 && fov < 180.0) {
            return Err(format!(
                "fov must be in (0, 180) degrees (got {})",
                number(fov)
            ));
        }
        let aperture = or_default(raw.aperture, 0.0);
        // Depth along the view, in f64: coordinates up to 1e9 square without overflow.
        let depth = |p: Vec3| {
            (p - raw.position.0)
                .as_dvec3()
                .dot(direction.as_dvec3().normalize()) as f32
        };
        let focus_distance = match (raw.focus_distance, raw.focus_on, raw.look_at) {
            (Some(_), Some(_), _) => {
                return Err("give `focus_distance` or `focus_on`, not both".into());
            }
            (Some(d), None, _) => d.0,
            (None, Some(p), _) => {
                let d = depth(p.0);
                if !(d > 0.0 && d.is_finite()) {
                    return Err(format!(
                        "focus_on {} is not in front of the camera",
                        vector(p.0)
                    ));
                }
                d
            }
            (None, None, Some(at)) => depth(at.0),
            (None, None, None) if aperture > 0.0 => {
                return Err(
                    "a camera with an aperture and a `direction` needs `focus_distance` or `focus_on`"
                        .into(),
                );
            }
            (None, None, None) => 1.0,
        };
        Ok(Self {
            position: raw.position.0,
            direction,
            up,
            fov,
            aperture,
            focus_distance,
        })
    }
}

impl CameraDesc {
    /// A pinhole at `position` looking along `direction` with `up` up and a vertical field of
    /// view of `fov` degrees, checked as a written `Camera` is (position within
    /// [`MAX_COORDINATE`], direction non-zero, `up` not parallel to it, fov in (0, 180)).
    pub fn pinhole(position: Vec3, direction: Vec3, up: Vec3, fov: f32) -> Result<Self, String> {
        let unit_max = |v: Vec3| {
            let m = v.abs().max_element();
            if m > 0.0 { v / m } else { v }
        };
        let direction = unit_max(direction);
        if direction == Vec3::ZERO || !direction.is_finite() {
            return Err("the view direction is zero".into());
        }
        if !position.is_finite() || position.abs().max_element() > MAX_COORDINATE {
            return Err(format!(
                "position must be within ±{MAX_COORDINATE:e} on every axis (got {})",
                vector(position)
            ));
        }
        let up = unit_max(up);
        if !up.is_finite() || direction.normalize().cross(up).length_squared() < 1e-12 {
            return Err("`up` must be non-zero and not parallel to the view direction".into());
        }
        if !(fov > 0.0 && fov < 180.0) {
            return Err(format!(
                "fov must be in (0, 180) degrees (got {})",
                number(fov)
            ));
        }
        Ok(Self {
            position,
            direction,
            up,
            fov,
            aperture: 0.0,
            focus_distance: 1.0,
        })
    }
}
