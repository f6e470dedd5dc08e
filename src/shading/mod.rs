//! Shading kernels: random numbers, sampling, textures and materials. No ECS here.

pub mod material;
pub mod microfacet;
pub mod rng;
pub mod sampling;
pub mod texture;
