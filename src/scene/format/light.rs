//! Point and spot lights as written in the scene's `lights` list:
//!
//! ```ron
//! lights: [
//!     Point(position: (0, 3, 0), intensity: 20, colour: (1, 0.9, 0.8)),
//!     Spot(position: (2, 4, 1), look_at: (0, 0, 0), intensity: 200,
//!          inner_angle: 15, outer_angle: 25),
//! ],
//! ```
//!
//! `intensity` is a radiant intensity in glTF's unit (candela, read as rondo's radiance units
//! × m²; default 1, glTF's): a surface at distance r facing the light receives `intensity ×
//! colour / r²`. A spot aims at `look_at` or along `direction` and has glTF's cone half-angles,
//! here in degrees: full intensity within `inner_angle` (default 0) of its axis, none beyond
//! `outer_angle` (default 45), the spec's smooth falloff between
//! ([`crate::lights::punctual`]).

use glam::Vec3;
use serde::Deserialize;

use super::number::{Color, NonNegative, V3, or_default};
use super::settings::MAX_COORDINATE;
use crate::lights::punctual::PunctualLight;
use crate::scene::error::{number, vector};

/// `Point(position, intensity, colour)` or `Spot(position, look_at | direction, intensity,
/// colour, inner_angle, outer_angle)`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(try_from = "RawLight")]
pub struct LightDesc {
    /// The light in world space.
    pub light: PunctualLight,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
enum RawLight {
    Point {
        position: V3,
        intensity: Option<NonNegative>,
        colour: Option<Color>,
    },
    Spot {
        position: V3,
        look_at: Option<V3>,
        direction: Option<V3>,
        intensity: Option<NonNegative>,
        colour: Option<Color>,
        inner_angle: Option<NonNegative>,
        outer_angle: Option<NonNegative>,
    },
}

/// The radiant intensity `colour × intensity` of a light at `position`, checked: the position
/// within [`MAX_COORDINATE`], the intensity and the light's power finite. `what` names the
/// light in errors.
pub fn checked_intensity(
    what: &str,
    position: Vec3,
    colour: Vec3,
    intensity: f32,
) -> Result<Vec3, String> {
    if position.abs().max_element() > MAX_COORDINATE {
        return Err(format!(
            "{what}: position must be within ±{MAX_COORDINATE:e} on every axis (got {})",
            vector(position)
        ));
    }
    let i = colour * intensity;
    if !(i.is_finite() && PunctualLight::point(position, i).power().is_finite()) {
        return Err(format!(
            "{what}: intensity {} times colour {} is too large to represent",
            number(intensity),
            vector(colour)
        ));
    }
    Ok(i)
}

/// Checks glTF's rule for a spot's cone half-angles, `0 ≤ inner ≤ outer ≤ right angle`, in
/// the unit they are written in (`right` is the right angle in that unit), naming the fields.
pub fn check_cone(
    what: &str,
    [inner_field, outer_field]: [&str; 2],
    inner: f32,
    outer: f32,
    right: f32,
) -> Result<(), String> {
    if !(outer > 0.0 && outer <= right) {
        return Err(format!(
            "{what}: `{outer_field}` must be in (0, {}] (got {})",
            number(right),
            number(outer)
        ));
    }
    if !(inner >= 0.0 && inner <= outer) {
        return Err(format!(
            "{what}: `{inner_field}` ({}) must be between 0 and `{outer_field}` ({})",
            number(inner),
            number(outer)
        ));
    }
    Ok(())
}

impl TryFrom<RawLight> for LightDesc {
    type Error = String;
    fn try_from(raw: RawLight) -> Result<Self, String> {
        let light = match raw {
            RawLight::Point {
                position,
                intensity,
                colour,
            } => {
                let i = checked_intensity(
                    "point light",
                    position.0,
                    or_default(colour, Vec3::ONE),
                    or_default(intensity, 1.0),
                )?;
                PunctualLight::point(position.0, i)
            }
            RawLight::Spot {
                position,
                look_at,
                direction,
                intensity,
                colour,
                inner_angle,
                outer_angle,
            } => {
                let what = "spot light";
                let axis = match (look_at, direction) {
                    (Some(at), None) => at.0 - position.0,
                    (None, Some(d)) => d.0,
                    (Some(_), Some(_)) => {
                        return Err(format!("{what}: give `look_at` or `direction`, not both"));
                    }
                    (None, None) => {
                        return Err(format!("{what}: `look_at` or `direction` is required"));
                    }
                };
                // Scaled by its largest component, so any non-zero length normalises.
                let axis = axis / axis.abs().max_element().max(f32::MIN_POSITIVE);
                if !(axis.is_finite() && axis.length_squared().is_normal()) {
                    return Err(format!(
                        "{what}: the direction is zero (`look_at` equals `position`?)"
                    ));
                }
                let inner = or_default(inner_angle, 0.0);
                let outer = or_default(outer_angle, 45.0);
                check_cone(what, ["inner_angle", "outer_angle"], inner, outer, 90.0)?;
                let i = checked_intensity(
                    what,
                    position.0,
                    or_default(colour, Vec3::ONE),
                    or_default(intensity, 1.0),
                )?;
                PunctualLight::spot(position.0, axis, i, inner.to_radians(), outer.to_radians())
            }
        };
        Ok(Self { light })
    }
}
