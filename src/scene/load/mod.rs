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

use crate::model::{MeshData, MeshRef, Shape, Transform};
use crate::shading::material::Material;
use crate::shading::texture::{ImageTexture, Sampling, Texture};
use crate::sky::{EnvironmentLight, Sky, Sun};

mod gltf;
mod reach;

use self::reach::{corner_reach, world_reach};
pub use super::assets::AssetCache;
use super::error::{Location, SceneError};
use super::format::{
    CameraDesc, EntityDesc, MAX_COORDINATE, MaterialDesc, PrefabDesc, SceneDesc, SettingsDesc,
    ShapeDesc, TextureDesc,
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
}

impl Origin {
    /// Offset of the entity named `qualified` in its file, found by that file's locator: its
    /// name's first string literal, or for an unnamed entity its `Entity(`.
    pub fn offset(&self, qualified: &str, locator: &Locator) -> Option<usize> {
        if self.named {
            locator.first(qualified.get(self.prefix as usize..)?)
        } else {
            locator.entity(self.index as usize)
        }
    }
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
    /// The camera.
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
    /// Work counted while loading.
    pub stats: LoadStats,
    /// The distant lights of `settings.environment` and `settings.sun`, the map loaded.
    pub sky: Sky,
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
    /// The `index`-th entity of the file: its name's first string literal if it has one, else
    /// its `Entity(`.
    Entity(usize, Option<&'s str>),
    /// The first string literal with these contents.
    Quoted(&'s str),
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
            Anchor::Entity(_, Some(name)) | Anchor::Quoted(name) => locator.first(name),
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
}

/// Reads, parses and validates the scene at `path`, expanding prefabs and loading textures and
/// meshes through `assets`.
///
/// Each call is one load of the cache ([`AssetCache::begin_load`]): a file read by an earlier
/// call is read again, unless a watcher reports changes to the cache.
pub fn load_scene(path: &Path, assets: &mut AssetCache) -> Result<LoadedScene, SceneError> {
    assets.begin_load();
    let source = std::fs::read_to_string(path)
        .map_err(|e| SceneError::at(path, None, format!("cannot read scene: {e}")))?;
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
    };
    x.depend(path);
    let mut scope = Scope::new();
    for (name, m) in &desc.materials {
        let material = x.material(&file, name, name, m)?;
        x.materials.insert(name.clone(), material);
        scope.insert(name.clone(), name.clone());
    }
    let sky = x.sky(&file, &desc.settings)?;
    x.expand(&file, &desc.entities, &scope, Affine3A::IDENTITY, "")?;
    x.unique_names()?;
    Ok(LoadedScene {
        path: path.to_path_buf(),
        camera: desc.camera,
        settings: desc.settings.clone(),
        materials: x.materials,
        entities: x.entities,
        dependencies: x.dependencies,
        sources: x.sources,
        origins: x.origins,
        material_origins: x.material_origins,
        stats: x.stats,
        sky,
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

    fn depend(&mut self, path: &Path) {
        if !self.seen.contains(path) {
            self.seen.insert(path.to_path_buf());
            self.dependencies.push(path.to_path_buf());
        }
    }

    /// The sky of the scene `file`'s settings: its environment map loaded (a dependency)
    /// through the cache, its sun placed.
    fn sky(&mut self, file: &SourceFile, settings: &SettingsDesc) -> Result<Sky, SceneError> {
        let environment = match &settings.environment {
            None => None,
            Some(env) => {
                let full = file.dir().join(&env.path);
                self.depend(&full);
                let fail = |e: String| {
                    file.error(
                        Anchor::Quoted(&env.path),
                        None,
                        format!("settings.environment: {}: {e}", full.display()),
                    )
                };
                let map = self.assets.environment(&full).map_err(fail)?;
                Some(EnvironmentLight::new(map, env.strength, env.world_from_map()).map_err(fail)?)
            }
        };
        let sun = settings
            .sun
            .map(|s| Sun::new(s.direction, s.angular_diameter.to_radians(), s.radiance));
        Ok(Sky { environment, sun })
    }

    /// Builds material `name` of `file`, loading its textures; records where it is defined
    /// under its table key `key`.
    fn material(
        &mut self,
        file: &SourceFile,
        name: &str,
        key: &str,
        m: &MaterialDesc,
    ) -> Result<Material, SceneError> {
        self.material_origins
            .insert(key.to_string(), (file.id, name.to_string()));
        let mut texture = |t: &TextureDesc| {
            self.texture(t, file.dir()).map_err(|(p, msg)| {
                file.error(
                    Anchor::Quoted(name),
                    Some(&p),
                    format!("material \"{name}\": {msg}"),
                )
            })
        };
        Ok(match m {
            MaterialDesc::Diffuse { albedo } => Material::Diffuse {
                albedo: texture(albedo)?,
            },
            MaterialDesc::Metal { albedo, roughness } => Material::Metal {
                albedo: texture(albedo)?,
                roughness: roughness.0.clamp(0.0, 1.0),
            },
            MaterialDesc::Glossy { albedo, roughness } => Material::Glossy {
                albedo: texture(albedo)?,
                roughness: roughness
                    .0
                    .clamp(crate::shading::microfacet::MIN_ROUGHNESS, 1.0),
            },
            MaterialDesc::Dielectric { ior } => Material::Dielectric { ior: ior.0 },
            MaterialDesc::Light {
                emit,
                intensity,
                two_sided,
            } => Material::Light {
                emit: texture(emit)?,
                intensity: intensity.0,
                two_sided: *two_sided,
            },
            MaterialDesc::Pbr {
                base_color,
                metallic,
                roughness,
                emissive,
                emissive_strength,
                normal_map,
                alpha_cutoff,
            } => {
                let base_color = texture(base_color)?;
                Material::Pbr {
                    alpha: alpha_cutoff
                        .map(|c| crate::shading::maps::AlphaMask::of_base_color(c.0, &base_color)),
                    base_color,
                    metallic: metallic.0,
                    roughness: roughness.0,
                    metallic_roughness: None,
                    emissive: texture(emissive)?,
                    emissive_strength: emissive_strength.0,
                    normal_map: match normal_map {
                        None => None,
                        Some(desc) => {
                            Some(self.normal_map(desc, file.dir()).map_err(|(p, msg)| {
                                file.error(
                                    Anchor::Quoted(name),
                                    Some(&p),
                                    format!("material \"{name}\": normal_map: {msg}"),
                                )
                            })?)
                        }
                    },
                }
            }
        })
    }

    /// Loads the normal map `desc` relative to `dir` as linear data (a dependency). Errors carry
    /// the path text.
    fn normal_map(
        &mut self,
        desc: &super::format::NormalMapDesc,
        dir: &Path,
    ) -> Result<crate::shading::maps::NormalMap, (String, String)> {
        let full = dir.join(&desc.path);
        self.depend(&full);
        let image = self
            .assets
            .image(&full, super::assets::Encoding::Linear)
            .map_err(|e| (desc.path.clone(), format!("{}: {e}", full.display())))?;
        let sampling = Sampling {
            filter: desc.filter,
            wrap: [desc.wrap; 2],
        };
        Ok(crate::shading::maps::NormalMap {
            texture: Texture::Image(image, sampling),
            scale: desc.scale.0,
        })
    }

    /// Builds a texture, loading image files relative to `dir`. Errors carry the path text.
    fn texture(&mut self, t: &TextureDesc, dir: &Path) -> Result<Texture, (String, String)> {
        Ok(match t {
            TextureDesc::Constant(c) => Texture::Constant(c.0),
            TextureDesc::Checker { scale, even, odd } => Texture::Checker {
                scale: scale.0,
                even: Box::new(self.texture(even, dir)?),
                odd: Box::new(self.texture(odd, dir)?),
            },
            TextureDesc::Image { path, filter, wrap } => {
                let full = dir.join(path);
                self.depend(&full);
                let sampling = Sampling {
                    filter: *filter,
                    wrap: [*wrap; 2],
                };
                if let Some(image) = self.textures.get(&full) {
                    return Ok(Texture::Image(image.clone(), sampling));
                }
                let image = self
                    .assets
                    .texture(&full)
                    .map_err(|e| (path.clone(), format!("{}: {e}", full.display())))?;
                self.textures.insert(full, image.clone());
                Texture::Image(image, sampling)
            }
        })
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
            };
            // No transform is the identity: `parent` exactly, without composing one.
            let transform = e.transform.map_or(parent, |t| parent * t.matrix());
            match (&e.shape, &e.prefab, &e.gltf) {
                (Some(shape), None, None) => {
                    self.place_shape(file, e, shape, scope, name, transform, origin)?
                }
                (None, Some(prefab), None) => {
                    self.place_prefab(file, e, prefab, scope, &name, transform, i)?
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

    /// The canonical path of prefab `path`, checked to be a regular file, once per path.
    fn canonical_prefab(&mut self, path: &Path) -> Result<PathBuf, String> {
        if let Some(c) = self.canonical.get(path) {
            return Ok(c.clone());
        }
        self.assets.note(path);
        let canonical = std::fs::canonicalize(path)
            .map_err(|err| format!("cannot read prefab {}: {err}", path.display()))?;
        if !std::fs::metadata(&canonical).is_ok_and(|m| m.is_file()) {
            return Err(format!("prefab {} is not a regular file", path.display()));
        }
        self.canonical.insert(path.to_path_buf(), canonical.clone());
        Ok(canonical)
    }

    #[expect(
        clippy::too_many_arguments,
        reason = "the entity and everything it is placed by"
    )]
    fn place_prefab(
        &mut self,
        file: &SourceFile,
        e: &EntityDesc,
        prefab: &str,
        scope: &Scope,
        name: &str,
        transform: Affine3A,
        index: usize,
    ) -> Result<(), SceneError> {
        let at = Anchor::Entity(index, e.name.as_deref());
        if e.material.is_some() {
            return Err(file.error(at, None, format!("entity \"{name}\": a prefab placement maps names with `materials`, not `material`")));
        }
        let path = file.dir().join(prefab);
        let canonical = self
            .canonical_prefab(&path)
            .map_err(|m| file.error(at, Some(prefab), format!("entity \"{name}\": {m}")))?;
        if let Some(start) = self.chain.iter().position(|p| *p == canonical) {
            let cycle: Vec<String> = self.chain[start..]
                .iter()
                .chain([&canonical])
                .map(|p| p.display().to_string())
                .collect();
            return Err(file.error(
                at,
                Some(prefab),
                format!("prefab cycle: {}", cycle.join(" → ")),
            ));
        }
        if self.chain.len() > MAX_PREFAB_DEPTH {
            return Err(file.error(
                at,
                Some(prefab),
                format!("prefabs nested deeper than {MAX_PREFAB_DEPTH}"),
            ));
        }
        self.depend(&path);
        let loaded = match self.prefabs.get(&canonical) {
            Some(p) => p.clone(),
            None => {
                let source = std::fs::read_to_string(&path).map_err(|err| {
                    file.error(
                        at,
                        Some(prefab),
                        format!(
                            "entity \"{name}\": cannot read prefab {}: {err}",
                            path.display()
                        ),
                    )
                })?;
                // Its text is quoted with a parse error only if it is meant to be RON: a mesh,
                // an image or any other file named as a prefab by mistake (or to read it
                // through the viewer) is not shown.
                let desc: PrefabDesc = parse(&path, &source).map_err(|e| {
                    let ron = path
                        .extension()
                        .is_some_and(|x| x.eq_ignore_ascii_case("ron"));
                    if ron { e } else { e.unquoted() }
                })?;
                let file = SourceFile {
                    id: self.sources.len() as u32,
                    path: path.clone(),
                    source: source.into(),
                };
                self.sources.push(SourceText {
                    path: path.clone(),
                    text: file.source.clone(),
                });
                let p = Rc::new(Prefab {
                    file,
                    desc,
                    defaults: RefCell::new(None),
                });
                self.prefabs.insert(canonical.clone(), p.clone());
                p
            }
        };
        let (prefab_file, desc) = (&loaded.file, &loaded.desc);

        // The prefab's names: mapped by the placement, else the prefab's own default. A
        // placement that maps nothing shares the scope built by the first such placement.
        let cached = e
            .materials
            .as_ref()
            .is_none_or(BTreeMap::is_empty)
            .then(|| loaded.defaults.borrow().clone())
            .flatten();
        let inner = match cached {
            Some(scope) => scope,
            None => {
                let mut inner = Scope::new();
                for (theirs, ours) in e.materials.iter().flatten() {
                    let Some(key) = scope.get(ours) else {
                        return Err(file.error(
                            at,
                            Some(ours),
                            format!("entity \"{name}\": maps \"{theirs}\" to unknown material \"{ours}\""),
                        ));
                    };
                    inner.insert(theirs.clone(), key.clone());
                }
                for (own, m) in &desc.materials {
                    if inner.contains_key(own) {
                        continue;
                    }
                    let key = format!("{}::{own}", canonical.display());
                    if !self.materials.contains_key(&key) {
                        let material = self.material(prefab_file, own, &key, m)?;
                        self.materials.insert(key.clone(), material);
                    }
                    inner.insert(own.clone(), key);
                }
                let inner = Rc::new(inner);
                if e.materials.as_ref().is_none_or(BTreeMap::is_empty) {
                    *loaded.defaults.borrow_mut() = Some(inner.clone());
                }
                inner
            }
        };
        if let Some(missing) = desc
            .entities
            .iter()
            .filter(|c| c.shape.is_some())
            .filter_map(|c| c.material.as_ref())
            .find(|m| !inner.contains_key(*m))
        {
            let loc = file
                .location(at, None)
                .map(|l| format!(":{}:{}", l.line, l.col))
                .unwrap_or_default();
            return Err(prefab_file.error(
                Anchor::Quoted(missing),
                None,
                format!(
                    "material \"{missing}\" is defined neither by this prefab nor by its placement \"{name}\" in {}{loc}",
                    file.path.display()
                ),
            ));
        }
        self.chain.push(canonical);
        let result = self.expand(
            prefab_file,
            &desc.entities,
            &inner,
            transform,
            &format!("{name}/"),
        );
        self.chain.pop();
        result
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
