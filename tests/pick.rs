//! Picking: the id buffer against a brute-force ray per pixel (every primitive, no BVH, in f64,
//! the camera ray built here from the camera's definition), the provenance table against the
//! places found in the files' text, and the viewer's picking routes.

mod common;

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use glam::{DAffine3, DQuat, DVec3};
use rondo::render::pick::SKY;
use rondo::scene::provenance::Provenance;
use rondo::serve::{Options, Viewer};
use rondo::systems::IdBuffer;
use rondo::watch::Picked;
use rondo::{PassPlan, Renderer};
use serde_json::{Value, json};

use common::gltf_doc::square_panel;
use common::temp_dir;

const WIDTH: u32 = 48;
const HEIGHT: u32 = 36;

/// The scene: two spheres, a floor quad (an entity named like its material), a prefab box
/// placed turned and scaled (its material mapped), a prefab of two more placements of that box
/// (its default material), and a glTF square.
fn scene_text(lens: &str) -> String {
    format!(
        r#"// picking test scene
Scene(
    camera: Camera(position: (0.3, 0.8, -6), look_at: (0, 0.2, 0), fov: 45.0{lens}),
    settings: Settings(width: {WIDTH}, height: {HEIGHT}, spp: 1, max_depth: 1),
    materials: {{
        "red": Diffuse(albedo: Constant((0.8, 0.1, 0.1))),
        "grey": Diffuse(albedo: Constant((0.5, 0.5, 0.5))),
    }},
    entities: [
        Entity(name: "ball", material: "red", shape: Sphere(center: (-1.6, 0.4, 0.5), radius: 0.7)),
        Entity(name: "small", material: "grey", shape: Sphere(center: (-0.6, -0.3, -1.0), radius: 0.35)),
        Entity(name: "crate", prefab: "prefabs/crate.ron", materials: {{ "wood": "red" }},
               transform: Transform(translate: (1.2, -0.5, 0.0), rotate: (0, 30, 0), scale: (0.9, 0.9, 0.9))),
        Entity(name: "stack", prefab: "prefabs/stack.ron",
               transform: Transform(translate: (0.2, -0.9, 1.5))),
        Entity(name: "panel", gltf: "panel.gltf", transform: Transform(translate: (-0.5, 0.6, 2.5))),
        Entity(name: "grey", material: "grey",
               shape: Quad(a: (-4, -1, -3), b: (4, -1, -3), c: (4, -1, 4), d: (-4, -1, 4))),
    ],
)
"#
    )
}

const CRATE: &str = r#"// a unit box standing on its centre
Prefab(
    materials: { "wood": Diffuse(albedo: Constant((0.6, 0.4, 0.2))) },
    entities: [
        Entity(name: "box", material: "wood", shape: Box(min: (-0.5, 0, -0.5), max: (0.5, 1, 0.5))),
    ],
)
"#;

const STACK: &str = r#"Prefab(
    entities: [
        Entity(name: "low", prefab: "crate.ron", transform: Transform(scale: (0.6, 0.6, 0.6))),
        Entity(name: "high", prefab: "crate.ron",
               transform: Transform(translate: (0.1, 0.6, 0), scale: (0.4, 0.4, 0.4))),
    ],
)
"#;

/// Writes the scene's files under `dir`; returns the scene's path.
fn write_files(dir: &Path, lens: &str) -> PathBuf {
    std::fs::create_dir_all(dir.join("prefabs")).expect("mkdir");
    std::fs::write(dir.join("prefabs/crate.ron"), CRATE).expect("write");
    std::fs::write(dir.join("prefabs/stack.ron"), STACK).expect("write");
    std::fs::write(dir.join("panel.gltf"), square_panel()).expect("write");
    let scene = dir.join("scene.ron");
    std::fs::write(&scene, scene_text(lens)).expect("write");
    scene
}

/// Loads and applies the scene; returns its ids and provenance.
fn pick(scene: &Path) -> (IdBuffer, Arc<Provenance>) {
    let mut r = Renderer::new(Some(2), PassPlan::Single).expect("pool");
    r.keep_provenance(true);
    r.load(scene).unwrap_or_else(|e| panic!("{e}"));
    r.run_once();
    (r.pick_ids(), r.provenance().expect("kept"))
}

// ------------------------------------------------------------------------------------------------
// The brute force: every primitive of the scene, as written above, in f64.

/// What a ray can hit: a sphere, a box placed by an affine map (its object-space corners), a
/// rectangle in a plane (a point, two edge vectors), each with the entity's name.
enum Solid {
    Sphere(DVec3, f64),
    Box(DAffine3, DVec3, DVec3),
    Rect(DVec3, DVec3, DVec3),
}

fn solids() -> Vec<(&'static str, Solid)> {
    let trs = |t: [f64; 3], ry: f64, s: f64| {
        DAffine3::from_scale_rotation_translation(
            DVec3::splat(s),
            DQuat::from_rotation_y(ry.to_radians()),
            DVec3::from(t),
        )
    };
    let unit = (DVec3::new(-0.5, 0.0, -0.5), DVec3::new(0.5, 1.0, 0.5));
    let stack = trs([0.2, -0.9, 1.5], 0.0, 1.0);
    vec![
        ("ball", Solid::Sphere(DVec3::new(-1.6, 0.4, 0.5), 0.7)),
        ("small", Solid::Sphere(DVec3::new(-0.6, -0.3, -1.0), 0.35)),
        (
            "crate/box",
            Solid::Box(trs([1.2, -0.5, 0.0], 30.0, 0.9), unit.0, unit.1),
        ),
        (
            "stack/low/box",
            Solid::Box(stack * trs([0.0; 3], 0.0, 0.6), unit.0, unit.1),
        ),
        (
            "stack/high/box",
            Solid::Box(stack * trs([0.1, 0.6, 0.0], 0.0, 0.4), unit.0, unit.1),
        ),
        (
            "panel/sign",
            Solid::Rect(DVec3::new(-0.5, 0.6, 2.5), DVec3::X, DVec3::Y),
        ),
        (
            "grey",
            Solid::Rect(DVec3::new(-4.0, -1.0, -3.0), DVec3::X * 8.0, DVec3::Z * 7.0),
        ),
    ]
}

/// Distance along the ray `o + t d` (t > 0) to `solid`, if it is hit.
fn distance(solid: &Solid, o: DVec3, d: DVec3) -> Option<f64> {
    match solid {
        Solid::Sphere(c, r) => {
            let oc = o - *c;
            let (b, cc) = (oc.dot(d), oc.length_squared() - r * r);
            let disc = b * b - cc;
            let t = -b - disc.max(0.0).sqrt();
            (disc >= 0.0 && t > 0.0).then_some(t)
        }
        Solid::Box(m, lo, hi) => {
            // The slab test in the box's own space: t is the same parameter there.
            let inv = m.inverse();
            let (lo_o, ld) = (inv.transform_point3(o), inv.transform_vector3(d));
            let (mut near, mut far) = (f64::NEG_INFINITY, f64::INFINITY);
            for k in 0..3 {
                let (a, b) = ((lo[k] - lo_o[k]) / ld[k], (hi[k] - lo_o[k]) / ld[k]);
                near = near.max(a.min(b));
                far = far.min(a.max(b));
            }
            (near <= far && near > 0.0).then_some(near)
        }
        Solid::Rect(p, u, v) => {
            let n = u.cross(*v);
            let t = (*p - o).dot(n) / d.dot(n);
            let q = o + d * t - *p;
            let (a, b) = (
                q.dot(*u) / u.length_squared(),
                q.dot(*v) / v.length_squared(),
            );
            (t > 0.0 && (0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b)).then_some(t)
        }
    }
}

/// The camera ray through film position `(x, y)` (pixels from the top-left corner), from the
/// camera's definition: position (0.3, 0.8, −6) looking at (0, 0.2, 0), up +y, 45° vertical
/// field of view; x grows to the right of the view, y downwards.
fn camera_ray(x: f64, y: f64) -> (DVec3, DVec3) {
    let eye = DVec3::new(0.3, 0.8, -6.0);
    let forward = (DVec3::new(0.0, 0.2, 0.0) - eye).normalize();
    let right = forward.cross(DVec3::Y).normalize();
    let up = right.cross(forward);
    let half = (22.5f64).to_radians().tan();
    let aspect = f64::from(WIDTH) / f64::from(HEIGHT);
    let sx = (2.0 * x / f64::from(WIDTH) - 1.0) * half * aspect;
    let sy = (1.0 - 2.0 * y / f64::from(HEIGHT)) * half;
    (eye, (forward + right * sx + up * sy).normalize())
}

/// The entity the ray through `(x, y)` hits first, with the distance to the next other one
/// (`None` for the sky).
fn brute_force(solids: &[(&'static str, Solid)], x: f64, y: f64) -> Option<(&'static str, f64)> {
    let (o, d) = camera_ray(x, y);
    let mut hits: Vec<(f64, &'static str)> = solids
        .iter()
        .filter_map(|(name, s)| distance(s, o, d).map(|t| (t, *name)))
        .collect();
    hits.sort_by(|a, b| a.0.total_cmp(&b.0));
    let gap = hits.get(1).map_or(f64::INFINITY, |h| h.0 - hits[0].0);
    hits.first().map(|h| (h.1, gap))
}

/// Checks every pixel of `ids` against the brute force. A pixel counts as clear when its ray and
/// four rays 0.02 pixel around it find the same entity, with the next entity at least 10⁻⁶
/// farther: the others lie on an edge, where rounding may decide. Returns the clear pixels.
fn compare(ids: &IdBuffer, provenance: &Provenance) -> usize {
    assert_eq!((ids.width, ids.height), (WIDTH, HEIGHT));
    let solids = solids();
    let names: Vec<String> = (0..provenance.len())
        .map(|i| provenance.entry(i).expect("entry").name.to_string())
        .collect();
    let mut clear = 0;
    let mut seen = std::collections::BTreeSet::new();
    for y in 0..HEIGHT {
        for x in 0..WIDTH {
            let (cx, cy) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
            let centre = brute_force(&solids, cx, cy);
            let e = 0.02;
            let around = [(e, 0.0), (-e, 0.0), (0.0, e), (0.0, -e)]
                .map(|(dx, dy)| brute_force(&solids, cx + dx, cy + dy).map(|h| h.0));
            let unambiguous = centre.is_none_or(|(_, gap)| gap > 1e-6)
                && around.iter().all(|a| *a == centre.map(|h| h.0));
            let id = ids.ids[(y * WIDTH + x) as usize];
            let got = (id != SKY).then(|| names.get(id as usize).map(String::as_str));
            if !unambiguous {
                continue;
            }
            clear += 1;
            let want = centre.map(|h| h.0);
            assert_eq!(got, want.map(Some), "pixel ({x}, {y}): id {id}");
            seen.insert(want.unwrap_or("sky"));
        }
    }
    let all: std::collections::BTreeSet<&str> = solids.iter().map(|s| s.0).chain(["sky"]).collect();
    assert_eq!(
        seen, all,
        "every entity and the sky are seen on clear pixels"
    );
    clear
}

#[test]
fn every_pixel_names_the_entity_a_brute_force_ray_hits_first() {
    let dir = temp_dir("pick-ids");
    let (ids, provenance) = pick(&write_files(&dir, ""));
    let clear = compare(&ids, &provenance);
    let pixels = (WIDTH * HEIGHT) as usize;
    assert!(
        clear * 100 >= pixels * 95,
        "{clear} of {pixels} pixels clear"
    );
}

#[test]
fn a_thin_lens_picks_through_its_centre() {
    let dir = temp_dir("pick-lens");
    let (ids, provenance) = pick(&write_files(&dir, ", aperture: 0.3, focus_distance: 2.0"));
    compare(&ids, &provenance);
}

// ------------------------------------------------------------------------------------------------
// The table.

/// `(line, column)` of byte `offset` of `text`, counted here: 1-based, columns in characters.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, text[start..offset].chars().count() + 1)
}

/// `(path, line, column)` of the first `needle`'s quote after the first `after` in `path`.
fn found(path: &Path, after: &str, needle: &str) -> (PathBuf, Option<(usize, usize)>) {
    let text = std::fs::read_to_string(path).expect("read");
    let from = text.find(after).expect("anchor");
    let at = from + text[from..].find(needle).expect("needle");
    (path.to_path_buf(), Some(line_col(&text, at)))
}

/// An entry's place as `(path, line, column)`.
fn place(p: &rondo::scene::provenance::Place) -> (PathBuf, Option<(usize, usize)>) {
    (p.path.to_path_buf(), p.location.map(|l| (l.line, l.col)))
}

#[test]
fn entries_give_names_materials_chains_and_places() {
    let temp = temp_dir("pick-table");
    let dir = temp.canonicalize().expect("canonical");
    let scene = write_files(&dir, "");
    let (_, provenance) = pick(&scene);
    let (crate_file, stack_file) = (dir.join("prefabs/crate.ron"), dir.join("prefabs/stack.ron"));
    let gltf = dir.join("panel.gltf");
    let by_name = |name: &str| {
        (0..provenance.len())
            .filter_map(|i| provenance.entry(i))
            .find(|e| e.name == name)
            .unwrap_or_else(|| panic!("no entry {name}"))
    };

    let ball = by_name("ball");
    assert_eq!(ball.material, "red");
    assert_eq!(
        place(&ball.entity),
        found(&scene, "Entity(name: \"ball\"", "\"ball\"")
    );
    assert_eq!(
        place(&ball.material_at),
        found(&scene, "materials", "\"red\"")
    );
    assert!(ball.chain.is_empty());

    // Named like its material: the entity's own name, not the material's key.
    let floor = by_name("grey");
    assert_eq!(
        place(&floor.entity),
        found(&scene, "Entity(name: \"grey\"", "\"grey\"")
    );
    assert_eq!(
        place(&floor.material_at),
        found(&scene, "materials", "\"grey\"")
    );

    // A prefab's box with its material mapped to the scene's.
    let boxed = by_name("crate/box");
    assert_eq!(boxed.material, "red");
    assert_eq!(
        place(&boxed.entity),
        found(&crate_file, "entities", "\"box\"")
    );
    assert_eq!(
        place(&boxed.material_at),
        found(&scene, "materials", "\"red\"")
    );
    let chain: Vec<_> = boxed
        .chain
        .iter()
        .map(|l| (l.name, l.gltf, l.file.to_path_buf(), place(&l.at)))
        .collect();
    assert_eq!(
        chain,
        [(
            "crate",
            false,
            crate_file.clone(),
            found(&scene, "Entity(name: \"crate\"", "\"crate\"")
        )]
    );

    // Two placements deep, with the prefab's own material.
    let high = by_name("stack/high/box");
    assert_eq!(high.material, "wood");
    assert_eq!(
        place(&high.entity),
        found(&crate_file, "entities", "\"box\"")
    );
    assert_eq!(
        place(&high.material_at),
        found(&crate_file, "materials", "\"wood\"")
    );
    let chain: Vec<_> = high
        .chain
        .iter()
        .map(|l| (l.name, l.file.to_path_buf(), place(&l.at)))
        .collect();
    assert_eq!(
        chain,
        [
            (
                "stack",
                stack_file.clone(),
                found(&scene, "Entity(name: \"stack\"", "\"stack\"")
            ),
            (
                "stack/high",
                crate_file.clone(),
                found(&stack_file, "Entity(name: \"high\"", "\"high\"")
            ),
        ]
    );

    // A glTF node: the file itself, its default material, the placement's place.
    let sign = by_name("panel/sign");
    assert_eq!(sign.material, "#default");
    assert_eq!(place(&sign.entity), (gltf.clone(), None));
    assert_eq!(place(&sign.material_at), (gltf.clone(), None));
    let chain: Vec<_> = sign
        .chain
        .iter()
        .map(|l| (l.name, l.gltf, place(&l.at)))
        .collect();
    assert_eq!(
        chain,
        [(
            "panel",
            true,
            found(&scene, "Entity(name: \"panel\"", "\"panel\"")
        )]
    );
    assert_eq!(provenance.len(), 7, "7 entities");
    assert!(provenance.entry(7).is_none());
}

// ------------------------------------------------------------------------------------------------
// The routes.

/// Status, headers and body of `GET target`.
fn get(addr: SocketAddr, target: &str) -> (u16, String, Vec<u8>) {
    let mut s = TcpStream::connect(addr).expect("connect");
    s.set_read_timeout(Some(Duration::from_secs(10)))
        .expect("timeout");
    write!(s, "GET {target} HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n").expect("send");
    let mut raw = Vec::new();
    s.read_to_end(&mut raw).expect("read");
    let split = raw.windows(4).position(|w| w == b"\r\n\r\n").expect("head");
    let head = String::from_utf8_lossy(&raw[..split]).to_string();
    let status = head[9..12].parse().expect("status");
    (status, head, raw[split + 4..].to_vec())
}

#[test]
fn the_routes_serve_the_ids_and_the_entries() {
    let temp = temp_dir("pick-routes");
    let dir = temp.canonicalize().expect("canonical");
    let scene = write_files(&dir, "");
    let (ids, provenance) = pick(&scene);
    let options = Options {
        editor_url: Some("vscode://file/{path}:{line}:{col}".into()),
        ..Options::default()
    };
    let (viewer, feed) =
        Viewer::start("127.0.0.1:0".parse().expect("addr"), false, options).expect("serve");
    let addr = viewer.addr();
    assert_eq!(get(addr, "/pick/ids.u32").0, 503, "nothing before a scene");
    assert_eq!(get(addr, "/pick.js").0, 200, "the script is always there");
    let client = feed.subscribe(4).expect("room");
    feed.pick_sink()(Picked {
        reload: 7,
        ids: Arc::new(ids.clone()),
        provenance: provenance.clone(),
    });
    let events: Vec<Value> = client
        .next_batch(Duration::ZERO)
        .iter()
        .map(|e| serde_json::from_str(e).expect("JSON"))
        .collect();
    assert_eq!(
        events,
        [json!({"kind": "pick", "reload": 7, "width": WIDTH, "height": HEIGHT, "entities": 7})]
    );

    let (status, head, body) = get(addr, "/pick/ids.u32");
    assert_eq!(status, 200);
    assert!(head.contains("X-Rondo-Reload: 7"), "{head}");
    assert_eq!(&body[..8], b"RONDOIDS");
    let u = |i: usize| u32::from_le_bytes(body[8 + 4 * i..12 + 4 * i].try_into().expect("4 bytes"));
    assert_eq!((u(0), u(1), u(2)), (WIDTH, HEIGHT, 7));
    assert_eq!(body.len(), 20 + 4 * ids.ids.len());
    let decoded: Vec<u32> = (0..ids.ids.len()).map(|i| u(3 + i)).collect();
    assert_eq!(decoded, ids.ids);

    let (status, _, body) = get(addr, "/pick/table.json");
    assert_eq!(status, 200);
    let table: Value = serde_json::from_slice(&body).expect("JSON");
    let entities = table["entities"].as_array().expect("entities");
    assert_eq!(table["reload"], 7);
    assert_eq!(entities.len(), 7);
    let high = entities
        .iter()
        .find(|e| e["name"] == "stack/high/box")
        .expect("high");
    let id = high["id"].as_u64().expect("id");
    let (status, _, body) = get(addr, &format!("/pick/entity.json?id={id}"));
    assert_eq!(status, 200);
    let one: Value = serde_json::from_slice(&body).expect("JSON");
    assert_eq!(&one, high, "one entry is the table's");
    let crate_file = dir.join("prefabs/crate.ron");
    let (path, lc) = found(&crate_file, "entities", "\"box\"");
    let (line, col) = lc.expect("found");
    assert_eq!(
        one["entity"],
        json!({"path": path.display().to_string(), "line": line, "column": col,
               "url": format!("vscode://file/{}:{line}:{col}", path.display())})
    );
    assert_eq!(one["material"], "wood");
    let kinds: Vec<&str> = one["chain"]
        .as_array()
        .expect("chain")
        .iter()
        .map(|l| l["kind"].as_str().expect("kind"))
        .collect();
    assert_eq!(kinds, ["prefab", "prefab"]);
    let sign = entities
        .iter()
        .find(|e| e["name"] == "panel/sign")
        .expect("sign");
    assert_eq!(sign["entity"]["line"], Value::Null);
    assert_eq!(sign["chain"][0]["kind"], "gltf");

    for bad in [
        "/pick/entity.json?id=7",
        "/pick/entity.json?id=4294967295",
        "/pick/entity.json",
        "/pick/entity.json?id=x",
    ] {
        assert_eq!(get(addr, bad).0, 404, "{bad}");
    }
    drop(viewer);
}
