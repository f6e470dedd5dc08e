//! Geometry kernels: rays, boxes, shapes, the BVH and the packed render-side arrays. No ECS here.

pub mod aabb;
pub mod bvh;
pub mod packed;
pub mod plane;
pub mod ray;
pub mod sphere;
pub mod triangle;
