//! The Lambertian lobe: reflectance `albedo / π`, directions cosine-sampled in a frame about
//! the normal, so they are never the zero vector. No ECS here.

use glam::Vec3;

use super::sampler::Sampler;
use super::sampling::{Frame, cosine_hemisphere, facing};
use super::scatter::Scatter;

/// A Lambertian reflector at one surface point (its texture already looked up).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Diffuse {
    /// Reflectance.
    pub albedo: Vec3,
}

impl Diffuse {
    /// f·cos θi and the density of `wi` for a ray arriving along `d` at a surface of unit
    /// normal `n` (either side): zero below the surface on the ray's side.
    #[inline(always)]
    pub fn eval(&self, d: Vec3, wi: Vec3, n: Vec3) -> (Vec3, f32) {
        let facing = facing(d, n);
        let cos = wi.dot(facing);
        if cos <= 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        let pdf = cos * std::f32::consts::FRAC_1_PI;
        (self.albedo * pdf, pdf)
    }

    /// A cosine-distributed direction about the normal on the side `d` came from (one 2D
    /// sample); the weight f·cos/pdf is the albedo.
    #[inline(always)]
    pub fn sample(&self, d: Vec3, n: Vec3, sampler: &mut impl Sampler) -> Scatter {
        let facing = facing(d, n);
        let local = cosine_hemisphere(sampler.next_2d());
        let direction = Frame::from_normal(facing).to_world(local).normalize();
        Scatter {
            direction,
            attenuation: self.albedo,
            pdf: Some(local.z * std::f32::consts::FRAC_1_PI),
            radiance_scale: 1.0,
        }
    }
}
