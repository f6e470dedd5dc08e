//! `KHR_texture_transform` on a texture reference: an affine map of its texture coordinates
//! (offset, rotation, scale) and an override of the set it reads.
//!
//! The spec's matrix is `T · R · S` with `R` the rows `(cos r, sin r)`, `(−sin r, cos r)`: its
//! GLSL sample writes these as the arguments of a column-major `mat3`, which would turn the
//! other way, but its worked example (offset `[0, 1]`, rotation π/2, scale 0.5 selects the
//! lower left quadrant) and the Khronos sample viewer take them as rows, and so does rondo.

use glam::{Affine2, Mat2, Vec2};
use gltf::json::Value;

/// The extension's name.
pub(super) const NAME: &str = "KHR_texture_transform";

/// Largest `texCoord` accepted (a primitive has at most this many sets that a file can name).
const MAX_SET: u64 = 255;

/// A texture reference's transform, in glTF's texture space (v pointing down the image).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Transform {
    /// `T · R · S` of the extension.
    pub(super) matrix: Affine2,
    /// The set it names instead of the reference's `texCoord`, if any.
    pub(super) texcoord: Option<u32>,
}

/// The matrix `T(offset) · R(rotation) · S(scale)` of the extension, in glTF's texture space.
pub(super) fn matrix(offset: Vec2, rotation: f32, scale: Vec2) -> Affine2 {
    let (sin, cos) = rotation.sin_cos();
    let r = Mat2::from_cols(Vec2::new(cos, -sin), Vec2::new(sin, cos));
    Affine2::from_mat2_translation(r * Mat2::from_diagonal(scale), offset)
}

/// The same map in rondo's texture space, where v points up the image (`v_rondo = 1 − v`):
/// `F · m · F` with `F(u, v) = (u, 1 − v)`, its own inverse.
pub(super) fn to_rondo_space(m: Affine2) -> Affine2 {
    let flip = Affine2::from_mat2_translation(Mat2::from_diagonal(Vec2::new(1.0, -1.0)), Vec2::Y);
    flip * m * flip
}

/// The transform of a texture reference from the value of its `KHR_texture_transform`
/// extension (`None`: the reference has none). `what` names the reference in errors.
pub(super) fn read(
    ext: Option<&Value>,
    what: &dyn Fn() -> String,
) -> Result<Option<Transform>, String> {
    let Some(ext) = ext else {
        return Ok(None);
    };
    let field = |name: &str| format!("{}: extensions.{NAME}.{name}", what());
    let Value::Object(obj) = ext else {
        return Err(format!("{}: extensions.{NAME} is not an object", what()));
    };
    let number = |name: &str, v: &Value| -> Result<f32, String> {
        match v.as_f64() {
            Some(x) if x.is_finite() && (x as f32).is_finite() => Ok(x as f32),
            _ => Err(format!("{} is {v}, must be a finite number", field(name))),
        }
    };
    let pair = |name: &str, default: Vec2| -> Result<Vec2, String> {
        match obj.get(name) {
            None => Ok(default),
            Some(Value::Array(a)) if a.len() == 2 => {
                Ok(Vec2::new(number(name, &a[0])?, number(name, &a[1])?))
            }
            Some(v) => Err(format!("{} is {v}, must be two numbers", field(name))),
        }
    };
    let offset = pair("offset", Vec2::ZERO)?;
    let scale = pair("scale", Vec2::ONE)?;
    let rotation = match obj.get("rotation") {
        None => 0.0,
        Some(v) => number("rotation", v)?,
    };
    let texcoord = match obj.get("texCoord") {
        None => None,
        Some(v) => match v.as_u64() {
            Some(n) if n <= MAX_SET => Some(n as u32),
            _ => {
                return Err(format!(
                    "{} is {v}, must be an integer in [0, {MAX_SET}]",
                    field("texCoord")
                ));
            }
        },
    };
    let matrix = matrix(offset, rotation, scale);
    if !matrix.is_finite() {
        return Err(format!("{}: extensions.{NAME} is not finite", what()));
    }
    Ok(Some(Transform { matrix, texcoord }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_spec_example_selects_the_lower_left_quadrant() {
        // offset [0, 1], rotation π/2, scale 0.5: the unit square lands on u ∈ [0, 0.5],
        // v ∈ [0.5, 1] (glTF's v points down: the lower half), rotated.
        let m = matrix(Vec2::Y, std::f32::consts::FRAC_PI_2, Vec2::splat(0.5));
        let near = |a: Vec2, b: Vec2| (a - b).length() < 1e-6;
        assert!(near(m.transform_point2(Vec2::ZERO), Vec2::new(0.0, 1.0)));
        assert!(near(m.transform_point2(Vec2::X), Vec2::new(0.0, 0.5)));
        assert!(near(m.transform_point2(Vec2::Y), Vec2::new(0.5, 1.0)));
        assert!(near(m.transform_point2(Vec2::ONE), Vec2::new(0.5, 0.5)));
    }

    #[test]
    fn rondo_space_flips_v_on_both_sides() {
        let m = matrix(Vec2::new(0.25, 0.5), 0.3, Vec2::new(2.0, 0.5));
        let r = to_rondo_space(m);
        for uv in [Vec2::ZERO, Vec2::new(0.3, 0.7), Vec2::new(-1.0, 2.0)] {
            let g = m.transform_point2(Vec2::new(uv.x, 1.0 - uv.y));
            let expected = Vec2::new(g.x, 1.0 - g.y);
            assert!((r.transform_point2(uv) - expected).length() < 1e-5);
        }
    }

    #[test]
    fn bad_fields_are_errors_naming_them() {
        let what = || "materials[0].baseColorTexture".to_string();
        let err = |v: Value| read(Some(&v), &what).expect_err("refused");
        let e = err(serde_json::json!({"offset": [0, "a"]}));
        assert!(e.contains("KHR_texture_transform.offset"), "{e}");
        let e = err(serde_json::json!({"rotation": 1e300}));
        assert!(e.contains("KHR_texture_transform.rotation"), "{e}");
        let e = err(serde_json::json!({"texCoord": -1}));
        assert!(e.contains("KHR_texture_transform.texCoord"), "{e}");
        let e = err(serde_json::json!({"scale": [1]}));
        assert!(e.contains("KHR_texture_transform.scale"), "{e}");
        let ok = read(Some(&serde_json::json!({"texCoord": 1})), &what).expect("read");
        assert_eq!(
            ok.map(|t| (t.matrix, t.texcoord)),
            Some((Affine2::IDENTITY, Some(1)))
        );
    }
}
