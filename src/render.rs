//! The path tracer: traces camera paths through packed geometry into a [`Film`]. No ECS here.

use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::camera::Camera;
use crate::film::Film;
use crate::geometry::packed::Geometry;
use crate::geometry::ray::{Ray, offset_ray_origin};
use crate::shading::material::Material;
use crate::shading::rng::Rng;

/// Rows per parallel work item. Small enough to balance two cores and to cancel promptly.
const BAND_ROWS: usize = 4;

/// Everything a render reads: a snapshot of the scene, independent of the ECS.
#[derive(Clone, Copy)]
pub struct SceneView<'a> {
    /// Packed geometry and its BVHs.
    pub geometry: &'a Geometry,
    /// Material table.
    pub materials: &'a [Material],
    /// Material index of every owner slot.
    pub owner_material: &'a [u32],
    /// The camera.
    pub camera: &'a Camera,
    /// Radiance of rays that leave the scene.
    pub background: Vec3,
    /// Rays per path, camera ray included.
    pub max_depth: u32,
}

/// Counters of one render.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraceStats {
    /// Rays traced (camera and scattered).
    pub rays: u64,
    /// Samples whose radiance was NaN or infinite; they are dropped, never written.
    pub nonfinite: u64,
}

impl std::ops::Add for TraceStats {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self {
            rays: self.rays + o.rays,
            nonfinite: self.nonfinite + o.nonfinite,
        }
    }
}

/// The render was cancelled before it finished; the film holds a partial pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cancelled;

/// Radiance arriving along `ray`, by unidirectional path tracing with BSDF sampling (the thesis's
/// algorithm): emission counts when a path hits an emitter.
pub fn trace_path(view: &SceneView, mut ray: Ray, rng: &mut Rng, stats: &mut TraceStats) -> Vec3 {
    let mut radiance = Vec3::ZERO;
    let mut throughput = Vec3::ONE;
    for depth in 0..view.max_depth {
        stats.rays += 1;
        let Some(hit) = view.geometry.intersect(&ray, f32::INFINITY) else {
            radiance += throughput * view.background;
            break;
        };
        let s = view.geometry.surface(&ray, &hit);
        let material = &view.materials[view.owner_material[s.owner as usize] as usize];
        radiance += throughput * material.emitted(ray.direction, s.n, s.uv);
        if depth + 1 == view.max_depth {
            break;
        }
        let Some(scatter) = material.scatter(ray.direction, s.n, s.uv, rng) else {
            break;
        };
        throughput *= scatter.attenuation;
        if throughput == Vec3::ZERO {
            break;
        }
        let side = if scatter.direction.dot(s.n) > 0.0 {
            s.n
        } else {
            -s.n
        };
        ray = Ray::new(offset_ray_origin(s.p, side), scatter.direction);
    }
    radiance
}

/// Adds samples `samples` of every pixel to `film`, in parallel over bands of rows.
///
/// Each sample draws from its own generator seeded by (seed, pixel, sample index) and is added
/// to its pixel's sum in sample order, so the film is bit-identical whatever the thread count
/// and however the samples are split into passes. `progress(rows)` is called as bands finish.
/// If `cancel` becomes true, remaining bands are skipped and `Err(Cancelled)` is returned.
pub fn render_pass(
    view: &SceneView,
    film: &mut Film,
    seed: u64,
    samples: Range<u32>,
    cancel: &AtomicBool,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<TraceStats, Cancelled> {
    let (width, height) = (film.width, film.height);
    let stats = film
        .sum
        .par_chunks_mut(width as usize * BAND_ROWS)
        .enumerate()
        .map(|(band, pixels)| {
            let mut stats = TraceStats::default();
            if cancel.load(Ordering::Relaxed) {
                return stats;
            }
            let first = band * BAND_ROWS * width as usize;
            for (offset, sum) in pixels.iter_mut().enumerate() {
                let index = first + offset;
                let (x, y) = (
                    (index % width as usize) as f32,
                    (index / width as usize) as f32,
                );
                for sample in samples.clone() {
                    let mut rng = Rng::for_sample(seed, index as u64, u64::from(sample));
                    let (jx, jy) = (rng.next_f32(), rng.next_f32());
                    let ray = view.camera.ray(x + jx, y + jy, width, height);
                    let l = trace_path(view, ray, &mut rng, &mut stats);
                    if l.is_finite() {
                        *sum += l.as_dvec3();
                    } else {
                        stats.nonfinite += 1;
                    }
                }
            }
            progress((pixels.len() / width as usize) as u64);
            stats
        })
        .reduce(TraceStats::default, |a, b| a + b);
    if cancel.load(Ordering::Relaxed) {
        return Err(Cancelled);
    }
    film.samples = samples.end;
    Ok(stats)
}

/// Mean of a film's pixels, a convenience for tests and reports.
pub fn film_mean(film: &Film) -> DVec3 {
    let n = f64::from(film.samples.max(1)) * film.sum.len().max(1) as f64;
    film.sum.iter().copied().sum::<DVec3>() / n
}
