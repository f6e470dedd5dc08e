//! Where light paths start: a light chosen by its power towards the perfect specular surfaces,
//! and a ray from it aimed at them. No ECS here.
//!
//! The surfaces that may be perfect mirrors or glass (under `Method::Photons` also narrow
//! glossy conductors: [`may_be_chain`]) are bounded each by
//! a sphere (the targets, [`super::targets`]): an entity that is one sphere is its own, any
//! other the sphere around its box. Every ray that meets such a surface first passes through
//! its target, so aiming only at targets loses no path light tracing owns. A target is chosen
//! by `r²`, then:
//! - from a distant light (sun, environment map): a direction sampled as next-event estimation
//!   samples it, then a point on the disk across the target, the ray coming from beyond the
//!   scene. Its density per unit area across the ray is the mixture over every disk the line
//!   crosses: `crossed / (π Σ r²)`;
//! - from an emitting triangle: a point uniform by area; from an emitting sphere, a point
//!   uniform on the cap of it that can see the target (the rest sends it nothing); from a
//!   point or spot light, its position. Then a direction uniform in the cone of the target
//!   seen from there (the whole sphere from inside it). The density per unit area and
//!   steradian is the mixture over the targets whose cones hold the direction:
//!   `Σ (r² / Σ r²) · p_area / Ω`.
//!
//! The targets met by the first ray are found by the targets' tree, so a light path costs the
//! targets its first ray meets and the tree's depth, not a pass over every target.
//! Infinite planes are neither targets nor sources: paths through a mirror plane, and light an
//! emitting plane sends, stay with the path tracer (see the integrator's `is_chain_vertex`).

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use super::super::integrator::spawn;
use super::targets::{Reach, Targets, cone_solid_angle};
use crate::geometry::layout::Layout;
use crate::geometry::packed::{Geometry, HitKind};
use crate::geometry::ray::Ray;
use crate::geometry::sphere::{
    sample_sphere_area, sample_sphere_cone, sphere_point_error, sphere_uv,
};
use crate::geometry::store::{SphereStore, TriangleStore};
use crate::geometry::triangle::{sample_triangle_area, triangle_point_error};
use crate::lights::LightSet;
use crate::lights::area::{Emitter, radiance_scale};
use crate::shading::material::Material;
use crate::shading::microfacet::{alpha_from_roughness, is_narrow_alpha, is_specular_alpha};
use crate::shading::pbr::Pbr;
use crate::shading::sampler::Sampler;
use crate::shading::sampling::{Frame, concentric_disk};
use crate::shading::texture::TexCoords;

/// Whether a surface of material `m` may be a chain vertex somewhere (the integrator's
/// `is_chain_vertex`): a perfect mirror or smooth glass
/// ([`crate::shading::bsdf::Bsdf::is_specular`] at some point), with `glossy` also a narrow
/// glossy conductor ([`crate::shading::bsdf::Bsdf::is_narrow_glossy`]). Conservative: a
/// textured metallic–roughness material counts.
pub fn may_be_chain(m: &Material, glossy: bool) -> bool {
    match m {
        Material::Glossy { roughness, .. } => {
            let alpha = alpha_from_roughness(*roughness);
            is_specular_alpha(alpha) || (glossy && is_narrow_alpha(alpha))
        }
        Material::Dielectric { roughness, .. } => {
            is_specular_alpha(alpha_from_roughness(*roughness))
        }
        Material::Metal { roughness, .. } => *roughness == 0.0,
        Material::Pbr {
            metallic,
            roughness,
            metallic_roughness,
            ..
        } => metallic_roughness.is_some() || Pbr::new(Vec3::ZERO, *metallic, *roughness).is_delta(),
        Material::Transmissive {
            glass,
            base,
            texture,
            ..
        } => {
            may_be_chain(glass, glossy)
                || may_be_chain(base, glossy)
                || texture
                    .as_ref()
                    .is_some_and(|t| may_be_chain(&t.opaque, glossy))
        }
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
    /// Point or spot light `k` of the light set ([`LightSet::punctual`]).
    Punctual(usize),
}

/// The lights and targets of a scene, for starting light paths.
#[derive(Clone, Debug, Default)]
pub struct Sources {
    /// Bounding spheres of the entities that may be perfect specular.
    targets: Targets,
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
    /// The targets and sources of a scene, its materials and each owner's material given; empty
    /// (nothing to trace) without a finite surface that may be a chain vertex ([`may_be_chain`],
    /// with `glossy`) or without a light. Cost `O(n log n)` in the primitives.
    pub fn new<L: Layout>(
        geometry: &Geometry<L>,
        (materials, owner_material): (&[Material], &[u32]),
        lights: &LightSet,
        glossy: bool,
    ) -> Self {
        let material = |owner: u32| {
            owner_material
                .get(owner as usize)
                .and_then(|&m| materials.get(m as usize))
        };
        let targets = Targets::new(targets(geometry, &|owner| {
            material(owner).is_some_and(|m| may_be_chain(m, glossy))
        }));
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
            sources.push(Source::Emitter(emitter));
            weights.push(f64::from(
                emitter.area() * radiance_scale(&emission) * targets.share_seen_from(centroid),
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
        for (k, light) in lights.distant().iter().enumerate() {
            sources.push(Source::Distant(k));
            weights.push(f64::from(light.power(1.0)) * f64::from(targets.area()));
        }
        for (k, light) in lights.punctual().iter().enumerate() {
            sources.push(Source::Punctual(k));
            weights.push(f64::from(
                light.power() * targets.share_seen_from(light.position),
            ));
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
        Self {
            targets,
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

    /// Summed `r²` of the targets' bounding spheres.
    pub fn target_area(&self) -> f32 {
        self.targets.area()
    }

    /// A light path's first ray, from the sampler's next numbers; `None` where the light sends
    /// nothing that way. The target aimed at is chosen by `r²`; the density of what was sampled
    /// sums over every target the first ray (its line, from a distant light) meets, found by
    /// the targets' tree.
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
        let (j, chosen) = self.targets.choose(sampler.next_1d());
        let (c, r) = self.targets.get(j);
        let area = self.targets.area();
        match self.sources[k] {
            Source::Distant(d) => {
                let light = lights.distant().get(d)?;
                let u = sampler.next_2d();
                let (towards, radiance, pdf) = light.sample(u, || sampler.next_2d())?;
                let (t, b) = towards.any_orthonormal_pair();
                let disk = r * concentric_disk(sampler.next_2d());
                let q = c + disk.x * t + disk.y * b;
                let mut crossed = 1u32;
                self.targets
                    .for_each_met(q, towards, Reach::Line, j, |_| crossed += 1);
                let density = pmf * pdf * crossed as f32 / (PI * area);
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
                let two_sided = material.emission().is_some_and(|m| m.two_sided);
                let on = point_on(geometry, &e, (c, r), two_sided, sampler.next_2d());
                let direction = towards_target(c, r, on.p, sampler.next_2d())?;
                let term = |k: usize, (c, r): (Vec3, f32)| {
                    let w = if k == j { chosen } else { r * r / area };
                    w * on.density(c, r, k == j) / cone_solid_angle(c, r, on.p)
                };
                let mut sum = term(j, (c, r));
                self.targets
                    .for_each_met(on.p, direction, Reach::Ray, j, |k| {
                        sum += term(k, self.targets.get(k));
                    });
                let emitted = material.emitted_where_present(-direction, on.n, on.uv);
                let density = pmf * sum;
                let beta = emitted * (on.n.dot(direction).abs() / density);
                (density > 0.0 && emitted != Vec3::ZERO).then(|| Emitted {
                    ray: spawn(on.p, on.n, on.err, direction),
                    beta,
                })
            }
            Source::Punctual(i) => {
                let light = lights.punctual().get(i)?;
                let p = light.position;
                let direction = towards_target(c, r, p, sampler.next_2d())?;
                let mut sum = chosen / cone_solid_angle(c, r, p);
                self.targets.for_each_met(p, direction, Reach::Ray, j, |k| {
                    let (c, r) = self.targets.get(k);
                    sum += r * r / area / cone_solid_angle(c, r, p);
                });
                let intensity = light.intensity_towards(direction);
                let density = pmf * sum;
                (density > 0.0 && intensity != Vec3::ZERO).then(|| Emitted {
                    ray: Ray::new(p, direction),
                    beta: intensity / density,
                })
            }
        }
    }
}

/// A unit direction from `p` uniform in the cone of the sphere (`c`, `r`) (over all directions
/// from inside it).
fn towards_target(c: Vec3, r: f32, p: Vec3, u: Vec2) -> Option<Vec3> {
    let direction = if (c - p).length_squared() <= r * r {
        sample_sphere_area(u)
    } else {
        (sample_sphere_cone(c, r, p, u).0 - p).normalize()
    };
    direction.is_finite().then_some(direction)
}

/// A point sampled on an emitter.
struct OnEmitter {
    p: Vec3,
    /// Unit geometric normal.
    n: Vec3,
    uv: TexCoords,
    err: Vec3,
    /// A sphere emitter's centre and radius (`None` for a triangle, sampled by area).
    sphere: Option<(Vec3, f32)>,
    /// Whether the emitter sends light from both sides (then a sphere is sampled whole).
    two_sided: bool,
    /// `1 / area` of a triangle.
    inv_area: f32,
}

impl OnEmitter {
    /// Density per unit area of this point when aiming at the target (`c`, `r`): a triangle is
    /// sampled uniformly; a sphere on the cap that can see the target ([`cap`]); `chosen` says
    /// the point was sampled for this target (so it is on its cap, whatever rounding says).
    fn density(&self, c: Vec3, r: f32, chosen: bool) -> f32 {
        let Some((centre, radius)) = self.sphere else {
            return self.inv_area;
        };
        let (axis, cos_min) = cap(centre, radius, c, r, self.two_sided);
        let n = (self.p - centre) / radius;
        if chosen || n.dot(axis) > cos_min {
            1.0 / (2.0 * PI * radius * radius * (1.0 - cos_min))
        } else {
            0.0
        }
    }
}

/// The cap of an emitting sphere (centre `ce`, radius `re`) whose points can send light to the
/// sphere (`c`, `r`): unit axis and the cosine its normals exceed. A point `ce + re n` sees part
/// of the target in front of its tangent plane only if `n · (c − ce) − re > −r`; the whole
/// sphere where that bound does not cut it (a target around or at the emitter's centre) or
/// where the emitter also sends light inwards (`two_sided`).
fn cap(ce: Vec3, re: f32, c: Vec3, r: f32, two_sided: bool) -> (Vec3, f32) {
    let to = c - ce;
    let d = to.length();
    let cos_min = if d > 0.0 { (re - r) / d } else { -1.0 };
    if two_sided || !(cos_min > -1.0 && cos_min < 0.999) || !d.is_finite() {
        (Vec3::Z, -1.0)
    } else {
        (to / d, cos_min)
    }
}

/// A point on emitter `e` aimed at the target (`c`, `r`): uniform by area on a triangle, uniform
/// on the cap of a sphere that can see the target ([`cap`]).
fn point_on<L: Layout>(
    geometry: &Geometry<L>,
    e: &Emitter,
    (c, r): (Vec3, f32),
    two_sided: bool,
    u: Vec2,
) -> OnEmitter {
    let i = e.index as usize;
    let triangle = |p: Vec3, n: Vec3, uv: TexCoords, err: Vec3| OnEmitter {
        p,
        n,
        uv,
        err,
        sphere: None,
        two_sided,
        inv_area: 1.0 / e.area(),
    };
    match e.kind {
        HitKind::Sphere => {
            let (centre, radius) = geometry.spheres.get(i);
            let (axis, cos_min) = cap(centre, radius, c, r, two_sided);
            let cos = 1.0 - u.x * (1.0 - cos_min);
            let sin = (1.0 - cos * cos).max(0.0).sqrt();
            let phi = 2.0 * PI * u.y;
            let local = Vec3::new(sin * phi.cos(), sin * phi.sin(), cos);
            let n = Frame::from_normal(axis).to_world(local).normalize();
            let uv = sphere_uv(geometry.sphere_frame[i].transpose() * n);
            OnEmitter {
                p: centre + radius * n,
                n,
                uv: uv.into(),
                err: sphere_point_error(centre, radius),
                sphere: Some((centre, radius)),
                two_sided,
                inv_area: 0.0,
            }
        }
        HitKind::Instance { triangle: t } => {
            let [_, b1, b2] = sample_triangle_area(u);
            let s = geometry.instances.surface(e.index, t, b1, b2);
            let err = geometry.instances.point_error(e.index, t, b1, b2);
            triangle(s.p, s.n, s.tex_coords(), err)
        }
        HitKind::Triangle | HitKind::Plane => {
            let b = sample_triangle_area(u);
            let [a, bv, cv] = geometry.triangles.get(i);
            let [ta, tb, tc] = geometry.triangle_uv[i];
            let p = b[0] * a + b[1] * bv + b[2] * cv;
            let uv = b[0] * ta + b[1] * tb + b[2] * tc;
            let err = triangle_point_error([a, bv, cv], b);
            triangle(p, geometry.triangle_normal[i], uv.into(), err)
        }
    }
}

/// Bounding spheres of the entities whose owner `specular` says may be perfect specular, in
/// owner order: an entity that is one sphere is its own target; any other is bounded by the
/// sphere around its finite primitives' box. Widened a little so that rounding cannot put a
/// surface point outside.
fn targets<L: Layout>(geometry: &Geometry<L>, specular: &dyn Fn(u32) -> bool) -> Vec<(Vec3, f32)> {
    let owners = geometry
        .sphere_owner
        .iter()
        .chain(&geometry.triangle_owner)
        .copied()
        .chain((0..geometry.instances.len()).map(|i| geometry.instances.get(i).owner))
        .max()
        .map_or(0, |m| m as usize + 1);
    let mut bounds: Vec<Option<Bound>> = vec![None; owners];
    let mut grow = |owner: u32, add: Bound| {
        if specular(owner) {
            let b = &mut bounds[owner as usize];
            *b = Some(b.map_or(add, |b| b.union(add)));
        }
    };
    for (i, &owner) in geometry.sphere_owner.iter().enumerate() {
        let (c, r) = geometry.spheres.get(i);
        grow(owner, Bound::Sphere(c, r));
    }
    for (i, &owner) in geometry.triangle_owner.iter().enumerate() {
        let [a, b, c] = geometry.triangles.get(i);
        grow(owner, Bound::Box(a.min(b).min(c), a.max(b).max(c)));
    }
    for i in 0..geometry.instances.len() {
        let owner = geometry.instances.get(i).owner;
        if !specular(owner) {
            continue;
        }
        for t in 0..geometry.instances.get(i).blas.len() as u32 {
            let [a, b, c] = geometry.instances.world_triangle(i as u32, t);
            grow(owner, Bound::Box(a.min(b).min(c), a.max(b).max(c)));
        }
    }
    bounds
        .into_iter()
        .flatten()
        .map(|b| {
            let (centre, radius) = match b {
                Bound::Sphere(c, r) => (c, r),
                Bound::Box(lo, hi) => (0.5 * (lo + hi), 0.5 * (hi - lo).length()),
            };
            let pad = 1e-4 * (radius + centre.abs().max_element());
            (centre, radius + pad)
        })
        .collect()
}

/// What an entity's primitives so far fill: one sphere, or a box.
#[derive(Clone, Copy, Debug)]
enum Bound {
    Sphere(Vec3, f32),
    Box(Vec3, Vec3),
}

impl Bound {
    fn corners(self) -> (Vec3, Vec3) {
        match self {
            Self::Sphere(c, r) => (c - Vec3::splat(r), c + Vec3::splat(r)),
            Self::Box(lo, hi) => (lo, hi),
        }
    }

    /// The box around both.
    fn union(self, other: Self) -> Self {
        let ((a, b), (c, d)) = (self.corners(), other.corners());
        Self::Box(a.min(c), b.max(d))
    }
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI as PI64;

    use glam::Mat3;

    use super::*;
    use crate::geometry::packed::Primitive;
    use crate::lights::punctual::PunctualLight;
    use crate::shading::rng::Rng;
    use crate::shading::texture::Texture;
    use crate::sky::Sky;
    use crate::sky::sun::Sun;

    /// Two mirror balls whose cones, seen from the lights below, overlap.
    const BALLS: [(Vec3, f32); 2] = [(Vec3::ZERO, 1.0), (Vec3::new(1.5, 0.5, 0.0), 0.7)];

    fn sphere(center: Vec3, radius: f32) -> Primitive {
        Primitive::Sphere {
            center,
            radius,
            frame: Mat3::IDENTITY,
        }
    }

    fn mirror() -> Material {
        Material::Metal {
            albedo: Texture::Constant(Vec3::ONE),
            roughness: 0.0,
        }
    }

    /// Mean and standard error, over `n` light paths, of the flux (red channel) each first
    /// ray carries into each ball: its weight where it meets the ball, whatever else it meets.
    fn flux_into_balls(
        sources: &Sources,
        g: &Geometry,
        materials: &[Material],
        lights: &LightSet,
        n: u64,
    ) -> [(f64, f64); 2] {
        let mut sum = [(0.0f64, 0.0f64); 2];
        for k in 0..n {
            let mut rng = Rng::for_sample(11, k, 0);
            let Some(e) = sources.emit(g, materials, lights, &mut rng) else {
                continue;
            };
            for (b, &(c, r)) in BALLS.iter().enumerate() {
                if sphere_met_ray(c, r, e.ray.origin, e.ray.direction) {
                    let v = f64::from(e.beta.x);
                    sum[b].0 += v;
                    sum[b].1 += v * v;
                }
            }
        }
        sum.map(|(s, s2)| {
            let mean = s / n as f64;
            (mean, ((s2 / n as f64 - mean * mean) / n as f64).sqrt())
        })
    }

    fn sphere_met_ray(c: Vec3, r: f32, o: Vec3, d: Vec3) -> bool {
        let to = c - o;
        to.dot(d) > 0.0 && d.cross(to).length_squared() <= r * r
    }

    /// Solid angle of a ball seen from `p`, in f64.
    fn solid_angle(p: Vec3, (c, r): (Vec3, f32)) -> f64 {
        let d = f64::from((c - p).length());
        2.0 * PI64 * (1.0 - (1.0 - (f64::from(r) / d).powi(2)).sqrt())
    }

    #[test]
    fn a_glossy_material_is_a_target_where_its_bsdf_is_a_chain_vertex() {
        // Targets must cover every surface the light paths follow (see the module's notes):
        // a `Glossy` material may be a chain vertex exactly where its BSDF is a perfect
        // mirror or, with glossy chains, a narrow glossy conductor; sunlit.ron's gold ball
        // (roughness 0.3) is one only with them, a ball of roughness 0.6 never.
        let glossy = |roughness: f32| Material::Glossy {
            albedo: Texture::Constant(Vec3::ONE),
            roughness,
        };
        for step in 0..=100 {
            let m = glossy(step as f32 / 100.0);
            let bsdf = m.bsdf_at(-Vec3::Z, Vec3::Z, Vec2::ZERO);
            assert_eq!(may_be_chain(&m, false), bsdf.is_specular(), "{step}");
            let chain = bsdf.is_specular() || bsdf.is_narrow_glossy();
            assert_eq!(may_be_chain(&m, true), chain, "{step}");
        }
        assert!(!may_be_chain(&glossy(0.3), false) && may_be_chain(&glossy(0.3), true));
        assert!(!may_be_chain(&glossy(0.6), true));
        assert!(may_be_chain(&mirror(), false));
    }

    #[test]
    fn light_paths_carry_the_flux_each_light_sends_into_each_ball() {
        // The flux into a ball, independent of how light paths are aimed: from a point light
        // of intensity I, I Ω; from a small spherical lamp of radiance L and radius ρ (an
        // isotropic intensity L π ρ² seen from afar; ρ/d = 0.006 makes the difference ~1e-5),
        // L π ρ² Ω; from a sun of radiance L and solid angle Ωs, L Ωs π r² (a parallel beam
        // through the ball's cross-section). The balls' cones overlap, so the mixture
        // density over both targets is what makes the sums come out.
        let lamp = Vec3::new(0.3, 8.0, 0.2);
        let point = Vec3::new(3.0, 6.0, 1.0);
        let sun = Sun::new(
            Vec3::new(0.3, 1.0, 0.2),
            3f32.to_radians(),
            Vec3::splat(1000.0),
        );
        let materials = [
            mirror(),
            Material::Light {
                emit: Texture::Constant(Vec3::ONE),
                intensity: 100.0,
                two_sided: false,
            },
        ];
        let balls: Vec<(u32, Primitive)> = BALLS.iter().map(|&(c, r)| (0, sphere(c, r))).collect();
        let mut with_lamp = balls.clone();
        with_lamp.push((1, sphere(lamp, 0.05)));
        let owners = [0, 1];
        let cases: Vec<(Geometry, LightSet, [f64; 2])> = vec![
            {
                let g = Geometry::build(&with_lamp);
                let set = LightSet::build(&g, &materials, &owners);
                let i = 100.0 * PI64 * 0.05f64.powi(2);
                (g, set, BALLS.map(|b| i * solid_angle(lamp, b)))
            },
            {
                let g = Geometry::build(&balls);
                let light = PunctualLight::point(point, Vec3::splat(2.0));
                let set =
                    LightSet::build_with_lights(&g, &materials, &owners, &Sky::default(), &[light]);
                (g, set, BALLS.map(|b| 2.0 * solid_angle(point, b)))
            },
            {
                let g = Geometry::build(&balls);
                let sky = Sky {
                    environment: None,
                    sun: Some(sun),
                };
                let set = LightSet::build_with_sky(&g, &materials, &owners, &sky);
                let e = 1000.0 * f64::from(sun.solid_angle());
                (g, set, BALLS.map(|(_, r)| e * PI64 * f64::from(r).powi(2)))
            },
        ];
        for (what, (g, set, want)) in ["lamp", "point", "sun"].iter().zip(&cases) {
            let sources = Sources::new(g, (&materials, &owners), set, false);
            let got = flux_into_balls(&sources, g, &materials, set, 200_000);
            for b in 0..2 {
                let (mean, se) = got[b];
                assert!(
                    (mean - want[b]).abs() <= 4.0 * se && se < 0.01 * want[b],
                    "{what}, ball {b}: {mean} ± {se}, expected {}",
                    want[b]
                );
            }
        }
    }

    #[test]
    fn a_ball_is_its_own_target_and_a_lamp_aims_from_the_side_that_sees_it() {
        // From a spherical lamp 10 radii of the ball away, most light paths' first rays meet
        // the ball (90 %; the rest leave the cap's rim facing away): the target is the ball
        // itself (its box's sphere, √3 wider, would waste two thirds) and the lamp's points
        // are drawn on the side that can see it (half the lamp faces away): about 1 in 6
        // otherwise.
        let materials = [
            mirror(),
            Material::Light {
                emit: Texture::Constant(Vec3::ONE),
                intensity: 1.0,
                two_sided: false,
            },
        ];
        let g = Geometry::build(&[
            (0, sphere(Vec3::ZERO, 1.0)),
            (1, sphere(Vec3::Y * 10.0, 0.5)),
        ]);
        let set = LightSet::build(&g, &materials, &[0, 1]);
        let sources = Sources::new(&g, (&materials, &[0, 1]), &set, false);
        let n = 4000;
        let met = (0..n)
            .filter(|&k| {
                let mut rng = Rng::for_sample(3, k, 0);
                sources
                    .emit(&g, &materials, &set, &mut rng)
                    .is_some_and(|e| sphere_met_ray(Vec3::ZERO, 1.0, e.ray.origin, e.ray.direction))
            })
            .count();
        assert!(
            met as f64 > 0.8 * n as f64,
            "{met} of {n} light paths meet the ball"
        );
    }
}
