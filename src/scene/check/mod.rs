//! `rondo check`: what in a loaded scene is suspicious, without rendering it.
//!
//! Degenerate shapes, non-finite numbers and out-of-range settings are load errors already
//! ([`super::load::load_scene`]); this module looks at a scene that loaded and reports what is
//! legal but probably a mistake. Each heuristic is simple and stated on its [`WarningKind`]:
//!
//! ```text
//! warning: scene.ron:9:9: material "spare" is defined but no entity uses it
//! warning: scene.ron:30:9: entities "floor" and "ground" overlap in one plane (z-fighting: …); "ground" is at scene.ron:31:9
//! ```
//!
//! Each warning names the file, line and column of the entity (or material) it is about, found
//! by one scan of each file that has a warning ([`super::locate`]).
//!
//! The geometry is placed exactly as the renderer places it ([`world_primitives`]), so what is
//! checked is what would be traced. Every rule is linear in the scene (or n log n): the coplanar
//! rule compares only pieces whose boxes share a cell of a multi-level grid, never all pairs.

use std::collections::{BTreeSet, HashMap};
use std::fmt;
use std::path::PathBuf;
use std::sync::Arc;

use glam::{Vec2, Vec3};

use crate::geometry::instance::BlasCache;
use crate::geometry::packed::{Geometry, Primitive};
use crate::geometry::ray::{Ray, gamma, spawn_origin};
use crate::geometry::world::world_primitives;
use crate::model::{MeshData, MeshRef, Shape, Transform};
use crate::shading::material::Material;
use crate::shading::rng::Rng;
use crate::shading::sampling::{Frame, cosine_hemisphere};

mod coplanar;

pub use coplanar::{COPLANAR_TOLERANCE, MESH_TRIANGLE_BUDGET};

use super::error::{Location, number, write_located};
use super::load::LoadedScene;
use super::locate::Places;

/// What a [`Warning`] is about, with the rule that raises it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum WarningKind {
    /// Two planar surfaces of different entities lie in one plane (normals parallel within
    /// 10⁻⁶, every vertex of each within [`COPLANAR_TOLERANCE`] of the other's plane, relative to
    /// their size, or 8 float steps of their coordinates, whichever is larger), overlap with
    /// positive area (an infinite plane overlaps anything in it), and the overlap can be seen:
    /// their geometric normals point the same way (a rug on a floor), or one of them is glass.
    /// Mesh placements take part with their triangles up to [`MESH_TRIANGLE_BUDGET`] in all
    /// (in scene order); placements beyond it are not compared (memory for every triangle of
    /// every placement of a big mesh would grow with the product).
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

/// Tolerance of [`WarningKind::NonPlanarQuad`], relative to the quad's longest diagonal.
pub const NON_PLANAR_TOLERANCE: f32 = 1e-4;

/// One suspicious thing about a scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Warning {
    /// Which rule raised it.
    pub kind: WarningKind,
    /// What is wrong, naming the entities or materials concerned.
    pub message: String,
    /// The file of the entity or material it is about (the scene or a prefab).
    pub path: PathBuf,
    /// Where in that file, if the scene was read from text.
    pub location: Option<Location>,
}

impl fmt::Display for Warning {
    /// `path:line:col: message`, as errors are written (escaped and bounded the same way).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write_located(f, &self.path, self.location, &self.message)
    }
}

/// Work counted by [`check_counted`], for the scaling tests.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CheckStats {
    /// Pairs of planar pieces compared by the coplanar rule.
    pub comparisons: u64,
    /// Bytes of scene text scanned to locate the warnings.
    pub located_bytes: u64,
}

/// Everything suspicious about `scene`, in a stable order (by kind, then by the order the
/// entities and materials appear).
pub fn check_scene(scene: &LoadedScene) -> Vec<Warning> {
    check_counted(scene).0
}

/// [`check_scene`], with the work it did.
pub fn check_counted(scene: &LoadedScene) -> (Vec<Warning>, CheckStats) {
    let mut out = Out {
        scene,
        places: Places::new(&scene.sources),
        warnings: Vec::new(),
    };
    let comparisons = coplanar_overlaps(scene, &mut out);
    lights_facing_away(scene, &mut out);
    non_planar_quads(scene, &mut out);
    unused_materials(scene, &mut out);
    outside_view(scene, &mut out);
    albedo_above_one(scene, &mut out);
    let stats = CheckStats {
        comparisons,
        located_bytes: out.places.bytes_scanned(),
    };
    let mut warnings = out.warnings;
    warnings.sort_by_key(|w| w.kind);
    (warnings, stats)
}

/// The warnings found so far, with the locators that place them.
struct Out<'a> {
    scene: &'a LoadedScene,
    places: Places<'a>,
    warnings: Vec<Warning>,
}

impl Out<'_> {
    /// File and location of entity `i`.
    fn entity_place(&mut self, i: usize) -> (PathBuf, Option<Location>) {
        let Some(o) = self.scene.origins.get(i) else {
            return (self.scene.path.clone(), None);
        };
        let name = &self.scene.entities[i].name;
        let location = self
            .places
            .locator(o.file)
            .and_then(|l| o.offset(name, l).map(|off| l.location(off)));
        let path = self.places.path(o.file).unwrap_or(&self.scene.path);
        (path.to_path_buf(), location)
    }

    /// `; "name" is at path:line:col` of entity `i`, or nothing if it has no location.
    fn entity_at(&mut self, i: usize) -> String {
        match self.entity_place(i) {
            (path, Some(l)) => format!(
                "; \"{}\" is at {}:{}:{}",
                self.scene.entities[i].name,
                path.display(),
                l.line,
                l.col
            ),
            (_, None) => String::new(),
        }
    }

    /// A warning about entity `i`.
    fn entity(&mut self, i: usize, kind: WarningKind, message: String) {
        let (path, location) = self.entity_place(i);
        self.warnings.push(Warning {
            kind,
            message,
            path,
            location,
        });
    }

    /// A warning about the material with table key `key`.
    fn material(&mut self, key: &str, kind: WarningKind, message: String) {
        let origin = self.scene.material_origins.get(key);
        let location = origin.and_then(|(file, name)| {
            let l = self.places.locator(*file)?;
            l.first(name).map(|off| l.location(off))
        });
        let path = origin
            .and_then(|(file, _)| self.places.path(*file))
            .unwrap_or(&self.scene.path);
        self.warnings.push(Warning {
            kind,
            message,
            path: path.to_path_buf(),
            location,
        });
    }
}

/// [`WarningKind::CoplanarOverlap`], for each pair [`coplanar::coplanar_pairs`] finds. Returns
/// the number of pairs compared.
fn coplanar_overlaps(scene: &LoadedScene, out: &mut Out) -> u64 {
    let (pairs, comparisons) = coplanar::coplanar_pairs(scene);
    for (a, b) in pairs {
        let at = out.entity_at(b);
        out.entity(
            a,
            WarningKind::CoplanarOverlap,
            format!(
                "entities \"{}\" and \"{}\" overlap in one plane (z-fighting: which one is seen is decided by rounding){at}",
                scene.entities[a].name, scene.entities[b].name
            ),
        );
    }
    comparisons
}

/// [`WarningKind::LightFacesAway`].
fn lights_facing_away(scene: &LoadedScene, out: &mut Out) {
    let one_sided = |name: &str| {
        matches!(
            scene.materials.get(name),
            Some(Material::Light { two_sided: false, intensity, .. }) if *intensity > 0.0
        )
    };
    if !scene.entities.iter().any(|e| one_sided(&e.material)) {
        return;
    }
    // Meshes are placed as instances of one shared BVH each, as the renderer places them.
    let mut blas = BlasCache::default();
    let mut prims: Vec<(u32, Primitive)> = Vec::with_capacity(scene.entities.len());
    for (i, e) in scene.entities.iter().enumerate() {
        match &e.shape {
            Shape::Mesh(m) => prims.push((
                i as u32,
                Primitive::Instance {
                    blas: blas.get(&m.data),
                    world_from_object: e.transform.0,
                },
            )),
            shape => prims.extend(
                world_primitives(shape, &e.transform)
                    .into_iter()
                    .map(|p| (i as u32, p)),
            ),
        }
    }
    let geometry = Geometry::build(&prims);
    let mut rng = Rng::new(0x5eed, 7);
    for (i, e) in scene.entities.iter().enumerate() {
        if !one_sided(&e.material) {
            continue;
        }
        // Points on the emitter with their front normals: a few per primitive, at most 64
        // primitives (a mesh is sampled, not swept).
        let mut points = Vec::new();
        for prim in first_primitives(&e.shape, &e.transform, 64) {
            match prim {
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
                // `first_primitives` flattens meshes, so no instance reaches this check.
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
            out.entity(
                i,
                WarningKind::LightFacesAway,
                format!(
                    "entity \"{}\": one-sided light \"{}\" faces away from everything (nothing in front of its emitting side: it lights nothing; is its normal flipped?)",
                    e.name, e.material
                ),
            );
        }
    }
}

/// The world-space primitives of `shape`, at most `count` (a mesh's first triangles, without
/// transforming the rest).
fn first_primitives(shape: &Shape, transform: &Transform, count: usize) -> Vec<Primitive> {
    match shape {
        Shape::Mesh(m) if m.data.triangles.len() > count => {
            let head = MeshData {
                positions: m.data.positions.clone(),
                triangles: m.data.triangles[..count].to_vec(),
                ..MeshData::default()
            };
            let shape = Shape::Mesh(MeshRef {
                path: m.path.clone(),
                data: Arc::new(head),
            });
            world_primitives(&shape, transform)
        }
        shape => world_primitives(shape, transform),
    }
}

/// [`WarningKind::NonPlanarQuad`].
fn non_planar_quads(scene: &LoadedScene, out: &mut Out) {
    for (i, e) in scene.entities.iter().enumerate() {
        let Shape::Quad { a, b, c, d } = e.shape else {
            continue;
        };
        let m = &e.transform.0;
        let [a, b, c, d] = [a, b, c, d].map(|p| m.transform_point3(p));
        let n = (b - a).cross(c - a).normalize_or_zero();
        let diagonal = (c - a).length().max((d - b).length());
        let off = (d - a).dot(n).abs();
        if off > NON_PLANAR_TOLERANCE * diagonal {
            out.entity(
                i,
                WarningKind::NonPlanarQuad,
                format!(
                    "entity \"{}\": quad is not planar: d is {off:.3e} off the plane of a, b, c ({:.2}% of its diagonal); it renders as two triangles folded along a–c",
                    e.name,
                    100.0 * off / diagonal
                ),
            );
        }
    }
}

/// [`WarningKind::UnusedMaterial`].
fn unused_materials(scene: &LoadedScene, out: &mut Out) {
    let used: BTreeSet<&str> = scene.entities.iter().map(|e| e.material.as_str()).collect();
    for name in scene.materials.keys() {
        if !used.contains(name.as_str()) {
            out.material(
                name,
                WarningKind::UnusedMaterial,
                format!("material \"{name}\" is defined but no entity uses it"),
            );
        }
    }
}

/// [`WarningKind::OutsideView`].
fn outside_view(scene: &LoadedScene, out: &mut Out) {
    let cam = &scene.camera;
    let forward = cam.direction.normalize();
    let right = forward.cross(cam.up).normalize();
    let up = right.cross(forward);
    let aspect = scene.settings.width as f32 / scene.settings.height as f32;
    let tan_v = 2.0 * (0.5 * cam.fov.to_radians()).tan();
    let tan_h = tan_v * aspect;
    let mut bounds: HashMap<usize, Shape> = HashMap::new();
    for (i, e) in scene.entities.iter().enumerate() {
        if scene
            .materials
            .get(&e.material)
            .is_some_and(Material::is_emissive)
        {
            continue;
        }
        // Bounding sphere of the entity's primitives (of a mesh's bounding box); planes are
        // everywhere.
        let mut points = Vec::new();
        let mut infinite = false;
        let prims = match &e.shape {
            Shape::Mesh(m) => {
                let bounds = bounds
                    .entry(Arc::as_ptr(&m.data) as usize)
                    .or_insert_with(|| {
                        let p = &m.data.positions;
                        Shape::Box {
                            min: p.iter().fold(Vec3::INFINITY, |a, &v| a.min(v)),
                            max: p.iter().fold(Vec3::NEG_INFINITY, |a, &v| a.max(v)),
                        }
                    });
                world_primitives(bounds, &e.transform)
            }
            shape => world_primitives(shape, &e.transform),
        };
        for prim in prims {
            match prim {
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
            out.entity(
                i,
                WarningKind::OutsideView,
                format!(
                    "entity \"{}\" is far outside the camera's view (it can still cast shadows or be reflected)",
                    e.name
                ),
            );
        }
    }
}

/// [`WarningKind::AlbedoAboveOne`].
fn albedo_above_one(scene: &LoadedScene, out: &mut Out) {
    for (name, m) in &scene.materials {
        let albedo = match m {
            Material::Diffuse { albedo }
            | Material::Metal { albedo, .. }
            | Material::Glossy { albedo, .. }
            | Material::Pbr {
                base_color: albedo, ..
            } => albedo,
            _ => continue,
        };
        let max = albedo.max_channel();
        if max > 1.0 {
            out.material(
                name,
                WarningKind::AlbedoAboveOne,
                format!(
                    "material \"{name}\": albedo component {} is above 1 (it reflects more light than it receives)",
                    number(max)
                ),
            );
        }
    }
}

#[cfg(test)]
mod tests {
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
            sky: Default::default(),
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
}
