//! Placing a glTF 2.0 file in a scene: `Entity(name, gltf, transform, materials)`.
//!
//! The file's default scene becomes one entity per node and triangle primitive, named
//! `<placement>/<node name, or #index>` (`/<primitive index>` added for a mesh of several
//! primitives), each placed by the placement's transform times the node's. Every node that uses
//! a mesh shares its data, so it is instanced. The file's materials become `Pbr` materials keyed
//! `<canonical path>::<material name, or #index>` unless the placement maps their names to the
//! scene's, as a prefab placement does. Its lights and cameras are placed by `gltf_lights.rs`.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Affine3A, Vec3};

use super::gltf_glass::{Transmission, transmission};
use super::{Anchor, Expander, Origin, Placed, Scope, SourceFile};
use crate::model::{MeshRef, Shape, Transform};
use crate::scene::assets::{Encoding, GltfAsset, inside_folder};
use crate::scene::error::SceneError;
use crate::scene::format::EntityDesc;
use crate::scene::gltf_read::{
    AlphaMode, GltfImage, GltfMaterial, GltfTexture, MAX_UV_SETS, Wrap as GltfWrap,
};
use crate::shading::maps::{AlphaMask, NormalMap};
use crate::shading::material::{Material, TransmissionTexture};
use crate::shading::texture::{Filter, ImageTexture, Sampling, Texture, UvMap, Wrap};

/// The name a placement's `materials` uses for primitives without a material.
const DEFAULT_MATERIAL: &str = "#default";

/// The labels of a file's materials or nodes, by index: the name when no other index has it,
/// it is not empty, does not start with `#` (the form of the others) and holds none of the
/// characters in `reserved`; else `#index`. Labels are therefore distinct, and a label followed
/// by a suffix starting with a reserved character is never another label.
fn labels<'a>(
    names: impl Iterator<Item = (usize, Option<&'a str>)> + Clone,
    reserved: &[char],
) -> HashMap<usize, String> {
    let mut holders: HashMap<&str, usize> = HashMap::new();
    for (i, name) in names.clone() {
        if let Some(n) = name {
            let first = *holders.entry(n).or_insert(i);
            if first != i {
                // Held by two indices: marked by an index no item has.
                holders.insert(n, usize::MAX);
            }
        }
    }
    names
        .map(|(i, name)| {
            let label = match name {
                Some(n)
                    if holders.get(n) == Some(&i)
                        && !n.is_empty()
                        && !n.starts_with('#')
                        && !n.contains(reserved) =>
                {
                    n.to_owned()
                }
                _ => format!("#{i}"),
            };
            (i, label)
        })
        .collect()
}

impl Expander<'_> {
    /// Places the glTF file `gltf` written by entity `e` of `file` (see the module's doc).
    #[expect(
        clippy::too_many_arguments,
        reason = "the entity and everything it is placed by"
    )]
    pub(super) fn place_gltf(
        &mut self,
        file: &SourceFile,
        e: &EntityDesc,
        gltf: &str,
        scope: &Scope,
        name: &str,
        transform: Affine3A,
        origin: Origin,
    ) -> Result<(), SceneError> {
        let at = Anchor::Entity(origin.index as usize, e.name.as_deref());
        let fail = |then: Option<&str>, message: String| {
            file.error(at, then, format!("entity \"{name}\": {message}"))
        };
        if e.material.is_some() {
            return Err(fail(
                None,
                "a glTF placement maps names with `materials`, not `material`".into(),
            ));
        }
        let full = file.dir().join(gltf);
        self.depend(&full);
        let asset = self.assets.gltf(&full).map_err(|m| fail(Some(gltf), m))?;
        for buffer in asset.buffer_files() {
            self.depend(buffer);
        }
        for w in &asset.scene.warnings {
            self.warn(&full, w);
        }
        self.place_gltf_lights(&full, &asset, transform)
            .map_err(|m| fail(Some(gltf), format!("glTF {}: {m}", full.display())))?;
        self.gltf_placements.push(name.to_owned());
        if self.camera_placement.as_deref() == Some(name) {
            self.camera_source = Some((asset.clone(), transform, full.clone()));
        }
        let materials = &asset.scene.materials;
        let material_labels = labels(
            materials
                .iter()
                .enumerate()
                .map(|(i, m)| (i, m.name.as_deref())),
            &[],
        );
        let material_labels: Vec<String> = (0..materials.len())
            .map(|i| material_labels[&i].clone())
            .collect();

        // The placement's names, checked against the file's.
        let mut mapped: HashMap<&str, String> = HashMap::new();
        for (theirs, ours) in e.materials.iter().flatten() {
            if theirs != DEFAULT_MATERIAL && !material_labels.contains(theirs) {
                return Err(fail(
                    Some(theirs),
                    format!(
                        "maps \"{theirs}\", which {} does not define (its materials: {})",
                        full.display(),
                        if material_labels.is_empty() {
                            "none".to_string()
                        } else {
                            material_labels.join(", ")
                        }
                    ),
                ));
            }
            let Some(key) = scope.get(ours) else {
                return Err(fail(
                    Some(ours),
                    format!("maps \"{theirs}\" to unknown material \"{ours}\""),
                ));
            };
            mapped.insert(theirs, key.clone());
        }

        let canonical = std::fs::canonicalize(&full).unwrap_or_else(|_| full.clone());
        let placement = self.place(origin, name, canonical.clone(), true);
        // The table key of each material index (`None`: the default material), made once.
        let mut keys: HashMap<Option<usize>, String> = HashMap::new();
        let mut placed_nodes: HashMap<usize, usize> = HashMap::new();
        // A node reached twice is one node: its name is its own. `/` and `@` start the suffixes
        // of primitives and repeats.
        let node_labels = labels(
            asset
                .scene
                .nodes
                .iter()
                .map(|n| (n.index, n.name.as_deref())),
            &['/', '@'],
        );
        let prefix = format!("{name}/");
        for node in &asset.scene.nodes {
            let base = &node_labels[&node.index];
            let Some(mesh) = node.mesh.and_then(|m| asset.scene.meshes.get(m)) else {
                continue;
            };
            // A node reached through two parents is placed twice: `label`, then `label@2`, …
            let count = placed_nodes.entry(node.index).or_default();
            *count += 1;
            let label = match *count {
                1 => base.clone(),
                k => format!("{base}@{k}"),
            };
            let world = transform * node.world_from_node;
            let many = mesh.primitives.len() > 1;
            for (p, prim) in mesh.primitives.iter().enumerate() {
                let key = match keys.get(&prim.material) {
                    Some(key) => key.clone(),
                    None => {
                        let label = match prim.material {
                            Some(i) => material_labels[i].as_str(),
                            None => DEFAULT_MATERIAL,
                        };
                        let key = match mapped.get(label) {
                            Some(key) => key.clone(),
                            None => {
                                let key = format!("{}::{label}", canonical.display());
                                if !self.materials.contains_key(&key) {
                                    let gltf_material = prim.material.map(|i| &materials[i]);
                                    let material = self
                                        .gltf_material(&asset, &full, gltf_material, label)
                                        .map_err(|m| {
                                            fail(
                                                Some(gltf),
                                                format!("glTF {}: {m}", full.display()),
                                            )
                                        })?;
                                    self.materials.insert(key.clone(), material);
                                    self.material_origins
                                        .insert(key.clone(), (file.id, label.to_owned()));
                                }
                                key
                            }
                        };
                        keys.insert(prim.material, key.clone());
                        key
                    }
                };
                let entity = if many {
                    format!("{prefix}{label}/{p}")
                } else {
                    format!("{prefix}{label}")
                };
                let bounds = self.gltf_bounds(&prim.data);
                let mesh_path = PathBuf::from(format!(
                    "{}#mesh{}/{p}",
                    full.display(),
                    node.mesh.unwrap_or_default()
                ));
                let placed = Placed {
                    name: entity,
                    shape: Shape::Mesh(MeshRef {
                        path: mesh_path,
                        data: prim.data.clone(),
                    }),
                    bounds: Some(bounds),
                    transform: Transform(world),
                    key,
                };
                let origin = Origin {
                    prefix: prefix.len() as u32,
                    named: false,
                    placement: Some(placement),
                    ..origin
                };
                self.push_entity(file, at, placed, origin)
                    .map_err(|mut e| {
                        e.message = format!("{} (from {})", e.message, full.display());
                        e
                    })?;
            }
        }
        // Node names may hold `/`: the qualified names are checked for collisions.
        self.slashed = true;
        Ok(())
    }

    /// Object-space bounds of a glTF primitive, computed once per load of its data.
    fn gltf_bounds(&mut self, data: &Arc<crate::model::MeshData>) -> [Vec3; 2] {
        let id = Arc::as_ptr(data) as usize;
        if let Some(b) = self.gltf_bounds.get(&id) {
            return *b;
        }
        let bounds = data.positions.iter().fold(
            [Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)],
            |[lo, hi], &p| [lo.min(p), hi.max(p)],
        );
        self.stats.limit_vertices += data.positions.len() as u64;
        self.gltf_bounds.insert(id, bounds);
        bounds
    }

    /// The rondo material of glTF material `m` (`None`: the spec's default material, white,
    /// metallic 1, roughness 1) of the file at `path`, its textures loaded.
    fn gltf_material(
        &mut self,
        asset: &GltfAsset,
        path: &Path,
        m: Option<&GltfMaterial>,
        label: &str,
    ) -> Result<Material, String> {
        let Some(m) = m else {
            return Ok(Material::pbr(Vec3::ONE, 1.0, 1.0));
        };
        let what = format!("material \"{label}\"");
        let factor = Vec3::from_slice(&m.base_color_factor[..3]);
        // The glass part of a partly transmissive material, its share and the base's metalness.
        let (mix, metallic) = match transmission(m) {
            Transmission::Glass(glass, notes) => {
                for note in notes {
                    self.warn(path, &format!("{what}: {note}"));
                }
                return Ok(*glass);
            }
            Transmission::Mix {
                weight,
                glass,
                base_metallic,
                notes,
            } => {
                for note in notes {
                    self.warn(path, &format!("{what}: {note}"));
                }
                (Some((weight, glass)), base_metallic)
            }
            Transmission::Opaque => (None, m.metallic),
        };
        for note in &m.layer_notes {
            self.warn(path, &format!("{what}: {note}"));
        }
        for (field, t) in m.textures() {
            if m.uv_slot(t).is_none() {
                let first = m.uv_sets().first().copied().unwrap_or_default();
                self.warn(
                    path,
                    &format!(
                        "{what}: {field} reads TEXCOORD_{}, beyond the {MAX_UV_SETS} sets a primitive carries: it reads TEXCOORD_{first}",
                        t.texcoord
                    ),
                );
            }
        }
        let image = |x: &mut Self, t: &GltfTexture, encoding: Encoding| {
            x.gltf_image(asset, path, t, encoding)
                .map_err(|e| format!("{what}: {e}"))
        };
        let textured = |x: &mut Self, t: &GltfTexture, encoding: Encoding| {
            let (img, sampling) = image(x, t, encoding)?;
            Ok::<_, String>(mapped(Texture::Image(img, sampling), uv_map(m, t)))
        };
        let base = match &m.base_color_texture {
            Some(t) => Some((image(self, t, Encoding::Srgb)?, uv_map(m, t))),
            None => None,
        };
        let base_color = scaled(
            base.clone()
                .map(|((img, sampling), map)| mapped(Texture::Image(img, sampling), map)),
            factor,
        );
        let emissive = match &m.emissive_texture {
            Some(t) => scaled(Some(textured(self, t, Encoding::Srgb)?), m.emissive),
            None => Texture::Constant(m.emissive),
        };
        let metallic_roughness = match &m.metallic_roughness_texture {
            Some(t) => Some(textured(self, t, Encoding::Linear)?),
            None => None,
        };
        let normal_map = match &m.normal_texture {
            Some((t, scale)) => Some(NormalMap {
                texture: textured(self, t, Encoding::Linear)?,
                scale: *scale,
            }),
            None => None,
        };
        // BLEND is stochastic transparency (`AlphaMask`'s doc): no cutoff.
        let cutoff = match m.alpha_mode {
            AlphaMode::Opaque => None,
            AlphaMode::Mask(cutoff) => Some(Some(cutoff)),
            AlphaMode::Blend => Some(None),
        };
        let (image, map) = match base {
            Some((image, map)) if image.0.has_alpha() => (Some(image), map),
            _ => (None, Box::default()),
        };
        let alpha = cutoff.map(|cutoff| AlphaMask {
            cutoff,
            factor: m.base_color_factor[3],
            image,
            map,
        });
        let layer_maps = self.gltf_layer_maps(asset, path, m, &what)?;
        let base = Material::Pbr {
            base_color,
            metallic,
            roughness: m.roughness,
            metallic_roughness,
            emissive,
            emissive_strength: 1.0,
            normal_map,
            alpha,
            layers: m.layers,
            layer_maps,
        };
        let Some((weight, glass)) = mix else {
            return Ok(base);
        };
        let texture = match &m.transmission_texture {
            Some(t) => {
                // Where the texture lowers the transmission, the spec's dielectric shades:
                // the base without metal (`TransmissionTexture`).
                let mut opaque = base.clone();
                if let Material::Pbr { metallic, .. } = &mut opaque {
                    *metallic = 0.0;
                }
                let (img, sampling) = self
                    .gltf_image(asset, path, t, Encoding::Linear)
                    .map_err(|e| format!("{what}: transmissionTexture: {e}"))?;
                Some(Box::new(TransmissionTexture {
                    texture: mapped(Texture::Image(img, sampling), uv_map(m, t)),
                    opaque,
                }))
            }
            None => None,
        };
        Ok(Material::Transmissive {
            weight,
            glass,
            base: Box::new(base),
            texture,
        })
    }

    /// Texture `t` of the glTF file at `path`: its image decoded with `encoding` (an external
    /// file through the cache, as a dependency; an embedded one once per content of the glTF
    /// file) and its sampler.
    pub(super) fn gltf_image(
        &mut self,
        asset: &GltfAsset,
        path: &Path,
        t: &GltfTexture,
        encoding: Encoding,
    ) -> Result<(Arc<ImageTexture>, Sampling), String> {
        let image = match asset.scene.images.get(t.image) {
            Some(GltfImage::File(relative)) => {
                let dir = path.parent().unwrap_or(Path::new(""));
                let full = dir.join(relative);
                self.depend(&full);
                inside_folder(dir, &full).map_err(|e| format!("image {}: {e}", full.display()))?;
                self.assets
                    .image(&full, encoding)
                    .map_err(|e| format!("image {}: {e}", full.display()))?
            }
            Some(GltfImage::Bytes { .. }) => asset.embedded_image(t.image, encoding)?,
            None => return Err(format!("image {} does not exist", t.image)),
        };
        let wrap = |w: GltfWrap| match w {
            GltfWrap::Repeat => Wrap::Repeat,
            GltfWrap::MirroredRepeat => Wrap::MirroredRepeat,
            GltfWrap::ClampToEdge => Wrap::Clamp,
        };
        let sampling = Sampling {
            filter: if t.nearest {
                Filter::Nearest
            } else {
                Filter::Bilinear
            },
            wrap: [wrap(t.wrap_s), wrap(t.wrap_t)],
        };
        Ok((image, sampling))
    }
}

/// A texture times a colour factor (the factor alone without a texture; the texture alone for
/// a white factor).
fn scaled(texture: Option<Texture>, factor: Vec3) -> Texture {
    match texture {
        None => Texture::Constant(factor),
        Some(texture) if factor == Vec3::ONE => texture,
        Some(texture) => Texture::Scaled(Box::new(texture), factor),
    }
}

/// Which coordinates texture `t` of material `m` reads: its slot among the sets the material's
/// primitives carry (slot 0 for a set beyond them, warned about), through its
/// `KHR_texture_transform`.
pub(super) fn uv_map(m: &GltfMaterial, t: &GltfTexture) -> Box<UvMap> {
    Box::new(UvMap {
        set: m.uv_slot(t).unwrap_or(0),
        transform: t.transform,
    })
}

/// `texture` read through `map`; `texture` itself for the identity map (set 0, no transform),
/// so files without transforms or second sets render as before.
pub(super) fn mapped(texture: Texture, map: Box<UvMap>) -> Texture {
    if *map == UvMap::default() {
        texture
    } else {
        Texture::Mapped(Box::new(texture), map)
    }
}
