//! Energy conservation of the GGX lobes (`Glossy`, `Pbr`) against independent truth: the
//! directional albedo of each white lobe by numerical integration of `eval` (a quadrature of the
//! test's own, not the lobe's sampler) is 1 within 1 % at 300 (angle, roughness) pairs up to 88°;
//! sampled directions follow the evaluated density (χ²); and white balls in a white furnace
//! render at 1 within 1 %, their silhouettes too.
//!
//! `cargo test --release --test energy -- --nocapture` prints the worst albedos and the furnace
//! table.

mod common;

use std::f64::consts::PI;

use common::chi2::chi_square_of_directions;
use common::furnace::{furnace_pixels, write_white_map};
use common::temp_dir;
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use rondo::shading::material::Material;
use rondo::shading::texture::Texture;

fn glossy(f0: Vec3, roughness: f32) -> Material {
    Material::Glossy {
        albedo: Texture::Constant(f0),
        roughness,
    }
}

/// GGX D(h) for α, in `f64`, written out here.
fn ggx_d(cos_h: f64, alpha: f64) -> f64 {
    let a2 = alpha * alpha;
    let t = cos_h * cos_h * (a2 - 1.0) + 1.0;
    a2 / (PI * t * t)
}

/// ∫ f cos θi dωi of `m` for a view at `theta` from the normal +z: a deterministic quadrature
/// of `eval`'s value, by the one-sample mixture of two warps of an `n × n` midpoint grid (the
/// half vector distributed as D(h) cos θh, reflected; and the cosine), each point weighted by
/// the mixture density ½ q_D + ½ q_cos, both computed here.
fn albedo(m: &Material, theta: f64, roughness: f64, n: usize) -> f64 {
    let alpha = roughness.max(0.01).powi(2);
    let wo = [theta.sin(), 0.0, theta.cos()];
    let d = Vec3::new(-wo[0] as f32, 0.0, -wo[2] as f32);
    let bsdf = m.bsdf_at(d, Vec3::Z, Vec2::ZERO);
    let density = |wi: [f64; 3]| {
        let h = [wo[0] + wi[0], wo[1] + wi[1], wo[2] + wi[2]];
        let l = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
        let h = [h[0] / l, h[1] / l, h[2] / l];
        let oh = wo[0] * h[0] + wo[1] * h[1] + wo[2] * h[2];
        let q_d = ggx_d(h[2], alpha) * h[2] / (4.0 * oh);
        0.5 * q_d + 0.5 * wi[2] / PI
    };
    let value = |wi: [f64; 3]| {
        let w = Vec3::new(wi[0] as f32, wi[1] as f32, wi[2] as f32).normalize();
        f64::from(bsdf.eval(w).expect("evaluable").0.x)
    };
    let mut sum = 0.0;
    for i in 0..n {
        let u1 = (i as f64 + 0.5) / n as f64;
        for j in 0..n {
            let phi = (j as f64 + 0.5) / n as f64 * 2.0 * PI;
            // The half vector: tan²θh = α² u / (1 − u) has the density D(h) cos θh.
            let tan2 = alpha * alpha * u1 / (1.0 - u1);
            let ch = 1.0 / (1.0 + tan2).sqrt();
            let sh = (1.0 - ch * ch).sqrt();
            let h = [sh * phi.cos(), sh * phi.sin(), ch];
            let oh = wo[0] * h[0] + wo[2] * h[2];
            let wi = [
                2.0 * oh * h[0] - wo[0],
                2.0 * oh * h[1],
                2.0 * oh * h[2] - wo[2],
            ];
            if oh > 0.0 && wi[2] > 0.0 {
                sum += 0.5 * value(wi) / density(wi);
            }
            // The cosine.
            let (s, c) = (u1.sqrt(), (1.0 - u1).sqrt());
            let wi = [s * phi.cos(), s * phi.sin(), c];
            sum += 0.5 * value(wi) / density(wi);
        }
    }
    sum / (n * n) as f64
}

/// A white lobe's name and its material of a given roughness.
type Lobe = (&'static str, fn(f32) -> Material);

/// The (angle in degrees, roughness) pairs: 15 angles up to 88°, 20 roughnesses from 0.05.
fn pairs() -> Vec<(f64, f64)> {
    let angles = [
        0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 65.0, 70.0, 75.0, 80.0, 83.0, 85.0, 87.0, 88.0,
    ];
    let mut out = Vec::new();
    for a in angles {
        for k in 0..20 {
            out.push((a, 0.05 + 0.95 * f64::from(k) / 19.0));
        }
    }
    out
}

#[test]
fn white_lobes_reflect_everything_at_every_angle_and_roughness() {
    let lobes: [Lobe; 4] = [
        ("Glossy", |r| glossy(Vec3::ONE, r)),
        ("Pbr metallic 1", |r| Material::pbr(Vec3::ONE, 1.0, r)),
        ("Pbr metallic 0", |r| Material::pbr(Vec3::ONE, 0.0, r)),
        ("Pbr metallic 0.5", |r| Material::pbr(Vec3::ONE, 0.5, r)),
    ];
    let mut failures = Vec::new();
    for (name, make) in lobes {
        let results: Vec<(f64, f64, f64)> = pairs()
            .into_par_iter()
            .map(|(deg, r)| {
                let m = make(r as f32);
                (deg, r, albedo(&m, deg.to_radians(), r, 160))
            })
            .collect();
        let worst = results.iter().copied().fold((0.0, 0.0, 1.0), |w, x| {
            if (x.2 - 1.0).abs() > (w.2 - 1.0f64).abs() {
                x
            } else {
                w
            }
        });
        let highest = results.iter().map(|x| x.2).fold(f64::MIN, f64::max);
        println!(
            "{name}: worst albedo {:.4} at {}°, roughness {:.2}; highest {highest:.4} ({} pairs)",
            worst.2,
            worst.0,
            worst.1,
            results.len()
        );
        for (deg, r, a) in results {
            if (a - 1.0).abs() > 0.01 {
                failures.push(format!("{name} {deg}° roughness {r:.2}: {a:.4}"));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} pairs off by more than 1 %:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

#[test]
fn a_coloured_pbr_reflects_at_most_what_white_does() {
    // The base scales only the cosine lobes and the conductor's F0 only its Fresnel: a darker
    // colour reflects less than white at every angle, never more than 1.
    for (deg, r) in [
        (0.0, 0.3),
        (60.0, 0.05),
        (88.0, 0.05),
        (80.0, 0.6),
        (88.0, 1.0),
    ] {
        for metallic in [0.0f32, 0.5, 1.0] {
            let m = Material::pbr(Vec3::splat(0.5), metallic, r as f32);
            let a = albedo(&m, f64::to_radians(deg), r, 160);
            assert!(a < 1.0 && a > 0.0, "{metallic} {deg}° {r}: {a}");
        }
    }
}

#[test]
fn sampled_directions_of_the_compensated_lobes_follow_the_density() {
    // Views and roughnesses where the cosine-sampled lobes carry much of the light.
    for (what, m, theta) in [
        ("Glossy", glossy(Vec3::new(0.9, 0.5, 0.2), 1.0), 1.3),
        ("Glossy", glossy(Vec3::ONE, 0.6), 0.4),
        (
            "Pbr metal",
            Material::pbr(Vec3::new(0.9, 0.6, 0.3), 1.0, 0.8),
            1.2,
        ),
        ("Pbr dielectric", Material::pbr(Vec3::ONE, 0.0, 0.7), 1.3),
        (
            "Pbr dielectric, narrow",
            Material::pbr(Vec3::ONE, 0.0, 0.3),
            80f32.to_radians(),
        ),
        (
            "Pbr mix",
            Material::pbr(Vec3::new(0.3, 0.8, 0.5), 0.5, 0.6),
            0.5,
        ),
    ] {
        let d = Vec3::new(f32::sin(theta), 0.0, -f32::cos(theta));
        let (chi2, limit) = chi_square_of_directions(&m, d, 300_000, 11);
        assert!(
            chi2 < limit,
            "{what} θ {theta}: χ² {chi2:.1} (limit {limit:.1})"
        );
    }
}

#[test]
fn white_balls_are_one_in_a_white_furnace() {
    // Each pixel is c L + (1 − c) 1, c the share of its camera rays that hit the ball: a black
    // ball rendered with the same rays gives 1 − c. So the ball's mean radiance is
    // Σ (v − (1 − c)) / Σ c; the silhouette is the pixels the ball covers partly or whose
    // centre is more than 0.85 of its radius from the centre (views beyond 58°).
    let dir = temp_dir("energy-furnace");
    write_white_map(&dir);
    let spp = 16;
    let background = furnace_pixels(&dir, "Diffuse(albedo: Constant((0, 0, 0)))", spp);
    let mut rows = Vec::new();
    let mut failures = Vec::new();
    let mut materials = Vec::new();
    for metallic in ["0", "0.5", "1"] {
        for roughness in ["0.05", "0.3", "0.6", "1"] {
            materials.push((
                format!("Pbr metallic {metallic:>3}, roughness {roughness:>4}"),
                format!(
                    "Pbr(base_color: Constant((1, 1, 1)), metallic: {metallic}, roughness: {roughness})"
                ),
            ));
        }
    }
    for roughness in ["0.05", "0.3", "0.6", "1"] {
        materials.push((
            format!("Glossy            roughness {roughness:>4}"),
            format!("Glossy(albedo: Constant((1, 1, 1)), roughness: {roughness})"),
        ));
    }
    // The ball's radius in pixels: tan(asin(1/4)) / tan(16°) of half the image.
    let radius = (0.25f64.asin().tan() / 16f64.to_radians().tan()) * 20.0;
    for (name, material) in materials {
        let v = furnace_pixels(&dir, &material, spp);
        let (mut sum, mut cover, mut edge_sum, mut edge_cover) = (0.0, 0.0, 0.0, 0.0);
        for (k, (v, b)) in v.iter().zip(&background).enumerate() {
            let c = 1.0 - b;
            let (x, y) = ((k % 40) as f64 + 0.5 - 20.0, (k / 40) as f64 + 0.5 - 20.0);
            sum += v - b;
            cover += c;
            if c > 0.0 && (c < 1.0 || (x * x + y * y).sqrt() > 0.85 * radius) {
                edge_sum += v - b;
                edge_cover += c;
            }
        }
        let (mean, edge) = (sum / cover, edge_sum / edge_cover);
        rows.push(format!("{name}: ball {mean:.4}, silhouette {edge:.4}"));
        if (mean - 1.0).abs() > 0.01 || (edge - 1.0).abs() > 0.02 {
            failures.push(format!("{name}: ball {mean:.4}, silhouette {edge:.4}"));
        }
    }
    println!("{}", rows.join("\n"));
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
