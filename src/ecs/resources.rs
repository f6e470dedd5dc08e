//! World resources: the scene-wide state (camera, settings, materials) and the render-side
//! snapshot the render system reads instead of querying entities.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use bevy_ecs::entity::Entity;
use bevy_ecs::resource::Resource;

use crate::film::Film;
use crate::geometry::instance::BlasCache;
use crate::geometry::layout::LayoutKind;
use crate::geometry::packed::Geometry;
use crate::lights::LightSet;
use crate::lights::punctual::PunctualLight;
use crate::render::TraceStats;
use crate::scene::format::{CameraDesc, SettingsDesc};
use crate::scene::load::LoadedScene;
use crate::shading::material::Material;
use crate::sky::Sky;

/// A freshly loaded scene waiting for [`crate::systems::apply_scene`].
#[derive(Resource, Default)]
pub struct PendingScene(pub Option<LoadedScene>);

/// The camera of the current scene.
#[derive(Resource, Clone, Copy, Debug, PartialEq)]
pub struct ActiveCamera(pub CameraDesc);

/// Image and sampling settings of the current scene.
#[derive(Resource, Clone, Debug, PartialEq, Default)]
pub struct RenderSettings(pub SettingsDesc);

/// The distant lights of the current scene (environment map and sun).
#[derive(Resource, Clone, Debug, PartialEq, Default)]
pub struct ActiveSky(pub Sky);

/// The point and spot lights of the current scene (its `lights` and those of its glTF files).
#[derive(Resource, Clone, Debug, PartialEq, Default)]
pub struct ActiveLights(pub Vec<PunctualLight>);

/// Materials of the current scene by name.
#[derive(Resource, Clone, Debug, PartialEq, Default)]
pub struct MaterialTable(pub BTreeMap<String, Material>);

/// Bumped on every applied scene that changes anything (see [`ChangeSummary::is_empty`]): an
/// unchanged save, or a metadata-only event, keeps the render going instead of starting over,
/// since a deterministic render of the same scene gives the same image.
#[derive(Resource, Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct SceneVersion(pub u64);

/// Packed geometry with its BVHs, rebuilt only when shapes or transforms change.
#[derive(Resource)]
pub struct PackedGeometry {
    /// Primitives and BVHs.
    pub geometry: Geometry,
    /// The entity behind each owner slot of the geometry.
    pub owners: Vec<Entity>,
    /// Mesh BVHs kept across rebuilds (an unchanged mesh is not rebuilt).
    pub blas_cache: BlasCache,
    /// Place meshes as instances of one shared BVH (the default) instead of copying their
    /// triangles into the scene BVH.
    pub instancing: bool,
    /// Whether the BVHs were refitted rather than built: fit for a preview only. The build
    /// follows before any real sample is traced.
    pub provisional: bool,
}

impl PackedGeometry {
    /// Whether side renders of the world may trace it: the BVHs are built (not only refitted)
    /// and `materials` has a material for every owner slot (a frame has run since the rebuild).
    pub fn traceable_with(&self, materials: &OwnerMaterials) -> bool {
        !self.provisional && materials.owner_material.len() >= self.owners.len()
    }
}

impl Default for PackedGeometry {
    fn default() -> Self {
        Self {
            geometry: Geometry::default(),
            owners: Vec::new(),
            blas_cache: BlasCache::default(),
            instancing: true,
            provisional: false,
        }
    }
}

/// Material table in the order the renderer indexes it, the material of each owner slot, and
/// the emitters those materials make (rebuilt together, without touching the BVH).
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct OwnerMaterials {
    /// Materials.
    pub materials: Vec<Material>,
    /// Index into `materials` per owner slot.
    pub owner_material: Vec<u32>,
    /// Emitters for next-event estimation.
    pub lights: LightSet,
}

/// What the last reload changed.
#[derive(Resource, Clone, Debug, Default, PartialEq, Eq)]
pub struct ChangeSummary {
    /// Entities spawned.
    pub added: usize,
    /// Entities whose shape, transform or material changed.
    pub changed: usize,
    /// Entities despawned.
    pub removed: usize,
    /// Whether the material table changed.
    pub materials: bool,
    /// Whether the camera changed.
    pub camera: bool,
    /// Whether the settings changed.
    pub settings: bool,
    /// Whether the distant lights changed (their settings, or the environment map's file).
    pub sky: bool,
    /// Whether the point and spot lights changed.
    pub lights: bool,
    /// Whether entities kept by the reload changed their order in the scene (geometry is packed
    /// in scene order, so this rebuilds the BVH).
    pub reordered: bool,
}

impl ChangeSummary {
    /// Whether the reload changed nothing at all.
    pub fn is_empty(&self) -> bool {
        *self == Self::default()
    }
}

/// Work counters, so tests can assert what a reload did.
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counters {
    /// BVH (geometry) builds so far.
    pub bvh_builds: u64,
    /// BVH refits so far: moves shown in a preview without a build
    /// ([`PackedGeometry::provisional`]).
    pub bvh_refits: u64,
    /// Material assignments so far.
    pub material_syncs: u64,
    /// Render passes completed so far (a live preview counts as one).
    pub passes: u64,
    /// Mesh (bottom-level) BVH builds so far.
    pub mesh_bvh_builds: u64,
}

/// Durations of the last runs of each step.
#[derive(Resource, Clone, Copy, Debug, Default)]
pub struct Timings {
    /// Last geometry pack + BVH build.
    pub bvh: Duration,
    /// Last render pass.
    pub pass: Duration,
    /// Rendering since the last reset (all passes).
    pub render: Duration,
}

/// How samples are split into passes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PassPlan {
    /// All samples in one pass (batch renders).
    Single,
    /// A first pass of `first` samples, then passes that double the total (live preview).
    Progressive {
        /// Samples of the first pass.
        first: u32,
    },
}

/// Render control shared with the outside (cancel flag, progress bar).
#[derive(Resource, Clone)]
pub struct RenderControl {
    /// Set to abandon the current pass (checked per band of rows).
    pub cancel: Arc<AtomicBool>,
    /// Pass plan.
    pub plan: PassPlan,
    /// Progress bar advanced by rows, if any.
    pub progress: Option<indicatif::ProgressBar>,
    /// Russian roulette on (the default; off only to test that it is unbiased).
    pub roulette: bool,
    /// Progressive renders start with a preview of one sample per `preview_block`² pixels, or
    /// larger blocks for large images (see [`crate::systems::preview_block`]); 1 = no preview.
    pub preview_block: u32,
    /// Layout of the geometry the render reads; images are bit-identical in every layout.
    pub layout: LayoutKind,
}

/// Where the live-preview image of the current scene stands.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Preview {
    /// No preview for this render (batch renders, or already replaced by real passes).
    #[default]
    Done,
    /// A reduced-resolution preview is to be rendered first.
    Due,
    /// The film holds the preview; it is cleared before the first real pass.
    InFilm,
}

/// The accumulating image and the statistics of the current render.
#[derive(Resource, Default)]
pub struct Accumulation {
    /// Sample sums.
    pub film: Film,
    /// Counters since the last reset.
    pub stats: TraceStats,
    /// Whether `film` holds every sample the settings ask for.
    pub complete: bool,
    /// Live-preview state.
    pub preview: Preview,
    /// First sample index a reset film starts at (0 but for a render of a sample range).
    pub first_sample: u32,
    /// Whether the film collects the feature buffers (albedo and normal) for a denoiser.
    pub features: bool,
}

impl Accumulation {
    /// Clears the film for a `width` × `height` image whose samples are rounded to multiples of
    /// 2⁻`shift` ([`crate::film::shift_for`]), reusing its memory when the size holds.
    pub fn reset(&mut self, width: u32, height: u32, shift: i32) {
        if self.film.width != width
            || self.film.height != height
            || self.film.features.is_some() != self.features
        {
            self.film = if self.features {
                Film::with_features(width, height)
            } else {
                Film::new(width, height)
            };
        }
        self.film.clear(self.first_sample);
        self.film.shift = shift;
        self.stats = TraceStats::default();
        self.complete = false;
    }
}

/// Where and whether [`crate::systems::write_image`] writes the film.
#[derive(Resource, Clone, Debug, Default)]
pub struct Output {
    /// Target file (`.png` or `.exr`); none to keep the image in memory only.
    pub path: Option<PathBuf>,
    /// Write after every pass (live preview) instead of only when complete.
    pub every_pass: bool,
    /// Result of the last write.
    pub last_error: Option<String>,
    /// Images written so far.
    pub writes: u64,
}
