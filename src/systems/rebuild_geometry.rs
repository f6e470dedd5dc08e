//! Packs entity shapes into world-space primitives and rebuilds the BVHs.

use std::time::Instant;

use bevy_ecs::prelude::*;
use glam::{Mat3, Vec2, Vec3};

use super::render_frame::preview_block;
use crate::ecs::components::{SceneOrder, Shape, Transform};
use crate::ecs::resources::{
    Accumulation, Counters, PackedGeometry, PassPlan, Preview, RenderControl, RenderSettings,
    Timings,
};
use crate::geometry::packed::{Geometry, Primitive};

const QUAD_UV: [Vec2; 4] = [Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y];

/// Entities whose shape, transform or place in the scene was added or changed.
type GeometryChanged = Or<(Changed<Shape>, Changed<Transform>, Changed<SceneOrder>)>;

/// Run condition: a `Shape` or `Transform` was added, changed or removed since the last check,
/// or the geometry is [`PackedGeometry::provisional`] and the next pass is not a preview.
pub fn geometry_changed(
    changed: Query<(), GeometryChanged>,
    mut removed: RemovedComponents<Shape>,
    packed: Res<PackedGeometry>,
    acc: Res<Accumulation>,
) -> bool {
    let removed_any = removed.read().count() > 0;
    removed_any || !changed.is_empty() || (packed.provisional && acc.preview != Preview::Due)
}

/// Rebuilds [`PackedGeometry`] from every entity, in scene order (so the result depends only on
/// the scene file, not on the history of edits). Runs only under [`geometry_changed`].
///
/// When entities only moved or changed size (the same primitives, owner by owner) and the next
/// pass is a live preview, the BVHs are refitted instead ([`Geometry::refit`]): the preview comes
/// without a build, and the geometry stays provisional until the build that follows the preview,
/// before any real sample, so images never depend on the history of edits.
#[expect(
    clippy::too_many_arguments,
    reason = "the entities, the packed geometry, and what decides refit or build"
)]
pub fn rebuild_geometry(
    entities: Query<(Entity, &SceneOrder, &Shape, &Transform)>,
    changed: Query<(), GeometryChanged>,
    mut removed: RemovedComponents<Shape>,
    settings: Res<RenderSettings>,
    control: Res<RenderControl>,
    mut packed: ResMut<PackedGeometry>,
    mut counters: ResMut<Counters>,
    mut timings: ResMut<Timings>,
) {
    let start = Instant::now();
    let edited = removed.read().count() > 0 || !changed.is_empty();
    let mut sorted: Vec<_> = entities.iter().collect();
    sorted.sort_by_key(|e| *e.1);
    let mut primitives = Vec::new();
    let mut meshes = Vec::new();
    let packed = &mut *packed;
    for (slot, (_, _, shape, transform)) in sorted.iter().enumerate() {
        match shape {
            // A mesh is placed by reference to its shared BVH, never copied.
            Shape::Mesh(mesh) if packed.instancing => {
                meshes.push(mesh.data.clone());
                let blas = packed.blas_cache.get(&mesh.data);
                primitives.push((
                    slot as u32,
                    Primitive::Instance {
                        blas,
                        world_from_object: transform.0,
                    },
                ));
            }
            _ => primitives.extend(
                world_primitives(shape, transform)
                    .into_iter()
                    .map(|p| (slot as u32, p)),
            ),
        }
    }
    packed.blas_cache.retain(&meshes);
    let s = &settings.0;
    let preview_next = match control.plan {
        PassPlan::Progressive { .. } => preview_block(control.preview_block, s.width, s.height) > 1,
        PassPlan::Single => false,
    };
    let same_owners = packed.owners.len() == sorted.len()
        && packed.owners.iter().zip(&sorted).all(|(a, b)| *a == b.0);
    if edited && preview_next && same_owners && packed.geometry.refit(&primitives) {
        packed.provisional = true;
        counters.bvh_refits += 1;
    } else {
        packed.geometry = Geometry::build(&primitives);
        packed.owners = sorted.iter().map(|e| e.0).collect();
        packed.provisional = false;
        counters.bvh_builds += 1;
    }
    counters.mesh_bvh_builds = packed.blas_cache.builds();
    timings.bvh = start.elapsed();
}

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
    use crate::scene::format::TransformDesc;

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
            let t = Transform(
                TransformDesc {
                    scale,
                    rotate: Vec3::new(10.0, 20.0, 30.0),
                    ..Default::default()
                }
                .matrix(),
            );
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
        let t = Transform(
            TransformDesc {
                scale: Vec3::new(2.0, 1.0, 1.0),
                ..Default::default()
            }
            .matrix(),
        );
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
