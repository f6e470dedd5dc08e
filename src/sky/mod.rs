//! Light from infinitely far away: an environment map and a sun. No ECS here.
//!
//! Both become distant lights of the light table ([`crate::lights::distant`]).

pub mod environment;
mod guide;
mod prefetch;
pub mod sun;

use std::sync::Arc;

use glam::{Mat3, Vec3};

pub use environment::EnvironmentMap;
pub use sun::Sun;

/// An environment map placed in the world.
#[derive(Clone, Debug)]
pub struct EnvironmentLight {
    /// The map and its distribution (shared: built once per load of the file).
    pub map: Arc<EnvironmentMap>,
    /// Scale of the map's radiance.
    pub strength: f32,
    /// Rotation from map space to world space.
    pub world_from_map: Mat3,
}

impl PartialEq for EnvironmentLight {
    /// The same map (by identity: a reload of an unchanged file shares it) placed alike.
    fn eq(&self, o: &Self) -> bool {
        Arc::ptr_eq(&self.map, &o.map)
            && self.strength == o.strength
            && self.world_from_map == o.world_from_map
    }
}

impl EnvironmentLight {
    /// `map` scaled by `strength` (finite, ≥ 0) and turned by `world_from_map`. Refused if
    /// the scaled radiance of a texel, or the light's power per unit of the scene's squared
    /// radius, is too large for an `f32`: every sample would be dropped as non-finite.
    pub fn new(
        map: Arc<EnvironmentMap>,
        strength: f32,
        world_from_map: Mat3,
    ) -> Result<Self, String> {
        let brightest = strength * map.max();
        let power = 4.0 * std::f32::consts::PI * strength * map.mean().max_element();
        if !brightest.is_finite() || !power.is_finite() {
            return Err(format!(
                "strength {strength:e} times the map's brightest texel ({:e}) is too large to \
                 represent",
                map.max()
            ));
        }
        Ok(Self {
            map,
            strength,
            world_from_map,
        })
    }

    /// Radiance along world direction `d` and the density with which the map's sampling gives
    /// it, from one texel lookup.
    #[inline]
    pub fn lookup(&self, d: Vec3) -> (Vec3, f32) {
        let (radiance, pdf) = self.map.lookup(self.world_from_map.transpose() * d);
        (self.strength * radiance, pdf)
    }
}

/// The distant lights of a scene.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Sky {
    /// The environment map, if any.
    pub environment: Option<EnvironmentLight>,
    /// The sun, if any.
    pub sun: Option<Sun>,
}
