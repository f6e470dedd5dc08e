//! Materials: how a surface scatters or emits light.
//!
//! The thesis's formulas are corrected here: Schlick's R0 is `((n1 − n2)/(n1 + n2))²` (the thesis
//! uses n1/n2), the dielectric *reflects* with probability R (the thesis refracts), and diffuse
//! directions are cosine-sampled in a frame, so they are never the zero vector.

use glam::{Vec2, Vec3};

use super::maps::{AlphaMask, NormalMap};
use super::microfacet::{
    alpha_from_roughness, cos2_sin2, distribution, is_specular_alpha, lambda,
    sample_visible_normal, schlick_rgb,
};
use super::pbr::Pbr;
use super::sampler::Sampler;
use super::sampling::{Frame, cosine_hemisphere, uniform_ball};
use super::texture::Texture;

/// A surface material.
#[derive(Clone, Debug, PartialEq)]
pub enum Material {
    /// Lambertian reflector.
    Diffuse {
        /// Reflectance.
        albedo: Texture,
    },
    /// Mirror with the thesis's fuzz: the reflected direction plus `roughness` times a random
    /// point of the unit ball; directions that end up below the surface are absorbed.
    Metal {
        /// Reflectance.
        albedo: Texture,
        /// Fuzz radius in [0, 1].
        roughness: f32,
    },
    /// Rough metal with an evaluable BSDF: GGX (Trowbridge–Reitz) microfacet reflection,
    /// Schlick's Fresnel with `albedo` as the reflectance at normal incidence, height-correlated
    /// Smith shadowing; directions are sampled from the visible normals (see
    /// [`super::microfacet`]). Unlike `Metal`, next-event estimation and MIS apply to it, except
    /// below [`super::microfacet::SPECULAR_ALPHA`], where it is a perfect mirror reflecting
    /// Schlick's Fresnel at the view's cosine.
    Glossy {
        /// Reflectance at normal incidence (Schlick's F0), per channel.
        albedo: Texture,
        /// Roughness in [`super::microfacet::MIN_ROUGHNESS`], 1]; GGX α = roughness².
        roughness: f32,
    },
    /// Smooth glass: Fresnel (Schlick) reflection, Snell refraction, total internal reflection.
    /// Refracted radiance is scaled by (n1/n2)², n1 the index on the side the camera path
    /// comes from.
    Dielectric {
        /// Index of refraction relative to the outside medium.
        ior: f32,
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
    /// (GGX specular over Lambertian base colour) mixed by `metallic`, plus an emission that
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
    },
}

/// A sampled continuation of a path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scatter {
    /// Unit direction of the new ray.
    pub direction: Vec3,
    /// Path throughput factor (BSDF · cos / pdf).
    pub attenuation: Vec3,
    /// Solid-angle density of `direction`, if the BSDF can evaluate it (`None` for mirror,
    /// glass and the fuzzed metal, which next-event estimation cannot use).
    pub pdf: Option<f32>,
    /// The factor of `attenuation` that is the (n1/n2)² compression of radiance at a
    /// refraction, 1 otherwise: Russian roulette decides on the throughput without it.
    pub radiance_scale: f32,
}

/// Mirror reflection of `d` about `n`.
#[inline]
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}

/// Refraction of unit `d` through a surface with unit normal `n` facing against `d`, with relative
/// index `eta = n1 / n2`. `None` on total internal reflection.
#[inline]
pub fn refract(d: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = (-d.dot(n)).min(1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((eta * d + (eta * cos_i - cos_t) * n).normalize())
}

/// Schlick's approximation of the Fresnel reflectance for light going from index `n1` to `n2` at
/// incidence cosine `cos_i`. Uses the cosine on the optically thinner side, as the approximation
/// requires; returns 1 on total internal reflection.
#[inline]
pub fn schlick(cos_i: f32, n1: f32, n2: f32) -> f32 {
    let r0 = ((n1 - n2) / (n1 + n2)).powi(2);
    let cos = if n1 > n2 {
        let sin2_t = (n1 / n2).powi(2) * (1.0 - cos_i * cos_i).max(0.0);
        if sin2_t >= 1.0 {
            return 1.0;
        }
        (1.0 - sin2_t).sqrt()
    } else {
        cos_i
    };
    r0 + (1.0 - r0) * (1.0 - cos).powi(5)
}

/// The GGX terms of a Glossy reflection from `wo` to `wi` about `facing`, shared by
/// [`Material::eval`] and [`Material::scatter`].
struct GlossyTerms {
    /// D(h) of the half vector.
    d: f32,
    /// Smith Λ of `wo` and of `wi`.
    lo: f32,
    li: f32,
    /// `wo · h`, for Fresnel.
    cos_oh: f32,
}

impl GlossyTerms {
    #[inline]
    fn new(wo: Vec3, wi: Vec3, facing: Vec3, alpha: f32) -> Self {
        let h = (wo + wi).normalize();
        let (c2h, s2h) = cos2_sin2(h, facing);
        let (c2o, s2o) = cos2_sin2(wo, facing);
        let (c2i, s2i) = cos2_sin2(wi, facing);
        Self {
            d: distribution(c2h, s2h, alpha),
            lo: lambda(c2o, s2o, alpha),
            li: lambda(c2i, s2i, alpha),
            cos_oh: wo.dot(h),
        }
    }

    /// Density of `wi` under visible-normal sampling: G₁(wo) D(h) / (4 cos θo).
    #[inline]
    fn pdf(&self, cos_o: f32) -> f32 {
        self.d / ((1.0 + self.lo) * 4.0 * cos_o)
    }
}

impl Material {
    /// Whether the material emits light (a `Light`, or a `Pbr` of non-zero emission).
    pub fn is_emissive(&self) -> bool {
        match self {
            Self::Light { .. } => true,
            Self::Pbr { .. } => self.max_emission() > 0.0,
            _ => false,
        }
    }

    /// Whether a path may continue from the surface: every material but `Light`, which only
    /// emits.
    pub fn scatters(&self) -> bool {
        !matches!(self, Self::Light { .. })
    }

    /// Whether the material has an alpha mask (a `Pbr` with `alpha`): only then may
    /// [`Material::is_present`] be false.
    pub fn is_masked(&self) -> bool {
        matches!(self, Self::Pbr { alpha: Some(_), .. })
    }

    /// Whether the surface is there at `uv`: false where its alpha mask says it is absent, so
    /// that rays pass through it; true for every material without a mask.
    #[inline]
    pub fn is_present(&self, uv: Vec2) -> bool {
        match self {
            Self::Pbr {
                alpha: Some(mask), ..
            } => mask.present(uv),
            _ => true,
        }
    }

    /// Whether next-event estimation applies: the BSDF can be evaluated for any pair of
    /// directions (see [`Material::eval`]). A `Pbr` whose lobes depend on a texture may still be
    /// a perfect mirror at some points, where [`Material::eval`] says so.
    pub fn samples_lights(&self) -> bool {
        match self {
            Self::Diffuse { .. } => true,
            Self::Glossy { roughness, .. } => !is_specular_alpha(alpha_from_roughness(*roughness)),
            Self::Pbr {
                metallic,
                roughness,
                metallic_roughness,
                ..
            } => {
                metallic_roughness.is_some()
                    || !Pbr::new(Vec3::ONE, *metallic, *roughness).is_delta()
            }
            _ => false,
        }
    }

    /// The metallic–roughness BRDF of a `Pbr` material at `uv`: the base colour, and the
    /// factors times the texture's blue (metallic) and green (roughness) channels.
    #[inline]
    fn pbr_at(
        base_color: &Texture,
        metallic: f32,
        roughness: f32,
        metallic_roughness: &Option<Texture>,
        uv: Vec2,
    ) -> Pbr {
        let (metallic, roughness) = match metallic_roughness {
            None => (metallic, roughness),
            Some(t) => {
                let texel = t.eval(uv);
                (metallic * texel.z, roughness * texel.y)
            }
        };
        Pbr::new(base_color.eval(uv), metallic, roughness)
    }

    /// BSDF times the cosine at the surface, and the density [`Material::scatter`] would give,
    /// for light arriving from `wi` and leaving against `d` (the incoming ray's direction).
    /// `None` where the BSDF has no density to evaluate (delta or fuzzed lobes); of a `Pbr` with
    /// a smooth specular lobe and a diffuse one, the diffuse lobe alone.
    #[inline(always)]
    pub fn eval(&self, d: Vec3, wi: Vec3, n: Vec3, uv: Vec2) -> Option<(Vec3, f32)> {
        match self {
            Self::Diffuse { albedo } => {
                let facing = if d.dot(n) < 0.0 { n } else { -n };
                let cos = wi.dot(facing);
                if cos <= 0.0 {
                    return Some((Vec3::ZERO, 0.0));
                }
                let pdf = cos * std::f32::consts::FRAC_1_PI;
                Some((albedo.eval(uv) * pdf, pdf))
            }
            Self::Glossy { albedo, roughness } => {
                let alpha = alpha_from_roughness(*roughness);
                if is_specular_alpha(alpha) {
                    return None;
                }
                let facing = if d.dot(n) < 0.0 { n } else { -n };
                let wo = -d;
                let (cos_o, cos_i) = (wo.dot(facing), wi.dot(facing));
                if cos_i <= 0.0 || cos_o <= 0.0 {
                    return Some((Vec3::ZERO, 0.0));
                }
                let g = GlossyTerms::new(wo, wi, facing, alpha);
                // f·cos θi = F D G₂ / (4 cos θo cos θi) · cos θi.
                let f = schlick_rgb(albedo.eval(uv), g.cos_oh);
                Some((
                    f * (g.d / ((1.0 + g.lo + g.li) * 4.0 * cos_o)),
                    g.pdf(cos_o),
                ))
            }
            Self::Pbr {
                base_color,
                metallic,
                roughness,
                metallic_roughness,
                ..
            } => {
                let facing = if d.dot(n) < 0.0 { n } else { -n };
                let pbr = Self::pbr_at(base_color, *metallic, *roughness, metallic_roughness, uv);
                (!pbr.is_delta()).then(|| pbr.eval(-d, wi, facing))
            }
            _ => None,
        }
    }

    /// Whether the feature buffers (albedo and normal, for a denoiser) look through this
    /// surface at `uv` to the next hit: where its BSDF is a perfect mirror or smooth glass (a
    /// delta BSDF, nothing of it evaluable), whose look is that of what it reflects or refracts.
    /// Open Image Denoise's documentation asks for this (its `RT` filter, "Albedo": follow
    /// perfect specular paths and store the first diffuse or glossy hit).
    #[inline]
    pub fn is_specular(&self, uv: Vec2) -> bool {
        match self {
            Self::Dielectric { .. } => true,
            Self::Metal { roughness, .. } => *roughness == 0.0,
            Self::Glossy { roughness, .. } => is_specular_alpha(alpha_from_roughness(*roughness)),
            Self::Pbr {
                base_color,
                metallic,
                roughness,
                metallic_roughness,
                ..
            } => Self::pbr_at(base_color, *metallic, *roughness, metallic_roughness, uv).is_delta(),
            Self::Diffuse { .. } | Self::Light { .. } => false,
        }
    }

    /// The colour the albedo feature buffer records for a ray along `d` hitting the surface
    /// (geometric normal `n`), before the integrator clamps it to [0, 1]: the reflectance (F0 of
    /// a glossy reflector, the base colour of a `Pbr`, white for glass) plus the radiance the
    /// surface emits towards the ray, so that an emitter records its emission, one that also
    /// reflects the sum.
    #[inline]
    pub fn feature_albedo(&self, d: Vec3, n: Vec3, uv: Vec2) -> Vec3 {
        let reflectance = match self {
            Self::Diffuse { albedo } | Self::Metal { albedo, .. } | Self::Glossy { albedo, .. } => {
                albedo.eval(uv)
            }
            Self::Pbr { base_color, .. } => base_color.eval(uv),
            Self::Dielectric { .. } => Vec3::ONE,
            Self::Light { .. } => Vec3::ZERO,
        };
        reflectance + self.emitted(d, n, uv)
    }

    /// The largest radiance the material emits in any channel, anywhere (0 for a non-emitter).
    pub fn max_emission(&self) -> f32 {
        match self {
            Self::Light {
                emit, intensity, ..
            } => emit.max_channel() * intensity.abs(),
            Self::Pbr {
                emissive,
                emissive_strength,
                ..
            } => emissive.max_channel() * emissive_strength.abs(),
            _ => 0.0,
        }
    }

    /// Radiance emitted towards a ray travelling along `d` that hit a surface with geometric
    /// normal `n`.
    #[inline]
    pub fn emitted(&self, d: Vec3, n: Vec3, uv: Vec2) -> Vec3 {
        match self {
            Self::Light {
                emit,
                intensity,
                two_sided,
            } if *two_sided || d.dot(n) < 0.0 => emit.eval(uv) * *intensity,
            Self::Pbr {
                emissive,
                emissive_strength,
                ..
            } => emissive.eval(uv) * *emissive_strength,
            _ => Vec3::ZERO,
        }
    }

    /// Samples the continuation of a ray travelling along unit `d` that hit a surface with unit
    /// geometric normal `n`. `None` if the path ends here (absorbed, or an emitter).
    #[inline(always)]
    pub fn scatter(
        &self,
        d: Vec3,
        n: Vec3,
        uv: Vec2,
        sampler: &mut impl Sampler,
    ) -> Option<Scatter> {
        // Surfaces are two-sided: shade with the normal on the side the ray came from.
        let facing = if d.dot(n) < 0.0 { n } else { -n };
        match self {
            Self::Diffuse { albedo } => {
                let local = cosine_hemisphere(sampler.next_2d());
                let direction = Frame::from_normal(facing).to_world(local).normalize();
                Some(Scatter {
                    direction,
                    attenuation: albedo.eval(uv),
                    pdf: Some(local.z * std::f32::consts::FRAC_1_PI),
                    radiance_scale: 1.0,
                })
            }
            Self::Metal { albedo, roughness } => {
                let u = sampler.next_2d();
                let fuzz = uniform_ball(u.extend(sampler.next_1d()));
                let r = reflect(d, facing) + *roughness * fuzz;
                if r.dot(facing) <= 0.0 {
                    return None;
                }
                Some(Scatter {
                    direction: r.normalize(),
                    attenuation: albedo.eval(uv),
                    pdf: None,
                    radiance_scale: 1.0,
                })
            }
            Self::Glossy { albedo, roughness } => {
                let alpha = alpha_from_roughness(*roughness);
                let wo = -d;
                let cos_o = wo.dot(facing);
                if is_specular_alpha(alpha) {
                    // A perfect mirror: G₂/G₁ → 1 and h → n as α → 0, so the weight is F(wo · n).
                    return (cos_o > 0.0).then(|| Scatter {
                        direction: reflect(d, facing).normalize(),
                        attenuation: schlick_rgb(albedo.eval(uv), cos_o),
                        pdf: None,
                        radiance_scale: 1.0,
                    });
                }
                let frame = Frame::from_normal(facing);
                let wo_local =
                    Vec3::new(wo.dot(frame.s), wo.dot(frame.t), cos_o.max(1e-6)).normalize();
                let u = sampler.next_2d();
                let h = frame.to_world(sample_visible_normal(wo_local, alpha, u));
                let direction = reflect(d, h).normalize();
                if direction.dot(facing) <= 0.0 || cos_o <= 0.0 {
                    return None;
                }
                // The terms are recomputed from (wo, direction) exactly as `eval` computes
                // them, so the two agree to rounding even for a near-mirror lobe.
                let g = GlossyTerms::new(wo, direction, facing, alpha);
                let f = schlick_rgb(albedo.eval(uv), g.cos_oh);
                // f·cos/pdf = F G₂ / G₁(wo) ≤ F: never more energy than Fresnel allows.
                Some(Scatter {
                    direction,
                    attenuation: f * ((1.0 + g.lo) / (1.0 + g.lo + g.li)),
                    pdf: Some(g.pdf(cos_o)),
                    radiance_scale: 1.0,
                })
            }
            Self::Dielectric { ior } => {
                let entering = d.dot(n) < 0.0;
                let (n1, n2) = if entering { (1.0, *ior) } else { (*ior, 1.0) };
                let cos_i = (-d.dot(facing)).clamp(0.0, 1.0);
                let r = schlick(cos_i, n1, n2);
                // Radiance crossing an interface is compressed with the solid angle: light
                // reaching the camera side (index n1) from the far side (n2) is scaled by
                // (n1/n2)² (Veach 1997, §5.2; pbrt-v4's `DielectricBxDF` in radiance mode).
                let (direction, scale) = match refract(d, facing, n1 / n2) {
                    Some(t) if sampler.next_1d() >= r => (t, (n1 / n2) * (n1 / n2)),
                    _ => (reflect(d, facing).normalize(), 1.0),
                };
                Some(Scatter {
                    direction,
                    attenuation: Vec3::splat(scale),
                    pdf: None,
                    radiance_scale: scale,
                })
            }
            Self::Pbr {
                base_color,
                metallic,
                roughness,
                metallic_roughness,
                ..
            } => {
                let pbr = Self::pbr_at(base_color, *metallic, *roughness, metallic_roughness, uv);
                let s = pbr.sample(-d, facing, sampler.next_2d())?;
                Some(Scatter {
                    direction: s.wi,
                    attenuation: s.weight,
                    pdf: s.pdf,
                    radiance_scale: 1.0,
                })
            }
            Self::Light { .. } => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::rng::Rng;

    #[test]
    fn schlick_at_normal_incidence_is_r0() {
        assert!((schlick(1.0, 1.0, 1.5) - 0.04).abs() < 1e-6);
        assert!((schlick(1.0, 1.5, 1.0) - 0.04).abs() < 1e-6);
        // Grazing incidence reflects everything.
        assert!((schlick(0.0, 1.0, 1.5) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn schlick_is_close_to_the_exact_fresnel_equations() {
        // Exact unpolarised Fresnel reflectance for air→glass (n = 1.5), from the Fresnel
        // equations: 0.0400, 0.0415, 0.0502, 0.0892 at 0°, 30°, 45°, 60°. Schlick's curve stays
        // within 0.02 of it there (0.0400, 0.0400, 0.0421, 0.0700).
        let exact = |theta_i: f32, n: f32| {
            let (ci, si) = (theta_i.cos(), theta_i.sin());
            let ct = (1.0 - (si / n).powi(2)).sqrt();
            let rs = ((ci - n * ct) / (ci + n * ct)).powi(2);
            let rp = ((ct - n * ci) / (ct + n * ci)).powi(2);
            0.5 * (rs + rp)
        };
        for deg in [0.0f32, 30.0, 45.0, 60.0] {
            let t = deg.to_radians();
            let (s, e) = (schlick(t.cos(), 1.0, 1.5), exact(t, 1.5));
            assert!((s - e).abs() < 0.02, "{deg}°: schlick {s}, exact {e}");
        }
    }

    #[test]
    fn dielectric_reflects_four_percent_at_normal_incidence() {
        let glass = Material::Dielectric { ior: 1.5 };
        let mut rng = Rng::new(11, 13);
        let n = 1_000_000;
        let reflected = (0..n)
            .filter(|_| {
                let s = glass
                    .scatter(-Vec3::Z, Vec3::Z, Vec2::ZERO, &mut rng)
                    .expect("scatters");
                s.direction.z > 0.0
            })
            .count();
        let fraction = reflected as f64 / n as f64;
        assert!((fraction - 0.04).abs() < 0.001, "{fraction}");
    }

    #[test]
    fn refraction_scales_radiance_by_the_squared_index_ratio() {
        // Along the camera path, entering glass (1 → 1.5) carries (1/1.5)², leaving it 1.5²;
        // reflection carries 1.
        let glass = Material::Dielectric { ior: 1.5 };
        let mut rng = Rng::new(4, 4);
        for (d, refracted) in [(-Vec3::Z, 1.0 / 2.25), (Vec3::Z, 2.25)] {
            for _ in 0..200 {
                let s = glass
                    .scatter(d, Vec3::Z, Vec2::ZERO, &mut rng)
                    .expect("scatters");
                let expected = if s.direction.dot(d) > 0.0 {
                    refracted
                } else {
                    1.0
                };
                assert!((s.attenuation - Vec3::splat(expected)).abs().max_element() < 1e-6);
            }
        }
    }

    #[test]
    fn glass_to_air_beyond_the_critical_angle_always_reflects() {
        let glass = Material::Dielectric { ior: 1.5 };
        let critical = (1.0f32 / 1.5).asin();
        let mut rng = Rng::new(1, 2);
        for k in 1..=50 {
            let theta = critical + (std::f32::consts::FRAC_PI_2 - critical) * k as f32 / 51.0;
            // Inside the glass, travelling out through a surface whose normal points outwards (+z).
            let d = Vec3::new(theta.sin(), 0.0, theta.cos());
            for _ in 0..100 {
                let s = glass
                    .scatter(d, Vec3::Z, Vec2::ZERO, &mut rng)
                    .expect("scatters");
                assert!(
                    s.direction.z < 0.0,
                    "θ = {theta}: escaped along {}",
                    s.direction
                );
            }
        }
    }

    #[test]
    fn refraction_obeys_snell_and_is_unit_length() {
        for deg in [1.0f32, 20.0, 40.0, 60.0, 80.0, 89.0] {
            let t = deg.to_radians();
            let d = Vec3::new(t.sin(), 0.0, -t.cos());
            let r = refract(d, Vec3::Z, 1.0 / 1.5).expect("no TIR entering glass");
            assert!((r.length() - 1.0).abs() < 1e-6);
            let sin_t = r.x.hypot(r.y);
            assert!((1.0 * t.sin() - 1.5 * sin_t).abs() < 1e-5, "{deg}°");
            assert!(r.z < 0.0, "refracted ray continues through the surface");
        }
    }

    #[test]
    fn diffuse_never_scatters_a_zero_or_nan_direction() {
        let m = Material::Diffuse {
            albedo: Texture::Constant(Vec3::splat(0.5)),
        };
        let mut rng = Rng::new(5, 5);
        let n = Vec3::new(0.0, 1.0, 0.0);
        for _ in 0..100_000 {
            let s = m
                .scatter(-n, n, Vec2::ZERO, &mut rng)
                .expect("diffuse always scatters");
            assert!((s.direction.length() - 1.0).abs() < 1e-4 && s.direction.dot(n) >= 0.0);
        }
    }

    #[test]
    fn diffuse_eval_matches_its_sampling_and_integrates_to_the_albedo() {
        let m = Material::Diffuse {
            albedo: Texture::Constant(Vec3::splat(0.6)),
        };
        let n = Vec3::Y;
        let d = Vec3::new(0.3, -1.0, 0.2).normalize();
        let mut rng = Rng::new(2, 3);
        let mut estimate = Vec3::ZERO;
        let count = 100_000;
        for _ in 0..count {
            let s = m.scatter(d, n, Vec2::ZERO, &mut rng).expect("scatters");
            let (f_cos, pdf) = m.eval(d, s.direction, n, Vec2::ZERO).expect("evaluable");
            assert!((pdf - s.pdf.expect("pdf")).abs() < 1e-5);
            assert!((f_cos / pdf - s.attenuation).abs().max_element() < 1e-4);
            // Uniform hemisphere estimate of ∫ f cos dω = albedo (pdf 1/2π).
            let z = rng.next_f32();
            let phi = 2.0 * std::f32::consts::PI * rng.next_f32();
            let r = (1.0 - z * z).sqrt();
            let wi = Vec3::new(r * phi.cos(), z, r * phi.sin());
            estimate +=
                m.eval(d, wi, n, Vec2::ZERO).expect("evaluable").0 * 2.0 * std::f32::consts::PI;
        }
        let mean = estimate / count as f32;
        assert!(
            (mean - Vec3::splat(0.6)).abs().max_element() < 0.01,
            "{mean}"
        );
        // Below the surface (on the far side from the viewer) the BSDF is zero.
        assert_eq!(m.eval(d, -n, n, Vec2::ZERO), Some((Vec3::ZERO, 0.0)));
    }

    #[test]
    fn metal_scatters_to_the_side_of_the_incoming_ray_or_absorbs() {
        let m = Material::Metal {
            albedo: Texture::Constant(Vec3::ONE),
            roughness: 1.0,
        };
        let mut rng = Rng::new(8, 1);
        let n = Vec3::Z;
        let d = Vec3::new(1.0, 0.0, -0.1).normalize();
        let mut absorbed = 0;
        for _ in 0..10_000 {
            match m.scatter(d, n, Vec2::ZERO, &mut rng) {
                Some(s) => assert!(s.direction.z > 0.0),
                None => absorbed += 1,
            }
        }
        assert!(
            absorbed > 0,
            "a grazing rough reflection loses some rays below the surface"
        );
        let smooth = Material::Metal {
            albedo: Texture::Constant(Vec3::ONE),
            roughness: 0.0,
        };
        let s = smooth.scatter(d, n, Vec2::ZERO, &mut rng).expect("mirror");
        assert!((s.direction - reflect(d, n)).length() < 1e-6);
    }

    #[test]
    fn light_emits_only_on_its_front_side_unless_two_sided() {
        let one = Material::Light {
            emit: Texture::Constant(Vec3::ONE),
            intensity: 15.0,
            two_sided: false,
        };
        assert_eq!(
            one.emitted(-Vec3::Y, Vec3::Y, Vec2::ZERO),
            Vec3::splat(15.0)
        );
        assert_eq!(one.emitted(Vec3::Y, Vec3::Y, Vec2::ZERO), Vec3::ZERO);
        let two = Material::Light {
            emit: Texture::Constant(Vec3::ONE),
            intensity: 2.0,
            two_sided: true,
        };
        assert_eq!(two.emitted(Vec3::Y, Vec3::Y, Vec2::ZERO), Vec3::splat(2.0));
    }
}
