//! Partial transmission (`KHR_materials_transmission` with transmission × (1 − metallic)
//! strictly between 0 and 1) as the spec's mix of glass and the opaque material: the loader's
//! weights, the rendered mix against the same mixture of the two pure renders (statistics),
//! the methods' agreement inside a closed mix of tinted glass, and determinism; the
//! transmission texture's share of glass point by point (closed forms under a white sky) and
//! its bad images.

mod common;

use std::path::{Path, PathBuf};

use common::gltf_doc::{Bin, doc};
use common::png_chunks::png_header;
use common::two_texel::{fresnel_ior, half_residual, png, quad_file, render_quad_with};
use common::{point_camera, render, temp_dir, with, write_scene};
use glam::Vec3;
use rondo::app::Overrides;
use rondo::scene::assets::AssetCache;
use rondo::scene::format::Method;
use rondo::scene::load::{LoadedScene, load_scene};
use rondo::shading::material::Material;

/// A glTF material: base colour 0.8, roughness `roughness`, metallic `metallic`,
/// transmission `transmission` of ior 1.5, and `volume` (`KHR_materials_volume`, `null`: none).
fn material(
    transmission: f64,
    metallic: f64,
    roughness: f64,
    volume: serde_json::Value,
) -> serde_json::Value {
    let mut extensions = serde_json::json!({
        "KHR_materials_transmission": {"transmissionFactor": transmission},
        "KHR_materials_ior": {"ior": 1.5},
    });
    if !volume.is_null() {
        extensions["KHR_materials_volume"] = volume;
    }
    serde_json::json!({
        "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0],
                                 "metallicFactor": metallic, "roughnessFactor": roughness},
        "extensions": extensions,
    })
}

/// Writes `name` into `dir`: one mesh of `positions` (triangles, unindexed) per material of
/// `materials`, each in its own node `n{k}`.
fn write_gltf(dir: &Path, name: &str, positions: &[f32], materials: &[serde_json::Value]) {
    let mut bin = Bin::default();
    let v = bin.f32s(positions);
    let count = positions.len() / 3;
    let meshes: Vec<_> = (0..materials.len())
        .map(
            |k| serde_json::json!({"primitives": [{"attributes": {"POSITION": 0}, "material": k}]}),
        )
        .collect();
    let nodes: Vec<_> = (0..materials.len())
        .map(|k| serde_json::json!({"name": format!("n{k}"), "mesh": k}))
        .collect();
    let parts = serde_json::json!({
        "extensionsUsed": ["KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_volume"],
        "accessors": [{"bufferView": v, "componentType": 5126, "count": count, "type": "VEC3"}],
        "materials": materials,
        "meshes": meshes,
        "nodes": nodes,
        "scenes": [{"nodes": (0..materials.len()).collect::<Vec<_>>()}],
    });
    std::fs::write(dir.join(name), doc(&bin, parts).to_string()).expect("write glTF");
}

/// The triangles of the closed box between corners `lo` and `hi`, each face as two triangles,
/// counter-clockwise seen from outside (normals out).
fn box_positions(lo: [f32; 3], hi: [f32; 3]) -> Vec<f32> {
    let corner = |k: usize| {
        [
            if k & 1 == 0 { lo[0] } else { hi[0] },
            if k & 2 == 0 { lo[1] } else { hi[1] },
            if k & 4 == 0 { lo[2] } else { hi[2] },
        ]
    };
    let faces = [
        [0, 4, 6, 2],
        [1, 3, 7, 5],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 2, 3, 1],
        [4, 5, 7, 6],
    ];
    faces
        .iter()
        .flat_map(|f| [f[0], f[1], f[2], f[0], f[2], f[3]])
        .flat_map(corner)
        .collect()
}

fn load(path: &Path) -> LoadedScene {
    load_scene(path, &mut AssetCache::default()).unwrap_or_else(|e| panic!("{e}"))
}

/// The material of the entity from node `n{k}`.
fn material_of(scene: &LoadedScene, k: usize) -> Material {
    let e = scene
        .entities
        .iter()
        .find(|e| e.name.ends_with(&format!("n{k}")))
        .expect("entity");
    scene.materials[&e.material].clone()
}

#[test]
fn partial_transmission_loads_as_a_mix_weighted_by_transmission_times_one_minus_metallic() {
    let dir = temp_dir("gltf-transmission-weights");
    // (transmission, metallic) and the spec's weight w = t·(1 − m), with the opaque part's
    // metalness m / (1 − w) (the spec's metal share of what is not glass).
    let cases = [
        (0.3, 0.0, 0.3, 0.0),
        (0.5, 0.0, 0.5, 0.0),
        (0.7, 0.0, 0.7, 0.0),
        (0.6, 0.5, 0.3, 0.5 / 0.7),
        (1.0, 0.5, 0.5, 1.0),
        (0.875, 0.2, 0.7, 0.2 / 0.3),
    ];
    let materials: Vec<_> = cases
        .iter()
        .map(|&(t, m, _, _)| material(t, m, 0.4, serde_json::Value::Null))
        .chain([
            material(1.0, 0.0, 0.4, serde_json::Value::Null),
            material(0.0, 0.3, 0.4, serde_json::Value::Null),
        ])
        .collect();
    write_gltf(
        &dir,
        "m.gltf",
        &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
        &materials,
    );
    let path = write_scene(
        &dir,
        "scene.ron",
        "Scene(camera: Camera(position: (0, 0, 5), look_at: (0, 0, 0)), \
         entities: [Entity(name: \"g\", gltf: \"m.gltf\")])",
    );
    let scene = load(&path);
    let glass = Material::Dielectric {
        ior: 1.5,
        roughness: 0.4,
        absorption: Vec3::ZERO,
    };
    for (k, &(t, m, w, base_metallic)) in cases.iter().enumerate() {
        let Material::Transmissive {
            weight,
            glass: g,
            base,
            texture: None,
        } = material_of(&scene, k)
        else {
            panic!("t {t}, m {m}: {:?}", material_of(&scene, k));
        };
        assert!(
            (f64::from(weight) - w).abs() < 1e-6,
            "t {t}, m {m}: {weight}"
        );
        assert_eq!(*g, glass, "t {t}, m {m}");
        let Material::Pbr {
            metallic,
            roughness,
            ..
        } = *base
        else {
            panic!("t {t}, m {m}: {base:?}");
        };
        assert!(
            (f64::from(metallic) - base_metallic).abs() < 1e-6 && roughness == 0.4,
            "t {t}, m {m}: metallic {metallic}, roughness {roughness}"
        );
    }
    // Weight 1 is glass alone, weight 0 the opaque material alone.
    assert_eq!(material_of(&scene, cases.len()), glass);
    assert!(matches!(
        material_of(&scene, cases.len() + 1),
        Material::Pbr { metallic: 0.3, .. }
    ));
    // The mix is no approximation any more: nothing warns of it.
    assert!(
        !scene
            .warnings
            .iter()
            .any(|w| w.contains("does not mix") || w.contains("(1 − metallic")),
        "{:?}",
        scene.warnings
    );
}

/// The scene of a big glTF triangle in the plane z = 0 (front face +z) of `material`, seen
/// head-on at one point by a camera at z = 5 (every pixel an independent estimate of one
/// radiance), on black, `lit` by a lamp in front of it and one behind it. A camera path meets
/// the triangle once at most, so the radiance is linear in its BSDF.
fn triangle_scene(dir: &Path, name: &str, material: serde_json::Value, lit: bool) -> PathBuf {
    let gltf = format!("{name}.gltf");
    write_gltf(
        dir,
        &gltf,
        &[-20.0, -20.0, 0.0, 20.0, -20.0, 0.0, 0.0, 20.0, 0.0],
        &[material],
    );
    write_scene(
        dir,
        &format!("{name}.ron"),
        &format!(
            "Scene(camera: {}, settings: Settings(width: 32, height: 32, max_depth: 4, \
             background: (0, 0, 0)), materials: {{ \
             \"front\": Light(emit: Constant((1, 1, 1)), intensity: 3), \
             \"back\": Light(emit: Constant((1, 1, 1)), intensity: 2) }}, \
             entities: [Entity(name: \"t\", gltf: \"{gltf}\"){}])",
            point_camera("(0, 0, 5)", "(0, 0, 0)", "(0, 1, 0)"),
            if lit {
                ", Entity(material: \"front\", shape: Sphere(center: (2, 0, 3), radius: 1)), \
                 Entity(material: \"back\", shape: Sphere(center: (0.7, 0.3, -3), radius: 1.5))"
            } else {
                ""
            },
        ),
    )
}

#[test]
fn a_partly_transmissive_surface_renders_the_weighted_mean_of_its_glass_and_opaque_renders() {
    // f = w·f_glass + (1 − w)·f_opaque and a path that meets the surface once: the radiance is
    // w·L_glass + (1 − w)·L_opaque, each measured on its own render (independent samples), and
    // the mix's render must agree within its noise. Rough glass, so that light sampling and
    // MIS apply to both parts.
    let dir = temp_dir("gltf-transmission-mix");
    let w = 0.3;
    let glass = triangle_scene(
        &dir,
        "glass",
        material(1.0, 0.0, 0.4, serde_json::Value::Null),
        true,
    );
    let opaque = triangle_scene(
        &dir,
        "opaque",
        material(0.0, 0.0, 0.4, serde_json::Value::Null),
        true,
    );
    let mix = triangle_scene(
        &dir,
        "mix",
        material(w, 0.0, 0.4, serde_json::Value::Null),
        true,
    );
    for method in [Method::Mis, Method::Nee] {
        let estimate = |path: &Path| common::point_estimate(&render(path, with(method, 64), None));
        let (g, o, m) = (estimate(&glass), estimate(&opaque), estimate(&mix));
        // The two parts look different: the test can tell them apart.
        let apart = (g.0 - o.0).abs() / (g.1 * g.1 + o.1 * o.1).sqrt();
        assert!(apart > 30.0, "{method}: glass {g:?}, opaque {o:?}");
        let expected = w * g.0 + (1.0 - w) * o.0;
        let se = (m.1 * m.1 + w * w * g.1 * g.1 + (1.0 - w) * (1.0 - w) * o.1 * o.1).sqrt();
        assert!(
            common::within(m.0, se, expected, 4.0),
            "{method}: mix {m:?}, {w}·{g:?} + {}·{o:?} = {expected} ± {se}",
            1.0 - w
        );
    }
}

#[test]
fn smooth_partial_glass_passes_its_share_of_the_fresnel_transmitted_light_behind_it() {
    // Closed form: a camera looks head-on at a smooth glTF surface (ior 1.5) with only a lamp
    // of radiance L = 2 behind it, on black. The glass part (probability w = t·(1 − m))
    // transmits 1 − F = 1 − ((1.5 − 1)/(1.5 + 1))² = 0.96 at normal incidence, and the
    // refraction into the denser side scales radiance by (1/1.5)²; its reflection sees black.
    // The opaque part only reflects black. So the radiance is w · 0.96 / 2.25 · L exactly
    // (rounding to 0 or to the full glass would give 0 or 0.853).
    let dir = temp_dir("gltf-transmission-closed-form");
    for (t, m) in [(0.3, 0.0), (0.7, 0.0), (0.6, 0.5)] {
        let w = t * (1.0 - m);
        let name = format!("t{t}-m{m}");
        let gltf = format!("{name}.gltf");
        write_gltf(
            &dir,
            &gltf,
            &[-20.0, -20.0, 0.0, 20.0, -20.0, 0.0, 0.0, 20.0, 0.0],
            &[material(t, m, 0.0, serde_json::Value::Null)],
        );
        let path = write_scene(
            &dir,
            &format!("{name}.ron"),
            &format!(
                "Scene(camera: {}, settings: Settings(width: 32, height: 32, max_depth: 4, \
                 background: (0, 0, 0)), materials: {{ \
                 \"lamp\": Light(emit: Constant((1, 1, 1)), intensity: 2) }}, \
                 entities: [Entity(name: \"t\", gltf: \"{gltf}\"), \
                 Entity(material: \"lamp\", shape: Sphere(center: (0, 0, -3), radius: 1.5))])",
                point_camera("(0, 0, 5)", "(0, 0, 0)", "(0, 1, 0)"),
            ),
        );
        let expected = w * 0.96 / 2.25 * 2.0;
        for method in [Method::Mis, Method::Naive, Method::Caustics] {
            let (mean, se) = common::point_estimate(&render(&path, with(method, 64), None));
            assert!(
                se > 0.0 && common::within(mean, se, expected, 4.0),
                "t {t}, m {m}, {method}: {mean} ± {se}, expected {expected}"
            );
        }
    }
}

#[test]
fn caustics_through_a_partly_transmissive_slab_agree_with_path_tracing() {
    // A floor lit by a small lamp through a closed slab, half smooth glass, half opaque, seen
    // beside the slab at a point under it. Light tracing takes the caustic paths that cross
    // the glass part (picked per hit as the path tracer picks it), the path tracer the rest:
    // the sum must be what path tracing alone finds.
    let dir = temp_dir("gltf-transmission-caustics");
    write_gltf(
        &dir,
        "slab.gltf",
        &box_positions([-1.5, 1.0, -1.5], [1.5, 1.2, 1.5]),
        &[material(0.5, 0.0, 0.0, serde_json::Value::Null)],
    );
    let scene = write_scene(
        &dir,
        "slab.ron",
        &format!(
            "Scene(camera: {}, settings: Settings(width: 16, height: 16, max_depth: 8, \
             background: (0, 0, 0)), materials: {{ \
             \"floor\": Diffuse(albedo: Constant((0.8, 0.8, 0.8))), \
             \"lamp\": Light(emit: Constant((1, 1, 1)), intensity: 20) }}, \
             entities: [Entity(name: \"slab\", gltf: \"slab.gltf\"), \
             Entity(material: \"floor\", shape: Quad(a: (-3, 0, -3), b: (-3, 0, 3), c: (3, 0, 3), d: (3, 0, -3))), \
             Entity(material: \"lamp\", shape: Sphere(center: (0, 3, 0), radius: 0.4))])",
            "Camera(position: (4, 0.5, 0), look_at: (0, 0, 0), up: (0, 1, 0), fov: 40)",
        ),
    );
    let (mis, light) = (
        over_seeds(&scene, Method::Mis, 64),
        over_seeds(&scene, Method::Caustics, 16),
    );
    let se = (mis.1 * mis.1 + light.1 * light.1).sqrt();
    assert!(
        mis.0 > 0.01 && (mis.0 - light.0).abs() <= 4.0 * se,
        "mis {mis:?}, caustics {light:?}"
    );
}

/// The mean of the red channel over the image of `scene` rendered with `method` at `spp`,
/// with its standard error over 8 seeds. Light tracing splats are not independent per pixel:
/// the image mean's error comes from independent seeds (Student's t with 7 degrees of
/// freedom: 4 standard errors are a safe bound).
fn over_seeds(scene: &Path, method: Method, spp: u32) -> (f64, f64) {
    let v: Vec<f64> = (0..8u64)
        .map(|seed| {
            let o = Overrides {
                seed: Some(100 + seed),
                ..with(method, spp)
            };
            let px = render(scene, o, None).film().mean();
            px.iter().map(|p| f64::from(p.x)).sum::<f64>() / px.len() as f64
        })
        .collect();
    common::mean_se(&v)
}

#[test]
fn a_partly_transmissive_emitter_emits_in_full_whichever_part_shades() {
    // The spec adds the emission whatever the transmission: on black, with nothing to reflect
    // or transmit, every sample sees exactly the emitted radiance.
    let dir = temp_dir("gltf-transmission-emission");
    let mut m = material(0.3, 0.0, 0.4, serde_json::Value::Null);
    m["emissiveFactor"] = serde_json::json!([0.25, 0.5, 0.75]);
    let path = triangle_scene(&dir, "glow", m, false);
    let r = render(&path, with(Method::Mis, 16), None);
    for p in r.film().mean() {
        assert!(
            (p - Vec3::new(0.25, 0.5, 0.75)).abs().max_element() < 1e-5,
            "{p}"
        );
    }
}

#[test]
fn the_methods_agree_inside_a_closed_box_partly_of_tinted_glass() {
    // A lamp and a floor inside a closed box whose walls are half tinted rough glass, half
    // opaque, seen from outside at one point. A path that picked the opaque part at a wall stays
    // on its side; one that refracted through the glass crosses the tinted inside. Shadow rays
    // must cross the walls as the BSDF-sampled paths do, or the methods disagree.
    let dir = temp_dir("gltf-transmission-box");
    let positions = box_positions([-2.0, -1.0, -2.0], [2.0, 3.0, 2.0]);
    let volume = serde_json::json!({"thicknessFactor": 1.0, "attenuationColor": [0.7, 0.8, 0.9],
                                    "attenuationDistance": 2.0});
    write_gltf(
        &dir,
        "box.gltf",
        &positions,
        &[material(0.5, 0.0, 0.3, volume)],
    );
    let scene = write_scene(
        &dir,
        "inside.ron",
        &format!(
            "Scene(camera: {}, settings: Settings(width: 16, height: 16, max_depth: 6, \
             background: (0, 0, 0)), materials: {{ \
             \"floor\": Diffuse(albedo: Constant((0.8, 0.8, 0.8))), \
             \"lamp\": Light(emit: Constant((1, 1, 1)), intensity: 4) }}, \
             entities: [Entity(name: \"box\", gltf: \"box.gltf\"), \
             Entity(material: \"floor\", shape: Quad(a: (-1.9, 0, -1.9), b: (-1.9, 0, 1.9), c: (1.9, 0, 1.9), d: (1.9, 0, -1.9))), \
             Entity(material: \"lamp\", shape: Quad(a: (-1, 2, -1), b: (1, 2, -1), c: (1, 2, 1), d: (-1, 2, 1)))])",
            point_camera("(0, 1, -5)", "(0.3, 0, 0)", "(0, 1, 0)"),
        ),
    );
    let loaded = load(&scene);
    assert!(
        loaded
            .materials
            .values()
            .any(|m| matches!(m, Material::Transmissive { .. })),
        "the box is a mix"
    );
    let estimates = common::point_estimates_by_method(&scene, 256);
    assert!(estimates[2].1 > 0.005, "{estimates:?}");
    common::assert_methods_agree("inside a partly glass box", &estimates);
}

#[test]
fn a_partly_transmissive_scene_renders_the_same_bits_on_any_thread_count() {
    let dir = temp_dir("gltf-transmission-threads");
    let mix = triangle_scene(
        &dir,
        "mix",
        material(0.3, 0.0, 0.0, serde_json::Value::Null),
        true,
    );
    for method in [Method::Mis, Method::Caustics] {
        let o = Overrides {
            width: Some(24),
            height: Some(16),
            ..with(method, 8)
        };
        let one = render(&mix, o, Some(1));
        let two = render(&mix, o, Some(2));
        assert_eq!(one.film().sum, two.film().sum, "{method}");
    }
}

/// A glTF material over a black, smooth base of metalness `metallic`, transmission factor
/// `factor` of ior 1.5 scaled by `transmissionTexture` (texture 0) read as `texture_info`
/// says (`{"index": 0}` and any `texCoord` or transform).
fn textured_material(
    factor: f64,
    metallic: f64,
    texture_info: serde_json::Value,
) -> serde_json::Value {
    serde_json::json!({
        "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": metallic,
                                 "roughnessFactor": 0},
        "extensions": {
            "KHR_materials_transmission": {"transmissionFactor": factor,
                                           "transmissionTexture": texture_info},
            "KHR_materials_ior": {"ior": 1.5},
        },
    })
}

/// The extensions the textured quads use.
const TEXTURED: [&str; 3] = [
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_texture_transform",
];

#[test]
fn a_transmission_texture_lets_the_sky_through_only_where_its_red_channel_says() {
    // A quad seen face-on under a white sky (radiance 1), its transmission texture's red 0 on
    // the left half and 1 on the right. Closed forms at view cosine c, F the exact Fresnel
    // reflectance of ior 1.5: the smooth glass reflects the sky with probability F and
    // refracts into the sky beyond with the rest, its radiance scaled by (1/1.5)², so
    // G = F + (1 − F)/2.25; the black smooth dielectric base reflects F (its black diffuse
    // nothing); a black metal reflects Schlick's (1 − c)⁵ (F0 = 0), below 10⁻⁶ here.
    // With transmission t, metallic m and red r the spec's mix is
    // m·metal + (1 − m)·(t·r·G + (1 − t·r)·F). Ignoring the texture gives the left half the
    // right half's value.
    let dir = temp_dir("gltf-transmission-texture");
    let glass = |c: f64| {
        let f = fresnel_ior(c);
        f + (1.0 - f) / 2.25
    };
    let metal = |c: f64| (1.0 - c).powi(5);
    let plain = serde_json::json!({"index": 0});
    // The texture through TEXCOORD_1 (u = (1 − x)/2 on this quad) or through a transform
    // u ↦ 1 − u sees the halves the other way round.
    let set_1 = serde_json::json!({"index": 0, "texCoord": 1});
    let mirrored = serde_json::json!({"index": 0, "extensions": {
        "KHR_texture_transform": {"offset": [1, 0], "scale": [-1, 1]}}});
    let cases = [
        // (transmission, metallic, texture reference, whether the halves swap)
        (1.0, 0.0, plain.clone(), false),
        (0.6, 0.5, plain, false),
        (1.0, 0.0, set_1, true),
        (1.0, 0.0, mirrored, true),
    ];
    let methods = [Method::Naive, Method::Mis, Method::Caustics];
    for ((t, m, info, swapped), method) in cases
        .iter()
        .flat_map(|case| methods.map(|method| (case.clone(), method)))
    {
        let pixels = render_quad_with(
            method,
            &dir,
            textured_material(t, m, info.clone()),
            &TEXTURED,
            ([0, 0, 0, 255], [255, 0, 0, 255]),
            64,
        );
        for right in [false, true] {
            let r = if right != swapped { 1.0 } else { 0.0 };
            let expected = |c: f64| {
                let share = t * r;
                let dielectric = share * glass(c) + (1.0 - share) * fresnel_ior(c);
                [m * metal(c) + (1.0 - m) * dielectric; 3]
            };
            let (mean, se, _, want) = half_residual(&pixels, right, expected);
            println!("{method}, t {t}, m {m}, {info}, right {right}: {want:?} {mean:?} ± {se:?}");
            for k in 0..3 {
                assert!(
                    mean[k].abs() <= 4.0 * se[k] + 1e-4,
                    "{method}, t {t}, m {m}, {info}, right half {right}: expected {want:?}, off by \
                     {mean:?} ± {se:?}"
                );
            }
        }
    }
}

#[test]
fn a_transmission_texture_makes_the_mix_even_at_full_transmission_and_is_not_warned_of() {
    // transmission 1, metallic 0 is glass alone without a texture; with one that can lower
    // it, the mix of weight 1 whose texture hands what it takes from the glass to the opaque
    // material without metal.
    let dir = temp_dir("gltf-transmission-texture-load");
    std::fs::write(dir.join("t.png"), png([0, 0, 0, 255], [255, 0, 0, 255])).expect("write");
    let material = textured_material(1.0, 0.0, serde_json::json!({"index": 0}));
    let file = quad_file(material, &TEXTURED);
    std::fs::write(dir.join("q.gltf"), file.to_string()).expect("write");
    let path = write_scene(
        &dir,
        "q.ron",
        "Scene(camera: Camera(position: (0, 0, 2), look_at: (0, 0, 0)), \
         entities: [Entity(name: \"q\", gltf: \"q.gltf\")])",
    );
    let scene = load(&path);
    let e = scene.entities.first().expect("the quad");
    let Material::Transmissive {
        weight,
        glass,
        base,
        texture: Some(texture),
    } = &scene.materials[&e.material]
    else {
        panic!("{:?}", scene.materials[&e.material]);
    };
    assert_eq!(*weight, 1.0);
    assert!(matches!(**glass, Material::Dielectric { ior: 1.5, .. }));
    assert!(matches!(**base, Material::Pbr { metallic: 0.0, .. }));
    assert!(matches!(
        texture.opaque,
        Material::Pbr { metallic: 0.0, .. }
    ));
    assert!(
        scene
            .warnings
            .iter()
            .all(|w| !w.contains("transmissionTexture")),
        "{:?}",
        scene.warnings
    );
}

#[test]
fn a_broken_or_oversized_transmission_texture_is_an_error_naming_its_image() {
    // Not a PNG at all, and a PNG header announcing 10⁵ × 10⁵ pixels with no data: errors
    // that name the material and the image, never a panic, never an allocation for the size.
    let dir = temp_dir("gltf-transmission-texture-broken");
    let huge = png_header(100_000, 100_000, &[]);
    let material = textured_material(0.5, 0.0, serde_json::json!({"index": 0}));
    let file = quad_file(material, &TEXTURED);
    std::fs::write(dir.join("q.gltf"), file.to_string()).expect("write");
    let path = write_scene(
        &dir,
        "q.ron",
        "Scene(camera: Camera(position: (0, 0, 2), look_at: (0, 0, 0)), \
         entities: [Entity(name: \"q\", gltf: \"q.gltf\")])",
    );
    for bytes in [b"not an image".to_vec(), huge] {
        std::fs::write(dir.join("t.png"), &bytes).expect("write");
        let result = std::panic::catch_unwind(|| load_scene(&path, &mut AssetCache::default()));
        let error = match result {
            Ok(Err(e)) => e.to_string(),
            Ok(Ok(_)) => panic!("{} bytes loaded", bytes.len()),
            Err(_) => panic!("the loader panicked on {} bytes", bytes.len()),
        };
        println!("{error}");
        assert!(
            error.contains("material \"#0\": transmissionTexture: image")
                && error.contains("t.png"),
            "{error}"
        );
    }
}

#[test]
fn caustics_through_a_transmission_texture_agree_with_path_tracing() {
    // A floor lit by a small lamp through a smooth panel that is glass on one half
    // (transmission texture red 1) and an opaque black dielectric on the other (red 0), seen
    // from the side. Light tracing must pick the panel's part where its light path hits it as
    // the path tracer does there (the texel at that point), or the caustic under the glass
    // half is counted twice or not at all.
    let dir = temp_dir("gltf-transmission-texture-caustics");
    std::fs::write(dir.join("t.png"), png([0, 0, 0, 255], [255, 0, 0, 255])).expect("write");
    let material = textured_material(1.0, 0.0, serde_json::json!({"index": 0}));
    std::fs::write(
        dir.join("q.gltf"),
        quad_file(material, &TEXTURED).to_string(),
    )
    .expect("write");
    let scene = write_scene(
        &dir,
        "floor.ron",
        "Scene(camera: Camera(position: (4, 0, -0.3), look_at: (0, 0, -1), up: (0, 0, 1), \
         fov: 40), settings: Settings(width: 16, height: 16, max_depth: 6, \
         background: (0, 0, 0)), materials: { \
         \"floor\": Diffuse(albedo: Constant((0.8, 0.8, 0.8))), \
         \"lamp\": Light(emit: Constant((1, 1, 1)), intensity: 20) }, \
         entities: [Entity(name: \"q\", gltf: \"q.gltf\"), \
         Entity(material: \"floor\", shape: Quad(a: (-3, -3, -1), b: (3, -3, -1), c: (3, 3, -1), d: (-3, 3, -1))), \
         Entity(material: \"lamp\", shape: Sphere(center: (0, 0, 2.5), radius: 0.3))])",
    );
    let (mis, light) = (
        over_seeds(&scene, Method::Mis, 256),
        over_seeds(&scene, Method::Caustics, 64),
    );
    let se = (mis.1 * mis.1 + light.1 * light.1).sqrt();
    println!("mis {mis:?}, caustics {light:?}");
    assert!(
        mis.0 > 0.01 && (mis.0 - light.0).abs() <= 4.0 * se,
        "mis {mis:?}, caustics {light:?}"
    );
}
