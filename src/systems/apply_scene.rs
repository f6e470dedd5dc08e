//! Applies a loaded scene to the world, touching only what changed.

use std::collections::HashMap;

use bevy_ecs::prelude::*;

use crate::ecs::components::{EntityName, MaterialRef, SceneOrder, Shape, Transform};
use crate::ecs::frame_log::FrameLog;
use crate::ecs::resources::{
    ActiveCamera, ActiveLights, ActiveSky, ChangeSummary, MaterialTable, PendingScene,
    RenderSettings, SceneVersion,
};
use crate::scene::load::LoadedEntity;

/// The components a reload compares and writes.
type SceneEntity = (
    Entity,
    &'static EntityName,
    &'static mut Shape,
    &'static mut Transform,
    &'static mut MaterialRef,
    &'static mut SceneOrder,
);

/// One entity's components as the reload query yields them.
type SceneEntityItem<'w> = (
    Entity,
    &'w EntityName,
    Mut<'w, Shape>,
    Mut<'w, Transform>,
    Mut<'w, MaterialRef>,
    Mut<'w, SceneOrder>,
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
    mut lights: ResMut<ActiveLights>,
    mut version: ResMut<SceneVersion>,
    mut summary: ResMut<ChangeSummary>,
    mut log: ResMut<FrameLog>,
) {
    let Some(scene) = pending.0.take() else {
        return;
    };
    let mut report = ChangeSummary::default();
    let n = scene.entities.len();
    // An entity usually keeps its place in the list: it is matched there by name, and only the
    // rest (the strays) go through a map of the names left unmatched. A one-entity edit of a big
    // scene so hashes a handful of names, not all of them.
    let mut matched = vec![false; n];
    let mut strays = Vec::new();
    // (old order, new order) of the entities kept, to tell a reorder from the shifts that
    // additions and removals cause.
    let mut kept: Vec<(u32, u32)> = Vec::with_capacity(n);
    for item in &mut entities {
        let i = item.5.0 as usize;
        match scene.entities.get(i) {
            Some(new) if new.name == item.1.0 => {
                matched[i] = true;
                kept.push((item.5.0, i as u32));
                report.changed += usize::from(update(item, new, i));
            }
            _ => strays.push(item.0),
        }
    }
    if !strays.is_empty() {
        let mut incoming: HashMap<&str, usize> = (0..n)
            .filter(|&i| !matched[i])
            .map(|i| (scene.entities[i].name.as_str(), i))
            .collect();
        for entity in strays {
            let Ok(item) = entities.get_mut(entity) else {
                continue;
            };
            let Some(i) = incoming.remove(item.1.0.as_str()) else {
                commands.entity(entity).despawn();
                report.removed += 1;
                continue;
            };
            matched[i] = true;
            kept.push((item.5.0, i as u32));
            report.changed += usize::from(update(item, &scene.entities[i], i));
        }
    }
    for (i, e) in scene.entities.iter().enumerate() {
        if matched[i] {
            continue;
        }
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
    report.lights = lights.set_if_neq(ActiveLights(scene.lights));
    if version.0 == 0 || !report.is_empty() {
        version.0 += 1;
    }
    log.applied = Some(report.clone());
    *summary = report;
}

/// Writes the components of an entity that differ from `new`, now at place `at` of the list:
/// whether its shape, transform or material changed. Nothing is cloned or flagged when equal.
fn update(
    (_, _, mut shape, mut transform, mut material, mut order): SceneEntityItem,
    new: &LoadedEntity,
    at: usize,
) -> bool {
    let a = *shape != new.shape;
    if a {
        *shape = new.shape.clone();
    }
    let b = transform.set_if_neq(new.transform);
    let c = material.0 != new.material;
    if c {
        material.0.clone_from(&new.material);
    }
    order.set_if_neq(SceneOrder(at as u32));
    a || b || c
}
