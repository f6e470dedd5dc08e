//! Materials: what a surface is made of, as the scene describes it. At a hit a material
//! becomes a [`Bsdf`] ([`Material::bsdf`]), its textures looked up once and its normal map
//! applied; the lobes live in their own files. No ECS here.

use glam::{Vec2, Vec3};

use super::bsdf::{Bsdf, Lobe};
use super::coat::Coated;
use super::conductor::Conductor;
use super::dielectric::Dielectric;
use super::diffuse::Diffuse;
use super::emission::Emission;
use super::fuzzed::Fuzzed;
use super::layer_maps::LayerMaps;
use super::layers::Layers;
use super::maps::{AlphaMask, NormalMap};
use super::microfacet::{alpha_from_roughness, is_specular_alpha};
use super::pbr::Pbr;
use super::rough_dielectric::RoughDielectric;
use super::sampler::Sampler;
use super::sampling::facing;
use super::scatter::Scatter;
use super::sheen::Sheen;
use super::specular::Specular;
use super::texture::{TexCoords, Texture};

/// A surface material.
#[derive(Clone, Debug, PartialEq)]
pub enum Material {
    /// Lambertian reflector.
    Diffuse {
        /// Reflectance.
        albedo: Texture,
    },
    /// Mirror with a fuzz ([`super::fuzzed`]): the reflected direction plus `roughness` times a
    /// random point of the unit ball; directions that end up below the surface are absorbed.
    Metal {
        /// Reflectance.
        albedo: Texture,
        /// Fuzz radius in [0, 1].
        roughness: f32,
    },
    /// Rough metal with an evaluable BSDF: GGX (Trowbridge–Reitz) microfacet reflection,
    /// Schlick's Fresnel with `albedo` as the reflectance at normal incidence, height-correlated
    /// Smith shadowing, and Kulla & Conty's compensation for the light that scatters between
    /// microfacets (a white `Glossy` reflects everything at any roughness); directions are
    /// sampled from the visible normals or the cosine (see [`super::conductor`]). Unlike `Metal`, next-event estimation and MIS apply to it, except
    /// below [`super::microfacet::SPECULAR_ALPHA`], where it is a perfect mirror reflecting
    /// Schlick's Fresnel at the view's cosine.
    Glossy {
        /// Reflectance at normal incidence (Schlick's F0), per channel.
        albedo: Texture,
        /// Roughness in [`super::microfacet::MIN_ROUGHNESS`], 1]; GGX α = roughness².
        roughness: f32,
    },
    /// Glass: exact Fresnel reflection, refraction, total internal reflection; smooth
    /// ([`super::dielectric`]) below [`super::microfacet::SPECULAR_ALPHA`], GGX-rough
    /// ([`super::rough_dielectric`]) above. Refracted radiance is scaled by (n1/n2)², n1 the
    /// index on the side the camera path comes from. Inside (behind its front faces) light is
    /// absorbed by Beer–Lambert's law at `absorption` per unit length; the integrator tracks
    /// only the last glass a path entered, not nested media (see [`crate::render::medium`]).
    Dielectric {
        /// Index of refraction relative to the outside medium.
        ior: f32,
        /// Perceptual roughness in [0, 1]; GGX α = roughness² (0: smooth glass).
        roughness: f32,
        /// Absorption coefficient σa per unit length inside, per channel (zero: clear glass).
        absorption: Vec3,
    },
    /// Emitter ("diffuse light"): emits `emit · intensity`, scatters nothing.
    Light {
        /// Emitted colour.
        emit: Texture,
        /// Scale of `emit`.
        intensity: f32,
        /// Emit from both sides instead of only the side the geometric normal points to.
        two_sided: bool,
    },
    /// The glTF 2.0 metallic–roughness material ([`super::pbr`]): a conductor and a dielectric
    /// (GGX specular over a Lambertian base colour that gets what the specular lobe does not
    /// reflect) mixed by `metallic`, both energy conserving (white reflects everything), plus an emission that
    /// is added to what it reflects, from both sides, and light-sampled like a `Light`'s.
    Pbr {
        /// Base colour: the conductor's F0 and the dielectric's diffuse reflectance.
        base_color: Texture,
        /// Metalness in [0, 1].
        metallic: f32,
        /// Perceptual roughness in [0, 1]; GGX α = roughness², clamped to
        /// [`super::microfacet::MIN_ROUGHNESS`]².
        roughness: f32,
        /// A linear texture whose green channel scales `roughness` and whose blue channel
        /// scales `metallic` (glTF's `metallicRoughnessTexture`).
        metallic_roughness: Option<Texture>,
        /// Emitted colour.
        emissive: Texture,
        /// Scale of `emissive` (`KHR_materials_emissive_strength`).
        emissive_strength: f32,
        /// Tangent-space normal map.
        normal_map: Option<NormalMap>,
        /// Alpha mask: where the surface is absent.
        alpha: Option<AlphaMask>,
        /// Specular strength and colour, a sheen and a clear coat ([`Layers::NONE`]: none).
        layers: Layers,
        /// Textures that scale the layers' factors over the surface (`None`: the factors hold
        /// everywhere, and no lookup is made).
        layer_maps: Option<Box<LayerMaps>>,
    },
    /// glTF's metallic–roughness material made partly transmissive by
    /// `KHR_materials_transmission`: the spec's mix f = w·f_glass + (1 − w)·f_base, estimated
    /// with one sample of the mixture. Each hit shades as `glass` with probability `weight` w,
    /// else as `base`, drawn from the path's own random numbers ([`Material::component`]);
    /// next-event estimation and the bounce at that hit use the same component, so the
    /// estimate is unbiased. With a `texture` the glass's probability varies over the surface
    /// ([`TransmissionTexture`]). A path enters the glass's volume only where it refracted
    /// through the glass component. It emits, is masked and covers as its base, whichever
    /// component shades. Built by the glTF loader (w strictly between 0 and 1, or up to 1 with a
    /// texture), not written in RON.
    Transmissive {
        /// The probability w of the glass component, transmission × (1 − metallic) (with a
        /// texture: where its red channel is 1).
        weight: f32,
        /// The transmissive component (a [`Material::Dielectric`]).
        glass: Box<Material>,
        /// The opaque component (a [`Material::Pbr`]).
        base: Box<Material>,
        /// `KHR_materials_transmission`'s `transmissionTexture` (`None`: the weight holds
        /// everywhere, and no lookup is made).
        texture: Option<Box<TransmissionTexture>>,
    },
}

/// A transmission texture on a [`Material::Transmissive`]: at a point whose red texel is r,
/// the glass takes the share w·r of the mix, and the `opaque` material the w·(1 − r) the
/// texture takes from it. For glTF (transmission t, metallic m, w = t·(1 − m)) that is the
/// spec's mix exactly: f = m·f_metal + (1 − m)·(t·r·f_glass + (1 − t·r)·f_dielectric), with
/// `base` the metal share m and the dielectric share (1 − m)(1 − t) over 1 − w (as without a
/// texture) and `opaque` the metallic–roughness material with metalness 0 (the dielectric).
#[derive(Clone, Debug, PartialEq)]
pub struct TransmissionTexture {
    /// A linear texture whose red channel scales the weight.
    pub texture: Texture,
    /// What shades where the texture lowers the transmission (a [`Material::Pbr`]).
    pub opaque: Material,
}

impl TransmissionTexture {
    /// The red channel at `uv`, clamped to [0, 1].
    #[inline]
    pub fn red(&self, uv: TexCoords) -> f32 {
        self.texture.eval(uv).x.clamp(0.0, 1.0)
    }
}

impl Material {
    /// Smooth clear glass of index `ior`.
    pub const fn glass(ior: f32) -> Self {
        Self::Dielectric {
            ior,
            roughness: 0.0,
            absorption: Vec3::ZERO,
        }
    }

    /// A metallic–roughness material of constant `base_color`, `metallic` and `roughness`,
    /// without textures, emission, normal map, alpha or layers.
    pub const fn pbr(base_color: Vec3, metallic: f32, roughness: f32) -> Self {
        Self::Pbr {
            base_color: Texture::Constant(base_color),
            metallic,
            roughness,
            metallic_roughness: None,
            emissive: Texture::Constant(Vec3::ZERO),
            emissive_strength: 1.0,
            normal_map: None,
            alpha: None,
            layers: Layers::NONE,
            layer_maps: None,
        }
    }

    /// The absorption coefficient inside the material if it bounds a volume a path can enter
    /// by refraction (glass; zero for clear glass); `None` for a surface that does not.
    #[inline]
    pub fn interior_absorption(&self) -> Option<Vec3> {
        match self {
            Self::Dielectric { absorption, .. } => Some(*absorption),
            Self::Transmissive { glass, .. } => glass.interior_absorption(),
            _ => None,
        }
    }

    /// The material a hit at texture coordinates `uv` shades as: for a
    /// [`Material::Transmissive`] of weight w its base if `u()` (uniform in [0, 1)) is at least
    /// w, else its glass, or with a [`TransmissionTexture`] of red r at `uv` its glass if `u()` is
    /// below w·r and the texture's opaque material otherwise. So the glass is picked with
    /// probability w·r, the weight at that point, from one number. Every other material is
    /// itself and draws no `u`.
    #[inline(always)]
    pub fn component(&self, uv: impl Into<TexCoords>, u: impl FnOnce() -> f32) -> &Self {
        match self {
            Self::Transmissive {
                weight,
                glass,
                base,
                texture,
            } => {
                let u = u();
                if u >= *weight {
                    return base;
                }
                match texture {
                    Some(t) if u >= *weight * t.red(uv.into()) => &t.opaque,
                    _ => glass,
                }
            }
            _ => self,
        }
    }

    /// Whether the material is a mix of components ([`Material::component`]).
    #[inline]
    pub fn is_mix(&self) -> bool {
        matches!(self, Self::Transmissive { .. })
    }

    /// What the material emits: a `Light`'s emission, a `Pbr`'s if it is not black; `None`
    /// for every other material.
    #[inline]
    pub fn emission(&self) -> Option<Emission<'_>> {
        match self {
            Self::Light {
                emit,
                intensity,
                two_sided,
            } => Some(Emission {
                texture: emit,
                scale: *intensity,
                two_sided: *two_sided,
            }),
            Self::Pbr {
                emissive,
                emissive_strength,
                ..
            } => Some(Emission {
                texture: emissive,
                scale: *emissive_strength,
                two_sided: true,
            })
            .filter(|e| e.max() > 0.0),
            Self::Transmissive { base, .. } => base.emission(),
            _ => None,
        }
    }

    /// Whether the material emits light (see [`Material::emission`]).
    pub fn is_emissive(&self) -> bool {
        self.emission().is_some()
    }

    /// The largest radiance the material emits in any channel, anywhere (0 for a non-emitter).
    pub fn max_emission(&self) -> f32 {
        self.emission().map_or(0.0, |e| e.max())
    }

    /// Radiance emitted towards a ray travelling along `d` that hit a surface with geometric
    /// normal `n`.
    #[inline]
    pub fn emitted(&self, d: Vec3, n: Vec3, uv: impl Into<TexCoords>) -> Vec3 {
        self.emission().map_or(Vec3::ZERO, |e| e.radiance(d, n, uv))
    }

    /// Radiance a point sampled on this emitter's whole surface sends towards a ray along `d`
    /// ([`Material::emitted`]), times the point's [`Material::coverage`]: nothing where its
    /// alpha mask says it is absent, a blended point its coverage's share (what rays passing it
    /// with probability 1 − coverage find on average), so that the light's density stays that
    /// of its whole surface. The one rule light samples and light paths follow.
    #[inline]
    pub fn emitted_where_present(&self, d: Vec3, n: Vec3, uv: impl Into<TexCoords>) -> Vec3 {
        let uv = uv.into();
        let coverage = self.coverage(uv);
        if coverage == 0.0 {
            Vec3::ZERO
        } else {
            self.emitted(d, n, uv) * coverage
        }
    }

    /// Whether any lookup of the material ([`Material::bsdf`], [`Material::emitted`],
    /// [`Material::coverage`]) reads texture coordinates: false when every texture is a
    /// constant and there is no normal map nor alpha mask. A hit on a material that reads none
    /// need not compute them (a sphere's cost an `atan2` and an `acos`).
    pub fn reads_tex_coords(&self) -> bool {
        match self {
            Self::Diffuse { albedo } | Self::Metal { albedo, .. } | Self::Glossy { albedo, .. } => {
                albedo.reads_uv()
            }
            Self::Dielectric { .. } => false,
            Self::Light { emit, .. } => emit.reads_uv(),
            Self::Pbr {
                base_color,
                metallic_roughness,
                emissive,
                normal_map,
                alpha,
                layer_maps,
                ..
            } => {
                base_color.reads_uv()
                    || metallic_roughness.is_some()
                    || emissive.reads_uv()
                    || normal_map.is_some()
                    || alpha.is_some()
                    || layer_maps.is_some()
            }
            Self::Transmissive {
                glass,
                base,
                texture,
                ..
            } => {
                glass.reads_tex_coords()
                    || base.reads_tex_coords()
                    || texture
                        .as_ref()
                        .is_some_and(|t| t.texture.reads_uv() || t.opaque.reads_tex_coords())
            }
        }
    }

    /// Whether the material has an alpha mask (a `Pbr` with `alpha`): only then may
    /// [`Material::coverage`] be below 1.
    pub fn is_masked(&self) -> bool {
        match self {
            Self::Pbr { alpha, .. } => alpha.is_some(),
            Self::Transmissive { base, .. } => base.is_masked(),
            _ => false,
        }
    }

    /// The probability that the surface is there at `uv` ([`AlphaMask::coverage`]): 0 where a
    /// cutoff mask makes it absent, its alpha where it is blended, 1 for every material
    /// without a mask. Rays pass through it with probability 1 − coverage.
    #[inline]
    pub fn coverage(&self, uv: impl Into<TexCoords>) -> f32 {
        match self {
            Self::Pbr {
                alpha: Some(mask), ..
            } => mask.coverage(uv.into()),
            Self::Transmissive { base, .. } => base.coverage(uv),
            _ => 1.0,
        }
    }

    /// The BSDF at a surface point hit by a ray along `d`, of unit geometric normal `n`, unit
    /// shading normal `ns` (on `n`'s side) and texture coordinates `uv` (one set, or the hit's
    /// [`TexCoords`]): the textures looked up, a normal map applied with the texture tangent and handedness `tangent()` gives
    /// (asked only by a normal-mapped material; `None` where the surface has none). Glass
    /// shades with `n`, so that its refraction follows the true surface and stays watertight.
    /// A [`Material::Transmissive`] shades here as its base: a hit first picks its component
    /// ([`Material::component`]) and builds that one's BSDF.
    #[inline(always)]
    pub fn bsdf(
        &self,
        d: Vec3,
        n: Vec3,
        ns: Vec3,
        uv: impl Into<TexCoords>,
        tangent: impl FnOnce() -> Option<(Vec3, f32)>,
    ) -> Bsdf<'_> {
        let uv = uv.into();
        let (lobe, ns, samples_lights) = match self {
            Self::Diffuse { albedo } => (
                Lobe::Diffuse(Diffuse {
                    albedo: albedo.eval(uv),
                }),
                ns,
                true,
            ),
            Self::Metal { albedo, roughness } => (
                Lobe::Fuzzed(Fuzzed {
                    albedo: albedo.eval(uv),
                    roughness: *roughness,
                }),
                ns,
                false,
            ),
            Self::Glossy { albedo, roughness } => {
                let alpha = alpha_from_roughness(*roughness);
                let lobe = Lobe::Conductor(Conductor {
                    f0: albedo.eval(uv),
                    alpha,
                });
                (lobe, ns, !is_specular_alpha(alpha))
            }
            Self::Dielectric { ior, roughness, .. } => {
                let alpha = alpha_from_roughness(*roughness);
                if is_specular_alpha(alpha) {
                    (Lobe::Dielectric(Dielectric { ior: *ior }), n, false)
                } else {
                    let lobe = Lobe::RoughDielectric(RoughDielectric { ior: *ior, alpha });
                    (lobe, n, true)
                }
            }
            Self::Light { .. } => (Lobe::None, ns, false),
            Self::Transmissive { base, .. } => return base.bsdf(d, n, ns, uv, tangent),
            Self::Pbr {
                base_color,
                metallic,
                roughness,
                metallic_roughness,
                normal_map,
                layers,
                layer_maps,
                ..
            } => {
                let ns = match normal_map {
                    Some(map) => normal_mapped(map, uv, n, ns, tangent),
                    None => ns,
                };
                let (m, r) = match metallic_roughness {
                    None => (*metallic, *roughness),
                    Some(t) => {
                        let texel = t.eval(uv);
                        (*metallic * texel.z, *roughness * texel.y)
                    }
                };
                // Light sampling is decided per material, not per point: a textured mix may
                // be evaluable at some points and a perfect mirror at others. The layers'
                // textures only scale their factors down, so the factors decide it.
                let coat_alpha = alpha_from_roughness(layers.clearcoat_roughness);
                let coated = layers.clearcoat > 0.0;
                let sheen = Sheen::new(layers.sheen_color, layers.sheen_roughness);
                let samples_lights = metallic_roughness.is_some()
                    || !Pbr::new(Vec3::ONE, *metallic, *roughness).is_delta()
                    || !sheen.is_off()
                    || (coated && !is_specular_alpha(coat_alpha));
                let textured;
                let (here, sheen, coat_alpha) = match layer_maps {
                    None => (layers, sheen, coat_alpha),
                    Some(maps) => {
                        textured = maps.at(layers, uv);
                        let sheen = Sheen::new(textured.sheen_color, textured.sheen_roughness);
                        let alpha = alpha_from_roughness(textured.clearcoat_roughness);
                        (&textured, sheen, alpha)
                    }
                };
                let specular = Specular::new(here.specular, here.specular_color);
                // Seen from the ray's side of the shading normal, as the lobe's evaluations
                // and samples will see it ([`Lobe`]).
                let facing = facing(d, ns);
                let base = Pbr::new(base_color.eval(uv), m, r)
                    .with_specular(specular)
                    .with_sheen(sheen)
                    .viewed((-d).dot(facing));
                let lobe = if coated {
                    Lobe::Coated(Coated {
                        base,
                        weight: here.clearcoat.min(1.0),
                        alpha: coat_alpha,
                    })
                } else {
                    Lobe::MetallicRoughness(base)
                };
                (lobe, ns, samples_lights)
            }
        };
        Bsdf::new(lobe, d, (n, ns), uv, samples_lights, self.emission())
    }

    /// [`Material::bsdf`] at a point whose shading normal is its geometric normal `n` and
    /// which has no texture tangent: a flat surface, as tests and single-bounce tools use it.
    pub fn bsdf_at(&self, d: Vec3, n: Vec3, uv: Vec2) -> Bsdf<'_> {
        self.bsdf(d, n, n, uv, || None)
    }

    /// One sampled bounce of a ray along unit `d` off a flat point of unit normal `n` (see
    /// [`Material::bsdf_at`]), a mix's component picked first by `sampler`'s next value;
    /// `None` if the path ends here.
    pub fn scatter(
        &self,
        d: Vec3,
        n: Vec3,
        uv: Vec2,
        sampler: &mut impl Sampler,
    ) -> Option<Scatter> {
        self.component(uv, || sampler.next_1d())
            .bsdf_at(d, n, uv)
            .sample(sampler)
    }
}

/// The absorption coefficient σa = −ln(colour) / distance of a medium that turns white light
/// `color` (each channel in [0, 1]) after `distance` (> 0, infinite: no absorption): Beer–Lambert,
/// as `KHR_materials_volume` defines its attenuation. A black channel absorbs everything
/// (σa = ∞).
pub fn absorption_coefficient(color: Vec3, distance: f32) -> Vec3 {
    if distance.is_infinite() {
        return Vec3::ZERO;
    }
    // −ln 1 is −0: `abs` keeps the clear channels at +0.
    color.to_array().map(|c| (-c.ln() / distance).abs()).into()
}

/// The shading normal `ns` perturbed by `map` at `uv` where `tangent()` gives a texture tangent;
/// `ns` elsewhere. Out of line: only normal-mapped hits get here.
#[inline(never)]
fn normal_mapped(
    map: &NormalMap,
    uv: TexCoords,
    n: Vec3,
    ns: Vec3,
    tangent: impl FnOnce() -> Option<(Vec3, f32)>,
) -> Vec3 {
    tangent().map_or(ns, |(t, sign)| map.perturb(uv, n, ns, t, sign))
}

#[cfg(test)]
mod tests;
