//! Picking: which owner slot (scene entity) each pixel's camera ray hits first, for the viewer.
//!
//! One ray per pixel, the camera's deterministic central ray: through the pixel's centre from
//! the eye (for a thin lens, the lens centre: the ray every lens ray of that film position
//! converges with on the plane of focus). Nothing is sampled or averaged, so an id is exact and
//! the same for any thread count; it depends on the scene and camera only, never on the film,
//! so partials, splits and merges need nothing of it. In a scene with alpha masks a surface
//! whose coverage there is below one half is passed through, as the image mostly shows what lies
//! behind it. No ECS here.

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
    let mut ray = view
        .camera
        .ray(x as f32 + 0.5, y as f32 + 0.5, width, height);
    for _ in 0..MAX_PASS_THROUGHS {
        let Some(hit) = view.geometry.intersect(&ray, f32::INFINITY) else {
            return SKY;
        };
        let owner = view.geometry.owner(&hit);
        if !view.masked {
            return owner;
        }
        let s = view.surface(&ray, &hit);
        if view.material_of(owner).coverage(s.tex_coords()) >= 0.5 {
            return owner;
        }
        let err = point_error(view.geometry, &hit, s.p);
        ray = spawn(s.p, s.n, err, ray.direction);
    }
    SKY
}
