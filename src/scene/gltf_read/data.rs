//! What a glTF file is read into: plain data with no tie to the `gltf` crate's document, and the
//! limits the reader holds a file to.

use std::ops::Range;
use std::sync::Arc;

use glam::{Affine2, Affine3A, Vec3};

use crate::model::MeshData;
use crate::shading::layers::Layers;

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
    /// The cameras of the default scene's nodes, in node order (a node reached twice is
    /// listed twice).
    pub cameras: Vec<GltfCamera>,
    /// The lights (`KHR_lights_punctual`) of the default scene's nodes, in node order.
    pub lights: Vec<GltfLight>,
    /// What was skipped or ignored, one sentence each.
    pub warnings: Vec<String>,
    /// Bytes held by the file's buffers (each source once), at most [`MAX_BUFFER_BYTES`](super::MAX_BUFFER_BYTES).
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
    /// Index of the node's camera in the file.
    pub camera: Option<usize>,
    /// Index of the node's light (`KHR_lights_punctual`) in the file.
    pub light: Option<usize>,
}

/// A camera placed by a node.
#[derive(Debug, Clone, PartialEq)]
pub struct GltfCamera {
    /// The node's index in the file.
    pub node: usize,
    /// The node's name in the file.
    pub node_name: Option<String>,
    /// The camera's name in the file.
    pub name: Option<String>,
    /// Camera to file space: the node's transform composed with its ancestors'. The camera
    /// looks along its −z, +y up.
    pub world_from_camera: Affine3A,
    /// Its projection.
    pub projection: GltfProjection,
}

/// A camera's projection.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum GltfProjection {
    /// Perspective: vertical field of view in radians, and the aspect ratio if the file gives
    /// one.
    Perspective {
        /// Vertical field of view, radians, in (0, π).
        yfov: f32,
        /// Width over height, if given.
        aspect_ratio: Option<f32>,
    },
    /// Orthographic (not supported as a scene camera).
    Orthographic,
}

/// A `KHR_lights_punctual` light placed by a node, its values checked (colour and intensity
/// finite and ≥ 0, cone angles `0 ≤ inner ≤ outer ≤ π/2`).
#[derive(Debug, Clone, PartialEq)]
pub struct GltfLight {
    /// The light's index in the file's list.
    pub index: usize,
    /// The light's name in the file.
    pub name: Option<String>,
    /// Light to file space: the node's transform composed with its ancestors'. Directional
    /// lights and spots shine along its −z.
    pub world_from_light: Affine3A,
    /// Linear colour.
    pub colour: Vec3,
    /// Candela for points and spots, lux for directional lights.
    pub intensity: f32,
    /// Its kind.
    pub kind: GltfLightKind,
}

/// The kind of a glTF light.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum GltfLightKind {
    /// Light from infinitely far away along −z.
    Directional,
    /// A point light.
    Point,
    /// A spot along −z with its cone half-angles in radians.
    Spot {
        /// Full intensity within this angle of the axis.
        inner: f32,
        /// No light beyond this angle.
        outer: f32,
    },
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
    /// Which `TEXCOORD_n` set it uses (`KHR_texture_transform`'s `texCoord` when it names one).
    pub texcoord: u32,
    /// Its `KHR_texture_transform`, carried into rondo's texture space (v pointing up the
    /// image, as the coordinates are stored).
    pub transform: Option<Affine2>,
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
    /// [`relative_uri`](super::relative_uri)).
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
    /// Whether the spec's back-face culling is off. Read but not used: rondo renders both
    /// sides, as Blender Cycles does (culling is a rasteriser's optimisation; scenes/README.md,
    /// "glTF models").
    pub double_sided: bool,
    /// `KHR_materials_transmission`'s factor (0 without the extension).
    pub transmission: f32,
    /// `KHR_materials_transmission`'s `transmissionTexture` (linear): its red channel scales
    /// the transmission factor.
    pub transmission_texture: Option<GltfTexture>,
    /// Index of refraction (`KHR_materials_ior`; 1.5 without it).
    pub ior: f32,
    /// `KHR_materials_volume`'s thickness factor (0 without it: a thin-walled surface).
    pub thickness: f32,
    /// `KHR_materials_volume`'s attenuation colour (white without it).
    pub attenuation_color: Vec3,
    /// `KHR_materials_volume`'s attenuation distance (infinite without it: no absorption).
    pub attenuation_distance: f32,
    /// `KHR_materials_specular`'s, `KHR_materials_sheen`'s and `KHR_materials_clearcoat`'s
    /// factors ([`Layers::NONE`] without them).
    pub layers: Layers,
    /// Those extensions' textures.
    pub layer_textures: GltfLayerTextures,
    /// What of those extensions is not read (the coat's normal texture), one sentence each.
    pub layer_notes: Vec<String>,
}

/// The textures of `KHR_materials_specular`, `KHR_materials_sheen` and
/// `KHR_materials_clearcoat` a material names, each multiplying its factor.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GltfLayerTextures {
    /// `specularTexture`: its alpha scales `specularFactor`.
    pub specular: Option<GltfTexture>,
    /// `specularColorTexture` (sRGB): its RGB scales `specularColorFactor`.
    pub specular_color: Option<GltfTexture>,
    /// `sheenColorTexture` (sRGB): its RGB scales `sheenColorFactor`.
    pub sheen_color: Option<GltfTexture>,
    /// `sheenRoughnessTexture`: its alpha scales `sheenRoughnessFactor`.
    pub sheen_roughness: Option<GltfTexture>,
    /// `clearcoatTexture`: its red scales `clearcoatFactor`.
    pub clearcoat: Option<GltfTexture>,
    /// `clearcoatRoughnessTexture`: its green scales `clearcoatRoughnessFactor`.
    pub clearcoat_roughness: Option<GltfTexture>,
}

impl GltfLayerTextures {
    /// Each texture slot with its field's name in the material.
    pub fn slots(&self) -> [(&'static str, Option<&GltfTexture>); 6] {
        [
            (
                "extensions.KHR_materials_specular.specularTexture",
                self.specular.as_ref(),
            ),
            (
                "extensions.KHR_materials_specular.specularColorTexture",
                self.specular_color.as_ref(),
            ),
            (
                "extensions.KHR_materials_sheen.sheenColorTexture",
                self.sheen_color.as_ref(),
            ),
            (
                "extensions.KHR_materials_sheen.sheenRoughnessTexture",
                self.sheen_roughness.as_ref(),
            ),
            (
                "extensions.KHR_materials_clearcoat.clearcoatTexture",
                self.clearcoat.as_ref(),
            ),
            (
                "extensions.KHR_materials_clearcoat.clearcoatRoughnessTexture",
                self.clearcoat_roughness.as_ref(),
            ),
        ]
    }
}

/// Bytes of a glTF file's buffers: a range of one shared allocation, so that a source named by
/// several buffers, and the images held in their views, are held once.
#[derive(Clone, Debug)]
pub struct SharedBytes {
    pub(super) data: Arc<Vec<u8>>,
    pub(super) range: Range<usize>,
}

impl SharedBytes {
    /// All of `data`.
    pub(super) fn whole(data: Arc<Vec<u8>>) -> Self {
        let range = 0..data.len();
        Self { data, range }
    }

    /// The part `range` (relative to these bytes), if inside them.
    pub(super) fn slice(&self, range: Range<usize>) -> Option<Self> {
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
