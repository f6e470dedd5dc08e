//! Bad input: every error names the file and, where one exists, the line and column.

mod common;

use common::{temp_dir, write_scene};
use rondo::scene::assets::AssetCache;
use rondo::scene::load::load_scene;

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

/// The line and column of an error's `…/scene.ron:line:col: ` prefix.
fn location(text: &str) -> (usize, usize) {
    let (line, col, _) = split(text);
    (line, col)
}

/// The message after an error's `…/scene.ron:line:col: ` prefix. The temporary path holds the
/// test's name, so assertions on words must look only here.
fn message(text: &str) -> &str {
    split(text).2
}

fn split(text: &str) -> (usize, usize, &str) {
    let (_, rest) = text
        .split_once("scene.ron:")
        .unwrap_or_else(|| panic!("no location in {text}"));
    let mut parts = rest.splitn(3, ':');
    let mut number = || {
        parts
            .next()
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("no line:col in {text}"))
    };
    let (line, col) = (number(), number());
    let message = parts
        .next()
        .and_then(|m| m.strip_prefix(' '))
        .unwrap_or_else(|| panic!("no message in {text}"));
    (line, col, message)
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
    assert_eq!(
        message(&e),
        "settings: spp must be a whole number >= 1 (got 0)"
    );
}

#[test]
fn negative_spp_is_rejected() {
    let src = "Scene(\n    camera: Camera(position: (0, 1, -5), look_at: (0, 1, 0)),\n    settings: Settings(spp: -4),\n)";
    let e = error_of("spp-neg", src);
    assert_eq!(location(&e).0, 3, "{e}");
    assert_eq!(
        message(&e),
        "settings: spp must be a whole number >= 1 (got -4)"
    );
}

#[test]
fn nan_and_infinite_numbers_are_rejected_where_they_stand() {
    for (name, value) in [("nan", "NaN"), ("inf", "inf")] {
        let src = format!(
            "{HEADER}    materials: {{ \"w\": Diffuse(albedo: Constant((1, 1, 1))) }},\n    entities: [\n        Entity(material: \"w\", shape: Sphere(center: (0, 0, 0), radius: {value})),\n    ],\n)"
        );
        let e = error_of(name, &src);
        assert_eq!(location(&e).0, 6, "{e}");
        assert_eq!(
            message(&e),
            format!("entity \"#0\": radius must be a finite number (got {value})")
        );
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
    let e = error_of("up-parallel", up);
    assert!(
        message(&e).starts_with("camera: ") && message(&e).contains("parallel"),
        "{e}"
    );
    let fov = "Scene(camera: Camera(position: (0, 0, 0), direction: (0, 0, 1), fov: 180))";
    let e = error_of("fov", fov);
    assert_eq!(
        message(&e),
        "camera: fov must be in (0, 180) degrees (got 180)"
    );
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

/// Loads `materials` and `entities` (RON text of the two fields) after a valid header.
fn scene_error(name: &str, materials: &str, entities: &str) -> String {
    error_of(
        name,
        &format!(
            "{HEADER}    materials: {{ {materials} }},\n    entities: [\n        {entities}\n    ],\n)"
        ),
    )
}

const WHITE: &str = "\"w\": Diffuse(albedo: Constant((1, 1, 1)))";
const BALL: &str =
    "Entity(name: \"ball\", material: \"w\", shape: Sphere(center: (0, 0, 0), radius: 1))";

#[test]
fn value_errors_name_the_field_and_the_entity_or_material() {
    let cases = [
        (
            "radius",
            WHITE.to_string(),
            BALL.replace("radius: 1", "radius: -1"),
            (6, "entity \"ball\": radius must be > 0 (got -1)"),
        ),
        (
            "center",
            WHITE.to_string(),
            BALL.replace("(0, 0, 0)", "(0, inf, 0)"),
            (6, "entity \"ball\": center must be a finite number (got inf)"),
        ),
        (
            "ior",
            format!("{WHITE}, \"glass\": Dielectric(ior: 0)"),
            BALL.to_string(),
            (4, "material \"glass\": ior must be > 0 (got 0)"),
        ),
        (
            "intensity",
            format!("{WHITE}, \"lamp\": Light(emit: Constant((1, 1, 1)), intensity: -2)"),
            BALL.to_string(),
            (4, "material \"lamp\": intensity must be >= 0 (got -2)"),
        ),
        (
            "albedo",
            WHITE.replace("(1, 1, 1)", "(1, -0.5, 1)"),
            BALL.to_string(),
            (4, "material \"w\": albedo must be >= 0 (got -0.5)"),
        ),
        (
            "checker",
            "\"c\": Diffuse(albedo: Checker(scale: NaN, even: Constant((1, 1, 1)), odd: Constant((0, 0, 0))))".to_string(),
            BALL.replace("\"w\"", "\"c\""),
            (4, "material \"c\": scale must be a finite number (got NaN)"),
        ),
        (
            "scale",
            WHITE.to_string(),
            BALL.replace("radius: 1)", "radius: 1), transform: Transform(scale: (1, 0, 1))"),
            (6, "entity \"ball\": scale must be non-zero on every axis (got [1, 0, 1])"),
        ),
        (
            "translate",
            WHITE.to_string(),
            BALL.replace("radius: 1)", "radius: 1), transform: Transform(translate: (1, 2, NaN))"),
            (6, "entity \"ball\": translate must be a finite number (got NaN)"),
        ),
        (
            "unnamed",
            WHITE.to_string(),
            "Entity(material: \"w\", shape: Triangle(a: (0, 0, 0), b: (1, 0, 0), c: (0, 1, -inf)))"
                .to_string(),
            (6, "entity \"#0\": c must be a finite number (got -inf)"),
        ),
    ];
    for (name, materials, entities, (line, expected)) in cases {
        let e = scene_error(name, &materials, &entities);
        assert_eq!(message(&e), expected, "{name}: {e}");
        assert_eq!(location(&e).0, line, "{name}: {e}");
    }
}

#[test]
fn settings_values_are_named() {
    let cases = [
        (
            "width: 0",
            "settings: width must be a whole number >= 1 (got 0)",
        ),
        (
            "height: 2.5",
            "settings: height must be a whole number >= 1 (got 2.5)",
        ),
        (
            "max_depth: -1",
            "settings: max_depth must be a whole number >= 1 (got -1)",
        ),
        (
            "spp: 2000000",
            "settings: spp must be at most 1048576 (got 2000000)",
        ),
        (
            "background: (0, -1, 0)",
            "settings: background must be >= 0 (got -1)",
        ),
        (
            "method: Fast",
            "settings: unknown method \"Fast\" (expected Naive, Nee, Mis, Caustics or Photons)",
        ),
    ];
    for (setting, expected) in cases {
        let src = format!(
            "Scene(\n    camera: Camera(position: (0, 1, -5), look_at: (0, 1, 0)),\n    settings: Settings({setting}),\n)"
        );
        let e = error_of(&setting.replace([' ', ':', '(', ')', ','], ""), &src);
        assert_eq!(message(&e), expected, "{e}");
        assert_eq!(location(&e).0, 3, "{e}");
    }
}

#[test]
fn kind_typos_list_the_kinds_in_the_users_words() {
    let e = scene_error("material-kind", &WHITE.replace("Diffuse", "Difuse"), BALL);
    assert_eq!(
        message(&e),
        "material \"w\": unknown material kind \"Difuse\" (expected Diffuse, Metal, Glossy, Dielectric, Light or Pbr)"
    );
    assert_eq!(location(&e).0, 4, "{e}");
    let e = scene_error("shape-kind", WHITE, &BALL.replace("Sphere", "Sphre"));
    assert_eq!(
        message(&e),
        "entity \"ball\": unknown shape kind \"Sphre\" (expected Sphere, Plane, Triangle, Quad, Box or Mesh)"
    );
    let e = scene_error("texture-kind", &WHITE.replace("Constant", "Constnt"), BALL);
    assert_eq!(
        message(&e),
        "material \"w\": unknown texture kind \"Constnt\" (expected Constant, Checker or Image)"
    );
    let e = scene_error("field", WHITE, &BALL.replace("radius", "radus"));
    assert_eq!(
        message(&e),
        "entity \"ball\": unknown field `radus` in Sphere (expected center or radius)"
    );
}

#[test]
fn value_errors_in_a_prefab_name_its_entity() {
    let dir = temp_dir("errors-prefab");
    write_scene(
        &dir,
        "part.ron",
        "Prefab(entities: [\n    Entity(name: \"knob\", material: \"m\", shape: Sphere(center: (0, 0, 0), radius: 0)),\n])",
    );
    let path = write_scene(
        &dir,
        "scene.ron",
        &format!(
            "{HEADER}    materials: {{ \"m\": Diffuse(albedo: Constant((1, 1, 1))) }},\n    entities: [ Entity(name: \"door\", prefab: \"part.ron\") ],\n)"
        ),
    );
    let Err(e) = load_scene(&path, &mut AssetCache::default()) else {
        panic!("a zero radius is an error");
    };
    let e = e.to_string();
    let (_, rest) = e.split_once("part.ron:2:").unwrap_or_else(|| panic!("{e}"));
    assert!(
        rest.ends_with(": entity \"knob\": radius must be > 0 (got 0)"),
        "{e}"
    );
}

/// A huge bad save gives an error of bounded size (an unbounded one would print a 50 MB save
/// as a 52 MB line) and a quoted line of at most 200 characters around the column.
#[test]
fn a_huge_bad_save_gives_a_bounded_message_and_source_line() {
    use rondo::scene::error::{MAX_MESSAGE, MAX_SOURCE_LINE};
    let long = "x".repeat(8 << 20);
    // One line: an entity named by 8 MB, an unknown material named by 8 MB, and after them
    // an unknown field, where the error points.
    let src = format!(
        "{HEADER}    materials: {{ \"m\": Diffuse(albedo: Constant((1, 1, 1))) }},\n    entities: [ Entity(name: \"{long}\", material: \"{long}y\", shape: Sphere(center: (0, 0, 0), radius: 1), colour: 1) ],\n)"
    );
    let dir = temp_dir("errors-huge");
    let path = write_scene(&dir, "scene.ron", &src);
    let e = load_scene(&path, &mut AssetCache::default()).expect_err("an unknown field");
    let text = e.to_string();
    assert!(text.len() <= MAX_MESSAGE, "{} bytes", text.len());
    assert!(e.message.len() <= MAX_MESSAGE, "{} bytes", e.message.len());
    let (line, col) = location(&text);
    assert_eq!(line, 5, "{}", &text[..200]);
    assert!(col > 2 * long.len(), "the column is past both names: {col}");
    assert!(
        message(&text).contains("unknown field `colour`"),
        "{}",
        &text[..200]
    );
    let quoted = e.source_line.expect("the scene's line is quoted");
    assert!(
        quoted.chars().count() <= MAX_SOURCE_LINE,
        "{} characters",
        quoted.chars().count()
    );
    assert!(
        quoted.starts_with('…') && quoted.ends_with("colour: 1) ],"),
        "a window around the column, to the end of the line: {quoted}"
    );

    // The unknown material's message names both 8 MB names: cut, keeping its start and its
    // end.
    let src = src.replace(", colour: 1", "");
    let path = write_scene(&dir, "scene.ron", &src);
    let e = load_scene(&path, &mut AssetCache::default()).expect_err("an unknown material");
    let text = e.to_string();
    assert!(text.len() <= MAX_MESSAGE, "{} bytes", text.len());
    assert!(
        message(&text).starts_with("entity \"xxx")
            && text.contains("xxx … xxx")
            && text.ends_with("xxxy\" (defined: m)"),
        "{text}"
    );
}

/// Control characters from a file (an escape sequence that would clear the
/// terminal, a bell, C1 controls, DEL) are escaped in the message and in the quoted line;
/// other characters, any script, are kept.
#[test]
fn control_characters_from_the_file_are_escaped() {
    let evil = "\u{1b}[2J\u{7}é\u{9b}31m\u{7f}猫";
    let src = format!(
        "{HEADER}    materials: {{ \"m\": Diffuse(albedo: Constant((1, 1, 1))) }},\n    entities: [ Entity(name: \"{evil}\", material: \"\t{evil}\", shape: Sphere(center: (0, 0, 0), radius: 1)) ],\n)"
    );
    let dir = temp_dir("errors-controls");
    let path = write_scene(&dir, "scene.ron", &src);
    let e = load_scene(&path, &mut AssetCache::default()).expect_err("an unknown material");
    let text = e.to_string();
    let quoted = e.source_line.clone().expect("a quoted line");
    for shown in [&text, &quoted] {
        assert!(
            !shown.chars().any(char::is_control),
            "a control character is shown as it is: {shown:?}"
        );
        assert!(
            shown.contains("\\u{1b}[2J\\u{7}é\\u{9b}31m\\u{7f}猫"),
            "{shown}"
        );
    }
    let line = src.lines().nth(4).expect("line 5");
    let col = line[..line.find("\"\t").expect("the material")]
        .chars()
        .count()
        + 1;
    assert_eq!(location(&text), (5, col), "{text}");
    assert!(
        quoted.contains("material: \" \\u{1b}"),
        "a tab is shown as one space: {quoted}"
    );
}

/// A file named as a prefab that is not a `.ron` file (a mesh, an image,
/// any file) is never quoted, even when its text is located by the parse error; a prefab is.
#[test]
fn source_lines_are_quoted_from_scene_and_prefab_files_only() {
    let dir = temp_dir("errors-quoting");
    write_scene(
        &dir,
        "tri.obj",
        "# secret\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    write_scene(
        &dir,
        "part.ron",
        "Prefab(entities: [\n    Entity(name: 1),\n])",
    );
    for (prefab, quoted) in [("tri.obj", false), ("part.ron", true)] {
        let path = write_scene(
            &dir,
            "scene.ron",
            &format!(
                "{HEADER}    materials: {{ \"m\": Diffuse(albedo: Constant((1, 1, 1))) }},\n    entities: [ Entity(name: \"door\", prefab: \"{prefab}\") ],\n)"
            ),
        );
        let e = load_scene(&path, &mut AssetCache::default()).expect_err("a bad prefab");
        assert!(e.path.ends_with(prefab), "{e}");
        assert!(e.location.is_some(), "{e}");
        assert_eq!(e.source_line.is_some(), quoted, "{prefab}: {e:?}");
    }
}

/// Numbers in errors stay short (1e308 is not printed as its 309 digits).
#[test]
fn huge_numbers_in_errors_are_written_short() {
    let src = format!(
        "{HEADER}    materials: {{ \"w\": Diffuse(albedo: Constant((1, 1, 1))) }},\n    entities: [\n        Entity(material: \"w\", shape: Sphere(center: (0, 0, 0), radius: 1e308)),\n    ],\n)"
    );
    let e = error_of("huge-number", &src);
    assert_eq!(
        message(&e),
        "entity \"#0\": radius must be a finite number (got 1e308)"
    );
    let src = format!(
        "{HEADER}    materials: {{ \"w\": Diffuse(albedo: Constant((1, 1, 1))) }},\n    entities: [\n        Entity(material: \"w\", shape: Sphere(center: (0, 0, 0), radius: -3e38)),\n    ],\n)"
    );
    let e = error_of("huge-negative", &src);
    assert_eq!(message(&e), "entity \"#0\": radius must be > 0 (got -3e38)");
}

/// Too deep a nesting says what to do, not which `ron` option to change.
#[test]
fn too_deep_a_nesting_is_named_in_the_users_words() {
    let depth = 300;
    let src = format!(
        "{HEADER}    materials: {{ \"m\": Diffuse(albedo: {}Constant((1, 1, 1)){}) }},\n)",
        "Checker(scale: 1, odd: Constant((0, 0, 0)), even: ".repeat(depth),
        ")".repeat(depth)
    );
    let e = error_of("deep", &src);
    assert!(
        message(&e).contains("nesting deeper than 128 levels") && !e.contains("ron::"),
        "{e}"
    );
}

#[test]
fn an_image_texture_takes_its_filter_and_wrap_and_refuses_unknown_ones() {
    use rondo::shading::material::Material;
    use rondo::shading::texture::{Filter, Sampling, Texture, Wrap};
    let dir = temp_dir("texture-sampling");
    image::Rgb32FImage::from_raw(2, 2, vec![0.5; 12])
        .expect("buffer")
        .save(dir.join("t.exr"))
        .expect("write texture");
    let scene = |texture: &str| {
        write_scene(
            &dir,
            "scene.ron",
            &format!(
                "{HEADER}    materials: {{\n        \"m\": Diffuse(albedo: {texture}),\n    }},\n)"
            ),
        )
    };
    let sampling_of = |texture: &str| {
        let loaded = load_scene(&scene(texture), &mut AssetCache::default()).expect("loads");
        match &loaded.materials["m"] {
            Material::Diffuse {
                albedo: Texture::Image(_, s),
            } => *s,
            other => panic!("{other:?}"),
        }
    };
    assert_eq!(sampling_of("Image(path: \"t.exr\")"), Sampling::default());
    assert_eq!(
        sampling_of("Image(path: \"t.exr\", filter: Bilinear, wrap: MirroredRepeat)"),
        Sampling {
            filter: Filter::Bilinear,
            wrap: [Wrap::MirroredRepeat; 2]
        }
    );
    let e = load_scene(
        &scene("Image(path: \"t.exr\", filter: Trilinear)"),
        &mut AssetCache::default(),
    )
    .expect_err("unknown filter")
    .to_string();
    assert_eq!(location(&e).0, 5, "{e}");
    assert!(e.contains("Trilinear") && e.contains("Bilinear"), "{e}");
}

#[test]
fn degenerate_input_is_rejected_at_load_time_with_a_located_message() {
    // Degenerate shapes, numbers beyond what f32 arithmetic survives, unusable cameras and
    // settings beyond the render limits. Each: the scene text, the line the message must point
    // at, and words it must contain.
    let cam = "camera: Camera(position: (0, 1, -5), look_at: (0, 1, 0))";
    let with = |entity: &str| {
        format!(
            "Scene(\n    {cam},\n    materials: {{ \"w\": Diffuse(albedo: Constant((0.5, 0.5, 0.5))) }},\n    entities: [\n        Entity(material: \"w\", {entity}),\n    ],\n)"
        )
    };
    let cases: Vec<(&str, String, usize, &str)> = vec![
        ("collinear quad", with("shape: Quad(a: (0, 0, 0), b: (1, 0, 0), c: (2, 0, 0), d: (0, 1, 0))"), 5, "quad: zero area"),
        ("repeated quad corner", with("shape: Quad(a: (0, 0, 0), b: (1, 0, 0), c: (1, 1, 0), d: (1, 1, 0))"), 5, "quad: zero area"),
        ("sliver triangle", with("shape: Triangle(a: (0, 0, 0), b: (1, 0, 0), c: (0.5, 1e-7, 0))"), 5, "triangle: zero area"),
        ("negative radius", with("shape: Sphere(center: (0, 0, 0), radius: -1)"), 5, "radius must be > 0 (got -1)"),
        ("infinite radius", with("shape: Sphere(center: (0, 0, 0), radius: inf)"), 5, "finite"),
        ("NaN centre", with("shape: Sphere(center: (0, NaN, 0), radius: 1)"), 5, "finite"),
        ("NaN plane normal", with("shape: Plane(point: (0, 0, 0), normal: (0, NaN, 1))"), 5, "finite"),
        ("tiny plane normal", with("shape: Plane(point: (0, 0, 0), normal: (0, 1e-30, 0))"), 5, "`normal` must be non-zero"),
        ("zero scale", with("shape: Sphere(center: (0, 0, 0), radius: 1), transform: Transform(scale: (1, 0, 1))"), 5, "scale"),
        ("infinite translate", with("shape: Sphere(center: (0, 0, 0), radius: 1), transform: Transform(translate: (-inf, 0, 0))"), 5, "finite"),
        ("number beyond f32", with("shape: Sphere(center: (1e39, 0, 0), radius: 1)"), 5, "finite"),
        // Finite but too large: f32 products of such coordinates overflow (a 10²⁰ triangle's
        // normal would be NaN and panic the render).
        ("10²⁰ triangle", with("shape: Triangle(a: (-1e20, -1, 5), b: (1e20, -1, 5), c: (0, 1e20, 5))"), 5, "reaches 1e20 in world space, beyond ±1e9"),
        ("10²⁵ scale", with("shape: Triangle(a: (-1, -1, 5), b: (1, -1, 5), c: (0, 1, 5)), transform: Transform(scale: (1e25, 1e25, 1e25))"), 5, "in world space, beyond ±1e9"),
        ("2·10⁹ sphere", with("shape: Sphere(center: (0, 0, 0), radius: 2e9)"), 5, "reaches 2e9 in world space"),
        ("10³⁰ plane point", with("shape: Plane(point: (0, -1e30, 0), normal: (0, 1, 0))"), 5, "reaches 1e30 in world space"),
        ("camera at 10¹⁰", "Scene(\n    camera: Camera(position: (1e10, 0, 0), direction: (0, 0, 1)),\n)".into(), 2, "position must be within ±1e9"),
        ("NaN colour", "Scene(\n    camera: Camera(position: (0, 1, -5), look_at: (0, 1, 0)),\n    materials: { \"w\": Diffuse(albedo: Constant((0.5, NaN, 0.5))) },\n)".into(), 3, "finite"),
        ("negative colour", "Scene(\n    camera: Camera(position: (0, 1, -5), look_at: (0, 1, 0)),\n    materials: { \"w\": Diffuse(albedo: Constant((0.5, -1, 0.5))) },\n)".into(), 3, "albedo must be >= 0 (got -1)"),
        ("NaN camera", "Scene(\n    camera: Camera(position: (NaN, 1, -5), look_at: (0, 1, 0)),\n)".into(), 2, "finite"),
        ("look_at = position", "Scene(\n    camera: Camera(position: (0, 1, -5), look_at: (0, 1, -5)),\n)".into(), 2, "view direction is zero"),
        ("zero up", "Scene(\n    camera: Camera(position: (0, 1, -5), look_at: (0, 1, 0), up: (0, 0, 0)),\n)".into(), 2, "`up` must be non-zero and not parallel"),
        ("up parallel, opposite", "Scene(\n    camera: Camera(position: (0, 0, 0), direction: (0, 0, 1), up: (0, 0, -3)),\n)".into(), 2, "`up` must be non-zero and not parallel"),
        ("fov 0", "Scene(\n    camera: Camera(position: (0, 0, 0), direction: (0, 0, 1), fov: 0),\n)".into(), 2, "fov must be in (0, 180) degrees (got 0)"),
        ("negative fov", "Scene(\n    camera: Camera(position: (0, 0, 0), direction: (0, 0, 1), fov: -30),\n)".into(), 2, "fov must be in (0, 180) degrees (got -30)"),
        ("10⁶×10⁶ image", "Scene(\n    camera: Camera(position: (0, 0, 0), direction: (0, 0, 1)),\n    settings: Settings(width: 1000000, height: 1000000),\n)".into(), 3, "width must be at most 16384 (got 1000000)"),
        ("image over the pixel budget", "Scene(\n    camera: Camera(position: (0, 0, 0), direction: (0, 0, 1)),\n    settings: Settings(width: 16384, height: 16384),\n)".into(), 3, "width × height must be at most"),
        ("10¹² spp", "Scene(\n    camera: Camera(position: (0, 0, 0), direction: (0, 0, 1)),\n    settings: Settings(spp: 1000000000000),\n)".into(), 3, "spp"),
        ("spp over the limit", "Scene(\n    camera: Camera(position: (0, 0, 0), direction: (0, 0, 1)),\n    settings: Settings(spp: 1048577),\n)".into(), 3, "spp must be at most 1048576 (got 1048577)"),
        ("max_depth over the limit", "Scene(\n    camera: Camera(position: (0, 0, 0), direction: (0, 0, 1)),\n    settings: Settings(max_depth: 100000),\n)".into(), 3, "max_depth must be at most 1024 (got 100000)"),
        ("NaN background", "Scene(\n    camera: Camera(position: (0, 0, 0), direction: (0, 0, 1)),\n    settings: Settings(background: (NaN, 0, 0)),\n)".into(), 3, "finite"),
        ("NaN intensity", "Scene(\n    camera: Camera(position: (0, 0, 0), direction: (0, 0, 1)),\n    materials: { \"l\": Light(emit: Constant((1, 1, 1)), intensity: NaN) },\n)".into(), 3, "finite"),
        ("NaN ior", "Scene(\n    camera: Camera(position: (0, 0, 0), direction: (0, 0, 1)),\n    materials: { \"g\": Dielectric(ior: NaN) },\n)".into(), 3, "finite"),
        ("zero ior", "Scene(\n    camera: Camera(position: (0, 0, 0), direction: (0, 0, 1)),\n    materials: { \"g\": Dielectric(ior: 0) },\n)".into(), 3, "ior must be > 0 (got 0)"),
    ];
    for (name, source, line, words) in cases {
        let e = error_of(name, &source);
        assert!(e.contains(&format!("scene.ron:{line}:")), "{name}: {e}");
        assert!(e.contains(words), "{name}: {e}");
    }
}

#[test]
fn an_entity_named_like_a_material_is_located_at_its_own_name() {
    // The material "ball" is defined (line 5) before the entity "ball" (line 8) whose sphere
    // reaches beyond the coordinate limit: the error points at the entity's name, not at the
    // first string "ball" of the file.
    let source = format!(
        "{HEADER}    materials: {{
        \"ball\": Diffuse(albedo: Constant((0.5, 0.5, 0.5))),
    }},
    entities: [
        Entity(name: \"floor\", material: \"ball\", shape: Plane(point: (0, 0, 0), normal: (0, 1, 0))),
        Entity(name: \"ball\", material: \"ball\", shape: Sphere(center: (0, 1e12, 0), radius: 1)),
    ],
)"
    );
    let text = error_of("entity-like-material", &source);
    let line = source
        .lines()
        .position(|l| l.contains("name: \"ball\""))
        .expect("entity")
        + 1;
    let col = source
        .lines()
        .nth(line - 1)
        .expect("line")
        .find("\"ball\"")
        .expect("name")
        + 1;
    assert_eq!(location(&text), (line, col), "{text}");
    assert!(message(&text).contains("beyond"), "{text}");
}
