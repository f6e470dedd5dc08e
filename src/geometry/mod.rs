//! Geometry kernels: rays, boxes, shapes, the BVH and the packed render-side arrays. No ECS here.

pub mod aabb;
pub mod bvh;
pub mod instance;
pub mod layout;
pub mod packed;
pub mod plane;
pub mod ray;
pub mod simd;
pub mod sphere;
pub mod store;
pub mod surface;
pub mod triangle;
pub mod world;
