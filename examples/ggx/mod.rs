//! GGX in `f64` for the table generators (`make_albedo_tables`, `make_glass_albedo_table`),
//! written independently of `src/shading/microfacet.rs`: Smith's Λ and Heitz's visible-normal
//! sampling (JCGT 2018).

use std::f64::consts::PI;

/// Smith's Λ of a direction of cosine `mu` to the normal, for GGX `alpha`.
pub fn lambda(mu: f64, alpha: f64) -> f64 {
    let tan2 = (1.0 - mu * mu).max(0.0) / (mu * mu);
    ((1.0 + alpha * alpha * tan2).sqrt() - 1.0) / 2.0
}

/// A visible normal for the view `wo` (unit, local frame, z up) from the uniform pair `(u1, u2)`.
pub fn visible_normal(wo: [f64; 3], alpha: f64, u1: f64, u2: f64) -> [f64; 3] {
    let v = [alpha * wo[0], alpha * wo[1], wo[2]];
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let v = [v[0] / l, v[1] / l, v[2] / l];
    let len2 = v[0] * v[0] + v[1] * v[1];
    let t1 = if len2 > 0.0 {
        [-v[1] / len2.sqrt(), v[0] / len2.sqrt(), 0.0]
    } else {
        [1.0, 0.0, 0.0]
    };
    let t2 = [
        v[1] * t1[2] - v[2] * t1[1],
        v[2] * t1[0] - v[0] * t1[2],
        v[0] * t1[1] - v[1] * t1[0],
    ];
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + v[2]);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
    let p3 = (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    let n: Vec<f64> = (0..3)
        .map(|k| p1 * t1[k] + p2 * t2[k] + p3 * v[k])
        .collect();
    let h = [alpha * n[0], alpha * n[1], n[2].max(0.0)];
    let l = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
    [h[0] / l, h[1] / l, h[2] / l]
}
