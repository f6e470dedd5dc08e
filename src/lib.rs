//! rondo: a data-oriented ECS path tracer for hand-written RON scenes, with hot reload.
//!
//! Scenes are RON files ([`scene`]). Their entities become bevy_ecs entities with [`Shape`],
//! [`Transform`] and [`MaterialRef`] components; systems ([`systems`]) pack them into
//! structure-of-arrays geometry with a BVH (obvhs) only when geometry changed, and the path
//! tracer ([`render`]) renders the packed snapshot with rayon. Kernels ([`geometry`],
//! [`shading`], [`lights`], [`film`]) know nothing about the ECS. See `ARCHITECTURE.md`.

pub mod app;
pub mod bench;
pub mod cli;
pub mod cpu;
pub mod denoise;
pub mod ecs;
pub mod export;
pub mod farm;
pub mod film;
pub mod geometry;
pub mod lights;
pub mod lsp;
pub mod metrics;
pub mod model;
pub mod output_file;
pub mod render;
pub mod scene;
pub mod serve;
pub mod shading;
pub mod sky;
pub mod systems;
pub mod watch;

pub use app::{Overrides, Renderer};
pub use ecs::components::{EntityName, MaterialRef, Shape, Transform};
pub use ecs::resources::PassPlan;
pub use film::Film;
pub use scene::error::SceneError;
