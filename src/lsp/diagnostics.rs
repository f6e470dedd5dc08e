//! Diagnostics of an open buffer: the loader's error, or `rondo check`'s warnings, with the same
//! messages, at the same `file:line:col`, turned into LSP ranges.
//!
//! A scene buffer is loaded as [`crate::scene::load::load_scene_source`] loads any scene text,
//! with an [`AssetCache`] kept per document: like `watch`, a keystroke re-parses only the
//! entities it touched, and meshes, textures and glTF files are read again only when their files
//! change. A prefab buffer is parsed as a prefab; what the loads of the open scenes that place
//! it find in it (a material name it does not map, a field out of range) is shown in it too. An
//! open prefab buffer stands for its file in those loads, saved or not ([`Analysis::set_overlays`]).

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use lsp_types::{
    Diagnostic, DiagnosticRelatedInformation, DiagnosticSeverity, Location, NumberOrString,
};

use crate::scene::assets::AssetCache;
use crate::scene::check::check_scene;
use crate::scene::error::SceneError;
use crate::scene::format::{PrefabDesc, parse};
use crate::scene::load::{LoadedScene, load_scene_source};

use super::documents::Document;
use super::syntax::{Kind, tokens};

/// What is kept between analyses of one document.
pub struct Analysis {
    assets: AssetCache,
    /// The last scene that loaded from the buffer (for hovers that need the expanded scene).
    pub scene: Option<LoadedScene>,
    /// What the last load found in other files (the prefabs it placed), for their buffers.
    pub elsewhere: Vec<Finding>,
}

/// An error or warning of a scene's load located in another file than the scene's.
#[derive(Clone, Debug)]
pub struct Finding {
    /// The file it is in (as the loader named it).
    pub file: PathBuf,
    /// 1-based line and column in characters, when known.
    located: Option<(usize, usize)>,
    message: String,
    severity: DiagnosticSeverity,
    code: Option<NumberOrString>,
}

impl Finding {
    /// The diagnostic of this finding in `doc`, the open buffer of its file.
    pub fn in_buffer(&self, doc: &Document) -> Diagnostic {
        let range = match self.located {
            Some((line, col)) => token_at(&doc.text, doc.offset_of_line_col(line, col)),
            None => 0..0,
        };
        Diagnostic {
            range: doc.range(range),
            severity: Some(self.severity),
            code: self.code.clone(),
            source: Some("rondo".into()),
            message: self.message.clone(),
            ..Diagnostic::default()
        }
    }
}

impl Default for Analysis {
    fn default() -> Self {
        let mut assets = AssetCache::default();
        // Assets are trusted while their metadata is unchanged, and the server reports saves
        // ([`Analysis::files_changed`]), so a keystroke reads no mesh or texture again.
        assets.set_reported_changes(true);
        Self {
            assets,
            scene: None,
            elsewhere: Vec::new(),
        }
    }
}

impl Analysis {
    /// Files changed on disk (a save, a watched file): read every asset again at the next load.
    pub fn files_changed(&mut self) {
        self.assets.invalidate_all();
    }

    /// Loads of this scene read the texts of `overlays` (canonical paths) instead of those
    /// files: the editor's open prefab buffers.
    pub fn set_overlays(&mut self, overlays: HashMap<PathBuf, Arc<str>>) {
        self.assets.set_overlays(overlays);
    }

    /// The diagnostics of `doc`, a prefab buffer whose file is `path`: its parse error, else
    /// `found`, what the open scenes' loads found in it.
    pub fn diagnose_prefab(doc: &Document, path: &Path, found: &[Finding]) -> Vec<Diagnostic> {
        match parse::<PrefabDesc>(path, &doc.text) {
            Ok(_) => found.iter().map(|f| f.in_buffer(doc)).collect(),
            Err(e) => vec![error(doc, path, &e)],
        }
    }

    /// The diagnostics of `doc`, a scene buffer whose file is `path`; what the load finds in
    /// other files is kept in [`Analysis::elsewhere`].
    pub fn diagnose(&mut self, doc: &Document, path: &Path) -> Vec<Diagnostic> {
        self.elsewhere.clear();
        match load_scene_source(path, doc.text.clone(), &mut self.assets) {
            Err(e) => {
                if e.path != path {
                    self.elsewhere.push(Finding {
                        file: e.path.clone(),
                        located: e.location.map(|l| (l.line, l.col)),
                        message: e.message.clone(),
                        severity: DiagnosticSeverity::ERROR,
                        code: None,
                    });
                }
                vec![error(doc, path, &e)]
            }
            Ok(scene) => {
                let mut out: Vec<Diagnostic> = scene
                    .warnings
                    .iter()
                    .map(|w| Diagnostic {
                        range: doc.range(0..0),
                        severity: Some(DiagnosticSeverity::WARNING),
                        source: Some("rondo".into()),
                        message: w.clone(),
                        ..Diagnostic::default()
                    })
                    .collect();
                for w in check_scene(&scene) {
                    let located = w.location.map(|l| (l.line, l.col));
                    let code = Some(NumberOrString::String(format!("{:?}", w.kind)));
                    let mut d = at(doc, path, &w.path, located, &w.message, &w.to_string());
                    d.severity = Some(DiagnosticSeverity::WARNING);
                    d.code = code.clone();
                    out.push(d);
                    if w.path != path {
                        self.elsewhere.push(Finding {
                            file: w.path.clone(),
                            located,
                            message: w.message.clone(),
                            severity: DiagnosticSeverity::WARNING,
                            code,
                        });
                    }
                }
                self.scene = Some(scene);
                out
            }
        }
    }
}

/// The diagnostic of a load error.
fn error(doc: &Document, path: &Path, e: &SceneError) -> Diagnostic {
    let located = e.location.map(|l| (l.line, l.col));
    let mut d = at(doc, path, &e.path, located, &e.message, &e.to_string());
    d.severity = Some(DiagnosticSeverity::ERROR);
    d
}

/// A diagnostic about `file` at `located` (1-based line and column in characters): in the
/// buffer, over the token there, with `message`; in another file (a prefab, a mesh), at the
/// buffer's start with `full`, the `file:line:col: message` text, and that place as related
/// information.
fn at(
    doc: &Document,
    path: &Path,
    file: &Path,
    located: Option<(usize, usize)>,
    message: &str,
    full: &str,
) -> Diagnostic {
    if file == path {
        let range = match located {
            Some((line, col)) => token_at(&doc.text, doc.offset_of_line_col(line, col)),
            None => 0..0,
        };
        return Diagnostic {
            range: doc.range(range),
            source: Some("rondo".into()),
            message: message.to_string(),
            ..Diagnostic::default()
        };
    }
    let related = super::uri::from_path(file)
        .parse::<lsp_types::Uri>()
        .ok()
        .filter(|_| file.is_absolute())
        .map(|uri| {
            let (line, col) = located.unwrap_or((1, 1));
            let p = lsp_types::Position::new(
                line.saturating_sub(1) as u32,
                col.saturating_sub(1) as u32,
            );
            vec![DiagnosticRelatedInformation {
                location: Location {
                    uri,
                    range: lsp_types::Range::new(p, p),
                },
                message: message.to_string(),
            }]
        });
    Diagnostic {
        range: doc.range(0..0),
        source: Some("rondo".into()),
        message: full.to_string(),
        related_information: related,
        ..Diagnostic::default()
    }
}

/// The bytes of the token starting at `offset`: a whole string, word or number; one character
/// for a sign; nothing at the end of the text.
pub fn token_at(text: &str, offset: usize) -> std::ops::Range<usize> {
    let mut found = offset..offset;
    let rest = text.get(offset..).unwrap_or_default();
    tokens(rest, |t| {
        if t.start == 0 {
            let end = match t.kind {
                Kind::Other => {
                    // A number: digits, signs, dots and exponents run together.
                    let n = rest
                        .char_indices()
                        .find(|&(i, c)| {
                            i > 0
                                && !(c.is_ascii_alphanumeric()
                                    || matches!(c, '.' | '_' | '+' | '-'))
                        })
                        .map_or(rest.len(), |(i, _)| i);
                    n.max(t.end)
                }
                _ => t.end,
            };
            found = offset..offset + end;
        }
        false
    });
    found
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_token_is_a_whole_string_word_or_number() {
        let t = "x: \"whit\", y: 12.5e-3, Box(";
        let at = |s: &str| token_at(t, t.find(s).expect(s));
        assert_eq!(&t[at("\"whit\"")], "\"whit\"");
        assert_eq!(&t[at("12.5")], "12.5e-3");
        assert_eq!(&t[at("Box")], "Box");
        assert_eq!(&t[at("(")], "(");
        assert_eq!(token_at(t, t.len()), t.len()..t.len());
    }
}
