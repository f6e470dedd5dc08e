//! glTF 2.0 reading (src/scene/gltf.rs) on small files written here: JSON with data-URI or
//! external buffers and `.glb` containers assembled byte by byte. Expected values are computed by
//! hand from the files, never taken from the reader's output.

mod common;

use std::path::Path;

use common::gltf_doc::{Bin, doc, glb};
use common::temp_dir;
use glam::{Vec2, Vec3};
use rondo::scene::gltf::{GltfScene, read_gltf};
use rondo::shading::rng::Rng;
use serde_json::{Value, json};

fn read(doc: &Value) -> Result<GltfScene, String> {
    read_gltf(Path::new("test.gltf"), doc.to_string().as_bytes(), |uri| {
        Err(format!("no external buffers here ({uri})"))
    })
}

const TRIANGLE: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];

/// One unindexed triangle in one mesh on one node.
fn triangle() -> (Bin, Value) {
    let mut bin = Bin::default();
    let v = bin.f32s(&TRIANGLE);
    let parts = json!({
        "accessors": [{"bufferView": v, "componentType": 5126, "count": 3, "type": "VEC3"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "nodes": [{"mesh": 0, "name": "tri"}],
        "scenes": [{"nodes": [0]}],
        "scene": 0,
    });
    (bin, parts)
}

#[test]
fn single_triangle() {
    let (bin, parts) = triangle();
    let scene = read(&doc(&bin, parts)).expect("reads");
    assert_eq!(scene.meshes.len(), 1);
    let data = &scene.meshes[0].primitives[0].data;
    assert_eq!(data.triangles, vec![[0, 1, 2]]);
    assert_eq!(
        data.positions,
        vec![Vec3::ZERO, Vec3::X, Vec3::Y],
        "positions as written"
    );
    assert!(data.normals.is_none(), "no NORMAL: flat shading");
    assert!(data.uvs.is_none());
    assert_eq!(scene.nodes.len(), 1);
    assert_eq!(scene.nodes[0].name.as_deref(), Some("tri"));
    assert_eq!(scene.nodes[0].mesh, Some(0));
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
}

#[test]
fn node_tree_composes_trs_and_matrix() {
    let (bin, mut parts) = triangle();
    let h = std::f32::consts::FRAC_1_SQRT_2;
    parts["nodes"] = json!([
        {"name": "root", "translation": [1.0, 2.0, 3.0], "children": [1]},
        // 90° about +Z, uniform scale 2.
        {"rotation": [0.0, 0.0, h, h], "scale": [2.0, 2.0, 2.0], "children": [2]},
        // A column-major matrix translating by (1, 0, 0).
        {"name": "leaf", "mesh": 0, "matrix": [1.0,0.0,0.0,0.0, 0.0,1.0,0.0,0.0, 0.0,0.0,1.0,0.0, 1.0,0.0,0.0,1.0]},
    ]);
    let scene = read(&doc(&bin, parts)).expect("reads");
    assert_eq!(
        scene.nodes.iter().map(|n| n.index).collect::<Vec<_>>(),
        vec![0, 1, 2]
    );
    let leaf = &scene.nodes[2];
    assert_eq!(leaf.name.as_deref(), Some("leaf"));
    // By hand: (0,0,0) → matrix (1,0,0) → scale (2,0,0) → rotate (0,2,0) → translate (1,4,3);
    // (0,1,0) → (1,1,0) → (2,2,0) → (-2,2,0) → (-1,4,3).
    for (p, want) in [
        (Vec3::ZERO, Vec3::new(1.0, 4.0, 3.0)),
        (Vec3::Y, Vec3::new(-1.0, 4.0, 3.0)),
    ] {
        let got = leaf.world_from_node.transform_point3(p);
        assert!((got - want).length() < 1e-5, "{p} → {got}, want {want}");
    }
    let root = scene.nodes[0].world_from_node.transform_point3(Vec3::ZERO);
    assert!((root - Vec3::new(1.0, 2.0, 3.0)).length() < 1e-6);
}

#[test]
fn mesh_used_by_two_nodes_is_one_mesh() {
    let (bin, mut parts) = triangle();
    parts["nodes"] = json!([
        {"mesh": 0, "translation": [-2.0, 0.0, 0.0]},
        {"mesh": 0, "translation": [2.0, 0.0, 0.0]},
    ]);
    parts["scenes"] = json!([{"nodes": [0, 1]}]);
    let scene = read(&doc(&bin, parts)).expect("reads");
    assert_eq!(scene.meshes.len(), 1, "one mesh, read once");
    assert_eq!(scene.nodes.len(), 2);
    assert!(scene.nodes.iter().all(|n| n.mesh == Some(0)));
    let x: Vec<f32> = scene
        .nodes
        .iter()
        .map(|n| n.world_from_node.transform_point3(Vec3::ZERO).x)
        .collect();
    assert_eq!(x, vec![-2.0, 2.0]);
}

/// The normal of triangle `t` (by its winding).
fn normal(p: &[Vec3], t: [u32; 3]) -> Vec3 {
    (p[t[1] as usize] - p[t[0] as usize]).cross(p[t[2] as usize] - p[t[0] as usize])
}

#[test]
fn strips_and_fans_are_converted_with_consistent_winding() {
    // A unit square in the XY plane: a strip 0,1,2,3 and a fan 0,1,3,2 both cover it with two
    // triangles facing +Z.
    let mut bin = Bin::default();
    let v = bin.f32s(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0]);
    let strip = bin.u16s(&[0, 1, 2, 3]);
    let fan = bin.u16s(&[0, 1, 3, 2]);
    let scalar =
        |view| json!({"bufferView": view, "componentType": 5123, "count": 4, "type": "SCALAR"});
    let parts = json!({
        "accessors": [
            {"bufferView": v, "componentType": 5126, "count": 4, "type": "VEC3"},
            scalar(strip),
            scalar(fan),
        ],
        "meshes": [{"primitives": [
            {"attributes": {"POSITION": 0}, "indices": 1, "mode": 5},
            {"attributes": {"POSITION": 0}, "indices": 2, "mode": 6},
            {"attributes": {"POSITION": 0}, "mode": 0},
            {"attributes": {"POSITION": 0}, "indices": 1, "mode": 1},
        ]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
    });
    let scene = read(&doc(&bin, parts)).expect("reads");
    let prims = &scene.meshes[0].primitives;
    assert_eq!(prims.len(), 2, "points and lines skipped");
    assert_eq!(scene.warnings.len(), 2, "{:?}", scene.warnings);
    assert!(scene.warnings[0].contains("mesh 0 primitive 2"));
    // Strip: (0,1,2), (2,1,3); fan: (0,1,3), (0,3,2) — the spec's orders.
    assert_eq!(prims[0].data.triangles, vec![[0, 1, 2], [2, 1, 3]]);
    assert_eq!(prims[1].data.triangles, vec![[0, 1, 3], [0, 3, 2]]);
    for prim in prims {
        for &t in &prim.data.triangles {
            let n = normal(&prim.data.positions, t);
            assert!(n.z > 0.0, "{t:?} faces {n}");
        }
    }
}

#[test]
fn sparse_accessor_replaces_elements() {
    let mut bin = Bin::default();
    let v = bin.f32s(&TRIANGLE);
    let idx = bin.u16s(&[2]);
    let val = bin.f32s(&[0.0, 5.0, 7.0]);
    let sparse = json!({"count": 1, "indices": {"bufferView": idx, "componentType": 5123},
                        "values": {"bufferView": val}});
    let parts = json!({
        "accessors": [
            {"bufferView": v, "componentType": 5126, "count": 3, "type": "VEC3", "sparse": sparse},
            // No buffer view: zeros, then the sparse value.
            {"componentType": 5126, "count": 3, "type": "VEC3", "sparse": sparse},
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}, {"attributes": {"POSITION": 1}}]}],
    });
    let scene = read(&doc(&bin, parts)).expect("reads");
    let p = &scene.meshes[0].primitives;
    assert_eq!(
        p[0].data.positions,
        vec![Vec3::ZERO, Vec3::X, Vec3::new(0.0, 5.0, 7.0)]
    );
    assert_eq!(
        p[1].data.positions,
        vec![Vec3::ZERO, Vec3::ZERO, Vec3::new(0.0, 5.0, 7.0)]
    );
    assert!(scene.nodes.is_empty(), "no scene, no nodes");
}

#[test]
fn normals_and_normalized_integer_texcoords() {
    let mut bin = Bin::default();
    let v = bin.f32s(&TRIANGLE);
    let n = bin.f32s(&[0.0, 0.0, 2.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0]);
    let uv8 = bin.view(vec![0, 0, 255, 0, 0, 255]);
    let uv16 = bin.u16s(&[0, 0, 65535, 0, 32768, 65535]);
    let parts = json!({
        "accessors": [
            {"bufferView": v, "componentType": 5126, "count": 3, "type": "VEC3"},
            {"bufferView": n, "componentType": 5126, "count": 3, "type": "VEC3"},
            {"bufferView": uv8, "componentType": 5121, "normalized": true, "count": 3, "type": "VEC2"},
            {"bufferView": uv16, "componentType": 5123, "normalized": true, "count": 3, "type": "VEC2"},
        ],
        "meshes": [{"primitives": [
            {"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}},
            {"attributes": {"POSITION": 0, "TEXCOORD_0": 3}},
        ]}],
    });
    let scene = read(&doc(&bin, parts)).expect("reads");
    let p = &scene.meshes[0].primitives;
    assert_eq!(p[0].data.normals.as_deref(), Some(&[Vec3::Z; 3][..]));
    // glTF's (u, v) is stored as (u, 1 − v): its v runs down the image, rondo's up.
    assert_eq!(
        p[0].data.uvs.as_deref(),
        Some(&[Vec2::Y, Vec2::ONE, Vec2::ZERO][..])
    );
    let uv = p[1].data.uvs.as_deref().expect("uvs");
    assert_eq!(uv[1], Vec2::ONE);
    assert!((uv[2] - Vec2::new(32768.0 / 65535.0, 0.0)).length() < 1e-7);
}

#[test]
fn materials_and_emissive_strength() {
    let (bin, mut parts) = triangle();
    parts["extensionsUsed"] = json!(["KHR_materials_emissive_strength"]);
    parts["extensionsRequired"] = json!(["KHR_materials_emissive_strength"]);
    parts["meshes"][0]["primitives"][0]["material"] = json!(0);
    parts["materials"] = json!([{
        "name": "Metal",
        "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.25, 1.0, 1.0], "metallicFactor": 0.75,
                                 "roughnessFactor": 0.5, "baseColorTexture": {"index": 0, "texCoord": 0}},
        "emissiveFactor": [1.0, 0.5, 0.0],
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}},
        "alphaMode": "MASK", "alphaCutoff": 0.25,
    }]);
    parts["textures"] = json!([{"source": 0, "sampler": 0}]);
    parts["samplers"] = json!([{"wrapS": 33648, "wrapT": 33071, "magFilter": 9728}]);
    parts["images"] = json!([{"uri": "tex%20ture.png"}]);
    let scene = read(&doc(&bin, parts)).expect("reads");
    assert_eq!(scene.meshes[0].primitives[0].material, Some(0));
    let m = &scene.materials[0];
    assert_eq!(m.name.as_deref(), Some("Metal"));
    assert_eq!(m.base_color_factor, [0.5, 0.25, 1.0, 1.0]);
    assert_eq!((m.metallic, m.roughness), (0.75, 0.5));
    assert_eq!(m.emissive, Vec3::new(4.0, 2.0, 0.0));
    assert_eq!(m.alpha_mode, rondo::scene::gltf::AlphaMode::Mask(0.25));
    let t = m.base_color_texture.as_ref().expect("texture");
    assert_eq!(t.image, 0);
    assert_eq!(t.wrap_s, rondo::scene::gltf::Wrap::MirroredRepeat);
    assert_eq!(t.wrap_t, rondo::scene::gltf::Wrap::ClampToEdge);
    assert!(t.nearest);
    assert_eq!(
        scene.images,
        vec![rondo::scene::gltf::GltfImage::File("tex ture.png".into())]
    );
}

#[test]
fn glb_and_external_buffers() {
    let (bin, parts) = triangle();
    let bytes = glb(&bin, parts.clone());
    let scene = read_gltf(Path::new("t.glb"), &bytes, |_| Err("none".into())).expect("glb reads");
    assert_eq!(
        scene.meshes[0].primitives[0].data.positions,
        vec![Vec3::ZERO, Vec3::X, Vec3::Y]
    );

    let dir = temp_dir("gltf-external");
    std::fs::create_dir_all(dir.join("data")).expect("mkdir");
    std::fs::write(dir.join("data/tri bin.bin"), &bin.bytes).expect("write");
    let mut d = doc(&bin, parts);
    d["buffers"][0]["uri"] = json!("data/tri%20bin.bin");
    let mut asked = Vec::new();
    let scene = read_gltf(Path::new("t.gltf"), d.to_string().as_bytes(), |uri| {
        asked.push(uri.to_owned());
        std::fs::read(dir.join(uri)).map_err(|e| e.to_string())
    })
    .expect("external buffer reads");
    assert_eq!(asked, vec!["data/tri bin.bin".to_string()]);
    assert_eq!(
        scene.meshes[0].primitives[0].data.triangles,
        vec![[0, 1, 2]]
    );
}

/// The error of reading `d`, which must fail.
fn error(d: &Value) -> String {
    read(d).expect_err("must fail")
}

#[test]
fn errors_name_the_file_and_the_problem() {
    let (bin, parts) = triangle();

    let mut d = doc(&bin, parts.clone());
    d["buffers"][0]["uri"] = json!("missing.bin");
    let e = error(&d);
    assert!(
        e.contains("test.gltf") && e.contains("buffer 0") && e.contains("missing.bin"),
        "{e}"
    );

    for uri in [
        "../up.bin",
        "/etc/passwd",
        "file:///etc/passwd",
        "a/../../b.bin",
        "C:\\x.bin",
    ] {
        let mut d = doc(&bin, parts.clone());
        d["buffers"][0]["uri"] = json!(uri);
        let e = error(&d);
        assert!(e.contains("not a relative path"), "{uri}: {e}");
    }

    let mut d = doc(&bin, parts.clone());
    d["accessors"][0]["count"] = json!(4);
    let e = error(&d);
    assert!(
        e.contains("accessor 0") && e.contains("outside buffer view"),
        "{e}"
    );

    let mut d = doc(&bin, parts.clone());
    d["accessors"][0]["byteOffset"] = json!(4);
    assert!(error(&d).contains("accessor 0"));

    let mut d = doc(&bin, parts.clone());
    d["bufferViews"][0]["byteLength"] = json!(1000);
    assert!(error(&d).contains("buffer view 0 outside its buffer"));

    let mut d = doc(&bin, parts.clone());
    d["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
    d["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    let e = error(&d);
    assert!(
        e.contains("unsupported required extension KHR_draco_mesh_compression"),
        "{e}"
    );

    let mut d = doc(&bin, parts.clone());
    d["nodes"][0]["mesh"] = json!(3);
    assert!(error(&d).contains("invalid"));

    let mut d = doc(&bin, parts.clone());
    d["nodes"] = json!([{"children": [1]}, {"children": [0]}]);
    assert!(error(&d).contains("cycle"));

    let mut d = doc(&bin, parts.clone());
    d["materials"] = json!([{"name": "Bad", "emissiveFactor": [1e38, 0.0, 0.0],
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 10.0}}}]);
    let e = error(&d);
    assert!(e.contains("material \"Bad\": non-finite"), "{e}");

    let g = glb(&bin, parts);
    for len in [0, 4, 11, 12, 20, g.len() / 2, g.len() - 1] {
        let e = read_gltf(Path::new("t.glb"), &g[..len], |_| Err("none".into()))
            .expect_err("truncated .glb");
        assert!(e.contains("t.glb"), "{e}");
    }
}

#[test]
fn corrupted_files_never_panic() {
    let (bin, parts) = triangle();
    let mut strip_parts = parts.clone();
    strip_parts["meshes"][0]["primitives"][0]["mode"] = json!(5);
    let files = [
        doc(&bin, parts.clone()).to_string().into_bytes(),
        doc(&bin, strip_parts).to_string().into_bytes(),
        glb(&bin, parts),
    ];
    let mut rng = Rng::new(23, 0);
    let mut outcomes = [0usize; 2];
    for round in 0..20_000 {
        let mut bytes = files[round % files.len()].clone();
        let flips = 1 + (rng.next_f32() * 4.0) as usize;
        for _ in 0..flips {
            let at = (rng.next_f32() * bytes.len() as f32) as usize % bytes.len();
            bytes[at] = match round % 3 {
                0 => (rng.next_f32() * 256.0) as u8,
                1 => b"0123456789-e.[]{}\""[(rng.next_f32() * 18.0) as usize % 18],
                _ => bytes[at] ^ (1 << ((rng.next_f32() * 8.0) as u32 % 8)),
            };
        }
        let result = std::panic::catch_unwind(|| {
            read_gltf(Path::new("f.gltf"), &bytes, |_| Err("none".into())).is_ok()
        });
        match result {
            Ok(ok) => outcomes[usize::from(ok)] += 1,
            Err(_) => panic!(
                "round {round} panicked on {:?}",
                String::from_utf8_lossy(&bytes)
            ),
        }
    }
    assert!(outcomes[0] > 0 && outcomes[1] > 0, "{outcomes:?}");
}
