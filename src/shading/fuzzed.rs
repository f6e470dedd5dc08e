//! The fuzzed mirror ("Metal"): the mirror direction plus `roughness` times a random point of
//! the unit ball; directions that end up below the surface are absorbed. It has no density, so
//! next-event estimation leaves it to BSDF sampling. No ECS here.

use glam::Vec3;

use super::sampler::Sampler;
use super::sampling::{facing, reflect, uniform_ball};
use super::scatter::Scatter;

/// A fuzzed mirror at one surface point (its texture already looked up).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fuzzed {
    /// Reflectance.
    pub albedo: Vec3,
    /// Fuzz radius in [0, 1]; 0 is a perfect mirror.
    pub roughness: f32,
}

impl Fuzzed {
    /// The fuzzed reflection of a ray along `d` at a surface of unit normal `n` (either side),
    /// from one 2D and one 1D sample; `None` if it points below the surface (absorbed).
    #[inline(always)]
    pub fn sample(&self, d: Vec3, n: Vec3, sampler: &mut impl Sampler) -> Option<Scatter> {
        let facing = facing(d, n);
        let u = sampler.next_2d();
        let fuzz = uniform_ball(u.extend(sampler.next_1d()));
        let r = reflect(d, facing) + self.roughness * fuzz;
        if r.dot(facing) <= 0.0 {
            return None;
        }
        Some(Scatter {
            direction: r.normalize(),
            attenuation: self.albedo,
            pdf: None,
            radiance_scale: 1.0,
        })
    }
}
