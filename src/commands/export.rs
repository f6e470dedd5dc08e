//! `rondo export`: a scene written for other renderers (`rondo::export`).

use rondo::cli::print_line;
use std::path::Path;

use anyhow::Result;

/// `rondo export`: writes the scene into `dir` and prints what it wrote.
pub fn run(scene: &Path, dir: &Path, max_triangles: u64) -> Result<()> {
    let report = rondo::export::export_scene(scene, dir, max_triangles)?;
    print_line(format_args!(
        "{}: {} triangles ({} mesh placements flattened), {} spheres, {} plane triangles; {} files in {}",
        scene.display(),
        report.triangles,
        report.mesh_placements,
        report.spheres,
        report.plane_triangles,
        report.files.len(),
        dir.display()
    ))?;
    Ok(())
}
