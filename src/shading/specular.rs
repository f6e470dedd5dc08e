//! The strength and colour of `Pbr`'s dielectric specular lobe (`KHR_materials_specular`) and
//! that lobe's directional albedo. The plain lobe's Fresnel is the exact one of ior 1.5. The
//! extension asks for reflectance `F0 = min(0.04 · specularColor, 1) · specular` at normal
//! incidence and `F90 = specular` at grazing angles; this lobe gets them by moving the exact
//! curve towards 1 by `k = (f0 − 0.04) / 0.96` per channel and scaling by the strength:
//! `F(μ) = weight (F_ior(μ) + k (1 − F_ior(μ)))`, which is F0 at μ = 1 (F_ior(1) = 0.04),
//! `weight` at grazing angles and never above `weight`. (The spec's informative code writes
//! the same end points with Schlick's curve.) No ECS here.
//!
//! No table of its own: the Fresnel is linear in `k`, between the exact dielectric's and the
//! white conductor's (Fresnel 1), so the lobe's albedo is `weight ((1 − k) E_d + k E_c)` from
//! the two tables [`super::energy`] reads, at every node and in their averages alike, and the
//! identity that makes the base's compensation exact ([`super::energy`]) holds for any
//! strength and colour.

use glam::Vec3;

use super::energy::AlbedoRow;
use super::fresnel::fresnel_dielectric;

/// Index of refraction of `Pbr`'s dielectric part (and of the clear coat).
pub const DIELECTRIC_IOR: f32 = 1.5;

/// Reflectance at normal incidence of `Pbr`'s dielectric part, `((ior − 1) / (ior + 1))²`,
/// before `KHR_materials_specular` scales and tints it.
pub const DIELECTRIC_F0: f32 = 0.04;

/// The dielectric specular lobe's Fresnel: `weight (F_ior + k (1 − F_ior))` per channel, with
/// `k = (f0 − 0.04) / 0.96`.
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

    /// How far towards Fresnel 1 the exact curve moves, per channel: `(f0 − 0.04) / 0.96`.
    #[inline]
    fn tint(&self) -> Vec3 {
        (self.f0 - Vec3::splat(DIELECTRIC_F0)) / (1.0 - DIELECTRIC_F0)
    }

    /// The lobe's Fresnel factor at cosine `cos`, per channel.
    #[inline]
    pub fn fresnel(&self, cos: f32) -> Vec3 {
        let f = fresnel_dielectric(cos, DIELECTRIC_IOR);
        if self.is_plain() {
            return Vec3::splat(f);
        }
        self.weight * (Vec3::splat(f) + self.tint() * (1.0 - f))
    }

    /// The albedo `weight ((1 − k) e_d + k e_c)` from the exact dielectric's `e_d` and the white
    /// conductor's `e_c` (of the same row and view, or both averages).
    #[inline]
    fn combine(&self, e_dielectric: f32, e_white: f32) -> Vec3 {
        self.weight * (Vec3::splat(e_dielectric) + self.tint() * (e_white - e_dielectric))
    }

    /// The lobe's directional albedo E_s(μ) at view cosine `mu`, per channel.
    #[inline]
    pub fn albedo(&self, row: &AlbedoRow, mu: f32) -> Vec3 {
        if self.is_plain() {
            return Vec3::splat(row.dielectric(mu));
        }
        self.combine(row.dielectric(mu), row.conductor(mu))
    }

    /// 1 − E_s,avg, the share of uniform light the lobe does not reflect, per channel.
    #[inline]
    pub fn lost(&self, row: &AlbedoRow) -> Vec3 {
        if self.is_plain() {
            return Vec3::splat(row.dielectric_lost());
        }
        Vec3::ONE - self.combine(1.0 - row.dielectric_lost(), 1.0 - row.conductor_lost())
    }
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
                // F0 = 0.04 through the general form gives the dielectric table back.
                assert!((plain.combine(d, row.conductor(mu)) - Vec3::splat(d)).length() < 1e-6);
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
