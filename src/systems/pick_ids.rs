//! The id buffer of the viewer's picking, from the world as it is: for every pixel, the entity
//! its central camera ray hits first ([`crate::render::pick`]), named by its place in the
//! scene's expansion order ([`SceneOrder`], the index of [`crate::scene::provenance`]'s
//! entries). Called between frames, not part of the schedule.

use bevy_ecs::world::World;

use super::render_frame::{camera_of, scene_view};
use crate::ecs::components::SceneOrder;
use crate::ecs::resources::{ActiveCamera, OwnerMaterials, PackedGeometry, RenderSettings};
use crate::render::pick::{SKY, first_owners};

/// One id per pixel, rows from the top: the entity's scene order, or [`SKY`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct IdBuffer {
    /// Pixels per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// `width × height` ids.
    pub ids: Vec<u32>,
}

/// The id buffer of the scene and camera in `world` at its settings' resolution. All sky if
/// the materials were not yet assigned to the geometry (no frame has run).
pub fn pick_ids(world: &World) -> IdBuffer {
    let packed = world.resource::<PackedGeometry>();
    let materials = world.resource::<OwnerMaterials>();
    let s = &world.resource::<RenderSettings>().0;
    let (width, height) = (s.width, s.height);
    if materials.owner_material.len() < packed.owners.len() {
        return IdBuffer {
            width,
            height,
            ids: vec![SKY; width as usize * height as usize],
        };
    }
    let camera = camera_of(&world.resource::<ActiveCamera>().0);
    let view = scene_view(&packed.geometry, materials, &camera, s, true);
    let order: Vec<u32> = packed
        .owners
        .iter()
        .map(|&e| world.get::<SceneOrder>(e).map_or(SKY, |o| o.0))
        .collect();
    let ids = first_owners(&view, width, height)
        .into_iter()
        .map(|slot| order.get(slot as usize).copied().unwrap_or(SKY))
        .collect();
    IdBuffer { width, height, ids }
}
