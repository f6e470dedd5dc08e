//! The surface at a hit, as shading needs it: the point, normals and texture coordinates
//! ([`Surface`]), and a triangle's texture-space tangent frame ([`Tangent`],
//! [`uv_derivatives`]). Computed by the packed geometry ([`super::packed`]) and by instances
//! ([`super::instance`]).

use glam::{Vec2, Vec3};

use crate::shading::texture::TexCoords;

/// Local geometry at a hit point, as shading needs it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface {
    /// The hit point, computed from the primitive (not from `o + t·d`) for accuracy.
    pub p: Vec3,
    /// Unit geometric normal as the primitive defines it (not flipped towards the ray).
    pub n: Vec3,
    /// Unit shading normal: interpolated vertex normals of meshes that have them, else `n`.
    /// On the same side as `n`.
    pub ns: Vec3,
    /// Texture coordinates.
    pub uv: Vec2,
    /// The second set of texture coordinates: a mesh's [`MeshData::uvs1`](crate::model::MeshData::uvs1)
    /// where it has one, else `uv`.
    pub uv1: Vec2,
    /// Owner (scene entity slot) of the primitive.
    pub owner: u32,
}

impl Surface {
    /// Both sets of texture coordinates, as materials read them.
    #[inline(always)]
    pub fn tex_coords(&self) -> TexCoords {
        TexCoords([self.uv, self.uv1])
    }
}

/// The texture-space tangent frame of a triangle at a hit, for normal mapping: derived per
/// triangle from the derivatives of position with respect to texture coordinates (not
/// MikkTSpace; a glTF `TANGENT` attribute is not read). A normal map orthogonalises `tangent`
/// against the shading normal (Gram–Schmidt) and takes the bitangent as `sign · n × tangent`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tangent {
    /// Unit world-space ∂p/∂u of the triangle.
    pub tangent: Vec3,
    /// The bitangent's handedness, ±1: the sign of `(∂p/∂u × ∂p/∂v) · n` for the hit's
    /// geometric normal `n` (the sign of the triangle's signed area in texture space when `n`
    /// is its `(b − a) × (c − a)`); −1 where the texture is mirrored.
    pub sign: f32,
}

impl Tangent {
    /// The frame of world-space derivatives `dpdu`, `dpdv` about geometric normal `n`; `None`
    /// if they are not finite or do not span the surface.
    #[inline]
    pub fn from_derivatives(dpdu: Vec3, dpdv: Vec3, n: Vec3) -> Option<Self> {
        let orientation = dpdu.cross(dpdv).dot(n);
        let tangent = dpdu.try_normalize()?;
        (orientation.is_finite() && orientation != 0.0).then(|| Self {
            tangent,
            sign: orientation.signum(),
        })
    }
}

/// Derivatives `(∂p/∂u, ∂p/∂v)` of the triangle `p` with texture coordinates `uv`, constant over
/// the triangle; `None` if the texture coordinates are degenerate (collinear or equal).
#[inline]
pub fn uv_derivatives(p: [Vec3; 3], uv: [Vec2; 3]) -> Option<(Vec3, Vec3)> {
    let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
    let (d1, d2) = (uv[1] - uv[0], uv[2] - uv[0]);
    let det = d1.x * d2.y - d2.x * d1.y;
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let r = 1.0 / det;
    let dpdu = (d2.y * e1 - d1.y * e2) * r;
    let dpdv = (d1.x * e2 - d2.x * e1) * r;
    (dpdu.is_finite() && dpdv.is_finite()).then_some((dpdu, dpdv))
}
