//! The white furnace of the energy tests: a ball of one material inside a constant white
//! environment, whose pixels a test compares against 1.

use std::path::Path;

use rondo::scene::format::Method;

use super::{render, with, write_scene};

/// Writes `one.exr` into `dir`: a 16 × 8 OpenEXR map of constant grey radiance 1.
pub fn write_white_map(dir: &Path) {
    let image = image::Rgb32FImage::from_raw(16, 8, vec![1.0; 16 * 8 * 3]).expect("buffer size");
    image.save(dir.join("one.exr")).expect("write map");
}

/// A unit ball of `material` in the white environment of [`write_white_map`] (in `dir`), 40 × 40
/// pixels rendered with MIS at `spp`: each pixel's red.
pub fn furnace_pixels(dir: &Path, material: &str, spp: u32) -> Vec<f64> {
    let scene = write_scene(
        dir,
        "ball.ron",
        &format!(
            "Scene(camera: Camera(position: (0, 0, -4), look_at: (0, 0, 0), fov: 32), \
             settings: Settings(width: 40, height: 40, max_depth: 8, \
             environment: Environment(path: \"one.exr\")), materials: {{ \"m\": {material} }}, \
             entities: [Entity(material: \"m\", shape: Sphere(center: (0, 0, 0), radius: 1))])"
        ),
    );
    let r = render(&scene, with(Method::Mis, spp), None);
    assert_eq!(r.stats().nonfinite, 0);
    r.film().mean().iter().map(|p| f64::from(p.x)).collect()
}
