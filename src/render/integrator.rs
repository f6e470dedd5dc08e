//! The path tracer: radiance along a camera ray by BSDF sampling, next-event estimation or
//! both (multiple importance sampling), with the path's denoiser features. No ECS here.

use glam::Vec3;

use super::medium::Medium;
use super::{
    BOUNCE_DIMENSIONS, BSDF_DIMENSION, COMPONENT_DIMENSION, LIGHT_CHOICE_DIMENSION,
    LIGHT_POINT_DIMENSION, MAX_PASS_THROUGHS, Method, ROULETTE_DIMENSION, SceneView,
    TEXEL_DIMENSION, TRANSPARENCY_DIMENSION, TraceStats,
};
use crate::cpu::{Lanes, Sse};
use crate::film::FeatureSample;
use crate::geometry::layout::Layout;
use crate::geometry::packed::{Geometry, Hit, HitKind};
use crate::geometry::ray::{Ray, gamma, spawn_origin};
use crate::geometry::sphere::sphere_point_error;
use crate::geometry::store::{SphereStore, TriangleStore};
use crate::geometry::surface::Surface;
use crate::geometry::triangle::triangle_point_error;
use crate::lights::Sampled;
use crate::shading::bsdf::Bsdf;
use crate::shading::sampler::Sampler;
use crate::shading::sampling::facing;

/// Bounces after which Russian roulette may end a path.
const ROULETTE_DEPTH: u32 = 3;

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

/// Whether a vertex with `bsdf` on a primitive of `kind` is a chain vertex of a light-traced
/// path under `method`: a perfect mirror or smooth glass, or under `Method::Photons` also a
/// narrow glossy conductor ([`Method::chains_glossy`]); never on an infinite plane (which no
/// light path can be aimed at).
#[inline(always)]
pub(super) fn is_chain_vertex(bsdf: &Bsdf, kind: HitKind, method: Method) -> bool {
    (bsdf.is_specular() || (method.chains_glossy() && bsdf.is_narrow_glossy()))
        && kind != HitKind::Plane
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
    // The side a ray along `dir` leaves to is the one a ray along `-dir` arrives from.
    Ray::new(spawn_origin(p, facing(-dir, n), err), dir)
}

/// The first hit of a surface that is present along `ray`, up to `end` (a shadow ray's end
/// point; `None`: without end), in a scene with alpha masks. Where a mask says its surface is
/// absent the ray passes through; a blended surface of coverage `c` ([`Material::coverage`]) is
/// passed with probability 1 − c (stochastic transparency: unbiased, no sorting). The ray then
/// starts again from the hit point, spawned on the far side with the point's error bound, in
/// the same direction or, with an `end`, towards it (so that the rounding of the new origin
/// cannot carry the segment into the surface at its end); `ray` is left as the segment that
/// found the returned hit. Cutoff masks draw no sampler dimension, so a path is what it would
/// be without the surfaces they remove. Blended surfaces share one value `u`, drawn from
/// `dimension` of `sampler` at the first of them: `u < c` keeps the surface, else the ray passes
/// and `(u − c) / (1 − c)`, again uniform in [0, 1) and independent of the choice made, serves
/// the next one. After [`MAX_PASS_THROUGHS`] the next hit counts as present. Called through
/// [`Lanes::out_of_line`] by [`closest_present`] and [`blocked`]: the masked scenes' loop stays
/// out of the render loop, compiled for the same instructions.
#[inline(always)]
fn first_present<L: Layout, W: Lanes>(
    lanes: W,
    view: &SceneView<L>,
    ray: &mut Ray,
    end: Option<Vec3>,
    (sampler, dimension): (&mut impl Sampler, u32),
    stats: &mut TraceStats,
) -> Option<Hit> {
    let mut t_max = end.map_or(f32::INFINITY, |e| (e - ray.origin).length());
    let mut u: Option<f32> = None;
    for _ in 0..MAX_PASS_THROUGHS {
        let hit = view.geometry.intersect_with(lanes, ray, t_max)?;
        let s = view.surface(ray, &hit);
        let material = &view.materials[view.owner_material[s.owner as usize] as usize];
        let c = material.coverage(s.tex_coords());
        if c >= 1.0 {
            return Some(hit);
        }
        if c > 0.0 {
            let x = *u.get_or_insert_with(|| {
                sampler.seek(dimension);
                sampler.next_1d()
            });
            if x < c {
                return Some(hit);
            }
            u = Some((x - c) / (1.0 - c));
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

/// The first hit of a surface that is present along `ray`: in a scene with alpha masks
/// [`first_present`] (without end, out of line, `ray` left as the segment that found the hit,
/// blended surfaces decided from `dimension` of `sampler`), else the closest hit. The one way a
/// camera path's or a light path's ray finds its next vertex.
#[inline(always)]
pub(super) fn closest_present<L: Layout, W: Lanes>(
    lanes: W,
    view: &SceneView<L>,
    ray: &mut Ray,
    (sampler, dimension): (&mut impl Sampler, u32),
    stats: &mut TraceStats,
) -> Option<Hit> {
    if view.masked {
        lanes.out_of_line(
            #[inline(always)]
            |lanes| first_present(lanes, view, ray, None, (sampler, dimension), stats),
        )
    } else {
        view.geometry.intersect_with(lanes, ray, f32::INFINITY)
    }
}

/// Whether a present surface blocks the segment of `ray` of `length` towards `end` (a point;
/// `None`: a direction without end): [`first_present`] in a scene with alpha masks, else an
/// occlusion query. The one way a shadow ray or a light path's connection to the camera is
/// tested.
#[inline(always)]
pub(super) fn blocked<L: Layout, W: Lanes>(
    lanes: W,
    view: &SceneView<L>,
    mut ray: Ray,
    (length, end): (f32, Option<Vec3>),
    (sampler, dimension): (&mut impl Sampler, u32),
    stats: &mut TraceStats,
) -> bool {
    if view.masked {
        lanes
            .out_of_line(
                #[inline(always)]
                |lanes| first_present(lanes, view, &mut ray, end, (sampler, dimension), stats),
            )
            .is_some()
    } else {
        view.geometry.occluded_with(lanes, &ray, length)
    }
}

/// Radiance arriving along `ray`, by path tracing with the view's [`Method`]:
/// - `Naive`: BSDF sampling only; emitters count when a path hits them.
/// - `Nee`: at every diffuse vertex a shadow ray goes to a point sampled on an emitter; emitters
///   hit by the BSDF-sampled continuation of such a vertex are then not counted again.
/// - `Mis`: both, weighted by the power heuristic (Veach 1997, ch. 9).
///
/// Surfaces that alpha masks make absent are passed through without a bounce, a depth step or a
/// sampler dimension, at most [`MAX_PASS_THROUGHS`] per ray.
///
/// Inside tinted glass (a path that refracted into it) the throughput falls by Beer–Lambert's
/// law over each segment, bounce and shadow rays alike ([`Medium`], which says what is
/// approximated).
///
/// A mix ([`crate::shading::material::Material::Transmissive`]) shades at each hit as one of
/// its components, picked from the bounce's [`COMPONENT_DIMENSION`] with the probabilities at
/// the hit point (a transmission texture varies them): a one-sample estimate of the mixture,
/// unbiased because light sampling, the bounce and the medium beyond all use the component
/// picked. The surface emits as the whole mix.
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
pub(super) fn trace_path_with<L: Layout, S: Sampler, W: Lanes>(
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
    // The medium the current ray travels through.
    let mut medium = Medium::CLEAR;
    // Under `Method::Caustics` and `Method::Photons`, light tracing (the `caustics` module) owns
    // the paths camera → D → S… → light, D the camera's first hit continued by its non-delta
    // part and each S a chain vertex ([`is_chain_vertex`]: a perfect mirror or glass, under
    // `Photons` also a narrow glossy conductor, whose light samples are then not taken); under
    // `Photons` with the sample's photons, the photons also own camera → … → D → S… → light, D
    // a later vertex that is not an S and either the first one (seen through S… only) or
    // Lambertian: the number of S after such a D so far, `None` once the path is not one of
    // them. Its emission from a finite emitter or a distant light is then not counted here.
    let mut caustic: Option<u32> = None;
    // Whether every vertex so far was an S: the camera sees this hit through mirrors and glass.
    let mut through_chain = true;
    // Whether light tracing owns the paths through the camera's first hit (see `caustic`).
    let light_traces_first_hit = view.method.traces_light();
    for depth in 0..view.max_depth {
        stats.rays += 1;
        let start = ray.origin;
        let transparency = TRANSPARENCY_DIMENSION + 2 * depth;
        let found = closest_present(lanes, view, &mut ray, (&mut *sampler, transparency), stats);
        let Some(hit) = found else {
            let mut seen = view.background;
            let mut light = view.background;
            let lit = caustic.is_none_or(|k| k == 0);
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
                if lit {
                    light += emitted * weight;
                }
            }
            radiance += throughput * light;
            features.get_or_insert(FeatureSample {
                albedo: feature_albedo(throughput / eta_scale * seen),
                normal: Vec3::ZERO,
            });
            break;
        };
        let s = view.surface(&ray, &hit);
        if !medium.is_clear() {
            throughput *= medium.transmittance((s.p - start).length());
        }
        let whole = &view.materials[view.owner_material[s.owner as usize] as usize];
        // A mix shades as one component, NEE and bounce alike; the medium beyond is that one's.
        let material = whole.component(s.tex_coords(), || {
            sampler.seek(COMPONENT_DIMENSION + depth);
            sampler.next_1d()
        });
        let mut bsdf = material.bsdf(ray.direction, s.n, s.ns, s.tex_coords(), || {
            view.geometry.uv_tangent(&hit).map(|t| (t.tangent, t.sign))
        });
        if whole.is_mix() {
            bsdf = bsdf.with_emission(whole.emission());
        }
        if features.is_none() && (!bsdf.is_specular() || depth + 1 == view.max_depth) {
            let n = bsdf.shading_normal();
            features = Some(FeatureSample {
                albedo: feature_albedo(throughput / eta_scale * bsdf.feature_albedo()),
                normal: facing(ray.direction, n),
            });
        }
        let specular = is_chain_vertex(&bsdf, hit.kind, view.method);
        let light_traced = caustic.is_some_and(|k| k > 0) && hit.kind != HitKind::Plane;
        caustic = caustic.filter(|_| specular).map(|k| k + 1);
        if let Some(emitted) = bsdf.emitted().filter(|_| !light_traced) {
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
        // Photons arriving at D after S… (`Method::Photons`), past the camera's first hit (light
        // tracing's), where the camera sees D through S… only or D is Lambertian; for paths
        // that reach a light with the camera's rays left: at most `max_depth − depth − 2` S.
        let gathered = match view.photons {
            Some(map) if depth > 0 && !specular && (through_chain || bsdf.is_lambertian()) => {
                let max_chain = view.max_depth.saturating_sub(depth + 2);
                radiance += throughput * map.gather(&s, &bsdf, max_chain);
                true
            }
            _ => false,
        };
        through_chain &= specular;
        // Only a vertex the path continues from needs the hit point's error bound.
        let err = point_error(view.geometry, &hit, s.p);
        let dimension = 1 + depth * BOUNCE_DIMENSIONS;
        let beyond = medium.beyond(material, ray.direction, s.n);
        // A narrow glossy vertex of a chain the photons own: its light samples are theirs too.
        let owned = caustic.is_some_and(|k| k > 0);
        if sample_lights && bsdf.samples_lights() && !owned {
            sampler.seek(dimension + LIGHT_CHOICE_DIMENSION);
            let vertex = Vertex {
                surface: &s,
                err,
                bsdf: &bsdf,
                dimension,
                arriving: ray.direction,
                media: (medium, beyond),
            };
            radiance += throughput * direct_light(lanes, view, vertex, sampler, stats);
        }
        sampler.seek(dimension + BSDF_DIMENSION);
        let Some(scatter) = bsdf.sample(sampler) else {
            break;
        };
        if ((depth == 0 && light_traces_first_hit) || gathered) && !specular {
            caustic = scatter.pdf.map(|_| 0);
        }
        previous = scatter.pdf.map(|pdf| (s.p, pdf));
        medium = medium.leaving(beyond, ray.direction, s.n, scatter.direction);
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
    /// Direction of the ray that hit the surface.
    arriving: Vec3,
    /// The medium that ray travelled through, and the one beyond the surface
    /// ([`Medium::beyond`]).
    media: (Medium, Medium),
}

/// One light sample at a vertex's surface `s` for a ray arriving along `d`: emitted radiance
/// from a point sampled on an emitter, times the BSDF and cosine, over the light density,
/// MIS-weighted against BSDF sampling under `Method::Mis` (a point or spot light's irradiance
/// over its selection probability, at full weight).
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
            // Only a masked scene has emitters that are absent in places.
            let emitted = if view.masked {
                emitter.emitted_where_present(wi, light.n, light.uv)
            } else {
                emitter.emitted(wi, light.n, light.uv)
            };
            // Shadow ray between the two offset points, so neither surface can block it.
            let from = spawn(s.p, s.n, err, wi).origin;
            let end = spawn_origin(light.p, facing(wi, light.n), light.err);
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
        Sampled::Punctual(light) => {
            // The shadow ray ends at the light itself: a point on no surface.
            let wi = (light.position - s.p).normalize();
            let from = spawn(s.p, s.n, err, wi).origin;
            let span = light.position - from;
            let length = span.length();
            if !(length > 0.0 && length.is_finite()) {
                return Vec3::ZERO;
            }
            let shadow = Ray::new(from, span / length);
            (
                wi,
                light.irradiance,
                light.pdf,
                (shadow, length, Some(light.position)),
            )
        }
    };
    // No BSDF-sampled ray finds a delta light: its sample is the only estimate, at full weight.
    let delta = matches!(sampled, Sampled::Punctual(_));
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
    let (shadow_ray, length, end) = shadow;
    let transparency = TRANSPARENCY_DIMENSION + 2 * bounce + 1;
    if blocked(
        lanes,
        view,
        shadow_ray,
        (length, end),
        (&mut *sampler, transparency),
        stats,
    ) {
        return Vec3::ZERO;
    }
    let weight = if matches!(
        view.method,
        Method::Mis | Method::Caustics | Method::Photons
    ) && !delta
    {
        power_heuristic(pdf_light, pdf_bsdf)
    } else {
        1.0
    };
    let (here, beyond) = vertex.media;
    let through = here.leaving(beyond, vertex.arriving, s.n, wi);
    // A shadow ray to a distant light has no length to attenuate over (see [`Medium`]).
    if through.is_clear() || !length.is_finite() {
        f_cos * emitted * (weight / pdf_light)
    } else {
        f_cos * emitted * through.transmittance(length) * (weight / pdf_light)
    }
}
