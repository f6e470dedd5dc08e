//! The glTF metallic–roughness material (`Pbr`) against independent truth: white furnaces (an
//! environment of radiance 1 around a sphere, seen through a vanishing-fov camera so that every
//! pixel is an independent estimate of one point's radiance; a smooth `Glossy` beside the
//! smooth `Pbr` there), the closed-form light of an emissive `Pbr` sphere on a plane, emission
//! added to reflection, and a RON error.

mod common;

use std::path::{Path, PathBuf};

use common::{
    assert_methods_agree, point_camera, point_estimate, render, temp_dir, with, within, write_scene,
};
use rondo::scene::assets::AssetCache;
use rondo::scene::format::Method;
use rondo::scene::load::load_scene;

/// Writes a 16 × 8 OpenEXR map of constant grey radiance 1.
fn write_white_map(dir: &Path) -> PathBuf {
    let image = image::Rgb32FImage::from_raw(16, 8, vec![1.0; 16 * 8 * 3]).expect("buffer size");
    let path = dir.join("one.exr");
    image.save(&path).expect("write map");
    path
}

/// A unit sphere of `material` in the white environment, seen almost head-on (θo ≈ 8°).
fn furnace(dir: &Path, material: &str) -> PathBuf {
    write_scene(
        dir,
        "furnace.ron",
        &format!(
            "Scene(camera: {}, settings: Settings(width: 32, height: 32, max_depth: 16, \
             environment: Environment(path: \"one.exr\")), materials: {{ \"m\": {material} }}, \
             entities: [Entity(material: \"m\", shape: Sphere(center: (0, 0, 0), radius: 1))])",
            point_camera("(0.6, 0.3, -4)", "(0, 0, 0)", "(0, 1, 0)")
        ),
    )
}

#[test]
fn smooth_white_mirrors_are_exactly_one_in_a_white_furnace_under_every_method() {
    // A white roughness-0 conductor (`Pbr`, F0 = 1) and a white roughness-0 `Glossy` (Schlick
    // F0 = 1): F = 1 at every angle, and the sphere is convex, so every pixel sees one
    // reflection of radiance 1 into the environment. A lobe this smooth is a perfect mirror, so
    // next-event estimation leaves it to BSDF sampling like a `Metal` of roughness 0.
    let dir = temp_dir("pbr-mirror");
    write_white_map(&dir);
    for material in [
        "Pbr(base_color: Constant((1, 1, 1)), metallic: 1, roughness: 0)",
        "Glossy(albedo: Constant((1, 1, 1)), roughness: 0)",
    ] {
        let scene = furnace(&dir, material);
        for method in [Method::Naive, Method::Nee, Method::Mis] {
            let r = render(&scene, with(method, 16), None);
            let (mean, se) = point_estimate(&r);
            let worst = r
                .film()
                .mean()
                .iter()
                .map(|p| (p.x - 1.0).abs())
                .fold(0.0f32, f32::max);
            assert!(
                worst < 1e-5,
                "{material} {method}: mean {mean} ± {se}, a pixel {worst} away from 1"
            );
        }
    }
}

#[test]
fn a_smooth_dielectric_pbr_mixes_its_mirror_and_diffuse_lobes_alike_under_every_method() {
    // Roughness 0, metallic 0: a perfect mirror of the Fresnel of ior 1.5 over a Lambertian base.
    // Next-event estimation and MIS evaluate the diffuse lobe alone, with the density of
    // sampling it, and leave the mirror to BSDF sampling: all three methods must agree.
    let dir = temp_dir("pbr-smooth-plastic");
    write_white_map(&dir);
    let material = "Pbr(base_color: Constant((0.8, 0.8, 0.8)), metallic: 0, roughness: 0)";
    let scene = furnace(&dir, material);
    let mut estimates = Vec::new();
    for method in [Method::Naive, Method::Nee, Method::Mis] {
        let r = render(&scene, with(method, 64), None);
        assert_eq!(r.stats().nonfinite, 0);
        let (mean, se) = point_estimate(&r);
        // At least the mirror's F ≥ 0.04 of the white environment, at most 1 (θo is small).
        assert!(
            mean > 0.04 && mean <= 1.0 + 3.0 * se,
            "{method}: {mean} ± {se}"
        );
        estimates.push((method, mean, se));
    }
    assert_methods_agree(material, &estimates);
}

#[test]
fn rough_conductors_and_dielectrics_never_gain_energy_and_the_methods_agree() {
    let dir = temp_dir("pbr-furnace");
    write_white_map(&dir);
    for material in [
        "Pbr(base_color: Constant((1, 1, 1)), metallic: 1, roughness: 0.3)",
        "Pbr(base_color: Constant((1, 1, 1)), metallic: 1, roughness: 1)",
        "Pbr(base_color: Constant((1, 1, 1)), metallic: 0, roughness: 0.5)",
        "Pbr(base_color: Constant((1, 1, 1)), metallic: 0, roughness: 1)",
        "Pbr(base_color: Constant((1, 1, 1)), metallic: 0.5, roughness: 0.7)",
    ] {
        let scene = furnace(&dir, material);
        let mut estimates = Vec::new();
        for method in [Method::Naive, Method::Nee, Method::Mis] {
            let (mean, se) = point_estimate(&render(&scene, with(method, 64), None));
            assert!(
                mean <= 1.0 + 3.0 * se,
                "{material} {method}: {mean} ± {se} gains"
            );
            estimates.push((method, mean, se));
        }
        assert_methods_agree(material, &estimates);
    }
}

#[test]
fn an_emissive_pbr_adds_its_emission_to_what_it_reflects() {
    // A white mirror-like conductor emitting 0.5 in the white furnace: 1 reflected + 0.5.
    let dir = temp_dir("pbr-emit-reflect");
    write_white_map(&dir);
    let scene = furnace(
        &dir,
        "Pbr(base_color: Constant((1, 1, 1)), metallic: 1, roughness: 0, \
         emissive: Constant((1, 1, 1)), emissive_strength: 0.5)",
    );
    for method in [Method::Naive, Method::Nee, Method::Mis] {
        let r = render(&scene, with(method, 16), None);
        let (mean, se) = point_estimate(&r);
        assert!(within(mean, se, 1.5, 3.5), "{method}: {mean} ± {se}");
        if method == Method::Naive {
            for p in r.film().mean() {
                assert!((p.x - 1.5).abs() < 1e-5, "naive pixel {}", p.x);
            }
        }
    }
}

#[test]
fn an_emissive_pbr_sphere_lights_a_plane_as_the_closed_form_says_and_is_light_sampled() {
    // A sphere of radius r = 0.5 and radiance L = 4 centred d = 2 above a diffuse plane of
    // albedo ρ = 0.5: the irradiance under its centre is π L r²/d², the plane's radiance
    // ρ L r²/d² = 0.125. max_depth 2 counts only light that reached the plane from the sphere.
    let dir = temp_dir("pbr-emit-plane");
    let scene = write_scene(
        &dir,
        "lamp.ron",
        &format!(
            "Scene(camera: {}, settings: Settings(width: 32, height: 32, max_depth: 2), \
             materials: {{ \"lamp\": Pbr(base_color: Constant((0.2, 0.2, 0.2)), metallic: 0, \
             emissive: Constant((1, 1, 1)), emissive_strength: 4), \
             \"ground\": Diffuse(albedo: Constant((0.5, 0.5, 0.5))) }}, \
             entities: [Entity(material: \"lamp\", shape: Sphere(center: (0, 2, 0), radius: 0.5)), \
             Entity(material: \"ground\", shape: Plane(point: (0, 0, 0), normal: (0, 1, 0)))])",
            point_camera("(3, 1, 0)", "(0, 0, 0)", "(0, 1, 0)")
        ),
    );
    let expected = 0.5 * 4.0 * 0.25 / 4.0;
    let mut estimates = Vec::new();
    for method in [Method::Naive, Method::Nee, Method::Mis] {
        let (mean, se) = point_estimate(&render(&scene, with(method, 256), None));
        assert!(
            within(mean, se, expected, 3.5),
            "{method}: {mean} ± {se}, expected {expected}"
        );
        estimates.push((method, mean, se));
    }
    assert_methods_agree("lamp", &estimates);
    // Light sampling finds the sphere: next-event estimation is far less noisy than BSDF
    // sampling, which hits a sphere of 6% of the hemisphere's projected solid angle.
    let (naive_se, nee_se) = (estimates[0].2, estimates[1].2);
    assert!(
        nee_se < 0.3 * naive_se,
        "nee ± {nee_se}, naive ± {naive_se}"
    );
}

#[test]
fn metallic_outside_zero_to_one_is_an_error_at_its_place() {
    let dir = temp_dir("pbr-error");
    let source = "Scene(\n    camera: Camera(position: (0, 1, -5), look_at: (0, 1, 0)),\n    \
                  settings: Settings(width: 8, height: 8, spp: 1),\n    \
                  materials: { \"gold\": Pbr(metallic: 1.5) },\n    entities: [],\n)";
    let path = write_scene(&dir, "scene.ron", source);
    let text = match load_scene(&path, &mut AssetCache::default()) {
        Ok(_) => panic!("metallic 1.5 loaded"),
        Err(e) => e.to_string(),
    };
    let (_, rest) = text.split_once("scene.ron:").expect("file named");
    let mut parts = rest.splitn(3, ':');
    let line: usize = parts.next().and_then(|n| n.parse().ok()).expect("line");
    let col: usize = parts.next().and_then(|n| n.parse().ok()).expect("column");
    let message = parts.next().expect("message");
    assert_eq!(line, 4, "{text}");
    assert!(col > 20, "{text}");
    for word in ["gold", "metallic", "between 0 and 1", "1.5"] {
        assert!(message.contains(word), "{word} missing: {text}");
    }
}
