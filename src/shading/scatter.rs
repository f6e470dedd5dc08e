//! A sampled continuation of a path: what every lobe's sampling returns. No ECS here.

use glam::Vec3;

/// A sampled continuation of a path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scatter {
    /// Unit direction of the new ray.
    pub direction: Vec3,
    /// Path throughput factor (BSDF · cos / pdf).
    pub attenuation: Vec3,
    /// Solid-angle density of `direction`, if the BSDF can evaluate it (`None` for mirror,
    /// glass and the fuzzed metal, which next-event estimation cannot use).
    pub pdf: Option<f32>,
    /// The factor of `attenuation` that is the (n1/n2)² compression of radiance at a
    /// refraction, 1 otherwise: Russian roulette decides on the throughput without it.
    pub radiance_scale: f32,
}
