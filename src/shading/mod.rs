//! Shading kernels: random numbers, samplers, sampling, textures, materials and the BSDF they
//! become at a hit, one file per lobe. No ECS here.

pub mod albedo_table;
pub mod bsdf;
pub mod coat;
pub mod conductor;
pub mod dielectric;
pub mod diffuse;
pub mod emission;
pub mod energy;
pub mod fresnel;
pub mod fuzzed;
pub mod glass_table;
pub mod layer_maps;
pub mod layers;
pub mod maps;
pub mod material;
pub mod microfacet;
pub mod pbr;
pub mod rng;
pub mod rough_dielectric;
pub mod sampler;
pub mod sampling;
pub mod scatter;
pub mod sheen;
pub mod sheen_table;
pub mod specular;
pub mod texture;
