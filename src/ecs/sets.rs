//! System ordering.

use bevy_ecs::schedule::SystemSet;

/// The stages of a frame, in order.
#[derive(SystemSet, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RenderSystems {
    /// Apply a loaded scene to the world.
    Load,
    /// Rebuild geometry and material assignments that changed.
    Build,
    /// Trace a pass.
    Render,
    /// Write the image.
    Output,
}
