//! The distant lights of the scene's sky (an environment map, a sun) as lights of the table:
//! chosen for next-event estimation with a probability that follows their power as the scene
//! receives it (π r² of the scene's bounding sphere times their irradiance, as pbrt-v4 estimates
//! an infinite light's power), and found by paths that leave the scene, where multiple importance
//! sampling weighs them against the BSDF. No ECS here.

use glam::{Vec2, Vec3};

use crate::sky::{EnvironmentLight, Sky, Sun};

/// A direction sampled towards a distant light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DistantSample {
    /// Unit direction towards the light.
    pub direction: Vec3,
    /// Radiance the light sends along it.
    pub radiance: Vec3,
    /// Probability density of the direction per steradian, selection included: what
    /// [`super::LightSet::distant_lookup`] gives for it.
    pub pdf: f32,
}

/// The distant lights of `sky`, environment first.
pub fn lights_of(sky: &Sky) -> Vec<DistantLight> {
    let env = sky.environment.clone().map(DistantLight::Environment);
    env.into_iter()
        .chain(sky.sun.map(DistantLight::Sun))
        .collect()
}

/// One distant light.
#[derive(Clone, Debug, PartialEq)]
pub enum DistantLight {
    /// An environment map.
    Environment(EnvironmentLight),
    /// A sun.
    Sun(Sun),
}

impl DistantLight {
    /// Radiance arriving along unit world direction `d` and the density with which
    /// [`DistantLight::sample`] gives `d`.
    #[inline]
    pub fn lookup(&self, d: Vec3) -> (Vec3, f32) {
        match self {
            Self::Environment(e) => e.lookup(d),
            Self::Sun(s) => (s.radiance(d), s.pdf(d)),
        }
    }

    /// The brightest radiance (any channel) the light sends.
    pub fn max_radiance(&self) -> f32 {
        match self {
            Self::Environment(e) => e.strength * e.map.max(),
            Self::Sun(s) => s.disk_radiance().max_element(),
        }
    }

    /// A unit world direction towards the light with the radiance the light sends along it and
    /// its density per steradian (selection not included), read from what was sampled rather
    /// than by looking the direction up again: `u` picks it (for a map, its texel), `jitter()`
    /// is asked for a second pair of numbers when one is needed (a map's position within the
    /// texel). `None` if there is nothing to sample. A direction within float rounding of a
    /// texel's edge (or of the sun's rim) may be looked up as the neighbour (or as outside):
    /// a set of measure zero, which weighs nothing in the estimate.
    #[inline]
    pub fn sample(&self, u: Vec2, jitter: impl FnOnce() -> Vec2) -> Option<(Vec3, Vec3, f32)> {
        match self {
            Self::Environment(e) => e.map.sample(u, jitter()).map(|s| {
                (
                    (e.world_from_map * s.direction).normalize(),
                    e.strength * s.radiance,
                    s.pdf,
                )
            }),
            Self::Sun(s) => Some((s.sample(u), s.disk_radiance(), 1.0 / s.solid_angle())),
        }
    }

    /// Power as the scene receives it, in the emitter table's units (area × radiance, i.e.
    /// flux / π), for a scene bounded by a sphere of radius `radius`: the flux through the
    /// sphere's cross-section, π r² × irradiance, over π. For a map, irradiance on a sphere
    /// averages to π × its mean radiance, so 4π r² × mean (pbrt-v4's estimate).
    pub fn power(&self, radius: f32) -> f32 {
        let r2 = radius * radius;
        match self {
            Self::Environment(e) if e.map.is_lit() => {
                4.0 * std::f32::consts::PI * r2 * e.strength * (e.map.mean().element_sum() / 3.0)
            }
            Self::Environment(_) => 0.0,
            Self::Sun(s) => r2 * s.solid_angle() * (s.disk_radiance().element_sum() / 3.0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    use glam::Mat3;

    use crate::sky::EnvironmentMap;

    #[test]
    fn a_rotated_map_is_read_and_sampled_in_world_space() {
        // A map lit in one texel around +x (u = 0.25 at the horizon); rotated 90° about y
        // (x → −z), the light comes from −z, and sampled directions point there.
        let (w, h) = (16u32, 8u32);
        let mut pixels = vec![0.0f32; 3 * (w * h) as usize];
        let texel = (4 * w + 4) as usize;
        pixels[3 * texel..3 * texel + 3].copy_from_slice(&[5.0; 3]);
        let map = Arc::new(EnvironmentMap::from_linear(w, h, &pixels).expect("map"));
        let rotation = Mat3::from_rotation_y(std::f32::consts::FRAC_PI_2);
        let light = DistantLight::Environment(EnvironmentLight {
            map: map.clone(),
            strength: 2.0,
            world_from_map: rotation,
        });
        let into_texel = Vec3::new(1.0, -0.1, 0.05).normalize();
        assert_eq!(map.radiance(into_texel), Vec3::splat(5.0));
        let world = rotation * into_texel;
        assert!(world.z < -0.9, "{world}");
        assert_eq!(
            light.lookup(world),
            (Vec3::splat(10.0), map.pdf(into_texel))
        );
        assert_eq!(light.lookup(into_texel).0, Vec3::ZERO);
        let (d, radiance, pdf) = light
            .sample(Vec2::new(0.3, 0.6), || Vec2::new(0.5, 0.5))
            .expect("lit");
        assert!(d.z < -0.9, "{d}");
        assert_eq!(light.lookup(d), (radiance, pdf));
    }

    #[test]
    fn a_strength_that_overflows_the_radiance_is_refused() {
        // One texel of 1.7e38: finite on its own, infinite at strength 1e38 (and at 3).
        let mut pixels = vec![0.5f32; 3 * 8 * 4];
        pixels[3 * 9..3 * 10].copy_from_slice(&[1.7e38; 3]);
        let map = Arc::new(EnvironmentMap::from_linear(8, 4, &pixels).expect("map"));
        for strength in [1e38, 3.0] {
            let e = EnvironmentLight::new(map.clone(), strength, Mat3::IDENTITY)
                .expect_err("overflowing strength refused");
            assert!(e.contains("too large to represent"), "{e}");
        }
        let light = EnvironmentLight::new(map, 1.5, Mat3::IDENTITY).expect("finite radiance");
        assert_eq!(
            DistantLight::Environment(light).max_radiance(),
            1.5 * 1.7e38
        );
    }
}
