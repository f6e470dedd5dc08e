//! Energy compensation of the GGX lobes: the directional albedo E(μ) of single-scattering GGX
//! looked up in precomputed tables ([`super::albedo_table`]), and the reciprocal lobe
//! `(1 − E(μo)) (1 − E(μi)) / (π (1 − E_avg))` of Kulla & Conty, "Revisiting Physically Based
//! Shading at Imageworks" (SIGGRAPH 2017 course), which both energy-conserving parts use: the
//! multiple scattering a GGX conductor's single-scattering lobe drops, and the diffuse base under
//! the dielectric specular lobe of `Pbr`. That lobe integrates, over `wi` with the cosine, to
//! exactly `1 − E(μo)`: with E_avg = 2 ∫ E(μ) μ dμ,
//! `∫ (1 − E(μi)) μi dωi / (π (1 − E_avg)) = 2 ∫ (1 − E) μ dμ / (1 − E_avg) = 1`. No ECS here.
//!
//! The tables are bilinear in roughness and √μ and the averages are the exact integrals of that
//! interpolant (see `examples/make_albedo_tables.rs`), so the identity above holds for the
//! looked-up values too, at every roughness, and a lobe plus its compensation reflects
//! `E_true(μo) + 1 − E_table(μo)`: 1 up to the table's interpolation error (under 0.3 % up to
//! 88° from the normal; a few % within 1° of grazing at roughness near 0.05, where E drops
//! from 1 over a fraction of a degree). Two 64 × 64 tables of `f32`: 32 KiB, nothing computed at
//! start-up.

use std::f32::consts::FRAC_1_PI;

use glam::Vec3;

use super::albedo_table::{
    CONDUCTOR, CONDUCTOR_LOST, COS_NODES, DIELECTRIC, DIELECTRIC_LOST, ROUGHNESS_NODES,
};
use super::microfacet::is_specular_alpha;

/// Where a GGX α falls between the tables' roughness rows: the lower row and the weight of the
/// upper one. A perfect mirror ([`is_specular_alpha`]) reads row 0, the mirror's own albedo.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AlbedoRow {
    row: usize,
    weight: f32,
}

impl AlbedoRow {
    /// The row position of GGX `alpha` (roughness = √α).
    #[inline]
    pub fn new(alpha: f32) -> Self {
        if is_specular_alpha(alpha) {
            return Self {
                row: 0,
                weight: 0.0,
            };
        }
        let r = alpha.max(0.0).sqrt().min(1.0) * (ROUGHNESS_NODES - 1) as f32;
        let row = (r as usize).min(ROUGHNESS_NODES - 2);
        Self {
            row,
            weight: r - row as f32,
        }
    }

    /// The bilinear value of `table` at view cosine `mu`.
    #[inline]
    fn lookup(&self, table: &[[f32; COS_NODES]; ROUGHNESS_NODES], mu: f32) -> f32 {
        let x = mu.clamp(0.0, 1.0).sqrt() * (COS_NODES - 1) as f32;
        let i = (x as usize).min(COS_NODES - 2);
        let u = x - i as f32;
        let at = |row: &[f32; COS_NODES]| row[i] + (row[i + 1] - row[i]) * u;
        let low = at(&table[self.row]);
        if self.weight == 0.0 {
            return low;
        }
        low + (at(&table[self.row + 1]) - low) * self.weight
    }

    /// The linear value of a row's losses, 1 − E_avg.
    #[inline]
    fn lost(&self, losses: &[f32; ROUGHNESS_NODES]) -> f32 {
        let low = losses[self.row];
        if self.weight == 0.0 {
            return low;
        }
        low + (losses[self.row + 1] - low) * self.weight
    }

    /// E(μ) of single-scattering GGX with Fresnel 1.
    #[inline]
    pub fn conductor(&self, mu: f32) -> f32 {
        self.lookup(&CONDUCTOR, mu)
    }

    /// 1 − E_avg of single-scattering GGX with Fresnel 1: the share of uniform light it loses.
    #[inline]
    pub fn conductor_lost(&self) -> f32 {
        self.lost(&CONDUCTOR_LOST)
    }

    /// E(μ) of single-scattering GGX with the exact Fresnel of ior 1.5.
    #[inline]
    pub fn dielectric(&self, mu: f32) -> f32 {
        self.lookup(&DIELECTRIC, mu)
    }

    /// 1 − E_avg of single-scattering GGX with the exact Fresnel of ior 1.5.
    #[inline]
    pub fn dielectric_lost(&self) -> f32 {
        self.lost(&DIELECTRIC_LOST)
    }
}

/// The compensation lobe's BRDF `(1 − e_o)(1 − e_i) / (π (1 − E_avg))` for the albedos `e_o`,
/// `e_i` of the two directions and `lost` = 1 − E_avg; 0 where the lobe it compensates loses
/// nothing (the mirror).
#[inline]
pub fn compensation(e_o: f32, e_i: f32, lost: f32) -> f32 {
    if lost <= 0.0 {
        return 0.0;
    }
    (1.0 - e_o).max(0.0) * (1.0 - e_i).max(0.0) * FRAC_1_PI / lost
}

/// The cosine-weighted average 2 ∫ F(μ) μ dμ of Schlick's Fresnel with reflectance `f0`:
/// f0 + (1 − f0)/21, since 2 ∫ (1 − μ)⁵ μ dμ = 2 B(2, 6) = 1/21.
#[inline]
pub fn schlick_average(f0: Vec3) -> Vec3 {
    f0 + (Vec3::ONE - f0) / 21.0
}

/// Kulla & Conty's colour of the multiply scattered light of a conductor of Schlick reflectance
/// `f0` whose white lobe loses `lost` = 1 − E_avg of uniform light:
/// F_avg² E_avg / (1 − F_avg (1 − E_avg)), the sum over the k ≥ 2 bounces of light that leaves
/// after each with probability E_avg and keeps F_avg at each, per unit of the white lobe's loss.
/// 1 for F0 = 1.
#[inline]
pub fn multiple_scattering_fresnel(f0: Vec3, lost: f32) -> Vec3 {
    let f_avg = schlick_average(f0);
    f_avg * f_avg * (1.0 - lost) / (Vec3::ONE - f_avg * lost)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 2 ∫ E(μ) μ dμ by the midpoint rule, fine enough for the table's kinks.
    fn average_by_quadrature(row: &AlbedoRow, e: impl Fn(&AlbedoRow, f32) -> f32) -> f64 {
        let n = 200_000;
        let sum: f64 = (0..n)
            .map(|k| {
                let mu = (k as f64 + 0.5) / n as f64;
                f64::from(e(row, mu as f32)) * mu
            })
            .sum();
        2.0 * sum / n as f64
    }

    #[test]
    fn the_averages_are_the_cosine_weighted_integrals_of_the_interpolated_tables() {
        for roughness in [0.04f32, 0.1, 0.33, 0.5, 0.77, 1.0] {
            let row = AlbedoRow::new(roughness * roughness);
            let c = average_by_quadrature(&row, AlbedoRow::conductor);
            let d = average_by_quadrature(&row, AlbedoRow::dielectric);
            assert!(
                (1.0 - c - f64::from(row.conductor_lost())).abs() < 2e-5,
                "{c}"
            );
            assert!(
                (1.0 - d - f64::from(row.dielectric_lost())).abs() < 2e-5,
                "{d}"
            );
        }
    }

    #[test]
    fn the_mirror_row_is_one_and_the_exact_fresnel_of_ior_one_and_a_half() {
        // The Fresnel equations' reflectance of unpolarised light from outside ior 1.5.
        let fresnel = |c: f64| {
            let eta = 1.5f64;
            let cos_t = (1.0 - (1.0 - c * c) / (eta * eta)).sqrt();
            let rs = (c - eta * cos_t) / (c + eta * cos_t);
            let rp = (eta * c - cos_t) / (eta * c + cos_t);
            0.5 * (rs * rs + rp * rp)
        };
        let row = AlbedoRow::new(1e-4);
        for mu in [0.0f32, 0.1, 0.5, 0.7, 1.0] {
            assert_eq!(row.conductor(mu), 1.0);
            let f = fresnel(f64::from(mu));
            assert!((f64::from(row.dielectric(mu)) - f).abs() < 2e-3, "{mu}");
        }
        // 2 ∫ F(μ) μ dμ by the midpoint rule (0.0918).
        let n = 100_000;
        let average = 2.0
            * (0..n)
                .map(|k| {
                    let mu = (k as f64 + 0.5) / n as f64;
                    fresnel(mu) * mu
                })
                .sum::<f64>()
            / n as f64;
        assert!((1.0 - f64::from(row.dielectric_lost()) - average).abs() < 1e-4);
        assert_eq!(compensation(0.5, 0.5, row.conductor_lost()), 0.0);
    }

    #[test]
    fn the_schlick_average_matches_quadrature_and_white_keeps_all_multiple_scattering() {
        let f0 = Vec3::new(0.9, 0.5, 0.04);
        let n = 100_000;
        let mut sum = Vec3::ZERO;
        for k in 0..n {
            let mu = (k as f32 + 0.5) / n as f32;
            sum += (f0 + (Vec3::ONE - f0) * (1.0 - mu).powi(5)) * mu;
        }
        let quadrature = 2.0 * sum / n as f32;
        assert!((quadrature - schlick_average(f0)).abs().max_element() < 1e-4);
        for lost in [0.6f32, 0.2, 0.01] {
            let white = multiple_scattering_fresnel(Vec3::ONE, lost);
            assert!((white - Vec3::ONE).abs().max_element() < 1e-6);
            let coloured = multiple_scattering_fresnel(f0, lost);
            assert!(coloured.max_element() < 1.0 && coloured.min_element() > 0.0);
        }
    }
}
