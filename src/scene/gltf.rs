//! glTF 2.0 files (`.gltf` and `.glb`) read into plain data: one [`MeshData`] per primitive, the
//! default scene's nodes with composed transforms, and the metallic–roughness materials. Nothing
//! here knows the ECS or the scene format; the scene loader places the result.
//!
//! The `gltf` crate parses and validates the JSON (every index in range); the GLB container,
//! buffers (data URIs, external files through the caller) and accessors (strides, normalised
//! integers, sparse substitution) are read here, each bounded by the data it reads before it
//! allocates, so a hostile file is an error, never a panic. Each buffer source (the `.glb`'s
//! binary chunk, for buffer 0 only; a data URI; an external file) is held once, however many
//! buffers and images name it, and all of them together are bounded by [`MAX_BUFFER_BYTES`].
//!
//! Supported: triangles (indexed or not; strips and fans converted), `POSITION`, `NORMAL` (flat
//! shading when absent: [`MeshData::normals`] is `None`), `TEXCOORD_0` (float or normalised
//! integers; stored as `(u, 1 − v)`, rondo's v pointing up the image), sparse accessors,
//! accessors without a buffer view (zeros), TRS and matrix node transforms, the
//! metallic–roughness material with its textures, `KHR_materials_emissive_strength`,
//! `KHR_materials_transmission`, `KHR_materials_ior` and `KHR_mesh_quantization`. Skipped with a
//! warning: points and lines, morph targets, skins, cameras, punctual lights. Ignored:
//! animations, vertex colours, tangents (normal maps derive them from texture coordinates). Any
//! other extension listed in `extensionsRequired` is an error naming it.

use std::collections::HashMap;
use std::ops::{Range, RangeInclusive};
use std::path::Path;
use std::sync::Arc;

use glam::{Affine3A, Mat3A, Mat4, Quat, Vec2, Vec3, Vec3A};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;

use crate::model::MeshData;

/// Most triangles (all primitives together) one file may produce.
pub const MAX_TRIANGLES: usize = 1 << 26;
/// Most vertices (all primitives together) one file may produce.
pub const MAX_VERTICES: usize = 1 << 26;
/// Most elements of an accessor without a buffer view (zeros, perhaps with sparse values): such
/// an accessor costs nothing in the file, so its size is bounded on its own.
pub const MAX_ZERO_FILLED: usize = 1 << 22;
/// Most node instances listed for the default scene (a node reached through several parents
/// counts once per path).
pub const MAX_NODE_INSTANCES: usize = 1 << 20;
/// Deepest node hierarchy followed (deeper nodes, and cycles, are an error).
pub const MAX_NODE_DEPTH: usize = 256;

/// Extensions that may appear in `extensionsRequired`.
const SUPPORTED_REQUIRED: &[&str] = &[
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_transmission",
    "KHR_mesh_quantization",
];

/// A glTF file read into plain data.
#[derive(Debug, Default)]
pub struct GltfScene {
    /// The file's meshes, in file order (indexed by [`GltfNode::mesh`]).
    pub meshes: Vec<GltfMesh>,
    /// The nodes of the default scene (or of the first scene if none is marked default), in
    /// depth-first order. A node reached twice is listed twice.
    pub nodes: Vec<GltfNode>,
    /// The file's materials, in file order (indexed by [`GltfPrimitive::material`]).
    pub materials: Vec<GltfMaterial>,
    /// The file's images, in file order (indexed by [`GltfTexture::image`]).
    pub images: Vec<GltfImage>,
    /// What was skipped or ignored, one sentence each.
    pub warnings: Vec<String>,
    /// Bytes held by the file's buffers (each source once), at most [`MAX_BUFFER_BYTES`].
    pub held_bytes: u64,
}

/// A glTF mesh: its triangle primitives (points and lines are left out).
#[derive(Debug)]
pub struct GltfMesh {
    /// The mesh's name in the file.
    pub name: Option<String>,
    /// Its triangle primitives. Each is its own [`MeshData`], shared (and instanced) by every
    /// node that uses the mesh.
    pub primitives: Vec<GltfPrimitive>,
}

/// One triangle primitive of a mesh.
#[derive(Debug)]
pub struct GltfPrimitive {
    /// Its geometry, in the mesh's object space.
    pub data: Arc<MeshData>,
    /// Index into [`GltfScene::materials`]; `None` for the glTF default material.
    pub material: Option<usize>,
}

/// A node of the default scene.
#[derive(Debug, Clone)]
pub struct GltfNode {
    /// The node's index in the file (for names of unnamed nodes).
    pub index: usize,
    /// The node's name in the file.
    pub name: Option<String>,
    /// Object to file space: the node's transform composed with its ancestors'.
    pub world_from_node: Affine3A,
    /// Index into [`GltfScene::meshes`].
    pub mesh: Option<usize>,
}

/// How a material's alpha is used.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AlphaMode {
    /// Alpha is ignored.
    Opaque,
    /// Rays pass where alpha is below the cutoff.
    Mask(f32),
    /// Blended transparency.
    Blend,
}

/// A texture coordinate wrap mode of a sampler.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wrap {
    /// Repeat (the default).
    Repeat,
    /// Repeat, mirrored every other time.
    MirroredRepeat,
    /// Clamp to the edge texel.
    ClampToEdge,
}

/// A material's reference to a texture.
#[derive(Debug, Clone, PartialEq)]
pub struct GltfTexture {
    /// Index into [`GltfScene::images`].
    pub image: usize,
    /// Which `TEXCOORD_n` set it uses (only set 0 is read).
    pub texcoord: u32,
    /// Wrap mode along u.
    pub wrap_s: Wrap,
    /// Wrap mode along v.
    pub wrap_t: Wrap,
    /// Whether magnification is nearest-texel (`NEAREST`); linear otherwise.
    pub nearest: bool,
}

/// An image referenced by a texture.
#[derive(Debug, Clone, PartialEq)]
pub enum GltfImage {
    /// A file, as a path relative to the glTF file's directory (percent-decoded; checked by
    /// [`relative_uri`]).
    File(String),
    /// Image bytes held in the file (a buffer view or a data URI), with their MIME type.
    Bytes {
        /// The encoded image, shared with the buffer that holds it.
        bytes: SharedBytes,
        /// Its MIME type, e.g. `image/png`.
        mime_type: String,
    },
}

/// A metallic–roughness material as the file gives it.
#[derive(Debug, Clone, PartialEq)]
pub struct GltfMaterial {
    /// The material's name in the file.
    pub name: Option<String>,
    /// Linear RGBA base colour factor.
    pub base_color_factor: [f32; 4],
    /// Base colour texture (sRGB).
    pub base_color_texture: Option<GltfTexture>,
    /// Metallic factor.
    pub metallic: f32,
    /// Perceptual roughness factor.
    pub roughness: f32,
    /// Metallic (B) and roughness (G) texture (linear).
    pub metallic_roughness_texture: Option<GltfTexture>,
    /// Normal map (linear) and its scale.
    pub normal_texture: Option<(GltfTexture, f32)>,
    /// Emitted radiance: the emissive factor × `KHR_materials_emissive_strength`.
    pub emissive: Vec3,
    /// Emissive texture (sRGB).
    pub emissive_texture: Option<GltfTexture>,
    /// Alpha mode.
    pub alpha_mode: AlphaMode,
    /// Whether back faces are shaded as front faces.
    pub double_sided: bool,
    /// `KHR_materials_transmission`'s factor (0 without the extension).
    pub transmission: f32,
    /// Whether the transmission factor is multiplied by a texture.
    pub transmission_texture: bool,
    /// Index of refraction (`KHR_materials_ior`; 1.5 without it).
    pub ior: f32,
}

/// Most bytes the buffers of one file may hold: its `.glb` binary chunk, its decoded data URIs
/// and its external buffer files, each source counted once however many buffers or images name
/// it (the file itself is bounded by the asset reader).
pub const MAX_BUFFER_BYTES: u64 = 1 << 30;

/// Bytes of a glTF file's buffers: a range of one shared allocation, so that a source named by
/// several buffers, and the images held in their views, are held once.
#[derive(Clone, Debug)]
pub struct SharedBytes {
    data: Arc<Vec<u8>>,
    range: Range<usize>,
}

impl SharedBytes {
    /// All of `data`.
    fn whole(data: Arc<Vec<u8>>) -> Self {
        let range = 0..data.len();
        Self { data, range }
    }

    /// The part `range` (relative to these bytes), if inside them.
    fn slice(&self, range: Range<usize>) -> Option<Self> {
        let start = self.range.start.checked_add(range.start)?;
        let end = self.range.start.checked_add(range.end)?;
        (start <= end && end <= self.range.end).then(|| Self {
            data: self.data.clone(),
            range: start..end,
        })
    }

    /// The size of the allocation these bytes keep alive (they may be a part of it).
    pub fn allocation_len(&self) -> usize {
        self.data.len()
    }

    /// What identifies these bytes without reading them: the allocation and the range in it
    /// (two images on one buffer view have the same identity).
    pub fn identity(&self) -> (usize, usize, usize) {
        (
            Arc::as_ptr(&self.data) as usize,
            self.range.start,
            self.range.end,
        )
    }
}

impl std::ops::Deref for SharedBytes {
    type Target = [u8];

    fn deref(&self) -> &[u8] {
        &self.data[self.range.clone()]
    }
}

impl PartialEq for SharedBytes {
    fn eq(&self, other: &Self) -> bool {
        **self == **other
    }
}

/// Reads a glTF file from its `bytes` (`.gltf` JSON or `.glb`); `path` names it in errors.
/// External buffers are fetched by `load_buffer` with a URI relative to the file's directory,
/// already checked by [`relative_uri`] (no absolute paths, no `..`, no other schemes), and the
/// most bytes the file may have (what is left of [`MAX_BUFFER_BYTES`]): a larger file must be
/// refused before it is read. Each distinct URI is fetched once.
pub fn read_gltf(
    path: &Path,
    bytes: Arc<Vec<u8>>,
    load_buffer: impl FnMut(&str, u64) -> Result<Vec<u8>, String>,
) -> Result<GltfScene, String> {
    read_gltf_within(path, bytes, MAX_BUFFER_BYTES, load_buffer)
}

/// [`read_gltf`] with `max_bytes` in place of [`MAX_BUFFER_BYTES`].
pub fn read_gltf_within(
    path: &Path,
    bytes: Arc<Vec<u8>>,
    max_bytes: u64,
    load_buffer: impl FnMut(&str, u64) -> Result<Vec<u8>, String>,
) -> Result<GltfScene, String> {
    read(bytes, max_bytes, load_buffer).map_err(|e| format!("glTF {}: {e}", path.display()))
}

/// The file's buffers, each source read once and counted against `max_bytes`: the binary
/// chunk (for buffer 0 only, as the spec says), data URIs and external files.
fn read_buffers(
    doc: &gltf::Document,
    file: &SharedBytes,
    blob: Option<Range<usize>>,
    max_bytes: u64,
    mut load_buffer: impl FnMut(&str, u64) -> Result<Vec<u8>, String>,
) -> Result<(Vec<SharedBytes>, u64), String> {
    let mut left = max_bytes;
    let take = |i: usize, n: usize, left: &mut u64| {
        *left = left.checked_sub(n as u64).ok_or_else(|| {
            format!("buffer {i}: the file's buffers hold more than {max_bytes} bytes")
        })?;
        Ok::<(), String>(())
    };
    let mut files: HashMap<String, SharedBytes> = HashMap::new();
    let mut buffers = Vec::new();
    for buffer in doc.buffers() {
        let i = buffer.index();
        let data = match buffer.source() {
            gltf::buffer::Source::Bin if i > 0 => {
                return Err(format!(
                    "buffer {i}: only buffer 0 may use the .glb's binary chunk"
                ));
            }
            gltf::buffer::Source::Bin => {
                let range = blob
                    .clone()
                    .ok_or_else(|| format!("buffer {i}: no binary chunk"))?;
                take(i, range.len(), &mut left)?;
                file.slice(range)
                    .ok_or("the binary chunk is outside the file")?
            }
            gltf::buffer::Source::Uri(uri) => match decode_data_uri(uri) {
                // Decoded before it is counted: it is smaller than its text, which the file holds.
                Some(r) => {
                    let (bytes, _) = r.map_err(|e| format!("buffer {i}: {e}"))?;
                    take(i, bytes.len(), &mut left)?;
                    SharedBytes::whole(Arc::new(bytes))
                }
                None => {
                    let rel = relative_uri(uri).map_err(|e| format!("buffer {i}: {e}"))?;
                    match files.get(&rel) {
                        Some(shared) => shared.clone(),
                        None => {
                            let bytes = load_buffer(&rel, left)
                                .map_err(|e| format!("buffer {i} ({rel}): {e}"))?;
                            take(i, bytes.len(), &mut left)?;
                            let shared = SharedBytes::whole(Arc::new(bytes));
                            files.insert(rel, shared.clone());
                            shared
                        }
                    }
                }
            },
        };
        if data.len() < buffer.length() {
            return Err(format!(
                "buffer {i}: {} bytes, shorter than its byteLength {}",
                data.len(),
                buffer.length()
            ));
        }
        buffers.push(data);
    }
    Ok((buffers, max_bytes - left))
}

fn read(
    bytes: Arc<Vec<u8>>,
    max_bytes: u64,
    load_buffer: impl FnMut(&str, u64) -> Result<Vec<u8>, String>,
) -> Result<GltfScene, String> {
    let file = SharedBytes::whole(bytes);
    let (json, blob) = if file.starts_with(b"glTF") {
        split_glb(&file)?
    } else {
        (0..file.len(), None)
    };
    let gltf = gltf::Gltf::from_slice_without_validation(&file[json])
        .map_err(|e| format!("invalid JSON: {e}"))?;
    let doc = &gltf.document;
    if let Some(ext) = doc
        .extensions_required()
        .find(|e| !SUPPORTED_REQUIRED.contains(e))
    {
        return Err(format!("unsupported required extension {ext}"));
    }
    validate(doc)?;
    let (buffers, held_bytes) = read_buffers(doc, &file, blob, max_bytes, load_buffer)?;

    let mut scene = GltfScene {
        held_bytes,
        ..GltfScene::default()
    };
    let mut budget = Budget {
        vertices: MAX_VERTICES,
        triangles: MAX_TRIANGLES,
    };
    for mesh in doc.meshes() {
        let mut primitives = Vec::new();
        for prim in mesh.primitives() {
            let what = format!("mesh {} primitive {}", mesh.index(), prim.index());
            match prim.mode() {
                Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip => {
                    scene
                        .warnings
                        .push(format!("{what}: points and lines are skipped"));
                    continue;
                }
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan => {}
            }
            if prim.morph_targets().next().is_some() {
                scene
                    .warnings
                    .push(format!("{what}: morph targets are ignored"));
            }
            let data =
                read_primitive(&prim, &buffers, &mut budget).map_err(|e| format!("{what}: {e}"))?;
            primitives.push(GltfPrimitive {
                data: Arc::new(data),
                material: prim.material().index(),
            });
        }
        scene.meshes.push(GltfMesh {
            name: mesh.name().map(str::to_owned),
            primitives,
        });
    }
    // Read from the JSON: the crate's `Image::source` unwraps a missing `mimeType` or `uri`.
    let views: Vec<gltf::buffer::View> = doc.views().collect();
    for (i, image) in doc.as_json().images.iter().enumerate() {
        let mime_type = image.mime_type.as_ref().map(|m| m.0.clone());
        scene.images.push(match (&image.buffer_view, &image.uri) {
            (Some(view), _) => {
                let view = views.get(view.value()).ok_or_else(|| {
                    format!("image {i}: buffer view {} does not exist", view.value())
                })?;
                GltfImage::Bytes {
                    bytes: view_shared(view, &buffers).map_err(|e| format!("image {i}: {e}"))?,
                    mime_type: mime_type.unwrap_or_default(),
                }
            }
            (None, Some(uri)) => match decode_data_uri(uri) {
                Some(r) => {
                    let (bytes, mime) = r.map_err(|e| format!("image {i}: {e}"))?;
                    GltfImage::Bytes {
                        bytes: SharedBytes::whole(Arc::new(bytes)),
                        mime_type: mime_type.unwrap_or(mime),
                    }
                }
                None => GltfImage::File(relative_uri(uri).map_err(|e| format!("image {i}: {e}"))?),
            },
            (None, None) => return Err(format!("image {i}: neither a uri nor a bufferView")),
        });
    }
    detach_images(&mut scene.images);
    for m in doc.materials() {
        scene.materials.push(read_material(&m)?);
    }
    if doc.cameras().next().is_some() {
        scene
            .warnings
            .push("cameras are ignored (the scene's camera is used)".into());
    }
    for ext in doc.extensions_used() {
        if !SUPPORTED_REQUIRED.contains(&ext) {
            scene.warnings.push(match ext {
                "KHR_lights_punctual" => "punctual lights (KHR_lights_punctual) are ignored".into(),
                other => format!("extension {other} is ignored"),
            });
        }
    }
    let roots = doc.default_scene().or_else(|| doc.scenes().next());
    if let Some(root) = roots {
        for node in root.nodes() {
            walk(&node, Affine3A::IDENTITY, 0, &mut scene)?;
        }
    }
    Ok(scene)
}

/// Copies out, once per buffer, the span that its images' views cover (at most the buffer), and
/// points the images into it: images outlive the read, the rest of a buffer (mesh data, decoded
/// by then, and a `.glb`'s JSON) is not held with them.
fn detach_images(images: &mut [GltfImage]) {
    let mut spans: HashMap<usize, Range<usize>> = HashMap::new();
    for image in images.iter() {
        if let GltfImage::Bytes { bytes, .. } = image {
            let span = spans
                .entry(Arc::as_ptr(&bytes.data) as usize)
                .or_insert(bytes.range.clone());
            *span = span.start.min(bytes.range.start)..span.end.max(bytes.range.end);
        }
    }
    let mut copies: HashMap<usize, SharedBytes> = HashMap::new();
    for image in images.iter_mut() {
        if let GltfImage::Bytes { bytes, .. } = image {
            let id = Arc::as_ptr(&bytes.data) as usize;
            let span = spans[&id].clone();
            if span.len() == bytes.data.len() {
                continue;
            }
            let copy = copies
                .entry(id)
                .or_insert_with(|| SharedBytes::whole(Arc::new(bytes.data[span.clone()].to_vec())));
            let start = bytes.range.start - span.start;
            *bytes = SharedBytes {
                data: copy.data.clone(),
                range: start..start + bytes.range.len(),
            };
        }
    }
}

/// Validates the document with the `gltf` crate (so that its accessors never index out of
/// range), ignoring only its complaint about required extensions rondo supports itself.
fn validate(doc: &gltf::Document) -> Result<(), String> {
    use gltf::json::validation::{Error, Validate};
    let root = doc.as_json();
    // gltf-json 1.4's validation indexes the accessors with a primitive's POSITION unchecked
    // (a panic when it is out of range): check those first.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            for (semantic, index) in &prim.attributes {
                if index.value() >= root.accessors.len() {
                    return Err(format!(
                        "mesh {m} primitive {p}: {semantic:?} accessor {} does not exist",
                        index.value()
                    ));
                }
            }
        }
    }
    let mut errors = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |path, error| {
        let path = path().to_string();
        // Required by the spec for POSITION but unused here (bounds are computed from the
        // data): files without them are read.
        let bounds = path.ends_with(".min") || path.ends_with(".max");
        let required =
            matches!(error, Error::Unsupported) && path.starts_with("extensionsRequired");
        if !(bounds || required) {
            errors.push(format!("{path}: {error}"));
        }
    });
    match errors.first() {
        None => Ok(()),
        Some(first) => Err(format!(
            "invalid: {first}{}",
            if errors.len() > 1 {
                format!(" (and {} more errors)", errors.len() - 1)
            } else {
                String::new()
            }
        )),
    }
}

/// Splits a `.glb` into the ranges of its JSON chunk and of its binary chunk, if any.
fn split_glb(bytes: &[u8]) -> Result<(Range<usize>, Option<Range<usize>>), String> {
    let word = |at: usize| -> Option<u32> {
        let b = bytes.get(at..at.checked_add(4)?)?;
        Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let truncated = || "truncated .glb".to_string();
    let version = word(4).ok_or_else(truncated)?;
    if version != 2 {
        return Err(format!(".glb version {version}, only 2 is read"));
    }
    let length = word(8).ok_or_else(truncated)? as usize;
    if length > bytes.len() {
        return Err(format!("truncated .glb: {} bytes of {length}", bytes.len()));
    }
    let chunk = |at: usize| -> Result<(u32, Range<usize>, usize), String> {
        let len = word(at).ok_or_else(truncated)? as usize;
        let kind = word(at + 4).ok_or_else(truncated)?;
        let start = at + 8;
        let end = start
            .checked_add(len)
            .filter(|&e| e <= length)
            .ok_or_else(truncated)?;
        Ok((kind, start..end, end.next_multiple_of(4)))
    };
    let (kind, json, next) = chunk(12)?;
    if kind != 0x4E4F_534A {
        return Err(".glb: the first chunk is not JSON".into());
    }
    let bin = if next + 8 <= length {
        let (kind, bin, _) = chunk(next)?;
        (kind == 0x004E_4942).then_some(bin)
    } else {
        None
    };
    Ok((json, bin))
}

/// Decodes a `data:` URI (base64 only): `None` if `uri` is not one, else its bytes and MIME type.
fn decode_data_uri(uri: &str) -> Option<Result<(Vec<u8>, String), String>> {
    let rest = uri.strip_prefix("data:")?;
    Some((|| {
        let (head, data) = rest.split_once(',').ok_or("data URI without a comma")?;
        let mime = head
            .strip_suffix(";base64")
            .ok_or("data URI not in base64")?;
        Ok((base64(data)?, mime.to_owned()))
    })())
}

/// Decodes standard base64 (padding optional).
fn base64(text: &str) -> Result<Vec<u8>, String> {
    let digit = |c: u8| -> Result<u32, String> {
        Ok(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            _ => return Err(format!("invalid base64 character {:?}", c as char)),
        }
        .into())
    };
    let text = text.trim_end_matches('=').as_bytes();
    let mut out = Vec::with_capacity(text.len() / 4 * 3 + 3);
    for group in text.chunks(4) {
        let mut n = 0u32;
        for (k, &c) in group.iter().enumerate() {
            n |= digit(c)? << (18 - 6 * k);
        }
        let bytes = n.to_be_bytes();
        match group.len() {
            1 => return Err("truncated base64".into()),
            len => out.extend_from_slice(&bytes[1..len]),
        }
    }
    Ok(out)
}

/// A URI of an external buffer or image as a relative path below the glTF file's directory:
/// percent-decoded; absolute paths, other schemes, backslashes and `..` components are errors.
pub fn relative_uri(uri: &str) -> Result<String, String> {
    let mut bytes = Vec::with_capacity(uri.len());
    let mut it = uri.bytes();
    while let Some(b) = it.next() {
        if b == b'%' {
            let hex = [it.next(), it.next()];
            let v = match hex {
                [Some(h), Some(l)] => std::str::from_utf8(&[h, l])
                    .ok()
                    .and_then(|s| u8::from_str_radix(s, 16).ok()),
                _ => None,
            };
            bytes.push(v.ok_or_else(|| format!("bad percent escape in URI {uri:?}"))?);
        } else {
            bytes.push(b);
        }
    }
    let path = String::from_utf8(bytes).map_err(|_| format!("URI {uri:?} is not UTF-8"))?;
    let bad = path.is_empty()
        || path.starts_with('/')
        || path.contains('\\')
        || path.contains(':')
        || path.split('/').any(|c| c == "..");
    if bad {
        return Err(format!(
            "URI {uri:?} is not a relative path below the file's directory"
        ));
    }
    Ok(path)
}

/// The bytes of a buffer view, checked against its buffer.
fn view_bytes<'b>(
    view: &gltf::buffer::View,
    buffers: &'b [SharedBytes],
) -> Result<&'b [u8], String> {
    let buffer = buffers.get(view.buffer().index()).ok_or("missing buffer")?;
    view.offset()
        .checked_add(view.length())
        .and_then(|end| buffer.get(view.offset()..end))
        .ok_or_else(|| format!("buffer view {} outside its buffer", view.index()))
}

/// The bytes of a buffer view, shared with its buffer.
fn view_shared(view: &gltf::buffer::View, buffers: &[SharedBytes]) -> Result<SharedBytes, String> {
    let buffer = buffers.get(view.buffer().index()).ok_or("missing buffer")?;
    view.offset()
        .checked_add(view.length())
        .and_then(|end| buffer.slice(view.offset()..end))
        .ok_or_else(|| format!("buffer view {} outside its buffer", view.index()))
}

/// The distance between elements of `size` bytes in `view`: its `byteStride`, which may not be
/// smaller than an element (elements would overlap), or the size when it has none.
fn stride(view: &gltf::buffer::View, size: usize) -> Result<usize, String> {
    match view.stride() {
        None => Ok(size),
        Some(stride) if stride >= size => Ok(stride),
        Some(stride) => Err(format!(
            "buffer view {}: byteStride {stride} is smaller than an element ({size} bytes)",
            view.index()
        )),
    }
}

/// What is left of the file's vertex and triangle allowance.
struct Budget {
    vertices: usize,
    triangles: usize,
}

/// The size in bytes of one component.
fn component_size(t: DataType) -> usize {
    match t {
        DataType::I8 | DataType::U8 => 1,
        DataType::I16 | DataType::U16 => 2,
        DataType::U32 | DataType::F32 => 4,
    }
}

/// One component at the start of `b` as a float (normalised integers mapped to [0, 1] or
/// [-1, 1] as the spec says).
fn component(b: &[u8], t: DataType, normalized: bool) -> f32 {
    let n = |v: f32, max: f32| {
        if normalized { (v / max).max(-1.0) } else { v }
    };
    match t {
        DataType::I8 => n(f32::from(b[0] as i8), 127.0),
        DataType::U8 => n(f32::from(b[0]), 255.0),
        DataType::I16 => n(f32::from(i16::from_le_bytes([b[0], b[1]])), 32767.0),
        DataType::U16 => n(f32::from(u16::from_le_bytes([b[0], b[1]])), 65535.0),
        DataType::U32 => n(
            u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
            4_294_967_295.0,
        ),
        DataType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
    }
}

/// An unsigned integer component at the start of `b` (`t` is `U8`, `U16` or `U32`).
fn uint(b: &[u8], t: DataType) -> u32 {
    match t {
        DataType::U8 => u32::from(b[0]),
        DataType::U16 => u32::from(u16::from_le_bytes([b[0], b[1]])),
        _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
    }
}

/// A strided run of `count` elements of `size` bytes starting `offset` bytes into a view.
fn elements(
    bytes: &[u8],
    offset: usize,
    stride: usize,
    size: usize,
    count: usize,
) -> Option<impl Iterator<Item = &[u8]>> {
    if count > 0 {
        let last = (count - 1).checked_mul(stride)?.checked_add(offset)?;
        bytes.get(last..last.checked_add(size)?)?;
    }
    Some((0..count).map(move |i| &bytes[offset + i * stride..offset + i * stride + size]))
}

/// The sparse substitutions of accessor `acc` (of `count` elements of `size` bytes): each
/// target element's index, checked to be below `count`, with its new value's bytes. Empty for an
/// accessor without sparse storage.
fn sparse_values<'b>(
    acc: &gltf::Accessor,
    count: usize,
    size: usize,
    buffers: &'b [SharedBytes],
) -> Result<Vec<(usize, &'b [u8])>, String> {
    let i = acc.index();
    let Some(sparse) = acc.sparse() else {
        return Ok(Vec::new());
    };
    let n = sparse.count();
    let idx = sparse.indices();
    let it = match idx.index_type() {
        gltf::accessor::sparse::IndexType::U8 => DataType::U8,
        gltf::accessor::sparse::IndexType::U16 => DataType::U16,
        gltf::accessor::sparse::IndexType::U32 => DataType::U32,
    };
    let isize = component_size(it);
    let ibytes =
        view_bytes(&idx.view(), buffers).map_err(|e| format!("accessor {i} sparse: {e}"))?;
    let vals = sparse.values();
    let vbytes =
        view_bytes(&vals.view(), buffers).map_err(|e| format!("accessor {i} sparse: {e}"))?;
    let (Some(indices), Some(values)) = (
        elements(ibytes, idx.offset(), isize, isize, n),
        elements(vbytes, vals.offset(), size, size, n),
    ) else {
        return Err(format!(
            "accessor {i}: sparse data outside its buffer views"
        ));
    };
    indices
        .zip(values)
        .map(|(ib, vb)| {
            let target = uint(ib, it) as usize;
            if target < count {
                Ok((target, vb))
            } else {
                Err(format!(
                    "accessor {i}: sparse index {target} out of range (count {count})"
                ))
            }
        })
        .collect()
}

/// Reads accessor `acc` as `count × dims` floats, sparse substitution applied.
fn read_floats(
    acc: &gltf::Accessor,
    dims: usize,
    buffers: &[SharedBytes],
) -> Result<Vec<f32>, String> {
    let i = acc.index();
    if acc.dimensions().multiplicity() != dims {
        return Err(format!(
            "accessor {i}: {:?}, expected {dims} components",
            acc.dimensions()
        ));
    }
    let t = acc.data_type();
    let csize = component_size(t);
    let size = csize * dims;
    let count = acc.count();
    let mut out = Vec::new();
    let read_elem = |e: &[u8], out: &mut Vec<f32>| {
        for k in 0..dims {
            out.push(component(&e[k * csize..], t, acc.normalized()));
        }
    };
    match acc.view() {
        Some(view) => {
            let bytes = view_bytes(&view, buffers).map_err(|e| format!("accessor {i}: {e}"))?;
            let stride = stride(&view, size).map_err(|e| format!("accessor {i}: {e}"))?;
            let items = elements(bytes, acc.offset(), stride, size, count).ok_or_else(|| {
                format!(
                    "accessor {i}: {count} elements outside buffer view {}",
                    view.index()
                )
            })?;
            out.reserve_exact(count * dims);
            for e in items {
                read_elem(e, &mut out);
            }
        }
        None => {
            if count > MAX_ZERO_FILLED {
                return Err(format!(
                    "accessor {i}: {count} elements without a buffer view, more than {MAX_ZERO_FILLED}"
                ));
            }
            out.resize(count * dims, 0.0);
        }
    }
    for (target, vb) in sparse_values(acc, count, size, buffers)? {
        let mut v = Vec::with_capacity(dims);
        read_elem(vb, &mut v);
        out[target * dims..(target + 1) * dims].copy_from_slice(&v);
    }
    Ok(out)
}

/// Reads an index accessor (unsigned integers, not normalised).
fn read_indices(acc: &gltf::Accessor, buffers: &[SharedBytes]) -> Result<Vec<u32>, String> {
    let i = acc.index();
    if !matches!(
        acc.data_type(),
        DataType::U8 | DataType::U16 | DataType::U32
    ) || acc.dimensions() != Dimensions::Scalar
        || acc.normalized()
    {
        return Err(format!(
            "accessor {i}: indices must be unsigned integer scalars"
        ));
    }
    // u32 values above 2^24 are not exact in f32: read integers directly.
    let t = acc.data_type();
    let size = component_size(t);
    let int = |b: &[u8]| uint(b, t);
    let count = acc.count();
    let mut out = match acc.view() {
        Some(view) => {
            let bytes = view_bytes(&view, buffers).map_err(|e| format!("accessor {i}: {e}"))?;
            let stride = stride(&view, size).map_err(|e| format!("accessor {i}: {e}"))?;
            elements(bytes, acc.offset(), stride, size, count)
                .ok_or_else(|| {
                    format!(
                        "accessor {i}: {count} elements outside buffer view {}",
                        view.index()
                    )
                })?
                .map(int)
                .collect()
        }
        None if count <= MAX_ZERO_FILLED => vec![0; count],
        None => {
            return Err(format!(
                "accessor {i}: {count} elements without a buffer view, more than {MAX_ZERO_FILLED}"
            ));
        }
    };
    for (target, vb) in sparse_values(acc, count, size, buffers)? {
        out[target] = int(vb);
    }
    Ok(out)
}

/// Reads one triangle primitive into a [`MeshData`].
fn read_primitive(
    prim: &gltf::Primitive,
    buffers: &[SharedBytes],
    budget: &mut Budget,
) -> Result<MeshData, String> {
    let pos = prim.get(&gltf::Semantic::Positions).ok_or("no POSITION")?;
    let n = pos.count();
    if n > budget.vertices {
        return Err(format!(
            "{n} vertices; at most {MAX_VERTICES} are read per file"
        ));
    }
    budget.vertices -= n;
    let positions: Vec<Vec3> = read_floats(&pos, 3, buffers)?
        .chunks_exact(3)
        .map(Vec3::from_slice)
        .collect();
    if let Some(k) = positions.iter().position(|p| !p.is_finite()) {
        return Err(format!("accessor {}: non-finite position {k}", pos.index()));
    }
    let normals = match prim.get(&gltf::Semantic::Normals) {
        None => None,
        Some(acc) if acc.count() == n => Some(
            read_floats(&acc, 3, buffers)?
                .chunks_exact(3)
                .map(|c| {
                    let v = Vec3::from_slice(c);
                    if v.is_finite() {
                        v.normalize_or_zero()
                    } else {
                        Vec3::ZERO
                    }
                })
                .collect(),
        ),
        Some(acc) => {
            return Err(format!(
                "accessor {}: {} normals for {n} positions",
                acc.index(),
                acc.count()
            ));
        }
    };
    let uvs = match prim.get(&gltf::Semantic::TexCoords(0)) {
        None => None,
        Some(acc) if acc.count() == n => {
            // glTF's v runs down the image from its top row, rondo's up from the bottom row.
            let uv: Vec<Vec2> = read_floats(&acc, 2, buffers)?
                .chunks_exact(2)
                .map(|t| Vec2::new(t[0], 1.0 - t[1]))
                .collect();
            if let Some(k) = uv.iter().position(|t| !t.is_finite()) {
                return Err(format!(
                    "accessor {}: non-finite texture coordinate {k}",
                    acc.index()
                ));
            }
            Some(uv)
        }
        Some(acc) => {
            return Err(format!(
                "accessor {}: {} texture coordinates for {n} positions",
                acc.index(),
                acc.count()
            ));
        }
    };
    let indices = match prim.indices() {
        Some(acc) => {
            let idx = read_indices(&acc, buffers)?;
            if let Some(&bad) = idx.iter().find(|&&v| v as usize >= n) {
                return Err(format!(
                    "accessor {}: index {bad} out of range ({n} vertices)",
                    acc.index()
                ));
            }
            idx
        }
        None => (0..n as u32).collect(),
    };
    let triangles = assemble(prim.mode(), &indices);
    if triangles.len() > budget.triangles {
        return Err(format!("more than {MAX_TRIANGLES} triangles in the file"));
    }
    budget.triangles -= triangles.len();
    Ok(MeshData {
        positions,
        normals,
        uvs,
        triangles,
    })
}

/// Triangles of a triangle list, strip or fan, each in the winding the spec gives (strips
/// alternate so that every triangle keeps the first one's orientation). Degenerate triangles
/// with repeated indices are dropped.
pub fn assemble(mode: Mode, idx: &[u32]) -> Vec<[u32; 3]> {
    let tris: Vec<[u32; 3]> = match mode {
        Mode::TriangleStrip => (0..idx.len().saturating_sub(2))
            .map(|i| {
                if i % 2 == 0 {
                    [idx[i], idx[i + 1], idx[i + 2]]
                } else {
                    [idx[i + 1], idx[i], idx[i + 2]]
                }
            })
            .collect(),
        Mode::TriangleFan => (1..idx.len().saturating_sub(1))
            .map(|i| [idx[0], idx[i], idx[i + 1]])
            .collect(),
        _ => idx.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
    };
    tris.into_iter()
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .collect()
}

/// A texture reference with its sampler.
fn texture(tex: &gltf::Texture, texcoord: u32) -> GltfTexture {
    use gltf::texture::{MagFilter, WrappingMode};
    let wrap = |w| match w {
        WrappingMode::Repeat => Wrap::Repeat,
        WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        WrappingMode::ClampToEdge => Wrap::ClampToEdge,
    };
    let sampler = tex.sampler();
    GltfTexture {
        image: tex.source().index(),
        texcoord,
        wrap_s: wrap(sampler.wrap_s()),
        wrap_t: wrap(sampler.wrap_t()),
        nearest: sampler.mag_filter() == Some(MagFilter::Nearest),
    }
}

/// Checks that a material's field `field` holds `v`, a finite number within `range` (the
/// spec's range for it; the RON loader refuses the same quantities out of range).
fn check_field(
    what: &dyn Fn() -> String,
    field: &str,
    v: f32,
    range: RangeInclusive<f32>,
) -> Result<(), String> {
    if v.is_finite() && range.contains(&v) {
        return Ok(());
    }
    let (lo, hi) = (range.start(), range.end());
    let within = if hi.is_finite() {
        format!("in [{lo}, {hi}]")
    } else if lo.is_finite() {
        format!("finite and at least {lo}")
    } else {
        "finite".into()
    };
    Err(format!("{}: {field} is {v}, must be {within}", what()))
}

/// Reads a material, checking its factors against the spec's ranges.
fn read_material(m: &gltf::Material) -> Result<GltfMaterial, String> {
    let pbr = m.pbr_metallic_roughness();
    let name = m.name().map(str::to_owned);
    let what = || match (&name, m.index()) {
        (Some(n), Some(i)) => format!("material \"{n}\" (materials[{i}])"),
        (None, Some(i)) => format!("materials[{i}]"),
        (_, None) => "default material".into(),
    };
    let unit = 0.0..=1.0;
    let any = f32::NEG_INFINITY..=f32::INFINITY;
    let at_least_0 = 0.0..=f32::INFINITY;
    for (k, v) in pbr.base_color_factor().into_iter().enumerate() {
        let field = format!("pbrMetallicRoughness.baseColorFactor[{k}]");
        check_field(&what, &field, v, unit.clone())?;
    }
    let metallic = pbr.metallic_factor();
    check_field(
        &what,
        "pbrMetallicRoughness.metallicFactor",
        metallic,
        unit.clone(),
    )?;
    let roughness = pbr.roughness_factor();
    check_field(
        &what,
        "pbrMetallicRoughness.roughnessFactor",
        roughness,
        unit.clone(),
    )?;
    for (k, v) in m.emissive_factor().into_iter().enumerate() {
        check_field(&what, &format!("emissiveFactor[{k}]"), v, unit.clone())?;
    }
    let strength = m.emissive_strength().unwrap_or(1.0);
    let field = "extensions.KHR_materials_emissive_strength.emissiveStrength";
    check_field(&what, field, strength, at_least_0.clone())?;
    let emissive = Vec3::from(m.emissive_factor()) * strength;
    if !emissive.is_finite() {
        return Err(format!(
            "{}: emissiveFactor × emissiveStrength is not finite",
            what()
        ));
    }
    let transmission = m.transmission().map_or(0.0, |t| t.transmission_factor());
    let field = "extensions.KHR_materials_transmission.transmissionFactor";
    check_field(&what, field, transmission, unit)?;
    let ior = m.ior().unwrap_or(1.5);
    if !(ior.is_finite() && ior > 0.0) {
        return Err(format!(
            "{}: extensions.KHR_materials_ior.ior is {ior}, must be finite and above 0",
            what()
        ));
    }
    if let Some(t) = m.normal_texture() {
        check_field(&what, "normalTexture.scale", t.scale(), any)?;
    }
    if let Some(cutoff) = m.alpha_cutoff() {
        check_field(&what, "alphaCutoff", cutoff, at_least_0)?;
    }
    let alpha_mode = match m.alpha_mode() {
        gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
        gltf::material::AlphaMode::Mask => AlphaMode::Mask(m.alpha_cutoff().unwrap_or(0.5)),
        gltf::material::AlphaMode::Blend => AlphaMode::Blend,
    };
    Ok(GltfMaterial {
        base_color_factor: pbr.base_color_factor(),
        base_color_texture: pbr
            .base_color_texture()
            .map(|t| texture(&t.texture(), t.tex_coord())),
        metallic,
        roughness,
        metallic_roughness_texture: pbr
            .metallic_roughness_texture()
            .map(|t| texture(&t.texture(), t.tex_coord())),
        normal_texture: m
            .normal_texture()
            .map(|t| (texture(&t.texture(), t.tex_coord()), t.scale())),
        emissive,
        emissive_texture: m
            .emissive_texture()
            .map(|t| texture(&t.texture(), t.tex_coord())),
        alpha_mode,
        double_sided: m.double_sided(),
        transmission,
        transmission_texture: m
            .transmission()
            .is_some_and(|t| t.transmission_texture().is_some()),
        ior,
        name,
    })
}

/// Smallest |scale| of a node on any axis, as the RON loader's `Transform` allows.
const MIN_SCALE: f32 = 1e-12;

/// Smallest volume of a node matrix's unit cube relative to the product of its axes' lengths
/// (1 for any rotation and scale; near 0 when the axes are nearly coplanar).
const MIN_AXIS_VOLUME: f32 = 1e-6;

/// The node's own transform (TRS or matrix), checked to be finite and invertible, as RON's
/// `Transform` is: no scale below [`MIN_SCALE`] on any axis, a matrix's last row `0 0 0 1`
/// (glTF matrices are affine) and its axes not (nearly) coplanar.
fn local(node: &gltf::Node) -> Result<Affine3A, String> {
    let i = node.index();
    let m = match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => {
            let row = [matrix[0][3], matrix[1][3], matrix[2][3], matrix[3][3]];
            if row != [0.0, 0.0, 0.0, 1.0] {
                return Err(format!(
                    "node {i}: matrix's last row is {row:?}, must be [0, 0, 0, 1] (an affine transform)"
                ));
            }
            let m = Affine3A::from_mat4(Mat4::from_cols_array_2d(&matrix));
            let axes = [m.matrix3.x_axis, m.matrix3.y_axis, m.matrix3.z_axis];
            if let Some(k) = axes.iter().position(|a| a.length() < MIN_SCALE) {
                return Err(format!(
                    "node {i}: matrix scales axis {k} to zero (length below {MIN_SCALE})"
                ));
            }
            let [x, y, z] = axes.map(Vec3A::normalize);
            let volume = Mat3A::from_cols(x, y, z).determinant().abs();
            if volume < MIN_AXIS_VOLUME {
                return Err(format!(
                    "node {i}: matrix is singular (its axes are coplanar)"
                ));
            }
            m
        }
        gltf::scene::Transform::Decomposed {
            translation,
            rotation,
            scale,
        } => {
            if let Some(k) = scale.iter().position(|s| s.abs() < MIN_SCALE) {
                return Err(format!(
                    "node {i}: scale[{k}] is {}, must be non-zero (at least {MIN_SCALE} in size)",
                    scale[k]
                ));
            }
            Affine3A::from_scale_rotation_translation(
                Vec3::from(scale),
                Quat::from_array(rotation).normalize(),
                Vec3::from(translation),
            )
        }
    };
    // Also catches what the comparisons above let through: NaN is below nothing.
    if !m.is_finite() {
        return Err(format!("node {i}: non-finite transform"));
    }
    Ok(m)
}

/// Lists `node` and its descendants with composed transforms.
fn walk(
    node: &gltf::Node,
    parent: Affine3A,
    depth: usize,
    scene: &mut GltfScene,
) -> Result<(), String> {
    if depth >= MAX_NODE_DEPTH {
        return Err(format!(
            "node {}: hierarchy deeper than {MAX_NODE_DEPTH} (or a cycle)",
            node.index()
        ));
    }
    let world = parent * local(node)?;
    if node.skin().is_some() {
        scene
            .warnings
            .push(format!("node {}: skin ignored", node.index()));
    }
    if scene.nodes.len() >= MAX_NODE_INSTANCES {
        return Err(format!(
            "more than {MAX_NODE_INSTANCES} node instances in the default scene"
        ));
    }
    scene.nodes.push(GltfNode {
        index: node.index(),
        name: node.name().map(str::to_owned),
        world_from_node: world,
        mesh: node.mesh().map(|m| m.index()),
    });
    for child in node.children() {
        walk(&child, world, depth + 1, scene)?;
    }
    Ok(())
}
