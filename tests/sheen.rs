//! `Pbr`'s sheen layer (`KHR_materials_sheen`) against independent truth: the sheen lobe's
//! directional albedo, tabulated by rondo, against a quadrature of the Charlie BRDF written
//! out here in `f64`; a black base under a white sheen reflecting exactly that albedo, and a
//! white one reflecting 1 (both by a quadrature of `eval`); sampled directions against the
//! evaluated density (χ²); white balls under a white sheen in a white furnace; and the RON
//! fields loading and refusing out-of-range values.
//!
//! `cargo test --release --test sheen -- --nocapture` prints the albedos, the χ² statistics and
//! the furnace.

mod common;

use common::chi2::chi_square_of_directions;
use common::furnace::{furnace_pixels, write_white_map};
use common::sheen_brdf::{hemisphere, sheen_cos};
use common::{layered_pbr, temp_dir, write_scene};
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use rondo::scene::assets::AssetCache;
use rondo::scene::load::load_scene;
use rondo::shading::layers::Layers;
use rondo::shading::material::Material;
use rondo::shading::sheen::Sheen;

fn sheen(color: Vec3, roughness: f32) -> Layers {
    Layers {
        sheen_color: color,
        sheen_roughness: roughness,
        ..Layers::NONE
    }
}

/// The directional albedo of `m` for a view at cosine `mu`, by [`hemisphere`] of its `eval`.
fn albedo(m: &Material, mu: f64) -> [f64; 3] {
    let d = Vec3::new(-(1.0 - mu * mu).sqrt() as f32, 0.0, -mu as f32);
    let bsdf = m.bsdf_at(d, Vec3::Z, Vec2::ZERO);
    hemisphere(mu, |_, wi| {
        let w = Vec3::new(wi[0] as f32, wi[1] as f32, wi[2] as f32).normalize();
        let v = bsdf.eval(w).expect("evaluable").0;
        [v.x, v.y, v.z].map(f64::from)
    })
}

/// The views and roughnesses swept, between the table's nodes.
const COSINES: [f64; 6] = [1.0, 0.8, 0.5, 0.3, 0.15, 0.08];
const ROUGHNESSES: [f64; 5] = [0.1, 0.3, 0.55, 0.8, 1.0];

fn cases() -> Vec<(f64, f64)> {
    COSINES
        .iter()
        .flat_map(|&mu| ROUGHNESSES.iter().map(move |&r| (mu, r)))
        .collect()
}

#[test]
fn the_tabulated_sheen_albedo_is_the_integral_of_the_charlie_brdf() {
    let rows: Vec<(f64, f64, f64, f64)> = cases()
        .par_iter()
        .map(|&(mu, r)| {
            let expected = hemisphere(mu, |wo, wi| [sheen_cos(wo, wi, r); 3])[0];
            let got = f64::from(Sheen::new(Vec3::ONE, r as f32).albedo(mu as f32));
            (mu, r, got, expected)
        })
        .collect();
    let mut failures = Vec::new();
    for (mu, r, got, expected) in rows {
        println!("sheen albedo μ {mu} roughness {r}: rondo {got:.4}, quadrature {expected:.4}");
        if (got - expected).abs() > 0.004 + 0.02 * expected {
            failures.push(format!("μ {mu} roughness {r}: {got:.4} vs {expected:.4}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn a_black_base_under_a_sheen_reflects_the_sheen_lobe_and_a_white_one_everything() {
    // Black base, no specular lobe: all that is reflected is the sheen, its colour times the
    // white lobe's albedo (below 1 at these views). White base and white sheen: the base gets
    // exactly what the sheen does not reflect, so 1 in all.
    let color = Vec3::new(1.0, 0.5, 0.25);
    let rows: Vec<(f64, f64, [f64; 3], f64, f64)> = cases()
        .par_iter()
        .map(|&(mu, r)| {
            let dark = Layers {
                specular: 0.0,
                ..sheen(color, r as f32)
            };
            let black = albedo(&layered_pbr(Vec3::ZERO, 0.0, 0.5, dark), mu);
            let white = albedo(
                &layered_pbr(Vec3::ONE, 0.0, 0.5, sheen(Vec3::ONE, r as f32)),
                mu,
            )[0];
            let lobe = hemisphere(mu, |wo, wi| [sheen_cos(wo, wi, r); 3])[0];
            (mu, r, black, white, lobe)
        })
        .collect();
    let mut failures = Vec::new();
    let mut worst_white = 0.0f64;
    for (mu, r, black, white, lobe) in rows {
        worst_white = worst_white.max((white - 1.0).abs());
        for (k, c) in color.to_array().into_iter().enumerate() {
            let expected = f64::from(c) * lobe;
            if (black[k] - expected).abs() > 0.004 + 0.02 * expected {
                failures.push(format!(
                    "black base μ {mu} r {r}: {black:.4?} vs lobe {lobe:.4}"
                ));
            }
        }
        if (white - 1.0).abs() > 0.01 {
            failures.push(format!("white base μ {mu} r {r}: {white:.4}"));
        }
    }
    println!("white base under a white sheen: worst |albedo − 1| {worst_white:.4}");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn sampled_directions_under_a_sheen_follow_the_density() {
    for (what, m, deg) in [
        (
            "sheen 0.3 over dielectric 0.6",
            layered_pbr(Vec3::new(0.2, 0.3, 0.8), 0.0, 0.6, sheen(Vec3::ONE, 0.3)),
            50.0f32,
        ),
        (
            "sheen 0.8 over metal 0.2",
            layered_pbr(
                Vec3::new(0.9, 0.6, 0.3),
                1.0,
                0.2,
                sheen(Vec3::new(1.0, 0.2, 0.2), 0.8),
            ),
            75.0,
        ),
        (
            "sheen 0 (the lobe's narrowest) over dielectric 0.3",
            layered_pbr(Vec3::splat(0.5), 0.0, 0.3, sheen(Vec3::splat(0.7), 0.0)),
            82.0,
        ),
        (
            "sheen 0.4 under a coat 0.3",
            layered_pbr(
                Vec3::new(0.3, 0.8, 0.5),
                0.0,
                0.7,
                Layers {
                    clearcoat: 1.0,
                    clearcoat_roughness: 0.3,
                    ..sheen(Vec3::ONE, 0.4)
                },
            ),
            65.0,
        ),
    ] {
        let theta = deg.to_radians();
        let d = Vec3::new(theta.sin(), 0.0, -theta.cos());
        let (chi2, limit) = chi_square_of_directions(&m, d, 300_000, 23);
        println!("{what} {deg}°: χ² {chi2:.1} (limit {limit:.1})");
        assert!(
            chi2 < limit,
            "{what} {deg}°: χ² {chi2:.1} (limit {limit:.1})"
        );
    }
}

#[test]
fn white_balls_under_a_white_sheen_stay_at_one_in_a_white_furnace() {
    // The ball's mean is Σ (v − b) / Σ (1 − b), b a black ball's pixels (the background's
    // share). The sheen takes from the base what it reflects itself, so neither may add light.
    let dir = temp_dir("sheen-furnace");
    write_white_map(&dir);
    let spp = 16;
    let background = furnace_pixels(&dir, "Diffuse(albedo: Constant((0, 0, 0)))", spp);
    let mut failures = Vec::new();
    for (metallic, roughness, sheen_roughness, coat) in [
        ("0", "0.5", "0", "0"),
        ("0", "0", "0.4", "0"),
        ("0", "0.5", "0.3", "0"),
        ("0", "1", "1", "0"),
        ("1", "0.3", "0.6", "0"),
        ("0", "0.4", "0.5", "1"),
    ] {
        let material = format!(
            "Pbr(base_color: Constant((1, 1, 1)), metallic: {metallic}, roughness: {roughness}, \
             sheen_color: (1, 1, 1), sheen_roughness: {sheen_roughness}, clearcoat: {coat}, \
             clearcoat_roughness: 0.2)"
        );
        let v = furnace_pixels(&dir, &material, spp);
        let (mut sum, mut cover) = (0.0, 0.0);
        for (v, b) in v.iter().zip(&background) {
            sum += v - b;
            cover += 1.0 - b;
        }
        let mean = sum / cover;
        println!(
            "white Pbr metallic {metallic}, roughness {roughness} under sheen {sheen_roughness}, \
             coat {coat}: ball {mean:.4}"
        );
        if !(0.985..=1.005).contains(&mean) {
            failures.push(format!("{material}: {mean:.4}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn ron_sheen_fields_load_and_out_of_range_values_are_refused() {
    let dir = temp_dir("sheen-ron");
    let scene = |material: &str| {
        write_scene(
            &dir,
            "s.ron",
            &format!(
                "Scene(camera: Camera(position: (0, 0, -4), look_at: (0, 0, 0), fov: 32), \
                 materials: {{ \"m\": {material} }}, \
                 entities: [Entity(material: \"m\", shape: Sphere(center: (0, 0, 0), radius: 1))])"
            ),
        )
    };
    let path = scene("Pbr(sheen_color: (1, 0.5, 0.25), sheen_roughness: 0.75)");
    let loaded = load_scene(&path, &mut AssetCache::default()).unwrap_or_else(|e| panic!("{e}"));
    let m = &loaded.materials[&loaded.entities[0].material];
    let Material::Pbr { layers, .. } = m else {
        panic!("{m:?}")
    };
    assert_eq!(layers.sheen_color, Vec3::new(1.0, 0.5, 0.25));
    assert_eq!(layers.sheen_roughness, 0.75);
    let plain = scene("Pbr(roughness: 0.5)");
    let loaded = load_scene(&plain, &mut AssetCache::default()).unwrap_or_else(|e| panic!("{e}"));
    let m = &loaded.materials[&loaded.entities[0].material];
    assert!(matches!(m, Material::Pbr { layers, .. } if *layers == Layers::NONE));
    for bad in ["sheen_color: (1, 1.5, 0)", "sheen_roughness: -0.1"] {
        let path = scene(&format!("Pbr({bad})"));
        let e = load_scene(&path, &mut AssetCache::default())
            .map(|_| ())
            .expect_err("refused");
        assert!(e.to_string().contains("s.ron"), "{e}");
    }
}
