//! Decoded assets by path (images, meshes, environment maps), reused across loads while their
//! files' bytes are unchanged.

use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use super::bounded_read::{MAX_INPUT_BYTES, read_bounded};
use super::gltf_read::{GltfImage, GltfScene, read_gltf};
use crate::model::MeshData;
use crate::shading::texture::ImageTexture;
use crate::sky::EnvironmentMap;

struct Cached<T> {
    /// Hash of the file's bytes when it was loaded.
    hash: u64,
    value: Arc<T>,
}

/// Decoded images, meshes and environment maps by path. A file's bytes are decoded again only
/// when their hash differs from the cached one: content decides, not the modification time or
/// the size, which a `cp -p`, a build tool or a `git checkout` on a coarse-mtime file system can
/// leave unchanged for a different file. An edit to one texture or mesh decodes that file only.
///
/// Every load reads and hashes each file it asks for (once per load), unless the caller reports
/// file changes ([`AssetCache::set_reported_changes`], the watcher): then a file is read again
/// only after [`AssetCache::invalidate`] named it (or its symlink's target, or a directory
/// above either), or when its metadata (length, times, device and inode of the file a symlink
/// resolves to) changed since it was read.
#[derive(Default)]
pub struct AssetCache {
    images: HashMap<PathBuf, Cached<ImageTexture>>,
    linear_images: HashMap<PathBuf, Cached<ImageTexture>>,
    meshes: HashMap<PathBuf, Cached<MeshData>>,
    environments: HashMap<PathBuf, Cached<EnvironmentMap>>,
    gltfs: HashMap<PathBuf, CachedGltf>,
    /// The scene file's last good parse, for the next load to re-parse only what changed.
    parsed_scene: Option<super::incremental::ParsedScene>,
    files: Files,
    decodes: u64,
    mesh_loads: u64,
    environment_builds: u64,
    /// Every asset or prefab path asked for since [`AssetCache::begin_load`], found or not.
    requested: Vec<PathBuf>,
    /// The same paths, for O(1) membership (a scene can ask for 10⁵ files).
    requested_set: HashSet<PathBuf>,
    /// Texts that stand for files (canonical paths): an editor's unsaved prefab buffers.
    overlays: HashMap<PathBuf, Arc<str>>,
}

/// What identifies the content of a file without reading it: metadata of the file a path
/// resolves to (symlinks followed).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Stamp {
    len: u64,
    modified: Option<std::time::SystemTime>,
    #[cfg(unix)]
    unix: (u64, u64, i64, i64),
}

impl Stamp {
    fn of(meta: &std::fs::Metadata) -> Self {
        #[cfg(unix)]
        use std::os::unix::fs::MetadataExt;
        Self {
            len: meta.len(),
            modified: meta.modified().ok(),
            #[cfg(unix)]
            unix: (meta.dev(), meta.ino(), meta.ctime(), meta.ctime_nsec()),
        }
    }
}

/// A file as last read: its metadata then, the hash of its bytes, and whether a change was
/// reported since.
struct Record {
    stamp: Stamp,
    hash: u64,
    stale: bool,
}

/// The files read, for telling which must be read again.
#[derive(Default)]
struct Files {
    records: HashMap<PathBuf, Record>,
    /// Paths as the watcher names them (canonical parent directory joined with the name; for a
    /// symlink also its canonical target) → the paths the files were asked for by.
    keys: BTreeMap<PathBuf, HashSet<PathBuf>>,
    /// Whether changes are reported through [`AssetCache::invalidate`].
    reported: bool,
    /// Paths read during the current load (each is read once per load).
    this_load: HashSet<PathBuf>,
    bytes_read: u64,
}

/// The paths under which a watcher may report a change of `path`: its own path with the parent
/// directory made canonical, and its canonical path (which differs for a symlink).
fn change_keys(path: &Path) -> Vec<PathBuf> {
    let mut keys = Vec::with_capacity(2);
    if let Ok(absolute) = std::path::absolute(path) {
        if let (Some(parent), Some(name)) = (absolute.parent(), absolute.file_name())
            && let Ok(dir) = parent.canonicalize()
        {
            keys.push(dir.join(name));
        }
        keys.push(absolute);
    }
    if let Ok(target) = path.canonicalize()
        && !keys.contains(&target)
    {
        keys.push(target);
    }
    keys
}

impl Files {
    /// The hash of the bytes of `path`, and the bytes when they had to be read: a file is
    /// trusted without reading when it was read during this load, or when changes are reported,
    /// none was for it and its metadata is as when it was read.
    fn current(&mut self, path: &Path) -> Result<(u64, Option<Vec<u8>>), String> {
        if let Some(r) = self.records.get(path)
            && !r.stale
            && (self.this_load.contains(path)
                || (self.reported
                    && std::fs::metadata(path).is_ok_and(|m| Stamp::of(&m) == r.stamp)))
        {
            return Ok((r.hash, None));
        }
        let (hash, bytes) = self.read(path)?;
        Ok((hash, Some(bytes)))
    }

    /// Reads `path`, records its metadata and hash, and returns the hash and the bytes.
    fn read(&mut self, path: &Path) -> Result<(u64, Vec<u8>), String> {
        let (meta, bytes) =
            read_bounded(path, MAX_INPUT_BYTES).map_err(|e| format!("cannot read: {e}"))?;
        self.bytes_read += bytes.len() as u64;
        let hash = hash_bytes(&bytes);
        let record = Record {
            stamp: Stamp::of(&meta),
            hash,
            stale: false,
        };
        self.records.insert(path.to_path_buf(), record);
        // Again at every read: a symlink may point elsewhere now (the old keys stay, at worst
        // causing a needless read).
        for key in change_keys(path) {
            self.keys.entry(key).or_default().insert(path.to_path_buf());
        }
        self.this_load.insert(path.to_path_buf());
        Ok((hash, bytes))
    }

    /// Marks stale every file read under a path or directory in `changed`.
    fn invalidate(&mut self, changed: &[PathBuf]) {
        for path in changed {
            for key in change_keys(path).iter().chain([path]) {
                let under = self
                    .keys
                    .range::<PathBuf, _>(key..)
                    .take_while(|(k, _)| k.starts_with(key));
                for (_, paths) in under {
                    for p in paths {
                        if let Some(r) = self.records.get_mut(p) {
                            r.stale = true;
                        }
                    }
                }
            }
        }
    }
}

/// Refuses `path`, a glTF file's buffer or image below the file's folder `dir` (by its URI,
/// checked by [`super::gltf_read::relative_uri`]), when it resolves outside that folder through a
/// symlink. A path that does not resolve is left for the read to report (and for a watcher to
/// wait for).
pub fn inside_folder(dir: &Path, path: &Path) -> Result<(), String> {
    let dir = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    let (Ok(folder), Ok(target)) = (dir.canonicalize(), path.canonicalize()) else {
        return Ok(());
    };
    if target.starts_with(&folder) {
        Ok(())
    } else {
        Err(format!(
            "resolves to {}, outside the glTF file's folder {}",
            target.display(),
            folder.display()
        ))
    }
}

/// Hash of a file's bytes.
fn hash_bytes(bytes: &[u8]) -> u64 {
    use std::hash::Hasher;
    let mut hasher = std::hash::DefaultHasher::new();
    hasher.write(bytes);
    hasher.finish()
}

/// The cached value for `path`, or `load(bytes)` when the file is new or its bytes changed.
fn cached<T>(
    files: &mut Files,
    map: &mut HashMap<PathBuf, Cached<T>>,
    path: &Path,
    load: impl FnOnce(&[u8]) -> Result<T, String>,
) -> Result<(Arc<T>, bool), String> {
    let (hash, bytes) = files.current(path)?;
    if let Some(c) = map.get(path)
        && c.hash == hash
    {
        return Ok((c.value.clone(), false));
    }
    // Trusted but not decoded this way (the other encoding of an image): read it now.
    let (hash, bytes) = match bytes {
        Some(bytes) => (hash, bytes),
        None => files.read(path)?,
    };
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

/// An embedded image's bytes ([`super::gltf_read::SharedBytes::identity`]) and its encoding.
type EmbeddedKey = ((usize, usize, usize), Encoding);

/// A glTF file as read, with the external buffer files it was read from and its embedded
/// images, decoded when first asked for.
pub struct GltfAsset {
    /// The file's meshes, nodes, materials and images.
    pub scene: GltfScene,
    /// External buffer files and the hashes of their bytes when they were read.
    buffers: Vec<(PathBuf, u64)>,
    /// Embedded images decoded so far, by the identity of their bytes (images on one buffer
    /// view are decoded once) and encoding.
    embedded: Mutex<HashMap<EmbeddedKey, Arc<ImageTexture>>>,
}

impl GltfAsset {
    /// The external buffer files the file was read from.
    pub fn buffer_files(&self) -> impl Iterator<Item = &Path> {
        self.buffers.iter().map(|(p, _)| p.as_path())
    }

    /// Embedded image `index` (bytes in the file) decoded with `encoding`, once per asset.
    pub fn embedded_image(
        &self,
        index: usize,
        encoding: Encoding,
    ) -> Result<Arc<ImageTexture>, String> {
        let Some(GltfImage::Bytes { bytes, mime_type }) = self.scene.images.get(index) else {
            return Err(format!("image {index} is not embedded"));
        };
        let mut embedded = self
            .embedded
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let key = (bytes.identity(), encoding);
        if let Some(image) = embedded.get(&key) {
            return Ok(image.clone());
        }
        // The MIME type names the format; the content decides when it is unknown.
        let hint = match mime_type.as_str() {
            "image/png" => "embedded.png",
            "image/jpeg" => "embedded.jpg",
            _ => "embedded",
        };
        let image = Arc::new(
            decode_image(Path::new(hint), bytes, encoding)
                .map_err(|e| format!("image {index}: {e}"))?,
        );
        embedded.insert(key, image.clone());
        Ok(image)
    }
}

/// A cached glTF file: the hash of its own bytes (those of its buffers are in the asset).
struct CachedGltf {
    hash: u64,
    value: Arc<GltfAsset>,
}

impl AssetCache {
    /// Number of image decodes so far.
    pub fn decodes(&self) -> u64 {
        self.decodes
    }

    /// Number of mesh file loads so far (OBJ and glTF files).
    pub fn mesh_loads(&self) -> u64 {
        self.mesh_loads
    }

    /// Number of environment maps decoded and given their distribution so far.
    pub fn environment_builds(&self) -> u64 {
        self.environment_builds
    }

    /// The environment map at `path` with its sampling distribution, built now or taken from
    /// the cache (once per content of the file, not once per load of the scene).
    pub fn environment(&mut self, path: &Path) -> Result<Arc<EnvironmentMap>, String> {
        self.note(path);
        let (value, fresh) = cached(&mut self.files, &mut self.environments, path, |bytes| {
            decode_environment(path, bytes)
        })?;
        self.environment_builds += u64::from(fresh);
        Ok(value)
    }

    /// The environment map file `path` decoded from its `bytes` to its width, height and
    /// linear RGB floats, without its distribution: the first half of
    /// [`AssetCache::environment`], apart for `rondo bench environment`.
    pub fn decode_environment_pixels(
        path: &Path,
        bytes: &[u8],
    ) -> Result<(u32, u32, Vec<f32>), String> {
        decode_environment_pixels(path, bytes)
    }

    /// Reads each file of `overlays` (canonical paths) as the text given instead of from
    /// disk, replacing the overlays set before: the language server's unsaved prefab buffers.
    pub fn set_overlays(&mut self, overlays: HashMap<PathBuf, Arc<str>>) {
        self.overlays = overlays;
    }

    /// The text standing for the file at `canonical`, if one was set.
    pub fn overlay(&self, canonical: &Path) -> Option<&str> {
        self.overlays.get(canonical).map(|t| &**t)
    }

    /// Starts a scene load: forgets the paths asked for by the previous one.
    pub fn begin_load(&mut self) {
        self.requested.clear();
        self.requested_set.clear();
        self.files.this_load.clear();
    }

    /// Whether the caller reports every change to the files through [`AssetCache::invalidate`]
    /// (a watcher). Then a file is read again only when a change was reported for it or its
    /// metadata changed; otherwise (the default) every load reads each file it asks for once.
    pub fn set_reported_changes(&mut self, on: bool) {
        self.files.reported = on;
    }

    /// Reports that the files or directories at `changed` may have changed: every asset file
    /// at or under one of them (by its path with the parent directory made canonical, or by
    /// its canonical path: a symlink is also named by its target's) is read again when next
    /// asked for.
    pub fn invalidate(&mut self, changed: &[PathBuf]) {
        self.files.invalidate(changed);
    }

    /// Reports that any file may have changed (events were lost): every file is read again
    /// when next asked for.
    pub fn invalidate_all(&mut self) {
        for r in self.files.records.values_mut() {
            r.stale = true;
        }
    }

    /// Bytes of asset files read so far.
    pub fn bytes_read(&self) -> u64 {
        self.files.bytes_read
    }

    /// Records that the load asked for `path` (a texture, a mesh or a prefab), whether or not
    /// it exists: a failed load still tells a watcher which files could fix it.
    pub fn note(&mut self, path: &Path) {
        if !self.requested_set.contains(path) {
            self.requested_set.insert(path.to_path_buf());
            self.requested.push(path.to_path_buf());
        }
    }

    /// Every texture, mesh or prefab path asked for since [`AssetCache::begin_load`].
    pub fn requested(&self) -> &[PathBuf] {
        &self.requested
    }

    /// The texture at `path`, decoded now or taken from the cache: an 8- or 16-bit image as
    /// sRGB-encoded colour, a float image as linear.
    pub fn texture(&mut self, path: &Path) -> Result<Arc<ImageTexture>, String> {
        self.image(path, Encoding::Srgb)
    }

    /// The image at `path` decoded with `encoding`, now or from the cache (each encoding of a
    /// file is cached on its own).
    pub fn image(&mut self, path: &Path, encoding: Encoding) -> Result<Arc<ImageTexture>, String> {
        self.note(path);
        let map = match encoding {
            Encoding::Srgb => &mut self.images,
            Encoding::Linear => &mut self.linear_images,
        };
        let (value, fresh) = cached(&mut self.files, map, path, |bytes| {
            decode_image(path, bytes, encoding)
        })?;
        self.decodes += u64::from(fresh);
        Ok(value)
    }

    /// The glTF file at `path` (`.gltf` or `.glb`), read now with its external buffers or taken
    /// from the cache when neither its bytes nor its buffers' have changed. Its buffer files
    /// are noted as asked for (see [`AssetCache::note`]), read or not.
    pub fn gltf(&mut self, path: &Path) -> Result<Arc<GltfAsset>, String> {
        self.note(path);
        let fail = |e: String| format!("glTF {}: {e}", path.display());
        let (hash, bytes) = self.files.current(path).map_err(fail)?;
        // Buffers read while checking, not to be read twice.
        let mut read = HashMap::new();
        if let Some(c) = self.gltfs.get(path)
            && c.hash == hash
        {
            let value = c.value.clone();
            for (buffer, _) in &value.buffers {
                self.note(buffer);
            }
            let mut unchanged = true;
            for (p, h) in &value.buffers {
                match self.files.current(p) {
                    Ok((now, bytes)) => {
                        if let Some(bytes) = bytes {
                            read.insert(p.clone(), bytes);
                        }
                        if now != *h {
                            unchanged = false;
                            break;
                        }
                    }
                    Err(_) => {
                        unchanged = false;
                        break;
                    }
                }
            }
            if unchanged {
                return Ok(value);
            }
        }
        let (hash, bytes) = match bytes {
            Some(bytes) => (hash, bytes),
            None => self.files.read(path).map_err(fail)?,
        };
        let dir = path.parent().unwrap_or(Path::new(""));
        let mut buffers = Vec::new();
        let mut asked = Vec::new();
        let files = &mut self.files;
        let scene = read_gltf(path, Arc::new(bytes), |relative, max| {
            let full = dir.join(relative);
            asked.push(full.clone());
            inside_folder(dir, &full)?;
            // Checked before reading: the file's buffers together are bounded.
            if let Ok(meta) = std::fs::metadata(&full)
                && meta.len() > max
            {
                return Err(format!(
                    "is {} bytes, more than the {max} left for the file's buffers",
                    meta.len()
                ));
            }
            let (hash, bytes) = match (files.current(&full)?, read.remove(&full)) {
                ((hash, Some(bytes)), _) | ((hash, None), Some(bytes)) => (hash, bytes),
                ((_, None), None) => files.read(&full)?,
            };
            buffers.push((full, hash));
            Ok(bytes)
        });
        for p in &asked {
            self.note(p);
        }
        self.mesh_loads += 1;
        let value = Arc::new(GltfAsset {
            scene: scene?,
            buffers,
            embedded: Mutex::new(HashMap::new()),
        });
        self.gltfs.insert(
            path.to_path_buf(),
            CachedGltf {
                hash,
                value: value.clone(),
            },
        );
        Ok(value)
    }

    /// Takes the scene file's last good parse (see [`super::incremental`]), if kept.
    pub fn take_parsed_scene(&mut self) -> Option<super::incremental::ParsedScene> {
        self.parsed_scene.take()
    }

    /// Keeps a scene file's parse for the next load.
    pub fn keep_parsed_scene(&mut self, parsed: super::incremental::ParsedScene) {
        self.parsed_scene = Some(parsed);
    }

    /// The mesh at `path`, read now or taken from the cache.
    pub fn mesh(&mut self, path: &Path) -> Result<Arc<MeshData>, String> {
        self.note(path);
        let (value, fresh) = cached(
            &mut self.files,
            &mut self.meshes,
            path,
            super::mesh::parse_obj,
        )?;
        self.mesh_loads += u64::from(fresh);
        Ok(value)
    }
}

/// How the 8- and 16-bit channels of an image encode its values (float images are linear).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Encoding {
    /// Colour, sRGB-encoded (base colour, emission, RON `Image` textures).
    Srgb,
    /// Data, linear (normal maps, metallic–roughness).
    Linear,
}

/// Largest image accepted, in texels (16384²).
pub const MAX_IMAGE_TEXELS: u64 = 1 << 28;

/// Longest side of an image accepted, in texels (JPEG's own limit is 65535).
pub const MAX_IMAGE_SIDE: u32 = 1 << 16;

/// A reader of the image file `path` in `bytes`, its format from the content, else from the
/// extension.
fn image_reader<'a>(
    path: &Path,
    bytes: &'a [u8],
) -> Result<image::ImageReader<std::io::Cursor<&'a [u8]>>, String> {
    let mut reader = image::ImageReader::new(std::io::Cursor::new(bytes));
    if let Ok(format) = image::ImageFormat::from_path(path) {
        reader.set_format(format);
    }
    reader
        .with_guessed_format()
        .map_err(|e| format!("cannot read image: {e}"))
}

/// The decoder of `reader`'s image once its header has shown an image of at most `max_texels`
/// texels, no side longer than `max_side` and none empty: a file that declares more (a few
/// bytes can declare gigabytes of pixels) is refused before any of its pixels is allocated.
/// `max_alloc` bounds what the decoder itself allocates.
fn sized_decoder<'a>(
    mut reader: image::ImageReader<std::io::Cursor<&'a [u8]>>,
    max_texels: u64,
    max_side: u32,
    max_alloc: u64,
) -> Result<impl image::ImageDecoder + 'a, String> {
    use image::ImageDecoder;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(max_side);
    limits.max_image_height = Some(max_side);
    limits.max_alloc = Some(max_alloc);
    reader.limits(limits);
    let decoder = reader.into_decoder().map_err(|e| match e {
        image::ImageError::Limits(l)
            if l.kind() == image::error::LimitErrorKind::DimensionError =>
        {
            format!("the image is wider or taller than {max_side} texels")
        }
        e => format!("cannot read image: {e}"),
    })?;
    let (width, height) = decoder.dimensions();
    if width == 0 || height == 0 {
        return Err("image is empty".into());
    }
    if u64::from(width) * u64::from(height) > max_texels {
        return Err(format!(
            "the image has {width}×{height} texels; at most {max_texels} are accepted"
        ));
    }
    Ok(decoder)
}

/// Decodes the image file `path` from its `bytes` (the format from the content, else from the
/// extension), with `encoding`; alpha is kept if it is not opaque everywhere. Its size is
/// checked from its header, before decoding.
pub fn decode_image(path: &Path, bytes: &[u8], encoding: Encoding) -> Result<ImageTexture, String> {
    let decoder = sized_decoder(
        image_reader(path, bytes)?,
        MAX_IMAGE_TEXELS,
        MAX_IMAGE_SIDE,
        MAX_IMAGE_TEXELS * 16,
    )?;
    let decoded = image::DynamicImage::from_decoder(decoder)
        .map_err(|e| format!("cannot decode image: {e}"))?;
    let (width, height) = (decoded.width(), decoded.height());
    // Float images (EXR) hold linear values; 8/16-bit ones are encoded as `encoding` says.
    Ok(match decoded {
        image::DynamicImage::ImageRgb32F(_) | image::DynamicImage::ImageRgba32F(_) => {
            let linear = decoded.into_rgb32f();
            ImageTexture::from_linear(width, height, linear.as_raw())
        }
        other if other.color().has_alpha() => {
            let rgba = other.into_rgba8();
            ImageTexture::from_rgba8(width, height, rgba.as_raw(), encoding == Encoding::Srgb)
        }
        other => {
            let rgb = other.into_rgb8();
            match encoding {
                Encoding::Srgb => ImageTexture::from_srgb8(width, height, rgb.as_raw()),
                Encoding::Linear => {
                    let floats: Vec<f32> =
                        rgb.as_raw().iter().map(|&v| f32::from(v) / 255.0).collect();
                    ImageTexture::from_linear(width, height, &floats)
                }
            }
        }
    })
}

/// Decodes the environment map `path` (OpenEXR or Radiance `.hdr`, linear radiance) from its
/// `bytes` and builds its distribution.
fn decode_environment(path: &Path, bytes: &[u8]) -> Result<EnvironmentMap, String> {
    let (width, height, pixels) = decode_environment_pixels(path, bytes)?;
    EnvironmentMap::from_linear_vec(width, height, pixels)
}

/// Most texels a byte of a Radiance `.hdr` file can stand for: a run-length encoded scanline
/// spends at least 2 bytes per run of up to 127 equal values in each of its 4 components, so a
/// scanline of `w` texels takes at least 8w/127 bytes (about 16 texels a byte). A file declaring
/// more for its length is truncated, and is refused before its pixels are allocated (the
/// decoder allocates them all first). Files in the obsolete repeat-count encoding that packs
/// more are refused too.
const HDR_TEXELS_PER_BYTE: u64 = 32;

/// Decodes the environment map `path` from its `bytes` to its width, height and linear RGB
/// floats (row-major from the top row). A map of more than
/// [`crate::sky::environment::MAX_TEXELS`] texels is refused from its header, before any of its
/// pixels is allocated.
fn decode_environment_pixels(path: &Path, bytes: &[u8]) -> Result<(u32, u32, Vec<f32>), String> {
    use crate::sky::environment::MAX_TEXELS;
    let reader = image_reader(path, bytes)?;
    match reader.format() {
        Some(image::ImageFormat::OpenExr) => return decode_exr_rgb(bytes),
        Some(image::ImageFormat::Hdr) => {}
        _ => return Err("an environment map must be an OpenEXR or Radiance .hdr file".into()),
    }
    // RGB f32, plus the decoder's own buffer.
    let decoder = sized_decoder(reader, MAX_TEXELS, 1 << 15, MAX_TEXELS * 28)?;
    let (width, height) = image::ImageDecoder::dimensions(&decoder);
    let texels = u64::from(width) * u64::from(height);
    if texels > HDR_TEXELS_PER_BYTE * bytes.len() as u64 {
        return Err(format!(
            "the header declares {width}×{height} texels, more than {len} bytes of run-length \
             encoded scanlines can hold (at most {HDR_TEXELS_PER_BYTE} texels a byte): the file \
             is truncated",
            len = bytes.len()
        ));
    }
    let decoded = image::DynamicImage::from_decoder(decoder)
        .map_err(|e| format!("cannot decode image: {e}"))?;
    Ok((
        decoded.width(),
        decoded.height(),
        decoded.into_rgb32f().into_raw(),
    ))
}

/// Decodes an OpenEXR file's first layer with R, G and B channels straight into RGB floats,
/// row-major from the top row of its data window: the `image` crate first fills the `exr`
/// crate's RGBA buffer and then copies it into its own (100 MB and a tenth of a second more for
/// a 4096 × 2048 map). A layer of more than [`crate::sky::environment::MAX_TEXELS`] texels is
/// refused before its pixels are allocated.
fn decode_exr_rgb(bytes: &[u8]) -> Result<(u32, u32, Vec<f32>), String> {
    use crate::sky::environment::MAX_TEXELS;
    use exr::prelude::{ReadChannels, ReadLayers, RgbaChannels, Vec2, read};
    /// The pixels being read, or `None` for a layer too large to hold.
    struct Rgb {
        width: usize,
        floats: Option<Vec<f32>>,
    }
    let read = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |size: Vec2<usize>, _: &RgbaChannels| {
                let texels = size.0 as u64 * size.1 as u64;
                Rgb {
                    width: size.0,
                    floats: (texels <= MAX_TEXELS).then(|| vec![0.0; 3 * texels as usize]),
                }
            },
            |rgb: &mut Rgb, at: Vec2<usize>, (r, g, b, _): (f32, f32, f32, f32)| {
                if let Some(floats) = &mut rgb.floats {
                    let i = 3 * (at.1 * rgb.width + at.0);
                    floats[i..i + 3].copy_from_slice(&[r, g, b]);
                }
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes));
    let image = read.map_err(|e| match e {
        exr::error::Error::Invalid(why) if why.starts_with("no layer") => {
            "the OpenEXR file has no layer with R, G and B channels".to_string()
        }
        e => format!("cannot decode image: {e}"),
    })?;
    let size = image.layer_data.size;
    let (width, height) = (size.0 as u32, size.1 as u32);
    match image.layer_data.channel_data.pixels.floats {
        Some(floats) => Ok((width, height, floats)),
        None => Err(format!(
            "the map has {width}×{height} texels; at most {MAX_TEXELS} are accepted"
        )),
    }
}
