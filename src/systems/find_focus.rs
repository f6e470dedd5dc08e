//! The focus distance of a point in the viewer: the depth of the surface a film position of a
//! camera shows, in the world as it is (the viewer's "focus on click"). Called between frames,
//! not part of the schedule.

use bevy_ecs::world::World;

use super::render_frame::{camera_of, scene_view};
use crate::ecs::resources::{OwnerMaterials, PackedGeometry, RenderSettings};
use crate::render::pick::depth_at;
use crate::scene::format::CameraDesc;

/// The depth along the view of `camera` of the first surface its central ray through `(x, y)`
/// hits, `x` and `y` being fractions of the image's width and height from its top-left corner
/// (so the answer is the same at any image size of the scene's aspect): the `focus_distance`
/// that makes that point sharp. `Some(None)` for the sky or background, `None` if the materials
/// were not yet assigned to the geometry (no frame has run).
pub fn find_focus(world: &World, camera: &CameraDesc, (x, y): (f32, f32)) -> Option<Option<f32>> {
    let packed = world.resource::<PackedGeometry>();
    let materials = world.resource::<OwnerMaterials>();
    let s = &world.resource::<RenderSettings>().0;
    if !packed.traceable_with(materials) {
        return None;
    }
    let camera = camera_of(camera);
    let view = scene_view(&packed.geometry, materials, &camera, s, true);
    let film = (x * s.width as f32, y * s.height as f32);
    Some(depth_at(&view, film, s.width, s.height))
}
