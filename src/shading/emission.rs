//! What a surface emits: a texture, its scale, and whether it emits from both sides. The one
//! reading of an emitter's radiance, for the integrator, the light table and the film's range.
//! No ECS here.

use glam::Vec3;

use super::texture::{TexCoords, Texture};

/// The emission of a material (see [`super::material::Material::emission`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Emission<'a> {
    /// Emitted colour.
    pub texture: &'a Texture,
    /// Scale of `texture`.
    pub scale: f32,
    /// Emits from both sides instead of only the side the geometric normal points to.
    pub two_sided: bool,
}

impl Emission<'_> {
    /// Radiance emitted towards a ray travelling along `d` that hit the surface (unit geometric
    /// normal `n`) at `uv`.
    #[inline]
    pub fn radiance(&self, d: Vec3, n: Vec3, uv: impl Into<TexCoords>) -> Vec3 {
        if self.two_sided || d.dot(n) < 0.0 {
            self.texture.eval(uv) * self.scale
        } else {
            Vec3::ZERO
        }
    }

    /// The largest radiance emitted in any channel, anywhere.
    pub fn max(&self) -> f32 {
        self.texture.max_channel() * self.scale.abs()
    }
}
