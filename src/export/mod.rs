//! `rondo export`: a scene as rondo loads it, written for other renderers to render the same
//! picture (the benchmark suite, `benches/suite/`).
//!
//! The output directory gets `scene.json` (camera, settings, sky, materials as rondo interprets
//! them, spheres, planes, and the list of mesh files; [`describe`]) and one binary
//! little-endian PLY file per material and vertex layout, with every triangle in world space
//! ([`ply`]): quads, boxes and triangles as rondo splits them, each mesh placement (instances,
//! glTF nodes, prefabs) flattened into its own copy of the mesh's vertices. Infinite planes are
//! listed in `scene.json` and also written as a large square ([`PLANE_PROXY_SCALE`]) for
//! renderers without planes.
//!
//! Output rules are those of every rondo output ([`crate::output_file`]): each file is written
//! atomically under a fixed name inside the directory (no name comes from the scene), and a
//! symlink at a file's name is replaced, never followed. The directory itself must not be a
//! symlink. The triangle count is computed from the loaded scene before anything is allocated
//! for it or written, and refused above the caller's bound.

pub mod describe;
pub mod ply;
mod textures;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::model::Shape;
use crate::scene::assets::AssetCache;
use crate::scene::load::load_scene;

/// Most triangles `rondo export` writes by default (and at most): 2²⁵ ≈ 33.5 M, about 3.2 GB
/// of PLY with normals and texture coordinates.
pub const MAX_TRIANGLES: u64 = 1 << 25;

/// Half-size of the square written for an infinite plane, in units of the scene's extent (the
/// largest distance of the camera or of any other shape's vertex from the plane's point, at
/// least 1): far enough that its edge lies near the horizon.
pub const PLANE_PROXY_SCALE: f32 = 100.0;

/// Why a scene could not be exported.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct ExportError(pub String);

/// What an export wrote.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ExportReport {
    /// Triangles of the scene's shapes, instances flattened (plane squares not counted).
    pub triangles: u64,
    /// Triangles written for planes (two per plane).
    pub plane_triangles: u64,
    /// Spheres.
    pub spheres: usize,
    /// Mesh placements flattened.
    pub mesh_placements: usize,
    /// Files written, `scene.json` last.
    pub files: Vec<PathBuf>,
}

/// Triangles that `shape` becomes (0 for spheres and planes).
pub fn triangle_count(shape: &Shape) -> u64 {
    match shape {
        Shape::Sphere { .. } | Shape::Plane { .. } => 0,
        Shape::Triangle { .. } => 1,
        Shape::Quad { .. } => 2,
        Shape::Box { .. } => 12,
        Shape::Mesh(mesh) => mesh.data.triangles.len() as u64,
    }
}

/// Loads `scene` and writes it into `dir` (created if missing), refusing a scene of more than
/// `max_triangles` triangles before writing anything.
pub fn export_scene(
    scene: &Path,
    dir: &Path,
    max_triangles: u64,
) -> Result<ExportReport, ExportError> {
    let mut cache = AssetCache::default();
    let loaded = load_scene(scene, &mut cache).map_err(|e| ExportError(e.to_string()))?;
    let triangles: u64 = loaded
        .entities
        .iter()
        .map(|e| triangle_count(&e.shape))
        .sum();
    if triangles > max_triangles {
        return Err(ExportError(format!(
            "{}: {triangles} triangles once instances are flattened, more than the {max_triangles} \
             an export may write (--max-triangles, at most {MAX_TRIANGLES})",
            scene.display()
        )));
    }
    prepare_dir(dir)?;
    let images = textures::ImageFiles::find(&loaded, &mut cache, dir)?;
    let groups = ply::groups(&loaded);
    let mut report = ExportReport {
        triangles,
        spheres: loaded
            .entities
            .iter()
            .filter(|e| matches!(e.shape, Shape::Sphere { .. }))
            .count(),
        mesh_placements: loaded
            .entities
            .iter()
            .filter(|e| matches!(e.shape, Shape::Mesh(_)))
            .count(),
        ..ExportReport::default()
    };
    report.files.extend(images.written.iter().cloned());
    let extent = describe::extent(&loaded);
    let mut mesh_files = BTreeMap::new();
    for (i, (key, members)) in groups.iter().enumerate() {
        let name = format!("mesh-{i:03}.ply");
        let path = dir.join(&name);
        let written = ply::write_group(&path, &loaded, key, members, extent)
            .map_err(|e| ExportError(format!("{}: {e}", path.display())))?;
        report.plane_triangles += written.plane_triangles;
        mesh_files.insert(name, (key.clone(), written));
        report.files.push(path);
    }
    let json = describe::scene_json(&loaded, &images, &mesh_files, &report)?;
    let path = dir.join("scene.json");
    let text = serde_json::to_string_pretty(&json)
        .map_err(|e| ExportError(format!("{}: {e}", path.display())))?;
    crate::output_file::write_bytes(&path, text.as_bytes())
        .map_err(|e| ExportError(format!("{}: {e}", path.display())))?;
    report.files.push(path);
    Ok(report)
}

/// Creates `dir` if missing; refuses it if it is a symlink or not a directory.
fn prepare_dir(dir: &Path) -> Result<(), ExportError> {
    let fail = |why: String| ExportError(format!("{}: cannot export here: {why}", dir.display()));
    match std::fs::symlink_metadata(dir) {
        Ok(meta) if meta.file_type().is_symlink() => Err(fail(
            "it is a symlink (exports never write through one)".into(),
        )),
        Ok(meta) if !meta.is_dir() => Err(fail("it is not a directory".into())),
        Ok(_) => Ok(()),
        Err(_) => std::fs::create_dir_all(dir).map_err(|e| fail(e.to_string())),
    }
}
