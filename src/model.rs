//! The entity data model: what a loaded entity is made of (its [`Shape`] in object space, its
//! [`Transform`], and the [`MeshData`] a mesh shape refers to). The loader (`scene/`) writes
//! it, the ECS (`ecs/`) holds `Shape` and `Transform` as components, the kernels read mesh
//! data; it imports none of them.

use bevy_ecs::component::Component;
use glam::{Affine3A, Mat3, Vec3};

/// Geometry of an entity in object space. Validated by the loader: finite, non-degenerate.
#[derive(Component, Clone, Debug, PartialEq)]
pub enum Shape {
    /// A sphere.
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius (> 0).
        radius: f32,
    },
    /// An infinite plane.
    Plane {
        /// A point on the plane.
        point: Vec3,
        /// Unit normal.
        normal: Vec3,
    },
    /// A triangle; geometric normal `(b − a) × (c − a)`.
    Triangle {
        /// First vertex.
        a: Vec3,
        /// Second vertex.
        b: Vec3,
        /// Third vertex.
        c: Vec3,
    },
    /// A quad `a b c d`, split into triangles `abc` and `acd`; geometric normal `(b − a) × (c − a)`.
    Quad {
        /// First corner.
        a: Vec3,
        /// Second corner.
        b: Vec3,
        /// Third corner.
        c: Vec3,
        /// Fourth corner.
        d: Vec3,
    },
    /// An axis-aligned box (six quads with outward normals) before its transform.
    Box {
        /// Minimum corner.
        min: Vec3,
        /// Maximum corner.
        max: Vec3,
    },
    /// A triangle mesh loaded from a Wavefront OBJ file.
    Mesh(MeshRef),
}

/// Placement of an entity: its composed `world_from_object` matrix (for an entity inside
/// prefabs, the product of every placement's `T · R · S` down to it).
#[derive(Component, Clone, Copy, Debug, PartialEq, Default)]
pub struct Transform(pub Affine3A);

impl Transform {
    /// Whether the linear part is a rotation (or reflection) times a uniform scale, so spheres
    /// stay spheres.
    pub fn is_similarity(&self) -> bool {
        let m = self.0.matrix3;
        let (x, y, z) = (m.x_axis, m.y_axis, m.z_axis);
        let s2 = x.length_squared();
        let close = |a: f32, b: f32| (a - b).abs() <= 1e-5 * s2.max(f32::MIN_POSITIVE);
        close(y.length_squared(), s2)
            && close(z.length_squared(), s2)
            && close(x.dot(y), 0.0)
            && close(y.dot(z), 0.0)
            && close(x.dot(z), 0.0)
    }

    /// The uniform scale of a similarity transform (length of its first axis).
    pub fn uniform_scale(&self) -> f32 {
        Vec3::from(self.0.matrix3.x_axis).length()
    }

    /// The rotation part of a similarity transform, object to world.
    pub fn rotation(&self) -> Mat3 {
        Mat3::from(self.0.matrix3) * (1.0 / self.uniform_scale())
    }
}

/// Triangle mesh data, shared by every entity that uses the same file.
#[derive(Debug, Default, PartialEq)]
pub struct MeshData {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals, if the file has them.
    pub normals: Option<Vec<Vec3>>,
    /// Per-vertex texture coordinates, if the file has them.
    pub uvs: Option<Vec<glam::Vec2>>,
    /// A second set of per-vertex texture coordinates, carried only when a material reads one
    /// (a glTF material whose textures name two `TEXCOORD_n` sets).
    pub uvs1: Option<Vec<glam::Vec2>>,
    /// Triangles as vertex indices (validated to be in range).
    pub triangles: Vec<[u32; 3]>,
}

/// A mesh file's data and where it came from; equal when it is the same loaded data.
#[derive(Clone, Debug)]
pub struct MeshRef {
    /// The file.
    pub path: std::path::PathBuf,
    /// The loaded data.
    pub data: std::sync::Arc<MeshData>,
}

impl PartialEq for MeshRef {
    /// Same file and same load: a re-read file is a new mesh, an unchanged one is not.
    fn eq(&self, other: &Self) -> bool {
        self.path == other.path && std::sync::Arc::ptr_eq(&self.data, &other.data)
    }
}
