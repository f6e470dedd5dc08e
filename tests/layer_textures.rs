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

use common::sheen_brdf::{hemisphere, sheen_cos};
use common::temp_dir;
use common::two_texel::{fresnel_ior, half_residual, render_quad};
use rondo::shading::texture::srgb_to_linear;
use serde_json::{Value, json};

/// A material over a black, non-metallic, smooth base with the extensions `extensions`.
fn black_base(extensions: Value) -> Value {
    json!({
        "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0, "roughnessFactor": 0},
        "extensions": extensions,
    })
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
