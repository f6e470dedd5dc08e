//! World-space triangles written as binary little-endian PLY, one file per material and
//! vertex layout (normals and texture coordinates present or not), read alike by Mitsuba 3's
//! `ply` shape and Blender's importer:
//!
//! ```text
//! ply
//! format binary_little_endian 1.0
//! element vertex N      property float x y z [nx ny nz] [u v]
//! element face M        property list uchar uint vertex_indices
//! end_header
//! ```
//!
//! Texture coordinates are rondo's: v points up the image (v = 0 is its bottom row), as in
//! OBJ and Blender; Mitsuba reads row 0 at v = 0, so its converter flips v.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::Path;

use glam::{Affine3A, Mat3, Vec2, Vec3};

use crate::geometry::packed::Primitive;
use crate::geometry::world::world_primitives;
use crate::model::Shape;
use crate::scene::load::{LoadedEntity, LoadedScene};

/// What one PLY file holds: the material's key and the vertex layout.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct GroupKey {
    /// Key of the material in the loaded scene's table.
    pub material: String,
    /// Whether vertices carry shading normals (meshes that have them).
    pub normals: bool,
    /// Whether vertices carry texture coordinates.
    pub uvs: bool,
}

/// Counts of one written file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Written {
    /// Vertices.
    pub vertices: u64,
    /// Triangles, the planes' squares included.
    pub triangles: u64,
    /// Triangles of the planes' squares.
    pub plane_triangles: u64,
}

/// The entities that go into each file, spheres left out.
pub fn groups(scene: &LoadedScene) -> BTreeMap<GroupKey, Vec<usize>> {
    let mut groups: BTreeMap<GroupKey, Vec<usize>> = BTreeMap::new();
    for (i, e) in scene.entities.iter().enumerate() {
        let (normals, uvs) = match &e.shape {
            Shape::Sphere { .. } => continue,
            Shape::Mesh(m) => (m.data.normals.is_some(), m.data.uvs.is_some()),
            _ => (false, true),
        };
        let key = GroupKey {
            material: e.material.clone(),
            normals,
            uvs,
        };
        groups.entry(key).or_default().push(i);
    }
    groups
}

/// The square standing for the plane through `point` with unit `normal`: corners `a b c d`
/// (front side along `normal`) and their texture coordinates, rondo's planar ones (offsets
/// along `normal.any_orthonormal_pair()`, as the renderer computes them).
pub fn plane_square(point: Vec3, normal: Vec3, half: f32) -> ([Vec3; 4], [Vec2; 4]) {
    let (t, b) = normal.any_orthonormal_pair();
    let offsets = if t.cross(b).dot(normal) >= 0.0 {
        [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
    } else {
        [(-1.0, -1.0), (-1.0, 1.0), (1.0, 1.0), (1.0, -1.0)]
    };
    let p = offsets.map(|(s, r)| point + half * (s * t + r * b));
    let uv = offsets.map(|(s, r)| Vec2::new(half * s, half * r));
    (p, uv)
}

/// One vertex as written.
struct Vertex {
    p: Vec3,
    n: Vec3,
    uv: Vec2,
}

/// Calls `vertex` for each vertex and `face` for each triangle (indices local to the entity)
/// of entity `e` in world space; returns (vertices, triangles).
fn emit(
    e: &LoadedEntity,
    plane_half: f32,
    vertex: &mut dyn FnMut(Vertex) -> std::io::Result<()>,
    face: &mut dyn FnMut([u32; 3]) -> std::io::Result<()>,
) -> std::io::Result<(u64, u64)> {
    match &e.shape {
        Shape::Sphere { .. } => Ok((0, 0)),
        Shape::Mesh(mesh) => {
            let m: Affine3A = e.transform.0;
            let normal_matrix = Mat3::from(m.matrix3).inverse().transpose();
            let mirror = m.matrix3.determinant() < 0.0;
            let data = &mesh.data;
            for (k, &p) in data.positions.iter().enumerate() {
                let n = data
                    .normals
                    .as_ref()
                    .map_or(Vec3::ZERO, |ns| (normal_matrix * ns[k]).normalize_or_zero());
                let uv = data.uvs.as_ref().map_or(Vec2::ZERO, |uvs| uvs[k]);
                vertex(Vertex {
                    p: m.transform_point3(p),
                    n,
                    uv,
                })?;
            }
            for t in &data.triangles {
                face(if mirror { [t[0], t[2], t[1]] } else { *t })?;
            }
            Ok((data.positions.len() as u64, data.triangles.len() as u64))
        }
        Shape::Plane { .. } => {
            let Some(Primitive::Plane { point, normal }) =
                world_primitives(&e.shape, &e.transform).pop()
            else {
                return Ok((0, 0));
            };
            let (p, uv) = plane_square(point, normal, plane_half);
            for k in 0..4 {
                vertex(Vertex {
                    p: p[k],
                    n: normal,
                    uv: uv[k],
                })?;
            }
            face([0, 1, 2])?;
            face([0, 2, 3])?;
            Ok((4, 2))
        }
        _ => {
            let mut count = 0u32;
            for prim in world_primitives(&e.shape, &e.transform) {
                if let Primitive::Triangle { p, uv } = prim {
                    for k in 0..3 {
                        vertex(Vertex {
                            p: p[k],
                            n: Vec3::ZERO,
                            uv: uv[k],
                        })?;
                    }
                    face([3 * count, 3 * count + 1, 3 * count + 2])?;
                    count += 1;
                }
            }
            Ok((3 * u64::from(count), u64::from(count)))
        }
    }
}

/// Writes the entities `members` of `scene` (one group of [`groups`]) to `path`; planes become
/// squares of half-size `PLANE_PROXY_SCALE · extent`. Counts first, then streams the data:
/// nothing but the file's buffer is allocated per triangle.
pub fn write_group(
    path: &Path,
    scene: &LoadedScene,
    key: &GroupKey,
    members: &[usize],
    extent: f32,
) -> std::io::Result<Written> {
    let plane_half = super::PLANE_PROXY_SCALE * extent;
    let mut written = Written::default();
    for &i in members {
        let e = &scene.entities[i];
        let (v, t) = emit(e, plane_half, &mut |_| Ok(()), &mut |_| Ok(()))?;
        written.vertices += v;
        written.triangles += t;
        if matches!(e.shape, Shape::Plane { .. }) {
            written.plane_triangles += t;
        }
    }
    if written.vertices > u64::from(u32::MAX) {
        return Err(std::io::Error::other(format!(
            "{} vertices, more than a PLY index can address",
            written.vertices
        )));
    }
    crate::output_file::write_atomically(path, |out| {
        write!(
            out,
            "ply\nformat binary_little_endian 1.0\ncomment rondo export, material {:?}\n\
             element vertex {}\nproperty float x\nproperty float y\nproperty float z\n",
            key.material.replace('\n', " "),
            written.vertices
        )?;
        if key.normals {
            out.write_all(b"property float nx\nproperty float ny\nproperty float nz\n")?;
        }
        if key.uvs {
            out.write_all(b"property float u\nproperty float v\n")?;
        }
        write!(
            out,
            "element face {}\nproperty list uchar uint vertex_indices\nend_header\n",
            written.triangles
        )?;
        for &i in members {
            emit(
                &scene.entities[i],
                plane_half,
                &mut |v| {
                    let mut floats = v.p.to_array().to_vec();
                    if key.normals {
                        floats.extend(v.n.to_array());
                    }
                    if key.uvs {
                        floats.extend(v.uv.to_array());
                    }
                    for f in floats {
                        out.write_all(&f.to_le_bytes())?;
                    }
                    Ok(())
                },
                &mut |_| Ok(()),
            )?;
        }
        let mut base = 0u32;
        for &i in members {
            let (v, _) = emit(&scene.entities[i], plane_half, &mut |_| Ok(()), &mut |t| {
                out.write_all(&[3])?;
                for k in t {
                    out.write_all(&(base + k).to_le_bytes())?;
                }
                Ok(())
            })?;
            base += v as u32;
        }
        Ok(())
    })?;
    Ok(written)
}
