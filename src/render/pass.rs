//! Passes: samples of every pixel traced in parallel bands of rows into a [`Film`], and the
//! quick preview of live editing. No ECS here.

use std::marker::PhantomData;
use std::ops::Range;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use rayon::prelude::*;

use super::camera::Camera;
use super::caustics::LightTracing;
use super::caustics::photons::PhotonMap;
use super::integrator::trace_path_with;
use super::{Cancelled, LENS_DIMENSION, Method, SceneView, TraceStats};
use crate::cpu::{Isa, Kernel, Lanes, Sse};
use crate::film::{Film, FilmBand, FixedPoint, Pixel};
use crate::geometry::layout::Layout;
use crate::geometry::layout::LayoutKind;
use crate::geometry::ray::Ray;
use crate::shading::rng::Rng;
use crate::shading::sampler::{IndependentPixel, PixelSampler, Sampler, SamplerKind, SobolPixel};

/// Rows per parallel work item. Small enough to balance two cores and to cancel promptly.
const BAND_ROWS: usize = 4;

/// Adds samples `samples` of every pixel to `film`, in parallel over bands of rows.
///
/// Each sample draws from its own generator (the view's [`SamplerKind`]) seeded by (seed,
/// pixel, sample index) and is added to its pixel's sum in sample order, so the film is
/// bit-identical whatever the thread count and however the samples are split into passes.
/// Under `Method::Caustics` the light paths of the same sample indices are then traced and
/// splatted ([`LightTracing`]), as exactly; under `Method::Photons` in groups of samples, each
/// group's light paths first, leaving the photons its camera paths gather (a map per sample).
/// `progress(rows)` is called as bands finish. If `cancel` becomes true, remaining bands are
/// skipped and `Err(Cancelled)` is returned.
pub fn render_pass<L: Layout>(
    view: &SceneView<L>,
    film: &mut Film,
    seed: u64,
    samples: Range<u32>,
    cancel: &AtomicBool,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<TraceStats, Cancelled> {
    // Matched once per pass, like the layout: each sampler gets its own copy of the loop.
    match view.sampler {
        SamplerKind::Independent => {
            render_pass_with::<L, IndependentPixel>(view, film, seed, samples, cancel, progress)
        }
        SamplerKind::Sobol => {
            render_pass_with::<L, SobolPixel>(view, film, seed, samples, cancel, progress)
        }
    }
}

fn render_pass_with<L: Layout, S: PixelSampler>(
    view: &SceneView<L>,
    film: &mut Film,
    seed: u64,
    samples: Range<u32>,
    cancel: &AtomicBool,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<TraceStats, Cancelled> {
    let mut stats = TraceStats::default();
    let light = LightTracing::new(view, (film.width, film.height), seed, &mut stats);
    match &light {
        Some(light) if view.method == Method::Photons => {
            // Samples in groups: their light paths leave the photons their camera paths
            // gather, a map per sample. Progress is each band's rows over the groups, summed
            // exactly.
            let group = light.samples_per_group();
            let groups = u64::from(samples.end.saturating_sub(samples.start))
                .div_ceil(u64::from(group))
                .max(1);
            let rows_done = AtomicU64::new(0);
            let share = |rows: u64| {
                let before = rows_done.fetch_add(rows, Ordering::Relaxed);
                progress((before + rows) / groups - before / groups);
            };
            for start in samples.clone().step_by(group as usize) {
                let part = start..(start + group).min(samples.end);
                let (traced, photons) =
                    light.trace(view, film, (seed, part.clone()), true, cancel)?;
                let maps: Vec<PhotonMap> = part
                    .clone()
                    .into_par_iter()
                    .zip(photons)
                    .map(|(sample, photons)| light.photon_map(photons, sample))
                    .collect();
                let gather = Some(Gather {
                    first: start,
                    maps: &maps,
                });
                let camera = camera_pass::<L, S>(view, gather, film, seed, part, cancel, &share)?;
                stats = stats + traced + camera;
            }
        }
        _ => {
            let all = samples.clone();
            stats = stats + camera_pass::<L, S>(view, None, film, seed, all, cancel, progress)?;
            if let Some(light) = &light {
                let (traced, _) =
                    light.trace(view, film, (seed, samples.clone()), false, cancel)?;
                stats = stats + traced;
            }
        }
    }
    film.samples = samples.end;
    if let Some(slot) = LayoutKind::ALL.iter().position(|&k| k == L::KIND) {
        stats.layout_passes[slot] += 1;
    }
    Ok(stats)
}

/// The photon maps of samples `first..`, one per sample, for `Method::Photons`.
#[derive(Clone, Copy)]
struct Gather<'a> {
    first: u32,
    maps: &'a [PhotonMap],
}

/// The camera paths of samples `samples` of every pixel, added to `film` in parallel bands;
/// with `gather`, each sample gathers from its photon map.
fn camera_pass<L: Layout, S: PixelSampler>(
    view: &SceneView<L>,
    gather: Option<Gather>,
    film: &mut Film,
    seed: u64,
    samples: Range<u32>,
    cancel: &AtomicBool,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<TraceStats, Cancelled> {
    let (width, height) = (film.width, film.height);
    let isa = Isa::selected();
    let fixed = film.fixed();
    let stats = film
        .bands(BAND_ROWS)
        .into_par_iter()
        .enumerate()
        .map(|(band, pixels)| {
            if cancel.load(Ordering::Relaxed) {
                return TraceStats::default();
            }
            let first = band * BAND_ROWS * width as usize;
            let rows = (pixels.sum.len() / width as usize) as u64;
            let stats = isa.run(Band::<L, S> {
                view,
                gather,
                pixels,
                first,
                size: (width, height),
                seed,
                samples: samples.clone(),
                fixed,
                sampler: PhantomData,
            });
            progress(rows);
            stats
        })
        .reduce(TraceStats::default, |a, b| a + b);
    if cancel.load(Ordering::Relaxed) {
        return Err(Cancelled);
    }
    Ok(stats)
}

/// The camera ray of one sample of pixel `(x, y)` of an image of `size`: the position in the
/// pixel from dimension 0, and for a camera with a lens the position on it from
/// [`LENS_DIMENSION`] (a pinhole draws nothing more).
#[inline(always)]
fn camera_ray(
    camera: &Camera,
    x: f32,
    y: f32,
    size: (u32, u32),
    sampler: &mut impl Sampler,
) -> Ray {
    let j = sampler.next_2d();
    let (fx, fy) = (x + j.x, y + j.y);
    if camera.has_lens() {
        sampler.seek(LENS_DIMENSION);
        let u = sampler.next_2d();
        camera.lens_ray(fx, fy, size.0, size.1, u)
    } else {
        camera.ray(fx, fy, size.0, size.1)
    }
}

/// Samples `samples` of the pixels of one band, whose first pixel has index `first`, added to
/// their sums: the work of a pass that [`Isa::run`] compiles once per instruction set.
struct Band<'a, L: Layout, S> {
    view: &'a SceneView<'a, L>,
    gather: Option<Gather<'a>>,
    pixels: FilmBand<'a>,
    first: usize,
    size: (u32, u32),
    seed: u64,
    samples: Range<u32>,
    fixed: FixedPoint,
    sampler: PhantomData<S>,
}

impl<L: Layout, S: PixelSampler> Kernel for Band<'_, L, S> {
    type Output = TraceStats;

    #[inline(always)]
    fn run<W: Lanes>(mut self, lanes: W) -> TraceStats {
        let width = self.size.0;
        let mut stats = TraceStats::default();
        let collect = self.pixels.features.is_some();
        for offset in 0..self.pixels.sum.len() {
            let index = self.first + offset;
            let (x, y) = (
                (index % width as usize) as f32,
                (index / width as usize) as f32,
            );
            let mut pixel = S::for_pixel(self.seed, index as u64);
            for sample in self.samples.clone() {
                let mut sampler = pixel.start_sample(sample);
                let ray = camera_ray(self.view.camera, x, y, self.size, &mut sampler);
                let gathering;
                let view = match self.gather {
                    Some(g) => {
                        let map = g.maps.get(sample.wrapping_sub(g.first) as usize);
                        gathering = SceneView {
                            photons: map,
                            ..*self.view
                        };
                        &gathering
                    }
                    None => self.view,
                };
                let (l, features) =
                    trace_path_with(lanes, view, ray, &mut sampler, &mut stats, collect);
                match self.pixels.add(offset, l, &features, self.fixed) {
                    None => stats.nonfinite += 1,
                    Some(clamped) => stats.clamped += u64::from(clamped),
                }
            }
        }
        stats
    }
}

/// A quick preview for live editing: one sample per `block`×`block` block of pixels, written to
/// every pixel of the block (so it costs 1/`block`² of a 1-spp pass). The film then holds one
/// "sample" per pixel that is *not* part of the converging image: the caller discards it before
/// the real passes. Cancellation works as in [`render_pass`].
pub fn render_preview<L: Layout>(
    view: &SceneView<L>,
    film: &mut Film,
    seed: u64,
    block: usize,
    cancel: &AtomicBool,
) -> Result<TraceStats, Cancelled> {
    // The preview traces no light paths: its paths keep what light tracing would add.
    let view = &SceneView {
        method: view.method.path_traced(),
        ..*view
    };
    let (width, height) = (film.width as usize, film.height as usize);
    let block = block.max(1);
    let fixed = film.fixed();
    let stats = film
        .bands(block)
        .into_par_iter()
        .enumerate()
        .map(|(band, mut rows)| {
            let mut stats = TraceStats::default();
            if cancel.load(Ordering::Relaxed) {
                return stats;
            }
            let collect = rows.features.is_some();
            let lines = rows.sum.len() / width;
            let cy = band * block + lines / 2;
            for bx in (0..width).step_by(block) {
                let cols = block.min(width - bx);
                let cx = bx + cols / 2;
                let mut rng = Rng::for_sample(seed, (cy * width + cx) as u64, 0);
                let size = (width as u32, height as u32);
                let ray = camera_ray(view.camera, cx as f32, cy as f32, size, &mut rng);
                let (l, features) = trace_path_with(Sse, view, ray, &mut rng, &mut stats, collect);
                // The block's centre pixel gets the sample; the rest of the block copies it.
                let centre = (lines / 2) * width + cx;
                match rows.add(centre, l, &features, fixed) {
                    None => stats.nonfinite += 1,
                    Some(clamped) => stats.clamped += u64::from(clamped),
                }
                fill_block(rows.sum, centre, width, bx..bx + cols, lines);
                if let Some((albedo, normal)) = &mut rows.features {
                    fill_block(albedo, centre, width, bx..bx + cols, lines);
                    fill_block(normal, centre, width, bx..bx + cols, lines);
                }
            }
            stats
        })
        .reduce(TraceStats::default, |a, b| a + b);
    if cancel.load(Ordering::Relaxed) {
        return Err(Cancelled);
    }
    film.samples = 1;
    Ok(stats)
}

/// Copies pixel `from` of a band of `lines` rows of `width` pixels to the columns `cols` of
/// every row.
fn fill_block(rows: &mut [Pixel], from: usize, width: usize, cols: Range<usize>, lines: usize) {
    let value = rows[from];
    for line in 0..lines {
        rows[line * width + cols.start..line * width + cols.end].fill(value);
    }
}
