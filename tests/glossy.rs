//! The Glossy (GGX) material: its sampling density integrates to one, `eval` and `scatter`
//! agree, white reflects everything (multiple scattering included), sampled directions follow
//! the density (χ²), the scene format reads it, and every light-transport method gives it the
//! same radiance.

mod common;

use common::chi2::{cell, chi_square_of_directions};
use common::{point_estimate, temp_dir, write_scene};
use glam::{Vec2, Vec3};
use rondo::scene::format::Method;
use rondo::shading::material::Material;
use rondo::shading::rng::Rng;
use rondo::shading::texture::Texture;
use rondo::{Overrides, PassPlan, Renderer};

fn glossy(albedo: f32, roughness: f32) -> Material {
    Material::Glossy {
        albedo: Texture::Constant(Vec3::splat(albedo)),
        roughness,
    }
}

/// An incoming ray direction making angle `theta` (radians) with the normal +z.
fn incoming(theta: f64) -> Vec3 {
    Vec3::new(theta.sin() as f32, 0.0, -(theta.cos() as f32))
}

/// ∫ over the hemisphere of `eval`'s (f·cos, pdf), by the midpoint rule on an n × m grid.
fn integrate(m: &Material, d: Vec3, n: usize, k: usize) -> (f64, f64) {
    let (mut f, mut p) = (0.0, 0.0);
    for i in 0..n {
        for j in 0..k {
            let (wi, dw) = cell(i, j, n, k);
            let (f_cos, pdf) = m
                .bsdf_at(d, Vec3::Z, Vec2::ZERO)
                .eval(wi)
                .expect("evaluable");
            f += f64::from(f_cos.x) * dw;
            p += f64::from(pdf) * dw;
        }
    }
    (f, p)
}

/// Mean attenuation of `count` sampled scatters (absorbed = 0), and the fraction absorbed.
fn sampled_albedo(m: &Material, d: Vec3, count: usize, seed: u64) -> (f64, f64) {
    let mut rng = Rng::new(seed, 1);
    let (mut sum, mut absorbed) = (0.0, 0usize);
    for _ in 0..count {
        match m.scatter(d, Vec3::Z, Vec2::ZERO, &mut rng) {
            Some(s) => sum += f64::from(s.attenuation.x),
            None => absorbed += 1,
        }
    }
    (sum / count as f64, absorbed as f64 / count as f64)
}

#[test]
fn sampling_density_integrates_to_one_minus_what_is_absorbed() {
    // VNDF sampling reflects some directions below the surface (they are absorbed); the
    // density over the upper hemisphere must integrate to exactly the rest.
    for (roughness, theta) in [(0.4f32, 0.0f64), (0.6, 0.5), (0.8, 1.0), (1.0, 1.3)] {
        let m = glossy(1.0, roughness);
        let d = incoming(theta);
        let (_, pdf_integral) = integrate(&m, d, 800, 400);
        let (_, absorbed) = sampled_albedo(&m, d, 400_000, 3);
        assert!(
            (pdf_integral + absorbed - 1.0).abs() < 0.01,
            "roughness {roughness}, θ {theta}: ∫pdf {pdf_integral} + absorbed {absorbed}"
        );
    }
}

#[test]
fn eval_and_scatter_agree_on_density_and_weight() {
    let mut rng = Rng::new(17, 4);
    for roughness in [0.0317f32, 0.05, 0.2, 0.5, 1.0] {
        let m = Material::Glossy {
            albedo: Texture::Constant(Vec3::new(0.9, 0.5, 0.2)),
            roughness,
        };
        for k in 0..2000 {
            let theta = 1.5 * (k as f64 + 0.5) / 2000.0;
            let phi = 0.37 * k as f64;
            let d = Vec3::new(
                (theta.sin() * phi.cos()) as f32,
                (theta.sin() * phi.sin()) as f32,
                -(theta.cos() as f32),
            );
            // Either side of the surface: Glossy is two-sided, like every material.
            let n = if k % 2 == 0 { Vec3::Z } else { -Vec3::Z };
            let d = if k % 2 == 0 { d } else { -d };
            let Some(s) = m.scatter(d, n, Vec2::ZERO, &mut rng) else {
                continue;
            };
            let pdf = s.pdf.expect("Glossy has a density");
            let (f_cos, eval_pdf) = m
                .bsdf_at(d, n, Vec2::ZERO)
                .eval(s.direction)
                .expect("evaluable");
            let rel = (eval_pdf - pdf).abs() / pdf;
            assert!(
                rel < 2e-3,
                "roughness {roughness}, θ {theta}: eval pdf {eval_pdf}, sampled {pdf}"
            );
            let weight = f_cos / eval_pdf;
            assert!(
                (weight - s.attenuation).abs().max_element()
                    < 2e-3 * s.attenuation.max_element().max(1e-3),
                "roughness {roughness}, θ {theta}: f·cos/pdf {weight}, attenuation {}",
                s.attenuation
            );
        }
    }
}

#[test]
fn below_alpha_one_thousandth_glossy_is_a_perfect_mirror_of_schlicks_fresnel() {
    // α = roughness²: 0.0316² < 10⁻³ ≤ 0.0317². Below, the lobe is a delta (pbrt-v4's
    // "effectively smooth"): the mirror direction, weight F = F0 + (1 − F0)(1 − cos θ)⁵ written
    // out here, no density, nothing to evaluate, no light sampling; above, an evaluable lobe.
    let f0 = Vec3::new(0.9, 0.5, 0.2);
    let mut rng = Rng::new(3, 3);
    for roughness in [0.0f32, 0.01, 0.0316] {
        let m = Material::Glossy {
            albedo: Texture::Constant(f0),
            roughness,
        };
        assert!(
            !m.bsdf_at(-Vec3::Z, Vec3::Z, Vec2::ZERO).samples_lights()
                && m.bsdf_at(-Vec3::Z, Vec3::Z, Vec2::ZERO).is_specular(),
            "{roughness}"
        );
        for theta in [0.0f32, 0.5, 1.2, 1.5] {
            let d = Vec3::new(theta.sin(), 0.0, -theta.cos());
            let s = m
                .scatter(d, Vec3::Z, Vec2::ZERO, &mut rng)
                .expect("a mirror");
            let fresnel = f0 + (Vec3::ONE - f0) * (1.0 - theta.cos()).powi(5);
            assert!((s.direction - Vec3::new(d.x, d.y, -d.z)).length() < 1e-6);
            assert!(
                (s.attenuation - fresnel).abs().max_element() < 1e-6,
                "{roughness} {theta}"
            );
            assert_eq!(s.pdf, None);
            assert_eq!(m.bsdf_at(d, Vec3::Z, Vec2::ZERO).eval(s.direction), None);
        }
    }
    let rough = Material::Glossy {
        albedo: Texture::Constant(f0),
        roughness: 0.0317,
    };
    let at = rough.bsdf_at(-Vec3::Z, Vec3::Z, Vec2::ZERO);
    assert!(at.samples_lights() && !at.is_specular());
}

#[test]
fn white_furnace_reflects_everything_and_creates_nothing() {
    // Albedo 1 makes Fresnel 1, and the multiple-scattering lobe returns what masking takes
    // from single scattering: ∫ f cos dω = 1. Two independent estimates (a grid over eval, and
    // the mean of sampled weights) agree with it.
    for (roughness, theta) in [
        (0.1f32, 0.0f64),
        (0.3, 0.6),
        (0.6, 1.0),
        (1.0, 0.0),
        (1.0, 1.4),
    ] {
        let m = glossy(1.0, roughness);
        let d = incoming(theta);
        let (sampled, absorbed) = sampled_albedo(&m, d, 400_000, 9);
        assert!(
            (sampled - 1.0).abs() < 0.01,
            "roughness {roughness}, θ {theta}: {sampled} ({absorbed} absorbed)"
        );
        if roughness >= 0.3 {
            let (grid, _) = integrate(&m, d, 1000, 500);
            assert!(
                (grid - 1.0).abs() < 0.01,
                "roughness {roughness}, θ {theta}: grid {grid}, sampled {sampled}"
            );
        }
    }
}

#[test]
fn sampled_directions_pass_a_chi_square_test_against_the_density() {
    for (roughness, theta) in [(0.5f32, 0.7f64), (0.9, 0.2)] {
        let (chi2, limit) =
            chi_square_of_directions(&glossy(0.7, roughness), incoming(theta), 500_000, 5);
        assert!(
            chi2 < limit,
            "roughness {roughness}, θ {theta}: χ² {chi2:.1} (limit {limit:.1})"
        );
    }
}

#[test]
fn the_scene_format_reads_glossy_and_clamps_its_roughness() {
    let dir = temp_dir("glossy-format");
    let path = write_scene(
        &dir,
        "g.ron",
        r#"Scene(
    camera: Camera(position: (0, 0, 5), look_at: (0, 0, 0)),
    materials: {
        "a": Glossy(albedo: Constant((0.9, 0.6, 0.3)), roughness: 0.3),
        "b": Glossy(albedo: Constant((1, 1, 1)), roughness: 0),
        "c": Glossy(albedo: Constant((1, 1, 1)), roughness: 7),
    },
)"#,
    );
    let mut cache = rondo::scene::assets::AssetCache::default();
    let scene = rondo::scene::load::load_scene(&path, &mut cache).unwrap_or_else(|e| panic!("{e}"));
    let roughness = |name: &str| match scene.materials.get(name) {
        Some(Material::Glossy { roughness, .. }) => *roughness,
        other => panic!("{name}: {other:?}"),
    };
    assert_eq!(roughness("a"), 0.3);
    assert_eq!(roughness("b"), rondo::shading::microfacet::MIN_ROUGHNESS);
    assert_eq!(roughness("c"), 1.0);
    // Roughness is required: a plate without it is an error at its line.
    let bad = write_scene(
        &dir,
        "bad.ron",
        "Scene(\n    camera: Camera(position: (0, 0, 5), look_at: (0, 0, 0)),\n    materials: { \"a\": Glossy(albedo: Constant((1, 1, 1))) },\n)",
    );
    let err = rondo::scene::load::load_scene(&bad, &mut cache)
        .expect_err("missing roughness")
        .to_string();
    assert!(
        err.contains("bad.ron:3:") && err.contains("roughness"),
        "{err}"
    );
}

#[test]
fn every_method_gives_a_glossy_floor_the_same_radiance() {
    // A Glossy floor under a square lamp, seen at one point (a camera with a vanishing field of
    // view makes every pixel an independent estimate of the same radiance). NEE and MIS use
    // eval() and the density; naive uses only scatter(). All must agree.
    let dir = temp_dir("glossy-methods");
    for (k, roughness) in [0.15f32, 0.5].into_iter().enumerate() {
        let path = write_scene(
            &dir,
            &format!("g{k}.ron"),
            &format!(
                r#"Scene(
    camera: Camera(position: (-1.2, 1.0, 0), look_at: (0.1, 0, 0), fov: 0.00001),
    settings: Settings(width: 16, height: 16, max_depth: 3),
    materials: {{
        "floor": Glossy(albedo: Constant((0.9, 0.9, 0.9)), roughness: {roughness}),
        "lamp": Light(emit: Constant((1, 1, 1)), intensity: 4),
    }},
    entities: [
        Entity(name: "floor", material: "floor", shape: Quad(a: (-5, 0, -5), b: (-5, 0, 5), c: (5, 0, 5), d: (5, 0, -5))),
        Entity(name: "lamp", material: "lamp", shape: Quad(a: (0.5, 1, -0.6), b: (1.7, 1, -0.6), c: (1.7, 1, 0.6), d: (0.5, 1, 0.6))),
    ],
)"#
            ),
        );
        let estimate = |method: Method, spp: u32, seed: u64| {
            let mut r = Renderer::new(None, PassPlan::Single).expect("pool");
            r.set_overrides(Overrides {
                method: Some(method),
                spp: Some(spp),
                seed: Some(seed),
                ..Default::default()
            });
            r.load(&path).unwrap_or_else(|e| panic!("{e}"));
            r.render_to_completion();
            assert_eq!(r.stats().nonfinite, 0);
            point_estimate(&r)
        };
        let reference = estimate(Method::Mis, 256, 1);
        assert!(reference.0 > 0.05, "the lamp is reflected: {reference:?}");
        for (method, spp) in [(Method::Naive, 512), (Method::Nee, 256), (Method::Mis, 128)] {
            let (mean, se) = estimate(method, spp, 50 + spp as u64);
            let z = (mean - reference.0) / (se * se + reference.1 * reference.1).sqrt();
            assert!(
                z.abs() < 4.0,
                "roughness {roughness}, {method}: {mean} ± {se} vs MIS {} ± {} (z = {z:.2})",
                reference.0,
                reference.1
            );
        }
    }
}
