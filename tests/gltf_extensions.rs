//! glTF extensions and features beyond the core material, on small files written here:
//! `KHR_texture_transform`, a second texture coordinate set (`TEXCOORD_1`), instancing by
//! `EXT_mesh_gpu_instancing`, `alphaMode: BLEND` as stochastic transparency, and the warnings
//! for extensions rondo does not read. Expected values come from the files by hand.

mod common;

use std::path::Path;

use common::gltf_doc::{Bin, doc};
use common::{point_camera, point_estimate, render, temp_dir, within, write_scene};
use glam::{Mat2, Quat, Vec2, Vec3};
use rondo::scene::assets::AssetCache;
use rondo::scene::load::load_scene;
use rondo::shading::texture::srgb_to_linear;
use rondo::{Overrides, PassPlan, Renderer, Shape};
use serde_json::{Value, json};

/// The top-left, top-right, bottom-left and bottom-right texels of the 2×2 test texture, dark
/// enough that a texel plus another (base colour plus emission) stays below 1 in the albedo.
const TEXELS: [[u8; 3]; 4] = [[128, 0, 0], [0, 128, 0], [0, 0, 128], [64, 64, 64]];

/// Texel `(i, j)` (column, row from the top) decoded to linear.
fn texel(i: usize, j: usize) -> Vec3 {
    Vec3::from(TEXELS[j * 2 + i].map(|b| srgb_to_linear(f32::from(b) / 255.0)))
}

fn texture_png() -> Vec<u8> {
    let image = image::RgbImage::from_fn(2, 2, |x, y| image::Rgb(TEXELS[(y * 2 + x) as usize]));
    let mut png = Vec::new();
    image
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .expect("encode");
    png
}

/// A quad over [−1, 1]² at z = 0 facing +z with `TEXCOORD_0` the glTF coordinates of the
/// corners (the corner (−1, 1) is the image's top-left) and `TEXCOORD_1` their transpose
/// `(v, u)`, textured by `t.png` through a NEAREST, REPEAT sampler, with material `material`.
fn quad_file(material: Value) -> Value {
    let mut bin = Bin::default();
    let v = bin.f32s(&[
        -1.0, -1.0, 0.0, 1.0, -1.0, 0.0, 1.0, 1.0, 0.0, -1.0, 1.0, 0.0,
    ]);
    let uv0 = bin.f32s(&[0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0]);
    let uv1 = bin.f32s(&[1.0, 0.0, 1.0, 1.0, 0.0, 1.0, 0.0, 0.0]);
    let i = bin.u16s(&[0, 1, 2, 0, 2, 3]);
    doc(
        &bin,
        json!({
            "extensionsUsed": ["KHR_texture_transform"],
            "accessors": [
                {"bufferView": v, "componentType": 5126, "count": 4, "type": "VEC3"},
                {"bufferView": uv0, "componentType": 5126, "count": 4, "type": "VEC2"},
                {"bufferView": uv1, "componentType": 5126, "count": 4, "type": "VEC2"},
                {"bufferView": i, "componentType": 5123, "count": 6, "type": "SCALAR"},
            ],
            "images": [{"uri": "t.png"}],
            "samplers": [{"magFilter": 9728, "minFilter": 9728, "wrapS": 10497, "wrapT": 10497}],
            "textures": [{"source": 0, "sampler": 0}],
            "materials": [material],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1, "TEXCOORD_1": 2}, "indices": 3, "material": 0}]}],
            "nodes": [{"name": "quad", "mesh": 0}],
            "scenes": [{"nodes": [0]}],
        }),
    )
}

/// Writes `t.png` and `model` (the file `file`) to `dir`, and a scene viewing it from
/// (0, 0, 2) over 32×32 pixels; returns the scene's path.
fn write_quad(dir: &Path, model: &str, file: &Value) -> std::path::PathBuf {
    std::fs::write(dir.join("t.png"), texture_png()).expect("write");
    std::fs::write(dir.join(model), file.to_string()).expect("write");
    write_scene(
        dir,
        &format!("{model}.ron"),
        &format!(
            r#"Scene(
    camera: Camera(position: (0, 0, 2), look_at: (0, 0, 0), fov: 40),
    settings: Settings(width: 32, height: 32, spp: 16, max_depth: 2, method: Naive),
    entities: [Entity(name: "m", gltf: "{model}")],
)"#
        ),
    )
}

/// The albedo feature buffer of the scene at `path`.
fn albedo(path: &Path) -> Vec<Vec3> {
    let mut r = Renderer::new(None, PassPlan::Single).expect("renderer");
    r.set_features(true);
    r.set_overrides(Overrides::default());
    r.load(path).unwrap_or_else(|e| panic!("{e}"));
    r.render_to_completion();
    let film = r.film();
    let f = film.features.as_ref().expect("features");
    f.albedo_mean(film.count())
}

/// The glTF coordinates `TEXCOORD_0` at point `(x, y)` of the 32×32 view (pixel centres at
/// half-integers): the view's half-width at z = 0 is 2·tan 20°.
fn uv_at(x: f32, y: f32) -> Vec2 {
    let half = 2.0 * 20f32.to_radians().tan();
    let px = (2.0 * x / 32.0 - 1.0) * half;
    let py = (1.0 - 2.0 * y / 32.0) * half;
    Vec2::new((px + 1.0) / 2.0, (1.0 - py) / 2.0)
}

/// The texel NEAREST and REPEAT read at glTF coordinates `uv` (v down the image).
fn nearest(uv: Vec2) -> (usize, usize) {
    let wrap = |c: f32| ((c - c.floor()) * 2.0).floor().min(1.0) as usize;
    (wrap(uv.x), wrap(uv.y))
}

/// For every pixel whose square reads one texel under `texel_of` (at its four corners and its
/// centre), the largest difference between its albedo and `expected` of that pixel's centre.
fn worst_over_whole_texel_pixels(
    albedo: &[Vec3],
    texel_of: impl Fn(Vec2) -> Vec<(usize, usize)>,
    expected: impl Fn(Vec2) -> Vec3,
) -> (f32, usize) {
    let (mut worst, mut checked) = (0.0f32, 0);
    for y in 0..32 {
        for x in 0..32 {
            let (fx, fy) = (x as f32, y as f32);
            let points = [
                (fx + 0.5, fy + 0.5),
                (fx, fy),
                (fx + 1.0, fy),
                (fx, fy + 1.0),
                (fx + 1.0, fy + 1.0),
            ];
            let centre = texel_of(uv_at(points[0].0, points[0].1));
            if points
                .iter()
                .any(|&(px, py)| texel_of(uv_at(px, py)) != centre)
            {
                continue;
            }
            checked += 1;
            let got = albedo[y * 32 + x];
            worst = worst.max(
                (got - expected(uv_at(fx + 0.5, fy + 0.5)))
                    .abs()
                    .max_element(),
            );
        }
    }
    (worst, checked)
}

/// The spec's transform `T · R · S` written out: `u' = sx·cos·u + sy·sin·v + ox`,
/// `v' = −sx·sin·u + sy·cos·v + oy` (its worked example: offset (0, 1), rotation π/2, scale 0.5
/// selects the lower left quadrant).
fn khr_transform(uv: Vec2, offset: Vec2, rotation: f32, scale: Vec2) -> Vec2 {
    let (s, c) = rotation.sin_cos();
    Vec2::new(
        scale.x * c * uv.x + scale.y * s * uv.y + offset.x,
        -scale.x * s * uv.x + scale.y * c * uv.y + offset.y,
    )
}

#[test]
fn texture_transform_moves_the_lookup_as_the_spec_computes_it() {
    let dir = temp_dir("gltf-ext-transform");
    let (offset, rotation, scale) = (Vec2::new(0.3, -0.2), 0.7f32, Vec2::new(1.7, 0.6));
    let material = json!({
        "name": "moved",
        "pbrMetallicRoughness": {
            "metallicFactor": 0.0,
            "baseColorTexture": {"index": 0, "extensions": {"KHR_texture_transform": {
                "offset": offset.to_array(), "rotation": rotation, "scale": scale.to_array()}}},
        },
    });
    let path = write_quad(&dir, "moved.gltf", &quad_file(material));
    let albedo = albedo(&path);
    let at = |uv: Vec2| nearest(khr_transform(uv, offset, rotation, scale));
    let (worst, checked) = worst_over_whole_texel_pixels(
        &albedo,
        |uv| vec![at(uv)],
        |uv| {
            let (i, j) = at(uv);
            texel(i, j)
        },
    );
    assert!(checked > 500, "only {checked} pixels inside one texel");
    assert!(worst < 1e-5, "largest difference {worst}");
    // The transform matters here: without it, most of those pixels read another texel.
    let moved = (0..32 * 32)
        .filter(|k| {
            let uv = uv_at((k % 32) as f32 + 0.5, (k / 32) as f32 + 0.5);
            at(uv) != nearest(uv)
        })
        .count();
    assert!(moved > 400, "{moved}");
}

#[test]
fn a_texture_reads_the_set_it_names_and_only_used_sets_are_carried() {
    let dir = temp_dir("gltf-ext-sets");
    // Set 1 named by the texture transform's `texCoord`, which overrides the reference's 0.
    let only_set_1 = json!({
        "pbrMetallicRoughness": {
            "metallicFactor": 0.0,
            "baseColorTexture": {"index": 0, "texCoord": 0,
                "extensions": {"KHR_texture_transform": {"texCoord": 1}}},
        },
    });
    let path = write_quad(&dir, "one.gltf", &quad_file(only_set_1));
    let transpose = |uv: Vec2| Vec2::new(uv.y, uv.x);
    let albedo_one = albedo(&path);
    let (worst, checked) = worst_over_whole_texel_pixels(
        &albedo_one,
        |uv| vec![nearest(transpose(uv))],
        |uv| {
            let (i, j) = nearest(transpose(uv));
            texel(i, j)
        },
    );
    assert!(
        checked > 500 && worst < 1e-5,
        "{checked} pixels, worst {worst}"
    );
    // One set read: the mesh carries it alone (as its first set), not both.
    let scene = load_scene(&path, &mut AssetCache::default()).unwrap_or_else(|e| panic!("{e}"));
    let Shape::Mesh(mesh) = &scene.entities[0].shape else {
        panic!("not a mesh")
    };
    assert!(mesh.data.uvs1.is_none());
    // TEXCOORD_1 of the corner (−1, −1) is (1, 0): stored as (u, 1 − v).
    assert_eq!(mesh.data.uvs.as_ref().expect("uvs")[0], Vec2::new(1.0, 1.0));

    // Base colour on set 0 and emission on set 1 (as Khronos' MultiUVTest): both carried, each
    // texture reading its own; the albedo feature is reflectance plus emission.
    let both = json!({
        "emissiveFactor": [1.0, 1.0, 1.0],
        "emissiveTexture": {"index": 0, "texCoord": 1},
        "pbrMetallicRoughness": {"metallicFactor": 0.0, "baseColorTexture": {"index": 0}},
    });
    let path = write_quad(&dir, "two.gltf", &quad_file(both));
    let albedo_two = albedo(&path);
    let (worst, checked) = worst_over_whole_texel_pixels(
        &albedo_two,
        |uv| vec![nearest(uv), nearest(transpose(uv))],
        |uv| {
            let ((i, j), (k, l)) = (nearest(uv), nearest(transpose(uv)));
            texel(i, j) + texel(k, l)
        },
    );
    assert!(
        checked > 400 && worst < 1e-5,
        "{checked} pixels, worst {worst}"
    );
    let scene = load_scene(&path, &mut AssetCache::default()).unwrap_or_else(|e| panic!("{e}"));
    let Shape::Mesh(mesh) = &scene.entities[0].shape else {
        panic!("not a mesh")
    };
    assert_eq!(mesh.data.uvs.as_ref().expect("uvs")[0], Vec2::new(0.0, 0.0));
    assert_eq!(
        mesh.data.uvs1.as_ref().expect("uvs1")[0],
        Vec2::new(1.0, 1.0)
    );
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
}

/// Five instances of a triangle: translations along x, rotations about z by k·30°, scales k+1.
fn instanced_file() -> (Value, Vec<(Vec3, Quat, Vec3)>) {
    let instances: Vec<(Vec3, Quat, Vec3)> = (0..5)
        .map(|k| {
            let kf = k as f32;
            (
                Vec3::new(3.0 * kf, 1.0, 0.0),
                Quat::from_rotation_z((30.0 * kf).to_radians()),
                Vec3::splat(kf + 1.0),
            )
        })
        .collect();
    let mut bin = Bin::default();
    let v = bin.f32s(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    let t: Vec<f32> = instances.iter().flat_map(|i| i.0.to_array()).collect();
    let r: Vec<f32> = instances.iter().flat_map(|i| i.1.to_array()).collect();
    let s: Vec<f32> = instances.iter().flat_map(|i| i.2.to_array()).collect();
    let (t, r, s) = (bin.f32s(&t), bin.f32s(&r), bin.f32s(&s));
    let file = doc(
        &bin,
        json!({
            "extensionsUsed": ["EXT_mesh_gpu_instancing"],
            "extensionsRequired": ["EXT_mesh_gpu_instancing"],
            "accessors": [
                {"bufferView": v, "componentType": 5126, "count": 3, "type": "VEC3"},
                {"bufferView": t, "componentType": 5126, "count": 5, "type": "VEC3"},
                {"bufferView": r, "componentType": 5126, "count": 5, "type": "VEC4"},
                {"bufferView": s, "componentType": 5126, "count": 5, "type": "VEC3"},
            ],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
            "nodes": [{"name": "many", "mesh": 0, "translation": [0.0, 0.0, 10.0],
                "extensions": {"EXT_mesh_gpu_instancing": {"attributes": {
                    "TRANSLATION": 1, "ROTATION": 2, "SCALE": 3}}}}],
            "scenes": [{"nodes": [0]}],
        }),
    );
    (file, instances)
}

#[test]
fn gpu_instancing_places_one_mesh_once_per_instance() {
    let dir = temp_dir("gltf-ext-instancing");
    let (file, instances) = instanced_file();
    std::fs::write(dir.join("i.gltf"), file.to_string()).expect("write");
    let path = write_scene(
        &dir,
        "scene.ron",
        r#"Scene(
    camera: Camera(position: (0, 0, -5), look_at: (0, 0, 5), fov: 40),
    settings: Settings(width: 8, height: 8, spp: 1),
    entities: [Entity(name: "g", gltf: "i.gltf")],
)"#,
    );
    let scene = load_scene(&path, &mut AssetCache::default()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.entities.len(), instances.len());
    let names: Vec<&str> = scene.entities.iter().map(|e| e.name.as_str()).collect();
    assert_eq!(
        names,
        ["g/many", "g/many@2", "g/many@3", "g/many@4", "g/many@5"]
    );
    for (e, (t, q, s)) in scene.entities.iter().zip(&instances) {
        // The node's translation, then the instance's T · R · S, by hand: the corner (1, 0, 0)
        // scaled by s, turned by the angle of q about z, moved by t and the node's +10 z.
        let angle = 2.0 * q.z.atan2(q.w);
        let corner = Mat2::from_angle(angle) * Vec2::new(s.x, 0.0);
        let expected = Vec3::new(corner.x, corner.y, 0.0) + *t + Vec3::new(0.0, 0.0, 10.0);
        let got = e.transform.0.transform_point3(Vec3::X);
        assert!(
            (got - expected).length() < 1e-5,
            "{}: {got} against {expected}",
            e.name
        );
    }
    let data = |k: usize| match &scene.entities[k].shape {
        Shape::Mesh(m) => m.data.clone(),
        other => panic!("not a mesh: {other:?}"),
    };
    assert!((1..5).all(|k| std::sync::Arc::ptr_eq(&data(0), &data(k))));
    // Rendered, the five are one bottom-level BVH.
    let mut r = Renderer::new(Some(1), PassPlan::Single).expect("renderer");
    r.load(&path).unwrap_or_else(|e| panic!("{e}"));
    r.render_to_completion();
    assert_eq!(r.counters().mesh_bvh_builds, 1);
}

#[test]
fn bad_instancing_and_transform_values_are_errors_naming_the_field() {
    let dir = temp_dir("gltf-ext-bad");
    let (mut file, _) = instanced_file();
    file["nodes"][0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]["SCALE"] = json!(9);
    std::fs::write(dir.join("i.gltf"), file.to_string()).expect("write");
    let path = write_scene(
        &dir,
        "scene.ron",
        r#"Scene(camera: Camera(position: (0, 0, -5), look_at: (0, 0, 5), fov: 40),
    entities: [Entity(name: "g", gltf: "i.gltf")])"#,
    );
    let e = load_scene(&path, &mut AssetCache::default())
        .expect_err("refused")
        .to_string();
    assert!(
        e.contains("i.gltf") && e.contains("EXT_mesh_gpu_instancing") && e.contains("SCALE"),
        "{e}"
    );
    let material = json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": 0,
        "extensions": {"KHR_texture_transform": {"scale": [1.0, "x"]}}}}});
    let path = write_quad(&dir, "bad.gltf", &quad_file(material));
    let e = load_scene(&path, &mut AssetCache::default())
        .expect_err("refused")
        .to_string();
    assert!(
        e.contains("bad.gltf")
            && e.contains("baseColorTexture")
            && e.contains("KHR_texture_transform.scale"),
        "{e}"
    );
}

#[test]
fn a_blended_surface_passes_one_minus_alpha_of_the_light_behind_it() {
    let dir = temp_dir("gltf-ext-blend");
    let alpha = 0.3;
    let mut bin = Bin::default();
    let v = bin.f32s(&[
        -1.0, -1.0, 0.0, 1.0, -1.0, 0.0, 1.0, 1.0, 0.0, -1.0, 1.0, 0.0,
    ]);
    let i = bin.u16s(&[0, 1, 2, 0, 2, 3]);
    // A black veil: what it reflects towards the camera is the black background, so all the
    // camera sees is the lamp behind it, through it.
    let file = doc(
        &bin,
        json!({
            "accessors": [
                {"bufferView": v, "componentType": 5126, "count": 4, "type": "VEC3"},
                {"bufferView": i, "componentType": 5123, "count": 6, "type": "SCALAR"},
            ],
            "materials": [{"name": "veil", "alphaMode": "BLEND",
                "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, alpha], "metallicFactor": 0.0}}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
            "nodes": [{"name": "veil", "mesh": 0}],
            "scenes": [{"nodes": [0]}],
        }),
    );
    std::fs::write(dir.join("veil.gltf"), file.to_string()).expect("write");
    for method in ["Naive", "Mis"] {
        let path = write_scene(
            &dir,
            &format!("{method}.ron"),
            &format!(
                r#"Scene(
    camera: {},
    settings: Settings(width: 32, height: 32, spp: 16, max_depth: 3, method: {method}, sampler: Independent),
    materials: {{ "lamp": Light(emit: Constant((1, 1, 1))) }},
    entities: [
        Entity(name: "v", gltf: "veil.gltf"),
        Entity(material: "lamp", shape: Quad(a: (-4, -4, -1), b: (4, -4, -1), c: (4, 4, -1), d: (-4, 4, -1))),
    ],
)"#,
                point_camera("(0, 0, 2)", "(0, 0, 0)", "(0, 1, 0)")
            ),
        );
        let r = render(&path, Overrides::default(), None);
        let (mean, se) = point_estimate(&r);
        let expected = 1.0 - alpha;
        assert!(se > 0.0 && se < 0.01, "{method}: se {se}");
        assert!(
            within(mean, se, expected, 3.0),
            "{method}: {mean} ± {se} against {expected}"
        );
    }
}

#[test]
fn shadow_rays_pass_a_blended_surface_with_probability_one_minus_alpha() {
    // A white floor lit by a lamp above, a black veil of alpha 0.4 between them, the camera
    // under the veil: at depth 2 the floor sees only the lamp's direct light, all of it through
    // the veil (shadow rays and, under MIS, bounce rays), so the floor's radiance with the veil
    // is 1 − alpha times that without it.
    let dir = temp_dir("gltf-ext-shadow");
    let alpha = 0.4;
    let mut bin = Bin::default();
    let v = bin.f32s(&[
        -1.0, -1.0, 0.0, 1.0, -1.0, 0.0, 1.0, 1.0, 0.0, -1.0, 1.0, 0.0,
    ]);
    let i = bin.u16s(&[0, 1, 2, 0, 2, 3]);
    let file = doc(
        &bin,
        json!({
            "accessors": [
                {"bufferView": v, "componentType": 5126, "count": 4, "type": "VEC3"},
                {"bufferView": i, "componentType": 5123, "count": 6, "type": "SCALAR"},
            ],
            "materials": [{"name": "veil", "alphaMode": "BLEND",
                "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, alpha], "metallicFactor": 0.0}}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
            "nodes": [{"name": "veil", "mesh": 0, "scale": [6.0, 6.0, 1.0]}],
            "scenes": [{"nodes": [0]}],
        }),
    );
    std::fs::write(dir.join("veil.gltf"), file.to_string()).expect("write");
    for method in ["Nee", "Mis"] {
        let estimate = |veil: bool| {
            let veil = if veil {
                r#"Entity(name: "v", gltf: "veil.gltf", transform: Transform(translate: (0, 0, 1))),"#
            } else {
                ""
            };
            let path = write_scene(
                &dir,
                &format!("{method}-{}.ron", !veil.is_empty()),
                &format!(
                    r#"Scene(
    camera: {},
    settings: Settings(width: 32, height: 32, spp: 64, max_depth: 2, method: {method}, sampler: Independent),
    materials: {{ "lamp": Light(emit: Constant((1, 1, 1))), "floor": Diffuse(albedo: Constant((1, 1, 1))) }},
    entities: [
        {veil}
        Entity(material: "floor", shape: Quad(a: (-4, -4, 0), b: (4, -4, 0), c: (4, 4, 0), d: (-4, 4, 0))),
        Entity(material: "lamp", shape: Quad(a: (-1, -1, 2), b: (-1, 1, 2), c: (1, 1, 2), d: (1, -1, 2))),
    ],
)"#,
                    point_camera("(0, 0, 0.5)", "(0, 0, 0)", "(0, 1, 0)")
                ),
            );
            point_estimate(&render(&path, Overrides::default(), None))
        };
        let ((with, se_with), (without, se_without)) = (estimate(true), estimate(false));
        let ratio = with / without;
        let se = ratio * ((se_with / with).powi(2) + (se_without / without).powi(2)).sqrt();
        let expected = 1.0 - alpha;
        assert!(se < 0.02, "{method}: se {se}");
        assert!(
            within(ratio, se, expected, 3.0),
            "{method}: {ratio} ± {se} against {expected}"
        );
    }
}

#[test]
fn unsupported_extensions_warn_what_will_look_wrong() {
    let dir = temp_dir("gltf-ext-warn");
    let material = json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}});
    let mut file = quad_file(material);
    file["extensionsUsed"] = json!([
        "KHR_materials_iridescence",
        "KHR_materials_anisotropy",
        "KHR_texture_transform"
    ]);
    let path = write_quad(&dir, "w.gltf", &file);
    let scene = load_scene(&path, &mut AssetCache::default()).unwrap_or_else(|e| panic!("{e}"));
    let warning = |ext: &str| {
        scene
            .warnings
            .iter()
            .find(|w| w.contains(ext))
            .unwrap_or_else(|| panic!("no warning for {ext}: {:?}", scene.warnings))
            .clone()
    };
    assert!(warning("KHR_materials_iridescence").contains("thin-film"));
    assert!(warning("KHR_materials_anisotropy").contains("brushed highlights"));
    assert!(
        scene
            .warnings
            .iter()
            .all(|w| !w.contains("KHR_texture_transform"))
    );
}
