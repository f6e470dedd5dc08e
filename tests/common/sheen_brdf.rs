//! The sheen lobe of `KHR_materials_sheen` written out in `f64` from the extension's text
//! (Estevez & Kulla's Charlie distribution and fitted Λ), and a hemisphere quadrature fine enough
//! for its low roughnesses: the independent truth of the sheen tests.

use std::f64::consts::PI;

/// The Charlie distribution `(2 + 1/α) sin^(1/α) θh / 2π` (Estevez & Kulla 2017).
pub fn charlie(cos_h: f64, alpha: f64) -> f64 {
    let sin2 = (1.0 - cos_h * cos_h).max(0.0);
    (2.0 + 1.0 / alpha) * sin2.powf(0.5 / alpha) / (2.0 * PI)
}

/// ln Λ as Estevez & Kulla fit it, as the extension's informative text writes it.
pub fn l(x: f64, alpha: f64) -> f64 {
    let t = (1.0 - alpha) * (1.0 - alpha);
    let mix = |x: f64, y: f64| x * (1.0 - t) + y * t;
    mix(21.5473, 25.3245) / (1.0 + mix(3.82987, 3.32435) * x.powf(mix(0.19823, 0.16801)))
        + mix(-1.97760, -1.27393) * x
        + mix(-4.32054, -4.85967)
}

pub fn lambda_sheen(c: f64, alpha: f64) -> f64 {
    if c.abs() < 0.5 {
        l(c, alpha).exp()
    } else {
        (2.0 * l(0.5, alpha) - l(1.0 - c, alpha)).exp()
    }
}

/// f·cos θi of the white sheen lobe of perceptual `roughness` (α = roughness², at least 0.05²)
/// for unit `wo`, `wi` about +z: `D V cos θi` with
/// `V = 1 / ((1 + Λ(μo) + Λ(μi)) 4 μo μi)`.
pub fn sheen_cos(wo: [f64; 3], wi: [f64; 3], roughness: f64) -> f64 {
    if wo[2] <= 0.0 || wi[2] <= 0.0 {
        return 0.0;
    }
    let alpha = roughness.max(0.05).powi(2);
    let h = [wo[0] + wi[0], wo[1] + wi[1], wo[2] + wi[2]];
    let len = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
    let v = 1.0
        / ((1.0 + lambda_sheen(wo[2], alpha) + lambda_sheen(wi[2], alpha)) * 4.0 * wo[2] * wi[2]);
    charlie(h[2] / len, alpha) * v * wi[2]
}

/// ∫ value(wi) dωi over the upper hemisphere for a view at cosine `mu` (in the xz plane): the
/// midpoint rule in (t, φ) with cos θi = t², whose steps shrink towards the horizon where the
/// sheen of a low roughness lives (dω = 2t dt dφ).
pub fn hemisphere(mu: f64, value: impl Fn([f64; 3], [f64; 3]) -> [f64; 3]) -> [f64; 3] {
    let (nt, nphi) = (700, 360);
    let wo = [(1.0 - mu * mu).sqrt(), 0.0, mu];
    let mut sum = [0.0f64; 3];
    for i in 0..nt {
        let t = (i as f64 + 0.5) / nt as f64;
        let c = t * t;
        let s = (1.0 - c * c).sqrt();
        for j in 0..nphi {
            let phi = (j as f64 + 0.5) / nphi as f64 * 2.0 * PI;
            let v = value(wo, [s * phi.cos(), s * phi.sin(), c]);
            for k in 0..3 {
                sum[k] += v[k] * 2.0 * t;
            }
        }
    }
    sum.map(|s| s * 2.0 * PI / (nt * nphi) as f64)
}
