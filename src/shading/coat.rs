//! A clear coat over the metallic–roughness BRDF (`KHR_materials_clearcoat`): a colourless GGX
//! dielectric layer (ior 1.5: the exact Fresnel, height-correlated Smith, its own roughness) of
//! strength `weight` over the whole [`Pbr`]. No ECS here.
//!
//! The BRDF is `weight f_coat(wo, wi) + (1 − weight E_c(μo)) f_base(wo, wi)`, E_c the coat
//! lobe's directional albedo (the dielectric table of [`super::albedo_table`]: the same lobe).
//! The base gets exactly what the coat does not reflect towards the view, so the albedo is
//! `weight E_c(μo) + (1 − weight E_c(μo)) a_base(μo)`: never above 1 when the base's is not,
//! and 1 over a white base that loses nothing (a clear, non-absorbing coat on a white base
//! returns all light, and so does this). The spec's informative `fresnel_coat` weighs the base
//! by `1 − weight F(V·H)` instead, which, as `fresnel_mix` does for the dielectric base
//! ([`super::pbr`]), gains light at grazing angles. The weight depends on the view alone, like
//! the spec's albedo scaling of sheen, so the layered BRDF is not exactly reciprocal; the
//! symmetric weight `(1 − E_c(μo))(1 − E_c(μi)) / (1 − E_c,avg)` is exact only for a Lambertian
//! base and gains light over the base's own specular lobe. The coat shades with the base's
//! normal (normal map included).
//!
//! Sampling picks the coat (visible normals, or its mirror direction below
//! [`super::microfacet::SPECULAR_ALPHA`]) with a probability that depends on `wo` only
//! ([`Coated::coat_probability`]), else samples the base, so the density of a direction is the
//! exact mixture `q·pdf_coat + (1 − q)·pdf_base`, which [`Coated::eval`] gives; a delta lobe
//! (the smooth coat's or the base's mirror) has no density and is left out of both.

use glam::{Vec2, Vec3};

use super::energy::AlbedoRow;
use super::fresnel::fresnel_dielectric;
use super::microfacet::{Terms, is_specular_alpha, sample_visible_normal};
use super::pbr::{Pbr, PbrSample};
use super::sampling::Frame;
use super::specular::DIELECTRIC_IOR;

/// A clear coat over a metallic–roughness BRDF at one surface point (textures looked up).
#[derive(Clone, Copy, Debug)]
pub struct Coated {
    /// The BRDF under the coat.
    pub base: Pbr,
    /// Strength of the coat (`clearcoatFactor`) in [0, 1].
    pub weight: f32,
    /// GGX α of the coat.
    pub alpha: f32,
}

impl Coated {
    /// Whether the coat is a perfect mirror (α below [`super::microfacet::SPECULAR_ALPHA`]).
    #[inline]
    pub fn is_smooth(&self) -> bool {
        is_specular_alpha(self.alpha)
    }

    /// Whether nothing of the BRDF can be evaluated: a smooth coat over a base that is a perfect
    /// mirror ([`Pbr::is_delta`]).
    #[inline]
    pub fn is_delta(&self) -> bool {
        (self.is_smooth() || self.weight <= 0.0) && self.base.is_delta()
    }

    /// The coat's Fresnel (ior 1.5) at cosine `cos`.
    #[inline]
    fn fresnel(cos: f32) -> f32 {
        fresnel_dielectric(cos, DIELECTRIC_IOR)
    }

    /// `weight E_c(μo)`: the share of light from the view the coat reflects.
    #[inline]
    fn reflected(&self, cos_o: f32) -> f32 {
        self.weight * AlbedoRow::new(self.alpha).dielectric(cos_o)
    }

    /// Probability of sampling the coat for a view at cosine `cos_o`: its share of the albedo,
    /// `weight E_c(μo)` against the base's estimate ([`Pbr::albedo_estimate`]) times what the
    /// coat leaves.
    #[inline]
    pub fn coat_probability(&self, cos_o: f32) -> f32 {
        self.probability(cos_o, self.reflected(cos_o))
    }

    /// [`Coated::coat_probability`] with `weight E_c(μo)` already found.
    #[inline]
    fn probability(&self, cos_o: f32, coat: f32) -> f32 {
        let total = coat + (1.0 - coat) * self.base.albedo_estimate(cos_o);
        if total <= 0.0 || !total.is_finite() {
            1.0
        } else {
            (coat / total).clamp(0.0, 1.0)
        }
    }

    /// BRDF times `cos θi` and the density of `wi` under [`Coated::sample`], for unit `wo`
    /// (towards the viewer) and `wi` (towards the light) about unit normal `n` on the viewer's
    /// side; zero when either is below the surface. Delta lobes (a smooth coat, the base's
    /// mirror) are left out of both.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3, n: Vec3) -> (Vec3, f32) {
        let (cos_o, cos_i) = (wo.dot(n), wi.dot(n));
        if cos_o <= 0.0 || cos_i <= 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        let coat = self.reflected(cos_o);
        let q = self.probability(cos_o, coat);
        let (f_base, pdf_base) = self.base.eval(wo, wi, n);
        let (f, pdf) = ((1.0 - coat) * f_base, (1.0 - q) * pdf_base);
        if self.is_smooth() {
            return (f, pdf);
        }
        let t = Terms::new(wo, wi, n, self.alpha);
        let d = t.d / (4.0 * cos_o);
        let f_coat = self.weight * Self::fresnel(t.cos_oh.abs()) * d / (1.0 + t.lo + t.li);
        (f + Vec3::splat(f_coat), pdf + q * d / (1.0 + t.lo))
    }

    /// Samples `wi` for unit `wo` about unit normal `n` (the viewer's side) from the uniform
    /// pair `u`: `u.x` first chooses the coat or the base, then is rescaled to reuse it. `None`
    /// if the direction is below the surface (absorbed) or has no density.
    #[inline]
    pub fn sample(&self, wo: Vec3, n: Vec3, u: Vec2) -> Option<PbrSample> {
        let cos_o = wo.dot(n);
        if cos_o <= 0.0 {
            return None;
        }
        let coat = self.reflected(cos_o);
        let q = self.probability(cos_o, coat);
        let wi = if u.x < q {
            if self.is_smooth() {
                return Some(PbrSample {
                    wi: (2.0 * cos_o * n - wo).normalize(),
                    weight: Vec3::splat(self.weight * Self::fresnel(cos_o) / q),
                    pdf: None,
                });
            }
            let u = Vec2::new((u.x / q).min(1.0), u.y);
            let frame = Frame::from_normal(n);
            let wo_local = Vec3::new(wo.dot(frame.s), wo.dot(frame.t), cos_o.max(1e-6)).normalize();
            let h = frame.to_world(sample_visible_normal(wo_local, self.alpha, u));
            (2.0 * wo.dot(h) * h - wo).normalize()
        } else {
            let u = Vec2::new(((u.x - q) / (1.0 - q)).clamp(0.0, 1.0), u.y);
            let s = self.base.sample(wo, n, u)?;
            if s.pdf.is_none() {
                // The base's mirror: its weight, under the coat, over this choice's probability.
                return Some(PbrSample {
                    weight: (1.0 - coat) * s.weight / (1.0 - q),
                    ..s
                });
            }
            s.wi
        };
        PbrSample::evaluated(wi, n, self.eval(wo, wi, n))
    }
}
