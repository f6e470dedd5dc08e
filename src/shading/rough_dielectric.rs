//! Rough glass: GGX microfacet reflection and transmission (Walter et al., "Microfacet Models
//! for Refraction through Rough Surfaces", EGSR 2007), the exact Fresnel reflectance
//! ([`super::fresnel`]) at each microfacet, height-correlated Smith shadowing, directions from
//! the visible normals ([`super::microfacet`]). The formulas follow pbrt-v4's `DielectricBxDF`
//! (`src/pbrt/bxdfs.h`, `.cpp`). No ECS here.
//!
//! A sample draws a visible microfacet normal h (one 2D sample), then reflects about it with
//! probability F(wo·h) or refracts through it otherwise (one 1D sample), so that the weight
//! f·cos/pdf is G₂/G₁ times 1 (reflection) or times the (n1/n2)² radiance compression
//! (transmission), as for the smooth glass ([`super::dielectric`]). The density of a direction
//! is that of its half vector times the Jacobian of the map h → wi: 1/(4|wo·h|) for
//! reflection, |wi·h| / (wi·h + wo·h/η)² for refraction (Walter et al., eq. 14 and 17).
//!
//! Single scattering alone loses the light that would bounce between microfacets again: a
//! rough glass ball in a white furnace kept 0.95 at roughness 0.3 and 0.34 at 1, since light
//! inside meets the interface many times. That loss is put back by scaling the lobe by
//! 1 / E(μo, α, η), E the single-scattering interface's directional albedo (reflected plus
//! transmitted flux) for the view's side, read from a precomputed table
//! ([`super::glass_table`]): Turquin's energy compensation for dielectrics ("Practical
//! multiple scattering compensation for microfacet models", 2019). The extra light leaves in the
//! single-scattering lobe's directions and split between reflection and transmission as it is,
//! where true multiple scattering would spread it wider; the scaled lobe is not reciprocal
//! (1/E depends on the view alone), which a path tracer that only ever evaluates it from the
//! camera's side does not notice. Sampled density and evaluated density are unchanged.

use glam::Vec3;

use super::dielectric::refract;
use super::fresnel::fresnel_dielectric;
use super::glass_table::{COS_NODES, ETA_MAX, ETA_NODES, GLASS, ROUGHNESS_NODES};
use super::microfacet::{cos2_sin2, distribution, lambda, sample_visible_normal};
use super::sampler::Sampler;
use super::sampling::{Frame, reflect};
use super::scatter::Scatter;

/// Rough glass of index `ior` relative to the outside medium and GGX `alpha`, at one point. Its
/// geometric normal points outside.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughDielectric {
    /// Index of refraction relative to the outside medium.
    pub ior: f32,
    /// GGX α (at least [`super::microfacet::SPECULAR_ALPHA`]; below, the glass is smooth).
    pub alpha: f32,
}

/// The value and density of one direction, and the radiance scale it carries.
#[derive(Clone, Copy, Debug)]
struct Evaluated {
    f_cos: f32,
    pdf: f32,
    radiance_scale: f32,
}

const NOTHING: Evaluated = Evaluated {
    f_cos: 0.0,
    pdf: 0.0,
    radiance_scale: 1.0,
};

impl RoughDielectric {
    /// The normal on the side of `wo` and the relative index η = n_beyond / n_wo of crossing
    /// the surface (of outward normal `n`) from that side; `None` for `wo` in the surface.
    #[inline]
    fn side(&self, wo: Vec3, n: Vec3) -> Option<(Vec3, f32)> {
        let cos_o = wo.dot(n);
        if cos_o > 0.0 {
            Some((n, self.ior))
        } else if cos_o < 0.0 {
            Some((-n, 1.0 / self.ior))
        } else {
            None
        }
    }

    /// The energy compensation 1 / E(μo, α, η) of a view of cosine `cos_o` on the side where the
    /// far side's relative index is `eta` (see the module docs): trilinear in √μ, roughness and
    /// ln η between the table's nodes; an index beyond [1/3, 3] reads the table's edge.
    #[inline]
    fn compensation(&self, cos_o: f32, eta: f32) -> f32 {
        /// Node below `x` (in node units, clamped) and the weight of the one above.
        #[inline(always)]
        fn cell(x: f32, nodes: usize) -> (usize, f32) {
            let x = x.clamp(0.0, (nodes - 1) as f32);
            let i = (x as usize).min(nodes - 2);
            (i, x - i as f32)
        }
        let (i, u) = cell(
            cos_o.clamp(0.0, 1.0).sqrt() * (COS_NODES - 1) as f32,
            COS_NODES,
        );
        let (j, v) = cell(
            self.alpha.max(0.0).sqrt() * (ROUGHNESS_NODES - 1) as f32,
            ROUGHNESS_NODES,
        );
        let (k, w) = cell(
            (eta.ln() / ETA_MAX.ln() + 1.0) * 0.5 * (ETA_NODES - 1) as f32,
            ETA_NODES,
        );
        let row = |k: usize, j: usize| {
            let r = &GLASS[k][j];
            r[i] + (r[i + 1] - r[i]) * u
        };
        let plane = |k: usize| row(k, j) + (row(k, j + 1) - row(k, j)) * v;
        let albedo = plane(k) + (plane(k + 1) - plane(k)) * w;
        if albedo > 0.0 { 1.0 / albedo } else { 1.0 }
    }

    /// Value (f·|cos θi|, energy compensated), density and radiance scale of `wi` for `wo` (both
    /// unit), with `up` the normal on `wo`'s side and `eta` the relative index from there.
    #[inline]
    fn evaluate(&self, wo: Vec3, wi: Vec3, up: Vec3, eta: f32) -> Evaluated {
        let single = self.evaluate_single(wo, wi, up, eta);
        Evaluated {
            f_cos: single.f_cos * self.compensation(wo.dot(up), eta),
            ..single
        }
    }

    /// [`Self::evaluate`] of the single-scattering lobe alone.
    #[inline]
    fn evaluate_single(&self, wo: Vec3, wi: Vec3, up: Vec3, eta: f32) -> Evaluated {
        let (cos_o, cos_i) = (wo.dot(up), wi.dot(up));
        if cos_o <= 0.0 || cos_i == 0.0 {
            return NOTHING;
        }
        let reflected = cos_i > 0.0;
        let etap = if reflected { 1.0 } else { eta };
        // The generalised half vector (Walter et al., eq. 16), facing `up`.
        let h = wo + etap * wi;
        let len2 = h.length_squared();
        if len2.is_nan() || len2 <= 0.0 {
            return NOTHING;
        }
        let h = h / len2.sqrt();
        let h = if h.dot(up) < 0.0 { -h } else { h };
        let (cos_oh, cos_ih) = (wo.dot(h), wi.dot(h));
        // Back-facing microfacets scatter nothing.
        if cos_oh <= 0.0 || cos_ih * cos_i <= 0.0 {
            return NOTHING;
        }
        let (c2h, s2h) = cos2_sin2(h, up);
        let (c2o, s2o) = cos2_sin2(wo, up);
        let (c2i, s2i) = cos2_sin2(wi, up);
        let d = distribution(c2h, s2h, self.alpha);
        let (lo, li) = (lambda(c2o, s2o, self.alpha), lambda(c2i, s2i, self.alpha));
        let g2 = 1.0 / (1.0 + lo + li);
        let f = fresnel_dielectric(cos_oh, eta);
        // Density of h among the normals visible from wo: G₁(wo) D(h) (wo·h) / cos θo.
        let pdf_h = d * cos_oh / ((1.0 + lo) * cos_o);
        if reflected {
            // f cos θi = F D G₂ / (4 cos θo).
            return Evaluated {
                f_cos: f * d * g2 / (4.0 * cos_o),
                pdf: pdf_h / (4.0 * cos_oh) * f,
                radiance_scale: 1.0,
            };
        }
        let denom = cos_ih + cos_oh / etap;
        let denom2 = denom * denom;
        if denom2.is_nan() || denom2 <= 0.0 {
            return NOTHING;
        }
        let jacobian = cos_ih.abs() / denom2;
        // f cos θi = (1 − F) D G₂ |wi·h| |wo·h| / ((wi·h + wo·h/η)² cos θo), times the (1/η)²
        // compression of radiance that crosses into a medium of η times the index.
        let radiance_scale = 1.0 / (eta * eta);
        Evaluated {
            f_cos: (1.0 - f) * d * g2 * jacobian * cos_oh / cos_o * radiance_scale,
            pdf: pdf_h * jacobian * (1.0 - f),
            radiance_scale,
        }
    }

    /// f·|cos θi| and the density of `wi` (either side) for a ray arriving along `d` at a
    /// surface of unit outward normal `n`.
    #[inline]
    pub fn eval(&self, d: Vec3, wi: Vec3, n: Vec3) -> (Vec3, f32) {
        let wo = -d;
        let Some((up, eta)) = self.side(wo, n) else {
            return (Vec3::ZERO, 0.0);
        };
        let e = self.evaluate(wo, wi, up, eta);
        (Vec3::splat(e.f_cos), e.pdf)
    }

    /// A reflection or refraction of a ray along `d` about a visible microfacet normal (one 2D
    /// sample for the normal, one 1D sample for the choice, by Fresnel); `None` if the
    /// direction ends on the wrong side of the surface or has no density.
    #[inline]
    pub fn sample(&self, d: Vec3, n: Vec3, sampler: &mut impl Sampler) -> Option<Scatter> {
        let wo = -d;
        let (up, eta) = self.side(wo, n)?;
        let frame = Frame::from_normal(up);
        let cos_o = wo.dot(up);
        let wo_local = Vec3::new(wo.dot(frame.s), wo.dot(frame.t), cos_o.max(1e-6)).normalize();
        let h = frame.to_world(sample_visible_normal(
            wo_local,
            self.alpha,
            sampler.next_2d(),
        ));
        let cos_oh = wo.dot(h);
        let f = fresnel_dielectric(cos_oh, eta);
        // A reflection must stay on wo's side and a refraction cross to the other; otherwise the
        // path ends (the microfacet's light is lost, as single scattering loses it).
        let wi = if sampler.next_1d() < f {
            Some(reflect(d, h).normalize()).filter(|wi| wi.dot(up) > 0.0)
        } else {
            refract(d, h, 1.0 / eta).filter(|wi| wi.dot(up) < 0.0)
        }?;
        // The value and density are recomputed from (wo, wi) exactly as `eval` does, so the
        // two agree to rounding.
        let e = self.evaluate(wo, wi, up, eta);
        (e.pdf > 0.0 && e.pdf.is_finite()).then(|| Scatter {
            direction: wi,
            attenuation: Vec3::splat(e.f_cos / e.pdf),
            pdf: Some(e.pdf),
            radiance_scale: e.radiance_scale,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::rng::Rng;

    fn dir(theta: f32, phi: f32) -> Vec3 {
        Vec3::new(
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        )
    }

    #[test]
    fn sampled_weights_and_densities_match_eval_on_both_sides() {
        let mut rng = Rng::new(21, 5);
        for alpha in [0.002f32, 0.05, 0.3, 1.0] {
            let glass = RoughDielectric { ior: 1.5, alpha };
            for k in 0..4000 {
                let theta = 1.55 * (k as f32 + 0.5) / 4000.0;
                let wo = dir(theta, 0.7 * k as f32);
                let d = if k % 2 == 0 { -wo } else { wo };
                let Some(s) = glass.sample(d, Vec3::Z, &mut rng) else {
                    continue;
                };
                let (f_cos, pdf) = glass.eval(d, s.direction, Vec3::Z);
                let sampled = s.pdf.expect("a density");
                assert!(
                    (pdf - sampled).abs() <= 1e-3 * pdf,
                    "α {alpha}: {pdf} {sampled}"
                );
                assert!(
                    (f_cos.x / pdf - s.attenuation.x).abs() <= 1e-3 * s.attenuation.x.max(1.0),
                    "α {alpha}"
                );
                // The weight is G₂/G₁ ≤ 1 times the radiance scale and the compensation.
                let up = if d.z < 0.0 { Vec3::Z } else { -Vec3::Z };
                let eta = if d.z < 0.0 { 1.5 } else { 1.0 / 1.5 };
                let compensation = glass.compensation(-d.dot(up), eta);
                assert!(
                    s.attenuation.x <= s.radiance_scale * compensation * (1.0 + 1e-4),
                    "α {alpha}"
                );
                let crossed = s.direction.z * d.z > 0.0;
                let expected = match (crossed, d.z < 0.0) {
                    (false, _) => 1.0,
                    (true, true) => 1.0 / 2.25,
                    (true, false) => 2.25,
                };
                assert!((s.radiance_scale - expected).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn single_scattering_transmission_is_reciprocal_up_to_the_squared_indices() {
        // Radiance transmission obeys f(wo → wi) / n_o² = f(wi → wo) / n_i² (Veach 1997, §5.2),
        // n the index on each direction's side; reflection is symmetric. The compensation, a
        // function of the view alone, is divided out.
        let glass = RoughDielectric {
            ior: 1.5,
            alpha: 0.3,
        };
        let mut rng = Rng::new(2, 9);
        let mut checked = 0;
        for _ in 0..20_000 {
            let a = dir(1.5 * rng.next_f32(), std::f32::consts::TAU * rng.next_f32());
            let b = dir(1.5 * rng.next_f32(), std::f32::consts::TAU * rng.next_f32());
            let (wo, wi) = (a, if rng.next_f32() < 0.5 { -b } else { b });
            let compensation = |w: Vec3| {
                let (cos, eta) = if w.z > 0.0 {
                    (w.z, 1.5)
                } else {
                    (-w.z, 1.0 / 1.5)
                };
                glass.compensation(cos, eta)
            };
            let (f_cos, _) = glass.eval(-wo, wi, Vec3::Z);
            let (g_cos, _) = glass.eval(-wi, wo, Vec3::Z);
            let (f, g) = (
                f_cos.x / wi.z.abs() / compensation(wo),
                g_cos.x / wo.z.abs() / compensation(wi),
            );
            let n_o = if wo.z > 0.0 { 1.0 } else { 1.5 };
            let n_i = if wi.z > 0.0 { 1.0 } else { 1.5 };
            let (lhs, rhs) = (f / (n_o * n_o), g / (n_i * n_i));
            if lhs > 1e-3 {
                checked += 1;
                assert!((lhs - rhs).abs() <= 5e-3 * lhs, "{wo} {wi}: {lhs} {rhs}");
            }
        }
        assert!(checked > 1000, "{checked}");
    }
}
