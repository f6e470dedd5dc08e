//! What the systems did in one run of the schedule: each system that acts writes its part, so a
//! caller learns what a frame rebuilt and what it cost from the frame itself.

use std::time::Duration;

use bevy_ecs::resource::Resource;

use super::resources::ChangeSummary;

/// What one run of the schedule did. Cleared before each run ([`crate::app::Renderer::run_once`]
/// returns it); a system that does nothing leaves its part empty.
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct FrameLog {
    /// What the scene applied in this frame changed; `None` if no scene was applied.
    pub applied: Option<ChangeSummary>,
    /// The geometry packed and its BVHs built or refitted, if they were.
    pub geometry: Option<GeometryWork>,
    /// Whether the materials of the owner slots and the light table were assigned again.
    pub materials: bool,
    /// The pass rendered; `None` if none ran to its end (the film was complete, or the pass was
    /// cancelled).
    pub pass: Option<PassWork>,
}

/// How [`crate::systems::rebuild_geometry`] brought the BVHs up to date.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BvhWork {
    /// Built from the primitives.
    Built,
    /// Refitted to moved primitives, for a preview only (the build follows before real samples).
    Refitted,
}

/// The geometry work of a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GeometryWork {
    /// Built or refitted.
    pub bvh: BvhWork,
    /// Primitives in the geometry.
    pub primitives: usize,
    /// Packing the primitives and building or refitting the BVHs.
    pub took: Duration,
}

/// A pass that ran to its end.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PassWork {
    /// Samples per pixel in the film after it.
    pub samples: u32,
    /// Whether it was the reduced-resolution preview.
    pub preview: bool,
    /// How long it took.
    pub took: Duration,
}
