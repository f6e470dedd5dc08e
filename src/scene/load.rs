//! Reading a scene file: parse, validate names and references, load textures.

use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::SystemTime;

use crate::ecs::components::{Shape, Transform};
use crate::shading::material::Material;
use crate::shading::texture::{ImageTexture, Texture};

use super::error::{Location, SceneError};
use super::format::{CameraDesc, MaterialDesc, SceneDesc, SettingsDesc, TextureDesc};

/// One entity of a loaded scene, ready to become ECS components.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadedEntity {
    /// Unique name.
    pub name: String,
    /// Object-space shape.
    pub shape: Shape,
    /// Placement.
    pub transform: Transform,
    /// Material name (present in [`LoadedScene::materials`]).
    pub material: String,
}

/// A parsed, validated scene with its textures loaded.
#[derive(Clone, Debug)]
pub struct LoadedScene {
    /// The scene file.
    pub path: PathBuf,
    /// The camera.
    pub camera: CameraDesc,
    /// Settings.
    pub settings: SettingsDesc,
    /// Materials by name.
    pub materials: BTreeMap<String, Material>,
    /// Entities in file order.
    pub entities: Vec<LoadedEntity>,
    /// Every file the scene depends on (itself first, then textures).
    pub dependencies: Vec<PathBuf>,
}

struct CachedImage {
    stamp: (Option<SystemTime>, u64),
    texture: Arc<ImageTexture>,
}

/// Decoded image textures by path; a file is decoded again only when its modification time or
/// size changes, so an edit to one texture reloads that texture only.
#[derive(Default)]
pub struct TextureCache {
    images: HashMap<PathBuf, CachedImage>,
    decodes: u64,
}

impl TextureCache {
    /// Number of image decodes so far.
    pub fn decodes(&self) -> u64 {
        self.decodes
    }

    /// The texture at `path`, decoded now or taken from the cache.
    pub fn get(&mut self, path: &Path) -> Result<Arc<ImageTexture>, String> {
        let meta = std::fs::metadata(path).map_err(|e| format!("cannot read image: {e}"))?;
        if meta.is_dir() {
            return Err("image path is a directory".into());
        }
        let stamp = (meta.modified().ok(), meta.len());
        if let Some(cached) = self.images.get(path)
            && cached.stamp == stamp
        {
            return Ok(cached.texture.clone());
        }
        let image = image::ImageReader::open(path)
            .and_then(|r| r.with_guessed_format())
            .map_err(|e| format!("cannot read image: {e}"))?
            .decode()
            .map_err(|e| format!("cannot decode image: {e}"))?
            .into_rgb8();
        if image.width() == 0 || image.height() == 0 {
            return Err("image is empty".into());
        }
        let texture = Arc::new(ImageTexture::from_srgb8(
            image.width(),
            image.height(),
            image.as_raw(),
        ));
        self.decodes += 1;
        self.images.insert(
            path.to_path_buf(),
            CachedImage {
                stamp,
                texture: texture.clone(),
            },
        );
        Ok(texture)
    }
}

/// Parses scene source text. RON's `implicit_some` is on, so optional fields are written bare.
pub fn parse_scene(path: &Path, source: &str) -> Result<SceneDesc, SceneError> {
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

/// Reads, parses and validates the scene at `path`, loading its textures through `cache`.
pub fn load_scene(path: &Path, cache: &mut TextureCache) -> Result<LoadedScene, SceneError> {
    let source = std::fs::read_to_string(path)
        .map_err(|e| SceneError::at(path, None, format!("cannot read scene: {e}")))?;
    let desc = parse_scene(path, &source)?;
    let loc = |offset: Option<usize>| offset.map(|o| Location::of_offset(&source, o));
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut dependencies = vec![path.to_path_buf()];

    let mut materials = BTreeMap::new();
    for (name, m) in &desc.materials {
        let at = find_quoted(&source, name, 0);
        let mut texture = |t: &TextureDesc| {
            resolve_texture(t, dir, cache, &mut dependencies).map_err(|(p, msg)| {
                SceneError::at(
                    path,
                    loc(find_quoted(&source, &p, at.unwrap_or(0)).or(at)),
                    format!("material \"{name}\": {msg}"),
                )
            })
        };
        let material = match m {
            MaterialDesc::Diffuse { albedo } => Material::Diffuse {
                albedo: texture(albedo)?,
            },
            MaterialDesc::Metal { albedo, roughness } => Material::Metal {
                albedo: texture(albedo)?,
                roughness: roughness.0.clamp(0.0, 1.0),
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
        };
        materials.insert(name.clone(), material);
    }

    let mut names = HashSet::new();
    let mut entities = Vec::with_capacity(desc.entities.len());
    for (i, e) in desc.entities.iter().enumerate() {
        let name = e.name.clone().unwrap_or_else(|| format!("#{i}"));
        let at = match &e.name {
            Some(n) => find_quoted(&source, n, 0),
            None => find_entity(&source, i),
        };
        if names.contains(&name) {
            let again = match &e.name {
                Some(n) => at.and_then(|f| find_quoted(&source, n, f + 1)).or(at),
                None => at,
            };
            return Err(SceneError::at(
                path,
                loc(again),
                format!("duplicate entity name \"{name}\""),
            ));
        }
        if !materials.contains_key(&e.material) {
            let known: Vec<&str> = materials.keys().map(String::as_str).collect();
            let offset = at.and_then(|a| find_quoted(&source, &e.material, a)).or(at);
            return Err(SceneError::at(
                path,
                loc(offset),
                format!(
                    "entity \"{name}\": unknown material \"{}\" (defined: {})",
                    e.material,
                    known.join(", ")
                ),
            ));
        }
        let transform = e.transform.map(|t| t.0).unwrap_or_default();
        if matches!(e.shape.0, Shape::Sphere { .. }) && !transform.is_uniform() {
            return Err(SceneError::at(
                path,
                loc(at),
                format!(
                    "entity \"{name}\": a sphere cannot take a non-uniform scale ({})",
                    transform.scale
                ),
            ));
        }
        names.insert(name.clone());
        entities.push(LoadedEntity {
            name,
            shape: e.shape.0.clone(),
            transform,
            material: e.material.clone(),
        });
    }

    Ok(LoadedScene {
        path: path.to_path_buf(),
        camera: desc.camera,
        settings: desc.settings,
        materials,
        entities,
        dependencies,
    })
}

/// Builds a texture, loading image files relative to `dir`. Errors carry the offending path text.
fn resolve_texture(
    t: &TextureDesc,
    dir: &Path,
    cache: &mut TextureCache,
    dependencies: &mut Vec<PathBuf>,
) -> Result<Texture, (String, String)> {
    Ok(match t {
        TextureDesc::Constant(c) => Texture::Constant(c.0),
        TextureDesc::Checker { scale, even, odd } => Texture::Checker {
            scale: scale.0,
            even: Box::new(resolve_texture(even, dir, cache, dependencies)?),
            odd: Box::new(resolve_texture(odd, dir, cache, dependencies)?),
        },
        TextureDesc::Image { path } => {
            let full = dir.join(path);
            if !dependencies.contains(&full) {
                dependencies.push(full.clone());
            }
            let image = cache
                .get(&full)
                .map_err(|e| (path.clone(), format!("{}: {e}", full.display())))?;
            Texture::Image(image)
        }
    })
}
