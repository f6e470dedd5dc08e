//! The strength and colour of `Pbr`'s dielectric specular lobe (`KHR_materials_specular`) and
//! that lobe's directional albedo. The lobe's Fresnel is Schlick's with reflectance
//! `weight · f0` at normal incidence and `weight` at grazing angles (the extension's
//! `F0 = min(0.04 · specularColor, 1) · specular`, `F90 = specular`); the default, weight 1 and
//! F0 = 0.04, is glTF's plain dielectric. No ECS here.
//!
//! No table of its own: Schlick's Fresnel is linear in (F0, F90), so the lobe's albedo is
//! `weight (f0 A(μ) + B(μ))`, where A and B are the albedos of the GGX lobe weighted by
//! `1 − (1 − μh)⁵` and by `(1 − μh)⁵`. The two tables give A + B (the conductor's, Fresnel 1) and
//! `0.04 A + B` (the dielectric's), hence A and B, at every node and in their averages alike, so
//! the identity that makes the base's compensation exact ([`super::energy`]) holds for any
//! strength and colour.

use glam::Vec3;

use super::energy::AlbedoRow;

/// Reflectance at normal incidence of `Pbr`'s dielectric part (ior 1.5), before
/// `KHR_materials_specular` scales and tints it.
pub const DIELECTRIC_F0: f32 = 0.04;

/// The dielectric specular lobe's Fresnel: `weight · (f0 + (1 − f0)(1 − μ)⁵)` per channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Specular {
    /// `specularFactor` in [0, 1]: scales the whole lobe (F0 and F90).
    pub weight: f32,
    /// Reflectance at normal incidence before `weight`, per channel in [0, 1]:
    /// `min(0.04 · specularColorFactor, 1)`.
    pub f0: Vec3,
}

impl Default for Specular {
    fn default() -> Self {
        Self::PLAIN
    }
}

impl Specular {
    /// glTF's plain dielectric: weight 1, F0 = 0.04 (ior 1.5), white.
    pub const PLAIN: Self = Self {
        weight: 1.0,
        f0: Vec3::splat(DIELECTRIC_F0),
    };

    /// The lobe of `KHR_materials_specular`'s `specularFactor` (`weight`, clamped to [0, 1]) and
    /// `specularColorFactor` (`color`, each channel at least 0).
    pub fn new(weight: f32, color: Vec3) -> Self {
        Self {
            weight: weight.clamp(0.0, 1.0),
            f0: (DIELECTRIC_F0 * color.max(Vec3::ZERO)).min(Vec3::ONE),
        }
    }

    /// Whether this is [`Specular::PLAIN`], whose albedo the dielectric table holds as it is.
    #[inline]
    pub fn is_plain(&self) -> bool {
        *self == Self::PLAIN
    }

    /// Reflectance at normal incidence, `weight · f0`.
    #[inline]
    pub fn normal(&self) -> Vec3 {
        self.weight * self.f0
    }

    /// Reflectance at grazing incidence, `weight`.
    #[inline]
    pub fn grazing(&self) -> f32 {
        self.weight
    }

    /// The albedo `weight (f0 A + B)` from the conductor's `e_white` = A + B and the
    /// dielectric's `e_plain` = 0.04 A + B (of the same row and view, or both averages).
    #[inline]
    fn combine(&self, e_white: f32, e_plain: f32) -> Vec3 {
        let a = (e_white - e_plain) / (1.0 - DIELECTRIC_F0);
        let b = e_white - a;
        self.weight * (self.f0 * a + Vec3::splat(b))
    }

    /// The lobe's directional albedo E_s(μ) at view cosine `mu`, per channel.
    #[inline]
    pub fn albedo(&self, row: &AlbedoRow, mu: f32) -> Vec3 {
        if self.is_plain() {
            return Vec3::splat(row.dielectric(mu));
        }
        self.combine(row.conductor(mu), row.dielectric(mu))
    }

    /// 1 − E_s,avg, the share of uniform light the lobe does not reflect, per channel.
    #[inline]
    pub fn lost(&self, row: &AlbedoRow) -> Vec3 {
        if self.is_plain() {
            return Vec3::splat(row.dielectric_lost());
        }
        Vec3::ONE - self.combine(1.0 - row.conductor_lost(), 1.0 - row.dielectric_lost())
    }
}

/// Schlick's Fresnel with reflectance `f0` at normal incidence and `f90` at grazing incidence,
/// at cosine `cos`; `f0 + (1 − f0)(1 − cos)⁵` for `f90` = 1, as [`super::microfacet::schlick_rgb`].
#[inline]
pub fn schlick_f90(f0: Vec3, f90: f32, cos: f32) -> Vec3 {
    let m = (1.0 - cos.clamp(0.0, 1.0)).powi(5);
    f0 + (Vec3::splat(f90) - f0) * m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_plain_lobe_reads_the_dielectric_table_and_a_white_f0_the_conductors() {
        for roughness in [0.05f32, 0.4, 1.0] {
            let row = AlbedoRow::new(roughness * roughness);
            for mu in [0.05f32, 0.5, 1.0] {
                let plain = Specular::new(1.0, Vec3::ONE);
                assert!(plain.is_plain());
                let d = row.dielectric(mu);
                // Through A and B, F0 = 0.04 gives the dielectric table back.
                assert!((plain.combine(row.conductor(mu), d) - Vec3::splat(d)).length() < 1e-6);
                // F0 = F90 = 1 is the conductor's white lobe.
                let white = Specular::new(1.0, Vec3::splat(25.0));
                assert!((white.albedo(&row, mu) - Vec3::splat(row.conductor(mu))).length() < 1e-5);
                // Half the strength, half the albedo.
                let half = Specular::new(0.5, Vec3::ONE);
                assert!((half.albedo(&row, mu) - Vec3::splat(0.5 * d)).length() < 1e-6);
            }
        }
    }
}
