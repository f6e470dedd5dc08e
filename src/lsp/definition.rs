//! Go to definition: a material name to its entry in `materials` (of this file, or of the
//! prefab a placement maps it from), a prefab, glTF, mesh or texture path to the file.

use std::path::Path;

use lsp_types::{Location, Position, Range, Uri};

use super::documents::Document;
use super::outline::{Outline, outline};
use super::reference::{Reference, read_prefab, reference_at, resolve};
use super::syntax::context_at;
use super::uri::from_path;

/// Where the name or path under byte `offset` of `doc` (the file `path`, the URI `uri`, its
/// outline `here`) is defined.
pub fn definition(
    doc: &Document,
    uri: &Uri,
    path: &Path,
    here: &Outline,
    offset: usize,
) -> Option<Location> {
    let context = context_at(&doc.text, offset);
    let (reference, _) = reference_at(&doc.text, here, &context, offset)?;
    match reference {
        Reference::Material(name) => {
            let def = here.material(&name)?;
            Some(Location::new(uri.clone(), doc.range(def.key.clone())))
        }
        Reference::PrefabMaterial { prefab, name } => {
            let file = resolve(path, &prefab);
            let prefab = Document::new(None, read_prefab(&file)?, 0);
            let there = outline(&prefab.text);
            // Its default, else the first of its entities that uses the name.
            let range = match there.material(&name) {
                Some(def) => def.key.clone(),
                None => there
                    .entities
                    .iter()
                    .find_map(|e| e.material.as_ref().filter(|m| m.0 == name))?
                    .1
                    .clone(),
            };
            Some(Location::new(
                from_path(&file).parse().ok()?,
                prefab.range(range),
            ))
        }
        Reference::File { value, .. } => {
            let file = resolve(path, &value);
            if !file.is_file() {
                return None;
            }
            let start = Position::new(0, 0);
            Some(Location::new(
                from_path(&std::path::absolute(&file).ok()?).parse().ok()?,
                Range::new(start, start),
            ))
        }
    }
}
