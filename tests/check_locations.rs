//! `rondo check` warnings name the file, line and column of the entity or material they are
//! about, in the scene or in the prefab the entity comes from.

mod common;

use common::{temp_dir, write_scene};

/// `line:col` (1-based) of the `nth` occurrence of `needle` in `text`, counted by hand.
fn line_col(text: &str, needle: &str, nth: usize) -> String {
    let at = text
        .match_indices(needle)
        .nth(nth)
        .unwrap_or_else(|| panic!("no {needle}"))
        .0;
    let line = text[..at].matches('\n').count() + 1;
    let line_start = text[..at].rfind('\n').map_or(0, |i| i + 1);
    format!("{line}:{}", text[line_start..at].chars().count() + 1)
}

#[test]
fn check_warnings_give_the_file_line_and_column_of_what_they_are_about() {
    let dir = temp_dir("check-locations");
    let prefab = r#"Prefab(
    materials: { "stone": Diffuse(albedo: Constant((0.5, 0.5, 0.5))) },
    entities: [
        Entity(name: "near", material: "stone", shape: Sphere(center: (0, 0, 0), radius: 1)),
        // Far beside the camera's view once placed.
        Entity(name: "rock", material: "stone", shape: Sphere(center: (500, 0, 0), radius: 1)),
    ])"#;
    write_scene(&dir, "far.ron", prefab);
    let scene = r#"Scene(
    camera: Camera(position: (0, 1, -10), look_at: (0, 0, 0)),
    materials: {
        "w": Diffuse(albedo: Constant((0.5, 0.5, 0.5))),
        "spare": Diffuse(albedo: Constant((0.5, 0.5, 0.5))),
    },
    entities: [
        Entity(name: "rug", material: "w",
               shape: Quad(a: (-1, 0, -1), b: (-1, 0, 1), c: (1, 0, 1), d: (1, 0, -1))),
        Entity(name: "mat", material: "w",
               shape: Quad(a: (0, 0, 0), b: (0, 0, 2), c: (2, 0, 2), d: (2, 0, 0))),
        Entity(name: "p", prefab: "far.ron"),
        Entity(material: "w", shape: Sphere(center: (0, 0, -400), radius: 1)),
    ],
)"#;
    let path = write_scene(&dir, "s.ron", scene);
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_rondo"))
        .arg("check")
        .arg(&path)
        .output()
        .expect("run rondo check");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    let (s, p) = (
        path.display().to_string(),
        dir.join("far.ron").display().to_string(),
    );
    let expected = [
        format!(
            "warning: {s}:{}: entities \"rug\" and \"mat\" overlap in one plane (z-fighting: which one is seen is decided by rounding); \"mat\" is at {s}:{}",
            line_col(scene, "\"rug\"", 0),
            line_col(scene, "\"mat\"", 0)
        ),
        format!(
            "warning: {s}:{}: material \"spare\" is defined but no entity uses it",
            line_col(scene, "\"spare\"", 0)
        ),
        format!(
            "warning: {p}:{}: entity \"p/rock\" is far outside the camera's view",
            line_col(prefab, "\"rock\"", 0)
        ),
        // The unnamed entity is located by its `Entity(` (the fourth of the scene).
        format!(
            "warning: {s}:{}: entity \"#3\" is far outside the camera's view",
            line_col(scene, "Entity(", 3)
        ),
    ];
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), expected.len() + 1, "{stdout}");
    for (line, want) in lines.iter().zip(&expected) {
        assert!(line.starts_with(want.as_str()), "got  {line}\nwant {want}…");
    }
    assert_eq!(lines[expected.len()], format!("{s}: 4 warnings"));
}

#[test]
fn a_warning_about_an_entity_named_like_a_material_points_at_the_entity() {
    let dir = temp_dir("check-locations-names");
    let scene = r#"Scene(
    camera: Camera(position: (0, 1, -10), look_at: (0, 0, 0)),
    materials: {
        "moon": Diffuse(albedo: Constant((0.5, 0.5, 0.5))),
    },
    entities: [
        Entity(name: "moon", material: "moon", shape: Sphere(center: (0, 0, -400), radius: 1)),
    ],
)"#;
    let path = write_scene(&dir, "s.ron", scene);
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_rondo"))
        .arg("check")
        .arg(&path)
        .output()
        .expect("run rondo check");
    let stdout = String::from_utf8_lossy(&out.stdout);
    // The material's key is the first "moon" of the file, the entity's name the second.
    let expected = format!(
        "warning: {}:{}: entity \"moon\" is far outside",
        path.display(),
        line_col(scene, "\"moon\"", 1)
    );
    assert!(
        stdout.lines().any(|l| l.starts_with(&expected)),
        "want {expected}…\ngot {stdout}"
    );
}

#[test]
fn a_warning_about_a_material_points_at_its_definition_after_the_entities_naming_it() {
    let dir = temp_dir("check-locations-materials");
    let scene = r#"Scene(
    camera: Camera(position: (0, 1, -10), look_at: (0, 0, 0)),
    entities: [
        Entity(name: "ball", material: "hot", shape: Sphere(center: (0, 0, 0), radius: 1)),
    ],
    materials: {
        "hot": Diffuse(albedo: Constant((1.5, 0.5, 0.5))),
    },
)"#;
    let path = write_scene(&dir, "s.ron", scene);
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_rondo"))
        .arg("check")
        .arg(&path)
        .output()
        .expect("run rondo check");
    let stdout = String::from_utf8_lossy(&out.stdout);
    // The entity's reference is the first "hot" of the file, the definition the second.
    let expected = format!(
        "warning: {}:{}: material \"hot\": albedo component",
        path.display(),
        line_col(scene, "\"hot\"", 1)
    );
    assert!(
        stdout.lines().any(|l| l.starts_with(&expected)),
        "want {expected}…\ngot {stdout}"
    );
}
