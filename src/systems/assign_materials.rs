//! Resolves each owner slot's material name to an index into the material table.

use bevy_ecs::prelude::*;

use crate::ecs::components::MaterialRef;
use crate::ecs::resources::{Counters, MaterialTable, OwnerMaterials, PackedGeometry};

/// Run condition: a `MaterialRef` was added or changed.
pub fn material_refs_changed(changed: Query<(), Changed<MaterialRef>>) -> bool {
    !changed.is_empty()
}

/// Rebuilds [`OwnerMaterials`]: cheap (one entry per entity and material), and never touches the
/// BVH, so a material-only edit costs no geometry work.
pub fn assign_materials(
    refs: Query<&MaterialRef>,
    packed: Res<PackedGeometry>,
    table: Res<MaterialTable>,
    mut out: ResMut<OwnerMaterials>,
    mut counters: ResMut<Counters>,
) {
    let names: Vec<&String> = table.0.keys().collect();
    let owner_material = packed
        .owners
        .iter()
        .map(|&e| {
            refs.get(e)
                .ok()
                .and_then(|r| names.binary_search(&&r.0).ok())
                .unwrap_or(0) as u32
        })
        .collect();
    out.set_if_neq(OwnerMaterials {
        materials: table.0.values().cloned().collect(),
        owner_material,
    });
    counters.material_syncs += 1;
}
