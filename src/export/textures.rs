//! Which file each loaded image came from. A loaded [`Texture::Image`] holds decoded texels,
//! not its file, so each image file the scene depends on (and each image of its glTF files) is
//! decoded again here, both as sRGB-encoded colour and as linear data, and matched to the
//! loaded images by their texels: the loaded image's nearest lookup at every sampled texel
//! centre equals the candidate's texel. The match also tells how rondo decoded the file.
//! Images embedded in a glTF file are written into the export's directory under fixed names
//! (`texture-NNN.png`).

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Vec2, Vec3};

use super::ExportError;
use crate::scene::assets::AssetCache;
use crate::scene::bounded_read::{MAX_INPUT_BYTES, read_bounded};
use crate::scene::gltf_read::GltfImage;
use crate::scene::load::LoadedScene;
use crate::shading::material::Material;
use crate::shading::texture::{ImageTexture, Texture, srgb_to_linear};

/// An image's file and how rondo decoded its values.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ImageFile {
    /// Absolute path (the scene's own file, or one written into the export).
    pub path: PathBuf,
    /// `"srgb"`: 8- and 16-bit values are sRGB-encoded colour; `"linear"`: they are data (or
    /// the file holds floats).
    pub encoding: &'static str,
}

/// The files of the scene's images, by the identity of the decoded image.
#[derive(Default)]
pub struct ImageFiles {
    by_image: HashMap<usize, ImageFile>,
    /// Files written into the export (embedded images).
    pub written: Vec<PathBuf>,
}

const IMAGE_EXTENSIONS: &[&str] = &["png", "jpg", "jpeg", "hdr", "exr"];

/// Texel centres compared per axis at most (a grid over the image).
const PROBES: u32 = 48;

fn identity(image: &Arc<ImageTexture>) -> usize {
    Arc::as_ptr(image) as usize
}

/// A candidate file decoded: size and linear texels under each reading.
struct Candidate {
    path: PathBuf,
    /// Bytes to write into the export when the image is embedded.
    embedded: Option<Vec<u8>>,
    width: u32,
    height: u32,
    /// (encoding, texels row-major from the top row).
    readings: Vec<(&'static str, Vec<Vec3>)>,
}

impl Candidate {
    fn decode(path: PathBuf, bytes: &[u8], embedded: bool) -> Option<Self> {
        let image = image::load_from_memory(bytes).ok()?;
        let (width, height) = (image.width(), image.height());
        let float = matches!(
            image.color(),
            image::ColorType::Rgb32F | image::ColorType::Rgba32F
        );
        let readings = if float {
            let rgb = image.to_rgb32f();
            vec![(
                "linear",
                rgb.pixels().map(|p| Vec3::from_array(p.0)).collect(),
            )]
        } else {
            let rgb = image.to_rgb8();
            let raw: Vec<Vec3> = rgb
                .pixels()
                .map(|p| Vec3::from_array(p.0.map(f32::from)) / 255.0)
                .collect();
            let srgb = raw.iter().map(|c| c.map(srgb_to_linear)).collect();
            vec![("srgb", srgb), ("linear", raw)]
        };
        Some(Self {
            path,
            embedded: embedded.then(|| bytes.to_vec()),
            width,
            height,
            readings,
        })
    }

    /// The reading of this file that `loaded` holds, if any.
    fn matches(&self, loaded: &ImageTexture) -> Option<&'static str> {
        let (w, h) = (self.width, self.height);
        let step_x = w.div_ceil(PROBES).max(1);
        let step_y = h.div_ceil(PROBES).max(1);
        // The last column and row too: a loaded image of another size differs there.
        let xs: Vec<u32> = (0..w).step_by(step_x as usize).chain([w - 1]).collect();
        let ys: Vec<u32> = (0..h).step_by(step_y as usize).chain([h - 1]).collect();
        self.readings.iter().find_map(|(encoding, texels)| {
            let all = ys.iter().all(|&j| {
                xs.iter().all(|&i| {
                    let uv = Vec2::new(
                        (i as f32 + 0.5) / w as f32,
                        1.0 - (j as f32 + 0.5) / h as f32,
                    );
                    let want = texels[(j * w + i) as usize];
                    let got = loaded.lookup(uv);
                    // 16-bit files were read at 8 bits here.
                    (got - want).abs().max_element() <= 3e-3 * want.max_element().max(1.0)
                })
            });
            all.then_some(*encoding)
        })
    }
}

/// Every image a material reads.
fn material_images(materials: &[&Material]) -> Vec<Arc<ImageTexture>> {
    fn walk(t: &Texture, out: &mut Vec<Arc<ImageTexture>>) {
        match t {
            Texture::Constant(_) => {}
            Texture::Checker { even, odd, .. } => {
                walk(even, out);
                walk(odd, out);
            }
            Texture::Image(image, _) => out.push(image.clone()),
            Texture::Scaled(inner, _) | Texture::Mapped(inner, _) => walk(inner, out),
        }
    }
    fn images(m: &Material, out: &mut Vec<Arc<ImageTexture>>) {
        match m {
            Material::Diffuse { albedo }
            | Material::Metal { albedo, .. }
            | Material::Glossy { albedo, .. } => walk(albedo, out),
            Material::Dielectric { .. } => {}
            Material::Light { emit, .. } => walk(emit, out),
            Material::Pbr {
                base_color,
                metallic_roughness,
                emissive,
                normal_map,
                alpha,
                layer_maps,
                ..
            } => {
                walk(base_color, out);
                for (_, _, t) in layer_maps.iter().flat_map(|m| m.channels()) {
                    walk(&t, out);
                }
                walk(emissive, out);
                if let Some(t) = metallic_roughness {
                    walk(t, out);
                }
                if let Some(n) = normal_map {
                    walk(&n.texture, out);
                }
                if let Some((image, _)) = alpha.as_ref().and_then(|a| a.image.as_ref()) {
                    out.push(image.clone());
                }
            }
            Material::Transmissive {
                glass,
                base,
                texture,
                ..
            } => {
                images(glass, out);
                images(base, out);
                if let Some(t) = texture {
                    walk(&t.texture, out);
                    images(&t.opaque, out);
                }
            }
        }
    }
    let mut out = Vec::new();
    for m in materials {
        images(m, &mut out);
    }
    out
}

impl ImageFiles {
    /// Names the images of `scene` (loaded with `cache`), writing the embedded ones it uses
    /// into `dir`. An image that matches no file is an error naming its material's scene.
    pub fn find(
        scene: &LoadedScene,
        cache: &mut AssetCache,
        dir: &Path,
    ) -> Result<Self, ExportError> {
        let materials: Vec<&Material> = scene.materials.values().collect();
        let mut images = material_images(&materials);
        images.sort_by_key(identity);
        images.dedup_by_key(|i| identity(i));
        let mut files = Self::default();
        if images.is_empty() {
            return Ok(files);
        }
        let candidates = candidates(scene, cache)?;
        let absolute = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
        let mut embedded_paths: HashMap<usize, PathBuf> = HashMap::new();
        for image in &images {
            let found = candidates
                .iter()
                .enumerate()
                .find_map(|(k, c)| c.matches(image).map(|e| (k, c, e)));
            let Some((k, candidate, encoding)) = found else {
                return Err(ExportError(format!(
                    "{}: a texture matches none of the scene's image files",
                    scene.path.display()
                )));
            };
            let path = match &candidate.embedded {
                None => absolute(&candidate.path),
                Some(bytes) => match embedded_paths.get(&k) {
                    Some(p) => p.clone(),
                    None => {
                        let ext = candidate
                            .path
                            .extension()
                            .and_then(|e| e.to_str())
                            .unwrap_or("png");
                        let path = dir.join(format!("texture-{:03}.{ext}", embedded_paths.len()));
                        crate::output_file::write_bytes(&path, bytes)
                            .map_err(|e| ExportError(format!("{}: {e}", path.display())))?;
                        files.written.push(path.clone());
                        let path = absolute(&path);
                        embedded_paths.insert(k, path.clone());
                        path
                    }
                },
            };
            files
                .by_image
                .insert(identity(image), ImageFile { path, encoding });
        }
        Ok(files)
    }

    /// The file of a loaded image, if it came from one of the scene's files.
    pub fn file(&self, image: &Arc<ImageTexture>) -> Option<&ImageFile> {
        self.by_image.get(&identity(image))
    }
}

/// The image files the scene depends on, and the images of its glTF files.
fn candidates(scene: &LoadedScene, cache: &mut AssetCache) -> Result<Vec<Candidate>, ExportError> {
    let mut out = Vec::new();
    let read = |p: &Path| {
        read_bounded(p, MAX_INPUT_BYTES)
            .map(|(_, bytes)| bytes)
            .map_err(|e| ExportError(format!("{}: {e}", p.display())))
    };
    for dep in scene.dependencies.iter().skip(1) {
        let ext = dep
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .unwrap_or_default();
        if IMAGE_EXTENSIONS.contains(&ext.as_str()) {
            out.extend(Candidate::decode(dep.clone(), &read(dep)?, false));
        } else if ext == "gltf" || ext == "glb" {
            let asset = cache
                .gltf(dep)
                .map_err(|e| ExportError(format!("{}: {e}", dep.display())))?;
            let base = dep.parent().unwrap_or(Path::new(""));
            for image in &asset.scene.images {
                match image {
                    GltfImage::File(relative) => {
                        let path = base.join(relative);
                        out.extend(Candidate::decode(path.clone(), &read(&path)?, false));
                    }
                    GltfImage::Bytes { bytes, mime_type } => {
                        let name = if mime_type == "image/jpeg" {
                            "embedded.jpg"
                        } else {
                            "embedded.png"
                        };
                        out.extend(Candidate::decode(PathBuf::from(name), bytes, true));
                    }
                }
            }
        }
    }
    Ok(out)
}
