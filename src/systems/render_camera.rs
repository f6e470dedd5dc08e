//! A side render of the world as it is through another camera: the viewer's framing previews.
//! The geometry, materials, lights and settings are those of the last applied scene; only the
//! camera and the image size differ. The film is fresh and never touches the accumulation, so
//! the progressive render is left as it was. Called between frames, not part of the schedule.

use std::sync::atomic::AtomicBool;

use super::render_frame::{camera_of, scene_film_shift, scene_view};
use crate::ecs::resources::{OwnerMaterials, PackedGeometry, RenderControl, RenderSettings};
use crate::film::Film;
use crate::render::{Cancelled, render_pass};
use crate::scene::format::CameraDesc;
use bevy_ecs::world::World;

/// Samples `0..spp` of every pixel of a `width` × `height` image of the world seen through
/// `camera`, with the scene's seed, sampler, method and film shift: the film `rondo render`
/// makes of the scene with that camera, size and sample count, bit for bit. `None` if the
/// materials were not yet assigned to the geometry (no frame has run); `Err` if `cancel` rose.
pub fn render_camera(
    world: &World,
    camera: &CameraDesc,
    (width, height): (u32, u32),
    spp: u32,
    cancel: &AtomicBool,
) -> Option<Result<Film, Cancelled>> {
    let packed = world.resource::<PackedGeometry>();
    let materials = world.resource::<OwnerMaterials>();
    let control = world.resource::<RenderControl>();
    let s = &world.resource::<RenderSettings>().0;
    if !packed.traceable_with(materials) {
        return None;
    }
    let camera = camera_of(camera);
    let view = scene_view(&packed.geometry, materials, &camera, s, control.roulette);
    let mut film = Film::new(width, height);
    // As `render_frame` resets the accumulation: the shift depends on the files alone.
    film.shift = scene_film_shift(materials, s.background);
    Some(render_pass(&view, &mut film, s.seed, 0..spp, cancel, &|_| {}).map(|_| film))
}
