//! Punctual lights: points and spots (glTF's `KHR_lights_punctual`), lights of the table that
//! sit at one point and are reached only by next-event estimation. No ECS here.
//!
//! A punctual light is a delta light: no BSDF-sampled ray can hit it, so its light sample is
//! the only estimate of what it sends and counts at full weight (multiple importance sampling
//! has nothing to weigh it against). A method that samples no lights (`Naive`) never sees it.
//!
//! Units follow glTF: the intensity is a radiant intensity `I` (glTF's candela, read as rondo's
//! radiance units times m² with no lumen conversion), so a surface at distance `r` whose normal
//! makes angle θ with the direction to the light receives irradiance `I cos θ / r²`: a light of
//! intensity 1 at distance 1 lights a facing surface as a `Sun` of irradiance 1 does.
//!
//! A spot shines along its axis with the smooth edge of the glTF spec's informative
//! implementation (KHR_lights_punctual, "Inner and Outer Cone Angles"): full intensity within
//! the inner cone, none outside the outer one, and in between the square of a ramp linear in
//! the cosine, `clamp((cos α − cos outer) / max(0.001, cos inner − cos outer), 0, 1)²`.

use std::f32::consts::PI;

use glam::Vec3;

/// The cone of a spot light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone {
    /// Unit direction the spot shines along.
    axis: Vec3,
    /// Cosine of the outer half-angle: no light at or beyond it.
    cos_outer: f32,
    /// `1 / max(0.001, cos inner − cos outer)`: the spec's `lightAngleScale`.
    scale: f32,
}

impl Cone {
    /// The part of the intensity sent along unit direction `d` (away from the light).
    #[inline]
    pub fn falloff(&self, d: Vec3) -> f32 {
        let t = ((self.axis.dot(d) - self.cos_outer) * self.scale).clamp(0.0, 1.0);
        t * t
    }

    /// The falloff integrated over all directions, in steradians: `2π ∫ falloff d(cos α)`, the
    /// ramp's square integrated in closed form, plus the full inner cap.
    pub fn solid_angle(&self) -> f32 {
        let width = 1.0 / self.scale;
        let full_from = (self.cos_outer + width).min(1.0);
        let ramp = full_from - self.cos_outer;
        2.0 * PI * (ramp * ramp * ramp * self.scale * self.scale / 3.0 + (1.0 - full_from))
    }
}

/// A point or spot light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PunctualLight {
    /// Where the light is.
    pub position: Vec3,
    /// Radiant intensity per channel (colour × intensity), along the axis for a spot.
    pub intensity: Vec3,
    /// The cone of a spot; `None` for a point light, which shines alike in all directions.
    pub cone: Option<Cone>,
}

/// What a punctual light sends to a shading point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PunctualSample {
    /// The light's position: the shadow ray's end.
    pub position: Vec3,
    /// Irradiance at the shading point on a surface facing the light, `I · falloff / r²` (the
    /// cosine at the receiver is the BSDF's): what the estimate multiplies the BSDF by.
    pub irradiance: Vec3,
    /// Probability of the sample: the light's selection probability (a delta light has no
    /// density over directions).
    pub pdf: f32,
}

impl PunctualLight {
    /// A point light at `position` of radiant intensity `intensity` per channel.
    pub fn point(position: Vec3, intensity: Vec3) -> Self {
        Self {
            position,
            intensity,
            cone: None,
        }
    }

    /// A spot at `position` shining along `axis` (non-zero, any length) with radiant
    /// intensity `intensity` within `inner` radians of the axis, fading to none at `outer`
    /// radians (0 ≤ `inner` ≤ `outer` ≤ π/2, as glTF's cone angles).
    pub fn spot(position: Vec3, axis: Vec3, intensity: Vec3, inner: f32, outer: f32) -> Self {
        let cos_outer = outer.cos();
        Self {
            position,
            intensity,
            cone: Some(Cone {
                axis: axis.normalize(),
                cos_outer,
                scale: 1.0 / (inner.cos() - cos_outer).max(0.001),
            }),
        }
    }

    /// Radiant intensity sent along unit direction `d` (away from the light).
    #[inline]
    pub fn intensity_towards(&self, d: Vec3) -> Vec3 {
        match &self.cone {
            None => self.intensity,
            Some(cone) => self.intensity * cone.falloff(d),
        }
    }

    /// What the light sends to shading point `p_ref`, chosen with probability `pmf`; `None` at
    /// the light's own position or where the cone sends nothing.
    #[inline]
    pub fn sample(&self, p_ref: Vec3, pmf: f32) -> Option<PunctualSample> {
        let from_light = p_ref - self.position;
        let dist2 = from_light.length_squared();
        if !(dist2 > 0.0 && dist2.is_finite()) {
            return None;
        }
        let intensity = self.intensity_towards(from_light / dist2.sqrt());
        (intensity != Vec3::ZERO).then(|| PunctualSample {
            position: self.position,
            irradiance: intensity / dist2,
            pdf: pmf,
        })
    }

    /// Power in the light table's units (flux / π, what an area light's area × radiance is):
    /// the mean intensity over the colour channels times the falloff's solid angle (4π for a
    /// point light), over π.
    pub fn power(&self) -> f32 {
        let solid_angle = self.cone.map_or(4.0 * PI, |c| c.solid_angle());
        self.intensity.element_sum() / 3.0 * solid_angle / PI
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The spec's informative falloff, written as the spec writes it (in f64).
    fn spec_falloff(inner: f64, outer: f64, cd: f64) -> f64 {
        let scale = 1.0 / (inner.cos() - outer.cos()).max(0.001);
        let offset = -outer.cos() * scale;
        let a = (cd * scale + offset).clamp(0.0, 1.0);
        a * a
    }

    #[test]
    fn a_spot_follows_the_spec_falloff() {
        let (inner, outer) = (0.3f32, 0.6f32);
        let spot = PunctualLight::spot(
            Vec3::ZERO,
            Vec3::new(0.0, -2.0, 0.0),
            Vec3::ONE,
            inner,
            outer,
        );
        for i in 0..=200 {
            let angle = 0.8 * i as f64 / 200.0;
            let d = Vec3::new(angle.sin() as f32, -angle.cos() as f32, 0.0);
            let got = spot.intensity_towards(d).x;
            let want = spec_falloff(f64::from(inner), f64::from(outer), angle.cos());
            assert!(
                (f64::from(got) - want).abs() < 1e-5,
                "{angle}: {got} vs {want}"
            );
        }
        assert_eq!(spot.intensity_towards(Vec3::NEG_Y), Vec3::ONE);
        assert_eq!(spot.intensity_towards(Vec3::Y), Vec3::ZERO);
    }

    #[test]
    fn the_cone_solid_angle_is_the_integrated_falloff() {
        // Midpoint rule in cos α over [−1, 1], 2π per unit of cos α; the inner = outer case
        // takes the spec's 0.001 floor, a ramp narrower than the cosine's range near the axis.
        for (inner, outer) in [
            (0.0, 0.5),
            (0.3, 0.6),
            (0.5, 0.5),
            (0.0, 0.05),
            (1.2, std::f32::consts::FRAC_PI_2),
        ] {
            let c = PunctualLight::spot(Vec3::ZERO, Vec3::Z, Vec3::ONE, inner, outer)
                .cone
                .expect("a spot");
            let n = 2_000_000;
            let sum: f64 = (0..n)
                .map(|i| {
                    let cos = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
                    spec_falloff(f64::from(inner), f64::from(outer), cos)
                })
                .sum();
            let want = 2.0 * std::f64::consts::PI * sum * 2.0 / n as f64;
            let got = f64::from(c.solid_angle());
            assert!(
                (got - want).abs() <= 1e-4 * want.max(1e-6),
                "({inner}, {outer}): {got} vs {want}"
            );
        }
    }

    #[test]
    fn irradiance_falls_with_the_square_of_the_distance() {
        let light = PunctualLight::point(Vec3::new(1.0, 2.0, 3.0), Vec3::new(4.0, 2.0, 1.0));
        let s = light.sample(Vec3::new(1.0, 2.0, 5.0), 0.25).expect("lit");
        assert_eq!(s.irradiance, Vec3::new(1.0, 0.5, 0.25));
        assert_eq!(s.pdf, 0.25);
        assert!(light.sample(light.position, 1.0).is_none());
        // 4π I / π with I the mean channel.
        assert!((light.power() - 4.0 * 7.0 / 3.0).abs() < 1e-5);
    }
}
