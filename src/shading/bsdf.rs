//! The BSDF at one surface point, as the integrator uses it: built once per hit from the
//! material ([`super::material::Material::bsdf`]: textures looked up, the normal map applied),
//! it evaluates, samples and gives the density of its lobe, says whether it is a perfect
//! specular one or can be light-sampled, and carries the surface's emission. The lobes live in
//! their own files ([`super::diffuse`], [`super::fuzzed`], [`super::conductor`],
//! [`super::dielectric`], [`super::rough_dielectric`], [`super::pbr`] with its layers
//! [`super::specular`], [`super::sheen`] and [`super::coat`]). No ECS here.
//!
//! Where the shading normal differs from the geometric one (a smooth mesh), the lobe sampled
//! about the shading normal is folded onto the side of the geometric surface the ray came from:
//! a direction that would pass through the surface (near silhouettes) is mirrored at it.
//! Following such a direction would leak light through the mesh, and dropping it darkened the
//! silhouettes (a white 10×6 UV sphere in a white furnace averaged 0.993, silhouette pixels
//! 0.69); folded, the lobe keeps its energy on the right side. Its value and density at a
//! direction are the sums over the direction and its mirror image, so the sampled weight is their
//! ratio (exactly the albedo for a diffuse surface) and next-event estimation and MIS use the
//! very density sampled from.

use glam::Vec3;

use super::coat::Coated;
use super::conductor::Conductor;
use super::dielectric::Dielectric;
use super::diffuse::Diffuse;
use super::emission::Emission;
use super::fuzzed::Fuzzed;
use super::microfacet::is_narrow_alpha;
use super::pbr::Pbr;
use super::rough_dielectric::RoughDielectric;
use super::sampler::Sampler;
use super::sampling::{facing, reflect};
use super::scatter::Scatter;
use super::texture::TexCoords;

/// The scattering part of a BSDF at one point: one lobe, its textures already looked up.
#[derive(Clone, Copy, Debug)]
pub enum Lobe {
    /// Scatters nothing (a pure emitter).
    None,
    /// Lambertian.
    Diffuse(Diffuse),
    /// The fuzzed mirror.
    Fuzzed(Fuzzed),
    /// GGX conductor.
    Conductor(Conductor),
    /// Smooth glass.
    Dielectric(Dielectric),
    /// Rough glass.
    RoughDielectric(RoughDielectric),
    /// The glTF metallic–roughness mix.
    MetallicRoughness(Pbr),
    /// The metallic–roughness mix under a clear coat.
    Coated(Coated),
}

impl Lobe {
    /// f·cos θi and the density of `wi` for a ray along `d` at unit normal `n` (either side);
    /// `None` where the lobe has no density to evaluate (delta or fuzzed lobes); of a
    /// metallic–roughness mix with a smooth specular lobe and a diffuse one, the diffuse lobe
    /// alone.
    #[inline(always)]
    fn eval(&self, d: Vec3, wi: Vec3, n: Vec3) -> Option<(Vec3, f32)> {
        match self {
            Self::Diffuse(l) => Some(l.eval(d, wi, n)),
            Self::Conductor(l) => l.eval(d, wi, n),
            Self::RoughDielectric(l) => Some(l.eval(d, wi, n)),
            Self::MetallicRoughness(l) => {
                let facing = facing(d, n);
                (!l.is_delta()).then(|| l.eval(-d, wi, facing))
            }
            Self::Coated(l) => {
                let facing = facing(d, n);
                (!l.is_delta()).then(|| l.eval(-d, wi, facing))
            }
            Self::None | Self::Fuzzed(_) | Self::Dielectric(_) => None,
        }
    }

    /// Samples the continuation of a ray along unit `d` at unit normal `n`; `None` if the path
    /// ends here (absorbed, or nothing scatters).
    #[inline(always)]
    fn sample(&self, d: Vec3, n: Vec3, sampler: &mut impl Sampler) -> Option<Scatter> {
        match self {
            Self::Diffuse(l) => Some(l.sample(d, n, sampler)),
            Self::Fuzzed(l) => l.sample(d, n, sampler),
            Self::Conductor(l) => l.sample(d, n, sampler),
            Self::Dielectric(l) => Some(l.sample(d, n, sampler)),
            Self::RoughDielectric(l) => l.sample(d, n, sampler),
            Self::MetallicRoughness(l) => {
                let facing = facing(d, n);
                let s = l.sample(-d, facing, sampler.next_2d())?;
                Some(Scatter {
                    direction: s.wi,
                    attenuation: s.weight,
                    pdf: s.pdf,
                    radiance_scale: 1.0,
                })
            }
            Self::Coated(l) => {
                let facing = facing(d, n);
                let s = l.sample(-d, facing, sampler.next_2d())?;
                Some(Scatter {
                    direction: s.wi,
                    attenuation: s.weight,
                    pdf: s.pdf,
                    radiance_scale: 1.0,
                })
            }
            Self::None => None,
        }
    }

    /// Whether the lobe is a perfect mirror or smooth glass (a delta lobe, nothing of it
    /// evaluable).
    #[inline]
    fn is_specular(&self) -> bool {
        match self {
            Self::Dielectric(_) => true,
            Self::Fuzzed(l) => l.roughness == 0.0,
            Self::Conductor(l) => l.is_specular(),
            Self::MetallicRoughness(l) => l.is_delta(),
            Self::Coated(l) => l.is_delta(),
            Self::Diffuse(_) | Self::RoughDielectric(_) | Self::None => false,
        }
    }

    /// The lobe's reflectance as the albedo feature buffer records it: the albedo, the F0 of a
    /// conductor, the base colour of the metallic–roughness mix, white for glass.
    #[inline]
    fn reflectance(&self) -> Vec3 {
        match self {
            Self::Diffuse(l) => l.albedo,
            Self::Fuzzed(l) => l.albedo,
            Self::Conductor(l) => l.f0,
            Self::MetallicRoughness(l) => l.base_color,
            Self::Coated(l) => l.base.base_color,
            Self::Dielectric(_) | Self::RoughDielectric(_) => Vec3::ONE,
            Self::None => Vec3::ZERO,
        }
    }
}

/// The BSDF at a surface point for a ray arriving along `d`.
#[derive(Clone, Copy, Debug)]
pub struct Bsdf<'a> {
    lobe: Lobe,
    /// Direction of the incoming ray.
    d: Vec3,
    /// Unit geometric normal (as the primitive defines it).
    n: Vec3,
    /// Unit normal the lobe shades with.
    ns: Vec3,
    /// Texture coordinates, for the emission.
    uv: TexCoords,
    samples_lights: bool,
    emission: Option<Emission<'a>>,
}

impl<'a> Bsdf<'a> {
    /// The BSDF of `lobe` for a ray along `d` at a point of geometric normal `n`, shading normal
    /// `ns` and texture coordinates `uv`; `samples_lights` says whether next-event estimation
    /// applies to it, `emission` what the surface emits.
    #[inline(always)]
    pub fn new(
        lobe: Lobe,
        d: Vec3,
        (n, ns): (Vec3, Vec3),
        uv: TexCoords,
        samples_lights: bool,
        emission: Option<Emission<'a>>,
    ) -> Self {
        Self {
            lobe,
            d,
            n,
            ns,
            uv,
            samples_lights,
            emission,
        }
    }

    /// The BSDF with `emission` as what the surface emits: that of a whole mix whose component
    /// the BSDF is ([`super::material::Material::component`]).
    #[inline]
    pub fn with_emission(self, emission: Option<Emission<'a>>) -> Self {
        Self { emission, ..self }
    }

    /// Whether a path may continue from the surface (false for a pure emitter).
    #[inline]
    pub fn scatters(&self) -> bool {
        !matches!(self.lobe, Lobe::None)
    }

    /// Whether next-event estimation applies: the lobe can be evaluated for any pair of
    /// directions. A textured metallic–roughness mix may still be a perfect mirror at this
    /// point, where [`Bsdf::eval`] says so.
    #[inline]
    pub fn samples_lights(&self) -> bool {
        self.samples_lights
    }

    /// Whether the lobe is a perfect mirror or smooth glass (a delta BSDF): the feature buffers
    /// look through such a surface to the next hit, whose look is what it reflects or refracts.
    /// Open Image Denoise's documentation asks for this (its `RT` filter, "Albedo": follow
    /// perfect specular paths and store the first diffuse or glossy hit).
    #[inline]
    pub fn is_specular(&self) -> bool {
        self.lobe.is_specular()
    }

    /// Whether the lobe is a narrow GGX conductor that is not a perfect mirror
    /// ([`super::microfacet::is_narrow_alpha`]): a glossy vertex `Method::Photons` follows along
    /// its light paths like a mirror.
    #[inline]
    pub fn is_narrow_glossy(&self) -> bool {
        matches!(self.lobe, Lobe::Conductor(l) if is_narrow_alpha(l.alpha))
    }

    /// Whether the lobe is Lambertian (a `Diffuse` material): where a photon map's density
    /// estimate is smooth whatever the directions.
    #[inline]
    pub fn is_lambertian(&self) -> bool {
        matches!(self.lobe, Lobe::Diffuse(_))
    }

    /// The normal the lobe shades with: the interpolated vertex normal of a smooth mesh
    /// (perturbed by a normal map), except for glass, whose refraction must follow the true
    /// surface to stay watertight.
    #[inline]
    pub fn shading_normal(&self) -> Vec3 {
        self.ns
    }

    /// Radiance the surface emits towards the incoming ray; `None` for a surface that does not
    /// emit.
    #[inline]
    pub fn emitted(&self) -> Option<Vec3> {
        self.emission.map(|e| e.radiance(self.d, self.n, self.uv))
    }

    /// The colour the albedo feature buffer records, before the integrator clamps it to [0, 1]:
    /// the lobe's reflectance plus the radiance the surface emits towards the ray, so that an
    /// emitter records its emission, one that also reflects the sum.
    #[inline]
    pub fn feature_albedo(&self) -> Vec3 {
        self.lobe.reflectance() + self.emitted().unwrap_or(Vec3::ZERO)
    }

    /// Whether the lobe is shaded with a normal other than the geometric one, so that it can
    /// reach through the surface and is folded.
    #[inline]
    fn is_smooth(&self) -> bool {
        self.ns != self.n
    }

    /// The geometric normal on the side the ray arrives from.
    #[inline]
    fn front(&self) -> Vec3 {
        facing(self.d, self.n)
    }

    /// BSDF times the cosine at the surface, and the density [`Bsdf::sample`] would give, for
    /// light arriving from `wi`. `None` where the BSDF has no density to evaluate (delta or
    /// fuzzed lobes). A folded lobe (see the module's notes) gives its value and density at
    /// `wi` plus those at its mirror image below the surface, and zero for a `wi` that passes
    /// through the surface.
    #[inline(always)]
    pub fn eval(&self, wi: Vec3) -> Option<(Vec3, f32)> {
        if !self.is_smooth() {
            return self.lobe.eval(self.d, wi, self.ns);
        }
        let n = self.front();
        if wi.dot(n) <= 0.0 {
            return Some((Vec3::ZERO, 0.0));
        }
        let (f_above, pdf_above) = self.lobe.eval(self.d, wi, self.ns)?;
        let (f_below, pdf_below) = self.lobe.eval(self.d, reflect(wi, n), self.ns)?;
        Some((f_above + f_below, pdf_above + pdf_below))
    }

    /// Samples the continuation of the path; `None` if it ends here (absorbed, or an emitter).
    /// A folded lobe's direction below the geometric surface is mirrored at it, and its weight
    /// and density are those of [`Bsdf::eval`]; `None` for a direction in the surface's plane
    /// or of zero density.
    #[inline(always)]
    pub fn sample(&self, sampler: &mut impl Sampler) -> Option<Scatter> {
        let scatter = self.lobe.sample(self.d, self.ns, sampler)?;
        if !self.is_smooth() {
            return Some(scatter);
        }
        let n = self.front();
        let direction = if scatter.direction.dot(n) > 0.0 {
            scatter.direction
        } else {
            reflect(scatter.direction, n).normalize()
        };
        if direction.dot(n) <= 0.0 {
            return None;
        }
        if scatter.pdf.is_none() {
            // A lobe without a density (the fuzzed metal): only its direction is folded.
            return Some(Scatter {
                direction,
                ..scatter
            });
        }
        let (f_cos, pdf) = self.eval(direction)?;
        (pdf > 0.0).then(|| Scatter {
            direction,
            attenuation: f_cos / pdf,
            pdf: Some(pdf),
            radiance_scale: 1.0,
        })
    }
}
