//! `rondo bench load`: load, first image and `rondo check` of generated scenes from 10³ to 10⁶
//! entities, stage by stage, with the growth factor per 10× (1 is constant, 10 linear, 100
//! quadratic).
//!
//! Each kind grows one thing: flat named entities, unnamed ones, materials, distinct meshes,
//! distinct textures, placements of one big mesh, placements of one big prefab, coplanar tiles.
//! Images are 16×12 at 1 spp, so rendering costs nothing and the figures are the loading path.
//! Stages are timed in CPU time of the process (all threads), which a busy machine does not
//! inflate as it does wall time; the first image is also given in wall time:
//!
//! - `parse`: reading and parsing the scene file (RON → serde types);
//! - `expand`: the rest of `load_scene` (prefabs, names, materials, assets, limits);
//! - `frame`: the first frame of a fresh renderer: the ECS diff by name and spawn, packing, BVH
//!   builds, light set and the 16×12 pass;
//! - `first image`: from a fresh renderer to the first pass (`load` + the frame), what a user
//!   waits for;
//! - `check`: `rondo check`'s rules on the loaded scene, warnings located.
//!
//! Watch-mode edit latency over the `flat` scenes is in [`super::load_watch_table`].

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use cpu_time::ProcessTime;

use crate::scene::assets::AssetCache;
use crate::scene::check::check_counted;
use crate::scene::load::{load_scene, parse_scene};
use crate::{Overrides, PassPlan, Renderer};

/// The scene kinds, with what grows in each.
pub const KINDS: [(&str, &str); 8] = [
    ("flat", "named entities (spheres)"),
    ("unnamed", "unnamed entities (quads)"),
    ("materials", "materials, one entity"),
    ("meshes", "distinct mesh files, one placement each"),
    ("textures", "distinct image textures, one entity each"),
    ("placements", "placements of one 90,000-vertex mesh"),
    (
        "prefab",
        "entities from placements of a 1,000-entity prefab",
    ),
    ("tiles", "coplanar overlapping tiles (check compares them)"),
];

/// Largest count generated for kinds that write one file per item.
pub const MAX_FILES: usize = 100_000;

/// The figures of one scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// The kind ([`KINDS`]).
    pub kind: &'static str,
    /// How many of what grows.
    pub count: usize,
    /// Scene file size in bytes.
    pub bytes: usize,
    /// Entities loaded.
    pub entities: usize,
    /// Reading and parsing (CPU time).
    pub parse: Duration,
    /// The rest of `load_scene` (CPU time).
    pub expand: Duration,
    /// A fresh renderer's first frame: apply, pack, BVH, lights, pass (CPU time).
    pub frame: Duration,
    /// A fresh renderer's load plus first frame (CPU time).
    pub first_image: Duration,
    /// The same in wall time.
    pub first_image_wall: Duration,
    /// `rondo check` on the loaded scene (CPU time).
    pub check: Duration,
    /// Warnings `check` found.
    pub warnings: usize,
    /// Resident memory held with the scene loaded in the renderer, MiB above the baseline.
    pub resident_mib: f64,
}

/// The process's resident set size in KiB (`VmRSS` of `/proc/self/status`, Linux).
fn resident_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmRSS:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// Grid position `k` of a square of side `side`, spaced `step`.
fn grid(k: usize, side: usize, step: f32) -> (f32, f32) {
    ((k % side) as f32 * step, (k / side) as f32 * step)
}

/// A scene around `entities`, with `materials` and a camera looking at a `size`-wide square.
fn scene_text(materials: &str, entities: &str, size: f32) -> String {
    let c = 0.5 * size;
    format!(
        "Scene(\n    camera: Camera(position: ({c}, {}, {}), look_at: ({c}, 0, {c}), fov: 50),\n    \
         settings: Settings(width: 16, height: 12, spp: 1, max_depth: 2),\n    \
         materials: {{\n{materials}    }},\n    entities: [\n{entities}    ],\n)\n",
        size + 5.0,
        -size - 5.0
    )
}

const CLAY: &str = "        \"clay\": Diffuse(albedo: Constant((0.7, 0.6, 0.5))),\n";
/// The flat scene's second material (its first entity's), so that one entity's material can be
/// changed to another.
const GLAZE: &str = "        \"glaze\": Diffuse(albedo: Constant((0.2, 0.3, 0.6))),\n";

/// Writes the scene of `kind` with `n` of what grows into `dir`; returns its path.
pub fn generate(kind: &str, n: usize, dir: &Path) -> Result<PathBuf, String> {
    let io = |e: std::io::Error| format!("{}: {e}", dir.display());
    std::fs::create_dir_all(dir).map_err(io)?;
    let side = (n as f64).sqrt().ceil().max(1.0) as usize;
    let size = side as f32;
    let mut entities = String::with_capacity(n * 110);
    let mut materials = String::from(CLAY);
    match kind {
        "flat" => {
            materials.push_str(GLAZE);
            for k in 0..n {
                let (x, z) = grid(k, side, 1.0);
                let material = if k == 0 { "glaze" } else { "clay" };
                let _ = writeln!(
                    entities,
                    "        Entity(name: \"e{k}\", material: \"{material}\", shape: Sphere(center: ({x}, 0.4, {z}), radius: 0.4)),"
                );
            }
        }
        "unnamed" | "tiles" => {
            // Tiles 1.1 wide on a grid of 1 overlap their neighbours; quads 0.9 wide do not.
            let w = if kind == "tiles" { 1.1 } else { 0.9 };
            for k in 0..n {
                let (x, z) = grid(k, side, 1.0);
                let (x1, z1) = (x + w, z + w);
                let _ = writeln!(
                    entities,
                    "        Entity(material: \"clay\", shape: Quad(a: ({x}, 0, {z}), b: ({x}, 0, {z1}), c: ({x1}, 0, {z1}), d: ({x1}, 0, {z}))),"
                );
            }
        }
        "materials" => {
            for k in 0..n {
                let _ = writeln!(
                    materials,
                    "        \"m{k}\": Diffuse(albedo: Constant((0.5, 0.5, 0.5))),"
                );
            }
            entities.push_str("        Entity(name: \"ball\", material: \"clay\", shape: Sphere(center: (0, 0, 0), radius: 1)),\n");
        }
        "meshes" | "textures" => {
            std::fs::create_dir_all(dir.join("assets")).map_err(io)?;
            for k in 0..n.min(MAX_FILES) {
                let (x, z) = grid(k, side, 1.0);
                if kind == "meshes" {
                    let obj = format!(
                        "v 0 0 0\nv 0.8 0 0\nv 0 0.8 0\nv 0 0 {}\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n",
                        0.5 + k as f32 * 1e-6
                    );
                    std::fs::write(dir.join(format!("assets/m{k}.obj")), obj).map_err(io)?;
                    let _ = writeln!(
                        entities,
                        "        Entity(name: \"e{k}\", material: \"clay\", shape: Mesh(path: \"assets/m{k}.obj\"), transform: Transform(translate: ({x}, 0, {z}))),"
                    );
                } else {
                    let v = (k % 251) as u8;
                    image::RgbImage::from_pixel(2, 2, image::Rgb([v, 128, 255 - v]))
                        .save(dir.join(format!("assets/t{k}.png")))
                        .map_err(|e| e.to_string())?;
                    let _ = writeln!(
                        materials,
                        "        \"t{k}\": Diffuse(albedo: Image(path: \"assets/t{k}.png\")),"
                    );
                    let _ = writeln!(
                        entities,
                        "        Entity(name: \"e{k}\", material: \"t{k}\", shape: Sphere(center: ({x}, 0.4, {z}), radius: 0.4)),"
                    );
                }
            }
        }
        "placements" => {
            let big = dir.join("big.obj");
            if !big.exists() {
                std::fs::write(&big, grid_mesh(300)).map_err(io)?;
            }
            for k in 0..n {
                let (x, z) = grid(k, side, 3.0);
                let _ = writeln!(
                    entities,
                    "        Entity(name: \"p{k}\", material: \"clay\", shape: Mesh(path: \"big.obj\"), transform: Transform(translate: ({x}, 0, {z}), rotate: (0, {}, 0))),",
                    (k * 37) % 360
                );
            }
        }
        "prefab" => {
            let mut children = String::new();
            for k in 0..1000 {
                let (x, z) = grid(k, 32, 0.1);
                let _ = writeln!(
                    children,
                    "        Entity(name: \"c{k}\", material: \"stone\", shape: Sphere(center: ({x}, 0.04, {z}), radius: 0.04)),"
                );
            }
            let prefab = format!(
                "Prefab(\n    materials: {{ \"stone\": Diffuse(albedo: Constant((0.5, 0.5, 0.5))) }},\n    entities: [\n{children}    ],\n)\n"
            );
            std::fs::write(dir.join("block.ron"), prefab).map_err(io)?;
            let placements = n.div_ceil(1000);
            let side = (placements as f64).sqrt().ceil() as usize;
            for k in 0..placements {
                let (x, z) = grid(k, side, 4.0);
                let _ = writeln!(
                    entities,
                    "        Entity(name: \"b{k}\", prefab: \"block.ron\", transform: Transform(translate: ({x}, 0, {z}))),"
                );
            }
        }
        other => return Err(format!("unknown kind {other:?}")),
    }
    let path = dir.join("scene.ron");
    std::fs::write(&path, scene_text(&materials, &entities, size)).map_err(io)?;
    Ok(path)
}

/// An OBJ height field of `side`² vertices.
fn grid_mesh(side: usize) -> String {
    let mut s = String::with_capacity(side * side * 40);
    let step = 2.0 / (side - 1) as f32;
    for j in 0..side {
        for i in 0..side {
            let (x, z) = (i as f32 * step, j as f32 * step);
            let _ = writeln!(s, "v {x} {} {z}", 0.1 * (3.0 * x).sin() * (2.0 * z).cos());
        }
    }
    for j in 0..side - 1 {
        for i in 0..side - 1 {
            let a = j * side + i + 1;
            let _ = writeln!(
                s,
                "f {a} {} {}\nf {a} {} {}",
                a + 1,
                a + side + 1,
                a + side + 1,
                a + side
            );
        }
    }
    s
}

/// Times every stage of the scene at `path`.
pub fn measure(kind: &'static str, count: usize, path: &Path) -> Result<Row, String> {
    let baseline = resident_kib();
    let start = ProcessTime::now();
    let source = std::fs::read_to_string(path).map_err(|e| e.to_string())?;
    parse_scene(path, &source).map_err(|e| e.to_string())?;
    let parse = start.elapsed();

    let start = ProcessTime::now();
    let loaded = load_scene(path, &mut AssetCache::default()).map_err(|e| e.to_string())?;
    let expand = start.elapsed().saturating_sub(parse);

    let start = ProcessTime::now();
    let (warnings, _) = check_counted(&loaded);
    let check = start.elapsed();
    let entities = loaded.entities.len();
    drop(loaded);

    let wall = Instant::now();
    let start = ProcessTime::now();
    let mut r = Renderer::new(None, PassPlan::Single).map_err(|e| e.to_string())?;
    r.set_overrides(Overrides {
        width: Some(16),
        height: Some(12),
        spp: Some(1),
        ..Overrides::default()
    });
    r.load(path).map_err(|e| e.to_string())?;
    let frame = ProcessTime::now();
    r.run_once();
    let (first_image, first_image_wall, frame) = (start.elapsed(), wall.elapsed(), frame.elapsed());
    let resident_mib = match (baseline, resident_kib()) {
        (Some(a), Some(b)) => b.saturating_sub(a) as f64 / 1024.0,
        _ => f64::NAN,
    };
    Ok(Row {
        kind,
        count,
        bytes: source.len(),
        entities,
        parse,
        expand,
        frame,
        first_image,
        first_image_wall,
        check,
        warnings: warnings.len(),
        resident_mib,
    })
}

/// Generates and measures every kind in `kinds` at every size of `sizes` (in a temporary
/// directory under `dir`), calling `each` after each scene (its error stops the run).
pub fn run(
    kinds: &[String],
    sizes: &[usize],
    dir: &Path,
    mut each: impl FnMut(&Row) -> Result<(), String>,
) -> Result<Vec<Row>, String> {
    let mut rows = Vec::new();
    for &(kind, _) in KINDS.iter().filter(|k| kinds.iter().any(|w| w == k.0)) {
        for &n in sizes {
            if matches!(kind, "meshes" | "textures") && n > MAX_FILES {
                continue;
            }
            let scene_dir = dir.join(format!("{kind}-{n}"));
            let path = generate(kind, n, &scene_dir)?;
            let row = measure(kind, n, &path)?;
            std::fs::remove_dir_all(&scene_dir).ok();
            each(&row)?;
            rows.push(row);
        }
    }
    Ok(rows)
}

/// One Markdown table per stage group: the figures of each kind over the sizes, and the growth
/// factor from each size to the next (10 per 10× is linear).
pub fn markdown(rows: &[Row]) -> String {
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    let mut s = String::from(
        "| kind | n | file MB | entities | parse ms | expand ms | frame ms | first image ms | (wall ms) | check ms | warnings | RSS MiB | growth per 10× (first image, check) |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n",
    );
    for (i, r) in rows.iter().enumerate() {
        let growth = match i.checked_sub(1).map(|p| &rows[p]) {
            Some(p) if p.kind == r.kind && p.count > 0 => {
                let f = (r.count as f64 / p.count as f64).log10();
                let g = |a: Duration, b: Duration| (ms(b) / ms(a).max(1e-3)).powf(1.0 / f);
                format!(
                    "×{:.1}, ×{:.1}",
                    g(p.first_image, r.first_image),
                    g(p.check, r.check)
                )
            }
            _ => String::new(),
        };
        let _ = writeln!(
            s,
            "| {} | {} | {:.1} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {} | {:.0} | {growth} |",
            r.kind,
            r.count,
            r.bytes as f64 / 1e6,
            r.entities,
            ms(r.parse),
            ms(r.expand),
            ms(r.frame),
            ms(r.first_image),
            ms(r.first_image_wall),
            ms(r.check),
            r.warnings,
            r.resident_mib
        );
    }
    s
}
