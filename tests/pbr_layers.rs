//! `Pbr`'s specular strength and colour (`KHR_materials_specular`) and clear coat
//! (`KHR_materials_clearcoat`) against independent truth: directional albedos by a quadrature
//! of `eval` (the test's own warps, not the lobes' samplers) against the same quadrature of
//! the BRDF written out here in `f64`, and against 1 for a white base (which loses nothing, so
//! neither layer may take or add light); the smooth coat's albedo by sampling against Schlick's
//! Fresnel; sampled directions against the evaluated density (χ²); white coated balls in a
//! white furnace; and a glTF file written here loading to the expected fields and warnings.
//!
//! `cargo test --release --test pbr_layers -- --nocapture` prints the albedos and the furnace.

mod common;

use std::f64::consts::PI;
use std::path::Path;

use common::chi2::chi_square_of_directions;
use common::furnace::{furnace_pixels, write_white_map};
use common::gltf_doc::{Bin, doc};
use common::{layered_pbr, temp_dir, write_scene};
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use rondo::scene::assets::AssetCache;
use rondo::scene::load::load_scene;
use rondo::shading::layers::Layers;
use rondo::shading::material::Material;
use rondo::shading::rng::Rng;
use serde_json::{Value, json};

fn specular(weight: f32, color: Vec3) -> Layers {
    Layers {
        specular: weight,
        specular_color: color,
        ..Layers::NONE
    }
}

fn coat(weight: f32, roughness: f32) -> Layers {
    Layers {
        clearcoat: weight,
        clearcoat_roughness: roughness,
        ..Layers::NONE
    }
}

/// GGX D(h) for α at cos θh.
fn ggx_d(cos_h: f64, alpha: f64) -> f64 {
    let a2 = alpha * alpha;
    let t = cos_h * cos_h * (a2 - 1.0) + 1.0;
    a2 / (PI * t * t)
}

/// Smith's Λ for GGX α at cos θ.
fn lambda(mu: f64, alpha: f64) -> f64 {
    let tan2 = (1.0 - mu * mu).max(0.0) / (mu * mu);
    ((1.0 + alpha * alpha * tan2).sqrt() - 1.0) / 2.0
}

/// The Fresnel equations' reflectance of unpolarised light from outside a dielectric of ior
/// 1.5 at cosine `c` (Born & Wolf §1.5.2).
fn fresnel_ior(c: f64) -> f64 {
    let eta = 1.5f64;
    let c = c.clamp(0.0, 1.0);
    let cos_t = (1.0 - (1.0 - c * c) / (eta * eta)).sqrt();
    let rs = (c - eta * cos_t) / (c + eta * cos_t);
    let rp = (eta * c - cos_t) / (eta * c + cos_t);
    0.5 * (rs * rs + rp * rp)
}

/// The dielectric lobe's Fresnel with reflectance `f0` at normal incidence and `f90` at grazing
/// angles: the exact curve of ior 1.5 moved towards 1 by `(f0 / f90 − 0.04) / 0.96`, scaled
/// by `f90` (`f0 = 0.04`, `f90 = 1` is the exact curve itself).
fn tinted_fresnel(f0: f64, f90: f64, c: f64) -> f64 {
    let f = fresnel_ior(c);
    let k = (f0 / f90 - 0.04) / 0.96;
    f90 * (f + k * (1.0 - f))
}

/// f·cos θi of a GGX lobe of α with [`tinted_fresnel`] of (f0, f90) at |wo·h|, height-correlated
/// Smith, for unit `wo`, `wi` about +z: `F D G₂ / (4 cos θo)`.
fn ggx_cos(wo: [f64; 3], wi: [f64; 3], alpha: f64, f0: f64, f90: f64) -> f64 {
    if wo[2] <= 0.0 || wi[2] <= 0.0 {
        return 0.0;
    }
    let h = [wo[0] + wi[0], wo[1] + wi[1], wo[2] + wi[2]];
    let l = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
    let h = [h[0] / l, h[1] / l, h[2] / l];
    let oh = (wo[0] * h[0] + wo[1] * h[1] + wo[2] * h[2]).abs();
    let f = tinted_fresnel(f0, f90, oh);
    let g2 = 1.0 / (1.0 + lambda(wo[2], alpha) + lambda(wi[2], alpha));
    f * ggx_d(h[2], alpha) * g2 / (4.0 * wo[2])
}

/// ∫ value(wi) dωi for a view at `theta` from +z (in the xz plane): a deterministic quadrature
/// by the one-sample mixture of warps of an `n × n` midpoint grid, one per GGX α in `alphas`
/// (the half vector distributed as D(h) cos θh, reflected) and the cosine, each point weighted
/// by the mixture density, all computed here. `value` is given the view and the direction.
fn integrate(
    theta: f64,
    alphas: &[f64],
    n: usize,
    value: impl Fn([f64; 3], [f64; 3]) -> [f64; 3],
) -> [f64; 3] {
    let wo = [theta.sin(), 0.0, theta.cos()];
    let k = (alphas.len() + 1) as f64;
    let density = |wi: [f64; 3]| {
        let h = [wo[0] + wi[0], wo[1] + wi[1], wo[2] + wi[2]];
        let l = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
        let h = [h[0] / l, h[1] / l, h[2] / l];
        let oh = wo[0] * h[0] + wo[1] * h[1] + wo[2] * h[2];
        let lobes: f64 = alphas
            .iter()
            .map(|&a| ggx_d(h[2], a) * h[2] / (4.0 * oh))
            .sum();
        (lobes + wi[2] / PI) / k
    };
    let mut sum = [0.0f64; 3];
    let mut add = |wi: [f64; 3]| {
        let v = value(wo, wi);
        let p = density(wi);
        for c in 0..3 {
            sum[c] += v[c] / p / k;
        }
    };
    for i in 0..n {
        let u1 = (i as f64 + 0.5) / n as f64;
        for j in 0..n {
            let phi = (j as f64 + 0.5) / n as f64 * 2.0 * PI;
            for &alpha in alphas {
                // tan²θh = α² u / (1 − u) has the density D(h) cos θh.
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
                    add(wi);
                }
            }
            let (s, c) = (u1.sqrt(), (1.0 - u1).sqrt());
            add([s * phi.cos(), s * phi.sin(), c]);
        }
    }
    sum.map(|s| s / (n * n) as f64)
}

/// The directional albedo of `m` (per channel) for a view at `theta`, by [`integrate`] of its
/// `eval`, the warps those of the GGX α in `alphas`.
fn albedo(m: &Material, theta: f64, alphas: &[f64]) -> [f64; 3] {
    let d = Vec3::new(-theta.sin() as f32, 0.0, -theta.cos() as f32);
    let bsdf = m.bsdf_at(d, Vec3::Z, Vec2::ZERO);
    integrate(theta, alphas, 160, |_, wi| {
        let w = Vec3::new(wi[0] as f32, wi[1] as f32, wi[2] as f32).normalize();
        let v = bsdf.eval(w).expect("evaluable").0;
        [v.x, v.y, v.z].map(f64::from)
    })
}

/// α of a perceptual roughness, as glTF defines it (roughness², at least 0.01²).
fn alpha(roughness: f64) -> f64 {
    roughness.max(0.01).powi(2)
}

const ANGLES: [f64; 5] = [0.0, 30.0, 60.0, 75.0, 85.0];
const ROUGHNESSES: [f64; 4] = [0.1, 0.3, 0.6, 1.0];

#[test]
fn the_specular_lobe_reflects_its_strength_and_colour_over_a_black_base() {
    // A black base leaves the dielectric specular lobe alone: its albedo per channel is that of
    // GGX with F0 = strength · min(0.04 · colour, 1) and F90 = strength (the exact curve of
    // ior 1.5 moved to those end points), written out here.
    let (weight, color) = (0.6f64, [3.0f64, 1.0, 0.25]);
    let cases: Vec<(f64, f64)> = ANGLES
        .iter()
        .flat_map(|&a| ROUGHNESSES.iter().map(move |&r| (a, r)))
        .collect();
    let failures: Vec<String> = cases
        .par_iter()
        .filter_map(|&(deg, r)| {
            let layers = specular(weight as f32, Vec3::from(color.map(|c| c as f32)));
            let m = layered_pbr(Vec3::ZERO, 0.0, r as f32, layers);
            let got = albedo(&m, deg.to_radians(), &[alpha(r)]);
            let expected = integrate(deg.to_radians(), &[alpha(r)], 160, |wo, wi| {
                color.map(|c| ggx_cos(wo, wi, alpha(r), weight * (0.04 * c).min(1.0), weight))
            });
            let off = (0..3).any(|c| (got[c] - expected[c]).abs() > 2e-3 + 0.01 * expected[c]);
            off.then(|| format!("{deg}° roughness {r}: {got:.4?} vs {expected:.4?}"))
        })
        .collect();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn a_white_base_under_a_tinted_or_weakened_specular_lobe_reflects_everything() {
    // The base gets, channel by channel, exactly what the specular lobe leaves: 1 in all.
    let layers = [
        specular(0.5, Vec3::new(2.0, 1.0, 0.3)),
        specular(1.0, Vec3::new(12.0, 5.0, 0.0)),
        specular(0.0, Vec3::ONE),
    ];
    let mut cases = Vec::new();
    for l in layers {
        for deg in ANGLES {
            for r in ROUGHNESSES {
                cases.push((l, deg, r));
            }
        }
    }
    let results: Vec<(String, [f64; 3])> = cases
        .par_iter()
        .map(|&(l, deg, r)| {
            let m = layered_pbr(Vec3::ONE, 0.0, r as f32, l);
            let a = albedo(&m, deg.to_radians(), &[alpha(r)]);
            (
                format!(
                    "specular {} {:?} {deg}° roughness {r}",
                    l.specular, l.specular_color
                ),
                a,
            )
        })
        .collect();
    let worst = results
        .iter()
        .flat_map(|(_, a)| a.iter())
        .fold(0.0f64, |w, &x| w.max((x - 1.0).abs()));
    println!("white base under the specular lobe: worst |albedo − 1| {worst:.4}");
    let failures: Vec<_> = results
        .iter()
        .filter(|(_, a)| a.iter().any(|x| (x - 1.0).abs() > 0.01))
        .map(|(w, a)| format!("{w}: {a:.4?}"))
        .collect();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn a_rough_coat_over_a_base_that_reflects_nothing_is_the_coat_lobe() {
    // Base black and its specular lobe off: what is reflected is the coat's GGX lobe (the
    // exact Fresnel of ior 1.5) times the coat's strength.
    let weight = 0.7f64;
    let mut cases = Vec::new();
    for deg in ANGLES {
        for r in ROUGHNESSES {
            cases.push((deg, r));
        }
    }
    let failures: Vec<String> = cases
        .par_iter()
        .filter_map(|&(deg, r)| {
            let layers = Layers {
                specular: 0.0,
                ..coat(weight as f32, r as f32)
            };
            let m = layered_pbr(Vec3::ZERO, 0.0, 0.5, layers);
            let got = albedo(&m, deg.to_radians(), &[alpha(r), alpha(0.5)])[0];
            let expected = integrate(deg.to_radians(), &[alpha(r)], 160, |wo, wi| {
                [weight * ggx_cos(wo, wi, alpha(r), 0.04, 1.0); 3]
            })[0];
            ((got - expected).abs() > 1e-3 + 0.01 * expected)
                .then(|| format!("{deg}° coat roughness {r}: {got:.4} vs {expected:.4}"))
        })
        .collect();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn a_clear_coat_over_a_white_base_loses_and_adds_nothing() {
    // A clear, non-absorbing coat over a base that reflects everything returns all light: the
    // base gets exactly what the coat does not reflect. Metallic 0 and 1, coats of every
    // roughness over a base of roughness 0.5, and a grey base under a coat stays below 1.
    let mut cases = Vec::new();
    for metallic in [0.0f32, 1.0] {
        for deg in ANGLES {
            for r in ROUGHNESSES {
                cases.push((metallic, deg, r));
            }
        }
    }
    let results: Vec<(String, f64, f64)> = cases
        .par_iter()
        .map(|&(metallic, deg, r)| {
            let alphas = [alpha(r), alpha(0.5)];
            let white = layered_pbr(Vec3::ONE, metallic, 0.5, coat(1.0, r as f32));
            let grey = layered_pbr(Vec3::splat(0.5), metallic, 0.5, coat(1.0, r as f32));
            (
                format!("metallic {metallic} {deg}° coat roughness {r}"),
                albedo(&white, deg.to_radians(), &alphas)[0],
                albedo(&grey, deg.to_radians(), &alphas)[0],
            )
        })
        .collect();
    let worst = results.iter().fold(0.0f64, |w, x| w.max((x.1 - 1.0).abs()));
    println!("white base under a clear coat: worst |albedo − 1| {worst:.4}");
    for (what, white, grey) in &results {
        assert!((white - 1.0).abs() <= 0.01, "{what}: white {white:.4}");
        assert!(*grey < 1.0 && *grey > 0.2, "{what}: grey {grey:.4}");
    }
}

#[test]
fn a_smooth_coat_reflects_the_exact_fresnel_and_passes_the_rest_to_the_base() {
    // Coat roughness 0 (glTF's default) is a mirror of the Fresnel reflectance of ior 1.5. Over a base
    // reflecting nothing the mean sampled weight is strength · F; over a white base, 1.
    let mut rng = Rng::new(21, 5);
    for deg in [0.0f32, 45.0, 80.0] {
        let theta = deg.to_radians();
        let d = Vec3::new(-theta.sin(), 0.0, -theta.cos());
        let fresnel = fresnel_ior(f64::from(theta.cos()));
        let dark = Layers {
            specular: 0.0,
            ..coat(0.8, 0.0)
        };
        for (m, expected) in [
            (layered_pbr(Vec3::ZERO, 0.0, 0.5, dark), 0.8 * fresnel),
            (layered_pbr(Vec3::ONE, 0.0, 0.5, coat(0.8, 0.0)), 1.0),
        ] {
            let count = 200_000;
            let mut sum = 0.0f64;
            for _ in 0..count {
                if let Some(s) = m.scatter(d, Vec3::Z, Vec2::ZERO, &mut rng) {
                    sum += f64::from(s.attenuation.x);
                }
            }
            let mean = sum / f64::from(count);
            assert!(
                (mean - expected).abs() < 0.01 * expected.max(0.1),
                "{deg}°: {mean:.4} vs {expected:.4}"
            );
        }
    }
}

#[test]
fn sampled_directions_of_the_layers_follow_the_density() {
    for (what, m, deg) in [
        (
            "coat 0.3 over dielectric 0.6",
            layered_pbr(Vec3::new(0.8, 0.5, 0.2), 0.0, 0.6, coat(1.0, 0.3)),
            40.0f32,
        ),
        (
            "coat 0.6 over metal 0.2",
            layered_pbr(Vec3::new(0.9, 0.6, 0.3), 1.0, 0.2, coat(0.5, 0.6)),
            70.0,
        ),
        (
            "coat 0.2 over mix 1",
            layered_pbr(Vec3::new(0.3, 0.8, 0.5), 0.5, 1.0, coat(0.8, 0.2)),
            80.0,
        ),
        (
            "tinted specular 0.4",
            layered_pbr(
                Vec3::new(0.2, 0.3, 0.9),
                0.0,
                0.4,
                specular(0.7, Vec3::new(3.0, 1.0, 0.2)),
            ),
            60.0,
        ),
    ] {
        let theta = deg.to_radians();
        let d = Vec3::new(theta.sin(), 0.0, -theta.cos());
        let (chi2, limit) = chi_square_of_directions(&m, d, 300_000, 17);
        assert!(
            chi2 < limit,
            "{what} {deg}°: χ² {chi2:.1} (limit {limit:.1})"
        );
    }
}

#[test]
fn white_coated_balls_are_one_in_a_white_furnace() {
    // The ball's mean is Σ (v − b) / Σ (1 − b), b a black ball's pixels (the background's share);
    // a coat over a white base must neither take nor add light.
    let dir = temp_dir("pbr-layers-furnace");
    write_white_map(&dir);
    let spp = 16;
    let background = furnace_pixels(&dir, "Diffuse(albedo: Constant((0, 0, 0)))", spp);
    let mut failures = Vec::new();
    for (metallic, roughness, coat_roughness) in [
        ("0", "0.5", "0"),
        ("0", "0.3", "0.3"),
        ("1", "0.6", "0.1"),
        ("0", "1", "1"),
    ] {
        let material = format!(
            "Pbr(base_color: Constant((1, 1, 1)), metallic: {metallic}, roughness: {roughness}, \
             clearcoat: 1, clearcoat_roughness: {coat_roughness}, specular: 0.5, \
             specular_color: (1.5, 1, 0.5))"
        );
        let v = furnace_pixels(&dir, &material, spp);
        let (mut sum, mut cover) = (0.0, 0.0);
        for (v, b) in v.iter().zip(&background) {
            sum += v - b;
            cover += 1.0 - b;
        }
        let mean = sum / cover;
        println!(
            "coated Pbr metallic {metallic}, roughness {roughness}, coat {coat_roughness}: ball {mean:.4}"
        );
        if (mean - 1.0).abs() > 0.01 {
            failures.push(format!("{material}: {mean:.4}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A one-triangle glTF file of material `material`, declaring `used` in `extensionsUsed` and
/// `required` in `extensionsRequired`.
fn triangle_file(material: Value, used: &[&str], required: &[&str]) -> Value {
    let mut bin = Bin::default();
    let v = bin.f32s(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    doc(
        &bin,
        json!({
            "extensionsUsed": used,
            "extensionsRequired": required,
            "accessors": [{"bufferView": v, "componentType": 5126, "count": 3, "type": "VEC3",
                           "min": [0, 0, 0], "max": [1, 1, 0]}],
            "materials": [material],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
            "nodes": [{"name": "t", "mesh": 0}],
            "scenes": [{"nodes": [0]}],
        }),
    )
}

/// Loads a scene placing glTF `file`; the loaded scene or the error's text.
fn load(dir: &Path, file: &Value) -> Result<rondo::scene::load::LoadedScene, String> {
    std::fs::write(dir.join("m.gltf"), file.to_string()).expect("write");
    let scene = write_scene(
        dir,
        "s.ron",
        "Scene(camera: Camera(position: (0, 0, 2), look_at: (0, 0, 0), fov: 40), \
         entities: [Entity(name: \"m\", gltf: \"m.gltf\")])",
    );
    load_scene(&scene, &mut AssetCache::default()).map_err(|e| e.to_string())
}

#[test]
fn gltf_specular_sheen_and_clearcoat_load_to_the_material_and_only_the_coat_normal_warns() {
    let dir = temp_dir("pbr-layers-gltf");
    let material = json!({
        "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1], "metallicFactor": 0},
        "extensions": {
            "KHR_materials_specular": {"specularFactor": 0.25, "specularColorFactor": [2, 1, 0.5]},
            "KHR_materials_clearcoat": {"clearcoatFactor": 0.75, "clearcoatRoughnessFactor": 0.125,
                                        "clearcoatNormalTexture": {"index": 0}},
            "KHR_materials_sheen": {"sheenColorFactor": [1, 0.5, 0.25], "sheenRoughnessFactor": 0.375},
        },
    });
    let exts = [
        "KHR_materials_specular",
        "KHR_materials_clearcoat",
        "KHR_materials_sheen",
    ];
    let scene = load(&dir, &triangle_file(material.clone(), &exts, &exts))
        .unwrap_or_else(|e| panic!("{e}"));
    let m = &scene.materials[&scene.entities[0].material];
    let Material::Pbr { layers, .. } = m else {
        panic!("{m:?}")
    };
    assert_eq!(
        *layers,
        Layers {
            specular: 0.25,
            specular_color: Vec3::new(2.0, 1.0, 0.5),
            sheen_color: Vec3::new(1.0, 0.5, 0.25),
            sheen_roughness: 0.375,
            clearcoat: 0.75,
            clearcoat_roughness: 0.125,
        }
    );
    let w = &scene.warnings;
    assert!(
        !w.iter()
            .any(|w| w.contains("extension KHR_materials_specular")
                || w.contains("extension KHR_materials_sheen")
                || w.contains("extension KHR_materials_clearcoat")),
        "{w:?}"
    );
    assert!(
        w.iter()
            .any(|w| w.contains("clearcoatNormalTexture is ignored") && w.contains("normal")),
        "{w:?}"
    );

    // Without the extensions, the defaults: the plain material.
    let plain = json!({"pbrMetallicRoughness": {"metallicFactor": 0}});
    let scene = load(&dir, &triangle_file(plain, &[], &[])).unwrap_or_else(|e| panic!("{e}"));
    let m = &scene.materials[&scene.entities[0].material];
    assert!(matches!(m, Material::Pbr { layers, .. } if *layers == Layers::NONE));

    // Out of range or of the wrong type: an error naming the field.
    for (ext, bad, field) in [
        (
            "KHR_materials_clearcoat",
            json!({"clearcoatFactor": 1.5}),
            "clearcoatFactor",
        ),
        (
            "KHR_materials_clearcoat",
            json!({"clearcoatRoughnessFactor": "rough"}),
            "clearcoatRoughnessFactor",
        ),
        (
            "KHR_materials_specular",
            json!({"specularColorFactor": [1, -1, 1]}),
            "specularColorFactor[1]",
        ),
        (
            "KHR_materials_specular",
            json!({"specularColorFactor": [1, 1]}),
            "specularColorFactor",
        ),
        (
            "KHR_materials_sheen",
            json!({"sheenColorFactor": [1, 1.5, 0]}),
            "sheenColorFactor[1]",
        ),
        (
            "KHR_materials_sheen",
            json!({"sheenRoughnessFactor": -0.5}),
            "sheenRoughnessFactor",
        ),
        (
            "KHR_materials_sheen",
            json!({"sheenColorTexture": {"index": 0}}),
            "sheenColorTexture.index",
        ),
        (
            "KHR_materials_clearcoat",
            json!({"clearcoatTexture": {"index": "0"}}),
            "clearcoatTexture.index",
        ),
        (
            "KHR_materials_specular",
            json!({"specularTexture": 2}),
            "specularTexture",
        ),
    ] {
        let mut m = json!({"pbrMetallicRoughness": {}});
        m["extensions"] = json!({ ext: bad });
        let e = load(&dir, &triangle_file(m, &[ext], &[])).expect_err("refused");
        assert!(e.contains(&format!("extensions.{ext}.{field}")), "{e}");
    }
}
