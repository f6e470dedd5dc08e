//! Hover: a material reference shows its definition; an entity its world bounds (from the last
//! scene that loaded from the buffer) and, for a prefab or glTF placement, the entities it
//! places.

use std::fmt::Write as _;
use std::path::Path;

use glam::Vec3;
use lsp_types::{Hover, HoverContents, MarkupContent, MarkupKind};

use super::documents::Document;
use super::outline::{Outline, outline};
use super::reference::{Reference, read_prefab, reference_at, resolve};
use super::syntax::context_at;
use crate::model::Shape;
use crate::scene::error::vector;
use crate::scene::load::{LoadedEntity, LoadedScene};

/// Most entities a placement's hover names.
const MAX_LISTED: usize = 20;
/// Longest definition shown, in bytes.
const MAX_SHOWN: usize = 2000;

/// The hover at byte `offset` of `doc` (the file `path`; outline `here`; `scene` the last scene
/// loaded from it).
pub fn hover(
    doc: &Document,
    path: Option<&Path>,
    here: &Outline,
    scene: Option<&LoadedScene>,
    offset: usize,
) -> Option<Hover> {
    let text = &doc.text;
    let context = context_at(text, offset);
    if let Some((reference, token)) = reference_at(text, here, &context, offset) {
        let shown = match reference {
            Reference::Material(name) => match here.material(&name) {
                Some(def) => code(&text[def.range.clone()]),
                None => format!(
                    "material \"{name}\" is not defined here (defined: {})",
                    here.materials
                        .iter()
                        .map(|m| m.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            },
            Reference::PrefabMaterial { prefab, name } => {
                let file = resolve(path?, &prefab);
                let source = read_prefab(&file)?;
                let there = outline(&source);
                match there.material(&name) {
                    Some(def) => format!("{}\n\nin {prefab}", code(&source[def.range.clone()])),
                    None => {
                        format!("\"{name}\" has no default in {prefab}: the placement must map it")
                    }
                }
            }
            Reference::File { value, .. } => {
                let file = resolve(path?, &value);
                match std::fs::metadata(&file) {
                    Ok(m) => format!("`{}` ({} bytes)", file.display(), m.len()),
                    Err(e) => format!("`{}`: {e}", file.display()),
                }
            }
        };
        return Some(markdown(shown, doc.range(token.start..token.end)));
    }
    let entity = here.entity_at(offset)?;
    let name = entity.name.clone()?;
    let mut shown = format!("entity \"{name}\"");
    let scene = scene.filter(|s| Some(s.path.as_path()) == path && !here.is_prefab());
    let prefix = format!("{name}/");
    let placed: Vec<&LoadedEntity> = scene
        .map(|s| {
            s.entities
                .iter()
                .filter(|e| e.name == name || e.name.starts_with(&prefix))
                .collect()
        })
        .unwrap_or_default();
    if let Some(bounds) = placed.iter().map(|e| world_bounds(e)).reduce(union) {
        match bounds {
            Some((lo, hi)) => {
                let _ = write!(
                    shown,
                    "\n\nworld bounds: min {} max {}",
                    vector(lo),
                    vector(hi)
                );
            }
            None => shown.push_str("\n\nworld bounds: unbounded (an infinite plane)"),
        }
    }
    if entity.prefab.is_some() || entity.gltf.is_some() {
        let names: Vec<String> = if placed.is_empty() {
            // Not loaded: the prefab's own top-level entities, as written.
            let written = entity.prefab.as_ref().map(|p| p.0.as_str());
            written
                .and_then(|p| read_prefab(&resolve(path?, p)))
                .map(|t| {
                    outline(&t)
                        .entities
                        .into_iter()
                        .filter_map(|e| e.name)
                        .map(|n| format!("{prefix}{n}"))
                        .collect()
                })
                .unwrap_or_default()
        } else {
            placed.iter().map(|e| e.name.clone()).collect()
        };
        let _ = write!(
            shown,
            "\n\nplaces {} entit{}",
            names.len(),
            if names.len() == 1 { "y" } else { "ies" }
        );
        for n in names.iter().take(MAX_LISTED) {
            let _ = write!(shown, "\n- `{n}`");
        }
        if names.len() > MAX_LISTED {
            let _ = write!(shown, "\n- … {} more", names.len() - MAX_LISTED);
        }
    }
    let range = entity.name_token.clone().unwrap_or(entity.range.clone());
    Some(markdown(shown, doc.range(range)))
}

/// `text` as a RON code block (at most [`MAX_SHOWN`] bytes of it).
fn code(text: &str) -> String {
    let mut end = text.len().min(MAX_SHOWN);
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    let cut = if end < text.len() { "\n…" } else { "" };
    format!("```ron\n{}{cut}\n```", &text[..end])
}

/// A Markdown hover over `range`.
fn markdown(value: String, range: lsp_types::Range) -> Hover {
    Hover {
        contents: HoverContents::Markup(MarkupContent {
            kind: MarkupKind::Markdown,
            value,
        }),
        range: Some(range),
    }
}

/// Union of two bounds (`None` is unbounded).
fn union(a: Option<(Vec3, Vec3)>, b: Option<(Vec3, Vec3)>) -> Option<(Vec3, Vec3)> {
    a.zip(b)
        .map(|((l0, h0), (l1, h1))| (l0.min(l1), h0.max(h1)))
}

/// The world-space box of an entity's shape placed by its transform (`None` for a plane); a
/// mesh's from all its vertices.
pub fn world_bounds(e: &LoadedEntity) -> Option<(Vec3, Vec3)> {
    let m = e.transform.0;
    let fold = |points: &mut dyn Iterator<Item = Vec3>| {
        points.fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| {
                let p = m.transform_point3(p);
                (lo.min(p), hi.max(p))
            },
        )
    };
    Some(match &e.shape {
        Shape::Sphere { center, radius } => {
            let c = m.transform_point3(*center);
            let r = Vec3::splat(radius * e.transform.uniform_scale());
            (c - r, c + r)
        }
        Shape::Plane { .. } => return None,
        Shape::Triangle { a, b, c } => fold(&mut [*a, *b, *c].into_iter()),
        Shape::Quad { a, b, c, d } => fold(&mut [*a, *b, *c, *d].into_iter()),
        Shape::Box { min, max } => fold(&mut (0..8).map(|k| {
            Vec3::new(
                if k & 1 == 0 { min.x } else { max.x },
                if k & 2 == 0 { min.y } else { max.y },
                if k & 4 == 0 { min.z } else { max.z },
            )
        })),
        Shape::Mesh(mesh) => fold(&mut mesh.data.positions.iter().copied()),
    })
}
