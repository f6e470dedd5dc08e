//! `rondo check`: what in a loaded scene is suspicious, without rendering it.
//!
//! Degenerate shapes, non-finite numbers and out-of-range settings are load errors already
//! ([`super::load::load_scene`]); this module looks at a scene that loaded and reports what is
//! legal but probably a mistake. Each heuristic is simple and stated on its [`WarningKind`]:
//!
//! ```text
//! warning: scenes/stress.ron: material "spare" is defined but no entity uses it
//! warning: scenes/stress.ron: entities "floor" and "ground" overlap in one plane (z-fighting: …)
//! ```
//!
//! The geometry is placed exactly as the renderer places it ([`world_primitives`]), so what is
//! checked is what would be traced.

use std::collections::{BTreeSet, HashMap};
use std::fmt;

use glam::{Vec2, Vec3};

use crate::ecs::components::Shape;
use crate::geometry::packed::{Geometry, Primitive};
use crate::geometry::ray::{Ray, gamma, spawn_origin};
use crate::shading::material::Material;
use crate::shading::rng::Rng;
use crate::shading::sampling::{Frame, cosine_hemisphere};
use crate::shading::texture::Texture;
use crate::systems::world_primitives;

use super::load::LoadedScene;

/// What a [`Warning`] is about, with the rule that raises it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum WarningKind {
    /// Two planar surfaces of different entities lie in one plane (normals parallel within
    /// 10⁻⁶, every vertex of each within [`COPLANAR_TOLERANCE`] of the other's plane, relative to
    /// their size, or 8 float steps of their coordinates, whichever is larger), overlap with
    /// positive area (an infinite plane overlaps anything in it), and the overlap can be seen:
    /// their geometric normals point the same way (a rug on a floor), or one of them is glass.
    /// Which one a ray sees is then decided by rounding: the image shows a speckled mix
    /// (z-fighting). Opposite normals on opaque surfaces are two solids touching (a box standing
    /// on a floor): the shared area is hidden between them and is not reported.
    CoplanarOverlap,
    /// A one-sided light sees no geometry in front of it: rays cast from sample points of its
    /// surface over the hemisphere its geometric normal points to (cosine-distributed, 64 per
    /// point) hit nothing. It lights nothing, and from behind it is black. Usually its normal
    /// (`(b − a) × (c − a)`) points the wrong way.
    LightFacesAway,
    /// A quad's fourth corner `d` is off the plane of `a b c` by more than
    /// [`NON_PLANAR_TOLERANCE`] of its longest diagonal: it renders as two triangles folded along
    /// `a–c`.
    NonPlanarQuad,
    /// A material is defined but no entity uses it.
    UnusedMaterial,
    /// A non-emitting entity is far outside the camera's view: its bounding sphere is behind the
    /// camera, or outside a frustum twice as wide as the field of view. It can still be seen in
    /// reflections or cast shadows, but often it is misplaced (a sign or a unit slip).
    OutsideView,
    /// A `Diffuse`, `Metal` or `Glossy` albedo has a component above 1: the surface reflects more
    /// light than it receives, so light gains energy at every bounce.
    AlbedoAboveOne,
}

/// Tolerance of [`WarningKind::CoplanarOverlap`], relative to the larger surface's size.
pub const COPLANAR_TOLERANCE: f32 = 1e-5;
/// Tolerance of [`WarningKind::NonPlanarQuad`], relative to the quad's longest diagonal.
pub const NON_PLANAR_TOLERANCE: f32 = 1e-4;

/// One suspicious thing about a scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Warning {
    /// Which rule raised it.
    pub kind: WarningKind,
    /// What is wrong, naming the entities or materials concerned.
    pub message: String,
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

/// Everything suspicious about `scene`, in a stable order (by kind, then by the order the
/// entities and materials appear).
pub fn check_scene(scene: &LoadedScene) -> Vec<Warning> {
    let placed: Vec<Vec<Primitive>> = scene
        .entities
        .iter()
        .map(|e| world_primitives(&e.shape, &e.transform))
        .collect();
    let mut warnings = Vec::new();
    coplanar_overlaps(scene, &placed, &mut warnings);
    lights_facing_away(scene, &placed, &mut warnings);
    non_planar_quads(scene, &mut warnings);
    unused_materials(scene, &mut warnings);
    outside_view(scene, &placed, &mut warnings);
    albedo_above_one(scene, &mut warnings);
    warnings.sort_by_key(|w| w.kind);
    warnings
}

/// A planar piece of an entity: a triangle, or an infinite plane (`None` vertices).
struct Flat {
    entity: usize,
    normal: Vec3,
    point: Vec3,
    vertices: Option<[Vec3; 3]>,
}

impl Flat {
    /// Distance within which another surface counts as lying in this one's plane.
    fn tolerance(&self, other: &Flat) -> f32 {
        let size = |f: &Flat| {
            f.vertices.map_or(0.0, |[a, b, c]| {
                (a - b).length().max((b - c).length()).max((c - a).length())
            })
        };
        let magnitude = |f: &Flat| match f.vertices {
            Some([a, b, c]) => a.abs().max(b.abs()).max(c.abs()).max_element(),
            None => f.point.abs().max_element(),
        };
        let step = 8.0 * f32::EPSILON * magnitude(self).max(magnitude(other));
        (COPLANAR_TOLERANCE * size(self).max(size(other))).max(step)
    }

    /// Whether every vertex of `other` (its point, for a plane) lies within `tol` of this plane.
    fn holds(&self, other: &Flat, tol: f32) -> bool {
        let off = |p: Vec3| (p - self.point).dot(self.normal).abs() <= tol;
        match other.vertices {
            Some(v) => v.iter().all(|&p| off(p)),
            None => off(other.point),
        }
    }
}

/// Whether two coplanar triangles overlap with positive area: no edge direction of either
/// separates their projections onto the plane (the separating axis theorem), with a margin of
/// `tol` so that triangles that only share an edge or a corner do not count.
fn triangles_overlap(a: [Vec3; 3], b: [Vec3; 3], normal: Vec3, tol: f32) -> bool {
    let (s, t) = normal.any_orthonormal_pair();
    let flat = |p: [Vec3; 3]| p.map(|v| Vec2::new(v.dot(s), v.dot(t)));
    let (a, b) = (flat(a), flat(b));
    let separated_by = |edge: Vec2| {
        let axis = edge.perp().normalize_or_zero();
        if axis == Vec2::ZERO {
            return false;
        }
        let range = |p: &[Vec2; 3]| {
            let d = p.map(|v| v.dot(axis));
            (d[0].min(d[1]).min(d[2]), d[0].max(d[1]).max(d[2]))
        };
        let ((a0, a1), (b0, b1)) = (range(&a), range(&b));
        a1 <= b0 + tol || b1 <= a0 + tol
    };
    let edges = |p: &[Vec2; 3]| [p[1] - p[0], p[2] - p[1], p[0] - p[2]];
    !edges(&a).into_iter().chain(edges(&b)).any(separated_by)
}

/// [`WarningKind::CoplanarOverlap`]: planar pieces are bucketed by their quantised normal (the
/// 27 neighbouring buckets are searched too), so only near-parallel pairs are compared.
fn coplanar_overlaps(scene: &LoadedScene, placed: &[Vec<Primitive>], out: &mut Vec<Warning>) {
    let mut flats = Vec::new();
    for (entity, prims) in placed.iter().enumerate() {
        for prim in prims {
            match *prim {
                Primitive::Triangle { p, .. } => {
                    let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
                    if n != Vec3::ZERO {
                        flats.push(Flat {
                            entity,
                            normal: n,
                            point: p[0],
                            vertices: Some(p),
                        });
                    }
                }
                Primitive::Plane { point, normal } => {
                    flats.push(Flat {
                        entity,
                        normal,
                        point,
                        vertices: None,
                    });
                }
                Primitive::Sphere { .. } | Primitive::Instance { .. } => {}
            }
        }
    }
    // A normal and its opposite are the same plane orientation: fold them together.
    let key = |n: Vec3| {
        let n = if n.x < 0.0 || (n.x == 0.0 && (n.y < 0.0 || (n.y == 0.0 && n.z < 0.0))) {
            -n
        } else {
            n
        };
        (n * 1000.0).round().as_ivec3()
    };
    let mut buckets: HashMap<glam::IVec3, Vec<usize>> = HashMap::new();
    for (i, f) in flats.iter().enumerate() {
        buckets.entry(key(f.normal)).or_default().push(i);
    }
    let see_through = |entity: usize| {
        matches!(
            scene.materials.get(&scene.entities[entity].material),
            Some(Material::Dielectric { .. })
        )
    };
    let mut pairs = BTreeSet::new();
    for (i, f) in flats.iter().enumerate() {
        for k in [key(f.normal), key(-f.normal)] {
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        let Some(others) = buckets.get(&(k + glam::IVec3::new(dx, dy, dz))) else {
                            continue;
                        };
                        for &j in others {
                            let g = &flats[j];
                            if j <= i || g.entity == f.entity {
                                continue;
                            }
                            let pair = (f.entity.min(g.entity), f.entity.max(g.entity));
                            if pairs.contains(&pair) || f.normal.dot(g.normal).abs() < 1.0 - 1e-6 {
                                continue;
                            }
                            let seen = f.normal.dot(g.normal) > 0.0
                                || see_through(f.entity)
                                || see_through(g.entity);
                            if !seen {
                                continue;
                            }
                            let tol = f.tolerance(g);
                            if !(f.holds(g, tol) && g.holds(f, tol)) {
                                continue;
                            }
                            let overlap = match (f.vertices, g.vertices) {
                                (Some(a), Some(b)) => triangles_overlap(a, b, f.normal, tol),
                                _ => true,
                            };
                            if overlap {
                                pairs.insert(pair);
                            }
                        }
                    }
                }
            }
        }
    }
    for (a, b) in pairs {
        out.push(Warning {
            kind: WarningKind::CoplanarOverlap,
            message: format!(
                "entities \"{}\" and \"{}\" overlap in one plane (z-fighting: which one is seen is decided by rounding)",
                scene.entities[a].name, scene.entities[b].name
            ),
        });
    }
}

/// [`WarningKind::LightFacesAway`].
fn lights_facing_away(scene: &LoadedScene, placed: &[Vec<Primitive>], out: &mut Vec<Warning>) {
    let one_sided = |name: &str| {
        matches!(
            scene.materials.get(name),
            Some(Material::Light { two_sided: false, intensity, .. }) if *intensity > 0.0
        )
    };
    if !scene.entities.iter().any(|e| one_sided(&e.material)) {
        return;
    }
    let prims: Vec<(u32, Primitive)> = placed
        .iter()
        .enumerate()
        .flat_map(|(i, p)| p.iter().map(move |p| (i as u32, p.clone())))
        .collect();
    let geometry = Geometry::build(&prims);
    let mut rng = Rng::new(0x5eed, 7);
    for (i, e) in scene.entities.iter().enumerate() {
        if !one_sided(&e.material) {
            continue;
        }
        // Points on the emitter with their front normals: a few per primitive, at most 64
        // primitives (a mesh is sampled, not swept).
        let mut points = Vec::new();
        for prim in placed[i].iter().take(64) {
            match *prim {
                Primitive::Triangle { p, .. } => {
                    let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
                    for (b1, b2) in [(1.0 / 3.0, 1.0 / 3.0), (0.1, 0.1), (0.8, 0.1), (0.1, 0.8)] {
                        points.push((p[0] + b1 * (p[1] - p[0]) + b2 * (p[2] - p[0]), n));
                    }
                }
                Primitive::Sphere { center, radius, .. } => {
                    for n in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
                        points.push((center + radius * n, n));
                    }
                }
                Primitive::Plane { point, normal } => points.push((point, normal)),
                // `world_primitives` flattens meshes, so no instance reaches this check.
                Primitive::Instance { .. } => {}
            }
        }
        let sees_something = points.iter().any(|&(p, n)| {
            if n == Vec3::ZERO {
                return true;
            }
            let origin = spawn_origin(p, n, gamma(8.0) * p.abs().max(Vec3::splat(1.0)));
            let frame = Frame::from_normal(n);
            (0..64).any(|_| {
                let local = cosine_hemisphere(Vec2::new(rng.next_f32(), rng.next_f32()));
                let ray = Ray::new(origin, frame.to_world(local).normalize());
                geometry
                    .intersect(&ray, f32::INFINITY)
                    .is_some_and(|h| geometry.owner(&h) as usize != i)
            })
        });
        if !sees_something {
            out.push(Warning {
                kind: WarningKind::LightFacesAway,
                message: format!(
                    "entity \"{}\": one-sided light \"{}\" faces away from everything (nothing in front of its emitting side: it lights nothing; is its normal flipped?)",
                    e.name, e.material
                ),
            });
        }
    }
}

/// [`WarningKind::NonPlanarQuad`].
fn non_planar_quads(scene: &LoadedScene, out: &mut Vec<Warning>) {
    for e in &scene.entities {
        let Shape::Quad { a, b, c, d } = e.shape else {
            continue;
        };
        let m = &e.transform.0;
        let [a, b, c, d] = [a, b, c, d].map(|p| m.transform_point3(p));
        let n = (b - a).cross(c - a).normalize_or_zero();
        let diagonal = (c - a).length().max((d - b).length());
        let off = (d - a).dot(n).abs();
        if off > NON_PLANAR_TOLERANCE * diagonal {
            out.push(Warning {
                kind: WarningKind::NonPlanarQuad,
                message: format!(
                    "entity \"{}\": quad is not planar: d is {off:.3e} off the plane of a, b, c ({:.2}% of its diagonal); it renders as two triangles folded along a–c",
                    e.name,
                    100.0 * off / diagonal
                ),
            });
        }
    }
}

/// [`WarningKind::UnusedMaterial`].
fn unused_materials(scene: &LoadedScene, out: &mut Vec<Warning>) {
    let used: BTreeSet<&str> = scene.entities.iter().map(|e| e.material.as_str()).collect();
    for name in scene.materials.keys() {
        if !used.contains(name.as_str()) {
            out.push(Warning {
                kind: WarningKind::UnusedMaterial,
                message: format!("material \"{name}\" is defined but no entity uses it"),
            });
        }
    }
}

/// [`WarningKind::OutsideView`].
fn outside_view(scene: &LoadedScene, placed: &[Vec<Primitive>], out: &mut Vec<Warning>) {
    let cam = &scene.camera;
    let forward = cam.direction.normalize();
    let right = forward.cross(cam.up).normalize();
    let up = right.cross(forward);
    let aspect = scene.settings.width as f32 / scene.settings.height as f32;
    let tan_v = 2.0 * (0.5 * cam.fov.to_radians()).tan();
    let tan_h = tan_v * aspect;
    for (i, e) in scene.entities.iter().enumerate() {
        if scene
            .materials
            .get(&e.material)
            .is_some_and(Material::is_emissive)
        {
            continue;
        }
        // Bounding sphere of the entity's primitives; planes are everywhere.
        let mut points = Vec::new();
        let mut infinite = false;
        for prim in &placed[i] {
            match *prim {
                Primitive::Triangle { p, .. } => points.extend(p),
                Primitive::Sphere { center, radius, .. } => {
                    points.extend([center - Vec3::splat(radius), center + Vec3::splat(radius)]);
                }
                Primitive::Plane { .. } => infinite = true,
                Primitive::Instance { .. } => {}
            }
        }
        if infinite || points.is_empty() {
            continue;
        }
        let (lo, hi) = points.iter().fold((points[0], points[0]), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        });
        let center = 0.5 * (lo + hi);
        let radius = 0.5 * (hi - lo).length();
        let rel = center - cam.position;
        let (x, y, z) = (rel.dot(right), rel.dot(up), rel.dot(forward));
        // Distance of the centre outside each side plane of the widened frustum.
        let beyond = |lateral: f32, tan: f32| (lateral.abs() - z * tan) / (1.0 + tan * tan).sqrt();
        let outside = z + radius < 0.0 || beyond(x, tan_h) > radius || beyond(y, tan_v) > radius;
        if outside {
            out.push(Warning {
                kind: WarningKind::OutsideView,
                message: format!(
                    "entity \"{}\" is far outside the camera's view (it can still cast shadows or be reflected)",
                    e.name
                ),
            });
        }
    }
}

/// The largest component of any constant colour in a texture (images are ≤ 1 by construction).
fn max_component(t: &Texture) -> f32 {
    match t {
        Texture::Constant(c) => c.max_element(),
        Texture::Checker { even, odd, .. } => max_component(even).max(max_component(odd)),
        Texture::Image(_) => 1.0,
    }
}

/// [`WarningKind::AlbedoAboveOne`].
fn albedo_above_one(scene: &LoadedScene, out: &mut Vec<Warning>) {
    for (name, m) in &scene.materials {
        let albedo = match m {
            Material::Diffuse { albedo }
            | Material::Metal { albedo, .. }
            | Material::Glossy { albedo, .. } => albedo,
            _ => continue,
        };
        let max = max_component(albedo);
        if max > 1.0 {
            out.push(Warning {
                kind: WarningKind::AlbedoAboveOne,
                message: format!(
                    "material \"{name}\": albedo component {max} is above 1 (it reflects more light than it receives)"
                ),
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use glam::{Affine3A, Quat};

    use super::*;
    use crate::ecs::components::Transform;
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
            dependencies: Vec::new(),
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
                &[
                    ("w", diffuse(0.5)),
                    ("glass", Material::Dielectric { ior: 1.5 }),
                ],
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
}
