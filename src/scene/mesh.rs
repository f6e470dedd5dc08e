//! Wavefront OBJ meshes (crate `tobj`): every shape of the file, triangulated, with no hidden
//! scale.

use std::path::Path;

use glam::{Vec2, Vec3};

use crate::ecs::components::MeshData;

/// Reads an OBJ file. Faces are triangulated; all its objects are merged into one mesh. Vertex
/// normals and texture coordinates (`vt`) are each kept when every object has one per vertex.
/// Malformed files, out-of-range
/// indices, non-finite coordinates and empty meshes are errors, never panics.
pub fn load_obj(path: &Path) -> Result<MeshData, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read OBJ: {e}"))?;
    parse_obj(&bytes)
}

/// Parses the bytes of an OBJ file, as [`load_obj`] (material libraries are not read: materials
/// come from the scene).
pub fn parse_obj(bytes: &[u8]) -> Result<MeshData, String> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let (models, _materials) = tobj::load_obj_buf(&mut &bytes[..], &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| format!("cannot read OBJ: {e}"))?;
    let mut mesh = MeshData::default();
    let mut normals = Some(Vec::new());
    let mut uvs = Some(Vec::new());
    for model in &models {
        let m = &model.mesh;
        if m.positions.len() % 3 != 0 || m.indices.len() % 3 != 0 {
            return Err(format!(
                "object \"{}\": malformed vertex or face data",
                model.name
            ));
        }
        let base = mesh.positions.len();
        let count = m.positions.len() / 3;
        for p in m.positions.chunks_exact(3) {
            let v = Vec3::new(p[0], p[1], p[2]);
            if !v.is_finite() {
                return Err(format!("object \"{}\": non-finite vertex {v}", model.name));
            }
            mesh.positions.push(v);
        }
        match (&mut normals, m.normals.len() == m.positions.len()) {
            (Some(n), true) => n.extend(
                m.normals
                    .chunks_exact(3)
                    .map(|c| Vec3::new(c[0], c[1], c[2]).normalize_or_zero()),
            ),
            _ => normals = None,
        }
        match (&mut uvs, m.texcoords.len() == 2 * count) {
            (Some(t), true) => {
                for c in m.texcoords.chunks_exact(2) {
                    let uv = Vec2::new(c[0], c[1]);
                    if !uv.is_finite() {
                        return Err(format!(
                            "object \"{}\": non-finite texture coordinate {uv}",
                            model.name
                        ));
                    }
                    t.push(uv);
                }
            }
            _ => uvs = None,
        }
        for f in m.indices.chunks_exact(3) {
            if f.iter().any(|&i| i as usize >= count) {
                return Err(format!(
                    "object \"{}\": face index out of range",
                    model.name
                ));
            }
            mesh.triangles
                .push([f[0], f[1], f[2]].map(|i| i + base as u32));
        }
    }
    if mesh.triangles.is_empty() {
        return Err("the file has no faces".into());
    }
    mesh.normals = normals.filter(|n| n.len() == mesh.positions.len());
    mesh.uvs = uvs.filter(|t| t.len() == mesh.positions.len());
    Ok(mesh)
}
