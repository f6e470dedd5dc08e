//! A textured quad seen face-on under a white sky, for the glTF texture tests: a 2 × 1 texture
//! splits it into two halves, each compared pixel by pixel with what its texel should give at
//! the pixel's view cosine.

use std::path::Path;

use serde_json::{Value, json};

use super::gltf_doc::{Bin, doc};
use super::{render, with, write_scene};
use rondo::scene::format::Method;

/// Pixels across the square view.
pub const SIZE: usize = 32;

/// A 2 × 1 RGBA PNG: `left` then `right`.
pub fn png(left: [u8; 4], right: [u8; 4]) -> Vec<u8> {
    let image =
        image::RgbaImage::from_fn(2, 1, |x, _| image::Rgba(if x == 0 { left } else { right }));
    let mut out = Vec::new();
    image
        .write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png)
        .expect("encode");
    out
}

/// A quad over [−1, 1]² at z = 0 facing +z, `TEXCOORD_0` u = (x + 1)/2 (left texel for x < 0)
/// and `TEXCOORD_1` u = (1 − x)/2 (the other way round), textured by `t.png` through a NEAREST,
/// clamped sampler, with material `material` using the extensions `used`.
pub fn quad_file(material: Value, used: &[&str]) -> Value {
    let mut bin = Bin::default();
    let v = bin.f32s(&[
        -1.0, -1.0, 0.0, 1.0, -1.0, 0.0, 1.0, 1.0, 0.0, -1.0, 1.0, 0.0,
    ]);
    let uv0 = bin.f32s(&[0.0, 0.5, 1.0, 0.5, 1.0, 0.5, 0.0, 0.5]);
    let uv1 = bin.f32s(&[1.0, 0.5, 0.0, 0.5, 0.0, 0.5, 1.0, 0.5]);
    let i = bin.u16s(&[0, 1, 2, 0, 2, 3]);
    doc(
        &bin,
        json!({
            "extensionsUsed": used,
            "accessors": [
                {"bufferView": v, "componentType": 5126, "count": 4, "type": "VEC3",
                 "min": [-1, -1, 0], "max": [1, 1, 0]},
                {"bufferView": uv0, "componentType": 5126, "count": 4, "type": "VEC2"},
                {"bufferView": uv1, "componentType": 5126, "count": 4, "type": "VEC2"},
                {"bufferView": i, "componentType": 5123, "count": 6, "type": "SCALAR"},
            ],
            "images": [{"uri": "t.png"}],
            "samplers": [{"magFilter": 9728, "minFilter": 9728, "wrapS": 33071, "wrapT": 33071}],
            "textures": [{"source": 0, "sampler": 0}],
            "materials": [material],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1, "TEXCOORD_1": 2}, "indices": 3, "material": 0}]}],
            "nodes": [{"name": "quad", "mesh": 0}],
            "scenes": [{"nodes": [0]}],
        }),
    )
}

/// Renders the quad of `material` textured by the texels `left`, `right` from (0, 0, 2) under
/// a white sky, `SIZE`² pixels, one bounce, `spp` samples: each pixel's linear RGB, row-major.
pub fn render_quad(
    dir: &Path,
    material: Value,
    used: &[&str],
    texels: ([u8; 4], [u8; 4]),
    spp: u32,
) -> Vec<[f64; 3]> {
    render_quad_with(Method::Naive, dir, material, used, texels, spp)
}

/// [`render_quad`] with `method`.
pub fn render_quad_with(
    method: Method,
    dir: &Path,
    material: Value,
    used: &[&str],
    (left, right): ([u8; 4], [u8; 4]),
    spp: u32,
) -> Vec<[f64; 3]> {
    std::fs::write(dir.join("t.png"), png(left, right)).expect("write");
    std::fs::write(dir.join("q.gltf"), quad_file(material, used).to_string()).expect("write");
    let scene = write_scene(
        dir,
        "q.ron",
        &format!(
            "Scene(camera: Camera(position: (0, 0, 2), look_at: (0, 0, 0), fov: 40), \
             settings: Settings(width: {SIZE}, height: {SIZE}, max_depth: 2, background: (1, 1, 1)), \
             entities: [Entity(name: \"q\", gltf: \"q.gltf\")])"
        ),
    );
    let r = render(&scene, with(method, spp), None);
    assert_eq!(r.stats().nonfinite, 0);
    r.film()
        .mean()
        .iter()
        .map(|p| [p.x, p.y, p.z].map(f64::from))
        .collect()
}

/// The cosine between the view and the quad's normal at the centre of pixel `(x, y)` (the
/// view's half-width at z = 0 is 2·tan 20°).
pub fn view_cosine(x: usize, y: usize) -> f64 {
    let half = 2.0 * 20f64.to_radians().tan();
    let at = |k: usize| (2.0 * (k as f64 + 0.5) / SIZE as f64 - 1.0) * half;
    let (px, py) = (at(x), at(y));
    2.0 / (px * px + py * py + 4.0).sqrt()
}

/// For the left half (`right` false) or the right one: the mean of the pixels less what
/// `expected` gives at their view cosines, per channel, with its standard error; the largest
/// difference of one pixel; and the mean expected.
pub fn half_residual(
    pixels: &[[f64; 3]],
    right: bool,
    expected: impl Fn(f64) -> [f64; 3],
) -> ([f64; 3], [f64; 3], f64, [f64; 3]) {
    let columns = if right { SIZE / 2..SIZE } else { 0..SIZE / 2 };
    let mut residuals = Vec::new();
    let mut sum = [0.0; 3];
    for y in 0..SIZE {
        for x in columns.clone() {
            let e = expected(view_cosine(x, y));
            (0..3).for_each(|k| sum[k] += e[k]);
            let p = pixels[y * SIZE + x];
            residuals.push([0, 1, 2].map(|k| p[k] - e[k]));
        }
    }
    let n = residuals.len() as f64;
    let mean = [0, 1, 2].map(|k| residuals.iter().map(|r| r[k]).sum::<f64>() / n);
    let se = [0, 1, 2].map(|k| {
        let var = residuals
            .iter()
            .map(|r| (r[k] - mean[k]).powi(2))
            .sum::<f64>()
            / (n - 1.0);
        (var / n).sqrt()
    });
    let worst = residuals
        .iter()
        .flatten()
        .fold(0.0f64, |w, r| w.max(r.abs()));
    (mean, se, worst, sum.map(|s| s / n))
}

/// The Fresnel reflectance of unpolarised light from outside a dielectric of ior 1.5 at cosine
/// `c` (Born & Wolf §1.5.2).
pub fn fresnel_ior(c: f64) -> f64 {
    let eta = 1.5f64;
    let cos_t = (1.0 - (1.0 - c * c) / (eta * eta)).sqrt();
    let rs = (c - eta * cos_t) / (c + eta * cos_t);
    let rp = (eta * c - cos_t) / (eta * c + cos_t);
    0.5 * (rs * rs + rp * rp)
}
