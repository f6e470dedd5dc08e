//! Glass against independent truth: the exact Fresnel share of the smooth glass, the rough
//! glass's sampled directions against its density (χ²), its reflectance and transmittance by
//! brute-force integration (never above 1, tending to Fresnel's as the roughness goes to 0), a
//! rough glass ball in a white furnace, a tinted slab against Beer–Lambert's closed form, and
//! the scene format and glTF extensions that describe it.

mod common;

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use common::chi2::chi2_test;
use common::furnace::write_white_map;
use common::gltf_doc::{Bin, doc};
use common::{point_camera, render, temp_dir, with, write_scene};
use glam::{Vec2, Vec3};
use rondo::scene::assets::AssetCache;
use rondo::scene::format::Method;
use rondo::scene::load::load_scene;
use rondo::shading::material::Material;
use rondo::shading::rng::Rng;

fn rough(ior: f32, roughness: f32) -> Material {
    Material::Dielectric {
        ior,
        roughness,
        absorption: Vec3::ZERO,
    }
}

/// Exact unpolarised Fresnel reflectance in angle form (Born & Wolf 1.5 (21a)–(21b)), light
/// from index `n_i` at angle `theta_i` into index `n_t`; 1 beyond the critical angle.
fn fresnel(theta_i: f64, n_i: f64, n_t: f64) -> f64 {
    if theta_i == 0.0 {
        return ((n_t - n_i) / (n_t + n_i)).powi(2);
    }
    let sin_t = n_i / n_t * theta_i.sin();
    if sin_t >= 1.0 {
        return 1.0;
    }
    let theta_t = sin_t.asin();
    let (minus, plus) = (theta_i - theta_t, theta_i + theta_t);
    0.5 * ((minus.sin() / plus.sin()).powi(2) + (minus.tan() / plus.tan()).powi(2))
}

/// A ray direction arriving at angle `theta` to the normal +z, from above (`outside`) or from
/// below.
fn arriving(theta: f64, outside: bool) -> Vec3 {
    let d = Vec3::new(theta.sin() as f32, 0.0, -(theta.cos() as f32));
    if outside { d } else { -d }
}

/// Direction of cell-centre `(i, j)` of an `n × m` grid over the whole sphere (cos θ ∈ [−1, 1],
/// φ ∈ [0, 2π)), and the cell's solid angle.
fn cell(i: usize, j: usize, n: usize, m: usize) -> (Vec3, f64) {
    let c = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
    let phi = (j as f64 + 0.5) / m as f64 * 2.0 * PI;
    let s = (1.0 - c * c).max(0.0).sqrt();
    let w = Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, c as f32);
    (w, 4.0 * PI / (n * m) as f64)
}

#[test]
fn smooth_glass_reflects_the_exact_fresnel_share_at_oblique_incidence() {
    // At 60° from air into n = 1.5 the Fresnel equations give R = 0.0892, Schlick's curve 0.0700;
    // from inside at 35° (below the 41.8° critical angle) 0.0566 against 0.0413.
    let glass = Material::glass(1.5);
    for (theta, outside) in [(60f64.to_radians(), true), (35f64.to_radians(), false)] {
        let d = arriving(theta, outside);
        let expected = if outside {
            fresnel(theta, 1.0, 1.5)
        } else {
            fresnel(theta, 1.5, 1.0)
        };
        let mut rng = Rng::new(3, 1);
        let n = 1_000_000;
        let reflected = (0..n)
            .filter(|_| {
                let s = glass
                    .scatter(d, Vec3::Z, Vec2::ZERO, &mut rng)
                    .expect("glass scatters");
                s.direction.z * d.z < 0.0
            })
            .count();
        let share = reflected as f64 / n as f64;
        let se = (expected * (1.0 - expected) / n as f64).sqrt();
        assert!(
            (share - expected).abs() < 5.0 * se,
            "θ {theta}, outside {outside}: reflected {share}, Fresnel {expected} ± {se}"
        );
    }
}

#[test]
fn rough_glass_samples_directions_by_its_density() {
    // Expected probability of each (cos θ, φ) bin over the whole sphere: the evaluated density
    // integrated over the bin on a sub-grid; one more bin for samples that end the path. The
    // density drops to 0 along a curve where the half vector leaves the visible hemisphere, so
    // the sub-grid is fine enough to place that edge within a bin.
    let (nc, nphi, sub, count) = (24usize, 24usize, 96usize, 600_000usize);
    for (roughness, theta, outside) in [
        (0.5f32, 0.6f64, true),
        (0.8, 1.2, true),
        (0.6, 0.3, false),
        (0.7, 0.9, false),
    ] {
        let glass = rough(1.5, roughness);
        let d = arriving(theta, outside);
        let bsdf = glass.bsdf_at(d, Vec3::Z, Vec2::ZERO);
        let mut expected = vec![0.0f64; nc * nphi + 1];
        for i in 0..nc * sub {
            for j in 0..nphi * sub {
                let (wi, dw) = cell(i, j, nc * sub, nphi * sub);
                let (_, pdf) = bsdf.eval(wi).expect("rough glass is evaluable");
                expected[(i / sub) * nphi + j / sub] += f64::from(pdf) * dw;
            }
        }
        let total: f64 = expected.iter().sum();
        assert!(
            total <= 1.0 + 5e-3,
            "roughness {roughness}, θ {theta}: ∫pdf {total}"
        );
        expected[nc * nphi] = (1.0 - total).max(0.0);
        let mut observed = vec![0usize; nc * nphi + 1];
        let mut rng = Rng::new(7, 2);
        for _ in 0..count {
            let bin = match glass.scatter(d, Vec3::Z, Vec2::ZERO, &mut rng) {
                None => nc * nphi,
                Some(s) => {
                    let w = s.direction;
                    let c = (f64::from(w.z) + 1.0) / 2.0;
                    let i = (c * nc as f64).clamp(0.0, nc as f64 - 1.0) as usize;
                    let phi = f64::from(w.y.atan2(w.x)).rem_euclid(2.0 * PI);
                    let j = (phi / (2.0 * PI) * nphi as f64).min(nphi as f64 - 1.0) as usize;
                    i * nphi + j
                }
            };
            observed[bin] += 1;
        }
        if let Err(e) = chi2_test(&expected, &observed, count) {
            panic!("roughness {roughness}, θ {theta}, outside {outside}: {e}");
        }
    }
}

/// Reflectance and transmittance (as flux: the radiance scale of refraction taken out) of the
/// rough interface for a ray along `d`, by the midpoint rule over an `n × m` grid in (θ, φ)
/// (fine at the poles, where the lobes of normal incidence peak).
fn integrated(glass: &Material, d: Vec3, n: usize, m: usize, eta2: f64) -> (f64, f64) {
    let bsdf = glass.bsdf_at(d, Vec3::Z, Vec2::ZERO);
    let (mut r, mut t) = (0.0, 0.0);
    for i in 0..n {
        let theta = (i as f64 + 0.5) / n as f64 * PI;
        let dw = theta.sin() * (PI / n as f64) * (2.0 * PI / m as f64);
        for j in 0..m {
            let phi = (j as f64 + 0.5) / m as f64 * 2.0 * PI;
            let wi = Vec3::new(
                (theta.sin() * phi.cos()) as f32,
                (theta.sin() * phi.sin()) as f32,
                theta.cos() as f32,
            );
            let (f_cos, _) = bsdf.eval(wi).expect("evaluable");
            if wi.z * d.z < 0.0 {
                r += f64::from(f_cos.x) * dw;
            } else {
                t += f64::from(f_cos.x) * dw * eta2;
            }
        }
    }
    (r, t)
}

/// The same by the mean of `count` sampled weights, split by where they went.
fn sampled(glass: &Material, d: Vec3, count: usize, eta2: f64) -> (f64, f64) {
    let mut rng = Rng::new(11, 3);
    let (mut r, mut t) = (0.0, 0.0);
    for _ in 0..count {
        if let Some(s) = glass.scatter(d, Vec3::Z, Vec2::ZERO, &mut rng) {
            if s.direction.z * d.z < 0.0 {
                r += f64::from(s.attenuation.x);
            } else {
                t += f64::from(s.attenuation.x) * eta2;
            }
        }
    }
    (r / count as f64, t / count as f64)
}

#[test]
fn a_rough_interface_passes_on_all_that_arrives_and_tends_to_fresnel() {
    // The flux through the interface is the transmitted radiance times (n_t/n_i)² (radiance is
    // compressed by (n_i/n_t)² crossing it), so R + T·(n_t/n_i)² is what leaves of what
    // arrives: 1, the single-scattering lobe's loss (light masked by the microfacets) put back
    // by the compensation. As the roughness goes to 0, R and T go to the smooth interface's
    // Fresnel F and 1 − F.
    for (theta, outside) in [(0.0f64, true), (0.8, true), (0.4, false), (1.2, true)] {
        let (n_i, n_t) = if outside { (1.0, 1.5) } else { (1.5, 1.0) };
        let eta2 = (n_t / n_i) * (n_t / n_i);
        let d = arriving(theta, outside);
        for roughness in [0.4f32, 0.7, 1.0] {
            let glass = rough(1.5, roughness);
            let (r, t) = integrated(&glass, d, 2000, 1000, eta2);
            let (rs, ts) = sampled(&glass, d, 400_000, eta2);
            // With the energy compensation nothing is lost or gained at the interface, up
            // to the table's interpolation error.
            assert!(
                (r + t - 1.0).abs() < 0.01,
                "θ {theta} roughness {roughness}: R {r} + T {t}"
            );
            assert!(
                (r - rs).abs() < 0.01 && (t - ts).abs() < 0.01,
                "θ {theta} roughness {roughness}: grid {r} {t}, sampled {rs} {ts}"
            );
        }
        let f = fresnel(theta, n_i, n_t);
        let mut last = f64::INFINITY;
        for roughness in [0.3f32, 0.15, 0.06] {
            let glass = rough(1.5, roughness);
            let (r, t) = sampled(&glass, d, 400_000, eta2);
            let gap = (r - f).abs() + (t - (1.0 - f)).abs();
            assert!(
                gap < last + 2e-3,
                "θ {theta}: the gap to Fresnel grows at roughness {roughness}: {gap}"
            );
            last = gap;
        }
        assert!(
            last < 0.01,
            "θ {theta}: roughness 0.06 is {last} from Fresnel"
        );
    }
}

#[test]
fn a_rough_glass_ball_in_a_white_furnace_keeps_all_the_light_at_every_roughness() {
    // A unit ball at distance 4 fills a 29° view; pixels whose centre ray meets it at under 0.97
    // of its radius are averaged. Everything a path can reach is the environment of radiance
    // 1, so a lossless ball is exactly 1. Single scattering alone lost the light that
    // microfacets would scatter more than once, at every crossing and every internal
    // reflection (0.954 at roughness 0.3, 0.79 at 0.5, 0.34 at 1); the energy compensation
    // puts it back, to the table's interpolation error.
    let dir = temp_dir("rough-glass-furnace");
    write_white_map(&dir);
    let (size, fov) = (40usize, 29.0f64);
    let half = (fov.to_radians() / 2.0).tan();
    for roughness in [0.0f32, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0] {
        let scene = write_scene(
            &dir,
            "furnace.ron",
            &format!(
                "Scene(camera: Camera(position: (0, 0, -4), look_at: (0, 0, 0), fov: {fov}), \
                 settings: Settings(width: {size}, height: {size}, max_depth: 64, \
                 environment: Environment(path: \"one.exr\")), \
                 materials: {{ \"m\": Dielectric(ior: 1.5, roughness: {roughness}) }}, \
                 entities: [Entity(material: \"m\", shape: Sphere(center: (0, 0, 0), radius: 1))])"
            ),
        );
        let r = render(&scene, with(Method::Mis, 64), None);
        let mean = r.film().mean();
        let (mut sum, mut count, mut top) = (0.0f64, 0usize, 0.0f32);
        for y in 0..size {
            for x in 0..size {
                let u = ((x as f64 + 0.5) / size as f64 * 2.0 - 1.0) * half;
                let v = ((y as f64 + 0.5) / size as f64 * 2.0 - 1.0) * half;
                let off_axis = (u * u + v * v).sqrt().atan();
                if 4.0 * off_axis.sin() < 0.97 {
                    let p = mean[y * size + x];
                    sum += f64::from(p.x);
                    top = top.max(p.x);
                    count += 1;
                }
            }
        }
        let ball = sum / count as f64;
        assert!(count > 500, "{count} pixels on the ball");
        let what =
            format!("roughness {roughness}: the ball averages {ball} (brightest pixel {top})");
        if roughness == 0.0 {
            // Smooth glass loses nothing (Fresnel's reflection and transmission add up to 1).
            assert!((ball - 1.0).abs() < 1e-4, "{what}");
        } else {
            assert!((ball - 1.0).abs() < 0.02, "{what}");
        }
    }
}

#[test]
fn a_tinted_slab_transmits_what_beer_lambert_and_fresnel_say() {
    // A 20 × 20 slab of glass, thickness s = 0.5, in front of a lamp of radiance 1 on black,
    // seen head-on: light crosses the front face (1 − R), is absorbed by e^{−σs} per crossing,
    // reflected back and forth inside with R each time, and leaves (1 − R): the geometric
    // series T = (1 − R)² e^{−σs} / (1 − R² e^{−2σs}) with R = ((n − 1)/(n + 1))². The
    // radiance scales of entering and leaving cancel.
    let dir = temp_dir("tinted-slab");
    let color = [0.5f64, 0.25, 0.8];
    let (distance, thickness, ior) = (1.0f64, 0.5f64, 1.5f64);
    let scene = write_scene(
        &dir,
        "slab.ron",
        &format!(
            "Scene(camera: {}, settings: Settings(width: 24, height: 24, max_depth: 24, \
             background: (0, 0, 0)), materials: {{ \
             \"glass\": Dielectric(ior: {ior}, attenuation_color: ({}, {}, {}), attenuation_distance: {distance}), \
             \"lamp\": Light(emit: Constant((1, 1, 1)), intensity: 1) }}, \
             entities: [Entity(material: \"glass\", shape: Box(min: (-10, -10, 0), max: (10, 10, {thickness}))), \
             Entity(material: \"lamp\", shape: Quad(a: (-30, -30, 3), b: (-30, 30, 3), c: (30, 30, 3), d: (30, -30, 3)))])",
            point_camera("(0, 0, -2)", "(0, 0, 1)", "(0, 1, 0)"),
            color[0],
            color[1],
            color[2],
        ),
    );
    let r = render(&scene, with(Method::Mis, 256), None);
    let px = r.film().mean();
    let reflectance = ((ior - 1.0) / (ior + 1.0)).powi(2);
    for (c, &col) in color.iter().enumerate() {
        let values: Vec<f64> = px.iter().map(|p| f64::from(p[c])).collect();
        let n = values.len() as f64;
        let mean = values.iter().sum::<f64>() / n;
        let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
        let se = (var / n).sqrt();
        let a = (col.ln() / distance * thickness).exp();
        let expected = (1.0 - reflectance).powi(2) * a / (1.0 - reflectance.powi(2) * a * a);
        assert!(
            (mean - expected).abs() < 4.0 * se + 1e-3,
            "channel {c}: {mean} ± {se}, Beer–Lambert {expected}"
        );
    }
}

fn load(path: &Path) -> rondo::scene::load::LoadedScene {
    load_scene(path, &mut AssetCache::default()).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn the_scene_format_reads_rough_and_tinted_glass_and_refuses_bad_values_at_their_place() {
    let dir = temp_dir("rough-glass-format");
    let path = write_scene(
        &dir,
        "g.ron",
        "Scene(\n    camera: Camera(position: (0, 0, 5), look_at: (0, 0, 0)),\n    materials: {\n        \
         \"clear\": Dielectric(ior: 1.5),\n        \
         \"frosted\": Dielectric(ior: 1.4, roughness: 0.3),\n        \
         \"tinted\": Dielectric(ior: 1.5, attenuation_color: (0.5, 1, 0.25), attenuation_distance: 2),\n        \
         \"colour only\": Dielectric(ior: 1.5, attenuation_color: (0.5, 0.5, 0.5)),\n    },\n)",
    );
    let scene = load(&path);
    let get = |name: &str| scene.materials.get(name).cloned().expect(name);
    assert_eq!(get("clear"), Material::glass(1.5));
    assert_eq!(get("frosted"), rough(1.4, 0.3));
    // σa = −ln(colour) / distance.
    let expected = Vec3::new(2f32.ln() / 2.0, 0.0, 4f32.ln() / 2.0);
    match get("tinted") {
        Material::Dielectric {
            ior,
            roughness,
            absorption,
        } => {
            assert_eq!((ior, roughness), (1.5, 0.0));
            assert!(
                (absorption - expected).abs().max_element() < 1e-6,
                "{absorption}"
            );
        }
        other => panic!("{other:?}"),
    }
    // Without a distance the attenuation is at infinity: nothing is absorbed.
    assert_eq!(get("colour only"), Material::glass(1.5));
    for (field, value, rule) in [
        ("roughness", "1.5", "between 0 and 1"),
        ("attenuation_color", "(0.5, 1.2, 1)", "between 0 and 1"),
        ("attenuation_distance", "0", "> 0"),
        ("attenuation_distance", "-1", "> 0"),
    ] {
        let bad = write_scene(
            &dir,
            "bad.ron",
            &format!(
                "Scene(\n    camera: Camera(position: (0, 0, 5), look_at: (0, 0, 0)),\n    \
                 materials: {{ \"g\": Dielectric(ior: 1.5, {field}: {value}) }},\n)"
            ),
        );
        let err = load_scene(&bad, &mut AssetCache::default())
            .expect_err(field)
            .to_string();
        assert!(
            err.contains("bad.ron:3:") && err.contains(field) && err.contains(rule),
            "{field} {value}: {err}"
        );
    }
}

/// Writes a glTF file of one triangle per material in `materials`, placed by a scene; returns
/// the scene's path.
fn gltf_scene(dir: &Path, materials: serde_json::Value) -> PathBuf {
    let mut bin = Bin::default();
    let v = bin.f32s(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    let count = materials.as_array().map_or(0, Vec::len);
    let meshes: Vec<_> = (0..count)
        .map(
            |k| serde_json::json!({"primitives": [{"attributes": {"POSITION": 0}, "material": k}]}),
        )
        .collect();
    let nodes: Vec<_> = (0..count)
        .map(|k| serde_json::json!({"name": format!("n{k}"), "mesh": k}))
        .collect();
    let parts = serde_json::json!({
        "extensionsUsed": ["KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_volume"],
        "accessors": [{"bufferView": v, "componentType": 5126, "count": 3, "type": "VEC3"}],
        "materials": materials,
        "meshes": meshes,
        "nodes": nodes,
        "scenes": [{"nodes": (0..count).collect::<Vec<_>>()}],
    });
    std::fs::write(dir.join("glass.gltf"), doc(&bin, parts).to_string()).expect("write");
    write_scene(
        dir,
        "scene.ron",
        "Scene(camera: Camera(position: (0, 0, 5), look_at: (0, 0, 0)), \
         entities: [Entity(name: \"g\", gltf: \"glass.gltf\")])",
    )
}

#[test]
fn gltf_transmission_ior_and_volume_become_rough_tinted_glass() {
    let dir = temp_dir("gltf-glass");
    let glass = |transmission: f64, metallic: f64, volume: serde_json::Value| {
        serde_json::json!({
            "pbrMetallicRoughness": {"metallicFactor": metallic, "roughnessFactor": 0.4},
            "extensions": {
                "KHR_materials_transmission": {"transmissionFactor": transmission},
                "KHR_materials_ior": {"ior": 1.45},
                "KHR_materials_volume": volume,
            }
        })
    };
    let volume = serde_json::json!({"thicknessFactor": 0.2, "attenuationColor": [0.5, 0.8, 1.0],
                                    "attenuationDistance": 3.0});
    let path = gltf_scene(
        &dir,
        serde_json::json!([
            glass(1.0, 0.0, volume.clone()),
            glass(0.7, 0.0, volume.clone()),
            glass(0.3, 0.0, volume.clone()),
            glass(
                1.0,
                0.0,
                serde_json::json!({"attenuationColor": [0.5, 0.5, 0.5], "attenuationDistance": 1.0})
            ),
        ]),
    );
    let scene = load(&path);
    let material = |k: usize| {
        let e = scene
            .entities
            .iter()
            .find(|e| e.name.ends_with(&format!("n{k}")))
            .expect("entity");
        scene.materials[&e.material].clone()
    };
    let tinted = Material::Dielectric {
        ior: 1.45,
        roughness: 0.4,
        absorption: Vec3::new(2f32.ln() / 3.0, -(0.8f32.ln()) / 3.0, 0.0),
    };
    let close = |a: &Material, b: &Material| match (a, b) {
        (
            Material::Dielectric {
                ior: i,
                roughness: r,
                absorption: s,
            },
            Material::Dielectric {
                ior: j,
                roughness: q,
                absorption: t,
            },
        ) => i == j && r == q && (*s - *t).abs().max_element() < 1e-6,
        _ => false,
    };
    assert!(close(&material(0), &tinted), "{:?}", material(0));
    // Partial transmission: a mix whose glass part is the same tinted glass (its weights are
    // checked in tests/gltf_transmission.rs).
    for k in [1, 2] {
        assert!(
            matches!(&material(k), Material::Transmissive { glass, .. } if close(glass, &tinted)),
            "{:?}",
            material(k)
        );
    }
    // Thickness 0 (the volume's default) is thin-walled: no absorption, and a warning that
    // says what an open surface then loses, 1/ior² = 1/1.45² ≈ 0.48 of the light. The three
    // materials with a thickness do not warn of it.
    assert_eq!(material(3), rough(1.45, 0.4));
    let thin: Vec<_> = scene
        .warnings
        .iter()
        .filter(|w| w.contains("thin-walled"))
        .collect();
    assert_eq!(thin.len(), 1, "{:?}", scene.warnings);
    assert!(
        thin[0].contains("absorbs nothing") && thin[0].contains("1/ior² = 0.48"),
        "{thin:?}"
    );

    for (bad, field) in [
        (
            serde_json::json!({"thicknessFactor": 1.0, "attenuationDistance": 0.0}),
            "attenuationDistance",
        ),
        (
            serde_json::json!({"thicknessFactor": 1.0, "attenuationDistance": -2.0}),
            "attenuationDistance",
        ),
        (
            serde_json::json!({"thicknessFactor": 1.0, "attenuationColor": [0.5, 1.5, 1.0]}),
            "attenuationColor[1]",
        ),
        (
            serde_json::json!({"thicknessFactor": -1.0}),
            "thicknessFactor",
        ),
    ] {
        let path = gltf_scene(&dir, serde_json::json!([glass(1.0, 0.0, bad)]));
        let err = load_scene(&path, &mut AssetCache::default())
            .expect_err(field)
            .to_string();
        assert!(
            err.contains("glass.gltf") && err.contains(&format!("KHR_materials_volume.{field}")),
            "{field}: {err}"
        );
    }
}

#[test]
fn every_method_sees_the_same_light_inside_rough_tinted_glass() {
    // A lamp and a floor inside a closed box of rough tinted glass, seen from outside at one
    // point (every pixel an estimate of the same radiance). Next-event estimation's shadow rays
    // from the floor to the lamp cross the tinted inside and must be attenuated as the
    // BSDF-sampled paths that reach the lamp are, or the methods disagree.
    let dir = temp_dir("rough-glass-methods");
    let scene = write_scene(
        &dir,
        "inside.ron",
        &format!(
            "Scene(camera: {}, settings: Settings(width: 16, height: 16, max_depth: 6, \
             background: (0, 0, 0)), materials: {{ \
             \"glass\": Dielectric(ior: 1.5, roughness: 0.3, attenuation_color: (0.7, 0.8, 0.9), attenuation_distance: 2), \
             \"floor\": Diffuse(albedo: Constant((0.8, 0.8, 0.8))), \
             \"lamp\": Light(emit: Constant((1, 1, 1)), intensity: 4) }}, \
             entities: [Entity(material: \"glass\", shape: Box(min: (-2, -1, -2), max: (2, 3, 2))), \
             Entity(material: \"floor\", shape: Quad(a: (-1.9, 0, -1.9), b: (-1.9, 0, 1.9), c: (1.9, 0, 1.9), d: (1.9, 0, -1.9))), \
             Entity(material: \"lamp\", shape: Quad(a: (-1, 2, -1), b: (1, 2, -1), c: (1, 2, 1), d: (-1, 2, 1)))])",
            point_camera("(0, 1, -5)", "(0.3, 0, 0)", "(0, 1, 0)"),
        ),
    );
    let estimates = common::point_estimates_by_method(&scene, 256);
    // Light does arrive through the glass (rough: next-event estimation applies at it too).
    assert!(estimates[2].1 > 0.005, "{estimates:?}");
    common::assert_methods_agree("inside tinted glass", &estimates);
}
