//! The absorbing medium a path segment travels through: what the integrator knows of volumes.
//! No ECS here.
//!
//! Glass ([`Material::Dielectric`]) with an absorption coefficient σa bounds a volume that
//! attenuates light by Beer–Lambert's law, exp(−σa·t) over a distance t. The integrator knows
//! only the medium of the last refraction: entering glass through a front face (the ray against
//! its outward normal) puts the path inside that glass's medium, leaving through a back face
//! puts it outside, in the clear space around every object; a reflection keeps the medium it
//! came from; any other surface (an object immersed in the glass) keeps it too. What this
//! approximates:
//! - nested media: leaving an inner glass (an ice cube in tinted water, a bubble) returns the
//!   path to clear space, not to the outer medium, whose absorption is then missed until the
//!   next refraction into it;
//! - a camera or light placed inside tinted glass starts in clear space;
//! - open meshes: a ray inside that escapes the scene through a hole, or a shadow ray that
//!   reaches a distant light, is not attenuated (it has no length to attenuate over).

use glam::Vec3;

use crate::shading::material::Material;

/// The medium a ray segment travels through: clear, or absorbing with a coefficient σa per
/// unit length (per channel).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Medium(Option<Vec3>);

impl Medium {
    /// Clear space: nothing is absorbed.
    pub const CLEAR: Self = Self(None);

    /// The medium of absorption coefficient `sigma` (clear if zero).
    #[inline]
    pub fn absorbing(sigma: Vec3) -> Self {
        Self((sigma != Vec3::ZERO).then_some(sigma))
    }

    /// The medium on the far side of `material`'s surface of geometric normal `n` for a ray
    /// along `d` arriving in this medium: the glass's inside when the ray arrives at a front
    /// face of glass, clear space at a back face of glass, this medium at any other surface.
    #[inline]
    pub fn beyond(self, material: &Material, d: Vec3, n: Vec3) -> Self {
        match material.interior_absorption() {
            None => self,
            Some(sigma) if d.dot(n) < 0.0 => Self::absorbing(sigma),
            Some(_) => Self::CLEAR,
        }
    }

    /// The medium a direction `wi` leaving a surface of geometric normal `n`, hit along `d`,
    /// travels through: `self` (the arriving ray's) on the side `d` came from, `beyond` on the
    /// other.
    #[inline]
    pub fn leaving(self, beyond: Self, d: Vec3, n: Vec3, wi: Vec3) -> Self {
        if wi.dot(n) * d.dot(n) > 0.0 {
            beyond
        } else {
            self
        }
    }

    /// The fraction of light that crosses `distance` of this medium, per channel (1 in clear
    /// space and over a distance that is not positive).
    #[inline]
    pub fn transmittance(self, distance: f32) -> Vec3 {
        match self.0 {
            Some(sigma) if distance > 0.0 => (-sigma * distance).exp(),
            _ => Vec3::ONE,
        }
    }

    /// Whether the medium absorbs anything.
    #[inline]
    pub fn is_clear(self) -> bool {
        self.0.is_none()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entering_tinted_glass_absorbs_until_leaving_it() {
        let sigma = Vec3::new(0.5, 1.0, 2.0);
        let glass = Material::Dielectric {
            ior: 1.5,
            roughness: 0.0,
            absorption: sigma,
        };
        let wall = Material::glass(1.5);
        let n = Vec3::Z;
        let inside = Medium::CLEAR.beyond(&glass, -Vec3::Z, n);
        assert_eq!(inside, Medium::absorbing(sigma));
        let t = inside.transmittance(2.0);
        assert!((t - Vec3::new((-1.0f32).exp(), (-2.0f32).exp(), (-4.0f32).exp())).length() < 1e-6);
        // Leaving through a back face: clear again; reflecting inside: still inside.
        assert_eq!(inside.beyond(&glass, Vec3::Z, n), Medium::CLEAR);
        let beyond = inside.beyond(&glass, Vec3::Z, n);
        assert_eq!(inside.leaving(beyond, Vec3::Z, n, -Vec3::Z), inside);
        assert_eq!(inside.leaving(beyond, Vec3::Z, n, Vec3::Z), Medium::CLEAR);
        // Clear glass leaves nothing to absorb; an opaque surface keeps the medium.
        assert!(Medium::CLEAR.beyond(&wall, -Vec3::Z, n).is_clear());
        let diffuse = Material::Diffuse {
            albedo: crate::shading::texture::Texture::Constant(Vec3::ONE),
        };
        assert_eq!(inside.beyond(&diffuse, Vec3::Z, n), inside);
        assert_eq!(Medium::CLEAR.transmittance(5.0), Vec3::ONE);
    }
}
