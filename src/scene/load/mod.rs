//! Reading a scene file: parse, expand prefabs, validate names and references, load textures
//! and meshes.
//!
//! Every stage is linear in what grows (entities, placements, materials, files): nothing is
//! searched from the start per item. Locations in the text are found only when an error needs
//! one ([`super::locate`]); dependencies are an ordered set; each mesh's bounds are computed once
//! and bound every placement's coordinates by 8 corners; each file is read and each asset
//! fetched once per load.

use std::borrow::Cow;
use std::cell::RefCell;
use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::sync::Arc;

use glam::{Affine3A, Vec3};

use crate::lights::punctual::PunctualLight;
use crate::model::{MeshData, MeshRef, Shape, Transform};
use crate::shading::material::Material;
use crate::shading::texture::ImageTexture;
use crate::sky::{Sky, Sun};

mod gltf_glass;
mod gltf_layers;
mod gltf_lights;
mod gltf_place;
mod materials;
mod prefab;
mod reach;

use self::reach::{corner_reach, world_reach};
use super::assets::AssetCache;
use super::assets::GltfAsset;
use super::bounded_read::read_text;
use super::error::{Location, SceneError};
use super::format::{
    CameraDesc, EntityDesc, MAX_COORDINATE, PrefabDesc, SceneCamera, SceneDesc, SettingsDesc,
    ShapeDesc, SunDesc,
};
use super::incremental::parse_scene_text;
use super::locate::{Locator, Places, SourceText};

/// Most entities a scene may expand to (prefabs can multiply quickly).
pub const MAX_ENTITIES: usize = 1_000_000;
/// Deepest prefab nesting accepted.
pub const MAX_PREFAB_DEPTH: usize = 64;

/// One entity of a loaded scene, ready to become ECS components.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadedEntity {
    /// Unique name; inside prefabs qualified by the placements (`box1/top`).
    pub name: String,
    /// Object-space shape.
    pub shape: Shape,
    /// Composed placement, `world_from_object`.
    pub transform: Transform,
    /// Key of the material in [`LoadedScene::materials`].
    pub material: String,
}

/// Where a loaded entity is written: which file, which entry of its `entities` list.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Origin {
    /// Index of the file in [`LoadedScene::sources`].
    pub file: u32,
    /// Position in that file's `entities` list.
    pub index: u32,
    /// Bytes of placement prefix in the qualified name (`box1/` of `box1/top`): the rest is
    /// the name written in the file.
    pub prefix: u32,
    /// Whether the entity has a `name` (otherwise it is `#index`).
    pub named: bool,
    /// The innermost prefab or glTF placement that put the entity there (an index in
    /// [`LoadedScene::placements`]); `None` for an entity written in the scene file itself.
    pub placement: Option<u32>,
}

impl Origin {
    /// Offset of the entity named `qualified` in its file, found by that file's locator: its
    /// name's string literal within its own `Entity(…)` (so that a material of the same name is
    /// not taken for it; the first string literal of the name where the entity is not written
    /// as `Entity(…)`), or for an unnamed entity its `Entity(`. Reads the entity's text up to
    /// its name.
    pub fn offset(&self, qualified: &str, locator: &Locator) -> Option<usize> {
        if self.named {
            let name = qualified.get(self.prefix as usize..)?;
            locator
                .in_entity(self.index as usize, name)
                .or_else(|| locator.first(name))
        } else {
            locator.entity(self.index as usize)
        }
    }
}

/// A prefab or glTF placement: the entity of a scene or prefab file whose `prefab` or `gltf`
/// put another file's contents into the scene.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Placement {
    /// Where the placing entity is written (its own `placement` is the one that placed its
    /// file, if any).
    pub origin: Origin,
    /// Its qualified name (`tall`, `room/lamp`): the prefix, without its `/`, of the names of
    /// the entities it placed.
    pub name: String,
    /// The file it places, canonical (absolute, symlinks resolved) where it could be.
    pub file: PathBuf,
    /// Whether it places a glTF file (otherwise a prefab).
    pub gltf: bool,
}

/// Work counted while loading, for the scaling tests and `rondo bench load`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LoadStats {
    /// Points transformed by the coordinate-limit check: each mesh's vertices once (for its
    /// bounds), 8 bounding-box corners per mesh placement, every vertex only when the corners
    /// exceed the limit, and the few points of each analytic shape.
    pub limit_vertices: u64,
    /// Entities of the scene file parsed: all of them on a first load, only those an edit
    /// touched on a reload ([`super::incremental`]).
    pub entities_parsed: u64,
}

/// A parsed, validated scene with its prefabs expanded and its assets loaded.
#[derive(Clone, Debug)]
pub struct LoadedScene {
    /// The scene file.
    pub path: PathBuf,
    /// The camera (a glTF file's resolved).
    pub camera: CameraDesc,
    /// Settings.
    pub settings: SettingsDesc,
    /// Materials by key: the scene's names, plus `prefab-path::name` for prefab defaults.
    pub materials: BTreeMap<String, Material>,
    /// Entities in expansion order.
    pub entities: Vec<LoadedEntity>,
    /// Every file the scene depends on: itself first, then prefabs, textures and meshes.
    pub dependencies: Vec<PathBuf>,
    /// The text of the scene file (first) and of each prefab file read, for locating.
    pub sources: Vec<SourceText>,
    /// Where each entity is written, parallel to [`Self::entities`] (may be empty for a scene
    /// built in code).
    pub origins: Vec<Origin>,
    /// Where each material is defined: file (index in [`Self::sources`]) and written name.
    pub material_origins: BTreeMap<String, (u32, String)>,
    /// Every prefab and glTF placement, each after the placement of its own file (see
    /// [`Origin::placement`]).
    pub placements: Vec<Placement>,
    /// Work counted while loading.
    pub stats: LoadStats,
    /// The distant lights of `settings.environment` and `settings.sun`, the map loaded (the
    /// sun may come from a placed glTF file's directional light: `settings.sun` is then set).
    pub sky: Sky,
    /// The point and spot lights: the scene's `lights`, then those of the glTF files placed, in
    /// expansion order.
    pub lights: Vec<PunctualLight>,
    /// What was loaded differently from how the files ask (parts of glTF files that rondo
    /// skips or approximates), one sentence each, naming the file.
    pub warnings: Vec<String>,
}

/// Parses scene source text. RON's `implicit_some` is on, so optional fields are written bare.
pub fn parse_scene(path: &Path, source: &str) -> Result<SceneDesc, SceneError> {
    parse(path, source)
}

fn parse<T: serde::de::DeserializeOwned>(path: &Path, source: &str) -> Result<T, SceneError> {
    crate::scene::format::parse(path, source)
}

/// What an error points at, resolved only when the error is made.
#[derive(Clone, Copy)]
enum Anchor<'s> {
    /// The `index`-th entity of the file: its name's string literal within its `Entity(…)` if it
    /// has one (see [`Origin::offset`]), else its `Entity(`.
    Entity(usize, Option<&'s str>),
    /// The first string literal with these contents.
    Quoted(&'s str),
    /// The material of this name: its key in the file's `materials` map (else the first string
    /// literal of the name).
    Material(&'s str),
    /// The second string literal with these contents (else the first).
    Again(&'s str),
}

/// A file being expanded, for error locations.
struct SourceFile {
    /// Index in [`LoadedScene::sources`].
    id: u32,
    path: PathBuf,
    source: Arc<str>,
}

impl SourceFile {
    /// The location of `anchor`, or of the first string literal `then` at or after it. Scans
    /// the file once: call it for errors only.
    fn location(&self, anchor: Anchor, then: Option<&str>) -> Option<Location> {
        let locator = Locator::new(&self.source);
        let base = match anchor {
            Anchor::Entity(index, Some(name)) => locator
                .in_entity(index, name)
                .or_else(|| locator.first(name)),
            Anchor::Quoted(name) => locator.first(name),
            Anchor::Material(name) => locator.material(name),
            Anchor::Entity(index, None) => locator.entity(index),
            Anchor::Again(name) => locator.second(name).or_else(|| locator.first(name)),
        };
        let offset = match (base, then) {
            (Some(b), Some(t)) => locator.after(t, b).or(base),
            (None, Some(t)) => locator.first(t),
            (b, None) => b,
        };
        offset.map(|o| locator.location(o))
    }

    /// An error at `anchor` (see [`SourceFile::location`]), quoting its line: this file parsed
    /// as a scene or a prefab.
    fn error(&self, anchor: Anchor, then: Option<&str>, message: impl Into<String>) -> SceneError {
        SceneError::at(&self.path, self.location(anchor, then), message).quoting(&self.source)
    }

    fn dir(&self) -> &Path {
        self.path.parent().unwrap_or(Path::new(""))
    }
}

/// Material names visible in one file, mapped to keys of the scene's material table.
type Scope = BTreeMap<String, String>;

/// A prefab file, read and parsed once per load.
struct Prefab {
    file: SourceFile,
    desc: PrefabDesc,
    /// The scope of a placement that maps no names (every default), once built.
    defaults: RefCell<Option<Rc<Scope>>>,
}

/// An entity about to be added: its qualified name, shape (with object-space bounds if it is a
/// mesh), placement and material key.
struct Placed {
    name: String,
    shape: Shape,
    bounds: Option<[Vec3; 2]>,
    transform: Transform,
    key: String,
}

/// A mesh fetched for this load, with its object-space bounds.
struct LoadedMesh {
    data: Arc<MeshData>,
    bounds: [Vec3; 2],
}

struct Expander<'a> {
    assets: &'a mut AssetCache,
    materials: BTreeMap<String, Material>,
    material_origins: BTreeMap<String, (u32, String)>,
    entities: Vec<LoadedEntity>,
    origins: Vec<Origin>,
    placements: Vec<Placement>,
    /// The placement whose file is being expanded (`None`: the scene file).
    placing: Option<u32>,
    /// Dependencies in first-seen order, with a set for O(1) membership.
    dependencies: Vec<PathBuf>,
    seen: HashSet<PathBuf>,
    sources: Vec<SourceText>,
    /// Prefabs by canonical path.
    prefabs: HashMap<PathBuf, Rc<Prefab>>,
    /// Canonical paths of prefab paths already resolved (and found to be regular files).
    canonical: HashMap<PathBuf, PathBuf>,
    /// Assets fetched for this load: the cache is asked once per file, not once per use.
    meshes: HashMap<PathBuf, LoadedMesh>,
    textures: HashMap<PathBuf, Arc<ImageTexture>>,
    /// Canonical paths of the prefabs being expanded, outermost first (cycle detection).
    chain: Vec<PathBuf>,
    /// Whether some written name contains `/`: only then can two qualified names collide.
    slashed: bool,
    stats: LoadStats,
    /// Bounds of glTF primitives by the address of their data, computed once per load.
    gltf_bounds: HashMap<usize, [Vec3; 2]>,
    /// Warnings in first-seen order, each once.
    warnings: Vec<String>,
    warned: HashSet<String>,
    /// Point and spot lights of placed glTF files.
    lights: Vec<PunctualLight>,
    /// Directional lights of placed glTF files, candidates for the scene's sun, each with what
    /// it is (its file and light) for a warning if it is not used.
    suns: Vec<(SunDesc, String)>,
    /// Qualified names of the glTF placements, for the error of a camera that names none.
    gltf_placements: Vec<String>,
    /// The placement whose camera the scene uses, if it is a glTF file's.
    camera_placement: Option<String>,
    /// That placement's file, transform and path, once placed.
    camera_source: Option<(Arc<GltfAsset>, Affine3A, PathBuf)>,
}

/// Reads, parses and validates the scene at `path`, expanding prefabs and loading textures and
/// meshes through `assets`.
///
/// Each call is one load of the cache ([`AssetCache::begin_load`]): a file read by an earlier
/// call is read again, unless a watcher reports changes to the cache.
pub fn load_scene(path: &Path, assets: &mut AssetCache) -> Result<LoadedScene, SceneError> {
    // A scene that cannot be read still starts a load: it asked for no file.
    assets.begin_load();
    let source = read_text(path)
        .map_err(|e| SceneError::at(path, None, format!("cannot read scene: {e}")))?;
    load_scene_source(path, source, assets)
}

/// [`load_scene`] of `source`, the text of the scene file `path` as an editor holds it (not
/// necessarily what is on disk): prefabs, meshes and textures are read from their files,
/// relative to `path`, and errors name `path`.
pub fn load_scene_source(
    path: &Path,
    source: String,
    assets: &mut AssetCache,
) -> Result<LoadedScene, SceneError> {
    assets.begin_load();
    let text: Arc<str> = source.as_str().into();
    // The parse is kept whatever the expansion finds, and a failed parse keeps the last good
    // one: the next edit starts from it.
    let mut kept = assets.take_parsed_scene();
    let loaded = parse_scene_text(path, source, &mut kept)
        .and_then(|(scene, n)| expand_scene(path, text, scene.desc(), n, assets));
    if let Some(scene) = kept {
        assets.keep_parsed_scene(scene);
    }
    loaded
}

/// Expands the parsed scene `desc` of the file `path` (its text `text`, `entities_parsed` of
/// its entities parsed by this load) into a [`LoadedScene`].
fn expand_scene(
    path: &Path,
    text: Arc<str>,
    desc: &SceneDesc,
    entities_parsed: usize,
    assets: &mut AssetCache,
) -> Result<LoadedScene, SceneError> {
    let file = SourceFile {
        id: 0,
        path: path.to_path_buf(),
        source: text,
    };
    let mut x = Expander {
        assets,
        materials: BTreeMap::new(),
        material_origins: BTreeMap::new(),
        entities: Vec::with_capacity(desc.entities.len()),
        origins: Vec::with_capacity(desc.entities.len()),
        placements: Vec::new(),
        placing: None,
        dependencies: Vec::new(),
        seen: HashSet::new(),
        sources: vec![SourceText {
            path: file.path.clone(),
            text: file.source.clone(),
        }],
        prefabs: HashMap::new(),
        canonical: HashMap::new(),
        meshes: HashMap::new(),
        textures: HashMap::new(),
        chain: vec![std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf())],
        slashed: false,
        stats: LoadStats {
            entities_parsed: entities_parsed as u64,
            ..LoadStats::default()
        },
        gltf_bounds: HashMap::new(),
        warnings: Vec::new(),
        warned: HashSet::new(),
        lights: Vec::new(),
        suns: Vec::new(),
        gltf_placements: Vec::new(),
        camera_placement: match &desc.camera {
            SceneCamera::Gltf(g) => Some(g.placement.clone()),
            SceneCamera::Camera(_) => None,
        },
        camera_source: None,
    };
    x.depend(path);
    let mut scope = Scope::new();
    for (name, m) in &desc.materials {
        let material = x.material(&file, name, name, m)?;
        x.materials.insert(name.clone(), material);
        scope.insert(name.clone(), name.clone());
    }
    let mut sky = x.sky(&file, &desc.settings)?;
    x.expand(&file, &desc.entities, &scope, Affine3A::IDENTITY, "")?;
    x.unique_names()?;
    let mut settings = desc.settings.clone();
    for (s, what) in std::mem::take(&mut x.suns) {
        if settings.sun.is_none() {
            sky.sun = Some(Sun::new(
                s.direction,
                s.angular_diameter.to_radians(),
                s.radiance,
            ));
            settings.sun = Some(s);
        } else {
            let warning =
                format!("{what} is ignored: the scene already has a sun, and rondo has one");
            if x.warned.insert(warning.clone()) {
                x.warnings.push(warning);
            }
        }
    }
    let camera = match &desc.camera {
        SceneCamera::Camera(c) => *c,
        SceneCamera::Gltf(g) => x.gltf_camera(&file, g, settings.width, settings.height)?,
    };
    let mut lights: Vec<PunctualLight> = desc.lights.iter().map(|l| l.light).collect();
    lights.append(&mut x.lights);
    Ok(LoadedScene {
        path: path.to_path_buf(),
        camera,
        settings,
        materials: x.materials,
        entities: x.entities,
        dependencies: x.dependencies,
        sources: x.sources,
        origins: x.origins,
        material_origins: x.material_origins,
        placements: x.placements,
        stats: x.stats,
        sky,
        lights,
        warnings: x.warnings,
    })
}

impl Expander<'_> {
    /// Records a warning about the file at `path`, once.
    fn warn(&mut self, path: &Path, message: &str) {
        let warning = format!("{}: {message}", path.display());
        if self.warned.insert(warning.clone()) {
            self.warnings.push(warning);
        }
    }

    /// Records the placement of `file` by the entity at `origin` named `name`; returns its index.
    fn place(&mut self, origin: Origin, name: &str, file: PathBuf, gltf: bool) -> u32 {
        self.placements.push(Placement {
            origin,
            name: name.to_owned(),
            file,
            gltf,
        });
        (self.placements.len() - 1) as u32
    }

    fn depend(&mut self, path: &Path) {
        if !self.seen.contains(path) {
            self.seen.insert(path.to_path_buf());
            self.dependencies.push(path.to_path_buf());
        }
    }

    /// The mesh at `full` with its object-space bounds, fetched once per load.
    fn mesh(&mut self, full: &Path) -> Result<(Arc<MeshData>, [Vec3; 2]), String> {
        if let Some(m) = self.meshes.get(full) {
            return Ok((m.data.clone(), m.bounds));
        }
        let data = self.assets.mesh(full)?;
        let bounds = data.positions.iter().fold(
            [Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)],
            |[lo, hi], &p| [lo.min(p), hi.max(p)],
        );
        self.stats.limit_vertices += data.positions.len() as u64;
        self.meshes.insert(
            full.to_path_buf(),
            LoadedMesh {
                data: data.clone(),
                bounds,
            },
        );
        Ok((data, bounds))
    }

    /// Expands `entities` of `file` under `parent` (`world_from_file`), naming them
    /// `prefix + name`.
    fn expand(
        &mut self,
        file: &SourceFile,
        entities: &[EntityDesc],
        scope: &Scope,
        parent: Affine3A,
        prefix: &str,
    ) -> Result<(), SceneError> {
        let mut names = HashSet::with_capacity(entities.len());
        for (i, e) in entities.iter().enumerate() {
            let local: Cow<str> = match &e.name {
                Some(n) => Cow::Borrowed(n),
                None => Cow::Owned(format!("#{i}")),
            };
            let at = Anchor::Entity(i, e.name.as_deref());
            if !names.insert(local.clone()) {
                let again = e.name.as_deref().map_or(at, Anchor::Again);
                return Err(file.error(again, None, format!("duplicate entity name \"{local}\"")));
            }
            self.slashed |= local.contains('/');
            let mut name = String::with_capacity(prefix.len() + local.len());
            name.push_str(prefix);
            name.push_str(&local);
            let origin = Origin {
                file: file.id,
                index: i as u32,
                prefix: prefix.len() as u32,
                named: e.name.is_some(),
                placement: self.placing,
            };
            // No transform is the identity: `parent` exactly, without composing one.
            let transform = e.transform.map_or(parent, |t| parent * t.matrix());
            match (&e.shape, &e.prefab, &e.gltf) {
                (Some(shape), None, None) => {
                    self.place_shape(file, e, shape, scope, name, transform, origin)?
                }
                (None, Some(prefab), None) => {
                    self.place_prefab(file, e, prefab, scope, &name, transform, origin)?
                }
                (None, None, Some(gltf)) => {
                    self.place_gltf(file, e, gltf, scope, &name, transform, origin)?
                }
                (None, None, None) => {
                    return Err(file.error(
                        at,
                        None,
                        format!("entity \"{name}\": `shape`, `prefab` or `gltf` is required"),
                    ));
                }
                _ => {
                    return Err(file.error(
                        at,
                        None,
                        format!(
                            "entity \"{name}\": give one of `shape`, `prefab` and `gltf`, not several"
                        ),
                    ));
                }
            }
            if self.entities.len() > MAX_ENTITIES {
                return Err(file.error(
                    at,
                    None,
                    format!("the scene expands to more than {MAX_ENTITIES} entities"),
                ));
            }
        }
        Ok(())
    }

    #[expect(
        clippy::too_many_arguments,
        reason = "the entity and everything it is placed by"
    )]
    fn place_shape(
        &mut self,
        file: &SourceFile,
        e: &EntityDesc,
        shape: &ShapeDesc,
        scope: &Scope,
        name: String,
        transform: Affine3A,
        origin: Origin,
    ) -> Result<(), SceneError> {
        let at = Anchor::Entity(origin.index as usize, e.name.as_deref());
        if e.materials.is_some() {
            return Err(file.error(
                at,
                None,
                format!(
                    "entity \"{name}\": `materials` maps a prefab's names; a shape takes `material`"
                ),
            ));
        }
        let Some(material) = &e.material else {
            return Err(file.error(
                at,
                None,
                format!("entity \"{name}\": `material` is required with `shape`"),
            ));
        };
        let Some(key) = scope.get(material) else {
            let known: Vec<&str> = scope.keys().map(String::as_str).collect();
            return Err(file.error(
                at,
                Some(material),
                format!(
                    "entity \"{name}\": unknown material \"{material}\" (defined: {})",
                    known.join(", ")
                ),
            ));
        };
        let transform = Transform(transform);
        let (shape, bounds) = match shape {
            ShapeDesc::Analytic(s) => (s.clone(), None),
            ShapeDesc::Mesh { path } => {
                let full = file.dir().join(path);
                self.depend(&full);
                let (data, bounds) = self.mesh(&full).map_err(|m| {
                    file.error(
                        at,
                        Some(path),
                        format!("entity \"{name}\": mesh {}: {m}", full.display()),
                    )
                })?;
                (Shape::Mesh(MeshRef { path: full, data }), Some(bounds))
            }
        };
        let placed = Placed {
            name,
            shape,
            bounds,
            transform,
            key: key.clone(),
        };
        self.push_entity(file, at, placed, origin)
    }

    /// Adds an entity after checking that a sphere stays a sphere and that the shape stays
    /// within [`MAX_COORDINATE`] of the origin (a mesh's bounds decide unless they reach past it).
    fn push_entity(
        &mut self,
        file: &SourceFile,
        at: Anchor,
        placed: Placed,
        origin: Origin,
    ) -> Result<(), SceneError> {
        let Placed {
            name,
            shape,
            bounds,
            transform,
            key,
        } = placed;
        if matches!(shape, Shape::Sphere { .. }) && !transform.is_similarity() {
            return Err(file.error(
                at,
                None,
                format!("entity \"{name}\": a sphere cannot take a non-uniform scale or shear (it would be an ellipsoid)"),
            ));
        }
        // The 8 corners of a mesh's bounds bound all its vertices; the exact scan runs only
        // when they exceed the limit, so the same scenes are accepted as by the exact scan.
        let within = bounds.is_some_and(|b| {
            self.stats.limit_vertices += 8;
            corner_reach(b, &transform) <= MAX_COORDINATE
        });
        if !within {
            let (reach, visited) = world_reach(&shape, &transform);
            self.stats.limit_vertices += visited;
            if reach.is_nan() || reach > MAX_COORDINATE {
                return Err(file.error(
                    at,
                    None,
                    format!("entity \"{name}\": reaches {reach:e} in world space, beyond ±{MAX_COORDINATE:e}"),
                ));
            }
        }
        self.entities.push(LoadedEntity {
            name,
            shape,
            transform,
            material: key,
        });
        self.origins.push(origin);
        Ok(())
    }

    /// Refuses two entities with one qualified name (`"tall/box"` written beside the child
    /// `"box"` of a placement `"tall"`): one of them would silently replace the other. Names are
    /// unique within each file, so this can only happen when a written name contains `/`.
    fn unique_names(&self) -> Result<(), SceneError> {
        if !self.slashed {
            return Ok(());
        }
        let mut seen: HashMap<&str, usize> = HashMap::with_capacity(self.entities.len());
        for (k, e) in self.entities.iter().enumerate() {
            let Some(first) = seen.insert(&e.name, k) else {
                continue;
            };
            let mut places = Places::new(&self.sources);
            let mut describe = |i: usize| {
                let (e, o) = (&self.entities[i], self.origins[i]);
                let offset = places.locator(o.file).and_then(|l| o.offset(&e.name, l));
                let location =
                    offset.and_then(|off| places.locator(o.file).map(|l| l.location(off)));
                let place = places.describe(o.file, location);
                let what = match o.prefix {
                    0 => format!("entity \"{}\"", e.name),
                    p => format!(
                        "\"{}\" of placement \"{}\"",
                        &e.name[p as usize..],
                        &e.name[..p as usize - 1]
                    ),
                };
                (format!("{what} at {place}"), location)
            };
            let (a, _) = describe(first);
            let (b, location) = describe(k);
            let file = &self.sources[self.origins[k].file as usize];
            return Err(SceneError::at(
                &file.path,
                location,
                format!(
                    "two entities are named \"{}\": {b} and {a}; one would replace the other, rename one",
                    e.name
                ),
            )
            .quoting(&file.text));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_unchanged_file_is_read_once() {
        let temp = tempfile::Builder::new()
            .prefix("rondo-cache-")
            .tempdir()
            .expect("dir");
        let dir = temp.path();
        let path = dir.join("t.obj");
        std::fs::write(&path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").expect("write");
        let mut cache = AssetCache::default();
        let a = cache.mesh(&path).expect("mesh");
        let b = cache.mesh(&path).expect("mesh");
        assert!(Arc::ptr_eq(&a, &b));
        assert_eq!(cache.mesh_loads(), 1);
        assert!(cache.mesh(dir).is_err(), "a directory is not a mesh");
    }
}
