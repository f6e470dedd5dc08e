//! Tests of `scene/check/mod.rs`.

use std::collections::BTreeMap;

use super::coplanar::{Flat, triangles_overlap};
use crate::shading::texture::Texture;

use glam::{Affine3A, Quat};

use super::*;
use crate::model::Transform;
use crate::scene::format::{CameraDesc, SettingsDesc};
use crate::scene::load::LoadedEntity;

fn diffuse(c: f32) -> Material {
    Material::Diffuse {
        albedo: Texture::Constant(Vec3::splat(c)),
    }
}

fn light(two_sided: bool) -> Material {
    Material::Light {
        emit: Texture::Constant(Vec3::ONE),
        intensity: 1.0,
        two_sided,
    }
}

/// A scene looking at the origin from (0, 2, −8) with `entities` as (name, material, shape,
/// transform) and the given materials.
fn scene(
    materials: &[(&str, Material)],
    entities: Vec<(&str, &str, Shape, Affine3A)>,
) -> LoadedScene {
    LoadedScene {
        path: "test.ron".into(),
        camera: CameraDesc {
            position: Vec3::new(0.0, 2.0, -8.0),
            direction: Vec3::new(0.0, -2.0, 8.0),
            up: Vec3::Y,
            fov: 40.0,
            aperture: 0.0,
            focus_distance: 1.0,
        },
        settings: SettingsDesc::default(),
        materials: materials
            .iter()
            .map(|(n, m)| (n.to_string(), m.clone()))
            .collect::<BTreeMap<_, _>>(),
        entities: entities
            .into_iter()
            .map(|(name, material, shape, t)| LoadedEntity {
                name: name.into(),
                shape,
                transform: Transform(t),
                material: material.into(),
            })
            .collect(),
        warnings: Vec::new(),
        dependencies: Vec::new(),
        sources: Vec::new(),
        origins: Vec::new(),
        material_origins: BTreeMap::new(),
        placements: Vec::new(),
        sky: Default::default(),
        lights: Vec::new(),
        stats: Default::default(),
    }
}

fn quad(a: [f32; 3], b: [f32; 3], c: [f32; 3], d: [f32; 3]) -> Shape {
    let v = Vec3::from_array;
    Shape::Quad {
        a: v(a),
        b: v(b),
        c: v(c),
        d: v(d),
    }
}

fn kinds(w: &[Warning]) -> Vec<WarningKind> {
    w.iter().map(|w| w.kind).collect()
}

const ID: Affine3A = Affine3A::IDENTITY;

#[test]
fn a_clean_scene_has_no_warnings() {
    let s = scene(
        &[("w", diffuse(0.5)), ("l", light(false))],
        vec![
            (
                "floor",
                "w",
                Shape::Plane {
                    point: Vec3::ZERO,
                    normal: Vec3::Y,
                },
                ID,
            ),
            (
                "ball",
                "w",
                Shape::Sphere {
                    center: Vec3::Y,
                    radius: 1.0,
                },
                ID,
            ),
            // Faces down (normal −y), onto the floor.
            (
                "lamp",
                "l",
                quad(
                    [-1.0, 4.0, -1.0],
                    [1.0, 4.0, -1.0],
                    [1.0, 4.0, 1.0],
                    [-1.0, 4.0, 1.0],
                ),
                ID,
            ),
            // Stands on the floor: its bottom face lies in the floor's plane, facing down
            // into it, hidden between the two.
            (
                "crate",
                "w",
                Shape::Box {
                    min: Vec3::new(2.0, 0.0, 0.0),
                    max: Vec3::new(3.0, 1.0, 1.0),
                },
                ID,
            ),
        ],
    );
    assert_eq!(check_scene(&s), vec![]);
}

#[test]
fn a_quad_lying_on_a_plane_or_on_another_quad_is_reported_once() {
    let rug = quad(
        [-1.0, 0.0, -1.0],
        [-1.0, 0.0, 1.0],
        [1.0, 0.0, 1.0],
        [1.0, 0.0, -1.0],
    );
    let s = scene(
        &[("w", diffuse(0.5))],
        vec![
            (
                "floor",
                "w",
                Shape::Plane {
                    point: Vec3::ZERO,
                    normal: Vec3::Y,
                },
                ID,
            ),
            ("rug", "w", rug.clone(), ID),
            // The same quad, shifted by half its size: still overlapping.
            (
                "mat",
                "w",
                quad(
                    [0.0, 0.0, 0.0],
                    [0.0, 0.0, 2.0],
                    [2.0, 0.0, 2.0],
                    [2.0, 0.0, 0.0],
                ),
                ID,
            ),
            // Turned over (facing down into the floor), opaque: a solid's face touching it.
            (
                "lid",
                "w",
                quad(
                    [-4.0, 0.0, -4.0],
                    [-2.0, 0.0, -4.0],
                    [-2.0, 0.0, -2.0],
                    [-4.0, 0.0, -2.0],
                ),
                ID,
            ),
            // Touching the rug along an edge only, lifted 1 unit: neither overlaps.
            (
                "step",
                "w",
                quad(
                    [1.0, 1.0, -1.0],
                    [1.0, 1.0, 1.0],
                    [3.0, 1.0, 1.0],
                    [3.0, 1.0, -1.0],
                ),
                ID,
            ),
            (
                "tile",
                "w",
                quad(
                    [1.0, 1.0, 1.0],
                    [1.0, 1.0, 3.0],
                    [3.0, 1.0, 3.0],
                    [3.0, 1.0, 1.0],
                ),
                ID,
            ),
        ],
    );
    let w = check_scene(&s);
    let messages: Vec<&str> = w.iter().map(|w| w.message.as_str()).collect();
    assert_eq!(
        kinds(&w),
        vec![WarningKind::CoplanarOverlap; 3],
        "{messages:?}"
    );
    assert!(
        messages[0].contains("\"floor\" and \"rug\""),
        "{messages:?}"
    );
    assert!(
        messages[1].contains("\"floor\" and \"mat\""),
        "{messages:?}"
    );
    assert!(messages[2].contains("\"rug\" and \"mat\""), "{messages:?}");
}

#[test]
fn a_glass_box_standing_on_a_floor_is_reported_and_an_opaque_one_is_not() {
    let cube = Shape::Box {
        min: Vec3::ZERO,
        max: Vec3::ONE,
    };
    let floor = Shape::Plane {
        point: Vec3::ZERO,
        normal: Vec3::Y,
    };
    let on_floor = |material: &'static str| {
        scene(
            &[("w", diffuse(0.5)), ("glass", Material::glass(1.5))],
            vec![
                ("floor", "w", floor.clone(), ID),
                ("cube", material, cube.clone(), ID),
            ],
        )
    };
    let w = check_scene(&on_floor("glass"));
    assert_eq!(kinds(&w), vec![WarningKind::CoplanarOverlap], "{w:?}");
    let w = check_scene(&on_floor("w"));
    assert_eq!(kinds(&w), vec![WarningKind::UnusedMaterial], "{w:?}");
}

#[test]
fn coplanar_surfaces_are_found_after_rotation_and_far_from_the_origin() {
    let r = Affine3A::from_rotation_translation(
        Quat::from_euler(glam::EulerRot::XYZ, 0.3, 1.1, -0.4),
        Vec3::new(1e4, -2e3, 5e3),
    );
    let tile = quad(
        [-1.0, 0.0, -1.0],
        [-1.0, 0.0, 1.0],
        [1.0, 0.0, 1.0],
        [1.0, 0.0, -1.0],
    );
    let s = scene(
        &[("w", diffuse(0.5))],
        vec![
            ("a", "w", tile.clone(), r),
            (
                "b",
                "w",
                tile.clone(),
                r * Affine3A::from_translation(Vec3::new(0.5, 0.0, 0.5)),
            ),
            // 0.1 above (100 float steps at 10⁴): a separate surface.
            (
                "c",
                "w",
                tile,
                r * Affine3A::from_translation(Vec3::new(0.5, 0.1, 0.5)),
            ),
        ],
    );
    let w = check_scene(&s);
    let coplanar: Vec<&Warning> = w
        .iter()
        .filter(|w| w.kind == WarningKind::CoplanarOverlap)
        .collect();
    assert_eq!(coplanar.len(), 1, "{w:?}");
    assert!(coplanar[0].message.contains("\"a\" and \"b\""));
}

#[test]
fn a_light_facing_away_from_everything_is_reported() {
    let up = quad(
        [-1.0, 4.0, -1.0],
        [-1.0, 4.0, 1.0],
        [1.0, 4.0, 1.0],
        [1.0, 4.0, -1.0],
    );
    let down = quad(
        [-1.0, 4.0, -1.0],
        [1.0, 4.0, -1.0],
        [1.0, 4.0, 1.0],
        [-1.0, 4.0, 1.0],
    );
    let floor = quad(
        [-5.0, 0.0, -5.0],
        [-5.0, 0.0, 5.0],
        [5.0, 0.0, 5.0],
        [5.0, 0.0, -5.0],
    );
    let with_lamp = |lamp: Shape, two_sided: bool| {
        scene(
            &[("w", diffuse(0.5)), ("l", light(two_sided))],
            vec![("floor", "w", floor.clone(), ID), ("lamp", "l", lamp, ID)],
        )
    };
    let w = check_scene(&with_lamp(up.clone(), false));
    assert_eq!(kinds(&w), vec![WarningKind::LightFacesAway], "{w:?}");
    assert!(w[0].message.contains("\"lamp\""));
    assert_eq!(check_scene(&with_lamp(down, false)), vec![]);
    assert_eq!(
        check_scene(&with_lamp(up, true)),
        vec![],
        "two-sided lights face both ways"
    );
}

#[test]
fn non_planar_quads_unused_materials_and_bright_albedos_are_reported() {
    let s = scene(
        &[
            ("w", diffuse(0.5)),
            ("spare", diffuse(0.5)),
            (
                "hot",
                Material::Diffuse {
                    albedo: Texture::Checker {
                        scale: 1.0,
                        even: Box::new(Texture::Constant(Vec3::splat(0.5))),
                        odd: Box::new(Texture::Constant(Vec3::new(0.2, 1.5, 0.2))),
                    },
                },
            ),
        ],
        vec![
            (
                "flat",
                "w",
                quad(
                    [0.0, 0.0, 0.0],
                    [1.0, 0.0, 0.0],
                    [1.0, 1.0, 0.0],
                    [0.0, 1.0, 1e-6],
                ),
                ID,
            ),
            (
                "bent",
                "hot",
                quad(
                    [0.0, 0.0, 3.0],
                    [1.0, 0.0, 3.0],
                    [1.0, 1.0, 3.0],
                    [0.0, 1.0, 3.1],
                ),
                ID,
            ),
        ],
    );
    let w = check_scene(&s);
    assert_eq!(
        kinds(&w),
        vec![
            WarningKind::NonPlanarQuad,
            WarningKind::UnusedMaterial,
            WarningKind::AlbedoAboveOne
        ],
        "{w:?}"
    );
    assert!(w[0].message.contains("\"bent\""));
    assert!(w[1].message.contains("\"spare\""));
    assert!(w[2].message.contains("\"hot\"") && w[2].message.contains("1.5"));
}

#[test]
fn a_pbr_base_colour_above_one_is_reported() {
    let pbr = |c: f32| Material::Pbr {
        base_color: Texture::Constant(Vec3::new(0.5, c, 0.5)),
        metallic: 0.0,
        roughness: 0.5,
        metallic_roughness: None,
        emissive: Texture::Constant(Vec3::ZERO),
        emissive_strength: 1.0,
        normal_map: None,
        alpha: None,
        layers: crate::shading::layers::Layers::NONE,
        layer_maps: None,
    };
    let sphere = Shape::Sphere {
        center: Vec3::ZERO,
        radius: 1.0,
    };
    let with = |c: f32| scene(&[("p", pbr(c))], vec![("ball", "p", sphere.clone(), ID)]);
    let w = check_scene(&with(1.25));
    assert_eq!(kinds(&w), vec![WarningKind::AlbedoAboveOne], "{w:?}");
    assert!(w[0].message.contains("1.25"), "{w:?}");
    assert_eq!(check_scene(&with(1.0)), vec![]);
}

#[test]
fn entities_behind_or_far_beside_the_camera_are_reported_but_lights_are_not() {
    let ball = |x: f32, z: f32| Shape::Sphere {
        center: Vec3::new(x, 0.0, z),
        radius: 1.0,
    };
    let s = scene(
        &[("w", diffuse(0.5)), ("l", light(true))],
        vec![
            ("seen", "w", ball(0.0, 0.0), ID),
            ("edge", "w", ball(4.0, 0.0), ID),
            ("behind", "w", ball(0.0, -20.0), ID),
            ("beside", "w", ball(60.0, 0.0), ID),
            ("lamp", "l", ball(0.0, -30.0), ID),
        ],
    );
    let w = check_scene(&s);
    assert_eq!(kinds(&w), vec![WarningKind::OutsideView; 2], "{w:?}");
    assert!(w[0].message.contains("\"behind\"") && w[1].message.contains("\"beside\""));
}

#[test]
fn the_grid_finds_exactly_the_pairs_that_comparing_all_pairs_finds() {
    // Quads of sizes over four orders of magnitude, in two planes, many overlapping, some
    // tilted a little; the rule's pairs must equal a brute force over every triangle pair
    // with the same predicate.
    let mut rng = Rng::new(11, 3);
    let mut r = || rng.next_f32();
    let mut entities = Vec::new();
    for k in 0..300 {
        let size = 10f32.powf(4.0 * r() - 2.0);
        let (x, z) = (20.0 * r() - 10.0, 20.0 * r() - 10.0);
        let y = if k % 2 == 0 { 0.0 } else { 1.0 };
        let tilt = if k % 7 == 0 { 1e-3 } else { 0.0 };
        let q = quad(
            [x, y, z],
            [x, y + tilt * size, z + size],
            [x + size, y + tilt * size, z + size],
            [x + size, y, z],
        );
        entities.push((format!("q{k}"), q));
    }
    let names: Vec<String> = entities.iter().map(|e| e.0.clone()).collect();
    let s = scene(
        &[("w", diffuse(0.5))],
        entities
            .iter()
            .enumerate()
            .map(|(k, (_, q))| (names[k].as_str(), "w", q.clone(), ID))
            .collect(),
    );
    let mut out = Out {
        scene: &s,
        places: Places::new(&s.sources),
        warnings: Vec::new(),
    };
    let comparisons = coplanar_overlaps(&s, &mut out);
    let found: BTreeSet<String> = out.warnings.iter().map(|w| w.message.clone()).collect();

    let flats: Vec<(usize, [Vec3; 3])> = s
        .entities
        .iter()
        .enumerate()
        .flat_map(|(i, e)| {
            world_primitives(&e.shape, &e.transform)
                .into_iter()
                .filter_map(move |p| match p {
                    Primitive::Triangle { p, .. } => Some((i, p)),
                    _ => None,
                })
        })
        .collect();
    let flat = |(entity, p): (usize, [Vec3; 3])| Flat {
        entity,
        normal: (p[1] - p[0]).cross(p[2] - p[0]).normalize(),
        point: p[0],
        vertices: Some(p),
    };
    let mut expected = BTreeSet::new();
    for (i, &a) in flats.iter().enumerate() {
        for &b in &flats[i + 1..] {
            let (f, g) = (flat(a), flat(b));
            let tol = f.tolerance(&g);
            if f.entity != g.entity
                && f.normal.dot(g.normal) > 1.0 - 1e-6
                && f.holds(&g, tol)
                && g.holds(&f, tol)
                && triangles_overlap(a.1, b.1, f.normal, tol)
            {
                expected.insert(format!(
                    "entities \"{}\" and \"{}\" overlap in one plane (z-fighting: which one is seen is decided by rounding)",
                    names[f.entity.min(g.entity)],
                    names[f.entity.max(g.entity)]
                ));
            }
        }
    }
    assert!(
        expected.len() > 20,
        "the test needs overlaps: {}",
        expected.len()
    );
    assert_eq!(found, expected);
    let all_pairs = (flats.len() * (flats.len() - 1) / 2) as u64;
    // Most quads are far apart, but the big ones cover much of the square: well under all
    // pairs, not far under (tests/scaling.rs measures the growth).
    assert!(
        comparisons < all_pairs * 2 / 3,
        "{comparisons} of {all_pairs}"
    );
}
