//! glTF files placed in RON scenes (`Entity(name, gltf, transform, materials)`): names,
//! transforms, instancing, materials and textures, on small files written here. Expected values
//! come from the files by hand, never from rondo's output.

mod common;

use std::path::{Path, PathBuf};

use common::gltf_doc::{Bin, doc, glb};
use common::{temp_dir, write_scene};
use glam::{Vec2, Vec3};
use rondo::scene::assets::AssetCache;
use rondo::scene::load::load_scene;
use rondo::shading::material::Material;
use rondo::shading::texture::{Texture, srgb_to_linear};
use rondo::{Overrides, PassPlan, Renderer, Shape};
use serde_json::{Value, json};

const TRIANGLE: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];

/// A file with mesh 0 (one triangle, material "Red") used by nodes "a" (translated by +x) and an
/// unnamed node 1 (scaled by 2), and mesh 1 (two primitives: an unnamed material and none) on
/// node "multi".
fn two_meshes() -> Value {
    let mut bin = Bin::default();
    let v = bin.f32s(&TRIANGLE);
    doc(
        &bin,
        json!({
            "accessors": [{"bufferView": v, "componentType": 5126, "count": 3, "type": "VEC3"}],
            "materials": [
                {"name": "Red", "pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.0, 0.0, 1.0], "metallicFactor": 0.25, "roughnessFactor": 0.5}},
                {"pbrMetallicRoughness": {"metallicFactor": 0.0}},
            ],
            "meshes": [
                {"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]},
                {"primitives": [
                    {"attributes": {"POSITION": 0}, "material": 1},
                    {"attributes": {"POSITION": 0}},
                ]},
            ],
            "nodes": [
                {"name": "a", "mesh": 0, "translation": [1.0, 0.0, 0.0]},
                {"mesh": 0, "scale": [2.0, 2.0, 2.0]},
                {"name": "multi", "mesh": 1},
            ],
            "scenes": [{"nodes": [0, 1, 2]}],
        }),
    )
}

/// A scene placing `model` as `g`, moved by +5 along z, with `materials` mapping its names.
fn placing(model: &str, materials: &str) -> String {
    format!(
        r#"Scene(
    camera: Camera(position: (0, 0, -5), look_at: (0, 0, 5), fov: 40),
    settings: Settings(width: 8, height: 8, spp: 1),
    materials: {{ "mine": Diffuse(albedo: Constant((0, 1, 0))) }},
    entities: [
        Entity(name: "g", gltf: "{model}",
               transform: Transform(translate: (0, 0, 5)),
               materials: {materials}),
    ],
)"#
    )
}

#[test]
fn nodes_become_named_placed_entities_sharing_their_meshes() {
    let dir = temp_dir("gltf-place");
    std::fs::write(dir.join("m.gltf"), two_meshes().to_string()).expect("write");
    let path = write_scene(
        &dir,
        "scene.ron",
        &placing("m.gltf", r##"{ "#1": "mine" }"##),
    );
    let scene = load_scene(&path, &mut AssetCache::default()).unwrap_or_else(|e| panic!("{e}"));
    let names: Vec<&str> = scene.entities.iter().map(|e| e.name.as_str()).collect();
    assert_eq!(names, ["g/a", "g/#1", "g/multi/0", "g/multi/1"]);

    // Node transforms composed with the placement's, by hand.
    let world = |k: usize, p: Vec3| scene.entities[k].transform.0.transform_point3(p);
    assert!((world(0, Vec3::ZERO) - Vec3::new(1.0, 0.0, 5.0)).length() < 1e-6);
    assert!((world(1, Vec3::X) - Vec3::new(2.0, 0.0, 5.0)).length() < 1e-6);
    assert!((world(2, Vec3::Y) - Vec3::new(0.0, 1.0, 5.0)).length() < 1e-6);

    // One mesh on two nodes is one loaded mesh.
    let data = |k: usize| match &scene.entities[k].shape {
        Shape::Mesh(m) => m.data.clone(),
        other => panic!("not a mesh: {other:?}"),
    };
    assert!(std::sync::Arc::ptr_eq(&data(0), &data(1)));
    assert!(!std::sync::Arc::ptr_eq(&data(0), &data(2)));

    // "Red" keeps the file's factors; "#1" is mapped to the scene's; no material is the
    // spec's default (white, metallic 1, roughness 1).
    let material = |k: usize| &scene.materials[&scene.entities[k].material];
    match material(0) {
        Material::Pbr {
            base_color: Texture::Constant(c),
            metallic,
            roughness,
            ..
        } => assert_eq!((*c, *metallic, *roughness), (Vec3::X, 0.25, 0.5)),
        other => panic!("{other:?}"),
    }
    assert_eq!(scene.entities[2].material, "mine");
    match material(3) {
        Material::Pbr {
            base_color: Texture::Constant(c),
            metallic,
            roughness,
            ..
        } => assert_eq!((*c, *metallic, *roughness), (Vec3::ONE, 1.0, 1.0)),
        other => panic!("{other:?}"),
    }
    assert!(scene.dependencies.iter().any(|d| d.ends_with("m.gltf")));

    // Rendered, the mesh used by two nodes is one bottom-level BVH (two meshes, three
    // distinct data: mesh 1's primitives are two).
    let mut r = Renderer::new(Some(1), PassPlan::Single).expect("renderer");
    r.load(&path).unwrap_or_else(|e| panic!("{e}"));
    r.render_to_completion();
    assert_eq!(r.counters().mesh_bvh_builds, 3);
}

#[test]
fn placement_errors_name_the_file_the_line_and_the_problem() {
    let dir = temp_dir("gltf-errors");
    std::fs::write(dir.join("m.gltf"), two_meshes().to_string()).expect("write");
    let error = |name: &str, text: &str| {
        let path = write_scene(&dir, name, text);
        load_scene(&path, &mut AssetCache::default())
            .expect_err("must fail")
            .to_string()
    };
    let e = error("unknown.ron", &placing("m.gltf", r#"{ "Blue": "mine" }"#));
    assert!(
        e.contains("unknown.ron:8:") && e.contains("\"Blue\""),
        "{e}"
    );
    assert!(e.contains("Red, #1"), "lists the file's materials: {e}");
    let e = error("ours.ron", &placing("m.gltf", r#"{ "Red": "nope" }"#));
    assert!(
        e.contains("ours.ron:8:") && e.contains("unknown material \"nope\""),
        "{e}"
    );
    let e = error("missing.ron", &placing("gone.glb", "{}"));
    assert!(e.contains("missing.ron:") && e.contains("gone.glb"), "{e}");
    let both = placing("m.gltf", "{}").replace(
        r#"gltf: "m.gltf","#,
        r#"gltf: "m.gltf", shape: Sphere(center: (0, 0, 0), radius: 1),"#,
    );
    let e = error("both.ron", &both);
    assert!(e.contains("not several"), "{e}");
    // A broken glTF file names itself and what is wrong.
    std::fs::write(dir.join("bad.gltf"), "{ not json").expect("write");
    let e = error("bad.ron", &placing("bad.gltf", "{}"));
    assert!(e.contains("bad.gltf") && e.contains("invalid JSON"), "{e}");
}

/// The top-left, top-right, bottom-left and bottom-right texels of the 2×2 test texture.
const TEXELS: [[u8; 3]; 4] = [[255, 0, 0], [0, 255, 0], [0, 0, 255], [128, 64, 32]];

fn texture_png() -> Vec<u8> {
    let image = image::RgbImage::from_fn(2, 2, |x, y| image::Rgb(TEXELS[(y * 2 + x) as usize]));
    let mut png = Vec::new();
    image
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .expect("encode");
    png
}

/// A quad over [−1, 1]² at z = 0 facing +z, with glTF texture coordinates (v down the image:
/// the corner (−1, 1) is the image's top-left), a dielectric (metallic 0) material textured by
/// image 0 with filter `mag_filter`, and that image from `image`.
fn textured_quad(bin: &mut Bin, mag_filter: u32, image: Value) -> Value {
    let v = bin.f32s(&[
        -1.0, -1.0, 0.0, 1.0, -1.0, 0.0, 1.0, 1.0, 0.0, -1.0, 1.0, 0.0,
    ]);
    let uv = bin.f32s(&[0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0]);
    let i = bin.u16s(&[0, 1, 2, 0, 2, 3]);
    json!({
        "accessors": [
            {"bufferView": v, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": uv, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": i, "componentType": 5123, "count": 6, "type": "SCALAR"},
        ],
        "images": [image],
        "samplers": [{"magFilter": mag_filter, "minFilter": mag_filter, "wrapS": 33071, "wrapT": 33071}],
        "textures": [{"source": 0, "sampler": 0}],
        "materials": [{"name": "tex", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}]}],
        "nodes": [{"name": "quad", "mesh": 0}],
        "scenes": [{"nodes": [0]}],
    })
}

/// The albedo feature buffer of a 32×32 view of the quad in `model` from (0, 0, 2).
fn albedo_of_quad(dir: &Path, model: &str) -> Vec<Vec3> {
    let path = write_scene(
        dir,
        &format!("{model}.ron"),
        &format!(
            r#"Scene(
    camera: Camera(position: (0, 0, 2), look_at: (0, 0, 0), fov: 40),
    settings: Settings(width: 32, height: 32, spp: 64, max_depth: 2, method: Naive),
    entities: [Entity(name: "m", gltf: "{model}")],
)"#
        ),
    );
    let mut r = Renderer::new(None, PassPlan::Single).expect("renderer");
    r.set_features(true);
    r.set_overrides(Overrides::default());
    r.load(&path).unwrap_or_else(|e| panic!("{e}"));
    r.render_to_completion();
    let film = r.film();
    let f = film.features.as_ref().expect("features");
    f.albedo_mean(film.count())
}

/// The texture at glTF coordinates `(u, v)` (v down the image), decoded from sRGB and filtered
/// as glTF's LINEAR with clamping: between texel centres, written out here independently.
fn bilinear(u: f32, v: f32) -> Vec3 {
    let texel = |i: i32, j: i32| {
        let (i, j) = (i.clamp(0, 1), j.clamp(0, 1));
        Vec3::from(TEXELS[(j * 2 + i) as usize].map(|b| srgb_to_linear(f32::from(b) / 255.0)))
    };
    let (x, y) = (u * 2.0 - 0.5, v * 2.0 - 0.5);
    let (i, j) = (x.floor(), y.floor());
    let (tx, ty) = (x - i, y - j);
    let (i, j) = (i as i32, j as i32);
    let top = texel(i, j) * (1.0 - tx) + texel(i + 1, j) * tx;
    let bottom = texel(i, j + 1) * (1.0 - tx) + texel(i + 1, j + 1) * tx;
    top * (1.0 - ty) + bottom * ty
}

/// The glTF texture coordinates seen at the centre of pixel `(x, y)` of the 32×32 view: the
/// view's half-width at z = 0 is 2·tan 20°.
fn uv_at(x: usize, y: usize) -> Vec2 {
    let half = 2.0 * 20f32.to_radians().tan();
    let px = (2.0 * (x as f32 + 0.5) / 32.0 - 1.0) * half;
    let py = (1.0 - 2.0 * (y as f32 + 0.5) / 32.0) * half;
    Vec2::new((px + 1.0) / 2.0, (1.0 - py) / 2.0)
}

#[test]
fn a_textured_quad_shows_its_texture_bilinearly_filtered() {
    let dir = temp_dir("gltf-texture");
    std::fs::write(dir.join("t.png"), texture_png()).expect("write");
    let mut bin = Bin::default();
    let parts = textured_quad(&mut bin, 9729, json!({"uri": "t.png"}));
    std::fs::write(dir.join("quad.gltf"), doc(&bin, parts).to_string()).expect("write");
    let albedo = albedo_of_quad(&dir, "quad.gltf");
    // The pixel's mean of a bilinear function over its square is the value at its centre.
    let mut worst = 0.0f32;
    for y in 0..32 {
        for x in 0..32 {
            let uv = uv_at(x, y);
            let expected = bilinear(uv.x, uv.y);
            worst = worst.max((albedo[y * 32 + x] - expected).abs().max_element());
        }
    }
    assert!(worst < 2e-3, "largest difference {worst}");
}

#[test]
fn a_glb_with_an_embedded_image_shows_its_texels() {
    let dir = temp_dir("gltf-glb");
    let mut bin = Bin::default();
    let png = bin.view(texture_png());
    let parts = textured_quad(
        &mut bin,
        9728,
        json!({"bufferView": png, "mimeType": "image/png"}),
    );
    std::fs::write(dir.join("quad.glb"), glb(&bin, parts)).expect("write");
    let albedo = albedo_of_quad(&dir, "quad.glb");
    // Nearest texels: each quadrant of the view is one texel (pixels on the centre lines mix).
    for y in (0..32).filter(|y| !(15..=16).contains(y)) {
        for x in (0..32).filter(|x| !(15..=16).contains(x)) {
            let texel = usize::from(y >= 16) * 2 + usize::from(x >= 16);
            let expected = Vec3::from(TEXELS[texel].map(|b| srgb_to_linear(f32::from(b) / 255.0)));
            let got = albedo[y * 32 + x];
            assert!(
                (got - expected).abs().max_element() < 1e-5,
                "pixel ({x}, {y}): {got} against {expected}"
            );
        }
    }
}

/// Paths of `scene`'s dependencies, relative to `dir`.
fn relative(dir: &Path, deps: &[PathBuf]) -> Vec<String> {
    deps.iter()
        .map(|d| {
            d.strip_prefix(dir)
                .unwrap_or(d)
                .to_string_lossy()
                .into_owned()
        })
        .collect()
}

#[test]
fn external_buffers_and_images_are_dependencies() {
    let dir = temp_dir("gltf-deps");
    std::fs::write(dir.join("t.png"), texture_png()).expect("write");
    let mut bin = Bin::default();
    let parts = textured_quad(&mut bin, 9729, json!({"uri": "t.png"}));
    let mut d = doc(&bin, parts);
    d["buffers"][0]["uri"] = json!("quad.bin");
    std::fs::write(dir.join("quad.bin"), &bin.bytes).expect("write");
    std::fs::write(dir.join("quad.gltf"), d.to_string()).expect("write");
    let path = write_scene(
        &dir,
        "scene.ron",
        r#"Scene(camera: Camera(position: (0, 0, 2), look_at: (0, 0, 0)),
                 entities: [Entity(name: "m", gltf: "quad.gltf")])"#,
    );
    let mut assets = AssetCache::default();
    let scene = load_scene(&path, &mut assets).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        relative(&dir, &scene.dependencies),
        ["scene.ron", "quad.gltf", "quad.bin", "t.png"]
    );
    // Unchanged files are not read into a new mesh; a changed buffer is.
    let loads = assets.mesh_loads();
    load_scene(&path, &mut assets).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(assets.mesh_loads(), loads);
    let mut moved = bin.bytes.clone();
    moved[0..4].copy_from_slice(&(-2.0f32).to_le_bytes());
    std::fs::write(dir.join("quad.bin"), moved).expect("write");
    load_scene(&path, &mut assets).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(assets.mesh_loads(), loads + 1);
}

#[test]
fn masks_blend_transmission_cameras_and_lights_load_as_documented() {
    let dir = temp_dir("gltf-kinds");
    let mut bin = Bin::default();
    let v = bin.f32s(&TRIANGLE);
    let mut parts = json!({
        "extensionsUsed": ["KHR_materials_transmission", "KHR_materials_ior", "KHR_lights_punctual"],
        "accessors": [{"bufferView": v, "componentType": 5126, "count": 3, "type": "VEC3"}],
        "materials": [
            {"name": "leaf", "alphaMode": "MASK", "alphaCutoff": 0.3,
             "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 0.8]}},
            {"name": "veil", "alphaMode": "BLEND"},
            {"name": "glass", "pbrMetallicRoughness": {"metallicFactor": 0.0, "roughnessFactor": 0.0},
             "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0},
                            "KHR_materials_ior": {"ior": 1.33}}},
        ],
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]},
            {"primitives": [{"attributes": {"POSITION": 0}, "material": 1}]},
            {"primitives": [{"attributes": {"POSITION": 0}, "material": 2}]},
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}],
        "nodes": [{"name": "l", "mesh": 0}, {"name": "v", "mesh": 1}, {"name": "g", "mesh": 2}],
        "scenes": [{"nodes": [0, 1, 2]}],
    });
    parts["nodes"][0]["camera"] = json!(0);
    std::fs::write(dir.join("k.gltf"), doc(&bin, parts).to_string()).expect("write");
    let path = write_scene(&dir, "scene.ron", &placing("k.gltf", "{}"));
    let scene = load_scene(&path, &mut AssetCache::default()).unwrap_or_else(|e| panic!("{e}"));
    let material = |k: usize| &scene.materials[&scene.entities[k].material];
    let alpha = |k: usize| match material(k) {
        Material::Pbr { alpha, .. } => alpha.clone().map(|a| (a.cutoff, a.factor)),
        other => panic!("{other:?}"),
    };
    assert_eq!(
        alpha(0),
        Some((Some(0.3), 0.8)),
        "MASK keeps its cutoff and factor"
    );
    assert_eq!(alpha(1), Some((None, 1.0)), "BLEND is blended, no cutoff");
    assert_eq!(material(2), &Material::glass(1.33));
    assert!(scene.warnings.iter().all(|w| w.contains("k.gltf")));
}

#[test]
fn hostile_gltf_placements_never_panic() {
    let dir = temp_dir("gltf-fuzz");
    let mut bin = Bin::default();
    let png = bin.view(texture_png());
    let parts = textured_quad(
        &mut bin,
        9729,
        json!({"bufferView": png, "mimeType": "image/png"}),
    );
    let good = glb(&bin, parts);
    let path = write_scene(
        &dir,
        "scene.ron",
        r#"Scene(camera: Camera(position: (0, 0, 2), look_at: (0, 0, 0)),
                 entities: [Entity(name: "m", gltf: "m.glb")])"#,
    );
    let mut rng = rondo::shading::rng::Rng::new(23, 5);
    let (mut loaded, mut refused) = (0, 0);
    for round in 0..3000 {
        let mut bytes = good.clone();
        match round % 3 {
            0 => bytes.truncate(rng.next_u32() as usize % good.len()),
            _ => {
                for _ in 0..1 + rng.next_u32() % 8 {
                    let at = rng.next_u32() as usize % bytes.len();
                    bytes[at] = rng.next_u32() as u8;
                }
            }
        }
        std::fs::write(dir.join("m.glb"), &bytes).expect("write");
        // A fresh cache: every round decodes its images.
        match load_scene(&path, &mut AssetCache::default()) {
            Ok(_) => loaded += 1,
            Err(e) => {
                assert!(e.to_string().contains("m.glb"), "{e}");
                refused += 1;
            }
        }
    }
    assert!(
        loaded > 0 && refused > 0,
        "{loaded} loaded, {refused} refused"
    );
}

/// Every path to a value inside `v` (object keys and array indices).
fn paths(v: &Value, at: Vec<Value>, out: &mut Vec<Vec<Value>>) {
    match v {
        Value::Object(m) => {
            for (k, c) in m {
                let mut p = at.clone();
                p.push(json!(k));
                out.push(p.clone());
                paths(c, p, out);
            }
        }
        Value::Array(a) => {
            for (i, c) in a.iter().enumerate() {
                let mut p = at.clone();
                p.push(json!(i));
                out.push(p.clone());
                paths(c, p, out);
            }
        }
        _ => {}
    }
}

/// `v` with the value at `path` removed (`None`) or replaced.
fn edited(v: &Value, path: &[Value], with: Option<Value>) -> Value {
    let mut v = v.clone();
    let mut slot = &mut v;
    for key in &path[..path.len() - 1] {
        slot = match key {
            Value::String(k) => &mut slot[k.as_str()],
            _ => &mut slot[key.as_u64().unwrap_or_default() as usize],
        };
    }
    let last = &path[path.len() - 1];
    match (slot, last, with) {
        (Value::Object(m), Value::String(k), None) => {
            m.remove(k);
        }
        (Value::Array(a), _, None) => {
            a.remove(last.as_u64().unwrap_or_default() as usize);
        }
        (slot, Value::String(k), Some(w)) => slot[k.as_str()] = w,
        (slot, _, Some(w)) => slot[last.as_u64().unwrap_or_default() as usize] = w,
        _ => {}
    }
    v
}

#[test]
fn every_field_removed_or_replaced_loads_or_is_refused() {
    let dir = temp_dir("gltf-fields");
    let mut bin = Bin::default();
    let png = bin.view(texture_png());
    let mut parts = textured_quad(
        &mut bin,
        9729,
        json!({"bufferView": png, "mimeType": "image/png"}),
    );
    parts["materials"][0]["normalTexture"] = json!({"index": 0, "scale": 0.5});
    parts["materials"][0]["alphaMode"] = json!("MASK");
    let path = write_scene(
        &dir,
        "scene.ron",
        r#"Scene(camera: Camera(position: (0, 0, 2), look_at: (0, 0, 0)),
                 entities: [Entity(name: "m", gltf: "m.gltf")])"#,
    );
    let document = doc(&bin, parts);
    let mut all = Vec::new();
    paths(&document, Vec::new(), &mut all);
    let replacements = [
        None,
        Some(json!(-1)),
        Some(json!(1e10)),
        Some(json!(4_294_967_295u64)),
        Some(json!("x")),
        Some(json!([])),
    ];
    let mut refused = 0;
    for p in &all {
        for with in &replacements {
            let text = edited(&document, p, with.clone()).to_string();
            std::fs::write(dir.join("m.gltf"), text).expect("write");
            if let Err(e) = load_scene(&path, &mut AssetCache::default()) {
                assert!(e.to_string().contains("m.gltf"), "{p:?}: {e}");
                refused += 1;
            }
        }
    }
    assert!(
        refused > all.len(),
        "{refused} of {} edits refused",
        6 * all.len()
    );
}

#[test]
fn an_embedded_jpeg_is_read() {
    let dir = temp_dir("gltf-jpeg");
    let mut jpeg = Vec::new();
    image::RgbImage::from_pixel(8, 8, image::Rgb([200, 100, 50]))
        .write_to(
            &mut std::io::Cursor::new(&mut jpeg),
            image::ImageFormat::Jpeg,
        )
        .expect("encode");
    let mut bin = Bin::default();
    let view = bin.view(jpeg);
    let parts = textured_quad(
        &mut bin,
        9728,
        json!({"bufferView": view, "mimeType": "image/jpeg"}),
    );
    std::fs::write(dir.join("quad.glb"), glb(&bin, parts)).expect("write");
    let albedo = albedo_of_quad(&dir, "quad.glb");
    // A flat colour survives JPEG within a step or two of 255.
    let expected = Vec3::new(200.0, 100.0, 50.0).map(|b| srgb_to_linear(b / 255.0));
    let got = albedo[16 * 32 + 16];
    assert!(
        (got - expected).abs().max_element() < 0.01,
        "{got} against {expected}"
    );
}

/// The names of the entities `model` (written as `m.gltf`) becomes, placed as `g`.
fn entity_names(dir: &Path, model: &Value) -> Result<Vec<String>, String> {
    std::fs::write(dir.join("m.gltf"), model.to_string()).expect("write");
    let path = write_scene(dir, "scene.ron", &placing("m.gltf", "{}"));
    let scene = load_scene(&path, &mut AssetCache::default()).map_err(|e| e.to_string())?;
    Ok(scene.entities.into_iter().map(|e| e.name).collect())
}

#[test]
fn generated_names_are_unique_whatever_the_nodes_are_called() {
    let dir = temp_dir("gltf-names");
    let mut model = two_meshes();
    // Node 3 is named like unnamed node 1's label, node 4 like node "multi"'s first primitive,
    // node 5 like the second instance of node 6, which is reached twice.
    model["nodes"] = json!([
        {"name": "a", "mesh": 0},
        {"mesh": 0},
        {"name": "multi", "mesh": 1},
        {"name": "#1", "mesh": 0},
        {"name": "multi/0", "mesh": 0},
        {"name": "y@2", "mesh": 0},
        {"name": "y", "mesh": 0},
        {"name": "parent", "children": [6]},
    ]);
    model["scenes"] = json!([{"nodes": [0, 1, 2, 3, 4, 5, 6, 7]}]);
    let names = entity_names(&dir, &model).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        names,
        [
            "g/a",
            "g/#1",
            "g/multi/0",
            "g/multi/1",
            "g/#3",
            "g/#4",
            "g/#5",
            "g/y",
            "g/y@2",
        ]
    );
    // Every name appears once; the file's 9 placed primitives give 9 entities.
    let distinct: std::collections::HashSet<&String> = names.iter().collect();
    assert_eq!(distinct.len(), 9);

    // A material named "#1" beside unnamed material 1: two materials, not one under one name.
    let mut model = two_meshes();
    model["materials"][0]["name"] = json!("#1");
    std::fs::write(dir.join("m.gltf"), model.to_string()).expect("write");
    let path = write_scene(&dir, "scene.ron", &placing("m.gltf", "{}"));
    let scene = load_scene(&path, &mut AssetCache::default()).unwrap_or_else(|e| panic!("{e}"));
    let metallic = |name: &str| {
        let e = scene.entities.iter().find(|e| e.name == name).expect(name);
        match &scene.materials[&e.material] {
            Material::Pbr { metallic, .. } => *metallic,
            other => panic!("{other:?}"),
        }
    };
    // Node "a" uses material 0 (metallic 0.25), "multi"'s first primitive material 1 (0).
    assert_eq!((metallic("g/a"), metallic("g/multi/0")), (0.25, 0.0));
}

#[test]
fn buffers_and_images_reached_through_symlinks_out_of_the_folder_are_refused() {
    let root = temp_dir("gltf-symlink");
    let (outside, model) = (root.join("outside"), root.join("model"));
    std::fs::create_dir_all(&outside).expect("mkdir");
    std::fs::create_dir_all(&model).expect("mkdir");
    let mut bin = Bin::default();
    let parts = textured_quad(&mut bin, 9729, json!({"uri": "t.png"}));
    let mut d = doc(&bin, parts);
    d["buffers"][0]["uri"] = json!("quad.bin");
    std::fs::write(model.join("quad.gltf"), d.to_string()).expect("write");
    std::fs::write(outside.join("quad.bin"), &bin.bytes).expect("write");
    std::fs::write(outside.join("t.png"), texture_png()).expect("write");
    let scene = write_scene(
        &root,
        "scene.ron",
        r#"Scene(camera: Camera(position: (0, 0, 2), look_at: (0, 0, 0)),
                 entities: [Entity(name: "m", gltf: "model/quad.gltf")])"#,
    );
    let load = || load_scene(&scene, &mut AssetCache::default()).map_err(|e| e.to_string());
    // Both files inside the folder: the model loads.
    for name in ["quad.bin", "t.png"] {
        std::fs::copy(outside.join(name), model.join(name)).expect("copy");
    }
    load().unwrap_or_else(|e| panic!("{e}"));
    // The buffer a symlink to a file outside.
    std::fs::remove_file(model.join("quad.bin")).expect("rm");
    std::os::unix::fs::symlink(outside.join("quad.bin"), model.join("quad.bin")).expect("ln");
    let e = load().expect_err("buffer outside");
    assert!(
        e.contains("quad.gltf")
            && e.contains("buffer 0")
            && e.contains("outside the glTF file's folder"),
        "{e}"
    );
    // The image a symlink to a file outside (through a symlinked folder), the buffer inside.
    std::fs::remove_file(model.join("quad.bin")).expect("rm");
    std::fs::write(model.join("quad.bin"), &bin.bytes).expect("write");
    std::fs::remove_file(model.join("t.png")).expect("rm");
    std::os::unix::fs::symlink(&outside, model.join("linked")).expect("ln");
    d["images"][0]["uri"] = json!("linked/t.png");
    std::fs::write(model.join("quad.gltf"), d.to_string()).expect("write");
    let e = load().expect_err("image outside");
    assert!(
        e.contains("t.png") && e.contains("outside the glTF file's folder"),
        "{e}"
    );
    // A symlink that stays inside the folder is followed.
    std::fs::create_dir_all(model.join("real")).expect("mkdir");
    std::fs::write(model.join("real/t.png"), texture_png()).expect("write");
    std::os::unix::fs::symlink(model.join("real"), model.join("inner")).expect("ln");
    d["images"][0]["uri"] = json!("inner/t.png");
    std::fs::write(model.join("quad.gltf"), d.to_string()).expect("write");
    load().unwrap_or_else(|e| panic!("{e}"));
}
