//! The edits of the watch benchmarks (`rondo bench watch`, `rondo bench load --watch-sizes`):
//! the kinds of edit a user makes (a material, a move, one entity), found in any scene's text.
//!
//! An edit is the scene's text with one thing changed in place: a material's colour, a small
//! sphere's centre (or, without spheres, an entity's translation), a mesh entity's translation,
//! one entity's material name. Targets are found from the parsed scene and located in the text
//! by its entities' `Entity(` tokens; each edited text is parsed again and kept only if it
//! differs from the original in exactly that material or entity, so a target the text scan got
//! wrong is left out rather than timed as something else. Saves alternate between the edited
//! and the original text; the saves are timed by [`super::load_watch_time`].

use std::path::Path;

use crate::Shape;
use crate::scene::format::{EntityDesc, SceneDesc, ShapeDesc};
use crate::scene::load::parse_scene;
use crate::scene::locate::{Locator, block_comment_end};

/// A kind of edit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A material's colour (its first `(r, g, b)`).
    Colour,
    /// The smallest sphere's centre, or an analytic entity's translation if there is no sphere.
    MoveSmall,
    /// The translation of the entity with the biggest mesh file.
    MoveMesh,
    /// The material name of one entity (the one nearest the middle of the list).
    EntityMaterial,
}

/// Every kind, in the order they are timed and reported.
pub const KINDS: [Kind; 4] = [
    Kind::Colour,
    Kind::MoveSmall,
    Kind::MoveMesh,
    Kind::EntityMaterial,
];

impl Kind {
    /// The name on the command line and in tables.
    pub fn name(self) -> &'static str {
        match self {
            Self::Colour => "colour",
            Self::MoveSmall => "move-small",
            Self::MoveMesh => "move-mesh",
            Self::EntityMaterial => "entity-material",
        }
    }

    /// The kind named `name`.
    pub fn from_name(name: &str) -> Option<Self> {
        KINDS.into_iter().find(|k| k.name() == name)
    }
}

/// One edit: the whole text with the change.
#[derive(Clone, Debug)]
pub struct Edit {
    /// What kind.
    pub kind: Kind,
    /// What it changes, e.g. `material "red"` or `sphere "e500"`.
    pub target: String,
    /// The scene's text with the change.
    pub edited: String,
}

/// The largest number of candidates tried per kind (each try parses the whole text again).
const TRIES: usize = 4;

/// The edits of every kind that `text` (the scene at `path`) has a target for.
pub fn find_edits(path: &Path, text: &str) -> Result<Vec<Edit>, String> {
    let scene = parse_scene(path, text).map_err(|e| e.to_string())?;
    let locator = Locator::new(text);
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut edits = Vec::new();
    for kind in KINDS {
        let tries = candidates(kind, &scene, text, &locator, dir);
        for (target, which, edited) in tries.into_iter().take(TRIES) {
            let Ok(parsed) = parse_scene(path, &edited) else {
                continue;
            };
            if differs_only(&scene, &parsed, &which) {
                edits.push(Edit {
                    kind,
                    target,
                    edited,
                });
                break;
            }
        }
    }
    Ok(edits)
}

/// What an edit may change.
enum Which {
    Material(String),
    Entity(usize),
}

/// Candidate edits of `kind`, best first: a description, what it changes, the edited text.
fn candidates(
    kind: Kind,
    scene: &SceneDesc,
    text: &str,
    locator: &Locator,
    dir: &Path,
) -> Vec<(String, Which, String)> {
    let middle = scene.entities.len() / 2;
    let named = |i: usize| {
        scene.entities[i]
            .name
            .clone()
            .unwrap_or_else(|| format!("#{i}"))
    };
    let span = |i: usize| {
        let start = locator.entity(i)?;
        let end = closing(text, start + "Entity".len())?;
        Some((start, end))
    };
    let mut out = Vec::new();
    match kind {
        Kind::Colour => {
            let mut names: Vec<(usize, &String)> = scene
                .materials
                .keys()
                .filter_map(|n| Some((material_key(text, locator, n)?, n)))
                .collect();
            names.sort();
            for (at, name) in names {
                let value = skip_ws(text, at);
                let Some(open) = text[value..].find('(').map(|o| value + o) else {
                    continue;
                };
                let Some(end) = closing(text, open) else {
                    continue;
                };
                let triple = (open..end).find_map(|p| {
                    (text.as_bytes()[p] == b'(')
                        .then(|| first_of_triple(text, p))
                        .flatten()
                });
                if let Some((range, v)) = triple {
                    let new = if v >= 0.5 { v - 0.25 } else { v + 0.25 };
                    let edited = splice(text, range, &new.to_string());
                    out.push((
                        format!("material {name:?}"),
                        Which::Material(name.clone()),
                        edited,
                    ));
                }
            }
        }
        Kind::MoveSmall => {
            let mut spheres: Vec<(f32, usize, usize)> = scene
                .entities
                .iter()
                .enumerate()
                .filter_map(|(i, e)| match &e.shape {
                    Some(ShapeDesc::Analytic(Shape::Sphere { radius, .. })) => {
                        Some((*radius, i.abs_diff(middle), i))
                    }
                    _ => None,
                })
                .collect();
            spheres.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            for &(radius, _, i) in spheres.iter().take(TRIES) {
                let Some((start, end)) = span(i) else {
                    continue;
                };
                // The radius as written (an f32's shortest decimal), so the centre moves by it.
                let by = radius.to_string().parse().unwrap_or(1.0);
                if let Some(edited) = bump_key(text, start, end, "center", by) {
                    out.push((format!("sphere {:?}", named(i)), Which::Entity(i), edited));
                }
            }
            if out.is_empty() {
                for (i, _) in scene.entities.iter().enumerate().filter(|(_, e)| {
                    matches!(e.shape, Some(ShapeDesc::Analytic(_)))
                        && e.transform.is_some_and(|t| t.translate != glam::Vec3::ZERO)
                }) {
                    let Some((start, end)) = span(i) else {
                        continue;
                    };
                    if let Some(edited) = move_entity(text, start, end) {
                        out.push((format!("entity {:?}", named(i)), Which::Entity(i), edited));
                        if out.len() == TRIES {
                            break;
                        }
                    }
                }
            }
        }
        Kind::MoveMesh => {
            let mut meshes: Vec<(u64, usize)> = scene
                .entities
                .iter()
                .enumerate()
                .filter_map(|(i, e)| match &e.shape {
                    Some(ShapeDesc::Mesh { path }) => {
                        let size = std::fs::metadata(dir.join(path)).map_or(0, |m| m.len());
                        Some((size, i))
                    }
                    _ => None,
                })
                .collect();
            meshes.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
            for &(_, i) in meshes.iter().take(TRIES) {
                if let Some(edited) = span(i).and_then(|(start, end)| move_entity(text, start, end))
                {
                    out.push((
                        format!("mesh entity {:?}", named(i)),
                        Which::Entity(i),
                        edited,
                    ));
                }
            }
        }
        Kind::EntityMaterial => {
            let mut users: Vec<(usize, usize, &String)> = scene
                .entities
                .iter()
                .enumerate()
                .filter_map(|(i, e)| match (&e.shape, &e.material) {
                    (Some(_), Some(m)) => Some((i.abs_diff(middle), i, m)),
                    _ => None,
                })
                .collect();
            users.sort();
            for &(_, i, current) in users.iter().take(TRIES) {
                let Some(other) = scene.materials.keys().find(|k| *k != current) else {
                    break;
                };
                let Some((start, end)) = span(i) else {
                    continue;
                };
                let Some(at) = find_key(text, start, end, "material") else {
                    continue;
                };
                let open = skip_ws(text, at);
                let Some(close) = string_end(text, open) else {
                    continue;
                };
                let quoted = format!("\"{}\"", other.replace('\\', "\\\\").replace('"', "\\\""));
                out.push((
                    format!("entity {:?}: {current:?} → {other:?}", named(i)),
                    Which::Entity(i),
                    splice(text, open..close, &quoted),
                ));
            }
        }
    }
    out
}

/// Whether `b` differs from `a` in what `which` names and nowhere else in its materials and
/// entities.
fn differs_only(a: &SceneDesc, b: &SceneDesc, which: &Which) -> bool {
    if a.camera != b.camera
        || a.entities.len() != b.entities.len()
        || !a.materials.keys().eq(b.materials.keys())
    {
        return false;
    }
    let materials = a
        .materials
        .iter()
        .zip(&b.materials)
        .all(|((k, x), (_, y))| {
            let target = matches!(which, Which::Material(m) if m == k);
            (x == y) != target
        });
    let entities = a
        .entities
        .iter()
        .zip(&b.entities)
        .enumerate()
        .all(|(i, (x, y))| {
            let target = matches!(which, Which::Entity(t) if *t == i);
            same_entity(x, y) != target
        });
    materials && entities
}

fn same_entity(a: &EntityDesc, b: &EntityDesc) -> bool {
    a.name == b.name
        && a.material == b.material
        && a.shape == b.shape
        && a.prefab == b.prefab
        && a.gltf == b.gltf
        && a.materials == b.materials
        && a.transform == b.transform
}

/// The offset after the `:` of material `name`'s key (its string literal followed by a colon).
fn material_key(text: &str, locator: &Locator, name: &str) -> Option<usize> {
    [locator.first(name), locator.second(name)]
        .into_iter()
        .flatten()
        .find_map(|quote| {
            let close = string_end(text, quote)?;
            let colon = skip_ws(text, close);
            (text[colon..].starts_with(':')).then_some(colon + 1)
        })
}

/// `text` with `range` replaced by `with`.
fn splice(text: &str, range: std::ops::Range<usize>, with: &str) -> String {
    let mut s = String::with_capacity(text.len() + with.len());
    s.push_str(&text[..range.start]);
    s.push_str(with);
    s.push_str(&text[range.end..]);
    s
}

/// The first offset at or after `at` that is not whitespace.
fn skip_ws(text: &str, at: usize) -> usize {
    at + text[at..].len() - text[at..].trim_start().len()
}

/// The offset after the string literal whose opening quote is at `quote`.
fn string_end(text: &str, quote: usize) -> Option<usize> {
    let bytes = text.as_bytes();
    if bytes.get(quote) != Some(&b'"') {
        return None;
    }
    let mut i = quote + 1;
    while i < bytes.len() {
        match bytes[i] {
            b'\\' => i += 2,
            b'"' => return Some(i + 1),
            _ => i += 1,
        }
    }
    None
}

/// The offset of the `)` matching the `(` at `open`, skipping strings and comments.
fn closing(text: &str, open: usize) -> Option<usize> {
    let bytes = text.as_bytes();
    if bytes.get(open) != Some(&b'(') {
        return None;
    }
    let (mut depth, mut i) = (0usize, open);
    while i < bytes.len() {
        match bytes[i] {
            b'(' => depth += 1,
            b')' => {
                depth -= 1;
                if depth == 0 {
                    return Some(i);
                }
            }
            b'"' => {
                i = string_end(text, i)?;
                continue;
            }
            b'/' if bytes.get(i + 1) == Some(&b'/') => {
                i += text[i..].find('\n')?;
            }
            b'/' if bytes.get(i + 1) == Some(&b'*') => {
                i = block_comment_end(bytes, i)?;
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    None
}

/// The offset after the `:` of field `key` in `text[start..end]`: `key` as a whole word followed
/// by a colon. Comments and strings are not skipped: [`find_edits`] checks the result.
fn find_key(text: &str, start: usize, end: usize, key: &str) -> Option<usize> {
    let ident = |b: u8| b.is_ascii_alphanumeric() || b == b'_';
    let bytes = text.as_bytes();
    let mut from = start;
    while let Some(k) = text[from..end].find(key).map(|k| from + k) {
        from = k + key.len();
        if k > 0 && ident(bytes[k - 1]) || bytes.get(from).is_some_and(|&b| ident(b)) {
            continue;
        }
        let colon = skip_ws(text, from);
        if text[colon..].starts_with(':') {
            return Some(colon + 1);
        }
    }
    None
}

/// The range and value of the first number of a `(x, y, z)` opening at `open`.
fn first_of_triple(text: &str, open: usize) -> Option<(std::ops::Range<usize>, f64)> {
    let number = |at: usize| {
        let at = skip_ws(text, at);
        let len = text[at..]
            .find(|c: char| !(c.is_ascii_digit() || matches!(c, '.' | '-' | '+' | 'e' | 'E')))
            .unwrap_or(text.len() - at);
        let v: f64 = text[at..at + len].parse().ok()?;
        Some((at..at + len, v, skip_ws(text, at + len)))
    };
    let (range, v, after) = number(open + 1)?;
    let mut at = after;
    for _ in 0..2 {
        at = text[at..].starts_with(',').then_some(at + 1)?;
        at = number(at)?.2;
    }
    let at = if text[at..].starts_with(',') {
        skip_ws(text, at + 1)
    } else {
        at
    };
    text[at..].starts_with(')').then_some((range, v))
}

/// `text` with the first number of field `key`'s `(x, y, z)` in `text[start..end]` increased
/// by `by`.
fn bump_key(text: &str, start: usize, end: usize, key: &str, by: f64) -> Option<String> {
    let at = skip_ws(text, find_key(text, start, end, key)?);
    let (range, v) = first_of_triple(text, at)?;
    Some(splice(text, range, &(v + by).to_string()))
}

/// `text` with the entity spanning `text[start..=end]` moved: its translation's x increased by
/// 5 % (at least 0.01), or a translation added.
fn move_entity(text: &str, start: usize, end: usize) -> Option<String> {
    let translate = find_key(text, start, end, "translate")
        .map(|at| skip_ws(text, at))
        .and_then(|at| first_of_triple(text, at));
    if let Some((range, v)) = translate {
        return Some(splice(
            text,
            range,
            &(v + 0.05 * v.abs() + 0.01).to_string(),
        ));
    }
    if let Some(at) = find_key(text, start, end, "transform") {
        let open = skip_ws(text, at) + text[skip_ws(text, at)..end].find('(')?;
        return Some(splice(
            text,
            open + 1..open + 1,
            "translate: (0.01, 0, 0), ",
        ));
    }
    let open = start + "Entity".len();
    Some(splice(
        text,
        open + 1..open + 1,
        "transform: Transform(translate: (0.01, 0, 0)), ",
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    const SCENE: &str = r#"Scene(
    camera: Camera(position: (0, 1, -5), look_at: (0, 0, 0), fov: 40),
    materials: {
        "tex": Diffuse(albedo: Image(path: "t.png")), // no colour here
        "red": Diffuse(albedo: Constant((0.65, 0.05, 0.05))),
        "white": Diffuse(albedo: Constant((0.7, 0.7, 0.7))),
    },
    entities: [
        Entity(name: "big", material: "red", shape: Sphere(center: (0, 0, 0), radius: 2)),
        Entity(name: "small /* ) */", material: "white", shape: Sphere(center: (1, 0, 0), radius: 0.1)),
        Entity(name: "mesh", material: "white", shape: Mesh(path: "m.obj")),
        Entity(name: "box", material: "red", shape: Box(min: (0, 0, 0), max: (1, 1, 1)),
               transform: Transform(rotate: (0, 15, 0))),
    ],
)
"#;

    #[test]
    fn every_kind_is_found_and_changes_only_its_target() {
        let path = Path::new("scene.ron");
        let edits = find_edits(path, SCENE).expect("parses");
        let kinds: Vec<Kind> = edits.iter().map(|e| e.kind).collect();
        assert_eq!(kinds, KINDS);
        let target = |k: Kind| &edits.iter().find(|e| e.kind == k).expect("kind").target;
        assert_eq!(target(Kind::Colour), "material \"red\"");
        assert_eq!(target(Kind::MoveSmall), "sphere \"small /* ) */\"");
        assert_eq!(target(Kind::MoveMesh), "mesh entity \"mesh\"");
        let colour = &edits[0].edited;
        assert!(colour.contains("Constant((0.4, 0.05, 0.05))"), "{colour}");
        let moved = &edits[1].edited;
        assert!(moved.contains("center: (1.1, 0, 0)"), "{moved}");
        let mesh = &edits[2].edited;
        assert!(
            mesh.contains("Entity(transform: Transform(translate: (0.01, 0, 0)), name: \"mesh\""),
            "{mesh}"
        );
    }

    #[test]
    fn without_spheres_an_entity_with_a_translation_moves() {
        let scene = SCENE
            .replace(
                "Sphere(center: (0, 0, 0), radius: 2)",
                "Box(min: (0, 0, 0), max: (1, 1, 1))",
            )
            .replace(
                "Sphere(center: (1, 0, 0), radius: 0.1)",
                "Box(min: (0, 0, 0), max: (1, 1, 1))",
            )
            .replace(
                "rotate: (0, 15, 0)",
                "rotate: (0, 15, 0), translate: (100, 0, 0)",
            );
        let edits = find_edits(Path::new("scene.ron"), &scene).expect("parses");
        let moved = edits
            .iter()
            .find(|e| e.kind == Kind::MoveSmall)
            .expect("found");
        assert_eq!(moved.target, "entity \"box\"");
        assert!(moved.edited.contains("translate: (105.01, 0, 0)"));
    }

    #[test]
    fn a_scene_without_targets_has_no_edits() {
        let scene = "Scene(camera: Camera(position: (0, 0, -1), look_at: (0, 0, 0), fov: 40))";
        assert!(
            find_edits(Path::new("s.ron"), scene)
                .expect("parses")
                .is_empty()
        );
    }
}
