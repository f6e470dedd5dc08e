//! What a string under the cursor names: a material of this file, a material of the prefab an
//! entity places, or a file.
//!
//! ```ron
//! Entity(name: "ball", material: "copper", …)                       // a material of this file
//! Entity(prefab: "prefabs/box.ron", materials: { "surface": "white" }) // the path, the
//!                                                                   // prefab's name, ours
//! Mesh(path: "meshes/bunny.obj")   Image(path: "t.png")             // files
//! ```

use std::path::{Path, PathBuf};

use super::outline::Outline;
use super::syntax::{Context, Kind, Token, slice};
use crate::scene::bounded_read::read_bounded;

/// What a string names.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Reference {
    /// A material name of this file (`material: "…"`, or a value of a placement's `materials`).
    Material(String),
    /// A material name of the prefab placed by the entity (a key of its `materials`).
    PrefabMaterial {
        /// The prefab's path as written.
        prefab: String,
        /// The name.
        name: String,
    },
    /// A file: the value of `prefab`, `gltf` or a `path`.
    File {
        /// The field: `prefab`, `gltf` or `path`.
        key: String,
        /// The struct holding the field (`Entity`, `Mesh`, `Image`, `NormalMap`,
        /// `Environment`).
        holder: String,
        /// The path as written.
        value: String,
    },
}

/// The reference of the string under the cursor in `context` (read from `text`, whose outline
/// is `outline`, at byte `offset`), with that string's token.
pub fn reference_at(
    text: &str,
    outline: &Outline,
    context: &Context,
    offset: usize,
) -> Option<(Reference, Token)> {
    let token = context
        .token
        .filter(|t| matches!(t.kind, Kind::Str { .. }))?;
    let value = text.get(token.contents())?.to_string();
    let (top, outer) = context.frames.split_last()?;
    let key = slice(text, top.key.clone());
    let reference = match top.open {
        b'(' if top.value && key == "material" => Reference::Material(value),
        b'(' if top.value && matches!(key, "prefab" | "gltf" | "path") => Reference::File {
            key: key.to_string(),
            holder: slice(text, top.name.clone()).to_string(),
            value,
        },
        b'{' if outer.len() >= 2
            && outer.last().is_some_and(|p| {
                p.open == b'(' && p.value && slice(text, p.key.clone()) == "materials"
            }) =>
        {
            if top.value {
                Reference::Material(value)
            } else {
                let (prefab, _) = outline.entity_at(offset)?.prefab.clone()?;
                Reference::PrefabMaterial {
                    prefab,
                    name: value,
                }
            }
        }
        _ => return None,
    };
    Some((reference, token))
}

/// `written` (a path in the file at `doc`) as a path: relative to the file's directory.
pub fn resolve(doc: &Path, written: &str) -> PathBuf {
    doc.parent().unwrap_or(Path::new("")).join(written)
}

/// Largest prefab read to answer a question about it.
pub const MAX_PREFAB_BYTES: u64 = 16 << 20;

/// The text of the prefab at `path`, if it is a regular file of at most [`MAX_PREFAB_BYTES`].
pub fn read_prefab(path: &Path) -> Option<String> {
    let (_, bytes) = read_bounded(path, MAX_PREFAB_BYTES).ok()?;
    String::from_utf8(bytes).ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lsp::outline::outline;
    use crate::lsp::syntax::context_at;

    fn at(text: &str, marker: &str) -> Option<Reference> {
        let offset = text.find(marker).expect(marker) + 1;
        let o = outline(text);
        reference_at(text, &o, &context_at(text, offset), offset).map(|r| r.0)
    }

    #[test]
    fn strings_name_materials_and_files() {
        let text = r#"Scene(materials: { "white": Diffuse(albedo: Image(path: "t.png")) },
            entities: [Entity(name: "b", material: "white", shape: Mesh(path: "m.obj")),
                       Entity(name: "p", materials: { "surface": "white2" }, prefab: "box.ron")])"#;
        assert_eq!(
            at(text, "\"white\","),
            Some(Reference::Material("white".into()))
        );
        assert_eq!(
            at(text, "\"white2\""),
            Some(Reference::Material("white2".into()))
        );
        assert_eq!(
            at(text, "\"surface\""),
            Some(Reference::PrefabMaterial {
                prefab: "box.ron".into(),
                name: "surface".into()
            })
        );
        let file = |key: &str, holder: &str, value: &str| {
            Some(Reference::File {
                key: key.into(),
                holder: holder.into(),
                value: value.into(),
            })
        };
        assert_eq!(at(text, "\"m.obj\""), file("path", "Mesh", "m.obj"));
        assert_eq!(at(text, "\"t.png\""), file("path", "Image", "t.png"));
        assert_eq!(at(text, "\"box.ron\""), file("prefab", "Entity", "box.ron"));
        assert_eq!(at(text, "\"white\":"), None, "a definition's name");
        assert_eq!(at(text, "\"b\""), None);
    }
}
