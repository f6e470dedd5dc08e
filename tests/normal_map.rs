//! Normal maps on the `Pbr` material: the shading normal the feature buffer records follows the
//! map's tilted normal in the frame of the texture coordinates (mirrored coordinates flip the
//! bitangent), the radiance of a sunlit normal-mapped plane is the glTF BRDF's closed form at
//! the tilted normal, and the texture tangent of a placed mesh is the hand-computed one. The
//! expected values are computed here from the map's bytes and the geometry, not from rondo.

mod common;

use std::f64::consts::PI;
use std::path::Path;
use std::sync::Arc;

use common::{point_camera, point_estimate, render, temp_dir, with, write_scene};
use glam::{Affine3A, DVec3, Mat3, Quat, Vec2, Vec3};
use rondo::geometry::instance::MeshBlas;
use rondo::geometry::packed::{Geometry, Primitive};
use rondo::geometry::ray::Ray;
use rondo::geometry::surface::Tangent;
use rondo::model::MeshData;
use rondo::scene::format::Method;
use rondo::{Overrides, PassPlan, Renderer};

/// The 8-bit encoding of a tangent-space normal: `round((v + 1) / 2 · 255)` per channel.
fn encode(n: DVec3) -> [u8; 3] {
    n.normalize()
        .to_array()
        .map(|v| ((v + 1.0) / 2.0 * 255.0).round() as u8)
}

/// The tangent-space normal a map texel holds: `2 · byte / 255 − 1` per channel.
fn decode(bytes: [u8; 3]) -> DVec3 {
    DVec3::from_array(bytes.map(|b| 2.0 * f64::from(b) / 255.0 - 1.0))
}

/// Writes a 2 × 2 map of the one texel `bytes` as `dir/name`.
fn write_map(dir: &Path, name: &str, bytes: [u8; 3]) {
    image::RgbImage::from_pixel(2, 2, image::Rgb(bytes))
        .save(dir.join(name))
        .expect("map written");
}

/// The world normal a map texel gives in the frame (tangent, bitangent, normal) with `scale`.
fn mapped(bytes: [u8; 3], scale: f64, frame: [DVec3; 3]) -> DVec3 {
    let m = decode(bytes);
    (frame[0] * m.x * scale + frame[1] * m.y * scale + frame[2] * m.z).normalize()
}

/// The unit square at z = 0 as an OBJ file: `vt` of its corners (−1, −1), (1, −1), (1, 1),
/// (−1, 1) as given, two triangles facing +z.
fn square_obj(uv: [[f32; 2]; 4]) -> String {
    let mut s = String::from("v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n");
    for [u, v] in uv {
        s += &format!("vt {u} {v}\n");
    }
    s + "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n"
}

/// Renders `source` (in `dir`) with the feature buffers on; returns every pixel's mean normal.
fn normals(dir: &Path, source: &str) -> Vec<Vec3> {
    let path = write_scene(dir, "scene.ron", source);
    let mut r = Renderer::new(None, PassPlan::Single).expect("thread pool");
    r.set_features(true);
    r.set_overrides(Overrides {
        spp: Some(4),
        ..Overrides::default()
    });
    r.load(&path).unwrap_or_else(|e| panic!("{e}"));
    r.render_to_completion();
    let film = r.film();
    let f = film.features.as_ref().expect("features were collected");
    f.normal_mean(film.count())
}

#[test]
fn the_shading_normal_follows_the_map_in_the_frame_of_the_texture_coordinates() {
    let dir = temp_dir("normal-map-aov");
    let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
    std::fs::write(
        dir.join("square.obj"),
        square_obj([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]),
    )
    .expect("obj written");
    // u runs along −x: the texture is mirrored, ∂p/∂u = −x while ∂p/∂v = +y.
    std::fs::write(
        dir.join("mirrored.obj"),
        square_obj([[1.0, 0.0], [0.0, 0.0], [0.0, 1.0], [1.0, 1.0]]),
    )
    .expect("obj written");
    // Each surface, facing +z, with its frame (∂p/∂u, ∂p/∂v, normal) worked out from its corners
    // and their texture coordinates.
    let quad = "shape: Quad(a: (-1, -1, 0), b: (1, -1, 0), c: (1, 1, 0), d: (-1, 1, 0))";
    let surfaces = [
        ("quad", quad.to_string(), [x, y, z]),
        (
            "mesh",
            "shape: Mesh(path: \"square.obj\")".to_string(),
            [x, y, z],
        ),
        (
            "mirrored mesh",
            "shape: Mesh(path: \"mirrored.obj\")".to_string(),
            [-x, y, z],
        ),
        // Turned 90° about z: ∂p/∂u = +y, ∂p/∂v = −x.
        (
            "turned mesh",
            "shape: Mesh(path: \"square.obj\"), transform: Transform(rotate: (0, 0, 90))"
                .to_string(),
            [y, -x, z],
        ),
    ];
    // Two tilts: 30° towards +u; 50° towards (−u, +v) at half scale.
    let tilt = |deg: f64, dir: DVec3| {
        let t = deg.to_radians();
        dir.normalize() * t.sin() + z * t.cos()
    };
    let maps = [
        (encode(tilt(30.0, x)), 1.0),
        (encode(tilt(50.0, -x + 0.7 * y)), 0.5),
    ];
    for (name, shape, frame) in &surfaces {
        for &(bytes, scale) in &maps {
            write_map(&dir, "n.png", bytes);
            let source = format!(
                r#"Scene(
                    camera: Camera(position: (0, 0, 3), look_at: (0, 0, 0), fov: 30),
                    settings: Settings(width: 8, height: 8, spp: 4, max_depth: 2, method: Naive),
                    materials: {{ "m": Pbr(base_color: Constant((0.5, 0.5, 0.5)), metallic: 0,
                        roughness: 0.5, normal_map: NormalMap(path: "n.png", scale: {scale})) }},
                    entities: [Entity(name: "s", material: "m", {shape})],
                )"#
            );
            let expected = mapped(bytes, scale, *frame);
            for (i, got) in normals(&dir, &source).iter().enumerate() {
                assert!(
                    (got.as_dvec3() - expected).length() < 1e-4,
                    "{name}, map {bytes:?} × {scale}: pixel {i} has normal {got}, expected {expected}"
                );
            }
        }
    }
}

/// The BRDF rondo's `Pbr` gives a dielectric (`metallic` 0) of grey base colour `base` and
/// perceptual roughness `roughness`, for unit view `v` and light `l` about unit normal `n`: the
/// spec's GGX specular lobe (`D`, height-correlated `V`, the exact Fresnel of ior 1.5) over the base
/// weighted by what that lobe leaves in both directions, (1 − E(μo))(1 − E(μi)) / (π (1 − E_avg)),
/// E the lobe's directional albedo and E_avg its cosine-weighted mean, both integrated here by
/// quadrature (rondo reads them from tables).
fn pbr_dielectric_brdf(base: f64, roughness: f64, n: DVec3, v: DVec3, l: DVec3) -> f64 {
    let albedo = |mu: f64| specular_albedo(roughness, mu);
    let e_avg = {
        let k = 64;
        (0..k)
            .map(|i| {
                let mu = (i as f64 + 0.5) / k as f64;
                2.0 * albedo(mu) * mu / k as f64
            })
            .sum::<f64>()
    };
    specular_brdf(roughness, n, v, l)
        + base * (1.0 - albedo(n.dot(v))) * (1.0 - albedo(n.dot(l))) / (PI * (1.0 - e_avg))
}

/// The spec's specular lobe alone, with the Fresnel equations' F of ior 1.5 (unpolarised light
/// from outside) in place of Schlick's: F · GGX `D` · height-correlated `V`.
fn specular_brdf(roughness: f64, n: DVec3, v: DVec3, l: DVec3) -> f64 {
    let a2 = roughness.powi(4);
    let h = (v + l).normalize();
    let (nl, nv, nh, vh) = (n.dot(l), n.dot(v), n.dot(h), v.dot(h).abs());
    let d = a2 / (PI * (nh * nh * (a2 - 1.0) + 1.0).powi(2));
    let vis =
        0.5 / (nl * (nv * nv * (1.0 - a2) + a2).sqrt() + nv * (nl * nl * (1.0 - a2) + a2).sqrt());
    let eta = 1.5f64;
    let cos_t = (1.0 - (1.0 - vh * vh) / (eta * eta)).sqrt();
    let rs = (vh - eta * cos_t) / (vh + eta * cos_t);
    let rp = (eta * vh - cos_t) / (eta * vh + cos_t);
    let f = 0.5 * (rs * rs + rp * rp);
    f * d * vis
}

/// Directional albedo of [`specular_brdf`] for a view at cosine `mu`: midpoint quadrature over
/// (cos θ, φ) of the hemisphere.
fn specular_albedo(roughness: f64, mu: f64) -> f64 {
    let v = DVec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
    let (nc, nphi) = (200, 200);
    let dw = 2.0 * PI / (nc * nphi) as f64;
    let mut sum = 0.0;
    for i in 0..nc {
        let c = (i as f64 + 0.5) / nc as f64;
        let s = (1.0 - c * c).sqrt();
        for j in 0..nphi {
            let phi = (j as f64 + 0.5) / nphi as f64 * 2.0 * PI;
            let l = DVec3::new(s * phi.cos(), s * phi.sin(), c);
            sum += specular_brdf(roughness, DVec3::Z, v, l) * c * dw;
        }
    }
    sum
}

#[test]
fn a_sunlit_normal_mapped_plane_sends_the_closed_form_radiance_of_its_tilted_normal() {
    let dir = temp_dir("normal-map-sun");
    // A horizontal square facing +y, u along +x and v along −z: frame (x, −z, y).
    let frame = [DVec3::X, -DVec3::Z, DVec3::Y];
    // The sun 48° from the zenith towards +x.
    let sun = DVec3::new(48f64.to_radians().sin(), 48f64.to_radians().cos(), 0.0);
    let camera = DVec3::new(-1.0, 4.0, 1.5);
    let (radiance, diameter) = (2000.0, 0.53f64);
    let (base, roughness) = (0.8, 0.5);
    // 40° towards +u (towards the sun: cos θ from 0.67 to 0.98); 35° towards (−u, +v) (away
    // from it: to 0.29).
    let tilted = |deg: f64, d: DVec3| {
        let t = deg.to_radians();
        d.normalize() * t.sin() + DVec3::Z * t.cos()
    };
    for m in [
        tilted(40.0, DVec3::X),
        tilted(35.0, DVec3::new(-0.6, 0.8, 0.0)),
    ] {
        let bytes = encode(m);
        write_map(&dir, "n.png", bytes);
        let n = mapped(bytes, 1.0, frame);
        // The lobe folded at the geometric surface adds nothing: the sun's mirror image is
        // below the tilted normal's horizon.
        let below = DVec3::new(sun.x, -sun.y, sun.z);
        assert!(below.dot(n) < 0.0 && sun.dot(n) > 0.0);
        // A uniform disk of half-angle a wholly above the horizon, centred at angle θ from the
        // normal, gives irradiance L π sin²a cos θ.
        let a = (0.5 * diameter).to_radians();
        let e = radiance * PI * a.sin().powi(2) * sun.dot(n);
        let v = camera.normalize();
        let expected = pbr_dielectric_brdf(base, roughness, n, v, sun) * e;
        let scene = write_scene(
            &dir,
            "sun.ron",
            &format!(
                "Scene(camera: {}, settings: Settings(width: 16, height: 16, max_depth: 3, \
                 sun: Sun(direction: ({}, {}, {}), angular_diameter: {diameter}, radiance: {radiance})), \
                 materials: {{ \"m\": Pbr(base_color: Constant(({base}, {base}, {base})), metallic: 0, \
                 roughness: {roughness}, normal_map: NormalMap(path: \"n.png\", filter: Bilinear, wrap: Repeat)) }}, \
                 entities: [Entity(material: \"m\", shape: Quad(a: (-50, 0, 50), b: (50, 0, 50), \
                 c: (50, 0, -50), d: (-50, 0, -50)))])",
                point_camera(
                    &format!("({}, {}, {})", camera.x, camera.y, camera.z),
                    "(0, 0, 0)",
                    "(0, 1, 0)"
                ),
                sun.x,
                sun.y,
                sun.z
            ),
        );
        for method in [Method::Nee, Method::Mis] {
            let (mean, se) = point_estimate(&render(&scene, with(method, 64), None));
            // The BRDF and cosine vary across the 0.53° disk by far less than 10⁻³.
            assert!(
                (mean - expected).abs() <= 3.5 * se + 1e-3 * expected,
                "map {bytes:?} {method}: {mean} ± {se}, closed form {expected}"
            );
        }
    }
}

#[test]
fn a_white_normal_mapped_surface_reflects_exactly_the_white_furnace() {
    // A white `Pbr` lit by a white environment from every direction above the surface sends
    // radiance 1, however far its map tilts the shading normal: the lobe about the tilted
    // normal reflects 1 over the whole sphere, and the part of it below the geometric surface
    // is folded above it, not lost (Cycles loses it: 0.83 for the Khronos-like bumps of
    // benches/gltf_models) nor gained. Normals tilted 75° towards and away from the camera,
    // seen 20° and 65° from the geometric normal (the view then below the tilted normal's
    // horizon for the tilt away), both the specular-dominated and a rough lobe.
    let dir = temp_dir("normal-map-furnace");
    let env = image::Rgb32FImage::from_raw(16, 8, vec![1.0; 16 * 8 * 3]).expect("buffer size");
    env.save(dir.join("one.exr")).expect("write map");
    let tilted = |deg: f64, d: DVec3| {
        let t = deg.to_radians();
        d.normalize() * t.sin() + DVec3::Z * t.cos()
    };
    for m in [tilted(75.0, DVec3::X), tilted(75.0, -DVec3::X)] {
        write_map(&dir, "n.png", encode(m));
        for view in [20f64, 65.0] {
            // Above the square (facing +y), on the −x side: u runs along +x.
            let (s, c) = view.to_radians().sin_cos();
            for roughness in [0.1, 0.6] {
                let scene = write_scene(
                    &dir,
                    "furnace.ron",
                    &format!(
                        "Scene(camera: {}, settings: Settings(width: 16, height: 16, max_depth: 2, \
                         environment: Environment(path: \"one.exr\")), \
                         materials: {{ \"m\": Pbr(base_color: Constant((1, 1, 1)), metallic: 0, \
                         roughness: {roughness}, normal_map: NormalMap(path: \"n.png\", filter: Nearest, wrap: Repeat)) }}, \
                         entities: [Entity(material: \"m\", shape: Quad(a: (-50, 0, 50), b: (50, 0, 50), \
                         c: (50, 0, -50), d: (-50, 0, -50)))])",
                        point_camera(&format!("({}, {c}, 0)", -s), "(0, 0, 0)", "(0, 1, 0)")
                    ),
                );
                for method in [Method::Nee, Method::Mis] {
                    let (mean, se) = point_estimate(&render(&scene, with(method, 64), None));
                    assert!(
                        (mean - 1.0).abs() <= 3.5 * se + 1e-3,
                        "map {m}, view {view}°, roughness {roughness}, {method}: {mean} ± {se}"
                    );
                }
            }
        }
    }
}

/// A triangle with texture coordinates `uv` at (0, 0, 0), (1, 0, 0), (0, 1, 0).
fn triangle_mesh(uv: [Vec2; 3]) -> MeshData {
    MeshData {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
        normals: None,
        uvs: Some(uv.to_vec()),
        uvs1: None,
        triangles: vec![[0, 1, 2]],
    }
}

/// The tangent at the hit of a ray straight down −z onto `at` (z = 0) in `g`.
fn tangent_at(g: &Geometry, at: Vec3) -> Option<Tangent> {
    let hit = g
        .intersect(&Ray::new(at + Vec3::Z, -Vec3::Z), f32::INFINITY)
        .expect("the ray hits");
    g.uv_tangent(&hit)
}

#[test]
fn the_texture_tangent_of_a_placed_mesh_is_the_hand_computed_one() {
    // u = x + y, v = y − x on the object-space triangle: ∂p/∂u = (½, ½, 0), ∂p/∂v = (−½, ½, 0),
    // ∂p/∂u × ∂p/∂v = +z/2, the triangle's normal: handedness +1.
    let uv = [Vec2::ZERO, Vec2::new(1.0, -1.0), Vec2::new(1.0, 1.0)];
    let blas = Arc::new(MeshBlas::build(&triangle_mesh(uv)));
    let turn = Quat::from_rotation_z(std::f32::consts::FRAC_PI_2);
    let t = Vec3::new(5.0, 0.0, 0.0);
    let close = |a: Vec3, b: Vec3| (a - b).length() < 1e-6;
    // Scaled by (2, 1, 1), turned 90° about z (x → y, y → −x), moved by t: ∂p/∂u =
    // R S (½, ½, 0) = R (1, ½, 0) = (−½, 1, 0); ∂p/∂v = R (−1, ½, 0) = (−½, −1, 0); their cross
    // product is +z, as is the world normal: handedness +1. Mirrored by (−2, 1, 1): ∂p/∂u =
    // R (−1, ½, 0) = (−½, −1, 0), ∂p/∂v = R (1, ½, 0) = (−½, 1, 0), cross product −z while the
    // normal (inverse transpose) stays +z: handedness −1.
    for (scale, tangent, sign, at) in [
        (
            Vec3::new(2.0, 1.0, 1.0),
            Vec3::new(-1.0, 2.0, 0.0),
            1.0,
            Vec3::new(4.7, 0.6, 0.0),
        ),
        (
            Vec3::new(-2.0, 1.0, 1.0),
            Vec3::new(-1.0, -2.0, 0.0),
            -1.0,
            Vec3::new(4.7, -0.6, 0.0),
        ),
    ] {
        let m = Affine3A::from_scale_rotation_translation(scale, turn, t);
        let g = Geometry::build(&[(
            0,
            Primitive::Instance {
                blas: blas.clone(),
                world_from_object: m,
            },
        )]);
        let got = tangent_at(&g, at).expect("an instanced triangle with uvs has a tangent");
        assert!(
            close(got.tangent, tangent.normalize()) && got.sign == sign,
            "placement scaled by {scale}: {got:?}, expected {} and {sign}",
            tangent.normalize()
        );
        // The same triangle packed flat in world space, vertex order kept (so its normal is
        // the world cross product, −z when mirrored, which turns the handedness back to +1).
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y].map(|v| m.transform_point3(v));
        let flat = Geometry::build(&[(0, Primitive::Triangle { p, uv })]);
        let got = tangent_at(&flat, at).expect("a packed triangle with uvs has a tangent");
        assert!(
            close(got.tangent, tangent.normalize()) && got.sign == 1.0,
            "packed, scaled by {scale}: {got:?}"
        );
    }
    // No tangent without texture coordinates, with degenerate ones, or on a sphere.
    let no_uv = Arc::new(MeshBlas::build(&MeshData {
        uvs: None,
        ..triangle_mesh(uv)
    }));
    let collinear = Arc::new(MeshBlas::build(&triangle_mesh([
        Vec2::ZERO,
        Vec2::ONE,
        Vec2::splat(2.0),
    ])));
    for blas in [no_uv, collinear] {
        let g = Geometry::build(&[(
            0,
            Primitive::Instance {
                blas,
                world_from_object: Affine3A::IDENTITY,
            },
        )]);
        assert_eq!(tangent_at(&g, Vec3::new(0.2, 0.2, 0.0)), None);
    }
    let sphere = Geometry::build(&[(
        0,
        Primitive::Sphere {
            center: Vec3::ZERO,
            radius: 0.5,
            frame: Mat3::IDENTITY,
        },
    )]);
    assert_eq!(tangent_at(&sphere, Vec3::ZERO), None);
}

#[test]
fn a_missing_normal_map_is_an_error_naming_the_material_and_the_file() {
    let dir = temp_dir("normal-map-missing");
    let path = write_scene(
        &dir,
        "scene.ron",
        r#"Scene(
            camera: Camera(position: (0, 0, 3), look_at: (0, 0, 0), fov: 30),
            materials: { "bumpy": Pbr(normal_map: NormalMap(path: "absent.png")) },
            entities: [Entity(material: "bumpy",
                shape: Quad(a: (-1, -1, 0), b: (1, -1, 0), c: (1, 1, 0), d: (-1, 1, 0)))],
        )"#,
    );
    let mut r = Renderer::new(Some(1), PassPlan::Single).expect("thread pool");
    let err = r.load(&path).expect_err("the map is missing").to_string();
    assert!(
        err.contains("bumpy") && err.contains("absent.png") && err.contains("normal_map"),
        "{err}"
    );
}

#[test]
fn a_normal_map_is_a_dependency_of_the_scene() {
    let dir = temp_dir("normal-map-dependency");
    write_map(&dir, "n.png", [128, 128, 255]);
    let path = write_scene(
        &dir,
        "scene.ron",
        r#"Scene(
            camera: Camera(position: (0, 0, 3), look_at: (0, 0, 0), fov: 30),
            materials: { "m": Pbr(normal_map: NormalMap(path: "n.png")) },
            entities: [Entity(material: "m",
                shape: Quad(a: (-1, -1, 0), b: (1, -1, 0), c: (1, 1, 0), d: (-1, 1, 0)))],
        )"#,
    );
    let mut assets = rondo::scene::assets::AssetCache::default();
    let scene =
        rondo::scene::load::load_scene(&path, &mut assets).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        scene.dependencies.contains(&dir.join("n.png")),
        "{:?}",
        scene.dependencies
    );
}

#[test]
fn perturb_orthogonalises_the_tangent_mirrors_what_falls_below_and_falls_back_when_degenerate() {
    use rondo::shading::maps::NormalMap;
    use rondo::shading::texture::Texture;
    // A constant map of texel `t`, i.e. tangent-space normal 2t − 1.
    let map = |x: f32, y: f32, z: f32, scale: f32| NormalMap {
        texture: Texture::Constant((Vec3::new(x, y, z) + Vec3::ONE) / 2.0),
        scale,
    };
    let close = |a: Vec3, b: Vec3| (a - b).length() < 1e-6;
    let (n, uv) = (Vec3::Z, Vec2::ZERO);
    let p = |m: &NormalMap, ns: Vec3, tangent: Vec3, sign: f32| m.perturb(uv, n, ns, tangent, sign);
    // A tangent leaning out of the surface is projected onto it (Gram–Schmidt).
    let tilted = map(0.6, 0.0, 0.8, 1.0);
    assert!(close(
        p(&tilted, n, Vec3::new(1.0, 0.0, 1.0), 1.0),
        Vec3::new(0.6, 0.0, 0.8)
    ));
    // The bitangent is n × t, turned by the handedness.
    let sideways = map(0.0, 0.6, 0.8, 1.0);
    assert!(close(
        p(&sideways, n, Vec3::X, 1.0),
        Vec3::new(0.0, 0.6, 0.8)
    ));
    assert!(close(
        p(&sideways, n, Vec3::X, -1.0),
        Vec3::new(0.0, -0.6, 0.8)
    ));
    // The scale multiplies x and y.
    let halved = map(0.6, 0.0, 0.8, 0.5);
    assert!(close(
        p(&halved, n, Vec3::X, 1.0),
        Vec3::new(0.3, 0.0, 0.8).normalize()
    ));
    // A normal below the surface is mirrored at it.
    let below = map(0.6, 0.0, -0.8, 1.0);
    assert!(close(p(&below, n, Vec3::X, 1.0), Vec3::new(0.6, 0.0, 0.8)));
    // Degenerate frames and results give the unperturbed shading normal back: a tangent along
    // the normal, a zero texel normal, one in the surface's plane, a NaN scale.
    let ns = Vec3::new(0.0, 0.6, 0.8);
    assert_eq!(p(&tilted, ns, ns, 1.0), ns);
    assert_eq!(p(&map(0.0, 0.0, 0.0, 1.0), ns, Vec3::X, 1.0), ns);
    assert_eq!(p(&map(1.0, 0.0, 0.0, 1.0), n, Vec3::X, 1.0), n);
    assert_eq!(p(&map(0.6, 0.0, 0.8, f32::NAN), ns, Vec3::X, 1.0), ns);
}

#[test]
fn a_gltf_normal_texture_tilts_the_normal_as_the_gltf_convention_says() {
    use common::gltf_doc::{Bin, doc};
    use serde_json::json;
    let dir = temp_dir("normal-map-gltf");
    // glTF's convention: the map's red along +u, green towards the image's top (+Y up), the
    // values linear. The quad over [−1, 1]² faces +z with u along +x and the image's top at
    // y = 1 (glTF's v runs down the image), so the frame is (x, y, z).
    let bytes = encode(DVec3::new(-0.4, 0.5, 0.77));
    write_map(&dir, "n.png", bytes);
    let mut bin = Bin::default();
    let v = bin.f32s(&[
        -1.0, -1.0, 0.0, 1.0, -1.0, 0.0, 1.0, 1.0, 0.0, -1.0, 1.0, 0.0,
    ]);
    let uv = bin.f32s(&[0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0]);
    let i = bin.u16s(&[0, 1, 2, 0, 2, 3]);
    let parts = json!({
        "accessors": [
            {"bufferView": v, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": uv, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": i, "componentType": 5123, "count": 6, "type": "SCALAR"},
        ],
        "images": [{"uri": "n.png"}],
        "textures": [{"source": 0}],
        "materials": [{"name": "bumpy", "normalTexture": {"index": 0, "scale": 0.5},
            "pbrMetallicRoughness": {"metallicFactor": 0.0}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}]}],
        "nodes": [{"name": "quad", "mesh": 0}],
        "scenes": [{"nodes": [0]}],
    });
    std::fs::write(dir.join("quad.gltf"), doc(&bin, parts).to_string()).expect("gltf written");
    let source = r#"Scene(
        camera: Camera(position: (0, 0, 3), look_at: (0, 0, 0), fov: 30),
        settings: Settings(width: 8, height: 8, spp: 4, max_depth: 2, method: Naive),
        entities: [Entity(name: "m", gltf: "quad.gltf")],
    )"#;
    let expected = mapped(bytes, 0.5, [DVec3::X, DVec3::Y, DVec3::Z]);
    for (i, got) in normals(&dir, source).iter().enumerate() {
        assert!(
            (got.as_dvec3() - expected).length() < 1e-4,
            "pixel {i} has normal {got}, expected {expected}"
        );
    }
}
