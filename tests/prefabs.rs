//! Prefabs: composition, material overrides, qualified names, errors, meshes.

mod common;

use common::{render, scenes_dir, temp_dir, write_scene};
use glam::Vec3;
use rondo::Overrides;
use rondo::geometry::packed::Primitive;
use rondo::scene::assets::AssetCache;
use rondo::scene::load::{LoadedScene, load_scene};
use rondo::systems::world_primitives;

const CAMERA: &str = "camera: Camera(position: (0, 0, -10), look_at: (0, 0, 0)),";

fn load(path: &std::path::Path) -> Result<LoadedScene, String> {
    load_scene(path, &mut AssetCache::default()).map_err(|e| e.to_string())
}

#[test]
fn a_sphere_placed_through_three_levels_lands_where_the_composed_matrix_says() {
    let dir = temp_dir("prefab-nesting");
    std::fs::create_dir_all(dir.join("parts")).expect("dir");
    write_scene(
        &dir,
        "parts/c.ron",
        r#"Prefab(
        materials: { "m": Diffuse(albedo: Constant((1, 1, 1))) },
        entities: [ Entity(name: "ball", material: "m", shape: Sphere(center: (1, 0, 0), radius: 1),
                           transform: Transform(scale: (2, 2, 2))) ])"#,
    );
    // Paths are relative to the file that names them: b.ron is in parts/ and names c.ron.
    write_scene(
        &dir,
        "parts/b.ron",
        r#"Prefab(entities: [
        Entity(name: "c", prefab: "c.ron", transform: Transform(rotate: (0, 90, 0))) ])"#,
    );
    let scene = write_scene(
        &dir,
        "a.ron",
        &format!(
            r#"Scene({CAMERA}
        entities: [ Entity(name: "b", prefab: "parts/b.ron", transform: Transform(translate: (10, 0, 0))) ])"#
        ),
    );
    let loaded = load(&scene).expect("loads");
    assert_eq!(loaded.entities.len(), 1);
    let e = &loaded.entities[0];
    assert_eq!(e.name, "b/c/ball");
    // By hand: scale 2 → centre (2,0,0), radius 2; +90° about y maps (x, z) to (z, −x) →
    // (0, 0, −2); translate → (10, 0, −2).
    let Primitive::Sphere { center, radius, .. } = world_primitives(&e.shape, &e.transform)[0]
    else {
        panic!("a sphere")
    };
    assert!(
        (center - Vec3::new(10.0, 0.0, -2.0)).length() < 1e-5,
        "{center}"
    );
    assert!((radius - 2.0).abs() < 1e-6);
    assert_eq!(loaded.dependencies.len(), 3, "{:?}", loaded.dependencies);
}

#[test]
fn placement_maps_override_prefab_defaults_and_names_are_qualified() {
    let dir = temp_dir("prefab-override");
    write_scene(
        &dir,
        "p.ron",
        r#"Prefab(
        materials: { "surface": Diffuse(albedo: Constant((0.1, 0.1, 0.1))), "trim": Diffuse(albedo: Constant((0.2, 0.2, 0.2))) },
        entities: [
            Entity(name: "top", material: "surface", shape: Quad(a: (0, 0, 0), b: (1, 0, 0), c: (1, 1, 0), d: (0, 1, 0))),
            Entity(name: "edge", material: "trim", shape: Triangle(a: (0, 0, 0), b: (1, 0, 0), c: (0, 1, 0))),
        ])"#,
    );
    let scene = write_scene(
        &dir,
        "s.ron",
        &format!(
            r#"Scene({CAMERA}
        materials: {{ "white": Diffuse(albedo: Constant((0.9, 0.9, 0.9))) }},
        entities: [
            Entity(name: "one", prefab: "p.ron", materials: {{ "surface": "white" }}),
            Entity(name: "two", prefab: "p.ron"),
        ])"#
        ),
    );
    let loaded = load(&scene).expect("loads");
    let names: Vec<&str> = loaded.entities.iter().map(|e| e.name.as_str()).collect();
    assert_eq!(names, ["one/top", "one/edge", "two/top", "two/edge"]);
    let albedo = |i: usize| match &loaded.materials[&loaded.entities[i].material] {
        rondo::shading::material::Material::Diffuse { albedo } => albedo.eval(glam::Vec2::ZERO).x,
        other => panic!("{other:?}"),
    };
    assert_eq!(
        [albedo(0), albedo(1), albedo(2), albedo(3)],
        [0.9, 0.2, 0.1, 0.2]
    );
    // Both placements share the prefab's default materials: one table entry each.
    assert_eq!(loaded.materials.len(), 3);
}

#[test]
fn a_prefab_cycle_is_an_error_that_prints_the_chain() {
    let dir = temp_dir("prefab-cycle");
    write_scene(
        &dir,
        "a.ron",
        r#"Prefab(entities: [ Entity(name: "to-b", prefab: "b.ron") ])"#,
    );
    write_scene(
        &dir,
        "b.ron",
        r#"Prefab(entities: [ Entity(name: "to-a", prefab: "a.ron") ])"#,
    );
    let scene = write_scene(
        &dir,
        "s.ron",
        &format!("Scene({CAMERA}\n    entities: [ Entity(name: \"x\", prefab: \"a.ron\") ])"),
    );
    let e = load(&scene).expect_err("cycle");
    assert!(
        e.contains("prefab cycle") && e.contains("a.ron → ") && e.contains("b.ron → "),
        "{e}"
    );
    assert!(
        e.contains("b.ron:1:"),
        "the error points at the placement that closes the cycle: {e}"
    );
}

#[test]
fn a_missing_prefab_names_the_placing_file_line_and_column() {
    let dir = temp_dir("prefab-missing");
    let scene = write_scene(
        &dir,
        "s.ron",
        &format!(
            "Scene({CAMERA}\n    entities: [\n        Entity(name: \"x\", prefab: \"nope.ron\"),\n    ])"
        ),
    );
    let e = load(&scene).expect_err("missing");
    assert!(e.contains("s.ron:3:35") && e.contains("nope.ron"), "{e}");
}

/// `line:col` (1-based) of the first occurrence of `needle` in `text`, counted by hand.
fn line_col(text: &str, needle: &str) -> String {
    let at = text.find(needle).unwrap_or_else(|| panic!("no {needle}"));
    let line = text[..at].matches('\n').count() + 1;
    let line_start = text[..at].rfind('\n').map_or(0, |i| i + 1);
    format!("{line}:{}", text[line_start..at].chars().count() + 1)
}

#[test]
fn a_written_name_equal_to_a_qualified_one_is_an_error_naming_both_places() {
    // "tall/box" written in the scene and the child "box" of the placement "tall" would be two
    // entities with one name: one would silently replace the other.
    let dir = temp_dir("prefab-collision");
    let prefab = r#"Prefab(
    materials: { "m": Diffuse(albedo: Constant((1, 1, 1))) },
    entities: [
        Entity(name: "box", material: "m", shape: Box(min: (0, 0, 0), max: (1, 1, 1))),
    ])"#;
    write_scene(&dir, "tall.ron", prefab);
    let source = format!(
        r#"Scene({CAMERA}
    materials: {{ "w": Diffuse(albedo: Constant((1, 1, 1))) }},
    entities: [
        Entity(name: "tall", prefab: "tall.ron"),
        Entity(name: "tall/box", material: "w", shape: Sphere(center: (0, 0, 0), radius: 1)),
    ])"#
    );
    let scene = write_scene(&dir, "s.ron", &source);
    let e = load(&scene).expect_err("two entities named tall/box");
    let written = format!("s.ron:{}", line_col(&source, "\"tall/box\""));
    let child = format!("tall.ron:{}", line_col(prefab, "\"box\""));
    assert!(
        e.contains(&written) && e.contains(&child) && e.contains("\"tall/box\""),
        "{e}"
    );
    // `rondo check` loads the scene the same way: it fails with the same message.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_rondo"))
        .arg("check")
        .arg(&scene)
        .output()
        .expect("run rondo check");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains(&written) && stderr.contains(&child),
        "{stderr}"
    );
    // Without the collision (another written name), the scene loads with both entities.
    let renamed = source.replace("\"tall/box\"", "\"tall-box\"");
    let scene = write_scene(&dir, "s.ron", &renamed);
    let loaded = load(&scene).expect("loads");
    let names: Vec<&str> = loaded.entities.iter().map(|e| e.name.as_str()).collect();
    assert_eq!(names, ["tall/box", "tall-box"]);
}

#[test]
fn a_material_nobody_defines_is_an_error_naming_both_files() {
    let dir = temp_dir("prefab-undefined");
    write_scene(
        &dir,
        "p.ron",
        "Prefab(entities: [\n  Entity(name: \"t\", material: \"paint\", shape: Sphere(center: (0, 0, 0), radius: 1)) ])",
    );
    let scene = write_scene(
        &dir,
        "s.ron",
        &format!("Scene({CAMERA}\n    entities: [ Entity(name: \"x\", prefab: \"p.ron\") ])"),
    );
    let e = load(&scene).expect_err("undefined");
    assert!(
        e.contains("p.ron:2:") && e.contains("\"paint\"") && e.contains("s.ron:2:"),
        "{e}"
    );
    // A placement mapping to a name the placing file does not define is its own error.
    let scene = write_scene(
        &dir,
        "s2.ron",
        &format!(
            "Scene({CAMERA}\n    entities: [ Entity(name: \"x\", prefab: \"p.ron\", materials: {{ \"paint\": \"blue\" }}) ])"
        ),
    );
    let e = load(&scene).expect_err("unknown mapping");
    assert!(e.contains("s2.ron:2:") && e.contains("\"blue\""), "{e}");
}

#[test]
fn cornell_from_prefabs_renders_identically_to_the_flat_cornell_box() {
    let o = Overrides {
        width: Some(40),
        height: Some(40),
        spp: Some(4),
        ..Default::default()
    };
    let flat = render(&scenes_dir().join("cornell.ron"), o, None);
    let composed = render(&scenes_dir().join("cornell_prefab.ron"), o, None);
    assert_eq!(flat.film().sum, composed.film().sum);
}

#[test]
fn the_bunny_obj_has_the_vertex_and_face_counts_of_its_file() {
    let path = scenes_dir().join("meshes/bunny.obj");
    let text = std::fs::read_to_string(&path).expect("bunny");
    let vertices = text.lines().filter(|l| l.starts_with("v ")).count();
    let faces = text.lines().filter(|l| l.starts_with("f ")).count();
    let mesh = AssetCache::default().mesh(&path).expect("loads");
    assert_eq!(
        (mesh.positions.len(), mesh.triangles.len()),
        (vertices, faces)
    );
    assert_eq!((vertices, faces), (1839, 3674), "the npm package's counts");
    assert!(mesh.normals.is_none());
}

#[test]
fn malformed_obj_files_are_errors_not_panics() {
    let dir = temp_dir("bad-obj");
    for (name, text) in [
        ("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"),
        ("garbage.obj", "v 0 zero 0\nf 1 2 3\n"),
        ("empty.obj", "# nothing\n"),
        ("nan.obj", "v 0 0 0\nv NaN 0 0\nv 0 1 0\nf 1 2 3\n"),
    ] {
        let path = write_scene(&dir, name, text);
        assert!(AssetCache::default().mesh(&path).is_err(), "{name} loaded");
    }
    let scene = write_scene(
        &dir,
        "s.ron",
        &format!(
            "Scene({CAMERA}\n    materials: {{ \"m\": Diffuse(albedo: Constant((1, 1, 1))) }},\n    entities: [ Entity(name: \"x\", material: \"m\", shape: Mesh(path: \"range.obj\")) ])"
        ),
    );
    let e = load(&scene).expect_err("bad mesh");
    assert!(e.contains("s.ron:3:") && e.contains("range.obj"), "{e}");
}

/// A small scene with a mesh placed three times (and a second mesh once).
fn instanced_scene(dir: &std::path::Path, material: &str) -> std::path::PathBuf {
    let bunny = scenes_dir().join("meshes/bunny.obj");
    if !dir.join("bunny.obj").exists() {
        std::fs::copy(&bunny, dir.join("bunny.obj")).expect("copy bunny");
    }
    if !dir.join("tri.obj").exists() {
        write_scene(dir, "tri.obj", "v -1 0 -1\nv 1 0 -1\nv 0 0 1\nf 1 2 3\n");
    }
    write_scene(
        dir,
        "s.ron",
        &format!(
            r#"Scene(
    camera: Camera(position: (0, 6, -22), look_at: (0, 4, 0), fov: 45),
    settings: Settings(width: 48, height: 32, spp: 4, max_depth: 4, background: (0.6, 0.7, 0.9)),
    materials: {{ "m": {material}, "floor": Diffuse(albedo: Constant((0.5, 0.5, 0.5))) }},
    entities: [
        Entity(name: "a", material: "m", shape: Mesh(path: "bunny.obj"), transform: Transform(translate: (-7, 0, 0), rotate: (0, 30, 0))),
        Entity(name: "b", material: "m", shape: Mesh(path: "bunny.obj"), transform: Transform(scale: (1.2, 1.2, 1.2))),
        Entity(name: "c", material: "m", shape: Mesh(path: "bunny.obj"), transform: Transform(translate: (7, 0, 2), rotate: (0, -60, 0))),
        Entity(name: "ground", material: "floor", shape: Mesh(path: "tri.obj"), transform: Transform(scale: (30, 1, 30))),
    ],
)"#
        ),
    )
}

#[test]
fn instanced_meshes_render_like_flattened_copies() {
    let dir = temp_dir("instanced-vs-flat");
    let path = instanced_scene(&dir, "Diffuse(albedo: Constant((0.7, 0.6, 0.5)))");
    let render_with = |instancing: bool| {
        let mut r = rondo::Renderer::new(None, rondo::PassPlan::Single).expect("pool");
        r.set_instancing(instancing);
        r.load(&path).unwrap_or_else(|e| panic!("{e}"));
        r.render_to_completion();
        r
    };
    let (inst, flat) = (render_with(true), render_with(false));
    // Instancing keeps the meshes out of the scene BVH: 4 placements instead of 3·3674 + 1.
    assert_eq!(inst.primitive_count(), 4);
    assert_eq!(flat.primitive_count(), 3 * 3674 + 1);
    // Object-space intersection rounds differently from world space, so pixels may differ in
    // the last bits, and a path grazing an edge may take another turn; the images must agree.
    let (a, b) = (inst.film().mean(), flat.film().mean());
    let diff: Vec<f32> = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (*x - *y).abs().max_element())
        .collect();
    let same = diff.iter().filter(|d| **d < 1e-4).count();
    assert!(
        same as f32 >= 0.97 * diff.len() as f32,
        "{same} of {} pixels agree",
        diff.len()
    );
    let mean = diff.iter().sum::<f32>() / diff.len() as f32;
    assert!(mean < 2e-3, "mean difference {mean}");
}

#[test]
fn a_material_edit_rebuilds_no_mesh_bvh_and_a_mesh_edit_rebuilds_only_that_mesh() {
    let dir = temp_dir("instanced-rebuilds");
    let path = instanced_scene(&dir, "Diffuse(albedo: Constant((0.7, 0.6, 0.5)))");
    let mut r = rondo::Renderer::new(None, rondo::PassPlan::Single).expect("pool");
    r.load(&path).expect("loads");
    r.render_to_completion();
    // Two distinct meshes, one BVH each, however many placements.
    assert_eq!(r.counters().mesh_bvh_builds, 2);
    assert_eq!(r.counters().bvh_builds, 1);

    instanced_scene(&dir, "Diffuse(albedo: Constant((0.2, 0.3, 0.9)))");
    r.load(&path).expect("reloads");
    r.render_to_completion();
    assert_eq!(
        (r.counters().bvh_builds, r.counters().mesh_bvh_builds),
        (1, 2)
    );

    // Edit the ground mesh (different size, so the cache sees the change): only it is rebuilt.
    write_scene(&dir, "tri.obj", "v -1 0 -1\nv 1 0 -1\nv 0 0 1.5\nf 1 2 3\n");
    r.load(&path).expect("reloads");
    r.render_to_completion();
    assert_eq!(
        (r.counters().bvh_builds, r.counters().mesh_bvh_builds),
        (2, 3)
    );
    assert_eq!(r.mesh_loads(), 3);
}

#[test]
fn obj_vertex_normals_give_interpolated_shading_normals_through_the_instance_transform() {
    use rondo::geometry::instance::{BlasCache, InstanceSet};
    use rondo::geometry::ray::Ray;
    let dir = temp_dir("obj-normals");
    let path = write_scene(
        &dir,
        "t.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn 0.6 0 0.8\nvn 0 0.6 0.8\nf 1//1 2//2 3//3\n",
    );
    let mesh = AssetCache::default().mesh(&path).expect("loads");
    assert!(mesh.normals.is_some());
    let blas = BlasCache::default().get(&mesh);
    let m = glam::Affine3A::from_scale(Vec3::new(2.0, 1.0, 1.0));
    let set = InstanceSet::build(vec![(0, blas, m)]);
    // Aim at the centroid (2/3, 1/3, 0) in world space.
    let target = Vec3::new(2.0 / 3.0, 1.0 / 3.0, 0.0);
    let ray = Ray::new(target + Vec3::Z, -Vec3::Z);
    let h = set.intersect(&ray, f32::INFINITY).expect("hit");
    let s = set.surface(h.instance, h.triangle, h.b1, h.b2);
    assert!((s.n - Vec3::Z).length() < 1e-6);
    // By hand: the mean vertex normal is (0.2, 0.2, 0.8667); normals transform by the inverse
    // transpose diag(1/2, 1, 1): (0.1, 0.2, 0.8667), normalised.
    let expected = Vec3::new(0.1, 0.2, 2.6 / 3.0).normalize();
    assert!((s.ns - expected).length() < 1e-4, "{} vs {expected}", s.ns);
}

#[test]
fn a_smooth_low_poly_sphere_renders_without_facets_or_nonfinite_samples() {
    // A 12×8 UV sphere with and without vertex normals, lit by a lamp: facet edges show as
    // jumps between neighbouring pixels, which smooth normals must reduce.
    let dir = temp_dir("smooth-sphere");
    write_scene(&dir, "flat.obj", &common::uv_sphere_obj(12, 8, false));
    write_scene(&dir, "smooth.obj", &common::uv_sphere_obj(12, 8, true));
    let scene = |mesh: &str| {
        write_scene(
            &dir,
            &format!("{mesh}.ron"),
            &format!(
                r#"Scene(
    camera: Camera(position: (0, 0, -3.2), look_at: (0, 0, 0), fov: 40),
    settings: Settings(width: 48, height: 48, spp: 128, max_depth: 3, background: (0, 0, 0)),
    materials: {{ "m": Diffuse(albedo: Constant((0.8, 0.8, 0.8))), "lamp": Light(emit: Constant((1, 1, 1)), intensity: 4) }},
    entities: [
        Entity(name: "ball", material: "m", shape: Mesh(path: "{mesh}.obj")),
        Entity(name: "lamp", material: "lamp", shape: Quad(a: (-2, 3, -3), b: (2, 3, -3), c: (2, 3, 1), d: (-2, 3, 1))),
    ],
)"#
            ),
        )
    };
    // Facets are horizontal bands: the curvature of the row-mean profile (second differences,
    // which a smooth ramp keeps small and steps make large) measures them; averaging a row's
    // pixels keeps the sampling noise out of it.
    let roughness = |r: &rondo::Renderer| {
        let px = r.film().mean();
        let rows: Vec<f32> = (8..40)
            .map(|y| (18..30).map(|x| px[y * 48 + x].x).sum::<f32>() / 12.0)
            .collect();
        rows.windows(3)
            .map(|w| (w[2] - 2.0 * w[1] + w[0]).abs())
            .sum::<f32>()
    };
    let flat = render(&scene("flat"), Overrides::default(), None);
    let smooth = render(&scene("smooth"), Overrides::default(), None);
    assert_eq!(smooth.stats().nonfinite, 0);
    let (f, s) = (roughness(&flat), roughness(&smooth));
    assert!(s < 0.6 * f, "row-profile curvature: smooth {s}, flat {f}");
}
