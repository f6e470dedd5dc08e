//! Picking: which owner slot (scene entity) each pixel's camera ray hits first, for the viewer.
//!
//! One ray per pixel, the camera's deterministic central ray: through the pixel's centre from
//! the eye (for a thin lens, the lens centre: the ray every lens ray of that film position
//! converges with on the plane of focus). Nothing is sampled or averaged, so an id is exact and
//! the same for any thread count; it depends on the scene and camera only, never on the film,
//! so partials, splits and merges need nothing of it. In a scene with alpha masks a surface
//! whose coverage there is below one half is passed through, as the image mostly shows what lies
//! behind it. No ECS here.

use glam::Vec3;
use rayon::prelude::*;

use super::integrator::{point_error, spawn};
use super::{MAX_PASS_THROUGHS, SceneView};
use crate::geometry::layout::Layout;

/// The id of a pixel whose ray hits nothing (the sky or background).
pub const SKY: u32 = u32::MAX;

/// The owner slot the central camera ray of every pixel of a `width` × `height` image hits
/// first ([`SKY`] for none), rows from the top, in parallel over rows.
pub fn first_owners<L: Layout>(view: &SceneView<L>, width: u32, height: u32) -> Vec<u32> {
    let mut ids = vec![SKY; width as usize * height as usize];
    if width == 0 {
        return ids;
    }
    ids.par_chunks_mut(width as usize)
        .enumerate()
        .for_each(|(y, row)| {
            for (x, id) in row.iter_mut().enumerate() {
                *id = first_owner(view, x as u32, y as u32, width, height);
            }
        });
    ids
}

/// The owner slot the central ray of pixel `(x, y)` hits first, or [`SKY`].
fn first_owner<L: Layout>(view: &SceneView<L>, x: u32, y: u32, width: u32, height: u32) -> u32 {
    let film = (x as f32 + 0.5, y as f32 + 0.5);
    first_hit(view, film, width, height).map_or(SKY, |(owner, _)| owner)
}

/// The depth ([`crate::render::camera::Camera::depth`]) of the first surface the central ray
/// of film position `(x, y)` (in pixels of a `width` × `height` image, continuous) hits, as
/// picking sees it: the `focus_distance` that makes the point shown there sharp. `None` for
/// the sky or background.
pub fn depth_at<L: Layout>(
    view: &SceneView<L>,
    (x, y): (f32, f32),
    width: u32,
    height: u32,
) -> Option<f32> {
    let (_, p) = first_hit(view, (x, y), width, height)?;
    Some(view.camera.depth(p))
}

/// The owner slot and point of the first surface the central ray of film position `(x, y)`
/// hits, passing through masked-out surfaces.
fn first_hit<L: Layout>(
    view: &SceneView<L>,
    (x, y): (f32, f32),
    width: u32,
    height: u32,
) -> Option<(u32, Vec3)> {
    let mut ray = view.camera.ray(x, y, width, height);
    for _ in 0..MAX_PASS_THROUGHS {
        let hit = view.geometry.intersect(&ray, f32::INFINITY)?;
        let owner = view.geometry.owner(&hit);
        if !view.masked {
            return Some((owner, ray.at(hit.t)));
        }
        let s = view.surface(&ray, &hit);
        if view.material_of(owner).coverage(s.tex_coords()) >= 0.5 {
            return Some((owner, s.p));
        }
        let err = point_error(view.geometry, &hit, s.p);
        ray = spawn(s.p, s.n, err, ray.direction);
    }
    None
}
