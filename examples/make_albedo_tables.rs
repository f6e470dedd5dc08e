//! Writes `src/shading/albedo_table/` (`mod.rs`, `conductor.rs`, `dielectric.rs`): the directional albedo E(μ, roughness) of rondo's
//! single-scattering GGX reflection (height-correlated Smith, α = roughness²) with Fresnel 1 (the
//! conductor's table) and with the exact Fresnel of a dielectric of ior 1.5 (the dielectric
//! specular lobe of `Pbr`), and each row's cosine-weighted average E_avg = 2 ∫ E(μ) μ dμ (as 1 − E_avg).
//!
//! ```text
//! cargo run --release --example make_albedo_tables -- src/shading/albedo_table
//! cargo run --release --example make_albedo_tables -- --check   # interpolation error
//! ```
//!
//! The GGX terms are written here again in `f64`, independently of `src/shading/microfacet.rs`.
//! Each entry is the mean of `F (1 + Λ(wo)) / (1 + Λ(wo) + Λ(wi))` (zero for `wi` below the
//! surface) over a `GRID × GRID` midpoint grid of the unit square mapped to microfacet normals
//! by Heitz's visible-normal sampling (JCGT 2018): that map carries the uniform measure to the
//! density `G₁(wo) D(h) (wo·h) / cos θo`, under which `f cos θi / pdf` is exactly that
//! integrand. Row 0 (roughness 0) is the mirror's limit: 1, and the dielectric's F(μ). Nodes are
//! uniform in roughness and in √μ, which puts them close together at grazing angles, where E
//! changes fastest. The averages are the exact integrals of the table as rondo interpolates it
//! (linear in √μ between nodes), computed from the rounded values written out, so that
//! `2 ∫ (1 − E(μ)) μ dμ = 1 − E_avg` holds for the interpolated table to rounding.
//! Deterministic: the same source gives the same bytes.

use rayon::prelude::*;

#[path = "ggx/mod.rs"]
mod ggx;

use ggx::{lambda, visible_normal};

/// Nodes in roughness (0 … 1).
const ROUGHNESS: usize = 64;
/// Nodes in √μ (0 … 1).
const COS: usize = 64;
/// Grid side of the quadrature over the visible-normal sample square.
const GRID: usize = 512;
/// The cosine used for the node μ = 0, where the view is in the surface's plane.
const GRAZING: f64 = 1e-6;
/// Index of refraction of the dielectric lobe.
const DIELECTRIC_IOR: f64 = 1.5;

/// The Fresnel factor a table is computed with.
#[derive(Clone, Copy)]
enum Fresnel {
    /// 1 at every angle (the conductor's table, its colour applied by rondo).
    One,
    /// The exact reflectance of unpolarised light from outside a dielectric of ior 1.5.
    Dielectric,
}

impl Fresnel {
    /// The reflectance at cosine `c` (Born & Wolf §1.5.2 for the dielectric).
    fn at(self, c: f64) -> f64 {
        match self {
            Self::One => 1.0,
            Self::Dielectric => {
                let c = c.clamp(0.0, 1.0);
                let eta = DIELECTRIC_IOR;
                let cos_t = (1.0 - (1.0 - c * c) / (eta * eta)).sqrt();
                let rs = (c - eta * cos_t) / (c + eta * cos_t);
                let rp = (eta * c - cos_t) / (eta * c + cos_t);
                0.5 * (rs * rs + rp * rp)
            }
        }
    }
}

/// Directional albedo at view cosine `mu` of GGX `alpha` with the Fresnel factor `fresnel`.
fn albedo(mu: f64, roughness: f64, fresnel: Fresnel) -> f64 {
    if roughness == 0.0 {
        return fresnel.at(mu);
    }
    let alpha = roughness * roughness;
    let mu = mu.max(GRAZING);
    let wo = [(1.0 - mu * mu).sqrt(), 0.0, mu];
    let lo = lambda(mu, alpha);
    let mut sum = 0.0;
    for i in 0..GRID {
        let u1 = (i as f64 + 0.5) / GRID as f64;
        for j in 0..GRID {
            let u2 = (j as f64 + 0.5) / GRID as f64;
            let h = visible_normal(wo, alpha, u1, u2);
            let oh = wo[0] * h[0] + wo[1] * h[1] + wo[2] * h[2];
            let wi_z = 2.0 * oh * h[2] - wo[2];
            if wi_z > 0.0 {
                sum += fresnel.at(oh) * (1.0 + lo) / (1.0 + lo + lambda(wi_z, alpha));
            }
        }
    }
    sum / (GRID * GRID) as f64
}

/// The √μ of node `i`.
fn x_node(i: usize) -> f64 {
    i as f64 / (COS - 1) as f64
}

/// A table over (roughness node, √μ node), rounded to the `f32` written out (in its shortest
/// exact form).
fn table(fresnel: Fresnel) -> Vec<Vec<f32>> {
    (0..ROUGHNESS)
        .into_par_iter()
        .map(|j| {
            let r = j as f64 / (ROUGHNESS - 1) as f64;
            (0..COS)
                .map(|i| albedo(x_node(i).powi(2), r, fresnel) as f32)
                .collect()
        })
        .collect()
}

/// 2 ∫ E(μ) μ dμ = 4 ∫ E(x) x³ dx for E linear in x = √μ between the nodes of `row`, in `f64`.
fn average(row: &[f32]) -> f64 {
    let mut sum = 0.0;
    for i in 0..COS - 1 {
        let (a, b) = (x_node(i), x_node(i + 1));
        let (ea, eb) = (f64::from(row[i]), f64::from(row[i + 1]));
        let s = (eb - ea) / (b - a);
        let x4 = (b.powi(4) - a.powi(4)) / 4.0;
        let x5 = (b.powi(5) - a.powi(5)) / 5.0;
        sum += ea * x4 + s * (x5 - a * x4);
    }
    4.0 * sum
}

/// The table's bilinear value at (μ, roughness), as rondo interpolates it.
fn interpolate(t: &[Vec<f32>], mu: f64, r: f64) -> f64 {
    let fx = mu.sqrt() * (COS - 1) as f64;
    let i = (fx as usize).min(COS - 2);
    let u = fx - i as f64;
    let fr = r * (ROUGHNESS - 1) as f64;
    let j = (fr as usize).min(ROUGHNESS - 2);
    let v = fr - j as f64;
    let at = |j: usize| f64::from(t[j][i]) * (1.0 - u) + f64::from(t[j][i + 1]) * u;
    at(j) * (1.0 - v) + at(j + 1) * v
}

/// Prints the largest error of the interpolated tables at the centres of their cells, of all
/// and of those at most 88° from the normal.
fn check(tables: &[(&str, Fresnel, Vec<Vec<f32>>)]) {
    for ((name, fresnel, t), min_mu) in tables
        .iter()
        .flat_map(|t| [(t, 0.0), (t, 88f64.to_radians().cos())])
    {
        let worst = (1..ROUGHNESS - 1)
            .into_par_iter()
            .map(|j| {
                let r = (j as f64 + 0.5) / (ROUGHNESS - 1) as f64;
                let mut worst = (0.0f64, 0.0, 0.0);
                for i in 0..COS - 1 {
                    let mu = ((x_node(i) + x_node(i + 1)) / 2.0).powi(2);
                    if mu < min_mu {
                        continue;
                    }
                    let e = (albedo(mu, r, *fresnel) - interpolate(t, mu, r)).abs();
                    if e > worst.0 {
                        worst = (e, mu, r);
                    }
                }
                worst
            })
            .reduce(|| (0.0, 0.0, 0.0), |a, b| if a.0 >= b.0 { a } else { b });
        eprintln!(
            "{name}, μ ≥ {min_mu:.3}: worst interpolation error {:.5} at μ {:.4}, roughness {:.3}",
            worst.0, worst.1, worst.2
        );
    }
}

/// Rust source of a table and its averages.
fn write(out: &mut String, name: &str, what: &str, t: &[Vec<f32>]) {
    out.push_str(&format!(
        "/// Directional albedo of {what},\n\
         /// by roughness node (rows) and √μ node (columns).\n\
         #[rustfmt::skip]\n\
         pub static {name}: [[f32; COS_NODES]; ROUGHNESS_NODES] = [\n"
    ));
    for row in t {
        out.push_str("    [\n");
        for chunk in row.chunks(8) {
            let items: Vec<String> = chunk.iter().map(|v| format!("{v:?}")).collect();
            out.push_str(&format!("        {},\n", items.join(", ")));
        }
        out.push_str("    ],\n");
    }
    out.push_str("];\n\n");
    out.push_str(&format!(
        "/// 1 − E_avg = 2 ∫ (1 − E(μ)) μ dμ of each row of [`{name}`] as interpolated (linear in\n\
         /// √μ), stored as the loss for its relative precision where E_avg is near 1.\n\
         #[rustfmt::skip]\n\
         pub static {name}_LOST: [f32; ROUGHNESS_NODES] = [\n"
    ));
    for chunk in t.chunks(8) {
        let items: Vec<String> = chunk
            .iter()
            .map(|row| format!("{:?}", (1.0 - average(row)) as f32))
            .collect();
        out.push_str(&format!("    {},\n", items.join(", ")));
    }
    out.push_str("];\n\n");
}

fn main() {
    let conductor = table(Fresnel::One);
    let dielectric = table(Fresnel::Dielectric);
    if std::env::args().any(|a| a == "--check") {
        check(&[
            ("conductor", Fresnel::One, conductor),
            ("dielectric", Fresnel::Dielectric, dielectric),
        ]);
        return;
    }
    let Some(dir) = std::env::args().nth(1).map(std::path::PathBuf::from) else {
        eprintln!("usage: make_albedo_tables DIR (src/shading/albedo_table) | --check");
        std::process::exit(2);
    };
    let mut head = String::new();
    head.push_str(
        "//! Directional albedo tables of GGX reflection, written by\n\
         //! `cargo run --release --example make_albedo_tables` (examples/make_albedo_tables.rs,\n\
         //! which says how they are computed; about 4 minutes on 2 cores): do not edit by hand.\n\
         //! Nodes are uniform in roughness (α = roughness², row 0 the mirror) and in √μ (μ the\n\
         //! cosine of the view). Read through [`super::energy`]. One file per table. No ECS here.\n\n",
    );
    head.push_str(&format!(
        "/// Number of roughness nodes (rows), uniform over 0 … 1.\n\
         pub const ROUGHNESS_NODES: usize = {ROUGHNESS};\n\n\
         /// Number of √μ nodes (columns), uniform over 0 … 1.\n\
         pub const COS_NODES: usize = {COS};\n\n\
         mod conductor;\n\
         mod dielectric;\n\n\
         pub use conductor::{{CONDUCTOR, CONDUCTOR_LOST}};\n\
         pub use dielectric::{{DIELECTRIC, DIELECTRIC_LOST}};\n"
    ));
    let save = |file: &str, text: &str| {
        let path = dir.join(file);
        if let Err(e) = std::fs::write(&path, text) {
            eprintln!("{}: {e}", path.display());
            std::process::exit(1);
        }
    };
    save("mod.rs", &head);
    for (file, name, what, t) in [
        (
            "conductor",
            "CONDUCTOR",
            "single-scattering GGX with Fresnel 1",
            &conductor,
        ),
        (
            "dielectric",
            "DIELECTRIC",
            "single-scattering GGX with the exact Fresnel of ior 1.5",
            &dielectric,
        ),
    ] {
        let mut out = format!(
            "//! The {file}'s table (see the module above), written by the generator.\n\n\
             use super::{{COS_NODES, ROUGHNESS_NODES}};\n\n"
        );
        write(&mut out, name, what, t);
        save(
            &format!("{file}.rs"),
            &format!("{}\n", out.trim_end_matches('\n')),
        );
    }
}
