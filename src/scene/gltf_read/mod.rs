//! glTF 2.0 files (`.gltf` and `.glb`) read into plain data: one [`MeshData`](crate::model::MeshData) per primitive, the
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
//! shading when absent: [`MeshData::normals`](crate::model::MeshData::normals) is `None`), the
//! `TEXCOORD_n` sets the primitive's material reads, at most two (float or normalised integers;
//! stored as `(u, 1 − v)`, rondo's v pointing up the image; `uv_sets.rs`), sparse accessors,
//! accessors without a buffer view (zeros), TRS and matrix node transforms,
//! `EXT_mesh_gpu_instancing` (`instancing.rs`), the metallic–roughness material with its
//! textures and their `KHR_texture_transform` (`texture_transform.rs`),
//! `KHR_materials_emissive_strength`, `KHR_materials_transmission` (its texture too),
//! `KHR_materials_ior`,
//! `KHR_materials_specular`, `KHR_materials_sheen` and `KHR_materials_clearcoat` with their
//! textures (`layers.rs`; the coat's normal texture is named in a warning),
//! `KHR_mesh_quantization`, the nodes' cameras and `KHR_lights_punctual` lights (`lights.rs`;
//! the scene loader decides what becomes of them). Skipped with a warning: points and lines,
//! morph targets, skins, and every other extension the file uses (the warning says what will
//! look wrong: `unsupported.rs`). Ignored: animations, vertex colours, tangents (normal maps
//! derive them from texture coordinates). Any other extension listed in `extensionsRequired` is
//! an error naming it.
//!
//! This file reads the document and assembles the result; the bytes behind it are in
//! `buffers.rs`, accessors in `accessors.rs`, materials in `material.rs` and the node tree with
//! its transform checks in `nodes.rs`. The scene loader places the result (`load/gltf_place.rs`).

use std::path::Path;
use std::sync::Arc;

use glam::Affine3A;
use gltf::mesh::Mode;

mod accessors;
mod buffers;
mod data;
mod field;
mod instancing;
mod layers;
mod lights;
mod material;
mod nodes;
mod texture_ref;
mod texture_transform;
mod unsupported;
mod uv_sets;

pub use self::accessors::assemble;
use self::accessors::{Budget, read_primitive, view_shared};
use self::buffers::{decode_data_uri, detach_images, read_buffers, split_glb};
use self::lights::{place_cameras_and_lights, read_cameras, read_lights};
use self::material::read_material;
use self::nodes::walk;

pub use self::buffers::{MAX_BUFFER_BYTES, relative_uri};
pub use self::data::{
    AlphaMode, GltfCamera, GltfImage, GltfLayerTextures, GltfLight, GltfLightKind, GltfMaterial,
    GltfMesh, GltfNode, GltfPrimitive, GltfProjection, GltfScene, GltfTexture, MAX_NODE_DEPTH,
    MAX_NODE_INSTANCES, MAX_TRIANGLES, MAX_VERTICES, MAX_ZERO_FILLED, SharedBytes, Wrap,
};
pub use self::uv_sets::MAX_UV_SETS;

/// Extensions that may appear in `extensionsRequired`.
const SUPPORTED_REQUIRED: &[&str] = &[
    "EXT_mesh_gpu_instancing",
    "KHR_lights_punctual",
    "KHR_materials_clearcoat",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_sheen",
    "KHR_materials_specular",
    "KHR_materials_transmission",
    "KHR_materials_volume",
    "KHR_mesh_quantization",
    "KHR_texture_transform",
];

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
    for m in doc.materials() {
        scene.materials.push(read_material(doc, &m)?);
    }
    for (i, m) in scene.materials.iter().enumerate() {
        let sets = m.uv_sets();
        if sets.len() > MAX_UV_SETS {
            let name = m
                .name
                .as_deref()
                .map_or(String::new(), |n| format!(" \"{n}\""));
            scene.warnings.push(format!(
                "material{name} (materials[{i}]) reads texture coordinate sets {sets:?}; only the first {MAX_UV_SETS} are carried, so its textures on TEXCOORD_{} read set {}",
                sets[MAX_UV_SETS..].iter().map(u32::to_string).collect::<Vec<_>>().join(", TEXCOORD_"),
                sets[0]
            ));
        }
    }
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
            let sets = prim
                .material()
                .index()
                .and_then(|m| scene.materials.get(m))
                .map_or_else(Vec::new, |m| m.uv_sets());
            let sets = &sets[..sets.len().min(MAX_UV_SETS)];
            let data = read_primitive(&prim, sets, &buffers, &mut budget)
                .map_err(|e| format!("{what}: {e}"))?;
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
    for ext in doc.extensions_used() {
        if !SUPPORTED_REQUIRED.contains(&ext) {
            scene.warnings.push(unsupported::warning(ext));
        }
    }
    let cameras = read_cameras(doc)?;
    let lights = read_lights(doc)?;
    let roots = doc.default_scene().or_else(|| doc.scenes().next());
    if let Some(root) = roots {
        for node in root.nodes() {
            walk(&node, Affine3A::IDENTITY, 0, &mut scene)?;
        }
    }
    instancing::expand(doc, &buffers, &mut scene)?;
    place_cameras_and_lights(&mut scene, &cameras, &lights);
    Ok(scene)
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
