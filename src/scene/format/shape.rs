//! Shapes as written, checked for degenerate and out-of-range geometry.

use glam::Vec3;
use serde::Deserialize;

use super::number::{Positive, V3};
use crate::model::Shape;
use crate::scene::error::vector;

/// A validated shape as written in RON.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(try_from = "RawShape")]
pub enum ShapeDesc {
    /// A shape defined by its numbers.
    Analytic(Shape),
    /// `Mesh(path)`: a Wavefront OBJ file, relative to the file that names it.
    Mesh {
        /// The path as written.
        path: String,
    },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
enum RawShape {
    Sphere { center: V3, radius: Positive },
    Plane { point: V3, normal: V3 },
    Triangle { a: V3, b: V3, c: V3 },
    Quad { a: V3, b: V3, c: V3, d: V3 },
    Box { min: V3, max: V3 },
    Mesh { path: String },
}

/// Twice the area of a triangle, relative to the square of its longest edge: 0 when degenerate.
fn relative_area(a: Vec3, b: Vec3, c: Vec3) -> f32 {
    let longest = (b - a)
        .length_squared()
        .max((c - a).length_squared())
        .max((c - b).length_squared());
    if longest == 0.0 {
        return 0.0;
    }
    (b - a).cross(c - a).length() / longest
}

impl TryFrom<RawShape> for ShapeDesc {
    type Error = String;
    fn try_from(raw: RawShape) -> Result<Self, String> {
        const MIN_AREA: f32 = 1e-6;
        let shape = match raw {
            RawShape::Sphere { center, radius } => Shape::Sphere {
                center: center.0,
                radius: radius.0,
            },
            RawShape::Plane { point, normal } => {
                let n = normal.0;
                if n.length_squared() == 0.0 || !n.length_squared().is_normal() {
                    return Err(format!(
                        "plane: `normal` must be non-zero (got {})",
                        vector(n)
                    ));
                }
                Shape::Plane {
                    point: point.0,
                    normal: n.normalize(),
                }
            }
            RawShape::Triangle { a, b, c } => {
                if relative_area(a.0, b.0, c.0) < MIN_AREA {
                    return Err("triangle: zero area (collinear or repeated vertices)".into());
                }
                Shape::Triangle {
                    a: a.0,
                    b: b.0,
                    c: c.0,
                }
            }
            RawShape::Quad { a, b, c, d } => {
                if relative_area(a.0, b.0, c.0) < MIN_AREA
                    || relative_area(a.0, c.0, d.0) < MIN_AREA
                {
                    return Err("quad: zero area (collinear or repeated corners)".into());
                }
                Shape::Quad {
                    a: a.0,
                    b: b.0,
                    c: c.0,
                    d: d.0,
                }
            }
            RawShape::Box { min, max } => {
                if !min.0.cmplt(max.0).all() {
                    return Err(format!(
                        "box: `min` must be less than `max` on every axis (got min {}, max {})",
                        min.0, max.0
                    ));
                }
                Shape::Box {
                    min: min.0,
                    max: max.0,
                }
            }
            RawShape::Mesh { path } => return Ok(Self::Mesh { path }),
        };
        Ok(Self::Analytic(shape))
    }
}
