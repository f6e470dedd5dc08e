//! Serde mirror of the RON scene format. Values are validated while they are parsed, so a bad
//! value is reported at its own line and column by the RON parser, with the field it belongs to
//! and the entity or material it is part of ([`parse`]).

use std::collections::BTreeMap;
use std::path::Path;

use glam::{Affine3A, EulerRot, Mat3, Quat, Vec3};
use serde::de::{DeserializeOwned, Error as _};
use serde::{Deserialize, Deserializer};

use crate::model::Shape;
use crate::scene::error::{SceneError, VALUE, number, vector};
use crate::shading::sampler::SamplerKind;
use crate::shading::texture::{Filter, Wrap};

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

/// A finite number (RON accepts `inf` and `NaN`; scenes may not).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Real(pub f32);

impl<'de> Deserialize<'de> for Real {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = f64::deserialize(d)?;
        let f = v as f32;
        if !f.is_finite() {
            return Err(D::Error::custom(format!(
                "{VALUE} must be a finite number (got {})",
                number(v)
            )));
        }
        Ok(Self(f))
    }
}

/// A number > 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Positive(pub f32);

impl<'de> Deserialize<'de> for Positive {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let Real(v) = Real::deserialize(d)?;
        if v <= 0.0 {
            return Err(D::Error::custom(format!(
                "{VALUE} must be > 0 (got {})",
                number(v)
            )));
        }
        Ok(Self(v))
    }
}

/// A number ≥ 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NonNegative(pub f32);

impl<'de> Deserialize<'de> for NonNegative {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let Real(v) = Real::deserialize(d)?;
        if v < 0.0 {
            return Err(D::Error::custom(format!(
                "{VALUE} must be >= 0 (got {})",
                number(v)
            )));
        }
        Ok(Self(v))
    }
}

/// A number in [0, 1].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UnitInterval(pub f32);

impl<'de> Deserialize<'de> for UnitInterval {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let Real(v) = Real::deserialize(d)?;
        if !(0.0..=1.0).contains(&v) {
            return Err(D::Error::custom(format!(
                "{VALUE} must be between 0 and 1 (got {})",
                number(v)
            )));
        }
        Ok(Self(v))
    }
}

/// A whole number ≥ 1 that fits a `u32`: image sides, samples, path depths.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Count(pub u32);

impl<'de> Deserialize<'de> for Count {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = f64::deserialize(d)?;
        if !(v >= 1.0 && v <= f64::from(u32::MAX) && v.fract() == 0.0) {
            return Err(D::Error::custom(format!(
                "{VALUE} must be a whole number >= 1 (got {})",
                number(v)
            )));
        }
        Ok(Self(v as u32))
    }
}

/// A finite vector written `(x, y, z)`; integers are accepted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct V3(pub Vec3);

impl<'de> Deserialize<'de> for V3 {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let [x, y, z] = <[Real; 3]>::deserialize(d)?;
        Ok(Self(Vec3::new(x.0, y.0, z.0)))
    }
}

/// A colour `(r, g, b)` with non-negative components.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Color(pub Vec3);

impl<'de> Deserialize<'de> for Color {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let [r, g, b] = <[NonNegative; 3]>::deserialize(d)?;
        Ok(Self(Vec3::new(r.0, g.0, b.0)))
    }
}

/// The whole scene file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, rename = "Scene")]
pub struct SceneDesc {
    /// The camera.
    pub camera: CameraDesc,
    /// Image and sampling settings.
    #[serde(default)]
    pub settings: SettingsDesc,
    /// Named materials.
    #[serde(default)]
    pub materials: BTreeMap<String, MaterialDesc>,
    /// The objects.
    #[serde(default)]
    pub entities: Vec<EntityDesc>,
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
        let aperture = raw.aperture.map_or(0.0, |a| a.0);
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

/// Largest accepted image side, in pixels.
pub const MAX_SIDE: u32 = 16_384;
/// Largest accepted pixel count (width · height).
pub const MAX_PIXELS: u64 = 1 << 26;
/// Largest accepted samples per pixel.
pub const MAX_SPP: u32 = 1 << 20;
/// Largest accepted path depth.
pub const MAX_DEPTH: u32 = 1024;
/// Largest accepted magnitude of any world-space coordinate (camera position, shape points and
/// sphere extents, after every transform). The kernels square and cube coordinates in `f32`
/// (triangle normals, the watertight test's `t`): beyond about 10⁹ the products overflow and
/// normals become NaN, so larger scenes are refused at load time.
pub const MAX_COORDINATE: f32 = 1e9;

/// Light-transport method.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Deserialize)]
pub enum Method {
    /// The thesis's path tracer: BSDF sampling only; light counts when a path hits an emitter.
    #[serde(alias = "naive")]
    Naive,
    /// Next-event estimation: a shadow ray to a sampled point on an emitter at every diffuse
    /// vertex; emitters hit by BSDF-sampled rays after such a vertex are not counted again.
    #[serde(alias = "nee")]
    Nee,
    /// NEE and BSDF sampling combined by the power heuristic (Veach 1997).
    #[default]
    #[serde(alias = "mis")]
    Mis,
}

impl std::str::FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.to_ascii_lowercase().as_str() {
            "naive" => Ok(Self::Naive),
            "nee" => Ok(Self::Nee),
            "mis" => Ok(Self::Mis),
            _ => Err(format!("unknown method {s:?} (naive, nee or mis)")),
        }
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Naive => "naive",
            Self::Nee => "nee",
            Self::Mis => "mis",
        })
    }
}

/// `Settings(width, height, spp, max_depth, background, environment, sun, seed, method, sampler,
/// denoise)`; every field optional.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, rename = "Settings", try_from = "RawSettings")]
pub struct SettingsDesc {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Rays per path, camera ray included (1 = emitters only).
    pub max_depth: u32,
    /// Radiance of rays that miss everything (without an `environment`).
    pub background: Vec3,
    /// An environment map lighting the scene from all around, instead of `background`.
    pub environment: Option<EnvironmentDesc>,
    /// A sun.
    pub sun: Option<SunDesc>,
    /// Random seed.
    pub seed: u64,
    /// Light-transport method.
    pub method: Method,
    /// Sample generator.
    pub sampler: SamplerKind,
    /// Denoise the image: `Some(true)` writes a denoised image (`render`, and the image `watch`
    /// writes), `Some(false)` turns the denoiser off everywhere (also in `watch`'s viewer),
    /// `None` (absent) denoises nothing unless `--denoise` asks. The raw sums are never replaced.
    pub denoise: Option<bool>,
}

impl Default for SettingsDesc {
    fn default() -> Self {
        Self {
            width: 512,
            height: 512,
            spp: 64,
            max_depth: 8,
            background: Vec3::ZERO,
            environment: None,
            sun: None,
            seed: 0,
            method: Method::Mis,
            sampler: SamplerKind::default(),
            denoise: None,
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Settings")]
struct RawSettings {
    width: Option<Count>,
    height: Option<Count>,
    spp: Option<Count>,
    max_depth: Option<Count>,
    background: Option<Color>,
    environment: Option<EnvironmentDesc>,
    sun: Option<SunDesc>,
    seed: Option<u64>,
    method: Option<Method>,
    sampler: Option<SamplerKind>,
    denoise: Option<bool>,
}

impl TryFrom<RawSettings> for SettingsDesc {
    type Error = String;
    fn try_from(raw: RawSettings) -> Result<Self, String> {
        let d = Self::default();
        let s = Self {
            width: raw.width.map_or(d.width, |c| c.0),
            height: raw.height.map_or(d.height, |c| c.0),
            spp: raw.spp.map_or(d.spp, |c| c.0),
            max_depth: raw.max_depth.map_or(d.max_depth, |c| c.0),
            background: raw.background.map_or(d.background, |c| c.0),
            environment: raw.environment,
            sun: raw.sun,
            seed: raw.seed.unwrap_or(d.seed),
            method: raw.method.unwrap_or(d.method),
            sampler: raw.sampler.unwrap_or(d.sampler),
            denoise: raw.denoise,
        };
        if s.environment.is_some() && raw.background.is_some() {
            return Err("give `background` or `environment`, not both".into());
        }
        s.validate()?;
        Ok(s)
    }
}

/// `Environment(path, strength, rotate)`: an equirectangular map of linear radiance (OpenEXR
/// or Radiance `.hdr`) around the scene; the convention is in [`crate::sky::environment`].
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(
    deny_unknown_fields,
    rename = "Environment",
    try_from = "RawEnvironment"
)]
pub struct EnvironmentDesc {
    /// The map's file, relative to the scene file.
    pub path: String,
    /// Scale of the map's radiance, ≥ 0.
    pub strength: f32,
    /// Rotation of the map in degrees about x, then y, then z, as a `Transform`'s.
    pub rotate: Vec3,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Environment")]
struct RawEnvironment {
    path: String,
    strength: Option<NonNegative>,
    rotate: Option<V3>,
}

impl TryFrom<RawEnvironment> for EnvironmentDesc {
    type Error = String;
    fn try_from(raw: RawEnvironment) -> Result<Self, String> {
        Ok(Self {
            path: raw.path,
            strength: raw.strength.map_or(1.0, |s| s.0),
            rotate: raw.rotate.map_or(Vec3::ZERO, |r| r.0),
        })
    }
}

impl EnvironmentDesc {
    /// Rotation from the map's space to the world's.
    pub fn world_from_map(&self) -> Mat3 {
        TransformDesc {
            rotate: self.rotate,
            ..TransformDesc::default()
        }
        .rotation()
    }
}

/// `Sun(direction, angular_diameter, irradiance | radiance, colour)`: a distant disk.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, rename = "Sun", try_from = "RawSun")]
pub struct SunDesc {
    /// Direction from the scene towards the sun, non-zero (any length).
    pub direction: Vec3,
    /// Angular diameter of the disk in degrees, in (0, 90]; 0.53 by default (the real sun).
    pub angular_diameter: f32,
    /// Radiance of the disk: `colour` × `radiance`, or the radiance that makes irradiance
    /// `colour` × `irradiance` on a plane facing the sun.
    pub radiance: Vec3,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Sun")]
struct RawSun {
    direction: V3,
    angular_diameter: Option<Positive>,
    irradiance: Option<NonNegative>,
    radiance: Option<NonNegative>,
    colour: Option<Color>,
}

impl TryFrom<RawSun> for SunDesc {
    type Error = String;
    fn try_from(raw: RawSun) -> Result<Self, String> {
        let d = raw.direction.0;
        let unit = d / d.abs().max_element().max(f32::MIN_POSITIVE);
        if d == Vec3::ZERO || !unit.length_squared().is_normal() {
            return Err(format!(
                "sun: `direction` must be non-zero (got {})",
                vector(d)
            ));
        }
        let diameter = raw.angular_diameter.map_or(0.53, |a| a.0);
        if diameter > 90.0 {
            return Err(format!(
                "sun: angular_diameter must be in (0, 90] degrees (got {})",
                number(diameter)
            ));
        }
        let colour = raw.colour.map_or(Vec3::ONE, |c| c.0);
        let radiance = match (raw.irradiance, raw.radiance) {
            (Some(e), None) => {
                crate::sky::Sun::radiance_for_irradiance(colour * e.0, diameter.to_radians())
            }
            (None, Some(l)) => colour * l.0,
            (Some(_), Some(_)) => {
                return Err("sun: give `irradiance` or `radiance`, not both".into());
            }
            (None, None) => return Err("sun: `irradiance` or `radiance` is required".into()),
        };
        if !radiance.is_finite() {
            return Err("sun: the radiance is too large to represent".into());
        }
        Ok(Self {
            direction: unit.normalize(),
            angular_diameter: diameter,
            radiance,
        })
    }
}

impl SettingsDesc {
    /// Checks the limits that keep a render from asking for absurd amounts of memory or time.
    pub fn validate(&self) -> Result<(), String> {
        for (field, value) in [
            ("width", self.width),
            ("height", self.height),
            ("spp", self.spp),
            ("max_depth", self.max_depth),
        ] {
            if value == 0 {
                return Err(format!("{field} must be >= 1 (got 0)"));
            }
        }
        for (field, value) in [("width", self.width), ("height", self.height)] {
            if value > MAX_SIDE {
                return Err(format!("{field} must be at most {MAX_SIDE} (got {value})"));
            }
        }
        let pixels = u64::from(self.width) * u64::from(self.height);
        if pixels > MAX_PIXELS {
            return Err(format!(
                "width × height must be at most {MAX_PIXELS} pixels (got {}×{} = {pixels})",
                self.width, self.height
            ));
        }
        if self.spp > MAX_SPP {
            return Err(format!("spp must be at most {MAX_SPP} (got {})", self.spp));
        }
        if self.max_depth > MAX_DEPTH {
            return Err(format!(
                "max_depth must be at most {MAX_DEPTH} (got {})",
                self.max_depth
            ));
        }
        Ok(())
    }
}

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
    /// `Dielectric(ior)`.
    Dielectric {
        /// Index of refraction.
        ior: Positive,
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
    /// `Pbr(base_color, metallic, roughness, emissive, emissive_strength, normal_map)`: the
    /// glTF 2.0 metallic–roughness material, with glTF's defaults (base colour 1, metallic 1,
    /// roughness 1, no emission, strength 1, no normal map).
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

fn black() -> TextureDesc {
    TextureDesc::Constant(Color(Vec3::ZERO))
}

fn unit_one() -> UnitInterval {
    UnitInterval(1.0)
}

fn zero() -> Real {
    Real(0.0)
}

fn one() -> NonNegative {
    NonNegative(1.0)
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

/// A validated shape as written in RON.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(try_from = "RawShape")]
pub enum ShapeDesc {
    /// A shape defined by its numbers.
    Analytic(Shape),
    /// `Mesh(path)`: a Wavefront OBJ file, relative to the file that names it.
    Mesh {
        /// The path as written.
        path: String,
    },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
enum RawShape {
    Sphere { center: V3, radius: Positive },
    Plane { point: V3, normal: V3 },
    Triangle { a: V3, b: V3, c: V3 },
    Quad { a: V3, b: V3, c: V3, d: V3 },
    Box { min: V3, max: V3 },
    Mesh { path: String },
}

/// Twice the area of a triangle, relative to the square of its longest edge: 0 when degenerate.
fn relative_area(a: Vec3, b: Vec3, c: Vec3) -> f32 {
    let longest = (b - a)
        .length_squared()
        .max((c - a).length_squared())
        .max((c - b).length_squared());
    if longest == 0.0 {
        return 0.0;
    }
    (b - a).cross(c - a).length() / longest
}

impl TryFrom<RawShape> for ShapeDesc {
    type Error = String;
    fn try_from(raw: RawShape) -> Result<Self, String> {
        const MIN_AREA: f32 = 1e-6;
        let shape = match raw {
            RawShape::Sphere { center, radius } => Shape::Sphere {
                center: center.0,
                radius: radius.0,
            },
            RawShape::Plane { point, normal } => {
                let n = normal.0;
                if n.length_squared() == 0.0 || !n.length_squared().is_normal() {
                    return Err(format!(
                        "plane: `normal` must be non-zero (got {})",
                        vector(n)
                    ));
                }
                Shape::Plane {
                    point: point.0,
                    normal: n.normalize(),
                }
            }
            RawShape::Triangle { a, b, c } => {
                if relative_area(a.0, b.0, c.0) < MIN_AREA {
                    return Err("triangle: zero area (collinear or repeated vertices)".into());
                }
                Shape::Triangle {
                    a: a.0,
                    b: b.0,
                    c: c.0,
                }
            }
            RawShape::Quad { a, b, c, d } => {
                if relative_area(a.0, b.0, c.0) < MIN_AREA
                    || relative_area(a.0, c.0, d.0) < MIN_AREA
                {
                    return Err("quad: zero area (collinear or repeated corners)".into());
                }
                Shape::Quad {
                    a: a.0,
                    b: b.0,
                    c: c.0,
                    d: d.0,
                }
            }
            RawShape::Box { min, max } => {
                if !min.0.cmplt(max.0).all() {
                    return Err(format!(
                        "box: `min` must be less than `max` on every axis (got min {}, max {})",
                        min.0, max.0
                    ));
                }
                Shape::Box {
                    min: min.0,
                    max: max.0,
                }
            }
            RawShape::Mesh { path } => return Ok(Self::Mesh { path }),
        };
        Ok(Self::Analytic(shape))
    }
}

/// `Transform(translate, rotate, scale)`: `world = T · R · S · object`, every part optional.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(try_from = "RawTransform")]
pub struct TransformDesc {
    /// Translation.
    pub translate: Vec3,
    /// Rotation in degrees about x, then y, then z (right-handed).
    pub rotate: Vec3,
    /// Scale per axis (non-zero).
    pub scale: Vec3,
}

impl Default for TransformDesc {
    fn default() -> Self {
        Self {
            translate: Vec3::ZERO,
            rotate: Vec3::ZERO,
            scale: Vec3::ONE,
        }
    }
}

impl TransformDesc {
    /// `parent_from_object = T · R · S`, with `R = Rz · Ry · Rx` (x applied first).
    pub fn matrix(&self) -> Affine3A {
        Affine3A::from_mat3_translation(
            self.rotation() * Mat3::from_diagonal(self.scale),
            self.translate,
        )
    }

    /// The rotation `R = Rz · Ry · Rx` alone.
    pub fn rotation(&self) -> Mat3 {
        let r = self.rotate * (std::f32::consts::PI / 180.0);
        Mat3::from_quat(Quat::from_euler(EulerRot::ZYX, r.z, r.y, r.x))
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Transform")]
struct RawTransform {
    translate: Option<V3>,
    rotate: Option<V3>,
    scale: Option<V3>,
}

impl TryFrom<RawTransform> for TransformDesc {
    type Error = String;
    fn try_from(raw: RawTransform) -> Result<Self, String> {
        let d = Self::default();
        let t = Self {
            translate: raw.translate.map_or(d.translate, |v| v.0),
            rotate: raw.rotate.map_or(d.rotate, |v| v.0),
            scale: raw.scale.map_or(d.scale, |v| v.0),
        };
        if t.scale.abs().min_element() < 1e-12 {
            return Err(format!(
                "scale must be non-zero on every axis (got {})",
                vector(t.scale)
            ));
        }
        Ok(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn trs(translate: Vec3, rotate: Vec3, scale: Vec3) -> Affine3A {
        TransformDesc {
            translate,
            rotate,
            scale,
        }
        .matrix()
    }

    #[test]
    fn rotation_about_y_matches_rtiow() {
        // +θ about y maps (x, z) to (x cosθ + z sinθ, −x sinθ + z cosθ).
        let m = trs(Vec3::ZERO, Vec3::new(0.0, 30.0, 0.0), Vec3::ONE);
        let p = m.transform_point3(Vec3::new(1.0, 0.0, 2.0));
        let (s, c) = 30f32.to_radians().sin_cos();
        assert!(
            (p - Vec3::new(c + 2.0 * s, 0.0, -s + 2.0 * c)).length() < 1e-5,
            "{p}"
        );
    }

    #[test]
    fn rotations_apply_x_then_y_then_z() {
        let m = trs(Vec3::ZERO, Vec3::new(90.0, 90.0, 0.0), Vec3::ONE);
        // Rx(90): y → z; then Ry(90): z → x.
        let p = m.transform_point3(Vec3::Y);
        assert!((p - Vec3::X).length() < 1e-6, "{p}");
    }

    #[test]
    fn translate_rotate_scale_compose_in_that_order() {
        let m = trs(
            Vec3::new(10.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 90.0),
            Vec3::new(2.0, 1.0, 1.0),
        );
        // S: (1,0,0) → (2,0,0); Rz(90): → (0,2,0); T: → (10,2,0).
        let p = m.transform_point3(Vec3::X);
        assert!((p - Vec3::new(10.0, 2.0, 0.0)).length() < 1e-5, "{p}");
    }
}
