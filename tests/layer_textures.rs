//! The textures of glTF's layer extensions on small files written here: `KHR_materials_specular`
//! (`specularTexture`'s alpha, `specularColorTexture`'s sRGB colour), `KHR_materials_clearcoat`
//! (`clearcoatTexture`'s red, `clearcoatRoughnessTexture`'s green) and `KHR_materials_sheen`
//! (`sheenColorTexture`'s sRGB colour, `sheenRoughnessTexture`'s alpha), plus the texture
//! transform and `texCoord` on one of them.
//!
//! Each file is a quad seen face-on under a white sky (radiance 1), one bounce: a pixel is the
//! material's directional albedo towards the camera. The texture has two texels, so the quad has
//! two halves; the base is black and, but for the specular test, the dielectric specular lobe is
//! off (`specularFactor` 0), so each half reflects only the layer its texel sets. Every half's
//! pixels are compared with the albedo computed here from the texel: exactly, for the smooth
//! lobes (a mirror under a uniform sky is noise-free), within the noise for the rough ones
//! (their albedos by quadrature of the BRDFs written out here).

mod common;

use std::f64::consts::PI;
use std::path::Path;

use common::gltf_doc::{Bin, doc};
use common::sheen_brdf::{hemisphere, sheen_cos};
use common::{render, temp_dir, with, write_scene};
use rondo::scene::format::Method;
use rondo::shading::texture::srgb_to_linear;
use serde_json::{Value, json};

/// Pixels across the square view.
const SIZE: usize = 32;

/// A 2 × 1 RGBA PNG: `left` then `right`.
fn png(left: [u8; 4], right: [u8; 4]) -> Vec<u8> {
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
fn quad_file(material: Value, used: &[&str]) -> Value {
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

/// A material over a black, non-metallic, smooth base with the extensions `extensions`.
fn black_base(extensions: Value) -> Value {
    json!({
        "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0, "roughnessFactor": 0},
        "extensions": extensions,
    })
}

/// Renders the quad of `material` textured by the texels `left`, `right` from (0, 0, 2) under
/// a white sky, `SIZE`² pixels, one bounce, `spp` samples: each pixel's linear RGB, row-major.
fn render_quad(
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
    let r = render(&scene, with(Method::Naive, spp), None);
    assert_eq!(r.stats().nonfinite, 0);
    r.film()
        .mean()
        .iter()
        .map(|p| [p.x, p.y, p.z].map(f64::from))
        .collect()
}

/// The cosine between the view and the quad's normal at the centre of pixel `(x, y)` (the
/// view's half-width at z = 0 is 2·tan 20°).
fn view_cosine(x: usize, y: usize) -> f64 {
    let half = 2.0 * 20f64.to_radians().tan();
    let at = |k: usize| (2.0 * (k as f64 + 0.5) / SIZE as f64 - 1.0) * half;
    let (px, py) = (at(x), at(y));
    2.0 / (px * px + py * py + 4.0).sqrt()
}

/// For the left half (`right` false) or the right one: the mean of the pixels less what
/// `expected` gives at their view cosines, per channel, with its standard error; the largest
/// difference of one pixel; and the mean expected.
fn half_residual(
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
fn fresnel_ior(c: f64) -> f64 {
    let eta = 1.5f64;
    let cos_t = (1.0 - (1.0 - c * c) / (eta * eta)).sqrt();
    let rs = (c - eta * cos_t) / (c + eta * cos_t);
    let rp = (eta * c - cos_t) / (eta * c + cos_t);
    0.5 * (rs * rs + rp * rp)
}

/// An 8-bit sRGB value decoded.
fn srgb(v: u8) -> f64 {
    f64::from(srgb_to_linear(f32::from(v) / 255.0))
}

/// The spec's `F0 = min(0.04 · colour, 1) · strength`, `F90 = strength` for the dielectric
/// lobe, on the exact curve of ior 1.5 moved towards 1 (`KHR_materials_specular`; the curve
/// `strength (F + k (1 − F))`, `k = (f0 − 0.04)/0.96`, is F0 at normal incidence and the
/// strength at grazing ones).
fn specular_fresnel(strength: f64, colour: f64, c: f64) -> f64 {
    let f0 = (0.04 * colour).min(1.0);
    let k = (f0 - 0.04) / 0.96;
    let f = fresnel_ior(c);
    strength * (f + k * (1.0 - f))
}

#[test]
fn specular_textures_scale_the_strength_by_alpha_and_the_colour_by_srgb_rgb() {
    let dir = temp_dir("layer-tex-specular");
    // specularColorFactor 25: the texel's colour c gives F0 = min(0.04 · 25 · c, 1) = c.
    let material = black_base(json!({"KHR_materials_specular": {
        "specularFactor": 1, "specularColorFactor": [25, 25, 25],
        "specularTexture": {"index": 0}, "specularColorTexture": {"index": 0}}}));
    let (left, right) = ([255, 255, 255, 255], [128, 64, 0, 102]);
    let pixels = render_quad(
        &dir,
        material,
        &["KHR_materials_specular"],
        (left, right),
        4,
    );
    // Left: F0 = F90 = 1, a white mirror. Right: strength 102/255 (alpha is linear), colour
    // decoded from sRGB.
    let (_, _, worst_left, _) = half_residual(&pixels, false, |_| [1.0; 3]);
    let strength = 102.0 / 255.0;
    let colour = [srgb(128), srgb(64), srgb(0)].map(|c| 25.0 * c);
    let (_, _, worst_right, _) = half_residual(&pixels, true, |c| {
        colour.map(|k| specular_fresnel(strength, k, c))
    });
    println!("specular: worst pixel {worst_left:.2e} (left), {worst_right:.2e} (right)");
    assert!(
        worst_left < 1e-4 && worst_right < 1e-4,
        "{worst_left} {worst_right}"
    );
}

/// `albedo` over the view's cosines (0.94–1), where it varies slowly: tabulated every 0.005
/// and interpolated linearly.
fn over_the_view(albedo: impl Fn(f64) -> f64) -> impl Fn(f64) -> f64 {
    let nodes: Vec<f64> = (0..=12).map(|k| albedo(0.94 + 0.005 * k as f64)).collect();
    move |c: f64| {
        let t = ((c - 0.94) / 0.005).clamp(0.0, 11.999);
        let k = t as usize;
        nodes[k] + (nodes[k + 1] - nodes[k]) * (t - k as f64)
    }
}

/// The directional albedo of a GGX lobe of α = 1 with the Fresnel of ior 1.5 at `|wo·h|`,
/// height-correlated Smith, for a view at cosine `mu`: `∫ F D G₂ (wo·h) / μo dωh` over the half
/// vectors whose reflection is above the surface (`dωi = 4 |wo·h| dωh`), with α = 1's
/// `D = 1/π` and `Λ(μ) = (1/μ − 1)/2`, by the midpoint rule in (cos θh, φ).
fn rough_coat_albedo(mu: f64) -> f64 {
    let wo = [(1.0 - mu * mu).sqrt(), 0.0, mu];
    let lambda = |c: f64| (1.0 / c - 1.0) / 2.0;
    let (nt, nphi) = (400, 400);
    let mut sum = 0.0;
    for i in 0..nt {
        let ch = (i as f64 + 0.5) / nt as f64;
        let sh = (1.0 - ch * ch).sqrt();
        for j in 0..nphi {
            let phi = (j as f64 + 0.5) / nphi as f64 * 2.0 * PI;
            let h = [sh * phi.cos(), sh * phi.sin(), ch];
            let oh = wo[0] * h[0] + wo[2] * h[2];
            let wi_z = 2.0 * oh * h[2] - wo[2];
            if oh <= 0.0 || wi_z <= 0.0 {
                continue;
            }
            let g2 = 1.0 / (1.0 + lambda(mu) + lambda(wi_z));
            sum += fresnel_ior(oh) / PI * g2 * oh / mu;
        }
    }
    // dωh = d(cos θh) dφ.
    sum * 2.0 * PI / (nt * nphi) as f64
}

#[test]
fn clearcoat_textures_scale_the_strength_by_red_and_the_roughness_by_green() {
    let dir = temp_dir("layer-tex-coat");
    let material = black_base(json!({
        "KHR_materials_specular": {"specularFactor": 0},
        "KHR_materials_clearcoat": {"clearcoatFactor": 1, "clearcoatRoughnessFactor": 1,
            "clearcoatTexture": {"index": 0}, "clearcoatRoughnessTexture": {"index": 0}}}));
    // Left: a full, smooth coat. Right: strength 128/255 (linear), roughness 1.
    let (left, right) = ([255, 0, 0, 255], [128, 255, 0, 255]);
    let used = ["KHR_materials_specular", "KHR_materials_clearcoat"];
    let pixels = render_quad(&dir, material, &used, (left, right), 256);
    let (_, _, worst_left, _) = half_residual(&pixels, false, |c| [fresnel_ior(c); 3]);
    let albedo = over_the_view(rough_coat_albedo);
    let strength = 128.0 / 255.0;
    let (mean, se, _, _) = half_residual(&pixels, true, |c| [strength * albedo(c); 3]);
    println!(
        "coat: smooth half worst pixel {worst_left:.2e}; rough half {:.5} ± {:.5} off {:.5}",
        mean[0],
        se[0],
        strength * albedo(1.0)
    );
    assert!(worst_left < 1e-4, "{worst_left}");
    for k in 0..3 {
        assert!(
            mean[k].abs() < 4.0 * se[k] + 2e-4 && se[k] < 2e-3,
            "channel {k}: {} ± {}",
            mean[k],
            se[k]
        );
    }
}

/// The white sheen lobe's directional albedo at view cosine `mu` and perceptual `roughness`.
fn sheen_albedo(mu: f64, roughness: f64) -> f64 {
    hemisphere(mu, |wo, wi| [sheen_cos(wo, wi, roughness); 3])[0]
}

#[test]
fn sheen_textures_scale_the_colour_by_srgb_rgb_and_the_roughness_by_alpha() {
    let dir = temp_dir("layer-tex-sheen");
    let material = black_base(json!({
        "KHR_materials_specular": {"specularFactor": 0},
        "KHR_materials_sheen": {"sheenColorFactor": [1, 1, 1], "sheenRoughnessFactor": 1,
            "sheenColorTexture": {"index": 0}, "sheenRoughnessTexture": {"index": 0}}}));
    // Left: white sheen of roughness 1. Right: colour decoded from sRGB, roughness 128/255.
    let (left, right) = ([255, 255, 255, 255], [255, 128, 0, 128]);
    let used = ["KHR_materials_specular", "KHR_materials_sheen"];
    let pixels = render_quad(&dir, material, &used, (left, right), 256);
    let white = over_the_view(|c| sheen_albedo(c, 1.0));
    let rough = over_the_view(|c| sheen_albedo(c, 128.0 / 255.0));
    let colour = [srgb(255), srgb(128), srgb(0)];
    let left = half_residual(&pixels, false, |c| [white(c); 3]);
    let right = half_residual(&pixels, true, |c| colour.map(|k| k * rough(c)));
    // rondo's sheen lobe (f32, the fitted Λ) and the one written here differ by up to 2 %
    // (tests/sheen.rs allows that); the textures' effects are far larger.
    for (name, (mean, se, _, expected)) in [("left", left), ("right", right)] {
        println!("sheen {name}: expected {expected:.5?}, residual {mean:.5?} ± {se:.5?}");
        for k in 0..3 {
            assert!(
                mean[k].abs() <= 4.0 * se[k] + 0.02 * expected[k] && se[k] < 2e-3,
                "{name} channel {k}: {} ± {} against {}",
                mean[k],
                se[k],
                expected[k],
            );
        }
    }
}

#[test]
fn a_layer_texture_follows_its_texcoord_and_transform() {
    let dir = temp_dir("layer-tex-transform");
    // specularColorFactor 25 makes a white mirror of the texel's alpha: 1 on the left texel,
    // 0.2 on the right.
    let texels = ([0, 0, 0, 255], [0, 0, 0, 51]);
    let used = ["KHR_materials_specular", "KHR_texture_transform"];
    let cases = [
        // `TEXCOORD_1` runs the other way: the halves swap.
        ("texCoord 1", json!({"index": 0, "texCoord": 1}), [0.2, 1.0]),
        // u' = 0.5 + 0.5 u lies in the right texel over the whole quad.
        (
            "transform",
            json!({"index": 0, "extensions": {"KHR_texture_transform": {"offset": [0.5, 0], "scale": [0.5, 1]}}}),
            [0.2, 0.2],
        ),
    ];
    for (name, info, [left, right]) in cases {
        let material = black_base(json!({"KHR_materials_specular": {
            "specularFactor": 1, "specularColorFactor": [25, 25, 25], "specularTexture": info}}));
        let pixels = render_quad(&dir, material, &used, texels, 4);
        for (half, expected) in [(false, left), (true, right)] {
            let (_, _, worst, _) = half_residual(&pixels, half, |_| [expected; 3]);
            assert!(worst < 1e-4, "{name}, right half {half}: {worst}");
        }
    }
}
