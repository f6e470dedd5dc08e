//! Smooth glass: Fresnel (Schlick) reflection, Snell refraction, total internal reflection. No
//! ECS here.
//!
//! The 2020 ray-tracing thesis rondo grows from (`../shared/seed/`, RTIOW-style) gets three
//! things wrong that are corrected here: Schlick's R0 is `((n1 − n2)/(n1 + n2))²` (the thesis
//! uses n1/n2), the dielectric *reflects* with probability R (the thesis refracts), and diffuse directions are cosine-sampled in a frame
//! ([`super::diffuse`]), so they are never the zero vector.

use glam::Vec3;

use super::sampler::Sampler;
use super::sampling::reflect;
use super::scatter::Scatter;

/// Refraction of unit `d` through a surface with unit normal `n` facing against `d`, with relative
/// index `eta = n1 / n2`. `None` on total internal reflection.
#[inline]
pub fn refract(d: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = (-d.dot(n)).min(1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((eta * d + (eta * cos_i - cos_t) * n).normalize())
}

/// Schlick's approximation of the Fresnel reflectance for light going from index `n1` to `n2` at
/// incidence cosine `cos_i`. Uses the cosine on the optically thinner side, as the approximation
/// requires; returns 1 on total internal reflection.
#[inline]
pub fn schlick(cos_i: f32, n1: f32, n2: f32) -> f32 {
    let r0 = ((n1 - n2) / (n1 + n2)).powi(2);
    let cos = if n1 > n2 {
        let sin2_t = (n1 / n2).powi(2) * (1.0 - cos_i * cos_i).max(0.0);
        if sin2_t >= 1.0 {
            return 1.0;
        }
        (1.0 - sin2_t).sqrt()
    } else {
        cos_i
    };
    r0 + (1.0 - r0) * (1.0 - cos).powi(5)
}

/// Smooth glass of index `ior` relative to the outside medium. Refracted radiance is scaled by
/// (n1/n2)², n1 the index on the side the camera path comes from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dielectric {
    /// Index of refraction relative to the outside medium.
    pub ior: f32,
}

impl Dielectric {
    /// Reflection or refraction of a ray along unit `d` at a surface of unit geometric normal
    /// `n` (pointing outside), chosen by Fresnel from one 1D sample.
    #[inline(always)]
    pub fn sample(&self, d: Vec3, n: Vec3, sampler: &mut impl Sampler) -> Scatter {
        let facing = if d.dot(n) < 0.0 { n } else { -n };
        let entering = d.dot(n) < 0.0;
        let (n1, n2) = if entering {
            (1.0, self.ior)
        } else {
            (self.ior, 1.0)
        };
        let cos_i = (-d.dot(facing)).clamp(0.0, 1.0);
        let r = schlick(cos_i, n1, n2);
        // Radiance crossing an interface is compressed with the solid angle: light reaching the
        // camera side (index n1) from the far side (n2) is scaled by (n1/n2)² (Veach 1997, §5.2;
        // pbrt-v4's `DielectricBxDF` in radiance mode).
        let (direction, scale) = match refract(d, facing, n1 / n2) {
            Some(t) if sampler.next_1d() >= r => (t, (n1 / n2) * (n1 / n2)),
            _ => (reflect(d, facing).normalize(), 1.0),
        };
        Scatter {
            direction,
            attenuation: Vec3::splat(scale),
            pdf: None,
            radiance_scale: scale,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schlick_at_normal_incidence_is_r0() {
        assert!((schlick(1.0, 1.0, 1.5) - 0.04).abs() < 1e-6);
        assert!((schlick(1.0, 1.5, 1.0) - 0.04).abs() < 1e-6);
        // Grazing incidence reflects everything.
        assert!((schlick(0.0, 1.0, 1.5) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn schlick_is_close_to_the_exact_fresnel_equations() {
        // Exact unpolarised Fresnel reflectance for air→glass (n = 1.5), from the Fresnel
        // equations: 0.0400, 0.0415, 0.0502, 0.0892 at 0°, 30°, 45°, 60°. Schlick's curve stays
        // within 0.02 of it there (0.0400, 0.0400, 0.0421, 0.0700).
        let exact = |theta_i: f32, n: f32| {
            let (ci, si) = (theta_i.cos(), theta_i.sin());
            let ct = (1.0 - (si / n).powi(2)).sqrt();
            let rs = ((ci - n * ct) / (ci + n * ct)).powi(2);
            let rp = ((ct - n * ci) / (ct + n * ci)).powi(2);
            0.5 * (rs + rp)
        };
        for deg in [0.0f32, 30.0, 45.0, 60.0] {
            let t = deg.to_radians();
            let (s, e) = (schlick(t.cos(), 1.0, 1.5), exact(t, 1.5));
            assert!((s - e).abs() < 0.02, "{deg}°: schlick {s}, exact {e}");
        }
    }

    #[test]
    fn refraction_obeys_snell_and_is_unit_length() {
        for deg in [1.0f32, 20.0, 40.0, 60.0, 80.0, 89.0] {
            let t = deg.to_radians();
            let d = Vec3::new(t.sin(), 0.0, -t.cos());
            let r = refract(d, Vec3::Z, 1.0 / 1.5).expect("no TIR entering glass");
            assert!((r.length() - 1.0).abs() < 1e-6);
            let sin_t = r.x.hypot(r.y);
            assert!((1.0 * t.sin() - 1.5 * sin_t).abs() < 1e-5, "{deg}°");
            assert!(r.z < 0.0, "refracted ray continues through the surface");
        }
    }
}
