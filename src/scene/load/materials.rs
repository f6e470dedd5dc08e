//! Scene descriptions of materials, textures, normal maps and the sky become render values,
//! their image files loaded through the asset cache (each a dependency of the scene).

use std::path::Path;

use super::{Anchor, Expander, SourceFile};
use crate::scene::assets::Encoding;
use crate::scene::error::SceneError;
use crate::scene::format::{MaterialDesc, NormalMapDesc, SettingsDesc, TextureDesc};
use crate::shading::layers::Layers;
use crate::shading::material::{Material, absorption_coefficient};
use crate::shading::texture::{Sampling, Texture};
use crate::sky::{EnvironmentLight, Sky, Sun};

impl Expander<'_> {
    /// The sky of the scene `file`'s settings: its environment map loaded (a dependency)
    /// through the cache, its sun placed.
    pub(super) fn sky(
        &mut self,
        file: &SourceFile,
        settings: &SettingsDesc,
    ) -> Result<Sky, SceneError> {
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
    pub(super) fn material(
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
                    Anchor::Material(name),
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
            MaterialDesc::Dielectric {
                ior,
                roughness,
                attenuation_color,
                attenuation_distance,
            } => Material::Dielectric {
                ior: ior.0,
                roughness: roughness.0,
                absorption: absorption_coefficient(
                    attenuation_color.map_or(glam::Vec3::ONE, |c| c.0),
                    attenuation_distance.map_or(f32::INFINITY, |d| d.0),
                ),
            },
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
                specular,
                specular_color,
                sheen_color,
                sheen_roughness,
                clearcoat,
                clearcoat_roughness,
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
                                    Anchor::Material(name),
                                    Some(&p),
                                    format!("material \"{name}\": normal_map: {msg}"),
                                )
                            })?)
                        }
                    },
                    layers: Layers {
                        specular: specular.0,
                        specular_color: specular_color.0,
                        sheen_color: sheen_color.0,
                        sheen_roughness: sheen_roughness.0,
                        clearcoat: clearcoat.0,
                        clearcoat_roughness: clearcoat_roughness.0,
                    },
                    layer_maps: None,
                }
            }
        })
    }

    /// Loads the normal map `desc` relative to `dir` as linear data (a dependency). Errors carry
    /// the path text.
    fn normal_map(
        &mut self,
        desc: &NormalMapDesc,
        dir: &Path,
    ) -> Result<crate::shading::maps::NormalMap, (String, String)> {
        let full = dir.join(&desc.path);
        self.depend(&full);
        let image = self
            .assets
            .image(&full, Encoding::Linear)
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
}
