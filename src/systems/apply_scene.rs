//! Applies a loaded scene to the world, touching only what changed.

use std::collections::HashMap;

use bevy_ecs::prelude::*;

use crate::ecs::components::{EntityName, MaterialRef, SceneOrder, Shape, Transform};
use crate::ecs::resources::{
    ActiveCamera, ActiveSky, ChangeSummary, MaterialTable, PendingScene, RenderSettings,
    SceneVersion,
};

/// The components a reload compares and writes.
type SceneEntity = (
    Entity,
    &'static EntityName,
    &'static mut Shape,
    &'static mut Transform,
    &'static mut MaterialRef,
    &'static mut SceneOrder,
);

/// Diffs the pending scene against the world by entity name: unchanged entities are not touched
/// (`set_if_neq`, so change detection stays quiet), changed ones are updated in place, missing
/// ones despawned and new ones spawned. The [`SceneVersion`] (and so the film) moves only when
/// something changed.
#[expect(
    clippy::too_many_arguments,
    reason = "one parameter per piece of scene state"
)]
pub fn apply_scene(
    mut commands: Commands,
    mut pending: ResMut<PendingScene>,
    mut entities: Query<SceneEntity>,
    mut camera: ResMut<ActiveCamera>,
    mut settings: ResMut<RenderSettings>,
    mut materials: ResMut<MaterialTable>,
    mut sky: ResMut<ActiveSky>,
    mut version: ResMut<SceneVersion>,
    mut summary: ResMut<ChangeSummary>,
) {
    let Some(scene) = pending.0.take() else {
        return;
    };
    let mut report = ChangeSummary::default();
    let mut incoming: HashMap<&str, usize> = scene
        .entities
        .iter()
        .enumerate()
        .map(|(i, e)| (e.name.as_str(), i))
        .collect();

    // (old order, new order) of the entities kept, to tell a reorder from the shifts that
    // additions and removals cause.
    let mut kept: Vec<(u32, u32)> = Vec::new();
    for (entity, name, mut shape, mut transform, mut material, mut order) in &mut entities {
        let Some(i) = incoming.remove(name.0.as_str()) else {
            commands.entity(entity).despawn();
            report.removed += 1;
            continue;
        };
        let new = &scene.entities[i];
        let a = shape.set_if_neq(new.shape.clone());
        let b = transform.set_if_neq(new.transform);
        let c = material.set_if_neq(MaterialRef(new.material.clone()));
        kept.push((order.0, i as u32));
        order.set_if_neq(SceneOrder(i as u32));
        if a || b || c {
            report.changed += 1;
        }
    }
    let mut fresh: Vec<usize> = incoming.into_values().collect();
    fresh.sort_unstable();
    for i in fresh {
        let e = &scene.entities[i];
        commands.spawn((
            EntityName(e.name.clone()),
            e.shape.clone(),
            e.transform,
            MaterialRef(e.material.clone()),
            SceneOrder(i as u32),
        ));
        report.added += 1;
    }

    kept.sort_unstable();
    report.reordered = kept.windows(2).any(|w| w[0].1 > w[1].1);
    report.camera = camera.set_if_neq(ActiveCamera(scene.camera));
    report.settings = settings.set_if_neq(RenderSettings(scene.settings));
    report.materials = materials.set_if_neq(MaterialTable(scene.materials));
    report.sky = sky.set_if_neq(ActiveSky(scene.sky));
    if version.0 == 0 || !report.is_empty() {
        version.0 += 1;
    }
    *summary = report;
}
