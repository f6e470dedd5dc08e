//! The application: an ECS `World` and `Schedule` driven by the command line or the watcher.

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use bevy_ecs::prelude::*;
use bevy_ecs::schedule::{SystemCondition, common_conditions::resource_changed};

use crate::ecs::frame_log::FrameLog;
use crate::ecs::resources::{
    Accumulation, ActiveCamera, ActiveLights, ActiveSky, ChangeSummary, Counters, MaterialTable,
    Output, OwnerMaterials, PackedGeometry, PassPlan, PendingScene, Preview, RenderControl,
    RenderSettings, SceneVersion, Timings,
};
use crate::ecs::sets::RenderSystems;
use crate::film::Film;
use crate::geometry::layout::LayoutKind;
use crate::render::TraceStats;
use crate::scene::assets::AssetCache;
use crate::scene::error::SceneError;
use crate::scene::format::{CameraDesc, Method, SettingsDesc};
use crate::scene::load::{LoadedScene, load_scene};
use crate::scene::provenance::Provenance;
use crate::shading::sampler::SamplerKind;
use crate::systems::{
    IdBuffer, apply_scene, assign_materials, geometry_changed, material_refs_changed, pick_ids,
    rebuild_geometry, render_camera, render_frame, write_image,
};

/// Command-line overrides of a scene's settings.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Overrides {
    /// Image width.
    pub width: Option<u32>,
    /// Image height.
    pub height: Option<u32>,
    /// Samples per pixel.
    pub spp: Option<u32>,
    /// Rays per path.
    pub max_depth: Option<u32>,
    /// Random seed.
    pub seed: Option<u64>,
    /// Light-transport method.
    pub method: Option<Method>,
    /// Sample generator.
    pub sampler: Option<SamplerKind>,
}

impl Overrides {
    /// Applies the overrides and checks the result against the format's limits.
    pub fn apply(&self, s: &mut SettingsDesc) -> Result<(), String> {
        s.width = self.width.unwrap_or(s.width);
        s.height = self.height.unwrap_or(s.height);
        s.spp = self.spp.unwrap_or(s.spp);
        s.max_depth = self.max_depth.unwrap_or(s.max_depth);
        s.seed = self.seed.unwrap_or(s.seed);
        s.method = self.method.unwrap_or(s.method);
        s.sampler = self.sampler.unwrap_or(s.sampler);
        s.validate()
    }
}

/// What [`Renderer::load`] loaded.
#[derive(Clone, Debug)]
pub struct LoadInfo {
    /// Every file the scene depends on.
    pub dependencies: Vec<std::path::PathBuf>,
    /// The settings, overrides applied.
    pub settings: SettingsDesc,
    /// What the load skipped or approximated ([`LoadedScene::warnings`]).
    pub warnings: Vec<String>,
    /// What the load read and decoded (unchanged files come from the cache).
    pub assets: AssetWork,
}

/// What one [`Renderer::load`] did with asset files.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AssetWork {
    /// Image textures decoded.
    pub textures_decoded: u64,
    /// Environment maps decoded and given their distribution.
    pub environments_built: u64,
    /// Bytes of asset files (textures, meshes, maps, glTF files and buffers) read.
    pub bytes_read: u64,
}

impl std::ops::AddAssign for AssetWork {
    fn add_assign(&mut self, other: Self) {
        self.textures_decoded += other.textures_decoded;
        self.environments_built += other.environments_built;
        self.bytes_read += other.bytes_read;
    }
}

/// The renderer: owns the world, the schedule, the texture cache and the thread pool.
pub struct Renderer {
    world: World,
    schedule: Schedule,
    assets: AssetCache,
    pool: rayon::ThreadPool,
    overrides: Overrides,
    /// Whether each load keeps where its entities come from ([`Renderer::keep_provenance`]).
    keep_provenance: bool,
    provenance: Option<Arc<Provenance>>,
}

impl Renderer {
    /// A renderer with `threads` worker threads (all cores if `None`) and the given pass plan.
    pub fn new(
        threads: Option<usize>,
        plan: PassPlan,
    ) -> Result<Self, rayon::ThreadPoolBuildError> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads.unwrap_or(0))
            .build()?;
        let mut world = World::new();
        world.init_resource::<PendingScene>();
        world.insert_resource(ActiveCamera(CameraDesc {
            position: glam::Vec3::ZERO,
            direction: glam::Vec3::Z,
            up: glam::Vec3::Y,
            fov: 40.0,
            aperture: 0.0,
            focus_distance: 1.0,
        }));
        world.init_resource::<RenderSettings>();
        world.init_resource::<MaterialTable>();
        world.init_resource::<ActiveSky>();
        world.init_resource::<ActiveLights>();
        world.init_resource::<SceneVersion>();
        world.init_resource::<PackedGeometry>();
        world.init_resource::<OwnerMaterials>();
        world.init_resource::<ChangeSummary>();
        world.init_resource::<Counters>();
        world.init_resource::<Timings>();
        world.init_resource::<FrameLog>();
        world.init_resource::<Accumulation>();
        world.init_resource::<Output>();
        world.insert_resource(RenderControl {
            cancel: Arc::new(AtomicBool::new(false)),
            plan,
            progress: None,
            roulette: true,
            // A 2×2-block preview costs a quarter of a 1-spp pass (large images take larger
            // blocks): the first image of a live edit comes that much sooner.
            preview_block: match plan {
                PassPlan::Progressive { .. } => 2,
                PassPlan::Single => 1,
            },
            layout: LayoutKind::default(),
        });

        let mut schedule = Schedule::default();
        schedule.configure_sets(
            (
                RenderSystems::Load,
                RenderSystems::Build,
                RenderSystems::Render,
                RenderSystems::Output,
            )
                .chain(),
        );
        schedule.add_systems((
            apply_scene.in_set(RenderSystems::Load),
            (
                rebuild_geometry.run_if(geometry_changed),
                assign_materials.run_if(
                    resource_changed::<PackedGeometry>
                        .or_eager(resource_changed::<MaterialTable>)
                        .or_eager(resource_changed::<ActiveSky>)
                        .or_eager(resource_changed::<ActiveLights>)
                        .or_eager(material_refs_changed),
                ),
            )
                .chain()
                .in_set(RenderSystems::Build),
            render_frame.in_set(RenderSystems::Render),
            write_image.in_set(RenderSystems::Output),
        ));
        Ok(Self {
            world,
            schedule,
            assets: AssetCache::default(),
            pool,
            overrides: Overrides::default(),
            keep_provenance: false,
            provenance: None,
        })
    }

    /// Sets the settings overrides applied to every scene loaded from now on.
    pub fn set_overrides(&mut self, overrides: Overrides) {
        self.overrides = overrides;
    }

    /// Whether the film collects the feature buffers (albedo and normal, [`crate::film::Features`])
    /// for a denoiser, from the next render on. Off by default: a render that needs no denoiser
    /// pays nothing for them. The image is the same either way.
    pub fn set_features(&mut self, on: bool) {
        let mut acc = self.world.resource_mut::<Accumulation>();
        if acc.features != on {
            acc.features = on;
            // A new film of the right kind at the next pass.
            acc.film = Film::default();
        }
    }

    /// Sets the output file; `every_pass` writes after each pass (live preview).
    pub fn set_output(&mut self, path: Option<&Path>, every_pass: bool) {
        let mut out = self.world.resource_mut::<Output>();
        out.path = path.map(Path::to_path_buf);
        out.every_pass = every_pass;
    }

    /// Sets the geometry layout the renderer traces (default: [`LayoutKind::default`]). Images
    /// are bit-identical in every layout; only speed differs.
    pub fn set_layout(&mut self, layout: LayoutKind) {
        let mut control = self.world.resource_mut::<RenderControl>();
        if control.layout != layout {
            control.layout = layout;
            self.restart_render();
        }
    }

    /// Places meshes as instances of a shared BVH (`true`, the default) or copies their
    /// triangles into the scene BVH (`false`, for comparisons). Call before loading.
    pub fn set_instancing(&mut self, on: bool) {
        self.world.resource_mut::<PackedGeometry>().instancing = on;
    }

    /// Whether meshes are placed as instances ([`Renderer::set_instancing`]).
    pub fn instancing(&self) -> bool {
        self.world.resource::<PackedGeometry>().instancing
    }

    /// Whether Russian roulette is on ([`Renderer::set_roulette`]).
    pub fn roulette(&self) -> bool {
        self.world.resource::<RenderControl>().roulette
    }

    /// Turns Russian roulette on or off (on by default; both are unbiased).
    pub fn set_roulette(&mut self, on: bool) {
        let mut control = self.world.resource_mut::<RenderControl>();
        if control.roulette != on {
            control.roulette = on;
            self.restart_render();
        }
    }

    /// Starts the loaded scene's render over (a reload of an unchanged scene keeps the film, so
    /// a change of how it is traced must say so).
    fn restart_render(&mut self) {
        let mut version = self.world.resource_mut::<SceneVersion>();
        if version.0 > 0 {
            version.0 += 1;
        }
    }

    /// Attaches a progress bar advanced by rendered rows.
    pub fn set_progress(&mut self, bar: Option<indicatif::ProgressBar>) {
        self.world.resource_mut::<RenderControl>().progress = bar;
    }

    /// The flag that cancels the pass in flight (shared with a watcher thread).
    pub fn cancel_flag(&self) -> Arc<AtomicBool> {
        self.world.resource::<RenderControl>().cancel.clone()
    }

    /// Loads the scene at `path` (textures through the cache), applies the overrides and queues
    /// it for the next frame. Returns what was loaded.
    pub fn load(&mut self, path: &Path) -> Result<LoadInfo, SceneError> {
        self.assets.begin_load();
        // The cache counts from its creation; the load's own work is what it adds.
        let (decodes, environments, bytes) = (
            self.assets.decodes(),
            self.assets.environment_builds(),
            self.assets.bytes_read(),
        );
        let mut scene = load_scene(path, &mut self.assets)?;
        self.overrides
            .apply(&mut scene.settings)
            .map_err(|m| SceneError::at(path, None, m))?;
        let info = LoadInfo {
            dependencies: scene.dependencies.clone(),
            settings: scene.settings.clone(),
            warnings: scene.warnings.clone(),
            assets: AssetWork {
                textures_decoded: self.assets.decodes().saturating_sub(decodes),
                environments_built: self
                    .assets
                    .environment_builds()
                    .saturating_sub(environments),
                bytes_read: self.assets.bytes_read().saturating_sub(bytes),
            },
        };
        if self.keep_provenance {
            self.provenance = Some(Arc::new(Provenance::of(&scene)));
        }
        self.submit(scene);
        Ok(info)
    }

    /// Makes the asset cache trust files for which no change is reported through
    /// [`Renderer::invalidate`] and whose metadata is unchanged, instead of reading every file at
    /// every load (see [`AssetCache::set_reported_changes`]). For a caller that watches them.
    pub fn set_reported_changes(&mut self, on: bool) {
        self.assets.set_reported_changes(on);
    }

    /// Reports files or directories that may have changed since the last load: their assets
    /// are read again at the next (see [`AssetCache::invalidate`]).
    pub fn invalidate(&mut self, changed: &[std::path::PathBuf]) {
        self.assets.invalidate(changed);
    }

    /// Reports that any file may have changed: the next load reads every asset again.
    pub fn invalidate_all(&mut self) {
        self.assets.invalidate_all();
    }

    /// Bytes of asset files read by the asset cache.
    pub fn asset_bytes_read(&self) -> u64 {
        self.assets.bytes_read()
    }

    /// Queues an already loaded scene for the next frame.
    pub fn submit(&mut self, scene: LoadedScene) {
        self.world.resource_mut::<PendingScene>().0 = Some(scene);
    }

    /// Runs the schedule once: applies a pending scene, rebuilds what changed, renders one pass
    /// and writes the image if due. Returns what the systems did.
    pub fn run_once(&mut self) -> FrameLog {
        let Self {
            world,
            schedule,
            pool,
            ..
        } = self;
        *world.resource_mut::<FrameLog>() = FrameLog::default();
        pool.install(|| schedule.run(world));
        world.resource::<FrameLog>().clone()
    }

    /// Runs frames until the film holds every sample. Returns the wall time of the render.
    pub fn render_to_completion(&mut self) -> Duration {
        let start = Instant::now();
        self.run_once();
        while !self.is_complete() {
            self.run_once();
        }
        start.elapsed()
    }

    /// Whether the film holds every sample of the current scene.
    pub fn is_complete(&self) -> bool {
        self.world.resource::<Accumulation>().complete
    }

    /// The accumulated film.
    pub fn film(&self) -> &Film {
        &self.world.resource::<Accumulation>().film
    }

    /// The accumulated film, to add to it or to take it.
    pub fn film_mut(&mut self) -> &mut Film {
        &mut self.world.resource_mut::<Accumulation>().into_inner().film
    }

    /// Makes the next render hold samples `first..spp` of every pixel instead of `0..spp`
    /// (a render of a sample range, see [`crate::farm`]). Call after loading.
    pub fn set_first_sample(&mut self, first: u32) {
        self.world.resource_mut::<Accumulation>().first_sample = first;
    }

    /// Trace counters of the current render.
    pub fn stats(&self) -> TraceStats {
        self.world.resource::<Accumulation>().stats
    }

    /// Work counters since creation.
    pub fn counters(&self) -> Counters {
        *self.world.resource::<Counters>()
    }

    /// Step durations.
    pub fn timings(&self) -> Timings {
        *self.world.resource::<Timings>()
    }

    /// What the last applied scene changed.
    pub fn change_summary(&self) -> ChangeSummary {
        self.world.resource::<ChangeSummary>().clone()
    }

    /// The current settings.
    pub fn settings(&self) -> SettingsDesc {
        self.world.resource::<RenderSettings>().0.clone()
    }

    /// The output status (images written, last write error).
    pub fn output(&self) -> &Output {
        self.world.resource::<Output>()
    }

    /// Number of primitives in the packed geometry.
    pub fn primitive_count(&self) -> usize {
        self.world
            .resource::<PackedGeometry>()
            .geometry
            .primitive_count()
    }

    /// Every texture, mesh and prefab path the last [`Renderer::load`] asked for, found or not:
    /// after a failed load, the files that may fix it.
    pub fn requested(&self) -> Vec<std::path::PathBuf> {
        self.assets.requested().to_vec()
    }

    /// Whether the film holds the reduced-resolution preview rather than real samples (its
    /// sample count is then 1 but its pixels are blocks).
    pub fn film_is_preview(&self) -> bool {
        self.world.resource::<Accumulation>().preview == Preview::InFilm
    }

    /// Number of mesh file loads by the asset cache.
    pub fn mesh_loads(&self) -> u64 {
        self.assets.mesh_loads()
    }

    /// Number of environment maps decoded and given their distribution by the asset cache.
    pub fn environment_builds(&self) -> u64 {
        self.assets.environment_builds()
    }

    /// Makes every later [`Renderer::load`] keep where the scene's entities come from (names,
    /// materials, placements; a clone of the names, linear in the scene), for picking.
    pub fn keep_provenance(&mut self, on: bool) {
        self.keep_provenance = on;
        if !on {
            self.provenance = None;
        }
    }

    /// Where the entities of the last scene loaded come from, if kept
    /// ([`Renderer::keep_provenance`]): indexed like the ids of [`Renderer::pick_ids`] once that
    /// scene is applied (by the next [`Renderer::run_once`]).
    pub fn provenance(&self) -> Option<Arc<Provenance>> {
        self.provenance.clone()
    }

    /// The id buffer of the scene and camera in the world ([`pick_ids`]): one central ray per
    /// pixel, traced on the renderer's threads.
    pub fn pick_ids(&self) -> IdBuffer {
        self.pool.install(|| pick_ids(&self.world))
    }

    /// The world as it is seen through `camera` at `size` with samples `0..spp`
    /// ([`render_camera`]), traced on the renderer's threads; the accumulated film is not
    /// touched. `None` before the first frame.
    pub fn render_camera(
        &self,
        camera: &CameraDesc,
        size: (u32, u32),
        spp: u32,
        cancel: &AtomicBool,
    ) -> Option<Result<Film, crate::render::Cancelled>> {
        self.pool
            .install(|| render_camera(&self.world, camera, size, spp, cancel))
    }

    /// The version of the scene in the world: it changes with every applied change.
    pub fn scene_version(&self) -> u64 {
        self.world.resource::<SceneVersion>().0
    }

    /// Number of image decodes by the asset cache.
    pub fn texture_decodes(&self) -> u64 {
        self.assets.decodes()
    }
}
