//! Where light paths start: a light chosen by its power towards the perfect specular surfaces,
//! and a ray from it aimed at them. No ECS here.
//!
//! The surfaces that may be perfect mirrors or glass ([`may_be_specular`]) are bounded each by
//! a sphere around its entity's box (the targets). Every ray that meets such a surface first
//! passes through its target, so aiming only at targets loses no path light tracing owns:
//! - from a distant light (sun, environment map): a direction sampled as next-event estimation
//!   samples it, then a point on the disk across one target (chosen by area, πr²), the ray
//!   coming from beyond the scene. Its density per unit area across the ray is the mixture over
//!   every disk the line crosses: `crossed / (π Σ r²)`;
//! - from an emitting sphere or triangle: a point uniform by area, then a direction uniform in
//!   the cone of one target seen from there (chosen by solid angle Ω; the whole sphere from
//!   inside it). Its density per steradian is `cones containing it / Σ Ω`.
//!
//! Infinite planes are neither targets nor sources: paths through a mirror plane, and light an
//! emitting plane sends, stay with the path tracer (see the integrator's `is_chain_vertex`).

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use super::super::integrator::spawn;
use crate::geometry::layout::Layout;
use crate::geometry::packed::{Geometry, HitKind};
use crate::geometry::ray::Ray;
use crate::geometry::sphere::{
    cone_one_minus_cos, sample_sphere_area, sample_sphere_cone, sphere_point_error, sphere_uv,
};
use crate::geometry::store::{SphereStore, TriangleStore};
use crate::geometry::triangle::{sample_triangle_area, triangle_point_error};
use crate::lights::LightSet;
use crate::lights::area::{Emitter, radiance_scale};
use crate::shading::material::Material;
use crate::shading::microfacet::{alpha_from_roughness, is_specular_alpha};
use crate::shading::pbr::Pbr;
use crate::shading::sampler::Sampler;
use crate::shading::sampling::concentric_disk;
use crate::shading::texture::TexCoords;

/// Whether a surface of material `m` may be a perfect mirror or smooth glass somewhere
/// ([`crate::shading::bsdf::Bsdf::is_specular`] at some point): conservative, a textured
/// metallic–roughness material counts.
pub fn may_be_specular(m: &Material) -> bool {
    match m {
        Material::Dielectric { roughness, .. } | Material::Glossy { roughness, .. } => {
            is_specular_alpha(alpha_from_roughness(*roughness))
        }
        Material::Metal { roughness, .. } => *roughness == 0.0,
        Material::Pbr {
            metallic,
            roughness,
            metallic_roughness,
            ..
        } => metallic_roughness.is_some() || Pbr::new(Vec3::ZERO, *metallic, *roughness).is_delta(),
        Material::Diffuse { .. } | Material::Light { .. } => false,
    }
}

/// Where a light path starts.
#[derive(Clone, Copy, Debug)]
enum Source {
    /// An emitting sphere or triangle.
    Emitter(Emitter),
    /// Distant light `k` of the light set ([`LightSet::distant`]).
    Distant(usize),
}

/// The lights and targets of a scene, for starting light paths.
#[derive(Clone, Debug, Default)]
pub struct Sources {
    /// Bounding spheres (centre, radius) of the entities that may be perfect specular.
    targets: Vec<(Vec3, f32)>,
    /// Cumulative `r²` of the targets.
    target_area: Vec<f32>,
    sources: Vec<Source>,
    /// Cumulative selection weights of the sources.
    weights: Vec<f64>,
    /// Centre and radius of a sphere around every finite primitive.
    scene: (Vec3, f32),
}

/// A light path's first ray and its weight (flux over the densities it was sampled with).
pub struct Emitted {
    /// The ray, leaving the light.
    pub ray: Ray,
    /// Its weight.
    pub beta: Vec3,
}

impl Sources {
    /// The targets and sources of a scene; empty (nothing to trace) without a finite surface
    /// that may be perfect specular or without a light. Cost linear in the primitives.
    pub fn new<L: Layout>(
        geometry: &Geometry<L>,
        materials: &[Material],
        owner_material: &[u32],
        lights: &LightSet,
    ) -> Self {
        let material = |owner: u32| {
            owner_material
                .get(owner as usize)
                .and_then(|&m| materials.get(m as usize))
        };
        let targets = targets(geometry, &|owner| {
            material(owner).is_some_and(may_be_specular)
        });
        let Some((lo, hi)) = geometry.finite_bounds().filter(|_| !targets.is_empty()) else {
            return Self::default();
        };
        let scene = (0.5 * (lo + hi), 0.5 * (hi - lo).length());
        let mut sources = Vec::new();
        let mut weights = Vec::new();
        let mut add_emitter = |emitter: Emitter, centroid: Vec3| {
            let Some(emission) = materials
                .get(emitter.material as usize)
                .and_then(Material::emission)
            else {
                return;
            };
            let seen: f32 = targets
                .iter()
                .map(|&(c, r)| cone_solid_angle(c, r, centroid))
                .sum();
            let share = (seen / (4.0 * PI)).min(1.0);
            sources.push(Source::Emitter(emitter));
            weights.push(f64::from(
                emitter.area() * radiance_scale(&emission) * share,
            ));
        };
        for (i, &owner) in geometry.sphere_owner.iter().enumerate() {
            if let Some(&m) = owner_material.get(owner as usize) {
                let (c, r) = geometry.spheres.get(i);
                add_emitter(Emitter::sphere(i, c, r, m), c);
            }
        }
        for (i, &owner) in geometry.triangle_owner.iter().enumerate() {
            if let Some(&m) = owner_material.get(owner as usize) {
                let v = geometry.triangles.get(i);
                let centroid = (v[0] + v[1] + v[2]) / 3.0;
                add_emitter(Emitter::triangle(HitKind::Triangle, i, v, m), centroid);
            }
        }
        for i in 0..geometry.instances.len() {
            let inst = geometry.instances.get(i);
            let Some(&m) = owner_material.get(inst.owner as usize) else {
                continue;
            };
            if !materials.get(m as usize).is_some_and(Material::is_emissive) {
                continue;
            }
            for t in 0..inst.blas.len() as u32 {
                let v = geometry.instances.world_triangle(i as u32, t);
                let kind = HitKind::Instance { triangle: t };
                let centroid = (v[0] + v[1] + v[2]) / 3.0;
                add_emitter(Emitter::triangle(kind, i, v, m), centroid);
            }
        }
        let area: f32 = targets.iter().map(|&(_, r)| r * r).sum();
        for (k, light) in lights.distant().iter().enumerate() {
            sources.push(Source::Distant(k));
            weights.push(f64::from(light.power(1.0)) * f64::from(area));
        }
        if sources.is_empty() {
            return Self::default();
        }
        // Every source keeps a share, so none whose power estimate is off is left unsampled.
        let total: f64 = weights.iter().filter(|w| w.is_finite()).sum();
        let floor = if total > 0.0 {
            1e-3 * total / weights.len() as f64
        } else {
            1.0
        };
        let mut sum = 0.0;
        let weights = weights
            .iter()
            .map(|&w| {
                sum += if w.is_finite() { w.max(0.0) } else { 0.0 } + floor;
                sum
            })
            .collect();
        let mut sum = 0.0;
        let target_area = targets
            .iter()
            .map(|&(_, r)| {
                sum += r * r;
                sum
            })
            .collect();
        Self {
            targets,
            target_area,
            sources,
            weights,
            scene,
        }
    }

    /// Whether there is nothing to trace.
    pub fn is_empty(&self) -> bool {
        self.sources.is_empty()
    }

    /// Number of targets.
    pub fn targets(&self) -> usize {
        self.targets.len()
    }

    /// A light path's first ray, from four sampler dimensions' worth of numbers; `None` where
    /// the light sends nothing that way.
    pub fn emit<L: Layout>(
        &self,
        geometry: &Geometry<L>,
        materials: &[Material],
        lights: &LightSet,
        sampler: &mut impl Sampler,
    ) -> Option<Emitted> {
        let total = *self.weights.last()?;
        let x = f64::from(sampler.next_1d()) * total;
        let k = self
            .weights
            .partition_point(|&w| w <= x)
            .min(self.sources.len() - 1);
        let below = if k == 0 { 0.0 } else { self.weights[k - 1] };
        let pmf = ((self.weights[k] - below) / total) as f32;
        match self.sources[k] {
            Source::Distant(d) => {
                let light = lights.distant().get(d)?;
                let u = sampler.next_2d();
                let (towards, radiance, pdf) = light.sample(u, || sampler.next_2d())?;
                let (q, crossed) = self.point_across(towards, sampler);
                let density = pmf * pdf * crossed as f32 / (PI * self.target_area.last()?);
                // From beyond the scene's bounding sphere, whatever the point.
                let reach = self.scene.1 + (q - self.scene.0).length() + 1.0;
                let ray = Ray::new(q + towards * reach, -towards);
                (density > 0.0).then(|| Emitted {
                    ray,
                    beta: radiance / density,
                })
            }
            Source::Emitter(e) => {
                let material = materials.get(e.material as usize)?;
                let (p, n, uv, err) = point_on(geometry, &e, sampler.next_2d());
                let (direction, crossed, seen) = self.direction_from(p, sampler)?;
                let emitted = material.emitted(-direction, n, uv);
                let density = pmf / e.area() * crossed as f32 / seen;
                let beta = emitted * (n.dot(direction).abs() / density);
                (density > 0.0 && emitted != Vec3::ZERO).then(|| Emitted {
                    ray: spawn(p, n, err, direction),
                    beta,
                })
            }
        }
    }

    /// A point on the disk across a target chosen by area, perpendicular to unit `towards`,
    /// and the number of targets whose disks the line through it crosses (at least the one
    /// chosen).
    fn point_across(&self, towards: Vec3, sampler: &mut impl Sampler) -> (Vec3, u32) {
        let area = self.target_area.last().copied().unwrap_or(0.0);
        let x = sampler.next_1d() * area;
        let j = self
            .target_area
            .partition_point(|&a| a <= x)
            .min(self.targets.len() - 1);
        let (c, r) = self.targets[j];
        let (t, b) = towards.any_orthonormal_pair();
        let disk = r * concentric_disk(sampler.next_2d());
        let q = c + disk.x * t + disk.y * b;
        let crossed = 1 + self
            .targets
            .iter()
            .enumerate()
            .filter(|&(i, &(c, r))| i != j && towards.cross(c - q).length_squared() <= r * r)
            .count() as u32;
        (q, crossed)
    }

    /// A unit direction from `p` in the cone of a target chosen by solid angle, the number of
    /// targets' cones it is in (at least the one chosen) and the sum of their solid angles.
    fn direction_from(&self, p: Vec3, sampler: &mut impl Sampler) -> Option<(Vec3, u32, f32)> {
        let seen: f32 = self
            .targets
            .iter()
            .map(|&(c, r)| cone_solid_angle(c, r, p))
            .sum();
        let x = sampler.next_1d() * seen;
        let mut sum = 0.0;
        let j = self
            .targets
            .iter()
            .position(|&(c, r)| {
                sum += cone_solid_angle(c, r, p);
                sum > x
            })
            .unwrap_or(self.targets.len() - 1);
        let (c, r) = self.targets[j];
        let u = sampler.next_2d();
        let direction = if (c - p).length_squared() <= r * r {
            sample_sphere_area(u)
        } else {
            (sample_sphere_cone(c, r, p, u).0 - p).normalize()
        };
        if !direction.is_finite() {
            return None;
        }
        let crossed = 1 + self
            .targets
            .iter()
            .enumerate()
            .filter(|&(i, &(c, r))| i != j && in_cone(c, r, p, direction))
            .count() as u32;
        Some((direction, crossed, seen))
    }
}

/// Solid angle of the cone of directions from `p` that meet the sphere (`c`, `r`): 4π from
/// inside it.
fn cone_solid_angle(c: Vec3, r: f32, p: Vec3) -> f32 {
    let d2 = (c - p).length_squared();
    if d2 <= r * r {
        4.0 * PI
    } else {
        2.0 * PI * cone_one_minus_cos(r * r / d2)
    }
}

/// Whether the ray from `p` along unit `d` meets the sphere (`c`, `r`) (always from inside).
fn in_cone(c: Vec3, r: f32, p: Vec3, d: Vec3) -> bool {
    let to = c - p;
    to.length_squared() <= r * r || (to.dot(d) > 0.0 && d.cross(to).length_squared() <= r * r)
}

/// A point uniform by area on emitter `e`: the point, its unit geometric normal, texture
/// coordinates and error bound.
fn point_on<L: Layout>(
    geometry: &Geometry<L>,
    e: &Emitter,
    u: Vec2,
) -> (Vec3, Vec3, TexCoords, Vec3) {
    let i = e.index as usize;
    match e.kind {
        HitKind::Sphere => {
            let (c, r) = geometry.spheres.get(i);
            let n = sample_sphere_area(u);
            let uv = sphere_uv(geometry.sphere_frame[i].transpose() * n);
            (c + r * n, n, uv.into(), sphere_point_error(c, r))
        }
        HitKind::Instance { triangle } => {
            let [_, b1, b2] = sample_triangle_area(u);
            let s = geometry.instances.surface(e.index, triangle, b1, b2);
            let err = geometry.instances.point_error(e.index, triangle, b1, b2);
            (s.p, s.n, s.tex_coords(), err)
        }
        HitKind::Triangle | HitKind::Plane => {
            let b = sample_triangle_area(u);
            let [a, bv, c] = geometry.triangles.get(i);
            let [ta, tb, tc] = geometry.triangle_uv[i];
            let p = b[0] * a + b[1] * bv + b[2] * c;
            let uv = b[0] * ta + b[1] * tb + b[2] * tc;
            let err = triangle_point_error([a, bv, c], b);
            (p, geometry.triangle_normal[i], uv.into(), err)
        }
    }
}

/// Bounding spheres of the entities whose owner `specular` says may be perfect specular, from
/// their finite primitives' boxes, in owner order; widened a little so that rounding cannot
/// put a surface point outside.
fn targets<L: Layout>(geometry: &Geometry<L>, specular: &dyn Fn(u32) -> bool) -> Vec<(Vec3, f32)> {
    let owners = geometry
        .sphere_owner
        .iter()
        .chain(&geometry.triangle_owner)
        .copied()
        .chain((0..geometry.instances.len()).map(|i| geometry.instances.get(i).owner))
        .max()
        .map_or(0, |m| m as usize + 1);
    let mut boxes: Vec<Option<(Vec3, Vec3)>> = vec![None; owners];
    let mut grow = |owner: u32, lo: Vec3, hi: Vec3| {
        if specular(owner) {
            let b = &mut boxes[owner as usize];
            *b = Some(b.map_or((lo, hi), |(a, z)| (a.min(lo), z.max(hi))));
        }
    };
    for (i, &owner) in geometry.sphere_owner.iter().enumerate() {
        let (c, r) = geometry.spheres.get(i);
        grow(owner, c - Vec3::splat(r), c + Vec3::splat(r));
    }
    for (i, &owner) in geometry.triangle_owner.iter().enumerate() {
        let [a, b, c] = geometry.triangles.get(i);
        grow(owner, a.min(b).min(c), a.max(b).max(c));
    }
    for i in 0..geometry.instances.len() {
        let owner = geometry.instances.get(i).owner;
        if !specular(owner) {
            continue;
        }
        for t in 0..geometry.instances.get(i).blas.len() as u32 {
            let [a, b, c] = geometry.instances.world_triangle(i as u32, t);
            grow(owner, a.min(b).min(c), a.max(b).max(c));
        }
    }
    boxes
        .into_iter()
        .flatten()
        .map(|(lo, hi)| {
            let centre = 0.5 * (lo + hi);
            let radius = 0.5 * (hi - lo).length();
            let pad = 1e-4 * (radius + centre.abs().max_element());
            (centre, radius + pad)
        })
        .collect()
}
