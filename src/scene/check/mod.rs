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
            l.material(name).map(|off| l.location(off))
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
mod tests;
