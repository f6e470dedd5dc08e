//! Area lights: the spheres and triangles whose material emits, and how a point is sampled on
//! one from a shading point. No ECS here.
//!
//! A point is chosen on a sphere uniformly in the cone of directions it subtends from the
//! shading point (only the visible cap), or uniformly by area from inside it; on a triangle
//! uniformly in the solid angle it subtends (a spherical triangle, Arvo 1995) when it is near
//! (area ≥ 0.3 × squared distance) and that angle is neither tiny nor near a hemisphere, else
//! uniformly by area. The sample and the density a BSDF-sampled hit is weighted with decide the
//! strategy by the same rule ([`Emitter::strategy`]). The shapes' own sampling lives beside them
//! ([`crate::geometry::sphere`], [`crate::geometry::triangle`]).

use glam::{Vec2, Vec3};

use crate::geometry::layout::Layout;
use crate::geometry::packed::{Geometry, HitKind};
use crate::geometry::sphere::{
    cone_one_minus_cos, sample_sphere_area, sample_sphere_cone, sphere_point_error, sphere_uv,
};
use crate::geometry::store::{SphereStore, TriangleStore};
use crate::geometry::triangle::{
    sample_spherical_triangle, sample_triangle_area, triangle_area, triangle_point_error,
    triangle_solid_angle,
};
use crate::shading::emission::Emission;
use crate::shading::texture::{TexCoords, Texture};

/// Solid angles (sr) between which a triangle is sampled by solid angle; outside, by area.
/// Below the lower bound the spherical triangle's angles lose precision in f32 and area
/// sampling is as good; near 2π the construction breaks down (pbrt-v4's bounds).
const SPHERICAL_MIN: f32 = 3e-4;
const SPHERICAL_MAX: f32 = 6.22;
/// Triangles with area below this times their squared distance from the shading point are
/// sampled by area, without computing their solid angle.
const SPHERICAL_MIN_AREA_RATIO: f32 = 0.3;

/// An emitting sphere or triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Emitter {
    /// The primitive's kind; with `index`, its slot.
    pub kind: HitKind,
    /// The primitive's slot (an instance's slot for an instanced triangle).
    pub index: u32,
    area: f32,
    /// Material index.
    pub material: u32,
    /// A sphere's centre, or the centroid of a triangle's world-space vertices: where the
    /// choice of strategy measures the distance from.
    centroid: Vec3,
    /// Whether the material reads texture coordinates ([`Emitter::reading_uv`]).
    reads_uv: bool,
}

/// A point sampled on an emitter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// The point.
    pub p: Vec3,
    /// Unit geometric normal of the emitter at `p`.
    pub n: Vec3,
    /// Texture coordinates at `p` (both sets).
    pub uv: TexCoords,
    /// Material index of the emitter.
    pub material: u32,
    /// Probability density of the direction from the shading point to `p`, per steradian
    /// (emitter selection included): what [`super::LightSet::pdf`] gives for the same point.
    pub pdf: f32,
    /// Absolute error bound of `p`, per component.
    pub err: Vec3,
}

/// How a point is chosen on one emitter from one shading point.
#[derive(Clone, Copy, Debug)]
pub enum Strategy {
    /// Uniformly by area.
    Area,
    /// Uniformly in a sphere's visible cone.
    Cone {
        /// `1 − cos θmax` of the cone; `2π` times this is its solid angle.
        one_minus_cos: f32,
    },
    /// Uniformly in a triangle's solid angle.
    Spherical {
        /// The solid angle.
        solid_angle: f32,
        /// The world-space vertices, fetched (for an instance: transformed) once for both the
        /// choice and the sample.
        vertices: [Vec3; 3],
    },
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

/// Radiance per unit area of an emission in the light table's units (intensity × mean emitted
/// colour); the emitter's power is its area times this.
pub fn radiance_scale(emission: &Emission) -> f32 {
    emission.scale * mean_colour(emission.texture)
}

impl Emitter {
    /// The sphere emitter in slot `index`, of centre `c` and radius `r`.
    pub fn sphere(index: usize, c: Vec3, r: f32, material: u32) -> Self {
        Self {
            kind: HitKind::Sphere,
            index: index as u32,
            area: 4.0 * std::f32::consts::PI * r * r,
            material,
            centroid: c,
            reads_uv: true,
        }
    }

    /// The triangle emitter `(kind, index)` with world-space vertices `v`.
    pub fn triangle(kind: HitKind, index: usize, v: [Vec3; 3], material: u32) -> Self {
        Self {
            kind,
            index: index as u32,
            area: triangle_area(v),
            material,
            centroid: (v[0] + v[1] + v[2]) * (1.0 / 3.0),
            reads_uv: true,
        }
    }

    /// The emitter, told whether its material reads texture coordinates
    /// ([`Material::reads_tex_coords`](crate::shading::material::Material::reads_tex_coords)):
    /// a sphere's samples of a material that reads none carry zero coordinates instead of
    /// computing them (an `atan2` and an `acos`). Emitters read them by default.
    pub fn reading_uv(self, reads_uv: bool) -> Self {
        Self { reads_uv, ..self }
    }

    /// The emitter's area.
    pub fn area(&self) -> f32 {
        self.area
    }

    /// How the emitter is sampled from shading point `p_ref`.
    #[inline(always)]
    pub fn strategy<L: Layout>(&self, geometry: &Geometry<L>, p_ref: Vec3) -> Strategy {
        let i = self.index as usize;
        match self.kind {
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
                if self.area < SPHERICAL_MIN_AREA_RATIO * (self.centroid - p_ref).length_squared() {
                    return Strategy::Area;
                }
                let v = self.vertices(geometry);
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
    fn vertices<L: Layout>(&self, geometry: &Geometry<L>) -> [Vec3; 3] {
        match self.kind {
            HitKind::Instance { triangle } => {
                geometry.instances.world_triangle(self.index, triangle)
            }
            _ => geometry.triangles.get(self.index as usize),
        }
    }

    /// Density per steradian, at `p_ref`, of the point `p` (unit normal `n`) sampled by
    /// `strategy`, selection excluded.
    #[inline]
    pub fn density(&self, strategy: Strategy, p_ref: Vec3, p: Vec3, n: Vec3) -> f32 {
        match strategy {
            Strategy::Area => {
                let to = p - p_ref;
                let dist2 = to.length_squared();
                let cos = (to.dot(n) / dist2.sqrt()).abs();
                dist2 / (self.area * cos)
            }
            Strategy::Cone { one_minus_cos } => 1.0 / (2.0 * std::f32::consts::PI * one_minus_cos),
            Strategy::Spherical { solid_angle, .. } => 1.0 / solid_angle,
        }
    }

    /// A point on the emitter seen from `p_ref`, from the uniform pair `u`, its density
    /// including the selection probability `pmf`; `None` where the construction degenerates.
    #[inline(always)]
    pub fn sample<L: Layout>(
        &self,
        geometry: &Geometry<L>,
        p_ref: Vec3,
        u: Vec2,
        pmf: f32,
    ) -> Option<LightSample> {
        let i = self.index as usize;
        let strategy = self.strategy(geometry, p_ref);
        let (p, n, uv, err) = match self.kind {
            HitKind::Sphere => {
                let (c, r) = geometry.spheres.get(i);
                let n = match strategy {
                    Strategy::Cone { .. } => sample_sphere_cone(c, r, p_ref, u).1,
                    _ => sample_sphere_area(u),
                };
                let uv = if self.reads_uv {
                    sphere_uv(geometry.sphere_frame[i].transpose() * n)
                } else {
                    Vec2::ZERO
                };
                (c + r * n, n, uv.into(), sphere_point_error(c, r))
            }
            HitKind::Triangle | HitKind::Instance { .. } => {
                let [b0, b1, b2] = match strategy {
                    Strategy::Spherical {
                        vertices,
                        solid_angle,
                    } => sample_spherical_triangle(vertices, p_ref, solid_angle, u)?,
                    _ => sample_triangle_area(u),
                };
                if let HitKind::Instance { triangle } = self.kind {
                    let s = geometry.instances.surface(self.index, triangle, b1, b2);
                    let err = geometry.instances.point_error(self.index, triangle, b1, b2);
                    (s.p, s.n, s.tex_coords(), err)
                } else {
                    let [a, b, c] = geometry.triangles.get(i);
                    let [ta, tb, tc] = geometry.triangle_uv[i];
                    let n = geometry.triangle_normal[i];
                    let err = triangle_point_error([a, b, c], [b0, b1, b2]);
                    (
                        b0 * a + b1 * b + b2 * c,
                        n,
                        (b0 * ta + b1 * tb + b2 * tc).into(),
                        err,
                    )
                }
            }
            HitKind::Plane => return None,
        };
        Some(LightSample {
            p,
            n,
            uv,
            material: self.material,
            pdf: pmf * self.density(strategy, p_ref, p, n),
            err,
        })
    }
}
