//! Picking in the viewer: the routes that say which entity each pixel shows and where it comes
//! from, for the page (`pick.js`) and for other tools.
//!
//! | route | content |
//! |---|---|
//! | `GET /pick.js` | the page's picking code (compiled in) |
//! | `GET /pick/ids.u32` | the id buffer (see [`IDS_MAGIC`]) |
//! | `GET /pick/table.json` | every entity: `{"reload": 3, "entities": [entry, …]}`, entry `i` of id `i` |
//! | `GET /pick/entity.json?id=N` | the entry of id `N` alone (`404` for an unknown id or the sky) |
//!
//! Until the first scene is rendered they answer `503`. An entry:
//!
//! ```text
//! {"id":4,"name":"tall/top","material":"surface",
//!  "entity":{"path":"/abs/prefabs/box.ron","line":7,"column":20,"url":"vscode://file/…:7:20"},
//!  "material_at":{"path":"/abs/prefabs/box.ron","line":3,"column":9},
//!  "chain":[{"name":"tall","kind":"prefab","file":"/abs/prefabs/box.ron",
//!            "at":{"path":"/abs/scene.ron","line":11,"column":23}}]}
//! ```
//!
//! `chain` lists the placements outermost first (`kind` is `prefab` or `gltf`); a place's `line`
//! and `column` are `null` where unknown (a glTF file's node or material); `url` is there only
//! with `watch --editor-url` (see [`parse_editor_url`]). Entries are located on the first
//! question after each reload ([`crate::scene::provenance`]), the table and the ids encoded
//! on their first request.

use std::io::Write;
use std::sync::OnceLock;

use serde_json::{Value, json};

use super::http;
use crate::scene::provenance::{Entry, Place};
use crate::watch::Picked;

/// The first 8 bytes of `/pick/ids.u32`. Then three little-endian `u32`: width, height and
/// reload number (low 32 bits); then `width × height` little-endian `u32` ids, rows from the
/// top: an entity's index in the scene's expansion order (the table's entry), or
/// [`crate::render::pick::SKY`] (`4294967295`) where the ray hits nothing. 20 bytes of header
/// keep the ids 4-byte aligned for a `Uint32Array` view.
pub const IDS_MAGIC: &[u8; 8] = b"RONDOIDS";

/// The page's picking code.
const SCRIPT: &str = include_str!("pick.js");

/// Longest `--editor-url` template accepted, in bytes.
pub const MAX_EDITOR_URL: usize = 1024;

/// Checks the argument of `--editor-url`: a URL template with `{path}` (and optionally
/// `{line}` and `{col}`), e.g. `vscode://file/{path}:{line}:{col}`, of a scheme that opens an
/// application (not `javascript:`, `data:`, `vbscript:` or `blob:`), without spaces or control
/// characters, at most [`MAX_EDITOR_URL`] bytes.
pub fn parse_editor_url(text: &str) -> Result<String, String> {
    let scheme = text.split_once(':').map(|(s, _)| s).unwrap_or_default();
    let scheme_ok = scheme.starts_with(|c: char| c.is_ascii_alphabetic())
        && scheme
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c));
    let refused = ["javascript", "data", "vbscript", "blob"]
        .iter()
        .any(|s| s.eq_ignore_ascii_case(scheme));
    if text.len() > MAX_EDITOR_URL {
        Err(format!("longer than {MAX_EDITOR_URL} bytes"))
    } else if !scheme_ok || refused {
        Err(format!(
            "{text:?} does not start with a scheme that opens an editor (e.g. vscode://file/{{path}}:{{line}}:{{col}})"
        ))
    } else if !text.contains("{path}") {
        Err(format!("{text:?} has no {{path}}"))
    } else if text.chars().any(|c| c.is_control() || c.is_whitespace()) {
        Err(format!("{text:?} holds spaces or control characters"))
    } else {
        Ok(text.to_string())
    }
}

/// The link of a place: `template` with `{path}` (percent-encoded but for `/` and `:`),
/// `{line}` and `{col}` (1 where unknown) filled in.
fn link(template: &str, place: &Place) -> String {
    let mut path = String::new();
    for b in place.path.to_string_lossy().bytes() {
        if b.is_ascii_alphanumeric() || b"/:-._~".contains(&b) {
            path.push(b as char);
        } else {
            path.push_str(&format!("%{b:02X}"));
        }
    }
    let (line, col) = place.location.map_or((1, 1), |l| (l.line, l.col));
    template
        .replace("{path}", &path)
        .replace("{line}", &line.to_string())
        .replace("{col}", &col.to_string())
}

/// A place as JSON.
fn place_json(place: &Place, editor_url: Option<&str>) -> Value {
    let mut v = json!({
        "path": place.path.display().to_string(),
        "line": place.location.map(|l| l.line),
        "column": place.location.map(|l| l.col),
    });
    if let Some(template) = editor_url {
        v["url"] = Value::String(link(template, place));
    }
    v
}

/// An entry as JSON.
fn entry_json(id: usize, entry: &Entry, editor_url: Option<&str>) -> Value {
    let chain: Vec<Value> = entry
        .chain
        .iter()
        .map(|l| {
            json!({
                "name": l.name,
                "kind": if l.gltf { "gltf" } else { "prefab" },
                "file": l.file.display().to_string(),
                "at": place_json(&l.at, editor_url),
            })
        })
        .collect();
    json!({
        "id": id,
        "name": entry.name,
        "material": entry.material,
        "entity": place_json(&entry.entity, editor_url),
        "material_at": place_json(&entry.material_at, editor_url),
        "chain": chain,
    })
}

/// The latest ids and provenance, with their encodings made on first request.
pub struct Picks {
    picked: Picked,
    ids: OnceLock<Vec<u8>>,
    table: OnceLock<Vec<u8>>,
}

impl Picks {
    /// Keeps `picked`; nothing is encoded yet.
    pub fn new(picked: Picked) -> Self {
        Self {
            picked,
            ids: OnceLock::new(),
            table: OnceLock::new(),
        }
    }

    /// The `pick` event that announces them.
    pub fn event(&self) -> Value {
        let p = &self.picked;
        json!({
            "kind": "pick",
            "reload": p.reload,
            "width": p.ids.width,
            "height": p.ids.height,
            "entities": p.provenance.len(),
        })
    }

    /// The id buffer's encoding (see [`IDS_MAGIC`]).
    fn ids(&self) -> &[u8] {
        self.ids.get_or_init(|| {
            let b = &self.picked.ids;
            let mut out = Vec::with_capacity(20 + 4 * b.ids.len());
            out.extend_from_slice(IDS_MAGIC);
            // The reload's low 32 bits, as documented.
            for v in [b.width, b.height, self.picked.reload as u32] {
                out.extend_from_slice(&v.to_le_bytes());
            }
            for id in &b.ids {
                out.extend_from_slice(&id.to_le_bytes());
            }
            out
        })
    }

    /// The whole table as JSON bytes (the editor URL is fixed for the server's life).
    fn table(&self, editor_url: Option<&str>) -> &[u8] {
        self.table.get_or_init(|| {
            let provenance = &self.picked.provenance;
            let entities: Vec<Value> = (0..provenance.len())
                .filter_map(|id| Some(entry_json(id, &provenance.entry(id)?, editor_url)))
                .collect();
            json!({ "reload": self.picked.reload, "entities": entities })
                .to_string()
                .into_bytes()
        })
    }

    /// The entry of `id` as JSON bytes, if there is one.
    fn entry(&self, id: usize, editor_url: Option<&str>) -> Option<Vec<u8>> {
        let entry = self.picked.provenance.entry(id)?;
        Some(entry_json(id, &entry, editor_url).to_string().into_bytes())
    }
}

/// The picking routes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Route {
    /// `/pick.js`.
    Script,
    /// `/pick/ids.u32`, `/pick/table.json` or `/pick/entity.json`.
    Data(Data),
}

/// The routes of the latest ids and provenance.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Data {
    /// `/pick/ids.u32`.
    Ids,
    /// `/pick/table.json`.
    Table,
    /// `/pick/entity.json`.
    Entity,
}

impl Route {
    /// The route of a path (query removed), matched exactly.
    pub fn of(path: &str) -> Option<Self> {
        Some(match path {
            "/pick.js" => Self::Script,
            "/pick/ids.u32" => Self::Data(Data::Ids),
            "/pick/table.json" => Self::Data(Data::Table),
            "/pick/entity.json" => Self::Data(Data::Entity),
            _ => return None,
        })
    }
}

/// The `id` of a query string `…?id=N` (decimal digits only, at most 10 of them).
fn query_id(target: &str) -> Option<usize> {
    let (_, query) = target.split_once('?')?;
    let value = query.split('&').find_map(|kv| kv.strip_prefix("id="))?;
    if value.is_empty() || value.len() > 10 || !value.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    value.parse().ok()
}

/// Answers a picking route: `target` is the request's (for the query), `picks` the latest.
pub fn answer(
    stream: &mut impl Write,
    route: Route,
    target: &str,
    picks: Option<&Picks>,
    editor_url: Option<&str>,
    with_body: bool,
) -> std::io::Result<()> {
    const JSON: &str = "application/json";
    let data = match route {
        Route::Script => {
            return http::respond(
                stream,
                200,
                &[("Content-Type", "text/javascript; charset=utf-8")],
                SCRIPT.as_bytes(),
                with_body,
            );
        }
        Route::Data(data) => data,
    };
    let Some(picks) = picks else {
        return http::respond_text(stream, 503, "no scene rendered yet\n", with_body);
    };
    let reload = picks.picked.reload.to_string();
    let respond = |stream: &mut _, content_type, body: &[u8]| {
        http::respond(
            stream,
            200,
            &[("Content-Type", content_type), ("X-Rondo-Reload", &reload)],
            body,
            with_body,
        )
    };
    match data {
        Data::Ids => respond(stream, "application/octet-stream", picks.ids()),
        Data::Table => respond(stream, JSON, picks.table(editor_url)),
        Data::Entity => match query_id(target).and_then(|id| picks.entry(id, editor_url)) {
            Some(body) => respond(stream, JSON, &body),
            None => http::respond_text(stream, 404, "no entity of that id\n", with_body),
        },
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::scene::error::Location;

    #[test]
    fn editor_urls_open_applications_only() {
        for ok in [
            "vscode://file/{path}:{line}:{col}",
            "idea://open?file={path}&line={line}",
            "subl://open?url=file://{path}&line={line}",
        ] {
            assert_eq!(parse_editor_url(ok).as_deref(), Ok(ok));
        }
        for bad in [
            "javascript:alert('{path}')",
            "JavaScript:x{path}",
            "data:text/html,{path}",
            "vbscript:{path}",
            "vscode://file/{line}",
            "{path}",
            "1x://{path}",
            "vscode://file/ {path}",
            "vscode://file/\n{path}",
            &format!("vscode://{}{{path}}", "x".repeat(MAX_EDITOR_URL)),
        ] {
            assert!(parse_editor_url(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn links_fill_the_template_and_escape_the_path() {
        let place = Place {
            path: Path::new("/tmp/a b/scène#1.ron"),
            location: Some(Location { line: 7, col: 20 }),
        };
        assert_eq!(
            link("vscode://file/{path}:{line}:{col}", &place),
            "vscode://file//tmp/a%20b/sc%C3%A8ne%231.ron:7:20"
        );
        let nowhere = Place {
            location: None,
            ..place
        };
        assert!(link("x://{path}@{line}.{col}", &nowhere).ends_with("@1.1"));
    }

    #[test]
    fn ids_come_from_the_query_as_decimal_numbers() {
        assert_eq!(query_id("/pick/entity.json?id=42"), Some(42));
        assert_eq!(query_id("/pick/entity.json?t=1&id=0"), Some(0));
        for bad in [
            "/pick/entity.json",
            "/pick/entity.json?id=",
            "/pick/entity.json?id=-1",
            "/pick/entity.json?id=1e3",
            "/pick/entity.json?id=99999999999",
            "/pick/entity.json?id=+1",
        ] {
            assert_eq!(query_id(bad), None, "{bad}");
        }
    }

    #[test]
    fn routes_match_whole_paths_only() {
        assert_eq!(Route::of("/pick/ids.u32"), Some(Route::Data(Data::Ids)));
        assert_eq!(Route::of("/pick.js"), Some(Route::Script));
        for bad in [
            "/pick",
            "/pick/",
            "/pick/ids.u32/",
            "//pick/ids.u32",
            "/PICK.JS",
        ] {
            assert_eq!(Route::of(bad), None, "{bad}");
        }
    }
}
