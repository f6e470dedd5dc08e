//! Bad input: every error names the file and, where one exists, the line and column.

mod common;

use common::{temp_dir, write_scene};
use rondo::scene::load::{AssetCache, load_scene};

const HEADER: &str = r#"Scene(
    camera: Camera(position: (0, 1, -5), look_at: (0, 1, 0)),
    settings: Settings(width: 8, height: 8, spp: 1),
"#;

/// Loads `body` appended to a valid header; returns the error text.
fn error_of(name: &str, source: &str) -> String {
    let dir = temp_dir(&format!("errors-{name}"));
    let path = write_scene(&dir, "scene.ron", source);
    match load_scene(&path, &mut AssetCache::default()) {
        Ok(_) => panic!("{name}: expected an error"),
        Err(e) => {
            let text = e.to_string();
            assert!(text.starts_with(&path.display().to_string()), "{text}");
            text
        }
    }
}

fn location(text: &str) -> (usize, usize) {
    let rest = text
        .split("scene.ron:")
        .nth(1)
        .unwrap_or_else(|| panic!("no location in {text}"));
    let mut parts = rest.split(':');
    let line = parts
        .next()
        .and_then(|l| l.parse().ok())
        .unwrap_or_else(|| panic!("{text}"));
    let col = parts
        .next()
        .and_then(|c| c.parse().ok())
        .unwrap_or_else(|| panic!("{text}"));
    (line, col)
}

#[test]
fn truncated_file_reports_where_it_ends() {
    let src = format!("{HEADER}    materials: {{ \"a\": Diffuse(albedo: Constant((1, 1");
    let e = error_of("truncated", &src);
    assert_eq!(location(&e).0, 4, "{e}");
}

#[test]
fn unknown_material_points_at_the_entity() {
    let src = format!(
        "{HEADER}    materials: {{ \"white\": Diffuse(albedo: Constant((1, 1, 1))) }},\n    entities: [\n        Entity(name: \"ball\", material: \"whit\", shape: Sphere(center: (0, 0, 0), radius: 1)),\n    ],\n)"
    );
    let e = error_of("unknown-material", &src);
    assert_eq!(location(&e), (6, 40), "{e}");
    assert!(
        e.contains("unknown material \"whit\"") && e.contains("white"),
        "{e}"
    );
}

#[test]
fn missing_texture_points_at_its_path() {
    let src = format!(
        "{HEADER}    materials: {{\n        \"tex\": Diffuse(albedo: Image(path: \"nope.png\")),\n    }},\n)"
    );
    let e = error_of("missing-texture", &src);
    assert_eq!(location(&e), (5, 44), "{e}");
    assert!(e.contains("nope.png"), "{e}");
}

#[test]
fn zero_spp_is_rejected_at_its_value() {
    let src = "Scene(\n    camera: Camera(position: (0, 1, -5), look_at: (0, 1, 0)),\n    settings: Settings(spp: 0),\n)";
    let e = error_of("spp0", src);
    assert_eq!(location(&e).0, 3, "{e}");
    assert!(e.contains("nonzero") || e.contains("zero"), "{e}");
}

#[test]
fn negative_spp_is_rejected() {
    let src = "Scene(\n    camera: Camera(position: (0, 1, -5), look_at: (0, 1, 0)),\n    settings: Settings(spp: -4),\n)";
    let e = error_of("spp-neg", src);
    assert_eq!(location(&e).0, 3, "{e}");
}

#[test]
fn nan_and_infinite_numbers_are_rejected_where_they_stand() {
    for (name, value) in [("nan", "NaN"), ("inf", "inf")] {
        let src = format!(
            "{HEADER}    materials: {{ \"w\": Diffuse(albedo: Constant((1, 1, 1))) }},\n    entities: [\n        Entity(material: \"w\", shape: Sphere(center: (0, 0, 0), radius: {value})),\n    ],\n)"
        );
        let e = error_of(name, &src);
        assert_eq!(location(&e).0, 6, "{e}");
        assert!(e.contains("finite"), "{e}");
    }
}

#[test]
fn degenerate_shapes_and_cameras_are_rejected() {
    let cases = [
        ("zero-radius", "Sphere(center: (0, 0, 0), radius: 0)"),
        (
            "zero-area",
            "Triangle(a: (0, 0, 0), b: (1, 1, 1), c: (2, 2, 2))",
        ),
        ("zero-normal", "Plane(point: (0, 0, 0), normal: (0, 0, 0))"),
        ("flat-box", "Box(min: (0, 0, 0), max: (1, 0, 1))"),
    ];
    for (name, shape) in cases {
        let src = format!(
            "{HEADER}    materials: {{ \"w\": Diffuse(albedo: Constant((1, 1, 1))) }},\n    entities: [ Entity(material: \"w\", shape: {shape}) ],\n)"
        );
        let e = error_of(name, &src);
        assert_eq!(location(&e).0, 5, "{name}: {e}");
    }
    let up = "Scene(camera: Camera(position: (0, 0, 0), direction: (0, 2, 0), up: (0, 1, 0)))";
    assert!(error_of("up-parallel", up).contains("parallel"));
    let fov = "Scene(camera: Camera(position: (0, 0, 0), direction: (0, 0, 1), fov: 180))";
    assert!(error_of("fov", fov).contains("fov"));
}

#[test]
fn duplicate_names_unknown_fields_and_stretched_spheres_are_rejected() {
    let dup = format!(
        "{HEADER}    materials: {{ \"w\": Diffuse(albedo: Constant((1, 1, 1))) }},\n    entities: [\n        Entity(name: \"a\", material: \"w\", shape: Sphere(center: (0, 0, 0), radius: 1)),\n        Entity(name: \"a\", material: \"w\", shape: Sphere(center: (3, 0, 0), radius: 1)),\n    ],\n)"
    );
    let e = error_of("dup", &dup);
    assert_eq!(location(&e).0, 7, "{e}");
    let unknown = format!("{HEADER}    colour: (1, 1, 1),\n)");
    let e = error_of("unknown-field", &unknown);
    assert_eq!(location(&e).0, 4, "{e}");
    let stretched = format!(
        "{HEADER}    materials: {{ \"w\": Diffuse(albedo: Constant((1, 1, 1))) }},\n    entities: [\n        Entity(name: \"egg\", material: \"w\", shape: Sphere(center: (0, 0, 0), radius: 1),\n               transform: Transform(scale: (1, 2, 1))),\n    ],\n)"
    );
    let e = error_of("stretched", &stretched);
    assert!(e.contains("non-uniform"), "{e}");
    assert_eq!(location(&e).0, 6, "{e}");
}

#[test]
fn integers_are_accepted_where_floats_are_expected() {
    let dir = temp_dir("integers");
    let src = format!(
        "{HEADER}    materials: {{ \"w\": Metal(albedo: Constant((1, 1, 1)), roughness: 2) }},\n    entities: [ Entity(material: \"w\", shape: Sphere(center: (0, 0, 0), radius: 1)) ],\n)"
    );
    let path = write_scene(&dir, "scene.ron", &src);
    let scene = load_scene(&path, &mut AssetCache::default()).expect("integers parse");
    assert_eq!(scene.entities.len(), 1);
    assert_eq!(scene.entities[0].name, "#0");
    // Roughness is clamped to [0, 1].
    let m = &scene.materials["w"];
    assert!(
        matches!(m, rondo::shading::material::Material::Metal { roughness, .. } if *roughness == 1.0)
    );
}

#[test]
fn the_binary_exits_non_zero_with_a_located_message_and_no_panic() {
    let dir = temp_dir("cli-error");
    let path = write_scene(
        &dir,
        "scene.ron",
        "Scene(camera: Camera(position: (0, 0, 0), direction: (0, 0, 1)), settings: Settings(spp: 0))",
    );
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_rondo"))
        .args(["render"])
        .arg(&path)
        .args(["-o"])
        .arg(dir.join("out.png"))
        .output()
        .expect("run rondo");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("scene.ron:1:") && !stderr.contains("panicked"),
        "{stderr}"
    );
    assert!(!dir.join("out.png").exists());
}

#[test]
fn an_explicit_name_cannot_collide_with_a_default_one() {
    let src = format!(
        "{HEADER}    materials: {{ \"w\": Diffuse(albedo: Constant((1, 1, 1))) }},\n    entities: [\n        Entity(name: \"#1\", material: \"w\", shape: Sphere(center: (0, 0, 0), radius: 1)),\n        Entity(material: \"w\", shape: Sphere(center: (3, 0, 0), radius: 1)),\n    ],\n)"
    );
    let e = error_of("default-name", &src);
    assert!(e.contains("duplicate entity name \"#1\""), "{e}");
    assert_eq!(location(&e).0, 7, "{e}");
}
