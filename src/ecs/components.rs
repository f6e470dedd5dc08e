//! Components of scene entities: pure data, written by the reload system with `set_if_neq`.
//!
//! ```ron
//! Entity(name: "ball", material: "glass",
//!        shape: Sphere(center: (0, 1, 0), radius: 1),
//!        transform: Transform(translate: (2, 0, 0), rotate: (0, 45, 0), scale: (1, 1, 1)))
//! Entity(name: "bunny", material: "white", shape: Mesh(path: "meshes/bunny.obj"))
//! ```

use bevy_ecs::component::Component;
use glam::{Affine3A, Mat3, Vec3};

/// The entity's name in the scene file; the key by which reloads match entities.
#[derive(Component, Clone, Debug, PartialEq, Eq, Hash)]
pub struct EntityName(pub String);

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

/// The order of the entity in its scene after prefab expansion: geometry is packed in this
/// order, so the image depends only on the scene file, never on the history of edits.
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct SceneOrder(pub u32);

/// Triangle mesh data, shared by every entity that uses the same file.
#[derive(Debug, Default, PartialEq)]
pub struct MeshData {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals, if the file has them.
    pub normals: Option<Vec<Vec3>>,
    /// Per-vertex texture coordinates, if the file has them.
    pub uvs: Option<Vec<glam::Vec2>>,
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

/// Name of the material in the scene's material table.
#[derive(Component, Clone, Debug, PartialEq, Eq)]
pub struct MaterialRef(pub String);
