//! `rondo export`: the triangles, spheres and textures it writes against values computed by
//! hand from the scene files.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::{temp_dir, write_scene};
use glam::Vec3;
use serde_json::Value;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn export(scene: &Path, dir: &Path, extra: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rondo"))
        .arg("export")
        .arg(scene)
        .arg("--output")
        .arg(dir)
        .args(extra)
        .output()
        .expect("run rondo")
}

fn export_ok(scene: &Path, dir: &Path) -> Value {
    let out = export(scene, dir, &[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(dir.join("scene.json")).expect("scene.json");
    serde_json::from_str(&text).expect("json")
}

/// A PLY file as read by a reader written here from the format's description.
struct Ply {
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    uvs: Option<Vec<[f32; 2]>>,
    faces: Vec<[u32; 3]>,
}

fn read_ply(path: &Path) -> Ply {
    let bytes = std::fs::read(path).expect("ply");
    let end = b"end_header\n";
    let header_end = bytes
        .windows(end.len())
        .position(|w| w == end)
        .expect("header")
        + end.len();
    let header = std::str::from_utf8(&bytes[..header_end]).expect("ascii header");
    assert!(header.starts_with("ply\nformat binary_little_endian 1.0\n"));
    let mut vertices = 0;
    let mut faces = 0;
    let mut props = Vec::new();
    for line in header.lines() {
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.as_slice() {
            ["element", "vertex", n] => vertices = n.parse().unwrap(),
            ["element", "face", n] => faces = n.parse().unwrap(),
            ["property", "float", name] => props.push(name.to_string()),
            ["property", "list", "uchar", "uint", "vertex_indices"] => {}
            _ => {}
        }
    }
    let mut at = header_end;
    let f32_at = |at: &mut usize| {
        let v = f32::from_le_bytes(bytes[*at..*at + 4].try_into().unwrap());
        *at += 4;
        v
    };
    let has = |n: &str| props.iter().any(|p| p == n);
    let (mut positions, mut normals, mut uvs) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..vertices {
        let vals: Vec<f32> = props.iter().map(|_| f32_at(&mut at)).collect();
        let get = |n: &str| vals[props.iter().position(|p| p == n).unwrap()];
        positions.push(Vec3::new(get("x"), get("y"), get("z")));
        if has("nx") {
            normals.push(Vec3::new(get("nx"), get("ny"), get("nz")));
        }
        if has("u") {
            uvs.push([get("u"), get("v")]);
        }
    }
    let mut tris = Vec::new();
    for _ in 0..faces {
        assert_eq!(bytes[at], 3);
        at += 1;
        let mut t = [0u32; 3];
        for k in &mut t {
            *k = u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
            at += 4;
        }
        tris.push(t);
    }
    assert_eq!(at, bytes.len(), "{}: trailing bytes", path.display());
    Ply {
        positions,
        normals: has("nx").then_some(normals),
        uvs: has("u").then_some(uvs),
        faces: tris,
    }
}

fn meshes(dir: &Path, json: &Value) -> Vec<(String, Ply)> {
    json["meshes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| {
            let file = PathBuf::from(m["file"].as_str().unwrap());
            assert_eq!(file.components().count(), 1, "a bare file name");
            (
                m["material"].as_str().unwrap().to_string(),
                read_ply(&dir.join(file)),
            )
        })
        .collect()
}

fn area(ply: &Ply) -> f64 {
    ply.faces
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| ply.positions[i as usize].as_dvec3());
            0.5 * (b - a).cross(c - a).length()
        })
        .sum()
}

#[test]
fn cornell_triangles_and_area_equal_the_quads_by_hand() {
    let dir = temp_dir("export-cornell");
    let json = export_ok(&Path::new(ROOT).join("scenes/cornell.ron"), &dir);
    // cornell.ron: five 555 × 555 walls and a 130 × 105 lamp (quads: 2 triangles each), a
    // 165 × 330 × 165 box and a 165-cube (12 triangles each); rotations keep areas.
    let wall = 555.0f64 * 555.0;
    let tall = 2.0 * (165.0 * 165.0 + 2.0 * 165.0 * 330.0);
    let short = 6.0 * 165.0 * 165.0;
    let expected = [
        ("white", 3.0 * wall + tall + short, 3 * 2 + 2 * 12),
        ("red", wall, 2),
        ("green", wall, 2),
        ("light", 130.0 * 105.0, 2),
    ];
    let meshes = meshes(&dir, &json);
    assert_eq!(meshes.len(), 4);
    let mut total = 0;
    for (material, want_area, want_triangles) in expected {
        let (_, ply) = meshes.iter().find(|(m, _)| m == material).expect(material);
        assert_eq!(ply.faces.len(), want_triangles, "{material}");
        let got = area(ply);
        assert!(
            (got - want_area).abs() < 1e-4 * want_area,
            "{material}: area {got}, by hand {want_area}"
        );
        total += ply.faces.len();
    }
    assert_eq!(total, 36);
    assert_eq!(json["counts"]["triangles"], 36);
    // The lamp faces down (its quad's (b − a) × (c − a)), as rondo emits it.
    let (_, lamp) = meshes.iter().find(|(m, _)| m == "light").unwrap();
    for t in &lamp.faces {
        let [a, b, c] = t.map(|i| lamp.positions[i as usize]);
        assert!((b - a).cross(c - a).normalize().y < -0.999);
    }
    assert_eq!(json["camera"]["fov_y_degrees"], 40.0);
    assert_eq!(
        json["camera"]["position"],
        serde_json::json!([278.0, 278.0, -800.0])
    );
    assert_eq!(json["materials"]["light"]["intensity"], 15.0);
}

#[test]
fn sphere_centre_and_radius_follow_the_transform() {
    let dir = temp_dir("export-sphere");
    let scene = write_scene(
        &dir,
        "s.ron",
        r#"Scene(camera: Camera(position: (0, 0, 10), look_at: (0, 0, 0)),
            materials: { "m": Diffuse(albedo: Constant((0.5, 0.5, 0.5))) },
            entities: [Entity(name: "ball", material: "m",
                shape: Sphere(center: (1, 0, 0), radius: 0.5),
                transform: Transform(translate: (0, 2, 0), rotate: (0, 0, 90), scale: (3, 3, 3)))])"#,
    );
    let out = dir.join("out");
    let json = export_ok(&scene, &out);
    let spheres = json["spheres"].as_array().unwrap();
    assert_eq!(spheres.len(), 1);
    // S: (1,0,0) → (3,0,0); Rz(90°): → (0,3,0); T: → (0,5,0). Radius 0.5 · 3.
    let c: Vec<f64> = spheres[0]["center"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert!(
        (c[0]).abs() < 1e-5 && (c[1] - 5.0).abs() < 1e-5 && c[2].abs() < 1e-5,
        "{c:?}"
    );
    assert!((spheres[0]["radius"].as_f64().unwrap() - 1.5).abs() < 1e-6);
    assert_eq!(spheres[0]["material"], "m");
    assert!(json["meshes"].as_array().unwrap().is_empty());
}

#[test]
fn transformed_instance_vertices_equal_the_transform_by_hand() {
    let dir = temp_dir("export-instance");
    std::fs::write(
        dir.join("tri.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\nf 1//1 2//2 3//3\n",
    )
    .unwrap();
    let scene = write_scene(
        &dir,
        "s.ron",
        r#"Scene(camera: Camera(position: (0, 0, 10), look_at: (0, 0, 0)),
            materials: { "m": Diffuse(albedo: Constant((0.5, 0.5, 0.5))) },
            entities: [
              Entity(name: "a", material: "m", shape: Mesh(path: "tri.obj")),
              Entity(name: "b", material: "m", shape: Mesh(path: "tri.obj"),
                transform: Transform(translate: (1, 2, 3), rotate: (0, 90, 0), scale: (2, 2, 2)))])"#,
    );
    let out = dir.join("out");
    let json = export_ok(&scene, &out);
    let meshes = meshes(&out, &json);
    assert_eq!(meshes.len(), 1);
    let ply = &meshes[0].1;
    assert_eq!(ply.positions.len(), 6);
    assert_eq!(ply.faces, vec![[0, 1, 2], [3, 4, 5]]);
    // Placement b by hand: S = 2, Ry(90°) maps (x, y, z) to (z, y, −x), then + (1, 2, 3).
    let by_hand = |p: Vec3| Vec3::new(2.0 * p.z, 2.0 * p.y, -2.0 * p.x) + Vec3::new(1.0, 2.0, 3.0);
    let object = [Vec3::ZERO, Vec3::X, Vec3::Y];
    for (k, p) in object.iter().enumerate() {
        assert!((ply.positions[k] - *p).length() < 1e-6);
        let want = by_hand(*p);
        assert!(
            (ply.positions[3 + k] - want).length() < 1e-5,
            "vertex {k}: {} against {want}",
            ply.positions[3 + k]
        );
    }
    // The normal (0, 0, 1) turns to (1, 0, 0).
    let normals = ply.normals.as_ref().expect("normals");
    assert!((normals[3] - Vec3::X).length() < 1e-5, "{}", normals[3]);
    assert!(ply.uvs.is_none());
    assert_eq!(json["counts"]["mesh_placements"], 2);
}

#[test]
fn export_refuses_more_triangles_than_the_bound_before_writing() {
    let dir = temp_dir("export-bound");
    let out = dir.join("out");
    let scene = Path::new(ROOT).join("scenes/cornell.ron");
    let refused = export(&scene, &out, &["--max-triangles", "35"]);
    assert!(!refused.status.success());
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(
        err.contains("36 triangles") && err.contains("cornell.ron"),
        "{err}"
    );
    assert!(!out.exists(), "nothing written");
    assert!(
        export(&scene, &out, &["--max-triangles", "36"])
            .status
            .success()
    );
}

#[cfg(unix)]
#[test]
fn export_never_writes_through_a_symlinked_directory() {
    let dir = temp_dir("export-symlink");
    let target = dir.join("elsewhere");
    std::fs::create_dir(&target).unwrap();
    let link = dir.join("out");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    let refused = export(&Path::new(ROOT).join("scenes/cornell.ron"), &link, &[]);
    assert!(!refused.status.success());
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(err.contains("symlink"), "{err}");
    assert_eq!(std::fs::read_dir(&target).unwrap().count(), 0);
}

#[test]
fn image_textures_name_their_files_and_encodings() {
    let dir = temp_dir("export-textures");
    let json = export_ok(&Path::new(ROOT).join("scenes/textures.ron"), &dir);
    let grid = &json["materials"]["grid"]["albedo"];
    assert_eq!(grid["kind"], "image");
    let want = std::path::absolute(Path::new(ROOT).join("scenes/textures/grid.png")).unwrap();
    assert_eq!(Path::new(grid["path"].as_str().unwrap()), want);
    assert_eq!(grid["encoding"], "srgb");
    assert_eq!(grid["filter"], "nearest");
    // glTF: the crate's normal map is read as linear data, its base colour as sRGB; both are
    // embedded images written beside scene.json.
    let out = dir.join("gltf");
    let json = export_ok(&Path::new(ROOT).join("scenes/gltf.ron"), &out);
    let (_, crate_material) = json["materials"]
        .as_object()
        .unwrap()
        .iter()
        .find(|(k, _)| k.ends_with("::Crate"))
        .expect("crate material");
    let normal = &crate_material["normal_map"]["texture"];
    assert_eq!(normal["encoding"], "linear");
    assert_eq!(crate_material["base_color"]["encoding"], "srgb");
    assert!(
        Path::new(normal["path"].as_str().unwrap()).starts_with(std::path::absolute(&out).unwrap())
    );
}

#[test]
fn a_transmission_texture_is_exported_with_the_opaque_part_it_hands_the_rest_to() {
    // A glTF quad of transmission 0.8 × a texture (red 0 | 128, read linear: 128/255 is 0.50
    // linear, 0.22 through sRGB, so the file's encoding is found as linear), metallic 0.
    let dir = temp_dir("export-transmission-texture");
    std::fs::write(
        dir.join("t.png"),
        common::two_texel::png([0, 0, 0, 255], [128, 0, 0, 255]),
    )
    .expect("write");
    let material = serde_json::json!({
        "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1], "metallicFactor": 0,
                                 "roughnessFactor": 0.2},
        "extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.8,
                                                      "transmissionTexture": {"index": 0}}},
    });
    let file = common::two_texel::quad_file(material, &["KHR_materials_transmission"]);
    std::fs::write(dir.join("q.gltf"), file.to_string()).expect("write");
    let scene = write_scene(
        &dir,
        "q.ron",
        "Scene(camera: Camera(position: (0, 0, 2), look_at: (0, 0, 0)), \
         entities: [Entity(name: \"q\", gltf: \"q.gltf\")])",
    );
    let json = export_ok(&scene, &dir.join("out"));
    let (_, m) = json["materials"]
        .as_object()
        .expect("materials")
        .iter()
        .next()
        .expect("one material");
    assert_eq!(m["kind"], "transmissive");
    assert!((m["weight"].as_f64().expect("weight") - 0.8).abs() < 1e-6);
    assert_eq!(m["glass"]["kind"], "dielectric");
    assert_eq!(m["base"]["kind"], "pbr");
    let texture = &m["transmission_texture"]["texture"];
    assert_eq!(texture["kind"], "image", "{m}");
    assert_eq!(texture["encoding"], "linear");
    let want = std::path::absolute(dir.join("t.png")).expect("absolute");
    assert_eq!(Path::new(texture["path"].as_str().expect("path")), want);
    let opaque = &m["transmission_texture"]["opaque"];
    assert_eq!(
        (&opaque["kind"], &opaque["metallic"]),
        (&"pbr".into(), &0.0.into())
    );
}
