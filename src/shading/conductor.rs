//! The rough conductor ("Glossy"): GGX (Trowbridge–Reitz) microfacet reflection, Schlick's
//! Fresnel with a per-channel reflectance at normal incidence, height-correlated Smith
//! shadowing; directions are sampled from the visible normals ([`super::microfacet`]). Below
//! [`super::microfacet::SPECULAR_ALPHA`] it is a perfect mirror reflecting Schlick's Fresnel at
//! the view's cosine. No ECS here.

use glam::Vec3;

use super::microfacet::{Terms, is_specular_alpha, sample_visible_normal, schlick_rgb};
use super::sampler::Sampler;
use super::sampling::{Frame, reflect};
use super::scatter::Scatter;

/// A GGX conductor at one surface point (its texture already looked up).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conductor {
    /// Reflectance at normal incidence (Schlick's F0), per channel.
    pub f0: Vec3,
    /// GGX α.
    pub alpha: f32,
}

impl Conductor {
    /// Whether the lobe is a perfect mirror (a delta lobe, nothing of it evaluable).
    #[inline]
    pub fn is_specular(&self) -> bool {
        is_specular_alpha(self.alpha)
    }

    /// Density of `wi` under visible-normal sampling: G₁(wo) D(h) / (4 cos θo).
    #[inline]
    fn pdf(t: &Terms, cos_o: f32) -> f32 {
        t.d / ((1.0 + t.lo) * 4.0 * cos_o)
    }

    /// f·cos θi and the density of `wi` for a ray arriving along `d` at a surface of unit
    /// normal `n` (either side); `None` for the perfect mirror.
    #[inline(always)]
    pub fn eval(&self, d: Vec3, wi: Vec3, n: Vec3) -> Option<(Vec3, f32)> {
        if self.is_specular() {
            return None;
        }
        let facing = if d.dot(n) < 0.0 { n } else { -n };
        let wo = -d;
        let (cos_o, cos_i) = (wo.dot(facing), wi.dot(facing));
        if cos_i <= 0.0 || cos_o <= 0.0 {
            return Some((Vec3::ZERO, 0.0));
        }
        let t = Terms::new(wo, wi, facing, self.alpha);
        // f·cos θi = F D G₂ / (4 cos θo cos θi) · cos θi.
        let f = schlick_rgb(self.f0, t.cos_oh);
        Some((
            f * (t.d / ((1.0 + t.lo + t.li) * 4.0 * cos_o)),
            Self::pdf(&t, cos_o),
        ))
    }

    /// A reflection of a ray along `d` about a visible normal (one 2D sample), or the mirror
    /// direction of a smooth lobe (no sample); `None` if it points below the surface.
    #[inline(always)]
    pub fn sample(&self, d: Vec3, n: Vec3, sampler: &mut impl Sampler) -> Option<Scatter> {
        let facing = if d.dot(n) < 0.0 { n } else { -n };
        let wo = -d;
        let cos_o = wo.dot(facing);
        if self.is_specular() {
            // A perfect mirror: G₂/G₁ → 1 and h → n as α → 0, so the weight is F(wo · n).
            return (cos_o > 0.0).then(|| Scatter {
                direction: reflect(d, facing).normalize(),
                attenuation: schlick_rgb(self.f0, cos_o),
                pdf: None,
                radiance_scale: 1.0,
            });
        }
        let frame = Frame::from_normal(facing);
        let wo_local = Vec3::new(wo.dot(frame.s), wo.dot(frame.t), cos_o.max(1e-6)).normalize();
        let u = sampler.next_2d();
        let h = frame.to_world(sample_visible_normal(wo_local, self.alpha, u));
        let direction = reflect(d, h).normalize();
        if direction.dot(facing) <= 0.0 || cos_o <= 0.0 {
            return None;
        }
        // The terms are recomputed from (wo, direction) exactly as `eval` computes them, so
        // the two agree to rounding even for a near-mirror lobe.
        let t = Terms::new(wo, direction, facing, self.alpha);
        let f = schlick_rgb(self.f0, t.cos_oh);
        // f·cos/pdf = F G₂ / G₁(wo) ≤ F: never more energy than Fresnel allows.
        Some(Scatter {
            direction,
            attenuation: f * ((1.0 + t.lo) / (1.0 + t.lo + t.li)),
            pdf: Some(Self::pdf(&t, cos_o)),
            radiance_scale: 1.0,
        })
    }
}
