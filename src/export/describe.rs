//! `scene.json`: what another renderer needs besides the triangles, as rondo interprets the
//! scene (defaults applied, units resolved: the sun's radiance rather than its irradiance, the
//! focus distance rather than `focus_on`).
//!
//! ```text
//! { "format": "rondo-export 1",
//!   "camera": { position, look_at, direction, up, fov_y_degrees, aperture_radius,
//!               focus_distance, width, height },
//!   "settings": { spp, max_depth (rays per path, camera ray included), method, seed },
//!   "background": [r, g, b] | null,
//!   "environment": { path, strength, world_from_map (3×3, rows), convention } | null,
//!   "sun": { direction (towards the sun), angular_diameter_degrees, radiance } | null,
//!   "materials": { key: { kind, ... textures ... } }  (kind "transmissive": { weight, glass,
//!                base, transmission_texture? }, two materials mixed: f = weight · glass +
//!                (1 − weight) · base; with transmission_texture { texture, opaque } the glass
//!                part is itself mixed, f = weight · (r · glass + (1 − r) · opaque) +
//!                (1 − weight) · base, r the texture's red channel at the point),
//!   "spheres": [ { center, radius, world_from_object_rotation, material } ],
//!   "planes": [ { point, normal, tangent, bitangent, material, proxy_half_size } ],
//!   "meshes": [ { file, material, vertices, triangles, normals, uvs } ],
//!   "counts": { triangles, plane_triangles, spheres, mesh_placements } }
//! ```
//!
//! A texture is `{"kind": "constant", "value": [r, g, b]}`, `{"kind": "checker", "scale": k,
//! "even": T, "odd": T}` (`even` where `sin(k·u)·sin(k·v) > 0`), `{"kind": "image", "path",
//! "encoding": "srgb" | "linear", "filter": "nearest" | "bilinear", "wrap": [u, v]}` or
//! `{"kind": "scaled", "factor": [r, g, b], "texture": T}`.

use std::collections::BTreeMap;

use glam::{Mat3, Vec3};
use serde_json::{Value, json};

use super::ply::{GroupKey, Written};
use super::textures::ImageFiles;
use super::{ExportError, ExportReport};
use crate::geometry::packed::Primitive;
use crate::geometry::world::world_primitives;
use crate::model::Shape;
use crate::scene::load::LoadedScene;
use crate::shading::layers::Layers;
use crate::shading::material::Material;
use crate::shading::texture::{Filter, Texture, Wrap};

fn v3(v: Vec3) -> Value {
    json!([v.x, v.y, v.z])
}

fn mat3_rows(m: Mat3) -> Value {
    let r = m.transpose();
    json!([
        r.x_axis.to_array(),
        r.y_axis.to_array(),
        r.z_axis.to_array()
    ])
}

/// The scene's extent for the planes' squares: the largest distance of the camera or of any
/// sphere's or triangle's point from the origin, at least 1.
pub fn extent(scene: &LoadedScene) -> f32 {
    let mut r = scene.camera.position.length().max(1.0);
    for e in &scene.entities {
        match &e.shape {
            Shape::Plane { .. } => {}
            Shape::Mesh(m) => {
                // The mesh's bounds' corners bound its vertices' distance.
                let t = e.transform.0;
                for p in &m.data.positions {
                    r = r.max(t.transform_point3(*p).length());
                }
            }
            shape => {
                for prim in world_primitives(shape, &e.transform) {
                    match prim {
                        Primitive::Sphere { center, radius, .. } => {
                            r = r.max(center.length() + radius);
                        }
                        Primitive::Triangle { p, .. } => {
                            for q in p {
                                r = r.max(q.length());
                            }
                        }
                        _ => {}
                    }
                }
            }
        }
    }
    r
}

fn texture(t: &Texture, images: &ImageFiles) -> Result<Value, ExportError> {
    Ok(match t {
        Texture::Constant(c) => json!({"kind": "constant", "value": v3(*c)}),
        Texture::Checker { scale, even, odd } => json!({
            "kind": "checker",
            "scale": scale,
            "even": texture(even, images)?,
            "odd": texture(odd, images)?,
        }),
        Texture::Scaled(inner, factor) => json!({
            "kind": "scaled",
            "factor": v3(*factor),
            "texture": texture(inner, images)?,
        }),
        Texture::Mapped(inner, map) => json!({
            "kind": "mapped",
            "set": map.set,
            "transform": map.transform.map(|m| m.to_cols_array()),
            "texture": texture(inner, images)?,
        }),
        Texture::Image(image, sampling) => {
            let Some(file) = images.file(image) else {
                return Err(ExportError("a texture's file was not found".into()));
            };
            json!({
                "kind": "image",
                "path": file.path,
                "encoding": file.encoding,
                "filter": match sampling.filter {
                    Filter::Nearest => "nearest",
                    Filter::Bilinear => "bilinear",
                },
                "wrap": sampling.wrap.map(|w| match w {
                    Wrap::Clamp => "clamp",
                    Wrap::Repeat => "repeat",
                    Wrap::MirroredRepeat => "mirrored_repeat",
                }),
            })
        }
    })
}

fn material(m: &Material, images: &ImageFiles) -> Result<Value, ExportError> {
    Ok(match m {
        Material::Diffuse { albedo } => {
            json!({"kind": "diffuse", "albedo": texture(albedo, images)?})
        }
        Material::Metal { albedo, roughness } => json!({
            "kind": "metal",
            "albedo": texture(albedo, images)?,
            "fuzz": roughness,
        }),
        Material::Glossy { albedo, roughness } => json!({
            "kind": "glossy",
            "albedo": texture(albedo, images)?,
            "roughness": roughness,
            "alpha": roughness * roughness,
        }),
        Material::Dielectric {
            ior,
            roughness,
            absorption,
        } => json!({
            "kind": "dielectric",
            "ior": ior,
            "roughness": roughness,
            "alpha": roughness * roughness,
            // σa per unit length, per channel (an infinite channel, black, is written null).
            "absorption": absorption.to_array(),
        }),
        Material::Light {
            emit,
            intensity,
            two_sided,
        } => json!({
            "kind": "light",
            "emit": texture(emit, images)?,
            "intensity": intensity,
            "two_sided": two_sided,
        }),
        Material::Pbr {
            base_color,
            metallic,
            roughness,
            metallic_roughness,
            emissive,
            emissive_strength,
            normal_map,
            alpha,
            layers,
            layer_maps,
        } => {
            let alpha = match alpha {
                None => Value::Null,
                Some(a) => {
                    let image = match &a.image {
                        None => Value::Null,
                        Some((image, sampling)) => {
                            texture(&Texture::Image(image.clone(), *sampling), images)?
                        }
                    };
                    json!({"cutoff": a.cutoff, "factor": a.factor, "image": image})
                }
            };
            let mut pbr = json!({
                "kind": "pbr",
                "base_color": texture(base_color, images)?,
                "metallic": metallic,
                "roughness": roughness,
                "metallic_roughness": match metallic_roughness {
                    None => Value::Null,
                    Some(t) => texture(t, images)?,
                },
                "emissive": texture(emissive, images)?,
                "emissive_strength": emissive_strength,
                "normal_map": match normal_map {
                    None => Value::Null,
                    Some(n) => json!({"texture": texture(&n.texture, images)?, "scale": n.scale}),
                },
                "alpha_mask": alpha,
            });
            // Only a material with layers describes them, so other scenes export as before.
            if *layers != Layers::NONE {
                pbr["layers"] = json!({
                    "specular": layers.specular,
                    "specular_color": layers.specular_color.to_array(),
                    "sheen_color": layers.sheen_color.to_array(),
                    "sheen_roughness": layers.sheen_roughness,
                    "clearcoat": layers.clearcoat,
                    "clearcoat_roughness": layers.clearcoat_roughness,
                });
            }
            if let Some(maps) = layer_maps {
                let mut out = serde_json::Map::new();
                for (name, channel, t) in maps.channels() {
                    out.insert(
                        name.into(),
                        json!({"channel": channel, "texture": texture(&t, images)?}),
                    );
                }
                pbr["layer_maps"] = Value::Object(out);
            }
            pbr
        }
        Material::Transmissive {
            weight,
            glass,
            base,
            texture,
        } => {
            let mut mix = json!({
                "kind": "transmissive",
                // f = weight · f_glass + (1 − weight) · f_base.
                "weight": weight,
                "glass": material(glass, images)?,
                "base": material(base, images)?,
            });
            // Only a textured mix describes its texture, so other scenes export as before.
            if let Some(t) = texture {
                mix["transmission_texture"] = json!({
                    "texture": self::texture(&t.texture, images)?,
                    "opaque": material(&t.opaque, images)?,
                });
            }
            mix
        }
    })
}

/// The document described in the module's doc.
pub fn scene_json(
    scene: &LoadedScene,
    images: &ImageFiles,
    meshes: &BTreeMap<String, (GroupKey, Written)>,
    report: &ExportReport,
) -> Result<Value, ExportError> {
    let cam = &scene.camera;
    let s = &scene.settings;
    let dir = cam.direction.normalize();
    let mut materials = serde_json::Map::new();
    for (key, m) in &scene.materials {
        let value = material(m, images)
            .map_err(|e| ExportError(format!("{}: material {key:?}: {e}", scene.path.display())))?;
        materials.insert(key.clone(), value);
    }
    let scene_dir = scene.path.parent().unwrap_or(std::path::Path::new(""));
    let environment = match &s.environment {
        None => Value::Null,
        Some(env) => {
            let path = scene_dir.join(&env.path);
            json!({
                "path": std::path::absolute(&path).unwrap_or(path),
                "strength": env.strength,
                "world_from_map": mat3_rows(env.world_from_map()),
                "convention": "Mitsuba 3 envmap at an identity transform: y up; a direction d \
                    away from the scene reads u = atan2(d.x, -d.z) / 2pi, v = acos(d.y) / pi, \
                    row 0 up; nearest texel",
            })
        }
    };
    let sun = match &s.sun {
        None => Value::Null,
        Some(sun) => json!({
            "direction": v3(sun.direction),
            "angular_diameter_degrees": sun.angular_diameter,
            "radiance": v3(sun.radiance),
        }),
    };
    let half = super::PLANE_PROXY_SCALE * extent(scene);
    let mut spheres = Vec::new();
    let mut planes = Vec::new();
    for e in &scene.entities {
        match &e.shape {
            Shape::Sphere { .. } | Shape::Plane { .. } => {}
            _ => continue,
        }
        for prim in world_primitives(&e.shape, &e.transform) {
            match prim {
                Primitive::Sphere {
                    center,
                    radius,
                    frame,
                } => spheres.push(json!({
                    "name": e.name,
                    "center": v3(center),
                    "radius": radius,
                    "world_from_object_rotation": mat3_rows(frame),
                    "material": e.material,
                })),
                Primitive::Plane { point, normal } => {
                    let (tangent, bitangent) = normal.any_orthonormal_pair();
                    planes.push(json!({
                        "name": e.name,
                        "point": v3(point),
                        "normal": v3(normal),
                        "tangent": v3(tangent),
                        "bitangent": v3(bitangent),
                        "material": e.material,
                        "proxy_half_size": half,
                    }));
                }
                _ => {}
            }
        }
    }
    let mesh_list: Vec<Value> = meshes
        .iter()
        .map(|(file, (key, w))| {
            json!({
                "file": file,
                "material": key.material,
                "vertices": w.vertices,
                "triangles": w.triangles,
                "plane_triangles": w.plane_triangles,
                "normals": key.normals,
                "uvs": key.uvs,
            })
        })
        .collect();
    Ok(json!({
        "format": "rondo-export 1",
        "source": std::path::absolute(&scene.path).unwrap_or_else(|_| scene.path.clone()),
        "camera": {
            "position": v3(cam.position),
            "look_at": v3(cam.position + dir * cam.focus_distance),
            "direction": v3(dir),
            "up": v3(cam.up.normalize()),
            "fov_y_degrees": cam.fov,
            "aperture_radius": cam.aperture,
            "focus_distance": cam.focus_distance,
            "width": s.width,
            "height": s.height,
        },
        "settings": {
            "spp": s.spp,
            "max_depth": s.max_depth,
            "method": s.method.to_string(),
            "seed": s.seed,
        },
        "background": if s.environment.is_some() { Value::Null } else { v3(s.background) },
        "environment": environment,
        "sun": sun,
        "materials": materials,
        "spheres": spheres,
        "planes": planes,
        "meshes": mesh_list,
        "counts": {
            "triangles": report.triangles,
            "plane_triangles": report.plane_triangles,
            "spheres": report.spheres,
            "mesh_placements": report.mesh_placements,
        },
    }))
}
