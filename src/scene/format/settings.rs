//! Image and sampling settings, the environment map and the sun, and the limits they are held to.

use glam::{Mat3, Vec3};
use serde::Deserialize;

use super::number::{Color, Count, NonNegative, Positive, V3, or_default};
use super::transform::TransformDesc;
use crate::scene::error::{number, vector};
use crate::shading::sampler::SamplerKind;

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
    /// The plain path tracer of Ray Tracing in One Weekend, as the 2020 thesis in
    /// `../shared/seed/` traces: BSDF sampling only; light counts when a path hits an emitter.
    #[serde(alias = "naive")]
    Naive,
    /// Next-event estimation: a shadow ray to a sampled point on an emitter at every diffuse
    /// vertex; emitters hit by BSDF-sampled rays after such a vertex are not counted again.
    #[serde(alias = "nee")]
    Nee,
    /// NEE and BSDF sampling combined by the power heuristic (Veach 1997).
    #[serde(alias = "mis")]
    Mis,
    /// `Mis` with the caustics (camera → diffuse → perfect mirrors and glass → light) found by
    /// light tracing instead. The default: where no caustic shows it costs about what `Mis`
    /// does (BENCHMARKS.md, "Caustics as the default?").
    #[default]
    #[serde(alias = "caustics")]
    Caustics,
    /// `Caustics`, with the caustics seen in mirrors and through glass (camera → mirror or
    /// glass → diffuse → mirror or glass → light) and those seen after a diffuse bounce
    /// gathered from photons the light paths leave, which also follow narrow glossy
    /// reflections (a `Glossy` of roughness below about 0.55):
    /// consistent (it converges to what `Caustics` does), biased at a finite sample count by a
    /// gather radius that shrinks with every sample.
    #[serde(alias = "photons")]
    Photons,
}

impl std::str::FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.to_ascii_lowercase().as_str() {
            "naive" => Ok(Self::Naive),
            "nee" => Ok(Self::Nee),
            "mis" => Ok(Self::Mis),
            "caustics" => Ok(Self::Caustics),
            "photons" => Ok(Self::Photons),
            _ => Err(format!(
                "unknown method {s:?} (naive, nee, mis, caustics or photons)"
            )),
        }
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Naive => "naive",
            Self::Nee => "nee",
            Self::Mis => "mis",
            Self::Caustics => "caustics",
            Self::Photons => "photons",
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
            method: Method::default(),
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
            width: or_default(raw.width, d.width),
            height: or_default(raw.height, d.height),
            spp: or_default(raw.spp, d.spp),
            max_depth: or_default(raw.max_depth, d.max_depth),
            background: or_default(raw.background, d.background),
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
            strength: or_default(raw.strength, 1.0),
            rotate: or_default(raw.rotate, Vec3::ZERO),
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
        let diameter = or_default(raw.angular_diameter, 0.53);
        if diameter > 90.0 {
            return Err(format!(
                "sun: angular_diameter must be in (0, 90] degrees (got {})",
                number(diameter)
            ));
        }
        let colour = or_default(raw.colour, Vec3::ONE);
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
