//! The generated scenes and rays every layout is measured on.

use glam::Vec3;

use crate::bench::layout_rows::Kind;
use crate::ecs::components::Shape;
use crate::geometry::ray::Ray;
use crate::shading::rng::Rng;

/// Mean distance between neighbouring primitive centres.
pub(super) const SPACING: f32 = 2.0;

/// `n` shapes of `kind` scattered uniformly in a cube of side `∛n · SPACING` centred on the
/// origin: spheres of radius 0.2–0.5, triangles with vertices within 0.6 of their centre.
pub fn generate(kind: Kind, n: usize, seed: u64) -> Vec<Shape> {
    let mut rng = Rng::new(seed, kind as u64 + 1);
    let side = cube_side(n);
    let unit = |rng: &mut Rng| loop {
        let v = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - Vec3::ONE;
        let l = v.length_squared();
        if l > 1e-3 && l <= 1.0 {
            return v / l.sqrt();
        }
    };
    (0..n)
        .map(|_| {
            let c = (Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5) * side;
            match kind {
                Kind::Sphere => Shape::Sphere {
                    center: c,
                    radius: 0.2 + 0.3 * rng.next_f32(),
                },
                Kind::Triangle => Shape::Triangle {
                    a: c + 0.6 * unit(&mut rng),
                    b: c + 0.6 * unit(&mut rng),
                    c: c + 0.6 * unit(&mut rng),
                },
            }
        })
        .collect()
}

pub(super) fn cube_side(n: usize) -> f32 {
    (n.max(1) as f32).cbrt() * SPACING
}

/// Rays with origins uniform in the scene's cube and directions uniform on the sphere.
pub(super) fn incoherent_rays(count: usize, rays: usize) -> Vec<Ray> {
    let mut rng = Rng::new(0x7a4, 5);
    let side = cube_side(count);
    (0..rays)
        .map(|_| {
            let o = (Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5) * side;
            let d = loop {
                let v = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - Vec3::ONE;
                if v.length_squared() > 1e-3 && v.length_squared() <= 1.0 {
                    break v.normalize();
                }
            };
            Ray::new(o, d)
        })
        .collect()
}
