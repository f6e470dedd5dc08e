//! Writes `src/shading/glass_table.rs`: the directional albedo E(μ, roughness, η) of rondo's
//! single-scattering rough dielectric interface (GGX reflection and transmission, exact
//! Fresnel, height-correlated Smith, α = roughness²), counted as flux: the reflected plus the
//! transmitted share of light arriving at view cosine μ on the side where the relative index of
//! the far side is η. `src/shading/rough_dielectric.rs` divides by it to put back what single
//! scattering loses.
//!
//! ```text
//! cargo run --release --example make_glass_albedo_table -- src/shading/glass_table.rs
//! cargo run --release --example make_glass_albedo_table -- --check   # interpolation error
//! ```
//!
//! The GGX terms come from `examples/ggx/`, written independently of `src/shading/`. Each entry
//! is the mean, over a `GRID × GRID` midpoint grid of the unit square mapped to visible
//! microfacet normals h, of `F(wo·h) w(wr) + (1 − F(wo·h)) w(wt)`, with wr and wt the reflection
//! and refraction of wo about h, `w = (1 + Λ(wo)) / (1 + Λ(wo) + Λ(wi))` where wi ends on the
//! side it should (else 0) and F the exact unpolarised Fresnel reflectance (1 under total
//! internal reflection): the expected weight of one sample of the lobe, which is its albedo.
//! Nodes are uniform in roughness (row 0 the smooth limit, 1), in √μ and in ln η over
//! [1/3, 3]. Deterministic: the same source gives the same bytes.

use rayon::prelude::*;

#[path = "ggx/mod.rs"]
mod ggx;

use ggx::{lambda, visible_normal};

/// Nodes in roughness (0 … 1).
const ROUGHNESS: usize = 20;
/// Nodes in √μ (0 … 1).
const COS: usize = 20;
/// Nodes in ln η, uniform over ln(1/3) … ln 3.
const ETA: usize = 25;
/// The largest relative index tabulated (its inverse is the smallest).
const ETA_MAX: f64 = 3.0;
/// Grid side of the quadrature over the visible-normal sample square.
const GRID: usize = 160;
/// The cosine used for the node μ = 0, where the view is in the surface's plane.
const GRAZING: f64 = 1e-6;

/// Exact unpolarised Fresnel reflectance at cosine `c` (> 0) to the microfacet, for relative
/// index `eta` of the far side: 1 under total internal reflection.
fn fresnel(c: f64, eta: f64) -> f64 {
    let sin2_t = (1.0 - c * c).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (c - eta * cos_t) / (c + eta * cos_t);
    let rp = (eta * c - cos_t) / (eta * c + cos_t);
    (rs * rs + rp * rp) / 2.0
}

/// Reflected plus transmitted flux at view cosine `mu`, for `roughness` and relative index `eta`.
fn albedo(mu: f64, roughness: f64, eta: f64) -> f64 {
    if roughness == 0.0 {
        return 1.0;
    }
    let alpha = roughness * roughness;
    let mu = mu.max(GRAZING);
    let wo = [(1.0 - mu * mu).sqrt(), 0.0, mu];
    let lo = lambda(mu, alpha);
    let weight = |wi_z: f64| (1.0 + lo) / (1.0 + lo + lambda(wi_z.abs(), alpha));
    let mut sum = 0.0;
    for i in 0..GRID {
        let u1 = (i as f64 + 0.5) / GRID as f64;
        for j in 0..GRID {
            let u2 = (j as f64 + 0.5) / GRID as f64;
            let h = visible_normal(wo, alpha, u1, u2);
            let c = wo[0] * h[0] + wo[1] * h[1] + wo[2] * h[2];
            if c <= 0.0 {
                continue;
            }
            let f = fresnel(c, eta);
            let reflected_z = 2.0 * c * h[2] - wo[2];
            if reflected_z > 0.0 {
                sum += f * weight(reflected_z);
            }
            let sin2_t = (1.0 - c * c).max(0.0) / (eta * eta);
            if f < 1.0 && sin2_t < 1.0 {
                // wt = −wo/η + (c/η − cos θt) h.
                let cos_t = (1.0 - sin2_t).sqrt();
                let refracted_z = -wo[2] / eta + (c / eta - cos_t) * h[2];
                if refracted_z < 0.0 {
                    sum += (1.0 - f) * weight(refracted_z);
                }
            }
        }
    }
    sum / (GRID * GRID) as f64
}

/// The √μ of node `i`.
fn x_node(i: usize) -> f64 {
    i as f64 / (COS - 1) as f64
}

/// The η of node `k`.
fn eta_node(k: usize) -> f64 {
    let t = k as f64 / (ETA - 1) as f64 * 2.0 - 1.0;
    ETA_MAX.powf(t)
}

/// The table by η node, roughness node and √μ node, rounded to the `f32` written out.
fn table() -> Vec<Vec<Vec<f32>>> {
    (0..ETA)
        .into_par_iter()
        .map(|k| {
            (0..ROUGHNESS)
                .map(|j| {
                    let r = j as f64 / (ROUGHNESS - 1) as f64;
                    (0..COS)
                        .map(|i| albedo(x_node(i).powi(2), r, eta_node(k)) as f32)
                        .collect()
                })
                .collect()
        })
        .collect()
}

/// The table's trilinear value at (μ, roughness, η), as rondo interpolates it.
fn interpolate(t: &[Vec<Vec<f32>>], mu: f64, r: f64, eta: f64) -> f64 {
    let cell = |x: f64, n: usize| {
        let x = x.clamp(0.0, (n - 1) as f64);
        let i = (x as usize).min(n - 2);
        (i, x - i as f64)
    };
    let (i, u) = cell(mu.sqrt() * (COS - 1) as f64, COS);
    let (j, v) = cell(r * (ROUGHNESS - 1) as f64, ROUGHNESS);
    let (k, w) = cell(
        (eta.ln() / ETA_MAX.ln() + 1.0) / 2.0 * (ETA - 1) as f64,
        ETA,
    );
    let row =
        |k: usize, j: usize| f64::from(t[k][j][i]) * (1.0 - u) + f64::from(t[k][j][i + 1]) * u;
    let plane = |k: usize| row(k, j) * (1.0 - v) + row(k, j + 1) * v;
    plane(k) * (1.0 - w) + plane(k + 1) * w
}

/// Prints the largest error of the interpolated table at the centres of its cells, for the
/// indices rondo's scenes use.
fn check(t: &[Vec<Vec<f32>>]) {
    for eta in [1.5, 1.0 / 1.5, 1.33, 1.0 / 1.33, 2.4, 1.0 / 2.4] {
        let worst = (1..ROUGHNESS - 1)
            .into_par_iter()
            .map(|j| {
                let r = (j as f64 + 0.5) / (ROUGHNESS - 1) as f64;
                let mut worst = (0.0f64, 0.0, 0.0);
                for i in 0..COS - 1 {
                    let mu = ((x_node(i) + x_node(i + 1)) / 2.0).powi(2);
                    let e = (albedo(mu, r, eta) - interpolate(t, mu, r, eta)).abs();
                    if e > worst.0 {
                        worst = (e, mu, r);
                    }
                }
                worst
            })
            .reduce(|| (0.0, 0.0, 0.0), |a, b| if a.0 >= b.0 { a } else { b });
        eprintln!(
            "η {eta:.3}: worst interpolation error {:.5} at μ {:.4}, roughness {:.3}",
            worst.0, worst.1, worst.2
        );
    }
}

/// The Rust source of the table.
fn source(t: &[Vec<Vec<f32>>]) -> String {
    let mut out = format!(
        "//! Directional albedo of rondo's single-scattering rough dielectric interface, written\n\
         //! by `cargo run --release --example make_glass_albedo_table` (examples/\n\
         //! make_glass_albedo_table.rs, which says how it is computed): do not edit by hand.\n\
         //! Reflected plus transmitted flux by η node, roughness node and √μ node; nodes are\n\
         //! uniform in ln η over [1/{ETA_MAX}, {ETA_MAX}], in roughness (α = roughness², row 0 the\n\
         //! smooth limit) and in √μ (μ the cosine of the view). Read through\n\
         //! [`super::rough_dielectric`]. No ECS here.\n\n\
         /// Number of η nodes, uniform in ln η over [1/[`ETA_MAX`], [`ETA_MAX`]].\n\
         pub const ETA_NODES: usize = {ETA};\n\n\
         /// The largest relative index tabulated; its inverse is the smallest.\n\
         pub const ETA_MAX: f32 = {ETA_MAX:?};\n\n\
         /// Number of roughness nodes, uniform over 0 … 1.\n\
         pub const ROUGHNESS_NODES: usize = {ROUGHNESS};\n\n\
         /// Number of √μ nodes, uniform over 0 … 1.\n\
         pub const COS_NODES: usize = {COS};\n\n\
         /// Reflected plus transmitted flux of the single-scattering interface.\n\
         #[rustfmt::skip]\n\
         pub static GLASS: [[[f32; COS_NODES]; ROUGHNESS_NODES]; ETA_NODES] = [\n"
    );
    for plane in t {
        out.push_str("    [\n");
        for row in plane {
            let items: Vec<String> = row.iter().map(|v| format!("{v:?}")).collect();
            out.push_str(&format!("        [{}],\n", items.join(", ")));
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
        eprintln!("usage: make_glass_albedo_table FILE (src/shading/glass_table.rs) | --check");
        std::process::exit(2);
    };
    if let Err(e) = std::fs::write(&path, source(&t)) {
        eprintln!("{path}: {e}");
        std::process::exit(1);
    }
}
