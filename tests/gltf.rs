//! glTF 2.0 reading (src/scene/gltf.rs) on small files written here: JSON with data-URI or
//! external buffers and `.glb` containers assembled byte by byte. Expected values are computed by
//! hand from the files, never taken from the reader's output.

mod common;

use std::path::Path;
use std::sync::Arc;

use common::gltf_doc::{Bin, doc, glb};
use common::temp_dir;
use glam::{Vec2, Vec3};
use rondo::scene::gltf_read::{GltfImage, GltfScene, read_gltf, read_gltf_within};
use rondo::shading::rng::Rng;
use serde_json::{Value, json};

fn read(doc: &Value) -> Result<GltfScene, String> {
    read_gltf(
        Path::new("test.gltf"),
        Arc::new(doc.to_string().into_bytes()),
        |uri, _| Err(format!("no external buffers here ({uri})")),
    )
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
    assert_eq!(m.alpha_mode, rondo::scene::gltf_read::AlphaMode::Mask(0.25));
    let t = m.base_color_texture.as_ref().expect("texture");
    assert_eq!(t.image, 0);
    assert_eq!(t.wrap_s, rondo::scene::gltf_read::Wrap::MirroredRepeat);
    assert_eq!(t.wrap_t, rondo::scene::gltf_read::Wrap::ClampToEdge);
    assert!(t.nearest);
    assert_eq!(
        scene.images,
        vec![rondo::scene::gltf_read::GltfImage::File(
            "tex ture.png".into()
        )]
    );
}

#[test]
fn glb_and_external_buffers() {
    let (bin, parts) = triangle();
    let bytes = glb(&bin, parts.clone());
    let scene = read_gltf(Path::new("t.glb"), Arc::new(bytes), |_, _| {
        Err("none".into())
    })
    .expect("glb reads");
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
    let scene = read_gltf(
        Path::new("t.gltf"),
        Arc::new(d.to_string().into_bytes()),
        |uri, _| {
            asked.push(uri.to_owned());
            std::fs::read(dir.join(uri)).map_err(|e| e.to_string())
        },
    )
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
    d["materials"] = json!([{"name": "Bad", "emissiveFactor": [1.0, 0.0, 0.0],
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 1e39}}}]);
    let e = error(&d);
    assert!(
        e.contains("material \"Bad\" (materials[0]): extensions.KHR_materials_emissive_strength.emissiveStrength is inf"),
        "{e}"
    );

    let g = glb(&bin, parts);
    for len in [0, 4, 11, 12, 20, g.len() / 2, g.len() - 1] {
        let e = read_gltf(Path::new("t.glb"), Arc::new(g[..len].to_vec()), |_, _| {
            Err("none".into())
        })
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
            read_gltf(Path::new("f.gltf"), Arc::new(bytes.clone()), |_, _| {
                Err("none".into())
            })
            .is_ok()
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

/// `triangle()` in a `.glb` whose JSON lists `buffers` buffers, all of its binary chunk.
fn glb_with_buffers(buffers: usize) -> Vec<u8> {
    let (bin, parts) = triangle();
    let mut bytes = glb(&bin, parts);
    // Rebuilt around the JSON chunk: a header (12 bytes), the chunk's length and type (8).
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().expect("4 bytes")) as usize;
    let mut d: Value = serde_json::from_slice(&bytes[20..20 + json_len]).expect("JSON");
    d["buffers"] = Value::Array(vec![json!({"byteLength": bin.bytes.len()}); buffers]);
    let bin_chunk = bytes.split_off(20 + json_len);
    let mut json_bytes = d.to_string().into_bytes();
    while !json_bytes.len().is_multiple_of(4) {
        json_bytes.push(b' ');
    }
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend(((12 + 8 + json_bytes.len() + bin_chunk.len()) as u32).to_le_bytes());
    out.extend((json_bytes.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(json_bytes);
    out.extend(bin_chunk);
    out
}

#[test]
fn only_buffer_zero_may_use_the_glb_binary_chunk() {
    let read_glb = |bytes: Vec<u8>| {
        read_gltf(Path::new("t.glb"), Arc::new(bytes), |_, _| {
            Err("none".into())
        })
    };
    let scene = read_glb(glb_with_buffers(1)).expect("one buffer reads");
    // The binary chunk holds the triangle's 9 floats, 36 bytes, and is held once.
    assert_eq!(scene.held_bytes, 36);
    for n in [2, 2000] {
        let e = read_glb(glb_with_buffers(n)).expect_err("a second buffer on the chunk");
        assert!(
            e.contains("t.glb") && e.contains("buffer 1") && e.contains("only buffer 0"),
            "{e}"
        );
    }
}

#[test]
fn images_on_one_buffer_view_share_its_bytes() {
    let (mut bin, mut parts) = triangle();
    let png = bin.view(vec![7; 1000]);
    parts["images"] = Value::Array(vec![
        json!({"bufferView": png, "mimeType": "image/png"});
        300
    ]);
    let bytes = glb(&bin, parts);
    let scene = read_gltf(Path::new("t.glb"), Arc::new(bytes), |_, _| {
        Err("none".into())
    })
    .expect("reads");
    assert_eq!(scene.images.len(), 300);
    let identities: Vec<_> = scene
        .images
        .iter()
        .map(|image| match image {
            GltfImage::Bytes { bytes, .. } => {
                assert_eq!(&bytes[..], &[7; 1000][..]);
                // Only the image's bytes outlive the read, not the file's JSON and mesh data.
                assert_eq!(bytes.allocation_len(), 1000);
                bytes.identity()
            }
            other => panic!("{other:?}"),
        })
        .collect();
    assert!(
        identities.iter().all(|i| *i == identities[0]),
        "every image is the same bytes of the one buffer"
    );
    // Held: the chunk once, 36 bytes of floats and the image's 1000 (padded to 4 between).
    assert_eq!(scene.held_bytes, 1036);
}

#[test]
fn buffer_sources_are_read_once_and_their_total_is_bounded() {
    let (bin, parts) = triangle();
    let len = bin.bytes.len();
    let mut d = doc(&bin, parts);
    // Buffers 0 and 2 name one file, buffer 1 another.
    d["buffers"] = json!([
        {"byteLength": len, "uri": "a.bin"},
        {"byteLength": len, "uri": "b.bin"},
        {"byteLength": len, "uri": "a.bin"},
    ]);
    let text = Arc::new(d.to_string().into_bytes());
    let mut asked = Vec::new();
    let scene = read_gltf_within(Path::new("t.gltf"), text.clone(), 100, |uri, max| {
        asked.push((uri.to_owned(), max));
        Ok(bin.bytes.clone())
    })
    .expect("72 bytes of 100");
    // Each file fetched once, told what is left: 100, then 100 − 36.
    assert_eq!(
        asked,
        [("a.bin".to_string(), 100), ("b.bin".to_string(), 64)]
    );
    assert_eq!(scene.held_bytes, 72);

    // Within 50 bytes the second file does not fit: a loader that returns it anyway is refused.
    let e = read_gltf_within(Path::new("t.gltf"), text, 50, |_, _| Ok(bin.bytes.clone()))
        .expect_err("72 bytes of 50");
    assert!(
        e.contains("t.gltf") && e.contains("buffer 1") && e.contains("more than 50 bytes"),
        "{e}"
    );

    // A data URI counts as well.
    let d = doc(&bin, triangle().1);
    let e = read_gltf_within(
        Path::new("t.gltf"),
        Arc::new(d.to_string().into_bytes()),
        35,
        |_, _| Err("none".into()),
    )
    .expect_err("36 bytes of 35");
    assert!(e.contains("more than 35 bytes"), "{e}");
}

/// The error of reading `triangle()` with its material (or node, or view) edited by `edit`.
fn refused(edit: impl Fn(&mut Value)) -> String {
    let (bin, parts) = triangle();
    let mut d = doc(&bin, parts);
    d["materials"] = json!([{"name": "M"}]);
    d["meshes"][0]["primitives"][0]["material"] = json!(0);
    edit(&mut d);
    error(&d)
}

#[test]
fn material_values_outside_the_spec_ranges_are_refused_naming_the_field() {
    let material = |field: &str, value: Value| {
        refused(|d| {
            let mut at = &mut d["materials"][0];
            let mut parts = field.split('.').peekable();
            while let Some(part) = parts.next() {
                if parts.peek().is_none() {
                    at[part] = value.clone();
                } else {
                    if at.get(part).is_none() {
                        at[part] = json!({});
                    }
                    at = &mut at[part];
                }
            }
            if field.starts_with("normalTexture") {
                d["images"] = json!([{"uri": "n.png"}]);
                d["textures"] = json!([{"source": 0}]);
            }
        })
    };
    let big = json!(1e39); // beyond f32: infinite once read
    for (field, value, named) in [
        (
            "pbrMetallicRoughness.baseColorFactor",
            json!([-5.0, 0.5, 0.5, 1.0]),
            "pbrMetallicRoughness.baseColorFactor[0] is -5",
        ),
        (
            "pbrMetallicRoughness.baseColorFactor",
            json!([0.5, 0.5, 0.5, 1.5]),
            "baseColorFactor[3] is 1.5",
        ),
        (
            "pbrMetallicRoughness.metallicFactor",
            json!(2.0),
            "metallicFactor is 2",
        ),
        (
            "pbrMetallicRoughness.roughnessFactor",
            json!(-0.5),
            "roughnessFactor is -0.5",
        ),
        (
            "emissiveFactor",
            json!([0.0, -1.0, 0.0]),
            "emissiveFactor[1] is -1",
        ),
        (
            "emissiveFactor",
            json!([0.0, 0.0, 3.0]),
            "emissiveFactor[2] is 3",
        ),
        (
            "extensions.KHR_materials_emissive_strength.emissiveStrength",
            json!(-2.0),
            "emissiveStrength is -2",
        ),
        (
            "extensions.KHR_materials_transmission.transmissionFactor",
            json!(1.5),
            "transmissionFactor is 1.5",
        ),
        ("alphaCutoff", big.clone(), "alphaCutoff is inf"),
        ("alphaCutoff", json!(-0.5), "alphaCutoff is -0.5"),
        (
            "normalTexture",
            json!({"index": 0, "scale": -1e39}),
            "normalTexture.scale is -inf",
        ),
    ] {
        let e = material(field, value);
        assert!(
            e.contains("test.gltf")
                && e.contains("material \"M\" (materials[0])")
                && e.contains(named),
            "{field}: {e}"
        );
    }
    // In range, the extremes included: read as given.
    let (bin, parts) = triangle();
    let mut d = doc(&bin, parts);
    d["materials"] = json!([{"pbrMetallicRoughness": {"baseColorFactor": [0.0, 1.0, 0.0, 1.0],
        "metallicFactor": 0.0, "roughnessFactor": 1.0}, "emissiveFactor": [1.0, 0.0, 1.0],
        "normalTexture": {"index": 0, "scale": -3.0}, "alphaMode": "MASK", "alphaCutoff": 2.0}]);
    d["images"] = json!([{"uri": "n.png"}]);
    d["textures"] = json!([{"source": 0}]);
    let m = &read(&d).expect("in range").materials[0];
    assert_eq!(m.base_color_factor, [0.0, 1.0, 0.0, 1.0]);
    assert_eq!(m.emissive, Vec3::new(1.0, 0.0, 1.0));
    assert_eq!(m.normal_texture.as_ref().map(|t| t.1), Some(-3.0));
}

#[test]
fn singular_or_projective_node_transforms_and_overlapping_strides_are_refused() {
    let node = |n: Value| refused(|d| d["nodes"][0] = n.clone());
    let m = |col3: [f32; 4], x: [f32; 3], y: [f32; 3]| {
        json!({"mesh": 0, "matrix": [x[0], x[1], x[2], 0.0, y[0], y[1], y[2], 0.0,
            0.0, 0.0, 1.0, 0.0, col3[0], col3[1], col3[2], col3[3]]})
    };
    for (n, named) in [
        (
            json!({"mesh": 0, "scale": [1.0, 0.0, 1.0]}),
            "node 0: scale[1] is 0",
        ),
        (
            json!({"mesh": 0, "scale": [1e-13, 1.0, 1.0]}),
            "node 0: scale[0]",
        ),
        (
            m([0.0, 0.0, 0.0, 1.0], [0.0; 3], [0.0, 1.0, 0.0]),
            "scales axis 0 to zero",
        ),
        // y = x: the axes are coplanar.
        (
            m([0.0, 0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [1.0, 0.0, 0.0]),
            "singular",
        ),
        (
            m([0.0, 0.0, 0.0, 2.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
            "last row",
        ),
    ] {
        let e = node(n.clone());
        assert!(e.contains("test.gltf") && e.contains(named), "{n}: {e}");
    }
    // 0.5 0 0 1 in the last row of a column-major matrix: elements 3, 7, 11 and 15.
    let mut projective = m([0.0, 0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
    projective["matrix"][3] = json!(0.5);
    assert!(node(projective).contains("[0.5, 0.0, 0.0, 1.0]"));
    // A skewed but invertible matrix and a mirroring scale are read.
    let (bin, parts) = triangle();
    let mut d = doc(&bin, parts);
    d["nodes"] = json!([m([0.0, 0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0])]);
    assert!(read(&d).is_ok());
    d["nodes"] = json!([{"mesh": 0, "scale": [-1.0, 1e-6, 1.0]}]);
    assert!(read(&d).is_ok());

    // Positions are 12 bytes each; a stride of 8 would read overlapping elements.
    let e = refused(|d| d["bufferViews"][0]["byteStride"] = json!(8));
    assert!(
        e.contains("accessor 0")
            && e.contains("byteStride 8 is smaller than an element (12 bytes)"),
        "{e}"
    );
}
