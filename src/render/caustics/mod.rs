//! Light tracing for caustics (`Method::Caustics`). No ECS here.
//!
//! Path space is split between two estimators, without weights: light tracing takes exactly
//! the paths light → S… → D → camera, where each S (at least one, at most `max_depth − 2`) is a
//! perfect mirror or smooth glass of a finite shape (the integrator's `is_chain_vertex`) and D, the camera's
//! first hit, is anything else; the path tracer (`Mis`) takes every other path, and drops these
//! ones: after the camera's first hit continued by its non-delta part, emission reached through
//! perfect specular vertices only (from a finite emitter or a distant light) is not counted
//! (see [`super::integrator`]). Both sides decide by the same tests, so their sum converges to
//! what `Mis` converges to, with the caustics sampled from the light, where they are easy.
//! At a mix (`Material::Transmissive`) both sides pick the component with the same
//! probabilities at the hit point (its transmission texture read there) and test the one
//! picked, so they split the same path space.
//!
//! A light path starts at a light aimed at the specular surfaces ([`emit`]), follows the
//! specular vertices by their BSDF sampling (the (n1/n2)² compression of radiance at
//! refractions left out: light paths carry flux, pbrt-v4's `TransportMode::Importance`), and at
//! the first other vertex D is connected to the camera ([`super::camera::Camera::importance`],
//! a lens point sampled on a thin lens) and splatted to the pixel it lands in.
//!
//! Each pass traces `N` light paths per sample index (from one per 256 pixels to one per 8, as
//! the caustics' share of the image measured by a pilot says: the `budget` module):
//! light path `k` of sample `s` draws from `Rng::for_sample(seed ⊕ LIGHT_SEED, k, s)` alone,
//! and splats are added to the film's exact sums, so images are bit-identical for any thread
//! count and any split of the samples. Splats are weighted `1 / N`: the film divides by the
//! sample count.
//!
//! Point and spot lights are light-traced too: no path tracer's path reaches them through a
//! specular surface, so their caustics are light that `Mis` lacks (the one place where
//! `Caustics` does not converge to `Mis`'s image, but to the physically right one).
//!
//! Under `Method::Photons` the same light paths also leave photons where they arrive after a
//! specular vertex, and the camera gathers them where it sees D through mirrors and glass
//! ([`photons`]); under `Caustics` those paths are left to the path tracer. Under `Photons` the
//! chains also hold narrow glossy conductors (`Bsdf::is_narrow_glossy`), followed by sampling
//! their lobe from the light's side (the GGX conductor's value is symmetric in its two
//! directions), and the path tracer takes no light sample at such a vertex of a chain it
//! leaves to light tracing or the photons.
//!
//! Not light-traced (left to the path tracer): D seen through a mirror or glass (but see
//! `Photons` above), D deeper than
//! the camera's first hit, glossy chains (but see `Photons`), emitting or mirror planes, the
//! constant background, and light leaving an emitter inside tinted glass is not attenuated
//! before its first hit.
//!
//! Alpha masks: light paths and their connections to the camera pass through surfaces where
//! the masks say they are absent, as the camera's paths do (`closest_present`, `blocked`:
//! cut-outs always, blended surfaces with probability 1 − coverage, drawn from the light path's
//! own numbers), and a masked emitter sends light from its present points only. The camera's first hit D is then
//! its first present surface on both sides.

mod budget;
pub mod emit;
pub mod photons;
pub mod targets;

use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};

use glam::Vec3;
use rayon::prelude::*;

use super::integrator::{blocked, closest_present, is_chain_vertex, point_error, spawn};
use super::medium::Medium;
use super::{Cancelled, Method, SceneView, TraceStats};
use crate::cpu::{Isa, Kernel, Lanes};
use crate::film::Film;
use crate::geometry::layout::Layout;
use crate::geometry::packed::Hit;
use crate::geometry::ray::Ray;
use crate::geometry::surface::Surface;
use crate::shading::material::Material;
use crate::shading::rng::Rng;
use crate::shading::sampler::Sampler;
use emit::Sources;
use photons::{Photon, PhotonMap};

/// Mixed into the seed of light paths, so their streams are not those of the pixels' samples.
const LIGHT_SEED: u64 = 0x6c69_6768_7420_7061;

/// Most light paths traced per work item.
const CHUNK: u64 = 1024;

/// Fewest work items per sample: a pass of one sample (`Method::Photons`) still shares its
/// light paths among the threads.
const MIN_CHUNKS: u64 = 32;

/// Most bytes of photons a `Photons` pass holds at once (see
/// [`LightTracing::samples_per_group`]).
const PHOTON_MEMORY: u64 = 64 << 20;

/// Most samples whose photon maps a `Photons` pass holds at once: few enough barriers between
/// light and camera paths to keep both threads busy.
const PHOTON_GROUP: u64 = 16;

/// Work items whose splats are held at once before they are added to the film: bounds the
/// memory of a pass to `BATCH · CHUNK` splats, whatever the image size.
const BATCH: u64 = 64;

/// One work item's light paths: their splats (pixel index, value before the `1 / N` weight),
/// the photons they left and their counters.
type Traced = (Vec<(usize, Vec3)>, Vec<Photon>, TraceStats);

/// The light paths of a render under `Caustics` or `Photons`: where they start and how many
/// each sample traces (the pilot's count, the `budget` module).
pub struct LightTracing {
    sources: Sources,
    paths: u64,
}

impl LightTracing {
    /// The light paths of renders of `view` at `size` and `seed` (the pilot's work added to
    /// `stats`); `None` (nothing to trace) unless the view's method is `Caustics` or
    /// `Photons` and the scene has a finite surface that may be perfect specular and a light.
    pub fn new<L: Layout>(
        view: &SceneView<L>,
        size: (u32, u32),
        seed: u64,
        stats: &mut TraceStats,
    ) -> Option<Self> {
        if !matches!(view.method, Method::Caustics | Method::Photons) {
            return None;
        }
        let sources = Sources::new(
            view.geometry,
            (view.materials, view.owner_material),
            view.lights,
            view.method.chains_glossy(),
        );
        if sources.is_empty() {
            return None;
        }
        // The pilot measures the share of the caustics light tracing connects to the camera,
        // not of those the photons bring: `Photons` traces the most paths.
        let paths = if view.method == Method::Photons {
            budget::most_paths(size)
        } else {
            budget::light_paths(view, &sources, size, seed, stats)
        };
        Some(Self { sources, paths })
    }

    /// Samples whose photon maps a `Photons` pass holds at once: as many as fit in
    /// `PHOTON_MEMORY` (64 MiB) at the most photons their paths can leave (one each), at most
    /// `PHOTON_GROUP` (16), at least one.
    pub fn samples_per_group(&self) -> u32 {
        let per_sample = self
            .paths
            .saturating_mul(std::mem::size_of::<Photon>() as u64);
        (PHOTON_MEMORY / per_sample.max(1)).clamp(1, PHOTON_GROUP) as u32
    }

    /// Traces the light paths of samples `samples` and adds their splats to `film` (see the
    /// module's notes); with `keep_photons`, also the photons they leave ([`photons`]): one
    /// list per sample, in the order of their paths.
    pub fn trace<L: Layout>(
        &self,
        view: &SceneView<L>,
        film: &mut Film,
        (seed, samples): (u64, Range<u32>),
        keep_photons: bool,
        cancel: &AtomicBool,
    ) -> Result<(TraceStats, Vec<Vec<Photon>>), Cancelled> {
        let mut stats = TraceStats::default();
        let count = samples.end.saturating_sub(samples.start) as usize;
        let mut kept: Vec<Vec<Photon>> = vec![Vec::new(); if keep_photons { count } else { 0 }];
        let size = (film.width, film.height);
        let scale = 1.0 / self.paths as f32;
        let fixed = film.fixed();
        // Paths per work item: the items of a sample hold them in order whatever their size,
        // so neither the splats' sums nor the photons' order depend on it.
        let chunk = self.paths.div_ceil(MIN_CHUNKS).clamp(1, CHUNK);
        let chunks = self.paths.div_ceil(chunk);
        let seed = seed ^ LIGHT_SEED;
        // Work items are (sample, chunk) pairs, so that the samples of a pass share the
        // threads even when one sample's light paths fit in a chunk.
        let first = u64::from(samples.start);
        let items = u64::from(samples.end.saturating_sub(samples.start)) * chunks;
        for batch in (0..items).step_by(BATCH as usize) {
            if cancel.load(Ordering::Relaxed) {
                return Err(Cancelled);
            }
            let done: Vec<Traced> = (batch..(batch + BATCH).min(items))
                .into_par_iter()
                .map(|item| {
                    let (sample, part) = (first + item / chunks, item % chunks);
                    Isa::selected().run(Chunk {
                        view,
                        sources: &self.sources,
                        size,
                        seed,
                        sample,
                        paths: part * chunk..((part + 1) * chunk).min(self.paths),
                        keep_photons,
                    })
                })
                .collect();
            for (item, (splats, photons, s)) in (batch..).zip(done) {
                stats = stats + s;
                if let Some(list) = kept.get_mut((item / chunks) as usize) {
                    list.extend(photons);
                }
                for (pixel, l) in splats {
                    let l = l * scale;
                    if !l.is_finite() {
                        stats.nonfinite += 1;
                    } else if film.sum[pixel].add(l, fixed) {
                        stats.clamped += 1;
                    }
                }
            }
        }
        Ok((stats, kept))
    }

    /// The photon map of sample `sample` from the photons its light paths left.
    pub fn photon_map(&self, photons: Vec<Photon>, sample: u32) -> PhotonMap {
        let first = photons::first_radius(self.sources.target_area(), self.paths);
        PhotonMap::new(photons, self.paths, photons::radius(first, sample))
    }
}

/// The light paths `paths` of sample `sample`: the work of a [`LightTracing::trace`] item, which
/// [`Isa::run`] compiles once per instruction set (as the camera's passes are), so the light
/// paths' traversals use the widest lanes the CPU has.
struct Chunk<'a, L: Layout> {
    view: &'a SceneView<'a, L>,
    sources: &'a Sources,
    size: (u32, u32),
    seed: u64,
    sample: u64,
    paths: Range<u64>,
    keep_photons: bool,
}

impl<L: Layout> Kernel for Chunk<'_, L> {
    type Output = Traced;

    #[inline(always)]
    fn run<W: Lanes>(self, lanes: W) -> Traced {
        let mut stats = TraceStats::default();
        let mut splats = Vec::new();
        let mut photons = Vec::new();
        let mut keep = self.keep_photons.then_some(&mut photons);
        for k in self.paths {
            let mut rng = Rng::for_sample(self.seed, k, self.sample);
            let left = keep.as_deref_mut();
            let at = (self.view, self.sources, self.size);
            splats.extend(light_path(lanes, at, &mut rng, &mut stats, left));
        }
        (splats, photons, stats)
    }
}

/// One light path: its splat (pixel index, value before the `1 / N` weight), if
/// it reaches a vertex the camera sees that is not a chain vertex (`is_chain_vertex`: a
/// perfect mirror or glass, under `Photons` also a narrow glossy conductor) after at least one
/// chain vertex; with `photons`, the photons it leaves on the way: wherever it arrives after a
/// chain vertex at a surface that may shade as another kind there (not a chain vertex, or a
/// mix, whose pick is the gather's to make).
#[inline(always)]
fn light_path<L: Layout, W: Lanes>(
    lanes: W,
    (view, sources, size): (&SceneView<L>, &Sources, (u32, u32)),
    sampler: &mut Rng,
    stats: &mut TraceStats,
    mut photons: Option<&mut Vec<Photon>>,
) -> Option<(usize, Vec3)> {
    let emitted = sources.emit(view.geometry, view.materials, view.lights, sampler)?;
    let (mut ray, mut beta) = (emitted.ray, emitted.beta);
    let mut medium = Medium::CLEAR;
    // Chain vertices so far.
    let mut specular = 0u32;
    loop {
        stats.rays += 1;
        let start = ray.origin;
        // An `Rng` has no dimensions: any will do.
        let hit = closest_present(lanes, view, &mut ray, (&mut *sampler, 0), stats)?;
        let s = view.geometry.surface(&ray, &hit);
        if !medium.is_clear() {
            beta *= medium.transmittance((s.p - start).length());
        }
        // A mix's component, picked as the path tracer picks it (see `trace_path`).
        let whole = view
            .materials
            .get(*view.owner_material.get(s.owner as usize)? as usize)?;
        let material = whole.component(s.tex_coords(), || sampler.next_1d());
        let bsdf = material.bsdf(ray.direction, s.n, s.ns, s.tex_coords(), || {
            view.geometry.uv_tangent(&hit).map(|t| (t.tangent, t.sign))
        });
        let chain = is_chain_vertex(&bsdf, hit.kind, view.method);
        let leaves_photon = specular > 0 && (whole.is_mix() || !chain);
        if let Some(kept) = photons.as_deref_mut().filter(|_| leaves_photon) {
            kept.push(Photon {
                p: s.p,
                n: s.n,
                direction: ray.direction,
                beta,
                owner: s.owner,
                chain: specular,
            });
        }
        if !chain {
            if specular == 0 {
                return None;
            }
            let at = Arrival {
                hit: &hit,
                surface: &s,
                material,
                direction: ray.direction,
            };
            return connect(lanes, view, at, beta, size, sampler, stats);
        }
        // The path tracer reaches a light through at most `max_depth − 2` specular vertices.
        if specular + 2 >= view.max_depth {
            return None;
        }
        let err = point_error(view.geometry, &hit, s.p);
        let beyond = medium.beyond(material, ray.direction, s.n);
        let scatter = bsdf.sample(sampler)?;
        medium = medium.leaving(beyond, ray.direction, s.n, scatter.direction);
        beta *= scatter.attenuation / scatter.radiance_scale;
        if beta == Vec3::ZERO {
            return None;
        }
        specular += 1;
        ray = spawn(s.p, s.n, err, scatter.direction);
    }
}

/// A light path's arrival at its non-specular vertex.
struct Arrival<'a> {
    hit: &'a Hit,
    surface: &'a Surface,
    material: &'a Material,
    /// Direction of the light path's ray that hit it.
    direction: Vec3,
}

/// The splat of a light path of weight `beta` arriving at `at`, connected to the camera: the
/// BSDF is built as for the camera's ray arriving there, so its value (with the cosine of the
/// light's side, about the shading normal, folded as the path tracer folds it) is the one the
/// path tracer samples, and the geometric cosines convert the light path's density at the
/// point into the camera's.
#[inline(always)]
fn connect<L: Layout, W: Lanes>(
    lanes: W,
    view: &SceneView<L>,
    at: Arrival,
    beta: Vec3,
    (width, height): (u32, u32),
    sampler: &mut Rng,
    stats: &mut TraceStats,
) -> Option<(usize, Vec3)> {
    let s = at.surface;
    let camera = view
        .camera
        .importance(s.p, width, height, sampler.next_2d())?;
    let to = camera.lens - s.p;
    let dist2 = to.length_squared();
    let wo = to / dist2.sqrt();
    let cos_in = s.n.dot(at.direction).abs();
    if !(dist2 > 0.0 && cos_in > 0.0) {
        return None;
    }
    let bsdf = at.material.bsdf(-wo, s.n, s.ns, s.tex_coords(), || {
        view.geometry
            .uv_tangent(at.hit)
            .map(|t| (t.tangent, t.sign))
    });
    let (f_cos, _) = bsdf.eval(-at.direction)?;
    if f_cos == Vec3::ZERO {
        return None;
    }
    let err = point_error(view.geometry, at.hit, s.p);
    let from = spawn(s.p, s.n, err, wo).origin;
    let span = camera.lens - from;
    let length = span.length();
    if !(length > 0.0 && length.is_finite()) {
        return None;
    }
    stats.rays += 1;
    let ray = Ray::new(from, span / length);
    let end = (length, Some(camera.lens));
    if blocked(lanes, view, ray, end, (&mut *sampler, 0), stats) {
        return None;
    }
    let value = beta * f_cos * (s.n.dot(wo).abs() / cos_in) * (camera.importance / dist2);
    let (x, y) = (camera.film.x as usize, camera.film.y as usize);
    Some((y * width as usize + x, value))
}
