//! The glTF 2.0 metallic–roughness BRDF (glTF 2.0 specification, Appendix B), made energy
//! conserving: a mix by `metallic` of a conductor (GGX, height-correlated Smith, Schlick's
//! Fresnel with F0 = base colour, plus Kulla & Conty's multiple-scattering lobe as
//! [`super::conductor`] has it) and a dielectric (GGX specular with the exact Fresnel of ior
//! 1.5, [`super::fresnel::fresnel_dielectric`], over a Lambertian base colour); α = roughness². Both Fresnel
//! terms take `|V·H|`, so the two single-scattering lobes are one GGX lobe whose Fresnel is the
//! mix by `metallic` of the two. The spec's sample code takes Schlick's F0 = 0.04 for the
//! dielectric too; the exact curve, which Cycles' Principled BSDF uses, reflects more at
//! oblique views (0.089 against 0.070 at 60°), so dark non-metals, whose look is mostly this
//! lobe, come out 2–9 % brighter under a sky than with Schlick's (benches/gltf_models). No ECS
//! here.
//!
//! How the dielectric differs from the spec's informative `fresnel_mix`: that weighs the base
//! by `1 − F(V·H)`, the Fresnel at the half vector of the pair, not by what the specular lobe
//! reflects at the view, so for a white base the directional albedo passes 1 towards the
//! horizon (1.03 at 60°, 1.35 at 80°, 1.77 at 88° for roughness 0.05, by numerical
//! integration), against the spec's normative text that an implementation conserve energy.
//! Here the base is Kulla & Conty's albedo-scaled lobe
//! `base (1 − E_s(μo)) (1 − E_s(μi)) / (π (1 − E_s,avg))` ([`super::energy`]), E_s the
//! directional albedo of the specular lobe (tabulated for ior 1.5): it is reciprocal, and it
//! reflects `base (1 − E_s(μo))`, exactly what the specular lobe leaves, so a white base
//! reflects E_s(μo) + 1 − E_s(μo) = 1 at every angle and a darker one less. Against
//! `fresnel_mix` the base is a little darker near normal incidence (the rough specular lobe
//! takes more than F(V·H) = 0.04 there) and much darker at grazing views.
//!
//! Sampling picks the specular lobe (visible normals, [`sample_visible_normal`]) or the
//! cosine-sampled lobes (the base and the conductor's compensation) with a probability that
//! depends on `wo` only ([`Pbr::specular_probability`]), so the density of a direction is the
//! exact mixture `p·pdf_spec + (1 − p)·pdf_cosine`, which next-event estimation and MIS evaluate
//! through [`Pbr::eval`].
//!
//! Below [`super::microfacet::SPECULAR_ALPHA`] the specular lobe is a perfect mirror (a delta
//! lobe): sampled with the same probability, its weight is the Fresnel factor at `wo · n` (the
//! limit of F G₂/G₁ as α → 0) over that probability, and it has no density, so [`Pbr::eval`] and
//! [`Pbr::sample`]'s densities cover the base alone, weighted by the mirror's albedo, the
//! Fresnel factor F(μ) (the tables' first row).
//!
//! A sheen layer (`KHR_materials_sheen`, [`super::sheen`]) goes over all of this by the spec's
//! albedo scaling: `f = f_sheen + (1 − max(sheen colour) E_sh(μo)) f_base`, E_sh the white
//! sheen lobe's directional albedo. The base keeps what the sheen does not reflect towards the
//! view, so a white base under a white sheen reflects `E_sh + (1 − E_sh) · 1 = 1` and any other
//! less. The weight depends on the view alone (as the clear coat's, [`super::coat`]): the layered
//! BRDF is not exactly reciprocal, which the spec's informative text accepts; its symmetric
//! alternative, the smaller of the two directions' weights, loses light for every base.
//! Sampling picks the sheen lobe (uniform over the hemisphere: it lives towards the horizon,
//! where a cosine density would starve it) with its share of the albedo, else the base, and the
//! density is that mixture.

use glam::{Vec2, Vec3};
use std::f32::consts::FRAC_1_PI;

use super::energy::{AlbedoRow, compensation, multiple_scattering_fresnel};
use super::microfacet::{
    Terms, alpha_from_roughness, is_specular_alpha, sample_visible_normal, schlick_rgb,
};
use super::sampling::{Frame, cosine_hemisphere, uniform_hemisphere};
use super::sheen::{Sheen, UNIFORM_PDF};
use super::specular::Specular;

/// The metallic–roughness BRDF at one surface point (textures already looked up).
#[derive(Clone, Copy, Debug)]
pub struct Pbr {
    /// Base colour: the conductor's F0, the dielectric's diffuse reflectance.
    pub base_color: Vec3,
    /// Mix factor in [0, 1]: 0 dielectric, 1 conductor.
    pub metallic: f32,
    /// GGX α = roughness², clamped as [`alpha_from_roughness`] does.
    pub alpha: f32,
    /// Strength and colour of the dielectric specular lobe (`KHR_materials_specular`).
    pub specular: Specular,
    /// The sheen layer over it all (`KHR_materials_sheen`; [`Sheen::NONE`]: none).
    pub sheen: Sheen,
    /// What one view fixes, computed once ([`Pbr::viewed`]); `None`: nothing kept. It is why
    /// `Pbr` has no `PartialEq`: the same BRDF may keep different views.
    view: Option<View>,
}

/// What the view at cosine `cos_o` fixes of a [`Pbr`]: the tables' row for its α and the
/// channel sums of its lobes' albedos ([`Pbr::albedo_sums`]), from which the probability of
/// sampling the specular lobe and the albedo estimate follow. A path vertex evaluates the BRDF
/// for its light sample and samples it, each more than once where a shading normal folds the
/// lobe ([`super::bsdf`]), always from the same view.
#[derive(Clone, Copy, Debug)]
struct View {
    cos_o: f32,
    row: AlbedoRow,
    sums: (f32, f32),
}

/// A sampled direction with its weight `f·cos / pdf` and its density.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PbrSample {
    /// Unit direction towards the light.
    pub wi: Vec3,
    /// `f·cos θi / pdf`.
    pub weight: Vec3,
    /// Solid-angle density of `wi` under [`Pbr::sample`]; `None` for the mirror direction of a
    /// smooth specular lobe (a delta lobe, [`Pbr::is_smooth`]).
    pub pdf: Option<f32>,
}

impl PbrSample {
    /// The sample of direction `wi`, above the surface of normal `n`, from the BRDF's
    /// `(f·cos θi, pdf)` there; `None` below the surface or where the density is not positive
    /// and finite.
    #[inline]
    pub(super) fn evaluated(wi: Vec3, n: Vec3, (f_cos, pdf): (Vec3, f32)) -> Option<Self> {
        (wi.dot(n) > 0.0 && pdf > 0.0 && pdf.is_finite()).then(|| Self {
            wi,
            weight: f_cos / pdf,
            pdf: Some(pdf),
        })
    }
}

impl Pbr {
    /// The BRDF of base colour `base_color`, `metallic` and perceptual `roughness` (both in
    /// [0, 1]; out-of-range values are clamped).
    pub fn new(base_color: Vec3, metallic: f32, roughness: f32) -> Self {
        Self {
            base_color,
            metallic: metallic.clamp(0.0, 1.0),
            alpha: alpha_from_roughness(roughness),
            specular: Specular::PLAIN,
            sheen: Sheen::NONE,
            view: None,
        }
    }

    /// This BRDF with the dielectric specular lobe `specular`.
    pub fn with_specular(self, specular: Specular) -> Self {
        Self {
            specular,
            view: None,
            ..self
        }
    }

    /// This BRDF under the sheen layer `sheen`.
    pub fn with_sheen(self, sheen: Sheen) -> Self {
        Self {
            sheen,
            view: None,
            ..self
        }
    }

    /// This BRDF with what a view at cosine `cos_o` (`wo · n` of later calls) fixes computed
    /// once: the evaluations and samples from that view read it instead of computing
    /// it again (the same bits; any other view computes its own). Call it last: what it keeps
    /// does not follow a field changed afterwards (`with_specular` and `with_sheen` drop it).
    #[inline]
    pub fn viewed(self, cos_o: f32) -> Self {
        let row = AlbedoRow::new(self.alpha);
        let sums = self.albedo_sums(&row, cos_o);
        Self {
            view: Some(View { cos_o, row, sums }),
            ..self
        }
    }

    /// The tables' row for α and the albedo sums at view cosine `cos_o`: the kept ones if the
    /// view is the one [`Pbr::viewed`] was given, else computed.
    #[inline(always)]
    fn row_and_sums(&self, cos_o: f32) -> (AlbedoRow, (f32, f32)) {
        match self.view {
            Some(v) if v.cos_o.to_bits() == cos_o.to_bits() => (v.row, v.sums),
            _ => {
                let row = AlbedoRow::new(self.alpha);
                let sums = self.albedo_sums(&row, cos_o);
                (row, sums)
            }
        }
    }

    /// Whether the specular lobe is a perfect mirror (α below [`super::microfacet::SPECULAR_ALPHA`]).
    #[inline]
    pub fn is_smooth(&self) -> bool {
        is_specular_alpha(self.alpha)
    }

    /// Whether the whole BRDF is a perfect mirror: a smooth specular lobe, no diffuse lobe (a
    /// conductor, or a black base) and no sheen. Nothing of it can be evaluated.
    #[inline]
    pub fn is_delta(&self) -> bool {
        self.is_smooth() && self.diffuse().max_element() <= 0.0 && self.sheen.is_off()
    }

    /// Fresnel factor of the combined specular lobe at cosine `c`: mix by `metallic` of the
    /// dielectric lobe's ([`Specular::fresnel`], the exact Fresnel of ior 1.5 unless
    /// `KHR_materials_specular` scales or tints it) and Schlick's of F0 = base colour (the two
    /// lobes share GGX's D and G, so their Fresnel-weighted terms add up to this one).
    #[inline]
    fn fresnel(&self, c: f32) -> Vec3 {
        self.specular
            .fresnel(c)
            .lerp(schlick_rgb(self.base_color, c), self.metallic)
    }

    /// The base's reflectance: `(1 − metallic) · base colour`.
    #[inline]
    fn diffuse(&self) -> Vec3 {
        (1.0 - self.metallic) * self.base_color
    }

    /// Probability of sampling the specular lobe for a view at cosine `cos_o`: its share of the
    /// lobes' albedos (mean over the channels), F(μo) E(μo) against the base's
    /// `(1 − metallic) base (1 − E_s(μo))` plus the compensation's `metallic F_ms (1 − E(μo))`.
    /// 1 for a white smooth conductor or a black base.
    #[inline]
    pub fn specular_probability(&self, cos_o: f32) -> f32 {
        probability(self.row_and_sums(cos_o).1)
    }

    /// An estimate of the directional albedo at view cosine `cos_o`, the mean over the
    /// channels: the specular lobe's F(μo) E(μo) plus what the cosine-sampled lobes reflect,
    /// under the sheen's albedo scaling, plus the sheen's. Layers above the BRDF weigh their
    /// sampling probability with it.
    #[inline]
    pub fn albedo_estimate(&self, cos_o: f32) -> f32 {
        if self.sheen.is_off() {
            return self.base_albedo_estimate(cos_o);
        }
        let split = self.sheen_split(cos_o);
        split.sheen + split.keep * split.base
    }

    /// [`Pbr::albedo_estimate`] of the BRDF under the sheen.
    #[inline]
    fn base_albedo_estimate(&self, cos_o: f32) -> f32 {
        let (spec, rest) = self.row_and_sums(cos_o).1;
        (spec + rest) / 3.0
    }

    /// The sheen layer's share of the light from a view at cosine `cos_o` and what it leaves
    /// to the base, and the probability of sampling it.
    #[inline]
    fn sheen_split(&self, cos_o: f32) -> SheenSplit {
        let e = self.sheen.albedo(cos_o);
        let keep = self.sheen.base_weight(e);
        // The floor keeps a density wherever the lobe is not exactly zero (a table entry may
        // round to 0 where the lobe is 10⁻³⁰), so that no direction it reflects goes unsampled.
        let sheen = self.sheen.color.element_sum() / 3.0 * Sheen::reflected(e).max(1e-6);
        let base = self.base_albedo_estimate(cos_o);
        let total = sheen + keep * base;
        let probability = if total > 0.0 && total.is_finite() {
            (sheen / total).clamp(0.0, 1.0)
        } else {
            1.0
        };
        SheenSplit {
            e,
            sheen,
            keep,
            base,
            probability,
        }
    }

    /// The channel sums of the specular lobe's albedo, F(μo) E(μo), and of the cosine-sampled
    /// lobes', `(1 − metallic) base (1 − E_s(μo))` plus the compensation's
    /// `metallic F_ms (1 − E(μo))`.
    #[inline]
    fn albedo_sums(&self, row: &AlbedoRow, cos_o: f32) -> (f32, f32) {
        let e = row.conductor(cos_o);
        let spec = self.fresnel(cos_o).element_sum() * e;
        let base = if self.specular.is_plain() {
            self.diffuse().element_sum() * (1.0 - row.dielectric(cos_o))
        } else {
            (self.diffuse() * (Vec3::ONE - self.specular.albedo(row, cos_o))).element_sum()
        };
        let multiple = self.metallic
            * multiple_scattering_fresnel(self.base_color, row.conductor_lost()).element_sum()
            * (1.0 - e);
        (spec, base + multiple)
    }

    /// BRDF times `cos θi` and the density of `wi` under [`Pbr::sample`], for unit `wo` (towards
    /// the viewer) and `wi` (towards the light) about unit normal `n` on the viewer's side. Zero
    /// when either is below the surface. Of a smooth material ([`Pbr::is_smooth`]) only the
    /// diffuse lobe and the sheen, with the density of sampling them.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3, n: Vec3) -> (Vec3, f32) {
        if self.sheen.is_off() {
            return self.eval_base(wo, wi, n);
        }
        let (cos_o, cos_i) = (wo.dot(n), wi.dot(n));
        if cos_o <= 0.0 || cos_i <= 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        let split = self.sheen_split(cos_o);
        let (f_base, pdf_base) = self.eval_base(wo, wi, n);
        let sin2_h = (wo + wi).normalize().cross(n).length_squared();
        let q = split.probability;
        (
            self.sheen.eval(cos_o, cos_i, sin2_h, split.e) + split.keep * f_base,
            q * UNIFORM_PDF + (1.0 - q) * pdf_base,
        )
    }

    /// [`Pbr::eval`] of the BRDF under the sheen.
    #[inline]
    fn eval_base(&self, wo: Vec3, wi: Vec3, n: Vec3) -> (Vec3, f32) {
        let (cos_o, cos_i) = (wo.dot(n), wi.dot(n));
        if cos_o <= 0.0 || cos_i <= 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        let (row, sums) = self.row_and_sums(cos_o);
        let p_spec = probability(sums);
        let cosine_lobes = self.cosine_lobes(&row, cos_o, cos_i) * cos_i;
        let pdf_cosine = (1.0 - p_spec) * cos_i * FRAC_1_PI;
        if self.is_smooth() {
            return (cosine_lobes, pdf_cosine);
        }
        let t = Terms::new(wo, wi, n, self.alpha);
        let (spec_cos, pdf_spec) = self.specular(&t, cos_o);
        (spec_cos + cosine_lobes, p_spec * pdf_spec + pdf_cosine)
    }

    /// The specular part of f·cos θi, F D G₂ / (4 cos θo), and its density under visible-normal
    /// sampling, G₁(wo) D / (4 cos θo).
    #[inline]
    fn specular(&self, t: &Terms, cos_o: f32) -> (Vec3, f32) {
        let f = self.fresnel(t.cos_oh.abs());
        let q = t.d / (4.0 * cos_o);
        (f * (q / (1.0 + t.lo + t.li)), q / (1.0 + t.lo))
    }

    /// The BRDF of the cosine-sampled lobes: the base under the dielectric specular lobe,
    /// `(1 − metallic) base (1 − E_s(μo))(1 − E_s(μi)) / (π (1 − E_s,avg))`, and the
    /// conductor's multiple scattering, `metallic F_ms (1 − E(μo))(1 − E(μi)) / (π (1 − E_avg))`.
    #[inline]
    fn cosine_lobes(&self, row: &AlbedoRow, cos_o: f32, cos_i: f32) -> Vec3 {
        let base = if self.specular.is_plain() {
            self.diffuse()
                * compensation(
                    row.dielectric(cos_o),
                    row.dielectric(cos_i),
                    row.dielectric_lost(),
                )
        } else {
            let (e_o, e_i) = (
                self.specular.albedo(row, cos_o),
                self.specular.albedo(row, cos_i),
            );
            let lost = self.specular.lost(row);
            self.diffuse()
                * Vec3::new(
                    compensation(e_o.x, e_i.x, lost.x),
                    compensation(e_o.y, e_i.y, lost.y),
                    compensation(e_o.z, e_i.z, lost.z),
                )
        };
        if self.metallic <= 0.0 {
            return base;
        }
        let lost = row.conductor_lost();
        base + (self.metallic * compensation(row.conductor(cos_o), row.conductor(cos_i), lost))
            * multiple_scattering_fresnel(self.base_color, lost)
    }

    /// Samples `wi` for unit `wo` about unit normal `n` (the viewer's side) from the uniform
    /// pair `u`: `u.x` first chooses the lobe, then is rescaled to reuse it. `None` if the
    /// sampled direction is below the surface (the specular lobe's masked part: absorbed) or has
    /// no density.
    #[inline]
    pub fn sample(&self, wo: Vec3, n: Vec3, u: Vec2) -> Option<PbrSample> {
        if self.sheen.is_off() {
            return self.sample_base(wo, n, u);
        }
        let cos_o = wo.dot(n);
        if cos_o <= 0.0 {
            return None;
        }
        let split = self.sheen_split(cos_o);
        let q = split.probability;
        let wi = if u.x < q {
            let u = Vec2::new((u.x / q).min(1.0), u.y);
            Frame::from_normal(n)
                .to_world(uniform_hemisphere(u))
                .normalize()
        } else {
            let u = Vec2::new(((u.x - q) / (1.0 - q)).clamp(0.0, 1.0), u.y);
            let s = self.sample_base(wo, n, u)?;
            if s.pdf.is_none() {
                // The base's mirror: its weight, under the sheen, over this choice's probability.
                return Some(PbrSample {
                    weight: split.keep * s.weight / (1.0 - q),
                    ..s
                });
            }
            s.wi
        };
        PbrSample::evaluated(wi, n, self.eval(wo, wi, n))
    }

    /// [`Pbr::sample`] of the BRDF under the sheen.
    #[inline]
    fn sample_base(&self, wo: Vec3, n: Vec3, u: Vec2) -> Option<PbrSample> {
        let cos_o = wo.dot(n);
        if cos_o <= 0.0 {
            return None;
        }
        let frame = Frame::from_normal(n);
        let p_spec = self.specular_probability(cos_o);
        if self.is_smooth() && u.x < p_spec {
            // The mirror direction; F at wo · h = wo · n.
            return Some(PbrSample {
                wi: (2.0 * cos_o * n - wo).normalize(),
                weight: self.fresnel(cos_o) / p_spec,
                pdf: None,
            });
        }
        let wi = if u.x < p_spec {
            let u = Vec2::new((u.x / p_spec).min(1.0), u.y);
            let wo_local = Vec3::new(wo.dot(frame.s), wo.dot(frame.t), cos_o.max(1e-6)).normalize();
            let h = frame.to_world(sample_visible_normal(wo_local, self.alpha, u));
            (2.0 * wo.dot(h) * h - wo).normalize()
        } else {
            let u = Vec2::new(((u.x - p_spec) / (1.0 - p_spec)).clamp(0.0, 1.0), u.y);
            frame.to_world(cosine_hemisphere(u)).normalize()
        };
        PbrSample::evaluated(wi, n, self.eval_base(wo, wi, n))
    }
}

/// The probability of sampling the specular lobe from the albedo sums of
/// [`Pbr::albedo_sums`]: its share of the lobes' albedos (mean over the channels), 1 where the
/// other lobes reflect nothing.
#[inline]
fn probability((spec, rest): (f32, f32)) -> f32 {
    if rest <= 0.0 || !rest.is_finite() {
        1.0
    } else {
        (spec / (spec + rest)).clamp(0.0, 1.0)
    }
}

/// How the sheen layer splits the light from one view ([`Pbr::sheen_split`]): the white lobe's
/// tabulated albedo E_sh(μo), the means over the channels of what the sheen reflects and of the
/// base's albedo (before scaling), the base's weight
/// `1 − max(colour) E_sh(μo)` and the probability of sampling the sheen.
#[derive(Clone, Copy, Debug)]
struct SheenSplit {
    e: f32,
    sheen: f32,
    keep: f32,
    base: f32,
    probability: f32,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::rng::Rng;
    use std::f64::consts::PI;

    /// A direction at polar angle θ (from +z) and azimuth φ.
    fn dir(theta: f32, phi: f32) -> Vec3 {
        Vec3::new(
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        )
    }

    /// The materials the tests sweep: (base colour, metallic, roughness).
    fn materials() -> Vec<Pbr> {
        let mut out = Vec::new();
        for (base, metallic) in [
            (Vec3::ONE, 0.0),
            (Vec3::new(0.9, 0.5, 0.2), 0.0),
            (Vec3::new(0.9, 0.5, 0.2), 0.5),
            (Vec3::ONE, 1.0),
            (Vec3::new(0.1, 0.7, 0.3), 1.0),
        ] {
            for roughness in [0.2, 0.5, 1.0] {
                out.push(Pbr::new(base, metallic, roughness));
            }
        }
        out
    }

    /// ∫ pdf(wi) dωi over the hemisphere: the midpoint rule in (t, φ) with cos θ = 1 − t², whose
    /// steps shrink towards the normal where the narrow lobes of low roughness peak
    /// (d cos θ = 2t dt).
    fn pdf_integral(m: &Pbr, wo: Vec3) -> f64 {
        let (nt, nphi) = (1500, 400);
        let mut sum = 0.0f64;
        for i in 0..nt {
            let t = (i as f64 + 0.5) / nt as f64;
            let c = 1.0 - t * t;
            let s = (1.0 - c * c).sqrt();
            for j in 0..nphi {
                let phi = (j as f64 + 0.5) / nphi as f64 * 2.0 * PI;
                let wi = Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, c as f32);
                sum += f64::from(m.eval(wo, wi, Vec3::Z).1) * 2.0 * t;
            }
        }
        sum * (1.0 / nt as f64) * (2.0 * PI / nphi as f64)
    }

    #[test]
    fn a_viewed_brdf_evaluates_and_samples_as_the_brdf_itself() {
        // What `viewed` keeps is read only for its own view, and is what the view computes:
        // every evaluation and sample, from that view or another, is the same bits. A sheen and
        // a tinted specular lobe take the other paths through the albedos.
        let mut rng = Rng::new(8, 3);
        let layered = [
            Pbr::new(Vec3::new(0.9, 0.5, 0.2), 0.3, 0.4)
                .with_sheen(Sheen::new(Vec3::new(0.8, 0.7, 0.9), 0.5)),
            Pbr::new(Vec3::new(0.9, 0.5, 0.2), 0.3, 0.4)
                .with_specular(Specular::new(0.7, Vec3::new(1.0, 0.6, 0.4))),
        ];
        for m in materials().into_iter().chain(layered) {
            for _ in 0..50 {
                let wo = dir(1.5 * rng.next_f32(), 6.0 * rng.next_f32());
                let viewed = m.viewed(wo.dot(Vec3::Z));
                let elsewhere = m.viewed(rng.next_f32());
                for _ in 0..20 {
                    let wi = dir(1.5 * rng.next_f32(), 6.0 * rng.next_f32());
                    let want = m.eval(wo, wi, Vec3::Z);
                    for got in [
                        viewed.eval(wo, wi, Vec3::Z),
                        elsewhere.eval(wo, wi, Vec3::Z),
                    ] {
                        assert_eq!(
                            got.0.to_array().map(f32::to_bits),
                            want.0.to_array().map(f32::to_bits)
                        );
                        assert_eq!(got.1.to_bits(), want.1.to_bits(), "{m:?} {wo} {wi}");
                    }
                    let u = Vec2::new(rng.next_f32(), rng.next_f32());
                    assert_eq!(viewed.sample(wo, Vec3::Z, u), m.sample(wo, Vec3::Z, u));
                }
                assert_eq!(
                    viewed.specular_probability(wo.z).to_bits(),
                    m.specular_probability(wo.z).to_bits()
                );
                assert_eq!(
                    viewed.albedo_estimate(wo.z).to_bits(),
                    m.albedo_estimate(wo.z).to_bits()
                );
            }
        }
    }

    #[test]
    fn the_brdf_is_reciprocal() {
        let mut rng = Rng::new(3, 7);
        for m in materials() {
            for _ in 0..2000 {
                let a = dir(
                    rng.next_f32() * 1.5,
                    rng.next_f32() * 2.0 * std::f32::consts::PI,
                );
                let b = dir(
                    rng.next_f32() * 1.5,
                    rng.next_f32() * 2.0 * std::f32::consts::PI,
                );
                // f = f·cos / cos.
                let f_ab = m.eval(a, b, Vec3::Z).0 / b.z;
                let f_ba = m.eval(b, a, Vec3::Z).0 / a.z;
                let scale = f_ab.max_element().max(1.0);
                assert!(
                    (f_ab - f_ba).abs().max_element() <= 1e-4 * scale,
                    "{m:?}: f({a}, {b}) = {f_ab} but f({b}, {a}) = {f_ba}"
                );
            }
        }
    }

    #[test]
    fn the_pdf_integrates_to_at_most_one_and_exactly_to_what_is_not_masked() {
        for m in materials() {
            for theta_o in [0.0f32, 0.6, 1.2] {
                let wo = dir(theta_o, 0.4);
                let integral = pdf_integral(&m, wo);
                // Visible-normal sampling sends the masked part of the lobe below the surface:
                // at most G₁-dependent loss, but never more than 1 in all.
                assert!(integral <= 1.0 + 2e-3, "{m:?} θo {theta_o}: {integral}");
                // At normal incidence the specular lobe (chosen with probability p) loses the
                // reflections about normals more than 45° off, a fraction α²/(1 + α²) of GGX's
                // D cos (its CDF in tan²θ is tan²θ / (α² + tan²θ)); the diffuse lobe loses none.
                if theta_o == 0.0 {
                    let a2 = f64::from(m.alpha).powi(2);
                    let p = f64::from(m.specular_probability(1.0));
                    let exact = 1.0 - p * a2 / (1.0 + a2);
                    assert!(
                        (integral - exact).abs() < 2e-3,
                        "{m:?}: {integral} vs {exact}"
                    );
                }
                assert!(integral > 0.3, "{m:?} θo {theta_o}: {integral}");
            }
        }
    }

    #[test]
    fn sampled_weights_and_densities_match_eval() {
        let mut rng = Rng::new(9, 1);
        for m in materials() {
            let wo = dir(0.7, 1.0);
            for _ in 0..2000 {
                let u = Vec2::new(rng.next_f32(), rng.next_f32());
                let Some(s) = m.sample(wo, Vec3::Z, u) else {
                    continue;
                };
                let (f_cos, pdf) = m.eval(wo, s.wi, Vec3::Z);
                let sampled = s.pdf.expect("a rough lobe has a density");
                assert!((pdf - sampled).abs() <= 1e-5 * pdf, "{m:?}");
                assert!((f_cos / pdf - s.weight).abs().max_element() < 1e-4, "{m:?}");
            }
        }
    }

    /// χ² of the sampled directions against the pdf on a (cos θ, φ) grid: expected counts from
    /// integrating the pdf over each bin numerically; bins expecting fewer than 5 are pooled.
    #[test]
    fn sampled_directions_follow_the_pdf_chi_squared() {
        let (nc, nphi, sub) = (16usize, 16usize, 12usize);
        let samples = 200_000usize;
        for m in [
            Pbr::new(Vec3::ONE, 0.0, 0.5),
            Pbr::new(Vec3::new(0.9, 0.5, 0.2), 0.3, 0.7),
            Pbr::new(Vec3::new(0.1, 0.7, 0.3), 1.0, 0.6),
            Pbr::new(Vec3::splat(0.8), 0.0, 1.0),
        ] {
            let wo = dir(0.8, 0.3);
            let mut observed = vec![0f64; nc * nphi];
            let mut rng = Rng::new(21, 5);
            for _ in 0..samples {
                let u = Vec2::new(rng.next_f32(), rng.next_f32());
                if let Some(s) = m.sample(wo, Vec3::Z, u) {
                    let c = s.wi.z.clamp(0.0, 1.0);
                    let phi = s.wi.y.atan2(s.wi.x).rem_euclid(2.0 * std::f32::consts::PI);
                    let i = ((c * nc as f32) as usize).min(nc - 1);
                    let j =
                        ((phi / (2.0 * std::f32::consts::PI) * nphi as f32) as usize).min(nphi - 1);
                    observed[i * nphi + j] += 1.0;
                }
            }
            let mut expected = vec![0f64; nc * nphi];
            for (k, e) in expected.iter_mut().enumerate() {
                let (i, j) = (k / nphi, k % nphi);
                let mut sum = 0.0f64;
                for a in 0..sub {
                    let c = (i as f64 + (a as f64 + 0.5) / sub as f64) / nc as f64;
                    let s = (1.0 - c * c).sqrt();
                    for b in 0..sub {
                        let phi =
                            (j as f64 + (b as f64 + 0.5) / sub as f64) / nphi as f64 * 2.0 * PI;
                        let wi =
                            Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, c as f32);
                        sum += f64::from(m.eval(wo, wi, Vec3::Z).1);
                    }
                }
                let area = (1.0 / nc as f64) * (2.0 * PI / nphi as f64);
                *e = sum / (sub * sub) as f64 * area * samples as f64;
            }
            // Pool the small bins into one.
            let (mut chi2, mut dof) = (0.0f64, 0usize);
            let (mut pool_o, mut pool_e) = (0.0f64, 0.0f64);
            for (o, e) in observed.iter().zip(&expected) {
                if *e < 5.0 {
                    pool_o += o;
                    pool_e += e;
                } else {
                    chi2 += (o - e).powi(2) / e;
                    dof += 1;
                }
            }
            if pool_e >= 5.0 {
                chi2 += (pool_o - pool_e).powi(2) / pool_e;
                dof += 1;
            }
            // Directions absorbed below the surface are not binned: the expected counts sum to
            // less than `samples` by the same fraction, so no bin stands for them.
            let dof = (dof - 1) as f64;
            // 0.1% critical value by the Wilson–Hilferty approximation (z = 3.09).
            let z = 3.09;
            let t = 1.0 - 2.0 / (9.0 * dof) + z * (2.0 / (9.0 * dof)).sqrt();
            let critical = dof * t * t * t;
            assert!(
                chi2 < critical,
                "{m:?}: χ² = {chi2:.1} over {dof} degrees of freedom (critical {critical:.1})"
            );
        }
    }

    #[test]
    fn a_smooth_lobe_is_a_mirror_of_the_exact_fresnel_and_the_density_is_the_diffuse_lobes() {
        // Roughness 0 (α = 10⁻⁴, below the mirror threshold), metallic 0, base 0.8, viewed at
        // θo = 1.05 (60°): the mirror direction comes with probability p and weight F(cos θo)/p,
        // F the Fresnel equations' reflectance from outside ior 1.5, written out here (0.0893;
        // Schlick's approximation gives 0.0702); every other direction is diffuse, so the
        // density integrates to 1 − p (nothing is masked).
        let m = Pbr::new(Vec3::splat(0.8), 0.0, 0.0);
        assert!(m.is_smooth() && !m.is_delta());
        assert!(Pbr::new(Vec3::splat(0.8), 1.0, 0.0).is_delta());
        assert!(!Pbr::new(Vec3::splat(0.8), 1.0, 0.04).is_smooth());
        let wo = dir(1.05, 0.4);
        let cos_o = 1.05f32.cos();
        let fresnel = {
            let (c, eta) = (f64::from(cos_o), 1.5f64);
            let cos_t = (1.0 - (1.0 - c * c) / (eta * eta)).sqrt();
            let rs = (c - eta * cos_t) / (c + eta * cos_t);
            let rp = (eta * c - cos_t) / (eta * c + cos_t);
            (0.5 * (rs * rs + rp * rp)) as f32
        };
        let p = m.specular_probability(cos_o);
        let mut rng = Rng::new(4, 9);
        let (count, mut mirrors) = (20_000, 0);
        for _ in 0..count {
            let u = Vec2::new(rng.next_f32(), rng.next_f32());
            let s = m
                .sample(wo, Vec3::Z, u)
                .expect("a cosine or mirror direction");
            match s.pdf {
                None => {
                    mirrors += 1;
                    let mirror = Vec3::new(-wo.x, -wo.y, wo.z);
                    assert!((s.wi - mirror).length() < 1e-5, "{}", s.wi);
                    assert!((s.weight * p - Vec3::splat(fresnel)).abs().max_element() < 1e-6);
                }
                Some(pdf) => {
                    let (f_cos, density) = m.eval(wo, s.wi, Vec3::Z);
                    assert!((pdf - density).abs() <= 1e-5 * density);
                    assert!((f_cos / density - s.weight).abs().max_element() < 1e-4);
                }
            }
        }
        let share = f64::from(mirrors) / f64::from(count);
        assert!((share - f64::from(p)).abs() < 0.01, "{share} vs {p}");
        let integral = pdf_integral(&m, wo);
        assert!(
            (integral - f64::from(1.0 - p)).abs() < 2e-3,
            "{integral} vs {}",
            1.0 - p
        );
    }

    #[test]
    fn a_white_conductor_reflects_everything() {
        // Base colour 1, metallic 1: F = 1, and the compensation lobe returns what masking
        // takes, so the mean sampled weight (absorbed = 0) is 1; a mirror's every weight is 1.
        let mut rng = Rng::new(5, 8);
        for roughness in [0.0f32, 0.3, 1.0] {
            let m = Pbr::new(Vec3::ONE, 1.0, roughness);
            let count = 200_000;
            let mut sum = 0.0f64;
            for _ in 0..count {
                let u = Vec2::new(rng.next_f32(), rng.next_f32());
                if let Some(s) = m.sample(dir(0.5, 0.0), Vec3::Z, u) {
                    sum += f64::from(s.weight.x);
                    if roughness == 0.0 {
                        assert!((s.weight - Vec3::ONE).abs().max_element() < 1e-5);
                    }
                }
            }
            let mean = sum / f64::from(count);
            assert!((mean - 1.0).abs() < 0.01, "roughness {roughness}: {mean}");
        }
    }
}
