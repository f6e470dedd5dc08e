//! The sun: a distant disk of constant radiance, sampled uniformly in the cone of directions it
//! subtends. No ECS here.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use crate::shading::sampling::unit_circle;

/// A distant disk seen under a small cone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sun {
    /// Unit direction from the scene towards the sun's centre.
    direction: Vec3,
    /// Two unit vectors completing `direction` to a frame.
    tangent: Vec3,
    bitangent: Vec3,
    /// `sin²` of the cone's half-angle: a direction is in the disk when its `sin²` angle to
    /// `direction` is at most this (more precise than comparing cosines near 1).
    sin2_max: f32,
    /// `1 − cos` of the half-angle: the cone's solid angle over 2π.
    one_minus_cos: f32,
    /// Radiance of the disk.
    radiance: Vec3,
}

impl Sun {
    /// A sun towards `direction` (non-zero) whose disk has angular diameter
    /// `angular_diameter` radians in (0, π/2] and the given radiance.
    pub fn new(direction: Vec3, angular_diameter: f32, radiance: Vec3) -> Self {
        let direction = direction.normalize();
        let (tangent, bitangent) = direction.any_orthonormal_pair();
        let half = 0.5 * f64::from(angular_diameter);
        Self {
            direction,
            tangent,
            bitangent,
            sin2_max: half.sin().powi(2) as f32,
            one_minus_cos: (2.0 * (0.5 * half).sin().powi(2)) as f32,
            radiance,
        }
    }

    /// The radiance that makes irradiance `irradiance` on a plane facing a sun of angular
    /// diameter `angular_diameter` radians: `E = L · π sin²(half-angle)` (the cosine-weighted
    /// solid angle of the disk).
    pub fn radiance_for_irradiance(irradiance: Vec3, angular_diameter: f32) -> Vec3 {
        let s = (0.5 * f64::from(angular_diameter)).sin();
        irradiance / (std::f64::consts::PI * s * s) as f32
    }

    /// Solid angle of the disk, `2π (1 − cos half-angle)`.
    pub fn solid_angle(&self) -> f32 {
        2.0 * PI * self.one_minus_cos
    }

    /// Radiance of the disk.
    pub fn disk_radiance(&self) -> Vec3 {
        self.radiance
    }

    /// Whether unit direction `d` points into the disk.
    #[inline]
    fn contains(&self, d: Vec3) -> bool {
        d.dot(self.direction) > 0.0 && d.cross(self.direction).length_squared() <= self.sin2_max
    }

    /// Radiance arriving along unit direction `d` (towards the sky).
    #[inline]
    pub fn radiance(&self, d: Vec3) -> Vec3 {
        if self.contains(d) {
            self.radiance
        } else {
            Vec3::ZERO
        }
    }

    /// Density per steradian with which [`Sun::sample`] gives `d`: uniform over the cone.
    #[inline]
    pub fn pdf(&self, d: Vec3) -> f32 {
        if self.contains(d) {
            1.0 / self.solid_angle()
        } else {
            0.0
        }
    }

    /// A unit direction uniform in the disk's cone. Always inlined: it runs once per light
    /// sample of a sunlit scene, and inlined into the render loop it is compiled for the
    /// loop's instructions (see [`crate::cpu`]), not the baseline's.
    #[inline(always)]
    pub fn sample(&self, u: Vec2) -> Vec3 {
        // cos θ = 1 − u·(1 − cos max), with sin θ from the product form, exact near θ = 0.
        let a = u.x * self.one_minus_cos;
        let cos_theta = 1.0 - a;
        let sin_theta = (a * (2.0 - a)).max(0.0).sqrt();
        let phi = unit_circle(u.y);
        (sin_theta * (phi.x * self.tangent + phi.y * self.bitangent) + cos_theta * self.direction)
            .normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_stay_in_the_disk_and_cover_it_uniformly() {
        // 0.53°: the real sun. The disk's solid angle is π sin² for small angles; samples all
        // count as inside, and their mean direction is the centre.
        let diameter = 0.53f32.to_radians();
        let sun = Sun::new(Vec3::new(0.3, 1.0, -0.2), diameter, Vec3::ONE);
        let half = 0.5 * diameter;
        assert!((sun.solid_angle() / (PI * half * half) - 1.0).abs() < 1e-4);
        let mut rng = crate::shading::rng::Rng::new(5, 6);
        let mut inner = 0;
        let n = 20_000;
        for _ in 0..n {
            let d = sun.sample(Vec2::new(rng.next_f32(), rng.next_f32()));
            assert!(sun.contains(d), "{d}");
            // Uniform in the cone: the inner half of the angle holds ~¼ of the samples.
            let angle = d.cross(sun.direction).length().asin();
            inner += u32::from(angle < 0.5 * half);
        }
        let share = f64::from(inner) / f64::from(n);
        assert!((share - 0.25).abs() < 0.015, "inner share {share}");
        assert_eq!(sun.radiance(-sun.direction), Vec3::ZERO);
        assert_eq!(sun.pdf(sun.tangent), 0.0);
    }

    #[test]
    fn irradiance_converts_by_the_disk_cosine_weighted_solid_angle() {
        let d = 0.53f32.to_radians();
        let l = Sun::radiance_for_irradiance(Vec3::splat(3.0), d);
        // Small angle: E ≈ L · Ω.
        let sun = Sun::new(Vec3::Y, d, l);
        assert!((l.x * sun.solid_angle() / 3.0 - 1.0).abs() < 1e-4);
    }
}
