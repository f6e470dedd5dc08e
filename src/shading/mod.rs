//! Shading kernels: random numbers, samplers, sampling, textures and materials. No ECS here.

pub mod maps;
pub mod material;
pub mod microfacet;
pub mod pbr;
pub mod rng;
pub mod sampler;
pub mod sampling;
pub mod texture;
