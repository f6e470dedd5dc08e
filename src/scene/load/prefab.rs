//! Prefab placements: a prefab file is read once per load, its entities expanded under the
//! placement's transform and names, its materials mapped to the placing file's.

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::rc::Rc;

use glam::Affine3A;

use super::{Anchor, Expander, MAX_PREFAB_DEPTH, Origin, Prefab, Scope, SourceFile, parse};
use crate::scene::bounded_read::read_text;
use crate::scene::error::SceneError;
use crate::scene::format::{EntityDesc, PrefabDesc};
use crate::scene::locate::SourceText;

impl Expander<'_> {
    /// The canonical path of prefab `path`, checked to be a regular file, once per path.
    fn canonical_prefab(&mut self, path: &Path) -> Result<PathBuf, String> {
        if let Some(c) = self.canonical.get(path) {
            return Ok(c.clone());
        }
        self.assets.note(path);
        let canonical = std::fs::canonicalize(path)
            .map_err(|err| format!("cannot read prefab {}: {err}", path.display()))?;
        if !std::fs::metadata(&canonical).is_ok_and(|m| m.is_file()) {
            return Err(format!("prefab {} is not a regular file", path.display()));
        }
        self.canonical.insert(path.to_path_buf(), canonical.clone());
        Ok(canonical)
    }

    #[expect(
        clippy::too_many_arguments,
        reason = "the entity and everything it is placed by"
    )]
    pub(super) fn place_prefab(
        &mut self,
        file: &SourceFile,
        e: &EntityDesc,
        prefab: &str,
        scope: &Scope,
        name: &str,
        transform: Affine3A,
        origin: Origin,
    ) -> Result<(), SceneError> {
        let at = Anchor::Entity(origin.index as usize, e.name.as_deref());
        if e.material.is_some() {
            return Err(file.error(at, None, format!("entity \"{name}\": a prefab placement maps names with `materials`, not `material`")));
        }
        let path = file.dir().join(prefab);
        let canonical = self
            .canonical_prefab(&path)
            .map_err(|m| file.error(at, Some(prefab), format!("entity \"{name}\": {m}")))?;
        if let Some(start) = self.chain.iter().position(|p| *p == canonical) {
            let cycle: Vec<String> = self.chain[start..]
                .iter()
                .chain([&canonical])
                .map(|p| p.display().to_string())
                .collect();
            return Err(file.error(
                at,
                Some(prefab),
                format!("prefab cycle: {}", cycle.join(" → ")),
            ));
        }
        if self.chain.len() > MAX_PREFAB_DEPTH {
            return Err(file.error(
                at,
                Some(prefab),
                format!("prefabs nested deeper than {MAX_PREFAB_DEPTH}"),
            ));
        }
        self.depend(&path);
        let loaded = match self.prefabs.get(&canonical) {
            Some(p) => p.clone(),
            None => {
                let source = match self.assets.overlay(&canonical) {
                    Some(text) => Ok(text.to_string()),
                    None => read_text(&path),
                };
                let source = source.map_err(|err| {
                    file.error(
                        at,
                        Some(prefab),
                        format!(
                            "entity \"{name}\": cannot read prefab {}: {err}",
                            path.display()
                        ),
                    )
                })?;
                // Its text is quoted with a parse error only if it is meant to be RON: a mesh,
                // an image or any other file named as a prefab by mistake (or to read it
                // through the viewer) is not shown.
                let desc: PrefabDesc = parse(&path, &source).map_err(|e| {
                    let ron = path
                        .extension()
                        .is_some_and(|x| x.eq_ignore_ascii_case("ron"));
                    if ron { e } else { e.unquoted() }
                })?;
                let file = SourceFile {
                    id: self.sources.len() as u32,
                    path: path.clone(),
                    source: source.into(),
                };
                self.sources.push(SourceText {
                    path: path.clone(),
                    text: file.source.clone(),
                });
                let p = Rc::new(Prefab {
                    file,
                    desc,
                    defaults: RefCell::new(None),
                });
                self.prefabs.insert(canonical.clone(), p.clone());
                p
            }
        };
        let (prefab_file, desc) = (&loaded.file, &loaded.desc);

        // The prefab's names: mapped by the placement, else the prefab's own default. A
        // placement that maps nothing shares the scope built by the first such placement.
        let cached = e
            .materials
            .as_ref()
            .is_none_or(BTreeMap::is_empty)
            .then(|| loaded.defaults.borrow().clone())
            .flatten();
        let inner = match cached {
            Some(scope) => scope,
            None => {
                let mut inner = Scope::new();
                for (theirs, ours) in e.materials.iter().flatten() {
                    let Some(key) = scope.get(ours) else {
                        return Err(file.error(
                            at,
                            Some(ours),
                            format!("entity \"{name}\": maps \"{theirs}\" to unknown material \"{ours}\""),
                        ));
                    };
                    inner.insert(theirs.clone(), key.clone());
                }
                for (own, m) in &desc.materials {
                    if inner.contains_key(own) {
                        continue;
                    }
                    let key = format!("{}::{own}", canonical.display());
                    if !self.materials.contains_key(&key) {
                        let material = self.material(prefab_file, own, &key, m)?;
                        self.materials.insert(key.clone(), material);
                    }
                    inner.insert(own.clone(), key);
                }
                let inner = Rc::new(inner);
                if e.materials.as_ref().is_none_or(BTreeMap::is_empty) {
                    *loaded.defaults.borrow_mut() = Some(inner.clone());
                }
                inner
            }
        };
        if let Some(missing) = desc
            .entities
            .iter()
            .filter(|c| c.shape.is_some())
            .filter_map(|c| c.material.as_ref())
            .find(|m| !inner.contains_key(*m))
        {
            let loc = file
                .location(at, None)
                .map(|l| format!(":{}:{}", l.line, l.col))
                .unwrap_or_default();
            return Err(prefab_file.error(
                Anchor::Quoted(missing),
                None,
                format!(
                    "material \"{missing}\" is defined neither by this prefab nor by its placement \"{name}\" in {}{loc}",
                    file.path.display()
                ),
            ));
        }
        let placement = self.place(origin, name, canonical.clone(), false);
        let outer = self.placing.replace(placement);
        self.chain.push(canonical);
        let result = self.expand(
            prefab_file,
            &desc.entities,
            &inner,
            transform,
            &format!("{name}/"),
        );
        self.chain.pop();
        self.placing = outer;
        result
    }
}
