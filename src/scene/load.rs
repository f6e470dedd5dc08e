//! Reading a scene file: parse, expand prefabs, validate names and references, load textures
//! and meshes.

use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::sync::Arc;

use glam::Affine3A;

use crate::ecs::components::{MeshData, MeshRef, Shape, Transform};
use crate::shading::material::Material;
use crate::shading::texture::{ImageTexture, Texture};

use super::error::{Location, SceneError};
use super::format::{
    CameraDesc, EntityDesc, MAX_COORDINATE, MaterialDesc, PrefabDesc, SceneDesc, SettingsDesc,
    ShapeDesc, TextureDesc,
};

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
}

struct Cached<T> {
    /// Hash of the file's bytes when it was loaded.
    hash: u64,
    value: Arc<T>,
}

/// Decoded images and meshes by path. Every load reads the file's bytes and decodes them again
/// only when their hash differs from the cached one: content decides, not the modification time
/// or the size, which a `cp -p`, a build tool or a `git checkout` on a coarse-mtime file system
/// can leave unchanged for a different file. An edit to one texture or mesh decodes that file
/// only; reading and hashing an unchanged file costs about 1 ms per 4 MB (SipHash).
#[derive(Default)]
pub struct AssetCache {
    images: HashMap<PathBuf, Cached<ImageTexture>>,
    meshes: HashMap<PathBuf, Cached<MeshData>>,
    decodes: u64,
    mesh_loads: u64,
    /// Every asset or prefab path asked for since [`AssetCache::begin_load`], found or not.
    requested: Vec<PathBuf>,
}

/// The cached value for `path`, or `load(bytes)` when the file is new or its bytes changed.
fn cached<T>(
    map: &mut HashMap<PathBuf, Cached<T>>,
    path: &Path,
    load: impl FnOnce(&[u8]) -> Result<T, String>,
) -> Result<(Arc<T>, bool), String> {
    use std::hash::Hasher;
    let meta = std::fs::metadata(path).map_err(|e| format!("cannot read: {e}"))?;
    if meta.is_dir() {
        return Err("is a directory, not a file".into());
    }
    // A device or a pipe (`/dev/zero`, a FIFO) would be read forever.
    if !meta.is_file() {
        return Err("is not a regular file".into());
    }
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read: {e}"))?;
    let mut hasher = std::hash::DefaultHasher::new();
    hasher.write(&bytes);
    let hash = hasher.finish();
    if let Some(c) = map.get(path)
        && c.hash == hash
    {
        return Ok((c.value.clone(), false));
    }
    let value = Arc::new(load(&bytes)?);
    map.insert(
        path.to_path_buf(),
        Cached {
            hash,
            value: value.clone(),
        },
    );
    Ok((value, true))
}

impl AssetCache {
    /// Number of image decodes so far.
    pub fn decodes(&self) -> u64 {
        self.decodes
    }

    /// Number of mesh file loads so far.
    pub fn mesh_loads(&self) -> u64 {
        self.mesh_loads
    }

    /// Starts a scene load: forgets the paths asked for by the previous one.
    pub fn begin_load(&mut self) {
        self.requested.clear();
    }

    /// Records that the load asked for `path` (a texture, a mesh or a prefab), whether or not
    /// it exists: a failed load still tells a watcher which files could fix it.
    pub fn note(&mut self, path: &Path) {
        if !self.requested.iter().any(|p| p == path) {
            self.requested.push(path.to_path_buf());
        }
    }

    /// Every texture, mesh or prefab path asked for since [`AssetCache::begin_load`].
    pub fn requested(&self) -> &[PathBuf] {
        &self.requested
    }

    /// The texture at `path`, decoded now or taken from the cache.
    pub fn texture(&mut self, path: &Path) -> Result<Arc<ImageTexture>, String> {
        self.note(path);
        let (value, fresh) = cached(&mut self.images, path, |bytes| decode_image(path, bytes))?;
        self.decodes += u64::from(fresh);
        Ok(value)
    }

    /// The mesh at `path`, read now or taken from the cache.
    pub fn mesh(&mut self, path: &Path) -> Result<Arc<MeshData>, String> {
        self.note(path);
        let (value, fresh) = cached(&mut self.meshes, path, super::mesh::parse_obj)?;
        self.mesh_loads += u64::from(fresh);
        Ok(value)
    }
}

/// Decodes the image file `path` from its `bytes` (the format from the content, else from the
/// extension).
fn decode_image(path: &Path, bytes: &[u8]) -> Result<ImageTexture, String> {
    let mut reader = image::ImageReader::new(std::io::Cursor::new(bytes));
    if let Ok(format) = image::ImageFormat::from_path(path) {
        reader.set_format(format);
    }
    let decoded = reader
        .with_guessed_format()
        .map_err(|e| format!("cannot read image: {e}"))?
        .decode()
        .map_err(|e| format!("cannot decode image: {e}"))?;
    if decoded.width() == 0 || decoded.height() == 0 {
        return Err("image is empty".into());
    }
    // Float images (EXR) hold linear values; 8/16-bit ones are sRGB-encoded.
    Ok(match decoded {
        image::DynamicImage::ImageRgb32F(_) | image::DynamicImage::ImageRgba32F(_) => {
            let linear = decoded.into_rgb32f();
            ImageTexture::from_linear(linear.width(), linear.height(), linear.as_raw())
        }
        other => {
            let srgb = other.into_rgb8();
            ImageTexture::from_srgb8(srgb.width(), srgb.height(), srgb.as_raw())
        }
    })
}

/// Parses scene source text. RON's `implicit_some` is on, so optional fields are written bare.
pub fn parse_scene(path: &Path, source: &str) -> Result<SceneDesc, SceneError> {
    parse(path, source)
}

fn parse<T: serde::de::DeserializeOwned>(path: &Path, source: &str) -> Result<T, SceneError> {
    ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
        .from_str(source)
        .map_err(|e| SceneError::from_ron(path, &e))
}

/// Byte offset of the quoted string `"text"` in `source` at or after `from`.
fn find_quoted(source: &str, text: &str, from: usize) -> Option<usize> {
    let needle = format!("\"{text}\"");
    source.get(from..)?.find(&needle).map(|i| i + from)
}

/// Byte offset of the `index`-th `Entity(` in `source` (a best effort for unnamed entities).
fn find_entity(source: &str, index: usize) -> Option<usize> {
    source.match_indices("Entity(").nth(index).map(|(i, _)| i)
}

/// A file being expanded, for error locations.
struct SourceFile {
    path: PathBuf,
    source: String,
}

impl SourceFile {
    fn loc(&self, offset: Option<usize>) -> Option<Location> {
        offset.map(|o| Location::of_offset(&self.source, o))
    }

    fn error(&self, offset: Option<usize>, message: impl Into<String>) -> SceneError {
        SceneError::at(&self.path, self.loc(offset), message)
    }

    fn dir(&self) -> &Path {
        self.path.parent().unwrap_or(Path::new(""))
    }
}

/// Material names visible in one file, mapped to keys of the scene's material table.
type Scope = BTreeMap<String, String>;

struct Expander<'a> {
    assets: &'a mut AssetCache,
    materials: BTreeMap<String, Material>,
    entities: Vec<LoadedEntity>,
    dependencies: Vec<PathBuf>,
    prefabs: HashMap<PathBuf, Rc<(SourceFile, PrefabDesc)>>,
    /// Canonical paths of the prefabs being expanded, outermost first (cycle detection).
    chain: Vec<PathBuf>,
}

/// Reads, parses and validates the scene at `path`, expanding prefabs and loading textures and
/// meshes through `assets`.
pub fn load_scene(path: &Path, assets: &mut AssetCache) -> Result<LoadedScene, SceneError> {
    let source = std::fs::read_to_string(path)
        .map_err(|e| SceneError::at(path, None, format!("cannot read scene: {e}")))?;
    let desc: SceneDesc = parse(path, &source)?;
    let file = SourceFile {
        path: path.to_path_buf(),
        source,
    };
    let mut x = Expander {
        assets,
        materials: BTreeMap::new(),
        entities: Vec::new(),
        dependencies: vec![path.to_path_buf()],
        prefabs: HashMap::new(),
        chain: vec![std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf())],
    };
    let mut scope = Scope::new();
    for (name, m) in &desc.materials {
        let material = x.material(&file, name, m)?;
        x.materials.insert(name.clone(), material);
        scope.insert(name.clone(), name.clone());
    }
    x.expand(&file, &desc.entities, &scope, Affine3A::IDENTITY, "")?;
    Ok(LoadedScene {
        path: path.to_path_buf(),
        camera: desc.camera,
        settings: desc.settings,
        materials: x.materials,
        entities: x.entities,
        dependencies: x.dependencies,
    })
}

impl Expander<'_> {
    fn depend(&mut self, path: &Path) {
        if !self.dependencies.iter().any(|d| d == path) {
            self.dependencies.push(path.to_path_buf());
        }
    }

    /// Builds material `name` of `file`, loading its textures.
    fn material(
        &mut self,
        file: &SourceFile,
        name: &str,
        m: &MaterialDesc,
    ) -> Result<Material, SceneError> {
        let at = find_quoted(&file.source, name, 0);
        let mut texture = |t: &TextureDesc| {
            self.texture(t, file.dir()).map_err(|(p, msg)| {
                let offset = find_quoted(&file.source, &p, at.unwrap_or(0)).or(at);
                file.error(offset, format!("material \"{name}\": {msg}"))
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
            TextureDesc::Image { path } => {
                let full = dir.join(path);
                self.depend(&full);
                let image = self
                    .assets
                    .texture(&full)
                    .map_err(|e| (path.clone(), format!("{}: {e}", full.display())))?;
                Texture::Image(image)
            }
        })
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
        let mut names = HashSet::new();
        for (i, e) in entities.iter().enumerate() {
            let local = e.name.clone().unwrap_or_else(|| format!("#{i}"));
            let at = match &e.name {
                Some(n) => find_quoted(&file.source, n, 0),
                None => find_entity(&file.source, i),
            };
            if !names.insert(local.clone()) {
                let again = match &e.name {
                    Some(n) => at.and_then(|f| find_quoted(&file.source, n, f + 1)).or(at),
                    None => at,
                };
                return Err(file.error(again, format!("duplicate entity name \"{local}\"")));
            }
            let name = format!("{prefix}{local}");
            let transform = parent * e.transform.unwrap_or_default().matrix();
            match (&e.shape, &e.prefab) {
                (Some(shape), None) => {
                    self.place_shape(file, e, shape, scope, name, transform, at)?
                }
                (None, Some(prefab)) => {
                    self.place_prefab(file, e, prefab, scope, &name, transform, at)?
                }
                (Some(_), Some(_)) => {
                    return Err(file.error(
                        at,
                        format!("entity \"{name}\": give `shape` or `prefab`, not both"),
                    ));
                }
                (None, None) => {
                    return Err(file.error(
                        at,
                        format!("entity \"{name}\": `shape` or `prefab` is required"),
                    ));
                }
            }
            if self.entities.len() > MAX_ENTITIES {
                return Err(file.error(
                    at,
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
        at: Option<usize>,
    ) -> Result<(), SceneError> {
        if e.materials.is_some() {
            return Err(file.error(
                at,
                format!(
                    "entity \"{name}\": `materials` maps a prefab's names; a shape takes `material`"
                ),
            ));
        }
        let Some(material) = &e.material else {
            return Err(file.error(
                at,
                format!("entity \"{name}\": `material` is required with `shape`"),
            ));
        };
        let Some(key) = scope.get(material) else {
            let known: Vec<&str> = scope.keys().map(String::as_str).collect();
            let offset = at
                .and_then(|a| find_quoted(&file.source, material, a))
                .or(at);
            return Err(file.error(
                offset,
                format!(
                    "entity \"{name}\": unknown material \"{material}\" (defined: {})",
                    known.join(", ")
                ),
            ));
        };
        let transform = Transform(transform);
        let shape = match shape {
            ShapeDesc::Analytic(s) => s.clone(),
            ShapeDesc::Mesh { path } => {
                let full = file.dir().join(path);
                self.depend(&full);
                let data = self.assets.mesh(&full).map_err(|m| {
                    let offset = at.and_then(|a| find_quoted(&file.source, path, a)).or(at);
                    file.error(
                        offset,
                        format!("entity \"{name}\": mesh {}: {m}", full.display()),
                    )
                })?;
                Shape::Mesh(MeshRef { path: full, data })
            }
        };
        if matches!(shape, Shape::Sphere { .. }) && !transform.is_similarity() {
            return Err(file.error(
                at,
                format!("entity \"{name}\": a sphere cannot take a non-uniform scale or shear (it would be an ellipsoid)"),
            ));
        }
        let reach = world_reach(&shape, &transform);
        if reach.is_nan() || reach > MAX_COORDINATE {
            return Err(file.error(
                at,
                format!("entity \"{name}\": reaches {reach:e} in world space, beyond ±{MAX_COORDINATE:e}"),
            ));
        }
        self.entities.push(LoadedEntity {
            name,
            shape,
            transform,
            material: key.clone(),
        });
        Ok(())
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
        at: Option<usize>,
    ) -> Result<(), SceneError> {
        let where_ = at.and_then(|a| find_quoted(&file.source, prefab, a)).or(at);
        if e.material.is_some() {
            return Err(file.error(at, format!("entity \"{name}\": a prefab placement maps names with `materials`, not `material`")));
        }
        let path = file.dir().join(prefab);
        self.assets.note(&path);
        let canonical = std::fs::canonicalize(&path).map_err(|err| {
            file.error(
                where_,
                format!(
                    "entity \"{name}\": cannot read prefab {}: {err}",
                    path.display()
                ),
            )
        })?;
        if let Some(start) = self.chain.iter().position(|p| *p == canonical) {
            let cycle: Vec<String> = self.chain[start..]
                .iter()
                .chain([&canonical])
                .map(|p| p.display().to_string())
                .collect();
            return Err(file.error(where_, format!("prefab cycle: {}", cycle.join(" → "))));
        }
        if self.chain.len() > MAX_PREFAB_DEPTH {
            return Err(file.error(
                where_,
                format!("prefabs nested deeper than {MAX_PREFAB_DEPTH}"),
            ));
        }
        if !std::fs::metadata(&canonical).is_ok_and(|m| m.is_file()) {
            return Err(file.error(
                where_,
                format!(
                    "entity \"{name}\": prefab {} is not a regular file",
                    path.display()
                ),
            ));
        }
        self.depend(&path);
        let loaded = match self.prefabs.get(&canonical) {
            Some(p) => p.clone(),
            None => {
                let source = std::fs::read_to_string(&path).map_err(|err| {
                    file.error(
                        where_,
                        format!(
                            "entity \"{name}\": cannot read prefab {}: {err}",
                            path.display()
                        ),
                    )
                })?;
                let desc: PrefabDesc = parse(&path, &source)?;
                let p = Rc::new((
                    SourceFile {
                        path: path.clone(),
                        source,
                    },
                    desc,
                ));
                self.prefabs.insert(canonical.clone(), p.clone());
                p
            }
        };
        let (prefab_file, desc) = (&loaded.0, &loaded.1);

        // The prefab's names: mapped by the placement, else the prefab's own default.
        let mut inner = Scope::new();
        for (theirs, ours) in e.materials.iter().flatten() {
            let Some(key) = scope.get(ours) else {
                let offset = at.and_then(|a| find_quoted(&file.source, ours, a)).or(at);
                return Err(file.error(
                    offset,
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
                let material = self.material(prefab_file, own, m)?;
                self.materials.insert(key.clone(), material);
            }
            inner.insert(own.clone(), key);
        }
        if let Some(missing) = desc
            .entities
            .iter()
            .filter(|c| c.shape.is_some())
            .filter_map(|c| c.material.as_ref())
            .find(|m| !inner.contains_key(*m))
        {
            let loc = file
                .loc(at)
                .map(|l| format!(":{}:{}", l.line, l.col))
                .unwrap_or_default();
            let offset = find_quoted(&prefab_file.source, missing, 0);
            return Err(prefab_file.error(
                offset,
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
}

/// Largest magnitude of any world-space coordinate of `shape` placed by `transform`: its
/// vertices (box corners, mesh positions), a sphere's centre plus radius, a plane's point. NaN or
/// infinite if the transform overflows.
fn world_reach(shape: &Shape, transform: &Transform) -> f32 {
    let m = &transform.0;
    let reach = |points: &mut dyn Iterator<Item = glam::Vec3>| {
        points.fold(0.0f32, |r, p| {
            let a = m.transform_point3(p).abs().max_element();
            if a.is_nan() || r.is_nan() {
                f32::NAN
            } else {
                r.max(a)
            }
        })
    };
    match shape {
        Shape::Sphere { center, radius } => {
            let c = m.transform_point3(*center).abs().max_element();
            c + radius * transform.uniform_scale()
        }
        Shape::Plane { point, .. } => reach(&mut std::iter::once(*point)),
        Shape::Triangle { a, b, c } => reach(&mut [*a, *b, *c].into_iter()),
        Shape::Quad { a, b, c, d } => reach(&mut [*a, *b, *c, *d].into_iter()),
        Shape::Box { min, max } => reach(&mut (0..8).map(|i| {
            glam::Vec3::new(
                if i & 1 == 0 { min.x } else { max.x },
                if i & 2 == 0 { min.y } else { max.y },
                if i & 4 == 0 { min.z } else { max.z },
            )
        })),
        Shape::Mesh(mesh) => reach(&mut mesh.data.positions.iter().copied()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quoted_strings_and_entities_are_found_by_offset() {
        let s = "Entity(name: \"a\"), Entity(name: \"b\")";
        assert_eq!(find_quoted(s, "b", 0), Some(32));
        assert_eq!(find_quoted(s, "a", 15), None);
        assert_eq!(find_entity(s, 1), Some(19));
    }

    #[test]
    fn an_unchanged_file_is_read_once() {
        let dir = std::env::temp_dir().join(format!("rondo-cache-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let path = dir.join("t.obj");
        std::fs::write(&path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").expect("write");
        let mut cache = AssetCache::default();
        let a = cache.mesh(&path).expect("mesh");
        let b = cache.mesh(&path).expect("mesh");
        assert!(Arc::ptr_eq(&a, &b));
        assert_eq!(cache.mesh_loads(), 1);
        assert!(cache.mesh(&dir).is_err(), "a directory is not a mesh");
    }
}
