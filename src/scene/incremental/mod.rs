//! Re-parsing a scene file after an edit: only the entities whose text changed.
//!
//! The last good parse is kept with the text it came from and the byte span of each entity of
//! its `entities` list. A new text is compared with it byte by byte from both ends; when
//! everything that differs lies within a run of whole entities of the old text, only that run,
//! as it now reads, is parsed (as a RON list) and spliced into the old description. Everything
//! else is byte-identical and was parsed in the same context (the list), so the result is what a
//! full parse gives. An edit wholly outside the list (a material, the camera, the settings) parses
//! the file with the list read as `[]` and keeps the entities, when the text around the list
//! still lexes on its own and still hands the list to `entities`. Whenever that cannot be shown cheaply (the edit touches text between
//! entities or outside the list, the run no longer parses as a list of whole entities, the file
//! uses RON `#![enable(…)]` attributes), the whole file is parsed, so errors keep their exact
//! `file:line:col`.

pub(super) mod lexer;
mod spans;
#[cfg(test)]
mod tests;

use std::ops::Range;
use std::path::{Path, PathBuf};

use self::lexer::{Lexeme, lex};
use self::spans::{Spans, entity_spans, list_items};
use super::error::SceneError;
use super::format::{EntityDesc, SceneDesc, parse};

/// A scene file's last good parse.
pub struct ParsedScene {
    path: PathBuf,
    text: String,
    desc: SceneDesc,
    /// Where the entities are in `text` (`None`: not found, so the next edit parses the whole
    /// file).
    spans: Option<Spans>,
}

impl ParsedScene {
    /// The parsed description.
    pub fn desc(&self) -> &SceneDesc {
        &self.desc
    }
}

/// Parses `text`, the contents of the scene file `path`, into `parsed`, reusing what it holds
/// (the last good parse of the same file) for the entities an edit left alone. Returns the
/// parse with the number of entities parsed. On an error `parsed` is left as it was, so the edit that mends a
/// broken save still starts from the last good parse.
pub fn parse_scene_text<'a>(
    path: &Path,
    text: String,
    parsed: &'a mut Option<ParsedScene>,
) -> Result<(&'a ParsedScene, usize), SceneError> {
    let mut previous = parsed.take();
    let spliced = match previous.as_mut().filter(|p| p.path == path) {
        Some(p) => splice(p, &text).or_else(|| splice_outside(p, &text)),
        None => None,
    };
    if let Some(n) = spliced
        && let Some(mut scene) = previous.take()
    {
        scene.text = text;
        return Ok((parsed.insert(scene), n));
    }
    let desc: SceneDesc = match parse(path, &text) {
        Ok(desc) => desc,
        Err(e) => {
            *parsed = previous;
            return Err(e);
        }
    };
    let spans = entity_spans(&text).filter(|s| s.entities.len() == desc.entities.len());
    let n = desc.entities.len();
    let scene = parsed.insert(ParsedScene {
        path: path.to_path_buf(),
        text,
        desc,
        spans,
    });
    Ok((scene, n))
}

/// Updates `previous` to `text` by re-parsing only the entities the edit touched and returns
/// how many it parsed, or returns `None`, changing nothing, when the edit is not confined to
/// whole entities (see the module's doc). The text itself is left for the caller to put in.
fn splice(previous: &mut ParsedScene, text: &str) -> Option<usize> {
    let Spans {
        entities: spans,
        list,
    } = previous.spans.as_ref()?;
    let (old, new) = (previous.text.as_bytes(), text.as_bytes());
    let (prefix, old_end) = changed(old, new);
    // The first entity that ends after the common prefix, and the last that starts before the
    // common suffix (for a pure insertion, before the byte after it): the edit must lie within
    // them.
    let first = spans.partition_point(|s| s.end <= prefix);
    let probe = old_end.max(prefix + 1);
    let last = spans.partition_point(|s| s.start < probe).checked_sub(1)?;
    if first > last || spans[first].start > prefix || spans[last].end < old_end {
        return None;
    }
    let start = spans[first].start;
    let end = (spans[last].end + new.len()).checked_sub(old.len())?;
    let run = text.get(start..end)?;
    // The run must read as whole entities separated by commas, nothing before, between or
    // after them but blanks and comments, so that the rest of the list reads as before.
    let items = list_items(run)?;
    let wrapped = format!("[{run}]");
    let entities: Vec<EntityDesc> = parse(&previous.path, &wrapped).ok()?;
    if entities.len() != items.len() || entities.is_empty() {
        return None;
    }
    let parsed = entities.len();
    let delta = new.len() as isize - old.len() as isize;
    let shift = |r: &Range<usize>| {
        let s = |x: usize| x.checked_add_signed(delta);
        Some(s(r.start)?..s(r.end)?)
    };
    let mut new_spans = Vec::with_capacity(spans.len() + items.len());
    new_spans.extend_from_slice(&spans[..first]);
    new_spans.extend(items.iter().map(|r| r.start + start..r.end + start));
    for r in &spans[last + 1..] {
        new_spans.push(shift(r)?);
    }
    let list = list.start..shift(list)?.end;
    previous.desc.entities.splice(first..=last, entities);
    previous.spans = Some(Spans {
        entities: new_spans,
        list,
    });
    Some(parsed)
}

/// The bytes of `old` that `new` changed: the length of their common prefix, and where the
/// common suffix starts in `old`.
fn changed(old: &[u8], new: &[u8]) -> (usize, usize) {
    let prefix = old.iter().zip(new).take_while(|(a, b)| a == b).count();
    let room = old.len().min(new.len()) - prefix;
    let suffix = old
        .iter()
        .rev()
        .zip(new.iter().rev())
        .take(room)
        .take_while(|(a, b)| a == b)
        .count();
    (prefix, old.len() - suffix)
}

/// Updates `previous` to `text` when the edit lies wholly before or after the entity list (a
/// material, the camera, the settings): the file is parsed with the list read as `[]`, and the
/// entities are kept. Returns 0 entities parsed, or `None`, changing nothing, unless the text
/// around the list still lexes on its own and still gives the list to `entities` at the scene's
/// top level (then the list's bytes read as before, in the same context).
fn splice_outside(previous: &mut ParsedScene, text: &str) -> Option<usize> {
    let spans = previous.spans.as_ref()?;
    let (old, new) = (previous.text.as_bytes(), text.as_bytes());
    let (prefix, old_end) = changed(old, new);
    let delta = new.len() as isize - old.len() as isize;
    let before = old_end <= spans.list.start;
    if !before && prefix < spans.list.end {
        return None;
    }
    let moved = |x: usize| {
        if before {
            x.checked_add_signed(delta)
        } else {
            Some(x)
        }
    };
    let list = moved(spans.list.start)?..moved(spans.list.end)?;
    let (head, tail) = (text.get(..list.start)?, text.get(list.end..)?);
    if head.contains("#!") || tail.contains("#!") {
        return None;
    }
    let lexemes = lex(head)?;
    lex(tail)?;
    // `entities` `:` at depth 1, right before the list.
    let [.., (_, Lexeme::Word(a, b)), (_, Lexeme::Colon)] = lexemes[..] else {
        return None;
    };
    let depth = lexemes.iter().fold(0isize, |d, (_, l)| match l {
        Lexeme::Open => d + 1,
        Lexeme::Close => d - 1,
        _ => d,
    });
    if &head[a..b] != "entities" || depth != 1 {
        return None;
    }
    let desc: SceneDesc = parse(&previous.path, &format!("{head}[]{tail}")).ok()?;
    if !desc.entities.is_empty() {
        return None;
    }
    let shifted = spans
        .entities
        .iter()
        .map(|r| Some(moved(r.start)?..moved(r.end)?))
        .collect::<Option<Vec<_>>>()?;
    let entities = std::mem::take(&mut previous.desc.entities);
    previous.desc = SceneDesc { entities, ..desc };
    previous.spans = Some(Spans {
        entities: shifted,
        list,
    });
    Some(0)
}
