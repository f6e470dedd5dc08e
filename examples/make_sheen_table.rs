//! Writes `src/shading/sheen_table.rs`: the directional albedo E(μ, roughness) of the sheen lobe
//! of `KHR_materials_sheen` as rondo evaluates it, white (colour 1): Estevez & Kulla's "Charlie"
//! distribution `D(h) = (2 + 1/α) sin^(1/α) θh / 2π` with their fitted Λ for visibility,
//! `f = D / (4 cos θo cos θi (1 + Λ(μo) + Λ(μi)))`, α = roughness² (roughness clamped below
//! at `ROUGHNESS_MIN`), from "Production Friendly Microfacet Sheen BRDF" (SIGGRAPH 2017) and the
//! extension's informative text.
//!
//! ```text
//! cargo run --release --example make_sheen_table -- src/shading/sheen_table.rs
//! cargo run --release --example make_sheen_table -- --check   # interpolation error
//! ```
//!
//! The lobe is written here again in `f64`, independently of `src/shading/sheen.rs`. Each entry
//! is `∫ f cos θi dωi` over the hemisphere by the midpoint rule on a grid in (t, φ) with
//! cos θi = t² (steps shrinking towards the horizon, where the lobe of a low roughness lives)
//! and φ over [0, π] (the lobe is symmetric about the plane of the view). Nodes are uniform in
//! roughness over [`ROUGHNESS_MIN`, 1] and in √μ. Deterministic: the same source gives the
//! same bytes.

use std::f64::consts::PI;

use rayon::prelude::*;

/// Nodes in roughness (`ROUGHNESS_MIN` … 1).
const ROUGHNESS: usize = 32;
/// Nodes in √μ (0 … 1).
const COS: usize = 32;
/// The smallest sheen roughness the lobe takes (smaller ones are clamped to it): its α is
/// 0.0025, the distribution's exponent 1/α = 400.
const ROUGHNESS_MIN: f64 = 0.05;
/// Steps in t = √cos θi.
const STEPS_T: usize = 2048;
/// Steps in φ over [0, π].
const STEPS_PHI: usize = 512;
/// The cosine used for the node μ = 0, where the view is in the surface's plane.
const GRAZING: f64 = 1e-6;

/// The Charlie distribution at cos θh for `alpha`.
fn charlie(cos_h: f64, alpha: f64) -> f64 {
    let sin2 = (1.0 - cos_h * cos_h).max(0.0);
    (2.0 + 1.0 / alpha) * sin2.powf(0.5 / alpha) / (2.0 * PI)
}

/// Estevez & Kulla's fit L(x) of ln Λ, its coefficients interpolated between their α = 0 and
/// α = 1 fits by (1 − α)².
fn fit(x: f64, alpha: f64) -> f64 {
    let w = (1.0 - alpha) * (1.0 - alpha);
    let mix = |at_one: f64, at_zero: f64| at_one + (at_zero - at_one) * w;
    let a = mix(21.5473, 25.3245);
    let b = mix(3.82987, 3.32435);
    let c = mix(0.19823, 0.16801);
    let d = mix(-1.97760, -1.27393);
    let e = mix(-4.32054, -4.85967);
    a / (1.0 + b * x.powf(c)) + d * x + e
}

/// Λ of a direction at cosine `mu`: the fit below 0.5, mirrored about 0.5 above.
fn lambda(mu: f64, alpha: f64) -> f64 {
    if mu < 0.5 {
        fit(mu, alpha).exp()
    } else {
        (2.0 * fit(0.5, alpha) - fit(1.0 - mu, alpha)).exp()
    }
}

/// Directional albedo at view cosine `mu` of the white sheen lobe of `roughness`.
fn albedo(mu: f64, roughness: f64) -> f64 {
    let alpha = roughness.max(ROUGHNESS_MIN).powi(2);
    let mu = mu.max(GRAZING);
    let wo = [(1.0 - mu * mu).sqrt(), 0.0, mu];
    let lo = lambda(mu, alpha);
    let azimuths: Vec<(f64, f64)> = (0..STEPS_PHI)
        .map(|j| ((j as f64 + 0.5) / STEPS_PHI as f64 * PI).sin_cos())
        .collect();
    let mut sum = 0.0;
    for i in 0..STEPS_T {
        let t = (i as f64 + 0.5) / STEPS_T as f64;
        let ci = t * t;
        let si = (1.0 - ci * ci).sqrt();
        let li = lambda(ci, alpha);
        for &(sin_phi, cos_phi) in &azimuths {
            let h = [wo[0] + si * cos_phi, si * sin_phi, wo[2] + ci];
            let len = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
            // f cos θi, with dω = 2t dt dφ.
            let f_cos = charlie(h[2] / len, alpha) / (4.0 * mu * (1.0 + lo + li));
            sum += f_cos * 2.0 * t;
        }
    }
    // Both halves of φ: 2 · (1/STEPS_T) · (π/STEPS_PHI).
    sum * 2.0 * PI / (STEPS_T * STEPS_PHI) as f64
}

/// The roughness of node `j`.
fn r_node(j: usize) -> f64 {
    ROUGHNESS_MIN + (1.0 - ROUGHNESS_MIN) * j as f64 / (ROUGHNESS - 1) as f64
}

/// The √μ of node `i`.
fn x_node(i: usize) -> f64 {
    i as f64 / (COS - 1) as f64
}

/// The table by roughness node and √μ node, rounded to the `f32` written out.
fn table() -> Vec<Vec<f32>> {
    (0..ROUGHNESS)
        .into_par_iter()
        .map(|j| {
            (0..COS)
                .map(|i| albedo(x_node(i).powi(2), r_node(j)) as f32)
                .collect()
        })
        .collect()
}

/// The table's bilinear value at (μ, roughness), as rondo interpolates it.
fn interpolate(t: &[Vec<f32>], mu: f64, r: f64) -> f64 {
    let cell = |x: f64, n: usize| {
        let x = x.clamp(0.0, (n - 1) as f64);
        let i = (x as usize).min(n - 2);
        (i, x - i as f64)
    };
    let (i, u) = cell(mu.sqrt() * (COS - 1) as f64, COS);
    let (j, v) = cell(
        (r - ROUGHNESS_MIN) / (1.0 - ROUGHNESS_MIN) * (ROUGHNESS - 1) as f64,
        ROUGHNESS,
    );
    let row = |j: usize| f64::from(t[j][i]) * (1.0 - u) + f64::from(t[j][i + 1]) * u;
    row(j) * (1.0 - v) + row(j + 1) * v
}

/// Prints the table's largest value and the largest error of the interpolated table at the
/// centres of its cells, of all and of those at most 88° from the normal.
fn check(t: &[Vec<f32>]) {
    let largest = t.iter().flatten().fold(0.0f32, |m, &v| m.max(v));
    eprintln!("largest albedo {largest}");
    for min_mu in [0.0, 88f64.to_radians().cos()] {
        let worst = (0..ROUGHNESS - 1)
            .into_par_iter()
            .map(|j| {
                let r = (r_node(j) + r_node(j + 1)) / 2.0;
                let mut worst = (0.0f64, 0.0, 0.0);
                for i in 0..COS - 1 {
                    let mu = ((x_node(i) + x_node(i + 1)) / 2.0).powi(2);
                    if mu < min_mu {
                        continue;
                    }
                    let e = (albedo(mu, r) - interpolate(t, mu, r)).abs();
                    if e > worst.0 {
                        worst = (e, mu, r);
                    }
                }
                worst
            })
            .reduce(|| (0.0, 0.0, 0.0), |a, b| if a.0 >= b.0 { a } else { b });
        eprintln!(
            "μ ≥ {min_mu:.3}: worst interpolation error {:.5} at μ {:.4}, roughness {:.3}",
            worst.0, worst.1, worst.2
        );
    }
}

/// The Rust source of the table.
fn source(t: &[Vec<f32>]) -> String {
    let mut out = format!(
        "//! Directional albedo of the white sheen lobe (Charlie distribution, Estevez & Kulla's\n\
         //! visibility), written by `cargo run --release --example make_sheen_table`\n\
         //! (examples/make_sheen_table.rs, which says how it is computed): do not edit by hand.\n\
         //! Nodes are uniform in sheen roughness over [`ROUGHNESS_MIN`] … 1 (α = roughness²) and\n\
         //! in √μ (μ the cosine of the view). Read through [`super::sheen`]. No ECS here.\n\n\
         /// The smallest sheen roughness the lobe takes (smaller ones are clamped to it).\n\
         pub const ROUGHNESS_MIN: f32 = {ROUGHNESS_MIN:?};\n\n\
         /// Number of roughness nodes, uniform over [`ROUGHNESS_MIN`] … 1.\n\
         pub const ROUGHNESS_NODES: usize = {ROUGHNESS};\n\n\
         /// Number of √μ nodes, uniform over 0 … 1.\n\
         pub const COS_NODES: usize = {COS};\n\n\
         /// Directional albedo of the white sheen lobe, by roughness node (rows) and √μ node\n\
         /// (columns).\n\
         #[rustfmt::skip]\n\
         pub static SHEEN: [[f32; COS_NODES]; ROUGHNESS_NODES] = [\n"
    );
    for row in t {
        out.push_str("    [\n");
        for chunk in row.chunks(8) {
            let items: Vec<String> = chunk.iter().map(|v| format!("{v:?}")).collect();
            out.push_str(&format!("        {},\n", items.join(", ")));
        }
        out.push_str("    ],\n");
    }
    out.push_str("];\n");
    out
}

fn main() {
    let t = table();
    if std::env::args().any(|a| a == "--check") {
        check(&t);
        return;
    }
    let Some(path) = std::env::args().nth(1) else {
        eprintln!("usage: make_sheen_table FILE (src/shading/sheen_table.rs) | --check");
        std::process::exit(2);
    };
    if let Err(e) = std::fs::write(&path, source(&t)) {
        eprintln!("{path}: {e}");
        std::process::exit(1);
    }
}
