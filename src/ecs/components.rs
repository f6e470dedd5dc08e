//! Components of scene entities: pure data, written by the reload system with `set_if_neq`.
//!
//! ```ron
//! Entity(name: "ball", material: "glass",
//!        shape: Sphere(center: (0, 1, 0), radius: 1),
//!        transform: Transform(translate: (2, 0, 0), rotate: (0, 45, 0), scale: (1, 1, 1)))
//! Entity(name: "bunny", material: "white", shape: Mesh(path: "meshes/bunny.obj"))
//! ```

use bevy_ecs::component::Component;

/// The entity data model's shape and placement, components of every scene entity.
pub use crate::model::{Shape, Transform};

/// The entity's name in the scene file; the key by which reloads match entities.
#[derive(Component, Clone, Debug, PartialEq, Eq, Hash)]
pub struct EntityName(pub String);

/// The order of the entity in its scene after prefab expansion: geometry is packed in this
/// order, so the image depends only on the scene file, never on the history of edits.
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct SceneOrder(pub u32);

/// Name of the material in the scene's material table.
#[derive(Component, Clone, Debug, PartialEq, Eq)]
pub struct MaterialRef(pub String);
