//! Loading and `rondo check` grow linearly: work is counted (comparisons, bytes scanned,
//! vertices transformed), not timed, over 10³, 10⁴ and 10⁵ items, so a fast machine cannot hide
//! a quadratic stage.

mod common;

use common::{temp_dir, write_scene};
use rondo::bench::load::generate;
use rondo::scene::assets::AssetCache;
use rondo::scene::check::check_counted;
use rondo::scene::load::{LoadedScene, load_scene};

const SIZES: [usize; 3] = [1_000, 10_000, 100_000];

fn load(path: &std::path::Path) -> LoadedScene {
    load_scene(path, &mut AssetCache::default()).unwrap_or_else(|e| panic!("{e}"))
}

/// Asserts that `work` grows by at most 15× per 10× of size (linear is 10×, quadratic 100×).
fn assert_linear(what: &str, work: &[u64]) {
    for w in work.windows(2) {
        assert!(
            w[1] > 0 && w[1] <= 15 * w[0].max(1),
            "{what} grows faster than linearly over {SIZES:?}: {work:?}"
        );
    }
}

#[test]
fn check_compares_and_locates_coplanar_tiles_in_linear_work() {
    let dir = temp_dir("scaling-tiles");
    let (mut comparisons, mut located, mut warnings) = (Vec::new(), Vec::new(), Vec::new());
    for n in SIZES {
        let path = generate("tiles", n, &dir.join(n.to_string())).expect("scene");
        let scene = load(&path);
        let (w, stats) = check_counted(&scene);
        // Each 1.1-wide tile on a grid of 1 overlaps its 8 neighbours: about 4 pairs per tile,
        // every one a warning that is located in the file.
        assert!(w.len() > 3 * n, "{n} tiles: {} warnings", w.len());
        assert!(w.iter().all(|w| w.location.is_some()));
        comparisons.push(stats.comparisons);
        located.push(stats.located_bytes);
        warnings.push(w.len() as u64);
    }
    assert_linear("comparisons of the coplanar rule", &comparisons);
    assert_linear("bytes scanned to locate warnings", &located);
    assert_linear("warnings", &warnings);
}

#[test]
fn the_limit_check_transforms_each_mesh_vertex_once_and_8_corners_per_placement() {
    let dir = temp_dir("scaling-placements");
    let mut visited = Vec::new();
    for n in SIZES {
        let path = generate("placements", n, &dir.join(n.to_string())).expect("scene");
        let scene = load(&path);
        // The generated mesh is a 300 × 300 height field.
        assert_eq!(scene.stats.limit_vertices, 90_000 + 8 * n as u64);
        visited.push(scene.stats.limit_vertices);
    }
    assert_linear("vertices visited by the limit check", &visited);
}

/// A scene placing a triangle mesh with vertices `s·x̂`, `s·ŷ` and 0, turned 45° about z.
fn diagonal_triangle(dir: &std::path::Path, s: f64) -> std::path::PathBuf {
    write_scene(
        dir,
        "tri.obj",
        &format!("v {s} 0 0\nv 0 {s} 0\nv 0 0 0\nf 1 2 3\n"),
    );
    write_scene(
        dir,
        "scene.ron",
        r#"Scene(camera: Camera(position: (0, 0, -5), look_at: (0, 0, 0)),
    materials: { "m": Diffuse(albedo: Constant((0.5, 0.5, 0.5))) },
    entities: [ Entity(name: "t", material: "m", shape: Mesh(path: "tri.obj"),
                       transform: Transform(rotate: (0, 0, 45))) ])"#,
    )
}

#[test]
fn a_mesh_whose_corners_exceed_the_limit_is_judged_by_its_vertices() {
    // Turned 45° about z, the bounding box's corner (s, s, 0) reaches √2·s, the vertices only
    // s/√2: with s = 10⁹ the corners exceed the ±10⁹ limit and the vertices do not.
    let dir = temp_dir("scaling-limit");
    let scene = load(&diagonal_triangle(&dir, 1e9));
    // 3 vertices for the bounds, 8 corners, then the exact scan of the 3 vertices.
    assert_eq!(scene.stats.limit_vertices, 3 + 8 + 3);
    let path = diagonal_triangle(&dir, 1.5e9);
    let e = load_scene(&path, &mut AssetCache::default())
        .expect_err("vertices at 1.06e9 are beyond the limit")
        .to_string();
    assert!(e.contains("scene.ron:3:") && e.contains("beyond"), "{e}");
    let scene = load(&diagonal_triangle(&dir, 1e8));
    assert_eq!(
        scene.stats.limit_vertices,
        3 + 8,
        "corners within the limit suffice"
    );
}

#[test]
fn a_reload_after_a_one_entity_edit_parses_that_entity_only() {
    let dir = temp_dir("scaling-incremental");
    for n in [1_000, 10_000] {
        let path = generate("flat", n, &dir.join(n.to_string())).expect("scene");
        let mut assets = AssetCache::default();
        let first = load_scene(&path, &mut assets).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(first.stats.entities_parsed, n as u64);
        // One entity's radius, then another's name: each reload parses one entity, and loads
        // what a fresh load of the file gives.
        let text = std::fs::read_to_string(&path).expect("read");
        let middle = format!("\"e{}\"", n / 2);
        let at = text.find(&middle).expect("entity")
            + text[text.find(&middle).expect("entity")..]
                .find("radius: 0.4")
                .expect("radius");
        let edited = format!(
            "{}radius: 0.3{}",
            &text[..at],
            &text[at + "radius: 0.4".len()..]
        );
        for edit in [edited.clone(), edited.replace("\"e7\"", "\"seven\"")] {
            std::fs::write(&path, &edit).expect("write");
            let scene = load_scene(&path, &mut assets).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(scene.stats.entities_parsed, 1, "{n} entities");
            let fresh = load(&path);
            assert_eq!(scene.entities, fresh.entities);
            assert_eq!(scene.materials.len(), fresh.materials.len());
        }
    }
}
