//! Where each entity of a loaded scene comes from, for the viewer's picking: its qualified name,
//! its material's written name, the chain of prefab and glTF placements that put it there, and
//! the `file:line:col` of each (the entity, the material's definition, every placement).
//!
//! A [`Provenance`] keeps the little of a [`LoadedScene`] this needs (names, material keys and
//! origins cloned, the files' texts shared). Locations are found on the first question only, as
//! `rondo check` finds its warnings' places: one [`Places`] scan per file, then per entity and
//! per placement a lookup plus a read of its own text up to its name, and per material one
//! lookup. Linear in the scene (up to the log of a binary search per location).

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use super::error::Location;
use super::load::{LoadedScene, Origin, Placement};
use super::locate::{Places, SourceText};

/// A file, and the line and column in it where known.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Place<'a> {
    /// The file: absolute where the scene's path could be made so.
    pub path: &'a Path,
    /// Line and column (1-based, columns in characters), if found.
    pub location: Option<Location>,
}

/// One placement of an entity's chain.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Link<'a> {
    /// The placing entity's qualified name.
    pub name: &'a str,
    /// Whether it places a glTF file (else a prefab).
    pub gltf: bool,
    /// The file it places.
    pub file: &'a Path,
    /// Where the placing entity is written.
    pub at: Place<'a>,
}

/// Everything known of where one entity comes from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Entry<'a> {
    /// Qualified name (`tall/box`).
    pub name: &'a str,
    /// The material's name as written where it is defined (`white`; a prefab's own `surface`;
    /// a glTF file's material label).
    pub material: &'a str,
    /// Where the entity is written; for a node of a glTF file, that file (no line).
    pub entity: Place<'a>,
    /// Where the material is defined; for a glTF file's own material, that file (no line).
    pub material_at: Place<'a>,
    /// The placements that put the entity there, outermost first (empty for an entity of the
    /// scene file).
    pub chain: Vec<Link<'a>>,
}

/// The locations, found once.
struct Located {
    /// Absolute path of each source file.
    paths: Vec<PathBuf>,
    /// Per entity.
    entities: Vec<Option<Location>>,
    /// Per placement.
    placements: Vec<Option<Location>>,
    /// Per material key: its file (index in the sources) and location.
    materials: HashMap<String, (u32, Option<Location>)>,
}

/// Where the entities of one loaded scene come from (see the module's doc).
pub struct Provenance {
    scene: PathBuf,
    names: Vec<String>,
    materials: Vec<String>,
    origins: Vec<Origin>,
    placements: Vec<Placement>,
    material_origins: BTreeMap<String, (u32, String)>,
    sources: Vec<SourceText>,
    located: OnceLock<Located>,
}

impl Provenance {
    /// What `scene` says of its entities' origins (cloned: the scene goes on to the renderer).
    pub fn of(scene: &LoadedScene) -> Self {
        Self {
            scene: absolute(&scene.path),
            names: scene.entities.iter().map(|e| e.name.clone()).collect(),
            materials: scene.entities.iter().map(|e| e.material.clone()).collect(),
            origins: scene.origins.clone(),
            placements: scene.placements.clone(),
            material_origins: scene.material_origins.clone(),
            sources: scene.sources.clone(),
            located: OnceLock::new(),
        }
    }

    /// Number of entities, in expansion order (the ids of [`Provenance::entry`]).
    pub fn len(&self) -> usize {
        self.names.len()
    }

    /// Whether the scene has no entities.
    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    /// Where entity `id` (its index in expansion order) comes from; `None` past the end. The
    /// first call locates every entity (see the module's doc).
    pub fn entry(&self, id: usize) -> Option<Entry<'_>> {
        let name = self.names.get(id)?;
        let key = &self.materials[id];
        let located = self.located.get_or_init(|| self.locate());
        let origin = self.origins.get(id);
        let gltf = origin
            .and_then(|o| o.placement)
            .and_then(|p| self.placements.get(p as usize))
            .filter(|p| p.gltf);
        let entity = match (gltf, origin) {
            (Some(p), _) => Place {
                path: &p.file,
                location: None,
            },
            (None, Some(o)) => Place {
                path: located.path(o.file).unwrap_or(&self.scene),
                location: located.entities[id],
            },
            (None, None) => Place {
                path: &self.scene,
                location: None,
            },
        };
        let written = self.material_origins.get(key).map(|(_, n)| n.as_str());
        let own_gltf = gltf.filter(|p| {
            key.strip_prefix(&*p.file.to_string_lossy())
                .is_some_and(|rest| rest.starts_with("::"))
        });
        let material_at = match (own_gltf, located.materials.get(key)) {
            (Some(p), _) => Place {
                path: &p.file,
                location: None,
            },
            (None, Some(&(file, location))) => Place {
                path: located.path(file).unwrap_or(&self.scene),
                location,
            },
            (None, None) => Place {
                path: &self.scene,
                location: None,
            },
        };
        let mut chain = Vec::new();
        let mut next = origin.and_then(|o| o.placement);
        // Each placement is recorded after the one that placed its file, so the walk ends.
        while let Some(p) = next.and_then(|p| self.placements.get(p as usize).map(|x| (p, x))) {
            let (index, placement) = p;
            chain.push(Link {
                name: &placement.name,
                gltf: placement.gltf,
                file: &placement.file,
                at: Place {
                    path: located.path(placement.origin.file).unwrap_or(&self.scene),
                    location: located.placements[index as usize],
                },
            });
            next = placement.origin.placement.filter(|&outer| outer < index);
        }
        chain.reverse();
        Some(Entry {
            name,
            material: written.unwrap_or(key),
            entity,
            material_at,
            chain,
        })
    }

    /// Every location, by one scan per file.
    fn locate(&self) -> Located {
        let mut places = Places::new(&self.sources);
        let mut at = |o: &Origin, name: &str| {
            let l = places.locator(o.file)?;
            o.offset(name, l).map(|off| l.location(off))
        };
        let entities = self
            .origins
            .iter()
            .zip(&self.names)
            .map(|(o, name)| {
                let of_gltf = o
                    .placement
                    .and_then(|p| self.placements.get(p as usize))
                    .is_some_and(|p| p.gltf);
                if of_gltf { None } else { at(o, name) }
            })
            .collect();
        let placements = self
            .placements
            .iter()
            .map(|p| at(&p.origin, &p.name))
            .collect();
        let mut materials = HashMap::new();
        for key in &self.materials {
            if materials.contains_key(key) {
                continue;
            }
            if let Some((file, name)) = self.material_origins.get(key) {
                let location = places
                    .locator(*file)
                    .and_then(|l| l.material(name).map(|off| l.location(off)));
                materials.insert(key.clone(), (*file, location));
            }
        }
        Located {
            paths: self.sources.iter().map(|s| absolute(&s.path)).collect(),
            entities,
            placements,
            materials,
        }
    }
}

impl Located {
    fn path(&self, file: u32) -> Option<&Path> {
        self.paths.get(file as usize).map(PathBuf::as_path)
    }
}

/// `path` made absolute against the current directory (without touching the file system),
/// or as it is if that fails.
fn absolute(path: &Path) -> PathBuf {
    std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf())
}
