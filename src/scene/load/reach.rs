//! How far a placed shape reaches from the origin: the coordinate limit the loader enforces.

use glam::Vec3;

use crate::model::{Shape, Transform};

/// An upper bound of [`world_reach`] for a mesh with object-space `bounds`, from the box's 8
/// corners: each world coordinate is affine in the object point, so its extremes over the box
/// are at corners. A margin of 8 ulps of the largest product covers the rounding of each
/// vertex's own transform, so a bound within the limit proves every vertex is.
pub(super) fn corner_reach([lo, hi]: [Vec3; 2], transform: &Transform) -> f32 {
    let m = &transform.0;
    let corners = (0..8).map(|i| {
        Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    });
    let reach = corners.fold(0.0f32, |r, p| {
        r.max(m.transform_point3(p).abs().max_element())
    });
    let size = lo.abs().max(hi.abs());
    let magnitude = glam::Mat3A::from_cols(
        m.matrix3.x_axis.abs(),
        m.matrix3.y_axis.abs(),
        m.matrix3.z_axis.abs(),
    ) * glam::Vec3A::from(size)
        + m.translation.abs();
    reach + 8.0 * f32::EPSILON * magnitude.max_element()
}

/// Largest magnitude of any world-space coordinate of `shape` placed by `transform`: its
/// vertices (box corners, mesh positions), a sphere's centre plus radius, a plane's point. NaN or
/// infinite if the transform overflows. Also returns the number of points transformed.
pub(super) fn world_reach(shape: &Shape, transform: &Transform) -> (f32, u64) {
    let m = &transform.0;
    let reach = |points: &mut dyn Iterator<Item = Vec3>| {
        points.fold((0.0f32, 0u64), |(r, n), p| {
            let a = m.transform_point3(p).abs().max_element();
            let r = if a.is_nan() || r.is_nan() {
                f32::NAN
            } else {
                r.max(a)
            };
            (r, n + 1)
        })
    };
    match shape {
        Shape::Sphere { center, radius } => {
            let c = m.transform_point3(*center).abs().max_element();
            (c + radius * transform.uniform_scale(), 1)
        }
        Shape::Plane { point, .. } => reach(&mut std::iter::once(*point)),
        Shape::Triangle { a, b, c } => reach(&mut [*a, *b, *c].into_iter()),
        Shape::Quad { a, b, c, d } => reach(&mut [*a, *b, *c, *d].into_iter()),
        Shape::Box { min, max } => reach(&mut (0..8).map(|i| {
            Vec3::new(
                if i & 1 == 0 { min.x } else { max.x },
                if i & 2 == 0 { min.y } else { max.y },
                if i & 4 == 0 { min.z } else { max.z },
            )
        })),
        Shape::Mesh(mesh) => reach(&mut mesh.data.positions.iter().copied()),
    }
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;
    use std::sync::Arc;

    use glam::Affine3A;

    use super::*;
    use crate::model::{MeshData, MeshRef};

    #[test]
    fn corners_bound_every_vertex_of_a_transformed_mesh() {
        let mut rng = crate::shading::rng::Rng::new(3, 5);
        let mut r = || 2.0 * rng.next_f32() - 1.0;
        for _ in 0..200 {
            let positions: Vec<Vec3> = (0..50).map(|_| Vec3::new(r(), r(), r()) * 1e3).collect();
            let t = Transform(Affine3A::from_scale_rotation_translation(
                Vec3::new(r(), r(), r()) * 1e5,
                glam::Quat::from_euler(glam::EulerRot::XYZ, r(), r(), r()),
                Vec3::new(r(), r(), r()) * 1e8,
            ));
            let bounds = positions.iter().fold(
                [Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)],
                |[lo, hi], &p| [lo.min(p), hi.max(p)],
            );
            let data = Arc::new(MeshData {
                positions,
                triangles: vec![[0, 1, 2]],
                ..MeshData::default()
            });
            let shape = Shape::Mesh(MeshRef {
                path: PathBuf::new(),
                data,
            });
            let (exact, n) = world_reach(&shape, &t);
            assert_eq!(n, 50);
            assert!(corner_reach(bounds, &t) >= exact, "{exact}");
        }
    }
}
