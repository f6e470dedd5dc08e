//! The GGX (Trowbridge–Reitz) microfacet distribution: density, Smith masking, sampling of the
//! visible normals, and the terms of one reflection ([`Terms`]) that both GGX lobes (the
//! conductor and the metallic–roughness mix) evaluate. No ECS here.
//!
//! References: Walter et al., "Microfacet Models for Refraction through Rough Surfaces" (EGSR
//! 2007) for D and Λ; Heitz, "Understanding the Masking-Shadowing Function in Microfacet-Based
//! BRDFs" (JCGT 2014) for the height-correlated G₂; Heitz, "Sampling the GGX Distribution of
//! Visible Normals" (JCGT 2018) for [`sample_visible_normal`].
//!
//! Angles are given as `(cos², sin²)` pairs computed by the caller from dot and cross products:
//! near the normal, `1 − cos²` in `f32` loses every digit, and with α = 10⁻⁴ the peak of D is
//! only 10⁻⁸ wide in sin²θ.

use glam::{Vec2, Vec3};
use std::f32::consts::PI;

use super::sampling::unit_circle;

/// Smallest accepted roughness; α = roughness² = 10⁻⁴ keeps D's peak (1/πα² ≈ 3·10⁷) and the
/// power-heuristic weights (pdf² ≈ 10¹⁴) well inside `f32`.
pub const MIN_ROUGHNESS: f32 = 0.01;

/// The α below which a GGX lobe is handled as a perfect mirror (a delta lobe: sampled, never
/// evaluated, so next-event estimation and MIS leave it to BSDF sampling), as pbrt-v4's
/// `TrowbridgeReitzDistribution::EffectivelySmooth` does at the same value. Such a lobe's
/// reflected directions spread about 1.3·α radians at half maximum, under 0.075°: about one
/// pixel of a 512-pixel-wide 40° view, so the mirror changes no visible detail. As an evaluable
/// lobe it is only found by light samples that land in that cone (a chance of order α² per
/// sample), so next-event estimation alone renders it almost black: a white roughness-0
/// conductor in a white furnace averages 0.02 instead of 1 as an evaluable lobe of α = 10⁻⁴.
pub const SPECULAR_ALPHA: f32 = 1e-3;

/// Whether a lobe of GGX `alpha` is handled as a perfect mirror ([`SPECULAR_ALPHA`]).
#[inline]
pub fn is_specular_alpha(alpha: f32) -> bool {
    alpha < SPECULAR_ALPHA
}

/// The α below which a GGX conductor (a `Glossy` material of roughness under about 0.55) joins
/// the chains of mirrors and glass that `Method::Photons` leaves to its light paths: its
/// highlight is narrow enough that the light it reflects onto a diffuse surface is a caustic,
/// which light paths find at once and camera paths only by chance. Measured on `sunlit.ron`
/// with its gold ball at roughness 0.3 to 0.54, and on `envmap.ron` (0.4): BENCHMARKS.md,
/// "Glossy caustics by photons".
pub const NARROW_ALPHA: f32 = 0.3;

/// Whether a lobe of GGX `alpha` is narrow but not a perfect mirror ([`NARROW_ALPHA`]).
#[inline]
pub fn is_narrow_alpha(alpha: f32) -> bool {
    !is_specular_alpha(alpha) && alpha < NARROW_ALPHA
}

/// The GGX α of a user-facing roughness in [0, 1] (α = roughness², the "perceptual" mapping of
/// Burley 2012 and glTF), clamped to [`MIN_ROUGHNESS`]² … 1.
#[inline]
pub fn alpha_from_roughness(roughness: f32) -> f32 {
    let r = roughness.clamp(MIN_ROUGHNESS, 1.0);
    r * r
}

/// `(cos², sin²)` of the angle between unit `w` and unit normal `n`.
#[inline]
pub fn cos2_sin2(w: Vec3, n: Vec3) -> (f32, f32) {
    let c = w.dot(n);
    (c * c, w.cross(n).length_squared())
}

/// The normal distribution D(h) = α² / (π (cos²θ·α² + sin²θ)²), per unit solid angle of h;
/// `∫ D(h) cos θ_h dω_h = 1`.
#[inline]
pub fn distribution(cos2: f32, sin2: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let t = cos2 * a2 + sin2;
    if t <= 0.0 {
        return 0.0;
    }
    a2 / (PI * t * t)
}

/// Smith's Λ(w) = (√(1 + α² tan²θ) − 1) / 2.
#[inline]
pub fn lambda(cos2: f32, sin2: f32, alpha: f32) -> f32 {
    if cos2 <= 0.0 {
        return f32::INFINITY;
    }
    let a2_tan2 = alpha * alpha * sin2 / cos2;
    // (√(1 + x) − 1)/2 = x / (2(√(1 + x) + 1)), exact also for tiny x.
    a2_tan2 / (2.0 * ((1.0 + a2_tan2).sqrt() + 1.0))
}

/// Masking G₁(w) = 1 / (1 + Λ(w)).
#[inline]
pub fn masking(cos2: f32, sin2: f32, alpha: f32) -> f32 {
    1.0 / (1.0 + lambda(cos2, sin2, alpha))
}

/// A microfacet normal (local frame, normal +z) sampled with density
/// `G₁(wo) · max(0, wo·h) · D(h) / cos θ_o` (the normals visible from unit `wo`, `wo.z > 0`),
/// by Heitz's 2018 method: stretch the view to the α = 1 configuration, sample the projected
/// hemisphere there, unstretch. Always inlined, as [`Terms::new`]: merely `#[inline]`, both
/// stayed out of line (2.2 % and 2.4 % of Veach's scene), compiled for the baseline instead of
/// into the dispatched render loop.
#[inline(always)]
pub fn sample_visible_normal(wo: Vec3, alpha: f32, u: Vec2) -> Vec3 {
    let vh = Vec3::new(alpha * wo.x, alpha * wo.y, wo.z).normalize();
    let len2 = vh.x * vh.x + vh.y * vh.y;
    let t1 = if len2 > 0.0 {
        Vec3::new(-vh.y, vh.x, 0.0) / len2.sqrt()
    } else {
        Vec3::X
    };
    let t2 = vh.cross(t1);
    let r = u.x.sqrt();
    let phi = unit_circle(u.y);
    let p1 = r * phi.x;
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.y;
    let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
    Vec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(0.0)).normalize()
}

/// The GGX terms of a reflection from unit `wo` to unit `wi` about unit normal `n`: what a
/// microfacet lobe needs to evaluate its value and density.
#[derive(Clone, Copy, Debug)]
pub struct Terms {
    /// D(h) of the half vector.
    pub d: f32,
    /// Smith Λ of `wo`.
    pub lo: f32,
    /// Smith Λ of `wi`.
    pub li: f32,
    /// `wo · h`, for Fresnel (signed: the lobes differ in how they fold it).
    pub cos_oh: f32,
}

impl Terms {
    /// The terms of GGX `alpha` for the reflection `wo` → `wi` about `n`.
    #[inline(always)]
    pub fn new(wo: Vec3, wi: Vec3, n: Vec3, alpha: f32) -> Self {
        let h = (wo + wi).normalize();
        let (c2h, s2h) = cos2_sin2(h, n);
        let (c2o, s2o) = cos2_sin2(wo, n);
        let (c2i, s2i) = cos2_sin2(wi, n);
        Self {
            d: distribution(c2h, s2h, alpha),
            lo: lambda(c2o, s2o, alpha),
            li: lambda(c2i, s2i, alpha),
            cos_oh: wo.dot(h),
        }
    }
}

/// Schlick's Fresnel with a per-channel reflectance `f0` at normal incidence.
#[inline]
pub fn schlick_rgb(f0: Vec3, cos: f32) -> Vec3 {
    let m = (1.0 - cos.clamp(0.0, 1.0)).powi(5);
    f0 + (Vec3::ONE - f0) * m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distribution_projected_area_integrates_to_one() {
        // ∫ D(h) cos θ dω over the hemisphere, by the midpoint rule in (cos θ, φ); D is
        // isotropic, so φ contributes 2π. A fine grid near cos θ = 1 resolves the peak.
        for alpha in [0.05f32, 0.2, 0.5, 1.0] {
            let n = 200_000;
            let mut sum = 0.0f64;
            for i in 0..n {
                let c = (i as f64 + 0.5) / n as f64;
                let (c2, s2) = (c * c, 1.0 - c * c);
                sum += f64::from(distribution(c2 as f32, s2 as f32, alpha)) * c;
            }
            let integral = sum / n as f64 * 2.0 * std::f64::consts::PI;
            assert!((integral - 1.0).abs() < 2e-3, "α = {alpha}: {integral}");
        }
    }

    #[test]
    fn lambda_is_zero_at_normal_incidence_and_matches_the_closed_form() {
        assert_eq!(lambda(1.0, 0.0, 0.3), 0.0);
        let (c, a) = (0.3f32, 0.7f32);
        let tan2 = (1.0 - c * c) / (c * c);
        let closed = ((1.0 + a * a * tan2).sqrt() - 1.0) / 2.0;
        assert!((lambda(c * c, 1.0 - c * c, a) - closed).abs() < 1e-6);
    }
}
