//! Completion at the cursor: material names in a material string, the names a placed prefab
//! takes in a placement's `materials` keys, files in a `prefab`, `gltf` or `path` string, and
//! outside strings the fields of the struct the cursor is in or the kinds its value can be
//! (shapes, materials, textures, …, from [`super::probe`]).

use std::path::Path;

use lsp_types::{CompletionItem, CompletionItemKind, CompletionTextEdit, TextEdit};

use super::documents::Document;
use super::outline::{Outline, outline};
use super::probe::{Slot, expected};
use super::reference::{Reference, read_prefab, reference_at, resolve};
use super::syntax::{Kind, context_at};

/// Most items returned, and most directory entries read for path completion.
pub const MAX_ITEMS: usize = 1000;

/// The completions at byte `offset` of `doc` (whose file is `path`, if it has one, and whose
/// outline is `here`).
pub fn completion(
    doc: &Document,
    path: Option<&Path>,
    here: &Outline,
    offset: usize,
) -> Vec<CompletionItem> {
    let text = &doc.text;
    let context = context_at(text, offset);
    let Some(token) = context.token else {
        return words(doc, here, &context.frames, offset..offset);
    };
    match token.kind {
        Kind::Word => words(doc, here, &context.frames, token.start..offset),
        Kind::Str { .. } => {
            let Some((reference, token)) = reference_at(text, here, &context, offset) else {
                return Vec::new();
            };
            let replace = token.contents();
            match reference {
                Reference::Material(_) => names(doc, material_names(here), replace),
                Reference::PrefabMaterial { prefab, .. } => {
                    let Some(prefab) = path.and_then(|p| read_prefab(&resolve(p, &prefab))) else {
                        return Vec::new();
                    };
                    names(doc, material_names(&outline(&prefab)), replace)
                }
                Reference::File { key, holder, .. } => {
                    let typed = text.get(replace.start..offset).unwrap_or_default();
                    match path {
                        Some(p) => files(doc, p, typed, extensions(&key, &holder), replace),
                        None => Vec::new(),
                    }
                }
            }
        }
        _ => Vec::new(),
    }
}

/// The material names a file gives: its `materials`, then (for a prefab, whose placements may
/// map them) the other names its entities use.
fn material_names(o: &Outline) -> Vec<String> {
    let mut out: Vec<String> = o.materials.iter().map(|m| m.name.clone()).collect();
    if o.is_prefab() {
        for name in o.used_materials() {
            if !name.is_empty() && !out.iter().any(|n| n == name) {
                out.push(name.to_string());
            }
        }
    }
    out
}

/// Items replacing bytes `replace` with each of `names`.
fn names(
    doc: &Document,
    names: Vec<String>,
    replace: std::ops::Range<usize>,
) -> Vec<CompletionItem> {
    names
        .into_iter()
        .take(MAX_ITEMS)
        .map(|n| {
            item(
                doc,
                n.clone(),
                n,
                CompletionItemKind::VALUE,
                replace.clone(),
            )
        })
        .collect()
}

/// Field names or kinds at a place outside strings, replacing the word being typed.
fn words(
    doc: &Document,
    here: &Outline,
    frames: &[super::syntax::Frame],
    replace: std::ops::Range<usize>,
) -> Vec<CompletionItem> {
    let Some(top) = frames.last() else {
        return Vec::new();
    };
    let (slot, kind) = if top.open == b'(' && !top.value {
        (Slot::Field, CompletionItemKind::FIELD)
    } else {
        (Slot::Value, CompletionItemKind::ENUM_MEMBER)
    };
    expected(&doc.text, frames, slot, here.is_prefab())
        .into_iter()
        .map(|w| item(doc, w.to_string(), w.to_string(), kind, replace.clone()))
        .collect()
}

/// The file extensions a path field takes (empty: any).
fn extensions(key: &str, holder: &str) -> &'static [&'static str] {
    match (key, holder) {
        ("prefab", _) => &["ron"],
        ("gltf", _) => &["gltf", "glb"],
        (_, "Mesh") => &["obj"],
        (_, "Image" | "NormalMap") => &["png", "jpg", "jpeg", "exr", "hdr"],
        (_, "Environment") => &["exr", "hdr"],
        _ => &[],
    }
}

/// The folders and files (of `exts`) in the folder of `typed`, a path relative to the file
/// `doc_path` being typed, each replacing bytes `replace` with its whole path.
fn files(
    doc: &Document,
    doc_path: &Path,
    typed: &str,
    exts: &[&str],
    replace: std::ops::Range<usize>,
) -> Vec<CompletionItem> {
    let folder = typed.rfind('/').map_or("", |i| &typed[..=i]);
    let Ok(entries) = std::fs::read_dir(resolve(doc_path, folder)) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for entry in entries.take(MAX_ITEMS).flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.starts_with('.') {
            continue;
        }
        let dir = entry.path().is_dir();
        let wanted = dir
            || exts.is_empty()
            || Path::new(&name)
                .extension()
                .is_some_and(|x| exts.iter().any(|e| x.eq_ignore_ascii_case(e)));
        if !wanted {
            continue;
        }
        let (label, kind) = if dir {
            (format!("{name}/"), CompletionItemKind::FOLDER)
        } else {
            (name, CompletionItemKind::FILE)
        };
        out.push(item(
            doc,
            label.clone(),
            format!("{folder}{label}"),
            kind,
            replace.clone(),
        ));
    }
    out.sort_by(|a, b| a.label.cmp(&b.label));
    out
}

/// An item shown as `label` that replaces bytes `replace` with `new_text`.
fn item(
    doc: &Document,
    label: String,
    new_text: String,
    kind: CompletionItemKind,
    replace: std::ops::Range<usize>,
) -> CompletionItem {
    CompletionItem {
        label,
        kind: Some(kind),
        filter_text: Some(new_text.clone()),
        text_edit: Some(CompletionTextEdit::Edit(TextEdit::new(
            doc.range(replace),
            new_text,
        ))),
        ..CompletionItem::default()
    }
}
