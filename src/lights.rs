//! Emitters as a sampling distribution, for next-event estimation. No ECS here.
//!
//! Every sphere and triangle whose material is a `Light` is an emitter. One is chosen with
//! probability proportional to its power (area × intensity × mean emitted colour), then a point
//! is chosen uniformly by area on it. Infinite planes are never light-sampled: their emission is
//! only found by BSDF sampling, at full weight.

use glam::{Vec2, Vec3};

use crate::geometry::layout::{Layout, SphereStore, TriangleStore};
use crate::geometry::packed::{Geometry, HitKind};
use crate::geometry::ray::gamma;
use crate::geometry::sphere::sphere_uv;
use crate::shading::material::Material;
use crate::shading::texture::Texture;

/// Marks a primitive slot that is not an emitter.
const NONE: u32 = u32::MAX;
/// The largest `f32` below 1.
const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;

#[derive(Clone, Copy, Debug, PartialEq)]
struct Emitter {
    kind: HitKind,
    index: u32,
    area: f32,
    material: u32,
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
    /// Probability density of the choice per unit area (emitter selection included).
    pub pdf_area: f32,
    /// Absolute error bound of `p`, per component.
    pub err: Vec3,
}

/// The emitters of a scene with their selection probabilities.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LightSet {
    emitters: Vec<Emitter>,
    /// Selection probability per emitter.
    pmf: Vec<f32>,
    /// Running sum of `pmf`, ending at 1.
    cdf: Vec<f32>,
    /// Emitter index per sphere slot, or `NONE`.
    sphere_emitter: Vec<u32>,
    /// Emitter index per triangle slot, or `NONE`.
    triangle_emitter: Vec<u32>,
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

impl LightSet {
    /// Collects the emitters of `geometry` given each owner's material.
    pub fn build<L: Layout>(
        geometry: &Geometry<L>,
        materials: &[Material],
        owner_material: &[u32],
    ) -> Self {
        let power_of = |owner: u32| -> Option<(u32, f32)> {
            let m = *owner_material.get(owner as usize)?;
            match materials.get(m as usize)? {
                Material::Light {
                    emit, intensity, ..
                } => Some((m, intensity * mean_colour(emit))),
                _ => None,
            }
        };
        let mut set = Self {
            sphere_emitter: vec![NONE; geometry.sphere_owner.len()],
            triangle_emitter: vec![NONE; geometry.triangle_owner.len()],
            ..Self::default()
        };
        let mut powers = Vec::new();
        let mut add = |set: &mut Self, kind: HitKind, i: usize, area: f32, (material, power)| {
            let slot = match kind {
                HitKind::Sphere => &mut set.sphere_emitter[i],
                _ => &mut set.triangle_emitter[i],
            };
            *slot = set.emitters.len() as u32;
            set.emitters.push(Emitter {
                kind,
                index: i as u32,
                area,
                material,
            });
            powers.push(area * power);
        };
        for (i, &owner) in geometry.sphere_owner.iter().enumerate() {
            if let Some(emission) = power_of(owner) {
                let (_, r) = geometry.spheres.get(i);
                add(
                    &mut set,
                    HitKind::Sphere,
                    i,
                    4.0 * std::f32::consts::PI * r * r,
                    emission,
                );
            }
        }
        for (i, &owner) in geometry.triangle_owner.iter().enumerate() {
            if let Some(emission) = power_of(owner) {
                let [a, b, c] = geometry.triangles.get(i);
                add(
                    &mut set,
                    HitKind::Triangle,
                    i,
                    0.5 * (b - a).cross(c - a).length(),
                    emission,
                );
            }
        }
        let total: f32 = powers.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            // Emitters with zero power (or none at all): nothing worth sampling.
            return Self {
                sphere_emitter: vec![NONE; set.sphere_emitter.len()],
                triangle_emitter: vec![NONE; set.triangle_emitter.len()],
                ..Self::default()
            };
        }
        set.pmf = powers.iter().map(|p| p / total).collect();
        let mut acc = 0.0;
        set.cdf = set
            .pmf
            .iter()
            .map(|p| {
                acc += p;
                acc
            })
            .collect();
        if let Some(last) = set.cdf.last_mut() {
            *last = 1.0;
        }
        set
    }

    /// Whether there is nothing to sample.
    pub fn is_empty(&self) -> bool {
        self.emitters.is_empty()
    }

    /// Number of emitters.
    pub fn len(&self) -> usize {
        self.emitters.len()
    }

    /// Samples a point: `u_select` picks the emitter; its remainder within the emitter's share,
    /// rescaled to [0, 1), and `u.y` pick the point on it (`u.x` is not used).
    #[inline]
    pub fn sample<L: Layout>(
        &self,
        geometry: &Geometry<L>,
        u_select: f32,
        u: Vec2,
    ) -> Option<LightSample> {
        let k = self
            .cdf
            .partition_point(|&c| c <= u_select)
            .min(self.emitters.len().checked_sub(1)?);
        let e = self.emitters[k];
        let i = e.index as usize;
        // Where `u_select` fell within the chosen emitter's share, rescaled to [0, 1), is the
        // first coordinate of the point (pbrt-v4's remapped discrete sample): the integrator
        // passes `u_select = u.x`, so one stratified 2D sample picks both emitter and point.
        let lo = if k == 0 { 0.0 } else { self.cdf[k - 1] };
        let u = Vec2::new(((u_select - lo) / self.pmf[k]).clamp(0.0, ONE_BELOW), u.y);
        let (p, n, uv, err) = match e.kind {
            HitKind::Sphere => {
                let (c, r) = geometry.spheres.get(i);
                let z = 1.0 - 2.0 * u.x;
                let s = (1.0 - z * z).max(0.0).sqrt();
                let phi = 2.0 * std::f32::consts::PI * u.y;
                let n = Vec3::new(s * phi.cos(), s * phi.sin(), z);
                let uv = sphere_uv(geometry.sphere_frame[i].transpose() * n);
                (c + r * n, n, uv, gamma(6.0) * (c.abs() + Vec3::splat(r)))
            }
            HitKind::Triangle => {
                let [a, b, c] = geometry.triangles.get(i);
                let su = u.x.sqrt();
                let (b0, b1) = (1.0 - su, u.y * su);
                let b2 = 1.0 - b0 - b1;
                let [ta, tb, tc] = geometry.triangle_uv[i];
                let n = (b - a).cross(c - a).normalize();
                let err = gamma(7.0) * ((b0 * a).abs() + (b1 * b).abs() + (b2 * c).abs());
                (
                    b0 * a + b1 * b + b2 * c,
                    n,
                    b0 * ta + b1 * tb + b2 * tc,
                    err,
                )
            }
            HitKind::Plane | HitKind::Instance { .. } => return None,
        };
        Some(LightSample {
            p,
            n,
            uv,
            material: e.material,
            pdf_area: self.pmf[k] / e.area,
            err,
        })
    }

    /// Density per unit area with which [`LightSet::sample`] picks a point on primitive
    /// `(kind, index)`; 0 if it is not an emitter.
    #[inline]
    pub fn pdf_area(&self, kind: HitKind, index: u32) -> f32 {
        let k = match kind {
            HitKind::Sphere => self.sphere_emitter.get(index as usize),
            HitKind::Triangle => self.triangle_emitter.get(index as usize),
            // Planes are infinite; instanced meshes are found by BSDF sampling only.
            HitKind::Plane | HitKind::Instance { .. } => None,
        };
        match k {
            Some(&k) if k != NONE => self.pmf[k as usize] / self.emitters[k as usize].area,
            _ => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::packed::Primitive;

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
        // ∫ pdf_area dA over each emitter = its selection probability; they sum to 1.
        let sphere_pdf = set.pdf_area(HitKind::Sphere, 0) * std::f32::consts::PI;
        let tri_pdf: f32 = (0..2)
            .map(|i| set.pdf_area(HitKind::Triangle, i) * 0.5)
            .sum();
        assert!((sphere_pdf - 2.0 * std::f32::consts::PI / total).abs() < 1e-6);
        assert!((tri_pdf - 1.0 / total).abs() < 1e-6);
        assert_eq!(
            set.pdf_area(HitKind::Sphere, 1),
            0.0,
            "glass is not an emitter"
        );

        // Sampled points lie on their emitter and report the same pdf.
        let mut rng = crate::shading::rng::Rng::new(1, 2);
        for _ in 0..1000 {
            let s = set
                .sample(
                    &g,
                    rng.next_f32(),
                    Vec2::new(rng.next_f32(), rng.next_f32()),
                )
                .expect("sample");
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
        }
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
        assert!(set.sample(&g, 0.5, Vec2::splat(0.5)).is_none());
    }
}
