//! Packs entity shapes into world-space primitives and rebuilds the BVHs.

use std::time::Instant;

use bevy_ecs::prelude::*;

use super::render_frame::preview_block;
use crate::ecs::components::{SceneOrder, Shape, Transform};
use crate::ecs::frame_log::{BvhWork, FrameLog, GeometryWork};
use crate::ecs::resources::{
    Accumulation, Counters, PackedGeometry, PassPlan, Preview, RenderControl, RenderSettings,
    Timings,
};
use crate::geometry::packed::{Geometry, Primitive};
use crate::geometry::world::world_primitives;

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
    reason = "the entities, the packed geometry, what decides refit or build, and what it did"
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
    mut log: ResMut<FrameLog>,
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
    let bvh = if edited && preview_next && same_owners && packed.geometry.refit(&primitives) {
        packed.provisional = true;
        counters.bvh_refits += 1;
        BvhWork::Refitted
    } else {
        packed.geometry = Geometry::build(&primitives);
        packed.owners = sorted.iter().map(|e| e.0).collect();
        packed.provisional = false;
        counters.bvh_builds += 1;
        BvhWork::Built
    };
    counters.mesh_bvh_builds = packed.blas_cache.builds();
    timings.bvh = start.elapsed();
    log.geometry = Some(GeometryWork {
        bvh,
        primitives: packed.geometry.primitive_count(),
        took: timings.bvh,
    });
}
