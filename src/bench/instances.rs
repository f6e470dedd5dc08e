//! `rondo bench instances`: build time and peak memory of a scene with N placements of one mesh.
//!
//! Each count runs in its own process (the parent re-runs the binary with `--single N`), because
//! peak memory (`VmHWM` from `/proc/self/status`) only ever grows within a process.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use crate::{Overrides, PassPlan, Renderer};

/// Figures of one run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InstanceRun {
    /// Placements of the mesh.
    pub count: usize,
    /// Triangles in the scene if every placement were copied.
    pub scene_triangles: u64,
    /// Loading the scene (parse, prefab expansion, mesh file) in milliseconds.
    pub load_ms: f64,
    /// Geometry packing + BVH builds in milliseconds.
    pub build_ms: f64,
    /// Rendering a 64×64 image at 1 spp in milliseconds.
    pub render_ms: f64,
    /// Peak resident memory of the process in KiB (`None` where `/proc` is unavailable).
    pub peak_kib: Option<u64>,
}

/// The process's peak resident set size in KiB, from `/proc/self/status` (Linux).
pub fn peak_rss_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// A scene placing `mesh` (a path relative to the scene directory) `count` times on a grid,
/// each placement turned differently.
pub fn scene_text(mesh: &str, count: usize) -> String {
    let side = (count as f64).sqrt().ceil().max(1.0) as usize;
    let mut entities = String::new();
    for k in 0..count {
        let (i, j) = ((k % side) as f32, (k / side) as f32);
        let _ = writeln!(
            entities,
            "        Entity(name: \"m{k}\", material: \"clay\", shape: Mesh(path: \"{mesh}\"), \
             transform: Transform(translate: ({}, 0, {}), rotate: (0, {}, 0))),",
            i * 12.0,
            j * 12.0,
            (k * 37) % 360
        );
    }
    let c = side as f32 * 6.0;
    format!(
        "Scene(\n    camera: Camera(position: ({c}, {}, {}), look_at: ({c}, 0, {c}), fov: 50),\n    \
         settings: Settings(width: 64, height: 64, spp: 1, max_depth: 3, background: (0.6, 0.7, 0.9)),\n    \
         materials: {{ \"clay\": Diffuse(albedo: Constant((0.7, 0.6, 0.5))) }},\n    entities: [\n{entities}    ],\n)\n",
        c * 1.5 + 10.0,
        -c - 10.0,
    )
}

/// Loads and renders a scene of `count` placements of the mesh at `mesh_path` in this process,
/// with meshes instanced (`true`) or copied into the scene BVH (`false`).
pub fn measure(mesh_path: &Path, count: usize, instancing: bool) -> Result<InstanceRun, String> {
    // A private directory of a fresh, unpredictable name (no planted files or symlinks),
    // removed with its contents when dropped.
    let temp = tempfile::Builder::new()
        .prefix("rondo-bench-instances-")
        .tempdir()
        .map_err(|e| format!("cannot create a temporary directory: {e}"))?;
    let dir = temp.path();
    let mesh =
        std::fs::canonicalize(mesh_path).map_err(|e| format!("{}: {e}", mesh_path.display()))?;
    let scene = dir.join("instances.ron");
    let text = scene_text(&mesh.to_string_lossy(), count);
    std::fs::write(&scene, text).map_err(|e| format!("{}: {e}", scene.display()))?;

    let mut r = Renderer::new(None, PassPlan::Single).map_err(|e| e.to_string())?;
    r.set_overrides(Overrides::default());
    r.set_instancing(instancing);
    let start = Instant::now();
    r.load(&scene).map_err(|e| e.to_string())?;
    let load_ms = start.elapsed().as_secs_f64() * 1e3;
    let render = r.render_to_completion();
    let build_ms = r.timings().bvh.as_secs_f64() * 1e3;
    let triangles = crate::scene::assets::AssetCache::default()
        .mesh(&mesh)
        .map(|m| m.triangles.len() as u64)
        .unwrap_or(0);
    Ok(InstanceRun {
        count,
        scene_triangles: triangles * count as u64,
        load_ms,
        build_ms,
        render_ms: (render.as_secs_f64() * 1e3 - build_ms).max(0.0),
        peak_kib: peak_rss_kib(),
    })
}

/// One CSV line of a run (see [`CSV_HEADER`]).
pub fn csv_line(r: &InstanceRun) -> String {
    format!(
        "{},{},{:.3},{:.3},{:.3},{}",
        r.count,
        r.scene_triangles,
        r.load_ms,
        r.build_ms,
        r.render_ms,
        r.peak_kib.map_or(String::new(), |k| k.to_string())
    )
}

/// Column names of [`csv_line`].
pub const CSV_HEADER: &str = "instances,scene_triangles,load_ms,build_ms,render_ms,peak_kib";

/// Parses a [`csv_line`] back (the parent reads its children's output this way).
pub fn parse_csv_line(line: &str) -> Option<InstanceRun> {
    let f: Vec<&str> = line.trim().split(',').collect();
    if f.len() != 6 {
        return None;
    }
    Some(InstanceRun {
        count: f[0].parse().ok()?,
        scene_triangles: f[1].parse().ok()?,
        load_ms: f[2].parse().ok()?,
        build_ms: f[3].parse().ok()?,
        render_ms: f[4].parse().ok()?,
        peak_kib: f[5].parse().ok(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_lines_round_trip() {
        let r = InstanceRun {
            count: 10,
            scene_triangles: 36_740,
            load_ms: 1.5,
            build_ms: 2.25,
            render_ms: 3.0,
            peak_kib: Some(4096),
        };
        assert_eq!(parse_csv_line(&csv_line(&r)), Some(r));
    }

    #[test]
    fn generated_scene_places_the_mesh_count_times() {
        let text = scene_text("m.obj", 7);
        assert_eq!(text.matches("Mesh(path: \"m.obj\")").count(), 7);
        assert!(text.contains("\"m6\""));
    }
}
