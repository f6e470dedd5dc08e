//! The rough conductor ("Glossy"): GGX (Trowbridge–Reitz) microfacet reflection, Schlick's
//! Fresnel with a per-channel reflectance at normal incidence, height-correlated Smith
//! shadowing, and the multiple scattering between microfacets that single-scattering GGX drops,
//! restored by Kulla & Conty's compensation lobe ([`super::energy`]). Below
//! [`super::microfacet::SPECULAR_ALPHA`] it is a perfect mirror reflecting Schlick's Fresnel at
//! the view's cosine (it loses nothing, so it has no compensation). No ECS here.
//!
//! The BRDF is `f_ss + F_ms (1 − E(μo)) (1 − E(μi)) / (π (1 − E_avg))`, E the white lobe's
//! directional albedo and F_ms [`multiple_scattering_fresnel`]: a white conductor reflects
//! E(μo) + 1 − E(μo) = 1 at every angle (a white ball of roughness 1 in a white furnace
//! averaged 0.38 with single scattering alone). Directions are sampled from the visible normals
//! ([`super::microfacet`]) with a probability that depends on `wo` only, else from the cosine,
//! and the density of a direction is the exact mixture of the two. The compensation is an added
//! lobe rather than Turquin's (2019) scaling of the single-scattering lobe by
//! `1 + F0 (1/E(μo) − 1)`: that scaling needs no second sampling strategy, but it depends on
//! `wo` alone, so the BRDF is not reciprocal, and `Pbr`, which shares this lobe, already mixes a
//! cosine-sampled lobe in; the added lobe is reciprocal and its value and density are evaluated
//! in one place ([`Conductor::eval`]) for both sampling and light sampling.

use std::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3};

use super::energy::{AlbedoRow, compensation, multiple_scattering_fresnel};
use super::microfacet::{Terms, is_specular_alpha, sample_visible_normal, schlick_rgb};
use super::sampler::Sampler;
use super::sampling::{Frame, cosine_hemisphere, facing, reflect};
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

    /// The probability of sampling the single-scattering lobe for a view at cosine `cos_o`
    /// (`row`: the tables' row of the lobe's α): its share of the lobes' albedos (mean over
    /// the channels), F(μo) E(μo) against F_ms (1 − E(μo)). 1 where nothing is compensated.
    #[inline(always)]
    fn probability(&self, row: &AlbedoRow, cos_o: f32) -> f32 {
        let e = row.conductor(cos_o);
        let single = schlick_rgb(self.f0, cos_o).element_sum() * e;
        let multiple =
            multiple_scattering_fresnel(self.f0, row.conductor_lost()).element_sum() * (1.0 - e);
        if multiple <= 0.0 || !multiple.is_finite() {
            1.0
        } else {
            (single / (single + multiple)).clamp(0.0, 1.0)
        }
    }

    /// f·cos θi and the density of `wi` for a ray arriving along `d` at a surface of unit
    /// normal `n` (either side); `None` for the perfect mirror.
    #[inline(always)]
    pub fn eval(&self, d: Vec3, wi: Vec3, n: Vec3) -> Option<(Vec3, f32)> {
        if self.is_specular() {
            return None;
        }
        let facing = facing(d, n);
        let wo = -d;
        let (cos_o, cos_i) = (wo.dot(facing), wi.dot(facing));
        if cos_i <= 0.0 || cos_o <= 0.0 {
            return Some((Vec3::ZERO, 0.0));
        }
        let row = AlbedoRow::new(self.alpha);
        let p = self.probability(&row, cos_o);
        Some(self.eval_above(wo, wi, facing, &row, p))
    }

    /// [`Conductor::eval`] of `wo` → `wi` about the normal `facing` on their side (both
    /// cosines positive), with the tables' row and the single-scattering lobe's probability `p`
    /// for `wo` already found: [`Conductor::sample`] has them from choosing the lobe.
    #[inline(always)]
    fn eval_above(&self, wo: Vec3, wi: Vec3, facing: Vec3, row: &AlbedoRow, p: f32) -> (Vec3, f32) {
        let (cos_o, cos_i) = (wo.dot(facing), wi.dot(facing));
        let t = Terms::new(wo, wi, facing, self.alpha);
        // Single scattering, f·cos θi = F D G₂ / (4 cos θo cos θi) · cos θi, and its density
        // under visible-normal sampling, G₁(wo) D(h) / (4 cos θo).
        let q = t.d / (4.0 * cos_o);
        let single = schlick_rgb(self.f0, t.cos_oh) * (q / (1.0 + t.lo + t.li));
        let lost = row.conductor_lost();
        let multiple = multiple_scattering_fresnel(self.f0, lost)
            * (compensation(row.conductor(cos_o), row.conductor(cos_i), lost) * cos_i);
        (
            single + multiple,
            p * (q / (1.0 + t.lo)) + (1.0 - p) * cos_i * FRAC_1_PI,
        )
    }

    /// A reflection of a ray along `d` about a visible normal or from the cosine (one 2D
    /// sample: `u.x` chooses the lobe and is rescaled to be reused), or the mirror direction of
    /// a smooth lobe (no sample); `None` if it points below the surface.
    #[inline(always)]
    pub fn sample(&self, d: Vec3, n: Vec3, sampler: &mut impl Sampler) -> Option<Scatter> {
        let facing = facing(d, n);
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
        if cos_o <= 0.0 {
            return None;
        }
        let frame = Frame::from_normal(facing);
        let u = sampler.next_2d();
        let row = AlbedoRow::new(self.alpha);
        let p = self.probability(&row, cos_o);
        let direction = if u.x < p {
            let u = Vec2::new((u.x / p).min(1.0), u.y);
            let wo_local = Vec3::new(wo.dot(frame.s), wo.dot(frame.t), cos_o.max(1e-6)).normalize();
            let h = frame.to_world(sample_visible_normal(wo_local, self.alpha, u));
            reflect(d, h).normalize()
        } else {
            let u = Vec2::new(((u.x - p) / (1.0 - p)).clamp(0.0, 1.0), u.y);
            frame.to_world(cosine_hemisphere(u)).normalize()
        };
        if direction.dot(facing) <= 0.0 {
            return None;
        }
        // Value and density from `eval`'s own arithmetic, so that the two agree to rounding.
        let (f_cos, pdf) = self.eval_above(wo, direction, facing, &row, p);
        (pdf > 0.0 && pdf.is_finite()).then(|| Scatter {
            direction,
            attenuation: f_cos / pdf,
            pdf: Some(pdf),
            radiance_scale: 1.0,
        })
    }
}
