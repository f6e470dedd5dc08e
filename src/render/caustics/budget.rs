//! How many light paths a pass traces: as many as the caustics' share of the image is worth.
//! No ECS here.
//!
//! The image's error is the camera paths' plus the light paths', which falls as `1/N` with
//! their number `N` while their cost grows with it; the best `N` per pixel grows as the square
//! root of the light paths' share of the variance (BENCHMARKS.md, "How many light paths": near
//! one path per 8–12 pixels on the sunlit scenes, where the caustics are a few per cent of the
//! image). That share is estimated by the caustics' share of the image's light, from a pilot
//! that depends on the scene, the seed and the image size only: [`PILOT`] light paths give
//! the caustics' part of the image's sum, as many camera samples at pixels drawn uniformly give
//! the rest (the path tracer's part, which leaves out what the light paths take). Every pass of
//! a render, and every partial of a split one, draws the same pilot, so they trace the same
//! number of paths per sample and stay bit-exact. A scene whose caustics hardly reach the
//! camera pays for [`MIN_PATHS_PER_PIXEL`] (about 0.5 % of a `mis` sample's time), one whose
//! caustics make [`FULL_SHARE`] of the image or more for [`MAX_PATHS_PER_PIXEL`].

use glam::Vec3;
use rayon::prelude::*;

use super::emit::Sources;
use super::light_path;
use crate::cpu::Sse;
use crate::geometry::layout::Layout;
use crate::render::integrator::trace_path;
use crate::render::{SceneView, TraceStats};
use crate::shading::rng::Rng;
use crate::shading::sampler::Sampler;
use crate::sky::environment::luminance;

/// Light paths and camera samples of the pilot (fewer on an image of fewer pixels).
pub(super) const PILOT: u64 = 1024;

/// Light paths per pixel and sample when the caustics make [`FULL_SHARE`] of the image's light
/// or more: the optimum measured on `envmap.ron` and `sun_caustics.ron`.
pub(super) const MAX_PATHS_PER_PIXEL: f64 = 0.125;

/// Light paths per pixel and sample when the pilot finds no caustic at all: few enough to cost
/// nothing, enough that a caustic the pilot missed still converges.
pub(super) const MIN_PATHS_PER_PIXEL: f64 = 1.0 / 256.0;

/// Share of the image's light from the light paths at and above which a pass traces
/// [`MAX_PATHS_PER_PIXEL`].
pub(super) const FULL_SHARE: f64 = 0.01;

/// Mixed into the seed of the pilot's paths, so they are none of a pass's.
const PILOT_SEED: u64 = 0x7069_6c6f_7420_7061;

/// The light paths per sample of an image of `size` (see the module's notes), with the
/// pilot's work added to `stats`.
pub(super) fn light_paths<L: Layout>(
    view: &SceneView<L>,
    sources: &Sources,
    size: (u32, u32),
    seed: u64,
    stats: &mut TraceStats,
) -> u64 {
    let pixels = u64::from(size.0) * u64::from(size.1);
    let share = caustic_share(view, sources, size, seed ^ PILOT_SEED, stats);
    paths_for_share(share, pixels)
}

/// The most light paths per sample an image of `size` traces: [`MAX_PATHS_PER_PIXEL`].
pub(super) fn most_paths(size: (u32, u32)) -> u64 {
    paths_for_share(1.0, u64::from(size.0) * u64::from(size.1))
}

/// Light paths per sample over `pixels` for a caustic share `share` of the image's light.
pub(super) fn paths_for_share(share: f64, pixels: u64) -> u64 {
    let per_pixel = (MAX_PATHS_PER_PIXEL * (share / FULL_SHARE).sqrt())
        .clamp(MIN_PATHS_PER_PIXEL, MAX_PATHS_PER_PIXEL);
    (pixels as f64 * per_pixel).ceil().max(1.0) as u64
}

/// The pilot's estimate of the light paths' share of the image's summed luminance, in [0, 1].
fn caustic_share<L: Layout>(
    view: &SceneView<L>,
    sources: &Sources,
    size: (u32, u32),
    seed: u64,
    stats: &mut TraceStats,
) -> f64 {
    let pixels = u64::from(size.0) * u64::from(size.1);
    let n = PILOT.min(pixels).max(1);
    // Per pilot index: the light path's splat and the camera sample, each as luminance. The
    // sums are taken in index order, so the estimate is the same on any number of threads.
    let drawn: Vec<(f64, f64, TraceStats)> = (0..n)
        .into_par_iter()
        .map(|k| {
            let mut stats = TraceStats::default();
            let mut rng = Rng::for_sample(seed, k, 0);
            let splat = light_path(Sse, (view, sources, size), &mut rng, &mut stats, None)
                .map_or(0.0, |(_, l)| f64::from(luminance(l)));
            let mut rng = Rng::for_sample(seed, k, 1);
            let u = rng.next_2d();
            let v = rng.next_2d();
            let x = (u.x * size.0 as f32).min(size.0 as f32 - 1.0).floor() + v.x;
            let y = (u.y * size.1 as f32).min(size.1 as f32 - 1.0).floor() + v.y;
            let ray = view.camera.ray(x, y, size.0, size.1);
            let l = trace_path(view, ray, &mut rng, &mut stats);
            let camera = if l.is_finite() {
                f64::from(luminance(l.max(Vec3::ZERO)))
            } else {
                0.0
            };
            (splat, camera, stats)
        })
        .collect();
    let (mut caustic, mut rest) = (0.0, 0.0);
    for (splat, camera, s) in drawn {
        caustic += splat;
        rest += camera;
        *stats = *stats + s;
    }
    // Both as the image's sum per sample: the splats' mean is the caustics' part of it, the
    // camera samples' mean is a pixel's mean of the rest.
    let caustic = caustic / n as f64;
    let rest = rest / n as f64 * pixels as f64;
    let total = caustic + rest;
    if total > 0.0 && total.is_finite() {
        (caustic / total).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_count_follows_the_square_root_of_the_share_between_its_bounds() {
        let pixels = 1 << 16;
        let at = |share: f64| paths_for_share(share, pixels) as f64 / pixels as f64;
        assert_eq!(at(0.0), MIN_PATHS_PER_PIXEL);
        assert_eq!(at(FULL_SHARE), MAX_PATHS_PER_PIXEL);
        assert_eq!(at(1.0), MAX_PATHS_PER_PIXEL);
        assert!((at(FULL_SHARE / 4.0) - MAX_PATHS_PER_PIXEL / 2.0).abs() < 1e-4);
        assert_eq!(paths_for_share(0.0, 1), 1);
    }
}
