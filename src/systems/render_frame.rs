//! Traces the next pass of samples into the accumulation film.

use std::sync::atomic::Ordering;
use std::time::Instant;

use bevy_ecs::prelude::*;

use glam::Vec3;

use crate::ecs::frame_log::{FrameLog, PassWork};
use crate::ecs::resources::{
    Accumulation, ActiveCamera, Counters, OwnerMaterials, PackedGeometry, PassPlan, Preview,
    RenderControl, RenderSettings, SceneVersion, Timings,
};
use crate::film::shift_for;
use crate::geometry::layout::{Aos, Hybrid, Layout, LayoutKind, Soa, SoaSimd};
use crate::geometry::packed::{Geometry, LayoutCache};
use crate::render::camera::Camera;
use crate::render::{Method, SceneView, has_masks, render_pass, render_preview};
use crate::scene::format::{self, CameraDesc, SettingsDesc};
use crate::shading::material::Material;

/// Paths a live preview traces at most, unless the smallest block gives more: about 9 ms on the
/// Cornell box with 2 threads (1.87 M samples/s), so the first image of a 512² edit comes within
/// ~20 ms of the save instead of the ~45 ms of a 2×2-block preview.
pub const PREVIEW_PATHS: u64 = 1 << 14;

/// The block size of the preview of a `width` × `height` image: `smallest`, or larger (a power of
/// two) until the preview traces at most [`PREVIEW_PATHS`] paths. 2 up to 256², 4 up to 512²,
/// 8 up to 1024².
pub fn preview_block(smallest: u32, width: u32, height: u32) -> u32 {
    let pixels = u64::from(width) * u64::from(height);
    let mut block = smallest.max(1);
    while block > 1 && block < 256 && pixels.div_ceil(u64::from(block * block)) > PREVIEW_PATHS {
        block *= 2;
    }
    block
}

// The kernels lay out the sampler's dimensions for paths as deep as the format accepts.
const _: () = assert!(crate::render::MAX_DEPTH == format::MAX_DEPTH);

/// The kernels' light-transport method for the scene file's.
pub fn method(m: format::Method) -> Method {
    match m {
        format::Method::Naive => Method::Naive,
        format::Method::Nee => Method::Nee,
        format::Method::Mis => Method::Mis,
        format::Method::Caustics => Method::Caustics,
        format::Method::Photons => Method::Photons,
    }
}

/// The kernels' view of the scene in the world: `geometry` (in any layout) seen through
/// `camera`, with the world's materials and lights and the settings `s`.
pub fn scene_view<'a, L: Layout>(
    geometry: &'a Geometry<L>,
    materials: &'a OwnerMaterials,
    camera: &'a Camera,
    s: &SettingsDesc,
    roulette: bool,
) -> SceneView<'a, L> {
    SceneView {
        geometry,
        materials: &materials.materials,
        owner_material: &materials.owner_material,
        lights: &materials.lights,
        camera,
        background: s.background,
        max_depth: s.max_depth,
        method: method(s.method),
        roulette,
        sampler: s.sampler,
        masked: has_masks(&materials.materials),
        photons: None,
    }
}

/// The film shift ([`film_shift`]) of the scene in the world: from its brightest material, sky,
/// punctual light or `background`.
pub fn scene_film_shift(materials: &OwnerMaterials, background: Vec3) -> i32 {
    film_shift(
        &materials.materials,
        background
            .max(Vec3::splat(materials.lights.sky_max_radiance()))
            .max(Vec3::splat(materials.lights.punctual_max_intensity())),
    )
}

/// The camera a description places.
pub fn camera_of(c: &CameraDesc) -> Camera {
    Camera::new(c.position, c.direction, c.up, c.fov).with_lens(c.aperture, c.focus_distance)
}

/// The fixed-point shift of a scene's film: from its brightest radiance, emitted by any material
/// of the table or arriving from the background (used or not, so it depends on the files alone).
pub fn film_shift(materials: &[Material], background: Vec3) -> i32 {
    let emitted = materials
        .iter()
        .map(Material::max_emission)
        .fold(0.0, f32::max);
    shift_for(emitted.max(background.abs().max_element()))
}

/// Renders one pass. A new scene version resets the film first. The samples of the pass follow
/// the [`PassPlan`]; a cancelled pass leaves the film incomplete and is redone on the next run.
#[expect(
    clippy::too_many_arguments,
    reason = "reads the whole render-side snapshot"
)]
pub fn render_frame(
    packed: Res<PackedGeometry>,
    materials: Res<OwnerMaterials>,
    camera: Res<ActiveCamera>,
    mut built: Local<Option<Camera>>,
    settings: Res<RenderSettings>,
    version: Res<SceneVersion>,
    control: Res<RenderControl>,
    mut acc: ResMut<Accumulation>,
    mut counters: ResMut<Counters>,
    mut timings: ResMut<Timings>,
    mut relaid: Local<LayoutCache>,
    mut log: ResMut<FrameLog>,
) {
    let s = &settings.0;
    if version.is_changed() || acc.film.width != s.width || acc.film.height != s.height {
        acc.reset(
            s.width,
            s.height,
            scene_film_shift(&materials, s.background),
        );
        acc.preview = Preview::Due;
        timings.render = Default::default();
    }
    if acc.complete || version.0 == 0 {
        return;
    }
    let block = match control.plan {
        PassPlan::Progressive { .. } => preview_block(control.preview_block, s.width, s.height),
        PassPlan::Single => 1,
    };
    if acc.preview == Preview::Due && block <= 1 {
        acc.preview = Preview::Done;
    }
    if acc.preview == Preview::InFilm {
        // The preview was shown; the converging image starts from zero.
        let shift = acc.film.shift;
        acc.reset(s.width, s.height, shift);
        acc.preview = Preview::Done;
    }
    let preview = acc.preview == Preview::Due;
    if packed.provisional && !preview {
        // A refitted tree is for previews only: the build comes first (see
        // `rebuild_geometry`).
        return;
    }
    let done = acc.film.samples;
    let end = match control.plan {
        PassPlan::Single => s.spp,
        PassPlan::Progressive { first } if done == 0 => first.min(s.spp),
        PassPlan::Progressive { .. } => (2 * done).min(s.spp),
    };
    // Built once per edit of the camera, not per pass.
    if camera.is_changed() {
        *built = None;
    }
    let cam = *built.get_or_insert_with(|| camera_of(&camera.0));
    let start = Instant::now();
    let progress = |rows: u64| {
        if let Some(bar) = &control.progress {
            bar.inc(rows);
        }
    };
    let acc = &mut *acc;
    // The layout is matched once per pass: `render_pass` and everything below it is
    // monomorphised per layout, so no ray pays for the choice. A layout other than the default
    // renders a copy kept in `relaid` until the geometry is rebuilt.
    let builds = counters.bvh_builds + counters.bvh_refits;
    macro_rules! pass {
        ($layout:ty) => {{
            let geometry = relaid.get::<$layout>(&packed.geometry, builds);
            let view = scene_view(geometry, &materials, &cam, s, control.roulette);
            if preview {
                render_preview(
                    &view,
                    &mut acc.film,
                    s.seed,
                    block as usize,
                    &control.cancel,
                )
            } else {
                render_pass(
                    &view,
                    &mut acc.film,
                    s.seed,
                    done..end,
                    &control.cancel,
                    &progress,
                )
            }
        }};
    }
    let result = match control.layout {
        LayoutKind::Soa => pass!(Soa),
        LayoutKind::Aos => pass!(Aos),
        LayoutKind::SoaSimd => pass!(SoaSimd),
        LayoutKind::Hybrid => pass!(Hybrid),
    };
    let elapsed = start.elapsed();
    timings.pass = elapsed;
    match result {
        Ok(_) if preview => {
            timings.render += elapsed;
            acc.preview = Preview::InFilm;
            counters.passes += 1;
            log.pass = Some(PassWork {
                samples: acc.film.samples,
                preview: true,
                took: elapsed,
            });
        }
        Ok(stats) => {
            timings.render += elapsed;
            acc.stats = acc.stats + stats;
            acc.complete = end == s.spp;
            counters.passes += 1;
            log.pass = Some(PassWork {
                samples: acc.film.samples,
                preview: false,
                took: elapsed,
            });
        }
        Err(_) => {
            // Restart cleanly: the partial pass added samples to some rows only.
            control.cancel.store(false, Ordering::Relaxed);
            let shift = acc.film.shift;
            acc.reset(s.width, s.height, shift);
            if acc.preview == Preview::InFilm {
                acc.preview = Preview::Done;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn preview_blocks_grow_with_the_image_and_never_start_a_preview() {
        assert_eq!(
            preview_block(1, 4096, 4096),
            1,
            "no preview stays no preview"
        );
        assert_eq!(preview_block(2, 32, 32), 2);
        assert_eq!(preview_block(2, 256, 256), 2);
        assert_eq!(preview_block(2, 512, 512), 4);
        assert_eq!(preview_block(2, 1024, 1024), 8);
        assert_eq!(preview_block(2, 1000, 700), 8);
    }
}
