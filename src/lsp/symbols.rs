//! Document symbols for the editor's outline: the file's materials, then its entities, each
//! over its whole text, selected at its name.

use lsp_types::{DocumentSymbol, SymbolKind};

use super::documents::Document;
use super::outline::Outline;

/// The symbols of `doc`, whose outline is `outline`.
pub fn symbols(doc: &Document, outline: &Outline) -> Vec<DocumentSymbol> {
    let mut out = Vec::with_capacity(outline.materials.len() + outline.entities.len());
    for m in &outline.materials {
        out.push(symbol(
            doc,
            m.name.clone(),
            m.kind.clone().map(|k| format!("material {k}")),
            SymbolKind::CONSTANT,
            m.range.clone(),
            m.key.clone(),
        ));
    }
    for (i, e) in outline.entities.iter().enumerate() {
        let detail = match (&e.prefab, &e.gltf, &e.shape) {
            (Some((p, _)), _, _) => format!("prefab {p}"),
            (_, Some((g, _)), _) => format!("glTF {g}"),
            (_, _, Some(s)) => s.clone(),
            _ => String::new(),
        };
        let selection = e.name_token.clone().unwrap_or(e.range.start..e.range.start);
        out.push(symbol(
            doc,
            e.name.clone().unwrap_or_else(|| format!("#{i}")),
            Some(detail),
            SymbolKind::OBJECT,
            e.range.clone(),
            selection,
        ));
    }
    out
}

/// One symbol over bytes `range`, selected at `selection`.
#[expect(
    deprecated,
    reason = "`deprecated` is a required field of lsp-types' struct"
)]
fn symbol(
    doc: &Document,
    name: String,
    detail: Option<String>,
    kind: SymbolKind,
    range: std::ops::Range<usize>,
    selection: std::ops::Range<usize>,
) -> DocumentSymbol {
    // Clients reject an empty name.
    let name = if name.is_empty() { "\"\"".into() } else { name };
    DocumentSymbol {
        name,
        detail: detail.filter(|d| !d.is_empty()),
        kind,
        tags: None,
        deprecated: None,
        range: doc.range(range),
        selection_range: doc.range(selection),
        children: None,
    }
}
