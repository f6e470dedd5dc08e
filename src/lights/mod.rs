//! Lights as a sampling distribution, for next-event estimation: the light table. No ECS here.
//!
//! Every sphere and triangle whose material emits ([`crate::shading::material::Material::emission`])
//! is an area light ([`area`]), and so is every triangle of an emissive instanced mesh (placed
//! through its instance transform, with its area in world space); the distant lights of the
//! scene's sky ([`distant`]) follow them in the table, then the point and spot lights
//! ([`punctual`]). One is chosen half by power, half evenly over the scene's lights ([`table`];
//! power is area × intensity × mean emitted colour for an area light, what the scene receives
//! for a distant one, flux / π for a punctual one), then a point on it or a direction towards
//! it. [`LightSet::sample`] and [`LightSet::pdf`] decide an area light's strategy by the same
//! rule, so the density a BSDF-sampled hit is weighted with is the one the light sample would
//! have had. Infinite planes are never light-sampled: their emission is only found by BSDF
//! sampling, at full weight.

pub mod area;
pub mod distant;
pub mod punctual;
pub mod table;

use glam::{Vec2, Vec3};

use crate::geometry::layout::Layout;
use crate::geometry::packed::{Geometry, HitKind};
use crate::geometry::store::{SphereStore, TriangleStore};
use crate::shading::material::Material;
use crate::sky::Sky;

use area::{Emitter, LightSample, radiance_scale};
use distant::{DistantLight, DistantSample};
use punctual::{PunctualLight, PunctualSample};
use table::{SelectionTable, mixed_weights};

/// Marks a primitive slot that is not an emitter.
const NONE: u32 = u32::MAX;

/// A light sample: a point on an emitter or a direction towards a distant light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Sampled {
    /// A point on a surface emitter.
    Surface(LightSample),
    /// A direction towards a distant light.
    Distant(DistantSample),
    /// A point or spot light: a delta light, whose sample counts at full weight.
    Punctual(PunctualSample),
}

/// The lights of a scene with their selection probabilities.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LightSet {
    emitters: Vec<Emitter>,
    /// Selection ([`table`]): the emitters, then the distant lights.
    table: SelectionTable,
    /// Emitter index per sphere slot, or `NONE`.
    sphere_emitter: Vec<u32>,
    /// Emitter index per triangle slot, or `NONE`.
    triangle_emitter: Vec<u32>,
    /// Emitter index of triangle 0 of each instance slot (its triangles follow in order), or
    /// `NONE` if the instance does not emit.
    instance_emitter: Vec<u32>,
    /// The distant lights: entries `emitters.len() + k` of the table.
    distant: Vec<DistantLight>,
    /// The point and spot lights: entries `emitters.len() + distant.len() + k` of the table.
    punctual: Vec<PunctualLight>,
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
        Self::build_with_lights(geometry, materials, owner_material, sky, &[])
    }

    /// [`LightSet::build_with_sky`] with the point and spot lights `punctual` after the distant
    /// lights, in the given order, each weighed by [`PunctualLight::power`].
    pub fn build_with_lights<L: Layout>(
        geometry: &Geometry<L>,
        materials: &[Material],
        owner_material: &[u32],
        sky: &Sky,
        punctual: &[PunctualLight],
    ) -> Self {
        let power_of = |owner: u32| -> Option<(u32, f32)> {
            let m = *owner_material.get(owner as usize)?;
            let emission = materials.get(m as usize)?.emission()?;
            Some((m, radiance_scale(&emission)))
        };
        let reads_uv = |material: u32| {
            materials
                .get(material as usize)
                .is_some_and(Material::reads_tex_coords)
        };
        let mut set = Self {
            sphere_emitter: vec![NONE; geometry.sphere_owner.len()],
            triangle_emitter: vec![NONE; geometry.triangle_owner.len()],
            instance_emitter: vec![NONE; geometry.instances.len()],
            ..Self::default()
        };
        let mut powers: Vec<f64> = Vec::new();
        // The light (a dense index) each emitter belongs to: one per emitting owner.
        let mut light_of: Vec<usize> = Vec::new();
        let mut light_of_owner: Vec<usize> = vec![usize::MAX; owner_material.len()];
        let mut lights = 0usize;
        let mut light_index = |owner: u32| {
            let slot = &mut light_of_owner[owner as usize];
            if *slot == usize::MAX {
                *slot = lights;
                lights += 1;
            }
            *slot
        };
        // Adds an emitter of `owner`, returning its index.
        let mut add = |set: &mut Self, emitter: Emitter, power: f32, owner: u32| {
            powers.push(f64::from(emitter.area()) * f64::from(power));
            light_of.push(light_index(owner));
            set.emitters.push(emitter);
            (set.emitters.len() - 1) as u32
        };
        for (i, &owner) in geometry.sphere_owner.iter().enumerate() {
            if let Some((material, power)) = power_of(owner) {
                let (c, r) = geometry.spheres.get(i);
                let emitter = Emitter::sphere(i, c, r, material).reading_uv(reads_uv(material));
                set.sphere_emitter[i] = add(&mut set, emitter, power, owner);
            }
        }
        for (i, &owner) in geometry.triangle_owner.iter().enumerate() {
            if let Some((material, power)) = power_of(owner) {
                let v = geometry.triangles.get(i);
                let emitter = Emitter::triangle(HitKind::Triangle, i, v, material);
                set.triangle_emitter[i] = add(&mut set, emitter, power, owner);
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
                add(
                    &mut set,
                    Emitter::triangle(kind, i, v, material),
                    power,
                    inst.owner,
                );
            }
        }
        let distant = distant::lights_of(sky);
        if !distant.is_empty() {
            let radius = geometry.finite_bounds().map_or(1.0, |(lo, hi)| {
                let r = 0.5 * (hi - lo).length();
                if r > 0.0 && r.is_finite() { r } else { 1.0 }
            });
            for light in &distant {
                powers.push(f64::from(light.power(radius)));
                light_of.push(lights);
                lights += 1;
            }
        }
        set.distant = distant;
        // Each point or spot light is a light of its own.
        for (k, light) in punctual.iter().enumerate() {
            powers.push(f64::from(light.power()));
            light_of.push(lights + k);
        }
        set.punctual = punctual.to_vec();
        set.table = SelectionTable::new(&mixed_weights(&powers, &light_of));
        if set.table.is_empty() {
            // Emitters with zero power (or none at all): nothing worth sampling.
            return Self {
                sphere_emitter: vec![NONE; set.sphere_emitter.len()],
                triangle_emitter: vec![NONE; set.triangle_emitter.len()],
                instance_emitter: vec![NONE; set.instance_emitter.len()],
                distant: set.distant,
                punctual: set.punctual,
                ..Self::default()
            };
        }
        set
    }

    /// Whether there is nothing to sample.
    pub fn is_empty(&self) -> bool {
        self.table.is_empty()
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

    /// The brightest radiant intensity (any channel) of the point and spot lights: the
    /// irradiance they give at unit distance, a scale for the film's fixed point.
    pub fn punctual_max_intensity(&self) -> f32 {
        self.punctual
            .iter()
            .map(|light| light.intensity.max_element())
            .fold(0.0, f32::max)
    }

    /// The point and spot lights, in table order after the distant lights.
    pub fn punctual(&self) -> &[PunctualLight] {
        &self.punctual
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

    /// Probability that [`LightSet::select`] picks light `k` (0 for an index out of range).
    #[inline]
    pub fn selection_pmf(&self, k: usize) -> f32 {
        self.table.pmf(k)
    }

    /// The light that `u_select` ∈ [0, 1) picks, read at 24-bit resolution, with its
    /// selection probability; `None` if there are no lights.
    #[inline]
    pub fn select(&self, u_select: f32) -> Option<(usize, f32)> {
        self.table.select(u_select)
    }

    /// Samples a light seen from shading point `p_ref`: `u_select` picks it, `u` the point on
    /// it (or the direction towards a distant one; a point or spot light needs neither);
    /// `jitter()` is asked for two more numbers only by a light that needs them (a map's
    /// texel). The numbers come from separate sampler
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
            let Some(light) = self.distant.get(d) else {
                let light = self.punctual.get(d - self.distant.len())?;
                return light.sample(p_ref, pmf).map(Sampled::Punctual);
            };
            // Value and density of what was sampled: no second lookup of the direction.
            let (direction, radiance, pdf) = light.sample(u, jitter)?;
            let pdf = pmf * pdf;
            return (pdf > 0.0).then_some(Sampled::Distant(DistantSample {
                direction,
                radiance,
                pdf,
            }));
        };
        e.sample(geometry, p_ref, u, pmf).map(Sampled::Surface)
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
        pmf * e.density(e.strategy(geometry, p_ref), p_ref, p, n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::packed::Primitive;
    use crate::shading::texture::Texture;

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
    fn selection_mixes_power_and_lights_and_pdfs_integrate_to_one() {
        // A unit-area square (two triangles, one light) of intensity 1 and a sphere of area
        // 4π·0.25 = π of intensity 2: powers 1 and 2π. Half the selection goes by power, half
        // evenly to the two lights (the square's half split between its triangles by area).
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
        let materials = [light(1.0), light(2.0), Material::glass(1.5)];
        let set = LightSet::build(&g, &materials, &[0, 1, 2]);
        assert_eq!(set.len(), 3);
        let total = 1.0 + 2.0 * std::f32::consts::PI;
        // Selection probabilities (spheres first, then triangles) sum to 1.
        let pmf: Vec<f32> = (0..3).map(|k| set.selection_pmf(k)).collect();
        assert!(
            (pmf[0] - (0.5 * 2.0 * std::f32::consts::PI / total + 0.25)).abs() < 1e-6,
            "{pmf:?}"
        );
        for triangle in &pmf[1..] {
            assert!((triangle - (0.25 / total + 0.125)).abs() < 1e-6, "{pmf:?}");
        }
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
        // A lamp of one big sphere and a small triangle, whose count in the selection table is
        // a few units of 2²⁴ (selection within a light goes by power). With the point's first coordinate taken from the selection
        // number's remainder, that coordinate had only those few values (one value: a single
        // vertex line). From its own dimension, the points cover the triangle uniformly: their
        // mean is the centroid, and the first coordinate of `u` moves them.
        let prims = vec![
            (
                0,
                Primitive::Sphere {
                    center: Vec3::new(0.0, 0.0, -500.0),
                    radius: 100.0,
                    frame: glam::Mat3::IDENTITY,
                },
            ),
            (
                0,
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
        let set = LightSet::build(&g, &[light(1.0)], &[0]);
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
