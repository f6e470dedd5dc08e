//! Systems, one per file, named verb_noun. They move data between the ECS and the kernels.

mod apply_scene;
mod assign_materials;
mod pick_ids;
mod rebuild_geometry;
mod render_camera;
mod render_frame;
mod write_image;

pub use crate::geometry::world::world_primitives;
pub use apply_scene::apply_scene;
pub use assign_materials::{assign_materials, material_refs_changed};
pub use pick_ids::{IdBuffer, pick_ids};
pub use rebuild_geometry::{geometry_changed, rebuild_geometry};
pub use render_camera::render_camera;
pub use render_frame::{PREVIEW_PATHS, film_shift, preview_block, render_frame};
pub use write_image::write_image;
