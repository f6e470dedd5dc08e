//! Emitters as a sampling distribution, for next-event estimation. No ECS here.
//!
//! Every sphere and triangle whose material is a `Light` (or an emissive `Pbr`) is an emitter, and so is every triangle
//! of an emissive instanced mesh (placed through its instance transform, with its area in world
//! space). One is chosen with probability proportional to its power (area × intensity × mean
//! emitted colour), then a point on it:
//! - on a sphere, uniformly in the cone of directions it subtends from the shading point (only
//!   the visible cap), or uniformly by area from inside it;
//! - on a triangle, uniformly in the solid angle it subtends (a spherical triangle, Arvo 1995)
//!   when it is near (area ≥ 0.3 × squared distance) and that angle is neither tiny nor near a
//!   hemisphere, else uniformly by area.
//!
//! [`LightSet::sample`] and [`LightSet::pdf`] decide the strategy by the same rule, so the
//! density a BSDF-sampled hit is weighted with is the one the light sample would have had.
//! Infinite planes are never light-sampled: their emission is only found by BSDF sampling, at
//! full weight.
//!
//! The distant lights of the scene's [`Sky`] (an environment map, a sun) follow the emitters in
//! the table, with their power as the scene receives it ([`DistantLight::power`]); a sample of
//! one is a direction ([`DistantSample`]), and a path that leaves the scene finds them.
//!
//! The selection table holds cumulative counts out of 2²⁴, the resolution of the random numbers
//! (`Rng::next_f32`): an emitter's probability is its count / 2²⁴, exactly the frequency with
//! which a 24-bit `u_select` picks it, within 2⁻²⁴ of its share of the power (the running sum is
//! taken in f64). An emitter whose count rounds to 0 is never picked and has density 0, so it is
//! left to BSDF sampling at full weight.

use glam::{Vec2, Vec3};

use crate::geometry::layout::Layout;
use crate::geometry::packed::{Geometry, HitKind};
use crate::geometry::ray::gamma;
use crate::geometry::sphere::sphere_uv;
use crate::geometry::store::{SphereStore, TriangleStore};
use crate::shading::material::Material;
use crate::shading::sampling::{
    cone_one_minus_cos, sample_sphere_cone, sample_spherical_triangle, triangle_solid_angle,
};
use crate::shading::texture::Texture;
use crate::sky::{DistantLight, Sky};

/// Marks a primitive slot that is not an emitter.
const NONE: u32 = u32::MAX;

/// Resolution of the selection table: cumulative counts out of 2²⁴.
const SELECT_SCALE: u32 = 1 << 24;

/// Solid angles (sr) between which a triangle is sampled by solid angle; outside, by area.
/// Below the lower bound the spherical triangle's angles lose precision in f32 and area
/// sampling is as good; near 2π the construction breaks down (pbrt-v4's bounds).
const SPHERICAL_MIN: f32 = 3e-4;
const SPHERICAL_MAX: f32 = 6.22;
/// Triangles with area below this times their squared distance from the shading point are
/// sampled by area, without computing their solid angle.
const SPHERICAL_MIN_AREA_RATIO: f32 = 0.3;

#[derive(Clone, Copy, Debug, PartialEq)]
struct Emitter {
    kind: HitKind,
    index: u32,
    area: f32,
    material: u32,
    /// A sphere's centre, or the centroid of a triangle's world-space vertices: where the
    /// choice of strategy measures the distance from.
    centroid: Vec3,
}

/// A light sample: a point on an emitter or a direction towards a distant light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Sampled {
    /// A point on a surface emitter.
    Surface(LightSample),
    /// A direction towards a distant light.
    Distant(DistantSample),
}

/// A direction sampled towards a distant light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DistantSample {
    /// Unit direction towards the light.
    pub direction: Vec3,
    /// Radiance the light sends along it.
    pub radiance: Vec3,
    /// Probability density of the direction per steradian, selection included: what
    /// [`LightSet::distant_lookup`] gives for it.
    pub pdf: f32,
}

/// A point sampled on an emitter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// The point.
    pub p: Vec3,
    /// Unit geometric normal of the emitter at `p`.
    pub n: Vec3,
    /// Texture coordinates at `p`.
    pub uv: Vec2,
    /// Material index of the emitter.
    pub material: u32,
    /// Probability density of the direction from the shading point to `p`, per steradian
    /// (emitter selection included): what [`LightSet::pdf`] gives for the same point.
    pub pdf: f32,
    /// Absolute error bound of `p`, per component.
    pub err: Vec3,
}

/// How a point is chosen on one emitter from one shading point.
#[derive(Clone, Copy, Debug)]
enum Strategy {
    /// Uniformly by area.
    Area,
    /// Uniformly in a sphere's visible cone; `2π` times this is its solid angle.
    Cone { one_minus_cos: f32 },
    /// Uniformly in a triangle's solid angle; its world-space vertices, fetched (for an
    /// instance: transformed) once for both the choice and the sample.
    Spherical {
        solid_angle: f32,
        vertices: [Vec3; 3],
    },
}

/// The emitters of a scene with their selection probabilities.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LightSet {
    emitters: Vec<Emitter>,
    /// Cumulative selection counts out of [`SELECT_SCALE`], ending at it.
    cdf: Vec<u32>,
    /// Emitter index per sphere slot, or `NONE`.
    sphere_emitter: Vec<u32>,
    /// Emitter index per triangle slot, or `NONE`.
    triangle_emitter: Vec<u32>,
    /// Emitter index of triangle 0 of each instance slot (its triangles follow in order), or
    /// `NONE` if the instance does not emit.
    instance_emitter: Vec<u32>,
    /// The distant lights: entries `emitters.len() + k` of the table.
    distant: Vec<DistantLight>,
}

/// Mean of a texture's colour, estimated from a few texture coordinates (exact for constants).
fn mean_colour(t: &Texture) -> f32 {
    let grid = [0.125f32, 0.375, 0.625, 0.875];
    let mut sum = Vec3::ZERO;
    for u in grid {
        for v in grid {
            sum += t.eval(Vec2::new(u, v));
        }
    }
    (sum / 16.0).element_sum() / 3.0
}

/// Area of triangle `[a, b, c]`.
#[inline]
fn triangle_area([a, b, c]: [Vec3; 3]) -> f32 {
    0.5 * (b - a).cross(c - a).length()
}

impl Emitter {
    /// The triangle emitter `(kind, index)` with world-space vertices `v`.
    fn triangle(kind: HitKind, index: usize, v: [Vec3; 3], material: u32) -> Self {
        Self {
            kind,
            index: index as u32,
            area: triangle_area(v),
            material,
            centroid: (v[0] + v[1] + v[2]) * (1.0 / 3.0),
        }
    }
}

impl LightSet {
    /// Collects the emitters of `geometry` given each owner's material: cost linear in the
    /// number of primitives and emitting mesh triangles.
    pub fn build<L: Layout>(
        geometry: &Geometry<L>,
        materials: &[Material],
        owner_material: &[u32],
    ) -> Self {
        Self::build_with_sky(geometry, materials, owner_material, &Sky::default())
    }

    /// [`LightSet::build`] with the distant lights of `sky`, whose power is measured on the
    /// bounding sphere of the finite geometry (radius 1 if there is none).
    pub fn build_with_sky<L: Layout>(
        geometry: &Geometry<L>,
        materials: &[Material],
        owner_material: &[u32],
        sky: &Sky,
    ) -> Self {
        let power_of = |owner: u32| -> Option<(u32, f32)> {
            let m = *owner_material.get(owner as usize)?;
            match materials.get(m as usize)? {
                Material::Light {
                    emit, intensity, ..
                } => Some((m, intensity * mean_colour(emit))),
                pbr @ Material::Pbr {
                    emissive,
                    emissive_strength,
                    ..
                } if pbr.is_emissive() => Some((m, emissive_strength * mean_colour(emissive))),
                _ => None,
            }
        };
        let mut set = Self {
            sphere_emitter: vec![NONE; geometry.sphere_owner.len()],
            triangle_emitter: vec![NONE; geometry.triangle_owner.len()],
            instance_emitter: vec![NONE; geometry.instances.len()],
            ..Self::default()
        };
        let mut powers: Vec<f64> = Vec::new();
        // Adds an emitter, returning its index; one of no (or no finite) power is never picked.
        let mut add = |set: &mut Self, emitter: Emitter, power: f32| {
            let p = f64::from(emitter.area) * f64::from(power);
            powers.push(if p > 0.0 && p.is_finite() { p } else { 0.0 });
            set.emitters.push(emitter);
            (set.emitters.len() - 1) as u32
        };
        for (i, &owner) in geometry.sphere_owner.iter().enumerate() {
            if let Some((material, power)) = power_of(owner) {
                let (c, r) = geometry.spheres.get(i);
                let emitter = Emitter {
                    kind: HitKind::Sphere,
                    index: i as u32,
                    area: 4.0 * std::f32::consts::PI * r * r,
                    material,
                    centroid: c,
                };
                set.sphere_emitter[i] = add(&mut set, emitter, power);
            }
        }
        for (i, &owner) in geometry.triangle_owner.iter().enumerate() {
            if let Some((material, power)) = power_of(owner) {
                let v = geometry.triangles.get(i);
                let emitter = Emitter::triangle(HitKind::Triangle, i, v, material);
                set.triangle_emitter[i] = add(&mut set, emitter, power);
            }
        }
        for i in 0..geometry.instances.len() {
            let inst = geometry.instances.get(i);
            let Some((material, power)) = power_of(inst.owner) else {
                continue;
            };
            // The instance's triangles take consecutive emitter indices, so a hit finds its
            // emitter by offset.
            set.instance_emitter[i] = set.emitters.len() as u32;
            for t in 0..inst.blas.len() as u32 {
                let v = geometry.instances.world_triangle(i as u32, t);
                let kind = HitKind::Instance { triangle: t };
                add(&mut set, Emitter::triangle(kind, i, v, material), power);
            }
        }
        let distant = sky.lights();
        if !distant.is_empty() {
            let radius = geometry.finite_bounds().map_or(1.0, |(lo, hi)| {
                let r = 0.5 * (hi - lo).length();
                if r > 0.0 && r.is_finite() { r } else { 1.0 }
            });
            for light in &distant {
                let p = f64::from(light.power(radius));
                powers.push(if p > 0.0 && p.is_finite() { p } else { 0.0 });
            }
        }
        set.distant = distant;
        let total: f64 = powers.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            // Emitters with zero power (or none at all): nothing worth sampling.
            return Self {
                sphere_emitter: vec![NONE; set.sphere_emitter.len()],
                triangle_emitter: vec![NONE; set.triangle_emitter.len()],
                instance_emitter: vec![NONE; set.instance_emitter.len()],
                distant: set.distant,
                ..Self::default()
            };
        }
        let mut acc = 0.0f64;
        set.cdf = powers
            .iter()
            .map(|p| {
                acc += p;
                ((acc / total) * f64::from(SELECT_SCALE)).round() as u32
            })
            .collect();
        if let Some(last) = set.cdf.last_mut() {
            *last = SELECT_SCALE;
        }
        set
    }

    /// Whether there is nothing to sample.
    pub fn is_empty(&self) -> bool {
        self.cdf.is_empty()
    }

    /// Number of emitters (distant lights not included).
    pub fn len(&self) -> usize {
        self.emitters.len()
    }

    /// The brightest radiance (any channel) the distant lights send.
    pub fn sky_max_radiance(&self) -> f32 {
        self.distant
            .iter()
            .map(DistantLight::max_radiance)
            .fold(0.0, f32::max)
    }

    /// The distant lights, in the order [`LightSet::distant_lookup`] numbers them.
    pub fn distant(&self) -> &[DistantLight] {
        &self.distant
    }

    /// Radiance that distant light `k` sends along direction `d`, and the density per
    /// steradian with which [`LightSet::sample`] gives `d` towards it (selection included; 0
    /// if it is never sampled there).
    #[inline]
    pub fn distant_lookup(&self, k: usize, d: Vec3) -> (Vec3, f32) {
        let pmf = self.selection_pmf(self.emitters.len() + k);
        let (radiance, pdf) = self.distant[k].lookup(d);
        (radiance, pmf * pdf)
    }

    /// Probability that [`LightSet::select`] picks emitter `k` (0 for an index out of range).
    #[inline]
    pub fn selection_pmf(&self, k: usize) -> f32 {
        let Some(&hi) = self.cdf.get(k) else {
            return 0.0;
        };
        let lo = if k == 0 { 0 } else { self.cdf[k - 1] };
        (hi - lo) as f32 * (1.0 / SELECT_SCALE as f32)
    }

    /// The emitter that `u_select` ∈ [0, 1) picks, read at 24-bit resolution, with its
    /// selection probability; `None` if there are no emitters.
    #[inline]
    pub fn select(&self, u_select: f32) -> Option<(usize, f32)> {
        if self.cdf.is_empty() {
            return None;
        }
        let g = ((u_select * SELECT_SCALE as f32) as u32).min(SELECT_SCALE - 1);
        let k = self.cdf.partition_point(|&c| c <= g);
        Some((k, self.selection_pmf(k)))
    }

    /// How emitter `e` is sampled from shading point `p_ref`.
    #[inline(always)]
    fn strategy<L: Layout>(geometry: &Geometry<L>, e: &Emitter, p_ref: Vec3) -> Strategy {
        let i = e.index as usize;
        match e.kind {
            HitKind::Sphere => {
                let (c, r) = geometry.spheres.get(i);
                let dc2 = (c - p_ref).length_squared();
                if dc2 > r * r {
                    Strategy::Cone {
                        one_minus_cos: cone_one_minus_cos(r * r / dc2),
                    }
                } else {
                    Strategy::Area
                }
            }
            HitKind::Triangle | HitKind::Instance { .. } => {
                // Far from the shading point (area / distance² small), area sampling's density
                // hardly varies over the triangle: the spherical construction would cost more
                // than it saves.
                if e.area < SPHERICAL_MIN_AREA_RATIO * (e.centroid - p_ref).length_squared() {
                    return Strategy::Area;
                }
                let v = Self::vertices(geometry, e);
                let solid_angle = triangle_solid_angle(v, p_ref);
                if (SPHERICAL_MIN..=SPHERICAL_MAX).contains(&solid_angle) {
                    Strategy::Spherical {
                        solid_angle,
                        vertices: v,
                    }
                } else {
                    Strategy::Area
                }
            }
            HitKind::Plane => Strategy::Area,
        }
    }

    /// World-space vertices of a triangle emitter.
    #[inline]
    fn vertices<L: Layout>(geometry: &Geometry<L>, e: &Emitter) -> [Vec3; 3] {
        match e.kind {
            HitKind::Instance { triangle } => geometry.instances.world_triangle(e.index, triangle),
            _ => geometry.triangles.get(e.index as usize),
        }
    }

    /// Density per steradian, at `p_ref`, of the point `p` (unit normal `n`) on emitter `e`
    /// sampled by `strategy`, selection excluded.
    #[inline]
    fn density(e: &Emitter, strategy: Strategy, p_ref: Vec3, p: Vec3, n: Vec3) -> f32 {
        match strategy {
            Strategy::Area => {
                let to = p - p_ref;
                let dist2 = to.length_squared();
                let cos = (to.dot(n) / dist2.sqrt()).abs();
                dist2 / (e.area * cos)
            }
            Strategy::Cone { one_minus_cos } => 1.0 / (2.0 * std::f32::consts::PI * one_minus_cos),
            Strategy::Spherical { solid_angle, .. } => 1.0 / solid_angle,
        }
    }

    /// Samples a light seen from shading point `p_ref`: `u_select` picks it, `u` the point on
    /// it (or the direction towards a distant one); `jitter()` is asked for two more numbers
    /// only by a light that needs them (a map's texel). The numbers come from separate sampler
    /// dimensions: rescaling the remainder of `u_select` within the emitter's share into a point
    /// coordinate leaves an emitter with a count of c out of 2²⁴ only c distinct values (a lone
    /// triangle lamp would always give one edge).
    #[inline(always)]
    pub fn sample<L: Layout>(
        &self,
        geometry: &Geometry<L>,
        p_ref: Vec3,
        u_select: f32,
        u: Vec2,
        jitter: impl FnOnce() -> Vec2,
    ) -> Option<Sampled> {
        let (k, pmf) = self.select(u_select)?;
        let Some(&e) = self.emitters.get(k) else {
            let d = k - self.emitters.len();
            let light = self.distant.get(d)?;
            let direction = light.sample(u, jitter)?;
            // Value and density from the direction itself, as a path that leaves the scene
            // along it is weighed.
            let (radiance, pdf) = light.lookup(direction);
            let pdf = pmf * pdf;
            return (pdf > 0.0).then_some(Sampled::Distant(DistantSample {
                direction,
                radiance,
                pdf,
            }));
        };
        let i = e.index as usize;
        let strategy = Self::strategy(geometry, &e, p_ref);
        let (p, n, uv, err) = match e.kind {
            HitKind::Sphere => {
                let (c, r) = geometry.spheres.get(i);
                let n = match strategy {
                    Strategy::Cone { .. } => sample_sphere_cone(c, r, p_ref, u).1,
                    _ => {
                        let z = 1.0 - 2.0 * u.x;
                        let s = (1.0 - z * z).max(0.0).sqrt();
                        let phi = 2.0 * std::f32::consts::PI * u.y;
                        Vec3::new(s * phi.cos(), s * phi.sin(), z)
                    }
                };
                let uv = sphere_uv(geometry.sphere_frame[i].transpose() * n);
                (c + r * n, n, uv, gamma(6.0) * (c.abs() + Vec3::splat(r)))
            }
            HitKind::Triangle | HitKind::Instance { .. } => {
                let [b0, b1, b2] = match strategy {
                    Strategy::Spherical {
                        vertices,
                        solid_angle,
                    } => sample_spherical_triangle(vertices, p_ref, solid_angle, u)?,
                    _ => {
                        let su = u.x.sqrt();
                        let (b0, b1) = (1.0 - su, u.y * su);
                        [b0, b1, 1.0 - b0 - b1]
                    }
                };
                if let HitKind::Instance { triangle } = e.kind {
                    let s = geometry.instances.surface(e.index, triangle, b1, b2);
                    let err = geometry.instances.point_error(e.index, triangle, b1, b2);
                    (s.p, s.n, s.uv, err)
                } else {
                    let [a, b, c] = geometry.triangles.get(i);
                    let [ta, tb, tc] = geometry.triangle_uv[i];
                    let n = geometry.triangle_normal[i];
                    let err = gamma(7.0) * ((b0 * a).abs() + (b1 * b).abs() + (b2 * c).abs());
                    (
                        b0 * a + b1 * b + b2 * c,
                        n,
                        b0 * ta + b1 * tb + b2 * tc,
                        err,
                    )
                }
            }
            HitKind::Plane => return None,
        };
        Some(Sampled::Surface(LightSample {
            p,
            n,
            uv,
            material: e.material,
            pdf: pmf * Self::density(&e, strategy, p_ref, p, n),
            err,
        }))
    }

    /// Density per steradian with which [`LightSet::sample`], called at `p_ref`, picks the
    /// point `p` (unit geometric normal `n`) of primitive `(kind, index)`, as a BSDF-sampled
    /// ray from `p_ref` finds it; 0 if it is not a sampled emitter.
    #[inline(always)]
    pub fn pdf<L: Layout>(
        &self,
        geometry: &Geometry<L>,
        kind: HitKind,
        index: u32,
        p_ref: Vec3,
        p: Vec3,
        n: Vec3,
    ) -> f32 {
        let k = match kind {
            HitKind::Sphere => self.sphere_emitter.get(index as usize).copied(),
            HitKind::Triangle => self.triangle_emitter.get(index as usize).copied(),
            HitKind::Instance { triangle } => self
                .instance_emitter
                .get(index as usize)
                .filter(|&&base| base != NONE)
                .map(|&base| base + triangle),
            // Planes are infinite.
            HitKind::Plane => None,
        };
        let Some(k) = k.filter(|&k| k != NONE) else {
            return 0.0;
        };
        let pmf = self.selection_pmf(k as usize);
        if pmf == 0.0 {
            return 0.0;
        }
        let e = &self.emitters[k as usize];
        pmf * Self::density(e, Self::strategy(geometry, e, p_ref), p_ref, p, n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::packed::Primitive;

    /// Surface emitters never ask for the second pair of numbers.
    fn no_jitter() -> Vec2 {
        unreachable!("only a map's texel needs a jitter")
    }

    /// The surface point of a sample.
    fn surface(s: Option<Sampled>) -> LightSample {
        match s {
            Some(Sampled::Surface(s)) => s,
            other => panic!("expected a surface sample, got {other:?}"),
        }
    }

    fn light(intensity: f32) -> Material {
        Material::Light {
            emit: Texture::Constant(Vec3::ONE),
            intensity,
            two_sided: false,
        }
    }

    #[test]
    fn selection_is_proportional_to_power_and_pdfs_integrate_to_one() {
        // A unit-area square (two triangles) of intensity 1 and a sphere of area 4π·0.25 = π
        // of intensity 2: powers 1 and 2π.
        let sq = |p: [Vec3; 3]| Primitive::Triangle {
            p,
            uv: [Vec2::ZERO; 3],
        };
        let prims = vec![
            (0, sq([Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0)])),
            (0, sq([Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), Vec3::Y])),
            (
                1,
                Primitive::Sphere {
                    center: Vec3::new(5.0, 0.0, 0.0),
                    radius: 0.5,
                    frame: glam::Mat3::IDENTITY,
                },
            ),
            (
                2,
                Primitive::Sphere {
                    center: Vec3::new(9.0, 0.0, 0.0),
                    radius: 1.0,
                    frame: glam::Mat3::IDENTITY,
                },
            ),
        ];
        let g = Geometry::build(&prims);
        let materials = [light(1.0), light(2.0), Material::Dielectric { ior: 1.5 }];
        let set = LightSet::build(&g, &materials, &[0, 1, 2]);
        assert_eq!(set.len(), 3);
        let total = 1.0 + 2.0 * std::f32::consts::PI;
        // Selection probabilities (spheres first, then triangles) are the power shares and
        // sum to 1.
        let pmf: Vec<f32> = (0..3).map(|k| set.selection_pmf(k)).collect();
        assert!(
            (pmf[0] - 2.0 * std::f32::consts::PI / total).abs() < 1e-6,
            "{pmf:?}"
        );
        assert!((pmf[1] + pmf[2] - 1.0 / total).abs() < 1e-6);
        assert_eq!(pmf.iter().sum::<f32>(), 1.0);
        let far = Vec3::new(0.0, 0.0, 100.0);
        assert_eq!(
            set.pdf(
                &g,
                HitKind::Sphere,
                1,
                far,
                Vec3::new(9.0, 0.0, 1.0),
                Vec3::Z
            ),
            0.0,
            "glass is not an emitter"
        );

        // Sampled points lie on their emitter and report the density `pdf` gives the same point
        // when a ray from the shading point finds it.
        let mut rng = crate::shading::rng::Rng::new(1, 2);
        let p_ref = Vec3::new(0.5, 0.5, 3.0);
        for _ in 0..1000 {
            let s = surface(set.sample(
                &g,
                p_ref,
                rng.next_f32(),
                Vec2::new(rng.next_f32(), rng.next_f32()),
                no_jitter,
            ));
            if s.p.x > 2.0 {
                assert!(((s.p - Vec3::new(5.0, 0.0, 0.0)).length() - 0.5).abs() < 1e-5);
            } else {
                assert!(
                    s.p.z.abs() < 1e-6
                        && s.p.x >= 0.0
                        && s.p.y >= 0.0
                        && s.p.x <= 1.0
                        && s.p.y <= 1.0
                );
            }
            let ray = crate::geometry::ray::Ray::new(p_ref, (s.p - p_ref).normalize());
            let hit = g
                .intersect(&ray, f32::INFINITY)
                .expect("the sampled point is seen");
            let found = g.surface(&ray, &hit);
            assert!((found.p - s.p).length() < 1e-4, "{} vs {}", found.p, s.p);
            let pdf = set.pdf(&g, hit.kind, hit.index, p_ref, found.p, found.n);
            assert!(
                (pdf - s.pdf).abs() <= 1e-3 * s.pdf,
                "sample pdf {} vs pdf {pdf} at {}",
                s.pdf,
                s.p
            );
        }
    }

    #[test]
    fn the_point_on_a_rarely_chosen_emitter_takes_its_whole_2d_sample() {
        // A big lamp and a small triangle 1000 times dimmer, whose count in the selection table is
        // a few units of 2²⁴. With the point's first coordinate taken from the selection
        // number's remainder, that coordinate had only those few values (one value: a single
        // vertex line). From its own dimension, the points cover the triangle uniformly: their
        // mean is the centroid, and the first coordinate of `u` moves them.
        let prims = vec![
            (
                0,
                Primitive::Sphere {
                    center: Vec3::new(0.0, 0.0, -50.0),
                    radius: 10.0,
                    frame: glam::Mat3::IDENTITY,
                },
            ),
            (
                1,
                Primitive::Triangle {
                    p: [
                        Vec3::ZERO,
                        Vec3::new(1.0, 0.0, 0.0),
                        Vec3::new(0.0, 1.0, 0.0),
                    ],
                    uv: [Vec2::ZERO; 3],
                },
            ),
        ];
        let g = Geometry::build(&prims);
        let set = LightSet::build(&g, &[light(1.0), light(1e-3)], &[0, 1]);
        // The triangle's share of the selection numbers: at the top of [0, 1).
        let dim = 1.0 - set.selection_pmf(1) * 0.5;
        assert!(set.selection_pmf(1) > 0.0 && set.selection_pmf(1) < 1e-5);
        // Far away, so the triangle is sampled by area: uniform barycentrics.
        let p_ref = Vec3::new(0.3, 0.3, 1000.0);
        let n = 64;
        let mut mean = Vec3::ZERO;
        for i in 0..n {
            for j in 0..n {
                let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                let s = surface(set.sample(&g, p_ref, dim, u, no_jitter));
                assert!(s.p.z.abs() < 1e-6, "picked the lamp, not the triangle");
                mean += s.p / (n * n) as f32;
            }
        }
        let centroid = Vec3::new(1.0 / 3.0, 1.0 / 3.0, 0.0);
        assert!((mean - centroid).length() < 0.01, "mean {mean}");
        let a = surface(set.sample(&g, p_ref, dim, Vec2::new(0.1, 0.5), no_jitter));
        let b = surface(set.sample(&g, p_ref, dim, Vec2::new(0.9, 0.5), no_jitter));
        assert!((a.p - b.p).length() > 0.1, "{} and {}", a.p, b.p);
    }

    #[test]
    fn a_scene_without_lights_has_an_empty_set() {
        let g = Geometry::build(&[(
            0,
            Primitive::Plane {
                point: Vec3::ZERO,
                normal: Vec3::Y,
            },
        )]);
        let set = LightSet::build(&g, &[light(1.0)], &[0]);
        assert!(set.is_empty());
        assert!(
            set.sample(&g, Vec3::ONE, 0.5, Vec2::splat(0.5), no_jitter)
                .is_none()
        );
    }
}
