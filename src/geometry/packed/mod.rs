//! Render-side geometry: world-space primitives packed in BVH order, in a choice of layouts.
//!
//! Spheres and triangles each get their own BVH and their own arrays, so a scene pays only for the
//! primitive kinds it uses; infinite planes are tested linearly outside any BVH. What the
//! intersection loops read is stored as the layout `L` says (see [`super::layout`]: one
//! `Vec<f32>` per field, or one struct per primitive); what only shading needs (owner, texture
//! coordinates, frames) sits beside it and is touched once per closest hit.
//!
//! `primitive.rs` holds what is packed, `pack.rs` the packing (`Geometry` and its BVHs),
//! `query.rs` the ray queries whose answer is a `Hit` (`hit.rs`), `cache.rs` the copies in other
//! layouts.

mod cache;
mod hit;
mod pack;
mod primitive;
mod query;

pub use cache::{Cached, LayoutCache};
pub use hit::{Hit, HitKind};
pub use pack::{BvhPlan, Geometry, PlaneRecord};
pub use primitive::{Primitive, triangle_normal};
