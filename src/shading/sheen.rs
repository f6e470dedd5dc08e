//! The sheen lobe of `KHR_materials_sheen`: the back-scattering of velvet and cloth, the "Charlie"
//! distribution of Estevez & Kulla, "Production Friendly Microfacet Sheen BRDF" (SIGGRAPH
//! 2017), `D(h) = (2 + 1/α) sin^(1/α) θh / 2π`, with their fitted Λ for visibility,
//! `f = colour · D / (4 cos θo cos θi (1 + Λ(μo) + Λ(μi)))`, no Fresnel (the extension's
//! informative text, whose α is the sheen roughness squared, as in Khronos' sample viewer).
//! [`super::pbr::Pbr`] layers it over the metallic–roughness BRDF by albedo scaling. No ECS here.
//!
//! Why this visibility and not Ashikhmin's simpler `1 / (4 (cos θo + cos θi − cos θo cos θi))`:
//! it is the spec's and Khronos' sample viewer's, so sheen looks as in the files' reference
//! renders, and Λ derives from the distribution (a shadowing function fitted to it), where
//! Ashikhmin's term ignores it. The fit does not keep the albedo below 1 everywhere, though:
//! towards the horizon it under-estimates Λ, and the white lobe's albedo (by quadrature of the
//! formula above, `examples/make_sheen_table.rs`) passes 1 within 1–3° of the horizon at
//! roughness below 0.25 (5.3 at grazing for roughness 0.05) and within 0.1° of it above.
//! There the lobe is divided by its albedo, so it reflects at most 1 ([`Sheen::eval`]);
//! elsewhere it is the formula as written. The cost is two `exp` and three `powf` per
//! evaluation.
//!
//! The lobe's directional albedo E(μ, roughness) is read from [`super::sheen_table`], computed by
//! `examples/make_sheen_table.rs` by brute-force quadrature in `f64`. Roughness below
//! [`ROUGHNESS_MIN`] is clamped to it (α = 0.0025): as the roughness goes to 0 the lobe
//! narrows onto the horizon and its albedo vanishes except at grazing views; the clamp keeps
//! `D` (up to 64 at the minimum) and its exponent (400) within `f32`.

use std::f32::consts::FRAC_1_PI;

use glam::Vec3;

pub use super::sheen_table::ROUGHNESS_MIN;
use super::sheen_table::{COS_NODES, ROUGHNESS_NODES, SHEEN};

/// Density of a uniformly sampled hemisphere direction, 1/2π: the sheen lobe is sampled so.
pub const UNIFORM_PDF: f32 = 0.5 * FRAC_1_PI;

/// The sheen layer's colour and roughness at one surface point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sheen {
    /// `sheenColorFactor`, each channel in [0, 1]; black turns the layer off.
    pub color: Vec3,
    /// Perceptual roughness from [`ROUGHNESS_MIN`] to 1; α = roughness².
    pub roughness: f32,
}

impl Default for Sheen {
    fn default() -> Self {
        Self::NONE
    }
}

impl Sheen {
    /// No sheen.
    pub const NONE: Self = Self {
        color: Vec3::ZERO,
        roughness: ROUGHNESS_MIN,
    };

    /// The layer of colour `color` (each channel clamped to [0, 1]) and perceptual `roughness`
    /// (clamped to [`ROUGHNESS_MIN`] … 1).
    pub fn new(color: Vec3, roughness: f32) -> Self {
        Self {
            color: color.clamp(Vec3::ZERO, Vec3::ONE),
            roughness: roughness.clamp(ROUGHNESS_MIN, 1.0),
        }
    }

    /// Whether the layer is off (a black colour): the base is left as it is.
    #[inline]
    pub fn is_off(&self) -> bool {
        self.color.max_element() <= 0.0
    }

    /// The lobe's f·cos θi for a view at cosine `cos_o` and a light at `cos_i` (both > 0) with
    /// `sin2_h`, the squared sine of the half vector to the normal: `D / (4 cos θo (1 + Λo + Λi))`
    /// times the colour, divided by `e_o`, the view's [`Sheen::albedo`], where that passes 1.
    #[inline]
    pub fn eval(&self, cos_o: f32, cos_i: f32, sin2_h: f32, e_o: f32) -> Vec3 {
        let alpha = self.roughness * self.roughness;
        let d = (2.0 + 1.0 / alpha) * sin2_h.clamp(0.0, 1.0).powf(0.5 / alpha) * (0.5 * FRAC_1_PI);
        let visibility = 4.0 * cos_o * (1.0 + lambda(cos_o, alpha) + lambda(cos_i, alpha));
        self.color * (d / (visibility * e_o.max(1.0)))
    }

    /// E(μ): the directional albedo at view cosine `mu` of the white lobe as the formula has it
    /// (it passes 1 near the horizon; [`Sheen::eval`] caps what it reflects at 1), bilinear in
    /// roughness and √μ between the table's nodes.
    #[inline]
    pub fn albedo(&self, mu: f32) -> f32 {
        let cell = |x: f32, n: usize| {
            let x = x.clamp(0.0, (n - 1) as f32);
            let i = (x as usize).min(n - 2);
            (i, x - i as f32)
        };
        let (i, u) = cell(
            mu.clamp(0.0, 1.0).sqrt() * (COS_NODES - 1) as f32,
            COS_NODES,
        );
        let (j, v) = cell(
            (self.roughness - ROUGHNESS_MIN) / (1.0 - ROUGHNESS_MIN) * (ROUGHNESS_NODES - 1) as f32,
            ROUGHNESS_NODES,
        );
        let at = |row: &[f32; COS_NODES]| row[i] + (row[i + 1] - row[i]) * u;
        let low = at(&SHEEN[j]);
        low + (at(&SHEEN[j + 1]) - low) * v
    }

    /// What the white lobe reflects from a view of [`Sheen::albedo`] `e`: `min(e, 1)`.
    #[inline]
    pub fn reflected(e: f32) -> f32 {
        e.clamp(0.0, 1.0)
    }

    /// What the layer leaves to the base for a view of [`Sheen::albedo`] `e`:
    /// `1 − max(colour) · min(e, 1)`, the spec's albedo scaling.
    #[inline]
    pub fn base_weight(&self, e: f32) -> f32 {
        (1.0 - self.color.max_element() * Self::reflected(e)).clamp(0.0, 1.0)
    }
}

/// Estevez & Kulla's fit L(x) of ln Λ, its coefficients interpolated between their fits for
/// α = 0 and α = 1 by (1 − α)².
#[inline]
fn fit(x: f32, alpha: f32) -> f32 {
    let w = (1.0 - alpha) * (1.0 - alpha);
    let mix = |at_one: f32, at_zero: f32| at_one + (at_zero - at_one) * w;
    let a = mix(21.5473, 25.3245);
    let b = mix(3.82987, 3.32435);
    let c = mix(0.19823, 0.16801);
    let d = mix(-1.97760, -1.27393);
    let e = mix(-4.32054, -4.85967);
    a / (1.0 + b * x.powf(c)) + d * x + e
}

/// Λ of a direction at cosine `mu` (> 0): the fit below 0.5 and its mirror image about 0.5
/// above, so that Λ is smooth there.
#[inline]
fn lambda(mu: f32, alpha: f32) -> f32 {
    if mu < 0.5 {
        fit(mu, alpha).exp()
    } else {
        (2.0 * fit(0.5, alpha) - fit(1.0 - mu, alpha)).exp()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_off_layer_leaves_the_base_whole_and_a_white_one_leaves_what_it_does_not_reflect() {
        assert!(Sheen::NONE.is_off());
        assert_eq!(Sheen::NONE.base_weight(0.5), 1.0);
        for r in [0.0f32, 0.3, 1.0] {
            let s = Sheen::new(Vec3::ONE, r);
            for mu in [0.0f32, 0.01, 0.5, 1.0] {
                let e = s.albedo(mu);
                assert!(e >= 0.0 && e.is_finite(), "roughness {r} μ {mu}: {e}");
                let sum = s.base_weight(e) + Sheen::reflected(e);
                assert!((sum - 1.0).abs() < 1e-6, "roughness {r} μ {mu}: {sum}");
            }
        }
    }
}
