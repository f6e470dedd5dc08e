//! Point and spot lights (`lights: [Point(…), Spot(…)]`, glTF's `KHR_lights_punctual`) and glTF
//! cameras (`camera: Gltf(placement, camera)`). Expected values are closed forms: irradiance
//! `I cos θ / r²` from a point light, the spec's cone falloff, the node transforms composed by
//! hand.

mod common;

use common::gltf_doc::{Bin, doc};
use common::{point_camera, render, temp_dir, with, write_scene};
use glam::Vec3;
use rondo::scene::assets::AssetCache;
use rondo::scene::format::Method;
use rondo::scene::load::{LoadedScene, load_scene};
use rondo::{PassPlan, Renderer};
use serde_json::{Value, json};

const ALBEDO: f64 = 0.5;

/// A scene of one diffuse ground quad (albedo [`ALBEDO`]) at y = 0 lit only by `lights`, seen
/// by a camera of vanishing field of view from above the ground point `(x, 0, z)`.
fn ground_scene(lights: &str, x: f64, z: f64) -> String {
    let camera = point_camera(
        &format!("({}, 1, {})", x + 0.3, z + 0.2),
        &format!("({x}, 0, {z})"),
        "(0, 1, 0)",
    );
    format!(
        r#"Scene(
    camera: {camera},
    settings: Settings(width: 4, height: 4, spp: 2, max_depth: 4),
    lights: [{lights}],
    materials: {{ "ground": Diffuse(albedo: Constant(({ALBEDO}, {ALBEDO}, {ALBEDO}))) }},
    entities: [
        Entity(name: "ground", material: "ground",
               shape: Quad(a: (-50, 0, 50), b: (50, 0, 50), c: (50, 0, -50), d: (-50, 0, -50))),
    ],
)"#
    )
}

/// Every pixel of the render of `source` under `method`: each sees the same ground point.
fn pixels(source: &str, method: Method) -> Vec<Vec3> {
    let dir = temp_dir("punctual");
    let path = write_scene(&dir, "s.ron", source);
    render(&path, with(method, 2), Some(1)).film().mean()
}

/// Radiance of the diffuse ground at `(x, 0, z)` lit by intensity `i` from `light`, times
/// `falloff`: ρ/π · I cos θ / r².
fn expected(light: [f64; 3], x: f64, z: f64, i: f64, falloff: f64) -> f64 {
    let d = [light[0] - x, light[1], light[2] - z];
    let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    let cos = d[1] / r2.sqrt();
    ALBEDO / std::f64::consts::PI * i * falloff * cos / r2
}

fn assert_close(got: &[Vec3], want: f64, what: &str) {
    assert_within(got, want, 1e-4, what);
}

/// Every channel of every pixel within `rel` of `want`.
fn assert_within(got: &[Vec3], want: f64, rel: f64, what: &str) {
    for p in got {
        for c in p.to_array() {
            let err = (f64::from(c) - want).abs();
            assert!(
                err <= rel * want + 1e-9,
                "{what}: pixel {c} vs I cos θ / r² radiance {want}"
            );
        }
    }
}

#[test]
fn a_point_light_gives_i_cos_theta_over_r_squared() {
    // Light sampling of a lone point light on a diffuse surface has no variance: every sample
    // is the closed form (the BSDF-sampled bounce finds nothing to light it).
    let light = [0.0, 2.0, 0.0];
    for (x, z) in [(0.0, 0.0), (1.0, 0.5), (-2.5, 1.0), (4.0, -3.0)] {
        let lights = "Point(position: (0, 2, 0), intensity: 3, colour: (1, 1, 1))";
        let want = expected(light, x, z, 3.0, 1.0);
        for method in [Method::Mis, Method::Nee] {
            let got = pixels(&ground_scene(lights, x, z), method);
            assert_close(&got, want, &format!("({x}, {z}) {method}"));
        }
    }
}

#[test]
fn a_coloured_light_scales_each_channel() {
    let lights = "Point(position: (0, 2, 0), intensity: 2, colour: (1, 0.5, 0.25))";
    let got = pixels(&ground_scene(lights, 0.5, 0.0), Method::Mis);
    let want = expected([0.0, 2.0, 0.0], 0.5, 0.0, 2.0, 1.0);
    for p in got {
        let rel = (p / want as f32) - Vec3::new(1.0, 0.5, 0.25);
        assert!(rel.abs().max_element() < 1e-4, "{p} vs {want} × colour");
    }
}

/// glTF's informative cone falloff, as the spec writes it (angles in radians).
fn spec_falloff(inner: f64, outer: f64, cos: f64) -> f64 {
    let scale = 1.0 / (inner.cos() - outer.cos()).max(0.001);
    let offset = -outer.cos() * scale;
    let a = (cos * scale + offset).clamp(0.0, 1.0);
    a * a
}

#[test]
fn a_spot_is_full_inside_dark_outside_and_follows_the_spec_between() {
    let lights = "Spot(position: (0, 2, 0), direction: (0, -1, 0), intensity: 4, inner_angle: 20, outer_angle: 30)";
    let (inner, outer) = (20f64.to_radians(), 30f64.to_radians());
    for degrees in [0.0, 12.0, 19.5, 21.0, 25.0, 29.0, 31.0, 40.0] {
        let a = f64::to_radians(degrees);
        let x = 2.0 * a.tan();
        let falloff = spec_falloff(inner, outer, a.cos());
        let want = expected([0.0, 2.0, 0.0], x, 0.0, 4.0, falloff);
        let got = pixels(&ground_scene(lights, x, 0.0), Method::Mis);
        if degrees < 20.0 {
            assert_eq!(falloff, 1.0, "inside the inner cone");
        } else if degrees > 30.0 {
            assert_eq!(falloff, 0.0, "outside the outer cone");
            assert!(got.iter().all(|p| *p == Vec3::ZERO), "{degrees}°: {got:?}");
        } else {
            assert!(falloff > 0.0 && falloff < 1.0);
        }
        // In the ramp the falloff changes by ~6 per radian: the camera's 10⁻⁵ jitter and the
        // f32 cosines move it by up to ~10⁻⁴ of itself.
        let rel = if falloff < 1.0 { 1e-3 } else { 1e-4 };
        assert_within(&got, want, rel, &format!("{degrees}° off the axis"));
    }
}

#[test]
fn editing_a_light_renders_what_a_fresh_render_shows() {
    let dir = temp_dir("punctual-edit");
    let first = ground_scene("Point(position: (0, 2, 0), intensity: 3)", 0.5, 0.5);
    let path = write_scene(&dir, "s.ron", &first);
    let mut live = Renderer::new(Some(1), PassPlan::Single).expect("pool");
    live.load(&path).unwrap_or_else(|e| panic!("{e}"));
    live.render_to_completion();
    let before = live.film().mean();
    let builds = live.counters().bvh_builds;

    let edited = first.replace("position: (0, 2, 0)", "position: (0.5, 1, 0)");
    std::fs::write(&path, &edited).expect("write");
    live.load(&path).unwrap_or_else(|e| panic!("{e}"));
    live.render_to_completion();
    let changes = live.change_summary();
    assert!(changes.lights, "{changes:?}");
    assert_eq!(changes.changed + changes.added + changes.removed, 0);
    assert_eq!(
        live.counters().bvh_builds,
        builds,
        "a light edit builds no BVH"
    );
    let after = live.film().mean();
    let fresh = render(&path, Default::default(), Some(1)).film().mean();
    assert_eq!(after, fresh, "the edit renders as the file renders");
    assert_ne!(after, before, "the edit changed the image");
    assert_close(
        &after,
        expected([0.5, 1.0, 0.0], 0.5, 0.5, 3.0, 1.0),
        "moved",
    );
}

/// A glTF file with a camera, a point light, a spot and a directional light, each on its own
/// node, plus a triangle (so the file also places an entity).
fn lit_gltf(lights: Value, cameras: Value) -> Value {
    let mut bin = Bin::default();
    let v = bin.f32s(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    // A quarter turn about x by −90°: the node's −z points down (−y).
    let down = [
        -std::f32::consts::FRAC_1_SQRT_2,
        0.0,
        0.0,
        std::f32::consts::FRAC_1_SQRT_2,
    ];
    let parts = json!({
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": lights}},
        "accessors": [{"bufferView": v, "componentType": 5126, "count": 3, "type": "VEC3"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "cameras": cameras,
        "nodes": [
            {"name": "cam", "camera": 0, "translation": [0.0, 1.0, 5.0]},
            {"name": "bulb", "translation": [1.0, 2.0, 0.0],
             "extensions": {"KHR_lights_punctual": {"light": 0}}},
            {"name": "spot", "translation": [0.0, 3.0, 0.0], "rotation": down,
             "extensions": {"KHR_lights_punctual": {"light": 1}}},
            {"name": "sun", "rotation": down,
             "extensions": {"KHR_lights_punctual": {"light": 2}}},
            {"name": "tri", "mesh": 0},
        ],
        "scenes": [{"nodes": [0, 1, 2, 3, 4]}],
    });
    doc(&bin, parts)
}

fn good_lights() -> Value {
    json!([
        {"type": "point", "intensity": 5.0, "color": [1.0, 0.5, 0.25], "name": "bulb"},
        {"type": "spot", "intensity": 7.0, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.4}},
        {"type": "directional", "intensity": 2.0},
    ])
}

/// [`good_lights`] with its first light replaced by `bad`.
fn first_light(bad: Value) -> Value {
    let mut lights = good_lights();
    lights[0] = bad;
    lights
}

fn perspective() -> Value {
    json!([{"type": "perspective", "perspective": {"yfov": 0.6, "aspectRatio": 1.0, "znear": 0.1}}])
}

/// Loads a scene placing `gltf` as "model", translated by (10, 0, 0) and scaled by 2, with the
/// scene's `camera` and `lights`.
fn load_placed(gltf: &Value, camera: &str, lights: &str) -> Result<LoadedScene, String> {
    let dir = temp_dir("punctual-gltf");
    std::fs::write(dir.join("m.gltf"), gltf.to_string()).expect("write");
    let source = format!(
        r#"Scene(
    camera: {camera},
    settings: Settings(width: 8, height: 8, spp: 1),
    lights: [{lights}],
    entities: [
        Entity(name: "model", gltf: "m.gltf",
               transform: Transform(translate: (10, 0, 0), scale: (2, 2, 2))),
    ],
)"#
    );
    let path = write_scene(&dir, "s.ron", &source);
    load_scene(&path, &mut AssetCache::default()).map_err(|e| e.to_string())
}

#[test]
fn gltf_lights_and_camera_load_where_their_nodes_put_them() {
    let gltf = lit_gltf(good_lights(), perspective());
    let scene = load_placed(
        &gltf,
        r#"Gltf(placement: "model", camera: "cam")"#,
        "Point(position: (0, 9, 0), intensity: 1)",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    // The scene's own light first, then the file's points and spots in node order.
    assert_eq!(scene.lights.len(), 3);
    assert_eq!(scene.lights[0].position, Vec3::new(0.0, 9.0, 0.0));
    let bulb = &scene.lights[1];
    assert_eq!(
        bulb.position,
        Vec3::new(12.0, 4.0, 0.0),
        "2 × (1, 2, 0) + (10, 0, 0)"
    );
    assert_eq!(
        bulb.intensity,
        Vec3::new(5.0, 2.5, 1.25),
        "candela × colour, unscaled"
    );
    assert!(bulb.cone.is_none());
    let spot = &scene.lights[2];
    assert!(
        (spot.position - Vec3::new(10.0, 6.0, 0.0)).length() < 1e-5,
        "{}",
        spot.position
    );
    assert_eq!(spot.intensity, Vec3::splat(7.0));
    for angle in [0.0f32, 0.1, 0.25, 0.3, 0.35, 0.45] {
        // Directions `angle` away from straight down: the node's −z after the quarter turn.
        let d = Vec3::new(angle.sin(), -angle.cos(), 0.0);
        let want = 7.0 * spec_falloff(0.2, 0.4, f64::from(angle.cos()));
        let got = f64::from(spot.intensity_towards(d).x);
        assert!((got - want).abs() < 1e-4, "{angle}: {got} vs {want}");
    }
    // The directional light is the sun: from straight above, 2 lux on a facing plane.
    let sun = scene
        .settings
        .sun
        .expect("a sun from the directional light");
    assert!(
        (sun.direction - Vec3::Y).length() < 1e-6,
        "{}",
        sun.direction
    );
    let half = f64::from(sun.angular_diameter).to_radians() / 2.0;
    let irradiance = f64::from(sun.radiance.x) * std::f64::consts::PI * half.sin().powi(2);
    assert!((irradiance - 2.0).abs() < 1e-4, "{irradiance}");
    assert!(scene.sky.sun.is_some());
    // The camera: at 2 × (0, 1, 5) + (10, 0, 0), looking along −z, y up, yfov 0.6 rad.
    let c = scene.camera;
    assert!(
        (c.position - Vec3::new(10.0, 2.0, 10.0)).length() < 1e-5,
        "{}",
        c.position
    );
    assert!(
        c.direction.normalize().dot(Vec3::NEG_Z) > 1.0 - 1e-6,
        "{}",
        c.direction
    );
    assert!(c.up.normalize().dot(Vec3::Y) > 1.0 - 1e-6, "{}", c.up);
    assert!(
        (f64::from(c.fov) - 0.6f64.to_degrees()).abs() < 1e-4,
        "{}",
        c.fov
    );
    assert_eq!(c.aperture, 0.0);
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
}

#[test]
fn the_only_camera_needs_no_name_and_a_scene_sun_wins() {
    let gltf = lit_gltf(good_lights(), perspective());
    let dir = temp_dir("punctual-sun");
    std::fs::write(dir.join("m.gltf"), gltf.to_string()).expect("write");
    let source = r#"Scene(
    camera: Gltf(placement: "outer/model"),
    settings: Settings(width: 16, height: 8, sun: Sun(direction: (1, 1, 0), irradiance: 1)),
    entities: [ Entity(name: "outer", prefab: "p.ron") ],
)"#;
    std::fs::write(
        dir.join("p.ron"),
        r#"Prefab(entities: [ Entity(name: "model", gltf: "m.gltf") ])"#,
    )
    .expect("write");
    let path = write_scene(&dir, "s.ron", source);
    let scene = load_scene(&path, &mut AssetCache::default()).unwrap_or_else(|e| panic!("{e}"));
    assert!((scene.camera.position - Vec3::new(0.0, 1.0, 5.0)).length() < 1e-6);
    let sun = scene.settings.sun.expect("the scene's sun");
    assert!((sun.direction - Vec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-6);
    let warned = |what: &str| scene.warnings.iter().any(|w| w.contains(what));
    assert!(warned("directional light 2"), "{:?}", scene.warnings);
    assert!(
        warned("aspectRatio"),
        "16 × 8 is not 1: {:?}",
        scene.warnings
    );
}

#[test]
fn bad_lights_and_cameras_are_refused_naming_the_field() {
    let ron = |lights: &str| {
        let dir = temp_dir("punctual-bad");
        let path = write_scene(&dir, "s.ron", &ground_scene(lights, 0.0, 0.0));
        load_scene(&path, &mut AssetCache::default())
            .map(|_| ())
            .map_err(|e| e.to_string())
    };
    let cases = [
        (
            "Point(position: (0, 2, 0), intensity: -1)",
            vec!["lights[0]", "intensity must be >= 0 (got -1)"],
        ),
        (
            "Point(position: (0, 2, 0)), Spot(position: (0, 2, 0), direction: (0, -1, 0), inner_angle: 30, outer_angle: 20)",
            vec![
                "lights[1]",
                "`inner_angle` (30) must be between 0 and `outer_angle` (20)",
            ],
        ),
        (
            "Spot(position: (0, 2, 0), direction: (0, -1, 0), outer_angle: 95)",
            vec!["`outer_angle` must be in (0, 90] (got 95)"],
        ),
        (
            "Spot(position: (0, 2, 0), look_at: (0, 2, 0))",
            vec!["direction is zero"],
        ),
        (
            "Point(position: (0, 2, 0), colour: (1, -1, 1))",
            vec!["colour must be >= 0"],
        ),
        (
            "Point(position: (0, 2e10, 0))",
            vec!["position must be within"],
        ),
        (
            "Point(position: (0, 2, 0), intensity: 1e38, colour: (10, 10, 10))",
            vec!["too large"],
        ),
        (
            "Lamp(position: (0, 2, 0))",
            vec!["unknown light kind \"Lamp\"", "Point", "Spot"],
        ),
    ];
    for (lights, words) in cases {
        let e = ron(lights).expect_err(lights);
        for w in words {
            assert!(e.contains(w), "{lights}: {e:?} lacks {w:?}");
        }
        assert!(e.contains("s.ron:"), "names the file: {e}");
    }

    let camera = r#"Gltf(placement: "model")"#;
    let gltf_cases = [
        (
            lit_gltf(
                first_light(json!({"type": "point", "intensity": -2.0})),
                perspective(),
            ),
            camera,
            "light 0: intensity -2 must be finite and >= 0",
        ),
        (
            lit_gltf(
                first_light(
                    json!({"type": "spot", "spot": {"innerConeAngle": 0.5, "outerConeAngle": 0.3}}),
                ),
                perspective(),
            ),
            camera,
            "`spot.innerConeAngle` (0.5) must be between 0 and `spot.outerConeAngle` (0.3)",
        ),
        (
            lit_gltf(
                first_light(json!({"type": "point", "color": [1.0, -1.0, 0.0]})),
                perspective(),
            ),
            camera,
            "light 0: color",
        ),
        (
            lit_gltf(
                good_lights(),
                json!([{"type": "orthographic",
                "orthographic": {"xmag": 1.0, "ymag": 1.0, "znear": 0.1, "zfar": 10.0}}]),
            ),
            camera,
            "orthographic",
        ),
        (
            lit_gltf(good_lights(), perspective()),
            r#"Gltf(placement: "model", camera: "nope")"#,
            "no camera named \"nope\" in its default scene (its cameras: \"cam\")",
        ),
        (
            lit_gltf(good_lights(), perspective()),
            r#"Gltf(placement: "elsewhere")"#,
            "no entity \"elsewhere\" places a glTF file (glTF placements: model)",
        ),
        (
            lit_gltf(
                good_lights(),
                json!([{"type": "perspective", "perspective": {"yfov": 4.0, "znear": 0.1}}]),
            ),
            camera,
            "fov must be in (0, 180) degrees",
        ),
    ];
    for (gltf, camera, words) in gltf_cases {
        let e = load_placed(&gltf, camera, "").expect_err(words);
        assert!(e.contains(words), "{e:?} lacks {words:?}");
        assert!(e.contains("s.ron:"), "names the file: {e}");
    }
}

#[test]
fn old_scenes_have_no_punctual_lights() {
    for entry in std::fs::read_dir(common::scenes_dir()).expect("scenes") {
        let path = entry.expect("entry").path();
        if path.extension().is_some_and(|e| e == "ron") {
            let scene = load_scene(&path, &mut AssetCache::default())
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            let has_lights = std::fs::read_to_string(&path)
                .expect("read")
                .contains("lights:");
            assert_eq!(!scene.lights.is_empty(), has_lights, "{}", path.display());
        }
    }
}
