//! The path tracer: traces camera paths through packed geometry into a [`Film`]. No ECS here.

use std::marker::PhantomData;
use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::camera::Camera;
use crate::cpu::{Isa, Kernel, Lanes, Sse};
use crate::film::{FeatureSample, Film, FilmBand, FixedPoint, Pixel};
use crate::geometry::layout::{DefaultLayout, Layout};
use crate::geometry::packed::{Geometry, Hit, HitKind, LayoutKind};
use crate::geometry::ray::{Ray, gamma, spawn_origin};
use crate::geometry::sphere::sphere_point_error;
use crate::geometry::store::{SphereStore, TriangleStore};
use crate::geometry::surface::Surface;
use crate::geometry::triangle::triangle_point_error;
use crate::lights::{LightSet, Sampled};
use crate::scene::format::{MAX_DEPTH, Method};
use crate::shading::bsdf::Bsdf;
use crate::shading::material::Material;
use crate::shading::rng::Rng;
use crate::shading::sampler::{IndependentPixel, PixelSampler, Sampler, SamplerKind, SobolPixel};

/// Rows per parallel work item. Small enough to balance two cores and to cancel promptly.
const BAND_ROWS: usize = 4;

/// Everything a render reads: a snapshot of the scene, independent of the ECS. Generic over the
/// geometry's layout, so that the whole pass is monomorphised per layout (no dispatch per ray).
#[derive(Clone, Copy)]
pub struct SceneView<'a, L: Layout = DefaultLayout> {
    /// Packed geometry and its BVHs.
    pub geometry: &'a Geometry<L>,
    /// Material table.
    pub materials: &'a [Material],
    /// Material index of every owner slot.
    pub owner_material: &'a [u32],
    /// Emitters, for next-event estimation.
    pub lights: &'a LightSet,
    /// The camera.
    pub camera: &'a Camera,
    /// Radiance of rays that leave the scene.
    pub background: Vec3,
    /// Rays per path, camera ray included.
    pub max_depth: u32,
    /// Light-transport method.
    pub method: Method,
    /// Whether paths may be ended early by Russian roulette (unbiased either way).
    pub roulette: bool,
    /// Sample generator of the converging passes.
    pub sampler: SamplerKind,
    /// Whether some material has an alpha mask ([`has_masks`] of `materials`): only then are
    /// hits tested for presence, so that scenes without masks pay nothing for them.
    pub masked: bool,
}

/// Whether any of `materials` has an alpha mask ([`Material::is_masked`]): the value of
/// [`SceneView::masked`].
pub fn has_masks(materials: &[Material]) -> bool {
    materials.iter().any(Material::is_masked)
}

/// Most surfaces one ray passes through where their alpha masks say they are absent; the next
/// hit then counts as present whatever its mask says. A bound on the work a hostile scene (a
/// stack of thousands of masked layers) can cause, far beyond what real scenes reach.
pub const MAX_PASS_THROUGHS: u32 = 1024;

/// Counters of one render.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraceStats {
    /// Rays traced (camera, scattered and shadow rays).
    pub rays: u64,
    /// Samples whose radiance was NaN or infinite; they are dropped, never written.
    pub nonfinite: u64,
    /// Samples with a channel beyond the film's range (2^[`crate::film::HEADROOM_BITS`] times
    /// the scene's brightest radiance); they are clamped to it.
    pub clamped: u64,
    /// Passes traced in each layout, in the order of [`LayoutKind::ALL`]: which monomorphised
    /// code really ran.
    pub layout_passes: [u64; 4],
}

impl std::ops::Add for TraceStats {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self {
            rays: self.rays + o.rays,
            nonfinite: self.nonfinite + o.nonfinite,
            clamped: self.clamped + o.clamped,
            layout_passes: std::array::from_fn(|k| self.layout_passes[k] + o.layout_passes[k]),
        }
    }
}

/// The render was cancelled before it finished; the film holds a partial pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cancelled;

/// Bounces after which Russian roulette may end a path.
const ROULETTE_DEPTH: u32 = 3;

/// The sampler's dimension layout: dimension 0 is the pixel position; bounce `b` then owns
/// dimensions `1 + b·BOUNCE_DIMENSIONS + k` with `k` one of the offsets below. Past the bounces
/// of the deepest path a scene may ask for, from [`EXTRA_DIMENSION`], come the dimensions added
/// later ([`LENS_DIMENSION`], [`TEXEL_DIMENSION`]): adding them moved no earlier dimension, so
/// a scene that does not use them renders exactly as before.
pub const BOUNCE_DIMENSIONS: u32 = 5;
/// The choice of an emitter for next-event estimation (1D).
pub const LIGHT_CHOICE_DIMENSION: u32 = 0;
/// The point on the chosen emitter (2D).
pub const LIGHT_POINT_DIMENSION: u32 = 1;
/// The BSDF's 2D sample, then one more 1D value (glass's choice, metal's fuzz depth).
pub const BSDF_DIMENSION: u32 = 2;
/// Russian roulette (1D).
pub const ROULETTE_DIMENSION: u32 = 4;
/// The first dimension past every bounce of a path of [`MAX_DEPTH`] rays.
pub const EXTRA_DIMENSION: u32 = 1 + MAX_DEPTH * BOUNCE_DIMENSIONS;
/// The position on the lens (2D), drawn only by a camera with an aperture.
pub const LENS_DIMENSION: u32 = EXTRA_DIMENSION;
/// Bounce `b`'s position within an environment map's texel (2D) at `TEXEL_DIMENSION + b`, drawn
/// only when next-event estimation picked the map.
pub const TEXEL_DIMENSION: u32 = EXTRA_DIMENSION + 1;

/// Veach's power heuristic (β = 2) weight of a strategy with density `a` against one with `b`.
#[inline]
fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2.is_infinite() {
        1.0
    } else if a2 + b2 == 0.0 {
        0.0
    } else {
        a2 / (a2 + b2)
    }
}

/// The weight of emission that a BSDF-sampled ray found, leaving `from` (the vertex's point and
/// BSDF density, if it sampled lights): 1 if it did not, or if light sampling could not have
/// produced the ray (`pdf_light(point)` = 0); under NEE 0 (the light sample counted it); under MIS the
/// power heuristic against the light density.
#[inline(always)]
fn emission_weight(
    method: Method,
    from: Option<(Vec3, f32)>,
    pdf_light: impl FnOnce(Vec3) -> f32,
) -> f32 {
    let Some((point, pdf_bsdf)) = from else {
        return 1.0;
    };
    let pdf_light = pdf_light(point);
    if pdf_light == 0.0 {
        1.0
    } else if method == Method::Nee {
        0.0
    } else {
        power_heuristic(pdf_bsdf, pdf_light)
    }
}

/// Absolute error bound of the hit point `s.p` of `hit`, per component (pbrt-v4, Section 6.8.5):
/// the point is recomputed from the primitive, so its error scales with the primitive's own
/// coordinates, not with the ray's travel. Public so tests can spawn rays exactly as the
/// integrator does.
#[inline(always)]
pub fn point_error<L: Layout>(geometry: &Geometry<L>, hit: &Hit, p: Vec3) -> Vec3 {
    let i = hit.index as usize;
    match hit.kind {
        HitKind::Sphere => {
            let (c, r) = geometry.spheres.get(i);
            sphere_point_error(c, r)
        }
        HitKind::Triangle => {
            let b0 = 1.0 - hit.b1 - hit.b2;
            triangle_point_error(geometry.triangles.get(i), [b0, hit.b1, hit.b2])
        }
        HitKind::Plane => gamma(8.0) * (p.abs() + geometry.planes[i].point.abs()),
        HitKind::Instance { triangle } => geometry
            .instances
            .point_error(hit.index, triangle, hit.b1, hit.b2),
    }
}

/// A ray from surface point `p` (geometric normal `n`, error `err`) along `dir`, started on the
/// side it leaves to: the one way the integrator starts a bounce or a shadow ray.
#[inline(always)]
pub fn spawn(p: Vec3, n: Vec3, err: Vec3, dir: Vec3) -> Ray {
    let side = if dir.dot(n) > 0.0 { n } else { -n };
    Ray::new(spawn_origin(p, side, err), dir)
}

/// The first hit of a surface that is present along `ray`, up to `end` (a shadow ray's end
/// point; `None`: without end), in a scene with alpha masks. Where a mask says its surface is
/// absent ([`Material::is_present`]) the ray passes through: it starts again from the hit
/// point, spawned on the far side with the point's error bound, in the same direction or, with
/// an `end`, towards it (so that the rounding of the new origin cannot carry the segment into
/// the surface at its end); `ray` is left as the segment that found the returned hit. No
/// sampler dimension is drawn, so a path is what it would be without the absent surfaces. After
/// [`MAX_PASS_THROUGHS`] the next hit counts as present.
#[inline]
fn first_present<L: Layout, W: Lanes>(
    lanes: W,
    view: &SceneView<L>,
    ray: &mut Ray,
    end: Option<Vec3>,
    stats: &mut TraceStats,
) -> Option<Hit> {
    let mut t_max = end.map_or(f32::INFINITY, |e| (e - ray.origin).length());
    for _ in 0..MAX_PASS_THROUGHS {
        let hit = view.geometry.intersect_with(lanes, ray, t_max)?;
        let s = view.geometry.surface(ray, &hit);
        let material = &view.materials[view.owner_material[s.owner as usize] as usize];
        if material.is_present(s.uv) {
            return Some(hit);
        }
        let err = point_error(view.geometry, &hit, s.p);
        let origin = spawn(s.p, s.n, err, ray.direction).origin;
        *ray = match end {
            None => Ray::new(origin, ray.direction),
            Some(e) => {
                let span = e - origin;
                t_max = span.length();
                // Past the end (or degenerate): nothing more in between.
                if t_max.is_nan() || t_max <= 0.0 || span.dot(ray.direction) <= 0.0 {
                    return None;
                }
                Ray::new(origin, span / t_max)
            }
        };
        stats.rays += 1;
    }
    view.geometry.intersect_with(lanes, ray, t_max)
}

/// Radiance arriving along `ray`, by path tracing with the view's [`Method`]:
/// - `Naive`: BSDF sampling only; emitters count when a path hits them (the thesis's algorithm).
/// - `Nee`: at every diffuse vertex a shadow ray goes to a point sampled on an emitter; emitters
///   hit by the BSDF-sampled continuation of such a vertex are then not counted again.
/// - `Mis`: both, weighted by the power heuristic (Veach 1997, ch. 9).
///
/// Surfaces that alpha masks make absent are passed through without a bounce, a depth step or a
/// sampler dimension, at most [`MAX_PASS_THROUGHS`] per ray.
///
/// Emission seen by the camera or after a glass/mirror bounce always counts in full. Russian
/// roulette (after a few bounces, survival probability = the path's throughput without the
/// (n1/n2)² radiance scale of refractions, as pbrt-v4's `etaScale`) ends paths early without
/// bias: a path inside glass is not killed for the compression it undoes on the way out.
#[inline(always)]
pub fn trace_path<L: Layout, S: Sampler>(
    view: &SceneView<L>,
    ray: Ray,
    sampler: &mut S,
    stats: &mut TraceStats,
) -> Vec3 {
    trace_path_with(Sse, view, ray, sampler, stats, false).0
}

/// [`trace_path`] with the BVHs' box tests as wide as `lanes`, and the path's features for the
/// denoiser: the albedo and the shading normal (on the side the path arrived from) of the first
/// hit that is not a perfect mirror or glass ([`Bsdf::is_specular`]) nor absent where an
/// alpha mask says so, the albedo ([`Bsdf::feature_albedo`]: reflectance plus emission)
/// tinted by the specular bounces before it; the background and distant lights seen along the
/// ray as albedo (and a zero normal) if the path leaves the scene first; zero if it ends first.
/// Each sample's albedo is clamped to [0, 1] per channel ([`feature_albedo`]) before it is
/// summed. They use no random numbers, so the radiance is the same whether they are collected or
/// not; without `collect` (a film without feature buffers) they are not computed and come back
/// zero.
#[inline(always)]
fn trace_path_with<L: Layout, S: Sampler, W: Lanes>(
    lanes: W,
    view: &SceneView<L>,
    mut ray: Ray,
    sampler: &mut S,
    stats: &mut TraceStats,
    collect: bool,
) -> (Vec3, FeatureSample) {
    let mut radiance = Vec3::ZERO;
    let mut throughput = Vec3::ONE;
    // The product of the refractions' radiance scales in `throughput`.
    let mut eta_scale = 1.0f32;
    // Point and BSDF density of the previous vertex, if it was one that sampled lights.
    let mut previous: Option<(Vec3, f32)> = None;
    let sample_lights = view.method != Method::Naive && !view.lights.is_empty();
    // Collected once, at the first hit that is not a perfect mirror or glass; `Some` at once
    // when not collected.
    let mut features = (!collect).then(FeatureSample::default);
    for depth in 0..view.max_depth {
        stats.rays += 1;
        let found = if view.masked {
            first_present(lanes, view, &mut ray, None, stats)
        } else {
            view.geometry.intersect_with(lanes, &ray, f32::INFINITY)
        };
        let Some(hit) = found else {
            let mut seen = view.background;
            let mut light = view.background;
            for k in 0..view.lights.distant().len() {
                let (emitted, pdf_light) = view.lights.distant_lookup(k, ray.direction);
                if emitted == Vec3::ZERO {
                    continue;
                }
                seen += emitted;
                let weight =
                    emission_weight(view.method, previous.filter(|_| sample_lights), |_| {
                        pdf_light
                    });
                light += emitted * weight;
            }
            radiance += throughput * light;
            features.get_or_insert(FeatureSample {
                albedo: feature_albedo(throughput / eta_scale * seen),
                normal: Vec3::ZERO,
            });
            break;
        };
        let s = view.geometry.surface(&ray, &hit);
        let material = &view.materials[view.owner_material[s.owner as usize] as usize];
        let bsdf = material.bsdf(ray.direction, s.n, s.ns, s.uv, || {
            view.geometry.uv_tangent(&hit).map(|t| (t.tangent, t.sign))
        });
        if features.is_none() && (!bsdf.is_specular() || depth + 1 == view.max_depth) {
            let n = bsdf.shading_normal();
            features = Some(FeatureSample {
                albedo: feature_albedo(throughput / eta_scale * bsdf.feature_albedo()),
                normal: if ray.direction.dot(n) < 0.0 { n } else { -n },
            });
        }
        if let Some(emitted) = bsdf.emitted() {
            let from = previous.filter(|_| sample_lights);
            let weight = emission_weight(view.method, from, |p_prev| {
                view.lights
                    .pdf(view.geometry, hit.kind, hit.index, p_prev, s.p, s.n)
            });
            radiance += throughput * emitted * weight;
        }
        if depth + 1 == view.max_depth || !bsdf.scatters() {
            break;
        }
        // Only a vertex the path continues from needs the hit point's error bound.
        let err = point_error(view.geometry, &hit, s.p);
        let dimension = 1 + depth * BOUNCE_DIMENSIONS;
        if sample_lights && bsdf.samples_lights() {
            sampler.seek(dimension + LIGHT_CHOICE_DIMENSION);
            let vertex = Vertex {
                surface: &s,
                err,
                bsdf: &bsdf,
                dimension,
            };
            radiance += throughput * direct_light(lanes, view, vertex, sampler, stats);
        }
        sampler.seek(dimension + BSDF_DIMENSION);
        let Some(scatter) = bsdf.sample(sampler) else {
            break;
        };
        previous = scatter.pdf.map(|pdf| (s.p, pdf));
        throughput *= scatter.attenuation;
        eta_scale *= scatter.radiance_scale;
        if throughput == Vec3::ZERO {
            break;
        }
        if view.roulette && depth >= ROULETTE_DEPTH {
            let survive = (throughput.max_element() / eta_scale).min(1.0);
            sampler.seek(dimension + ROULETTE_DIMENSION);
            if sampler.next_1d() >= survive {
                break;
            }
            throughput /= survive;
        }
        ray = spawn(s.p, s.n, err, scatter.direction);
    }
    (radiance, features.unwrap_or_default())
}

/// One sample's albedo as the feature buffer records it: each channel clamped to [0, 1], the
/// range Open Image Denoise requires of an albedo (its `RT` filter: "values in [0, 1]"). Clamped
/// per sample, before the pixel's average, so that a pixel partly covering a bright emitter
/// records the part it covers, not 1. A NaN stays NaN, so the film still drops the sample's
/// features as non-finite.
#[inline]
fn feature_albedo(albedo: Vec3) -> Vec3 {
    Vec3::from_array(albedo.to_array().map(|c| c.clamp(0.0, 1.0)))
}

/// A vertex a path continues from: the surface it hit, that point's error bound, and the BSDF
/// there.
#[derive(Clone, Copy)]
struct Vertex<'a> {
    surface: &'a Surface,
    err: Vec3,
    bsdf: &'a Bsdf<'a>,
    /// The bounce's first sampler dimension.
    dimension: u32,
}

/// One light sample at a vertex's surface `s` for a ray arriving along `d`: emitted radiance
/// from a point sampled on an emitter, times the BSDF and cosine, over the light density,
/// MIS-weighted against BSDF sampling under `Method::Mis`.
#[inline(always)]
fn direct_light<L: Layout, W: Lanes>(
    lanes: W,
    view: &SceneView<L>,
    vertex: Vertex,
    sampler: &mut impl Sampler,
    stats: &mut TraceStats,
) -> Vec3 {
    let Vertex {
        surface: s,
        err,
        bsdf,
        ..
    } = vertex;
    // The emitter from its own dimension, the point from the next (a map's texel, then the
    // position within it from one of the extra dimensions).
    let u_select = sampler.next_1d();
    sampler.seek(vertex.dimension + LIGHT_POINT_DIMENSION);
    let u = sampler.next_2d();
    let bounce = (vertex.dimension - 1) / BOUNCE_DIMENSIONS;
    let jitter = || {
        sampler.seek(TEXEL_DIMENSION + bounce);
        sampler.next_2d()
    };
    let Some(sampled) = view.lights.sample(view.geometry, s.p, u_select, u, jitter) else {
        return Vec3::ZERO;
    };
    // The direction to the light, what it sends along it, its density, and the shadow ray's
    // origin, direction, length and end point (none for a distant light).
    let (wi, emitted, pdf_light, shadow) = match sampled {
        Sampled::Surface(light) => {
            let to_light = light.p - s.p;
            let dist2 = to_light.length_squared();
            if dist2.is_nan() || dist2 <= 0.0 {
                return Vec3::ZERO;
            }
            let wi = to_light / dist2.sqrt();
            let emitter = &view.materials[light.material as usize];
            // A point where the emitter's mask says it is absent sends nothing: the light's
            // density stays that of its whole surface, as for the BSDF-sampled rays that pass
            // through such points.
            if view.masked && !emitter.is_present(light.uv) {
                return Vec3::ZERO;
            }
            let emitted = emitter.emitted(wi, light.n, light.uv);
            // Shadow ray between the two offset points, so neither surface can block it.
            let from = spawn(s.p, s.n, err, wi).origin;
            let to_side = if wi.dot(light.n) < 0.0 {
                light.n
            } else {
                -light.n
            };
            let end = spawn_origin(light.p, to_side, light.err);
            let span = end - from;
            let length = span.length();
            if length.is_nan() || length <= 0.0 {
                return Vec3::ZERO;
            }
            (
                wi,
                emitted,
                light.pdf,
                (Ray::new(from, span / length), length, Some(end)),
            )
        }
        Sampled::Distant(light) => {
            let wi = light.direction;
            let shadow = spawn(s.p, s.n, err, wi);
            (wi, light.radiance, light.pdf, (shadow, f32::INFINITY, None))
        }
    };
    if emitted == Vec3::ZERO {
        return Vec3::ZERO;
    }
    let Some((f_cos, pdf_bsdf)) = bsdf.eval(wi) else {
        return Vec3::ZERO;
    };
    if f_cos == Vec3::ZERO {
        return Vec3::ZERO;
    }
    if !(pdf_light > 0.0 && pdf_light.is_finite()) {
        return Vec3::ZERO;
    }
    stats.rays += 1;
    let (mut shadow_ray, length, end) = shadow;
    let occluded = if view.masked {
        first_present(lanes, view, &mut shadow_ray, end, stats).is_some()
    } else {
        view.geometry.occluded_with(lanes, &shadow_ray, length)
    };
    if occluded {
        return Vec3::ZERO;
    }
    let weight = if view.method == Method::Mis {
        power_heuristic(pdf_light, pdf_bsdf)
    } else {
        1.0
    };
    f_cos * emitted * (weight / pdf_light)
}

/// Adds samples `samples` of every pixel to `film`, in parallel over bands of rows.
///
/// Each sample draws from its own generator (the view's [`SamplerKind`]) seeded by (seed,
/// pixel, sample index) and is added to its pixel's sum in sample order, so the film is
/// bit-identical whatever the thread count and however the samples are split into passes.
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
    film.samples = samples.end;
    let mut stats = stats;
    if let Some(slot) = LayoutKind::ALL.iter().position(|&k| k == L::KIND) {
        stats.layout_passes[slot] += 1;
    }
    Ok(stats)
}

/// The camera ray of one sample of pixel `(x, y)` of an image of `size`: the position in the
/// pixel from dimension 0, and for a camera with a lens the position on it from
/// [`LENS_DIMENSION`] (a pinhole draws nothing more, so its renders are what they always were).
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
                let (l, features) =
                    trace_path_with(lanes, self.view, ray, &mut sampler, &mut stats, collect);
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

/// Mean of a film's pixels, a convenience for tests and reports.
pub fn film_mean(film: &Film) -> DVec3 {
    let n = film.sum.len().max(1) as f64;
    film.mean().iter().map(|m| m.as_dvec3()).sum::<DVec3>() / n
}
