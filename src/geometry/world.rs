//! Where a scene entity's shape lands in the world: the primitives the renderer packs, and the
//! `check` command tests, for a shape placed by its transform.

use glam::{Mat3, Vec2, Vec3};

use super::packed::Primitive;
use crate::model::{Shape, Transform};

const QUAD_UV: [Vec2; 4] = [Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y];

/// The world-space primitives of `shape` placed by `transform`; a mesh becomes its triangles
/// (the flattened form; the rebuild system instances meshes instead).
///
/// Triangles are transformed vertex by vertex and their normals recomputed from the result, so
/// normals are never transformed as points. A transform that mirrors (negative determinant)
/// would flip every normal, so vertex order is swapped to keep the declared front side.
pub fn world_primitives(shape: &Shape, transform: &Transform) -> Vec<Primitive> {
    let m = transform.0;
    let mirror = m.matrix3.determinant() < 0.0;
    let tri = |p: [Vec3; 3], uv: [Vec2; 3]| {
        let p = p.map(|v| m.transform_point3(v));
        if mirror {
            Primitive::Triangle {
                p: [p[0], p[2], p[1]],
                uv: [uv[0], uv[2], uv[1]],
            }
        } else {
            Primitive::Triangle { p, uv }
        }
    };
    let quad = |q: [Vec3; 4]| {
        let [a, b, c, d] = q;
        let [ta, tb, tc, td] = QUAD_UV;
        [tri([a, b, c], [ta, tb, tc]), tri([a, c, d], [ta, tc, td])]
    };
    match *shape {
        Shape::Sphere { center, radius } => vec![Primitive::Sphere {
            center: m.transform_point3(center),
            radius: radius * transform.uniform_scale(),
            frame: transform.rotation(),
        }],
        Shape::Plane { point, normal } => {
            let n = (Mat3::from(m.matrix3).inverse().transpose() * normal).normalize();
            vec![Primitive::Plane {
                point: m.transform_point3(point),
                normal: n,
            }]
        }
        Shape::Triangle { a, b, c } => vec![tri([a, b, c], [Vec2::ZERO, Vec2::X, Vec2::Y])],
        Shape::Quad { a, b, c, d } => quad([a, b, c, d]).to_vec(),
        Shape::Box { min, max } => box_quads(min, max).into_iter().flat_map(quad).collect(),
        Shape::Mesh(ref mesh) => {
            let p = &mesh.data.positions;
            let uv = |t: &[u32; 3]| match &mesh.data.uvs {
                Some(uvs) => t.map(|i| uvs[i as usize]),
                None => [Vec2::ZERO, Vec2::X, Vec2::Y],
            };
            mesh.data
                .triangles
                .iter()
                .map(|t| tri(t.map(|i| p[i as usize]), uv(t)))
                .collect()
        }
    }
}

/// The six faces of a box as quads whose normals `(b − a) × (c − a)` point outwards.
fn box_quads(min: Vec3, max: Vec3) -> Vec<[Vec3; 4]> {
    let center = 0.5 * (min + max);
    let mut faces = Vec::with_capacity(6);
    for axis in 0..3 {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        for side in [min[axis], max[axis]] {
            let corner = |cu: f32, cv: f32| {
                let mut p = Vec3::ZERO;
                p[axis] = side;
                p[u] = cu;
                p[v] = cv;
                p
            };
            let mut q = [
                corner(min[u], min[v]),
                corner(max[u], min[v]),
                corner(max[u], max[v]),
                corner(min[u], max[v]),
            ];
            let normal = (q[1] - q[0]).cross(q[2] - q[0]);
            if normal.dot(q[0] - center) < 0.0 {
                q.swap(1, 3);
            }
            faces.push(q);
        }
    }
    faces
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Affine3A, EulerRot, Quat};

    fn triangles(shape: &Shape, t: &Transform) -> Vec<[Vec3; 3]> {
        world_primitives(shape, t)
            .into_iter()
            .map(|p| match p {
                Primitive::Triangle { p, .. } => p,
                other => panic!("expected triangles, got {other:?}"),
            })
            .collect()
    }

    #[test]
    fn box_faces_point_outwards_even_when_mirrored() {
        let shape = Shape::Box {
            min: Vec3::ZERO,
            max: Vec3::new(1.0, 2.0, 3.0),
        };
        for scale in [Vec3::ONE, Vec3::new(-1.0, 1.0, 1.0)] {
            let rotation = Quat::from_euler(EulerRot::XYZ, 0.2, 0.3, 0.5);
            let t = Transform(Affine3A::from_scale_rotation_translation(
                scale,
                rotation,
                Vec3::ZERO,
            ));
            let tris = triangles(&shape, &t);
            assert_eq!(tris.len(), 12);
            let center = t.0.transform_point3(Vec3::new(0.5, 1.0, 1.5));
            for [a, b, c] in tris {
                let n = (b - a).cross(c - a);
                assert!(
                    n.dot((a + b + c) / 3.0 - center) > 0.0,
                    "inward face with scale {scale}"
                );
            }
        }
    }

    #[test]
    fn quad_splits_into_abc_and_acd_with_corner_uvs() {
        let (a, b, c, d) = (Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y);
        let prims = world_primitives(&Shape::Quad { a, b, c, d }, &Transform::default());
        assert_eq!(
            prims,
            vec![
                Primitive::Triangle {
                    p: [a, b, c],
                    uv: [Vec2::ZERO, Vec2::X, Vec2::ONE]
                },
                Primitive::Triangle {
                    p: [a, c, d],
                    uv: [Vec2::ZERO, Vec2::ONE, Vec2::Y]
                },
            ]
        );
    }

    #[test]
    fn plane_normal_is_transformed_as_a_normal() {
        // Shear-free but non-uniform scale: a normal transformed as a point would tilt.
        let shape = Shape::Plane {
            point: Vec3::ZERO,
            normal: Vec3::new(1.0, 1.0, 0.0).normalize(),
        };
        let t = Transform(Affine3A::from_scale(Vec3::new(2.0, 1.0, 1.0)));
        let Primitive::Plane { normal, .. } = world_primitives(&shape, &t)[0] else {
            panic!()
        };
        // The scaled plane x/2 + y = 0 has normal ∝ (1/2, 1, 0).
        assert!(
            (normal - Vec3::new(0.5, 1.0, 0.0).normalize()).length() < 1e-6,
            "{normal}"
        );
    }
}
