//! The ECS layer: components, resources and system sets. Kernels never see it.

pub mod components;
pub mod frame_log;
pub mod resources;
pub mod sets;
