//! Resolves each owner slot's material name to an index into the material table.

use bevy_ecs::prelude::*;

use crate::ecs::components::MaterialRef;
use crate::ecs::frame_log::FrameLog;
use crate::ecs::resources::{
    ActiveLights, ActiveSky, Counters, MaterialTable, OwnerMaterials, PackedGeometry,
};
use crate::lights::LightSet;

/// Run condition: a `MaterialRef` was added or changed.
pub fn material_refs_changed(changed: Query<(), Changed<MaterialRef>>) -> bool {
    !changed.is_empty()
}

/// Rebuilds [`OwnerMaterials`] and the light set (the sky's distant lights and the point and
/// spot lights included): linear in entities and primitives, and never
/// touches the BVH, so a material-only edit costs no geometry build.
#[expect(
    clippy::too_many_arguments,
    reason = "the materials, the geometry and every kind of light"
)]
pub fn assign_materials(
    refs: Query<&MaterialRef>,
    packed: Res<PackedGeometry>,
    table: Res<MaterialTable>,
    sky: Res<ActiveSky>,
    punctual: Res<ActiveLights>,
    mut out: ResMut<OwnerMaterials>,
    mut counters: ResMut<Counters>,
    mut log: ResMut<FrameLog>,
) {
    let names: Vec<&String> = table.0.keys().collect();
    let owner_material: Vec<u32> = packed
        .owners
        .iter()
        .map(|&e| {
            refs.get(e)
                .ok()
                .and_then(|r| names.binary_search(&&r.0).ok())
                .unwrap_or(0) as u32
        })
        .collect();
    let materials: Vec<_> = table.0.values().cloned().collect();
    let lights = LightSet::build_with_lights(
        &packed.geometry,
        &materials,
        &owner_material,
        &sky.0,
        &punctual.0,
    );
    out.set_if_neq(OwnerMaterials {
        materials,
        owner_material,
        lights,
    });
    counters.material_syncs += 1;
    log.materials = true;
}
