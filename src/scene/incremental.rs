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

use std::ops::Range;
use std::path::{Path, PathBuf};

use super::error::SceneError;
use super::format::{EntityDesc, SceneDesc, parse};
use super::locate::{block_comment_end, raw_string};

/// A scene file's last good parse.
pub struct ParsedScene {
    path: PathBuf,
    text: String,
    desc: SceneDesc,
    /// Where the entities are in `text` (`None`: not found, so the next edit parses the whole
    /// file).
    spans: Option<Spans>,
}

/// Where a scene file's entities are written.
#[derive(Clone, Debug, PartialEq)]
struct Spans {
    /// Byte span of each entity of the list.
    entities: Vec<Range<usize>>,
    /// Byte span of the list, from its `[` to just after its `]`.
    list: Range<usize>,
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

/// One significant lexical item of RON text: blanks, comments and the insides of strings and
/// characters are skipped.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Lexeme {
    /// `(`, `[` or `{`.
    Open,
    /// `)`, `]` or `}`.
    Close,
    Comma,
    Colon,
    /// An identifier (its text's range).
    Word(usize, usize),
    /// Anything else: a number, a string, a character, another sign.
    Other,
}

/// Calls `each` with every lexeme of `text` and its byte offset, until it returns `false`;
/// `None` for text that does not lex (an unterminated string, comment or character). Nothing is
/// collected, so a scan of a big file allocates nothing.
fn lex_each(text: &str, mut each: impl FnMut(usize, Lexeme) -> bool) -> Option<()> {
    let b = text.as_bytes();
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        let at = i;
        match c {
            b' ' | b'\t' | b'\n' | b'\r' => i += 1,
            b'/' if b.get(i + 1) == Some(&b'/') => {
                i = b[i..]
                    .iter()
                    .position(|&c| c == b'\n')
                    .map_or(b.len(), |p| i + p);
            }
            b'/' if b.get(i + 1) == Some(&b'*') => i = block_comment_end(b, i)?,
            b'"' => {
                i = quoted(b, i + 1, b'"')?;
                if !each(at, Lexeme::Other) {
                    return Some(());
                }
            }
            b'\'' => {
                i = quoted(b, i + 1, b'\'')?;
                if !each(at, Lexeme::Other) {
                    return Some(());
                }
            }
            b'(' | b'[' | b'{' => {
                i += 1;
                if !each(at, Lexeme::Open) {
                    return Some(());
                }
            }
            b')' | b']' | b'}' => {
                i += 1;
                if !each(at, Lexeme::Close) {
                    return Some(());
                }
            }
            b',' => {
                i += 1;
                if !each(at, Lexeme::Comma) {
                    return Some(());
                }
            }
            b':' => {
                i += 1;
                if !each(at, Lexeme::Colon) {
                    return Some(());
                }
            }
            c if c.is_ascii_alphabetic() || c == b'_' => {
                while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                    i += 1;
                }
                let word = &b[at..i];
                // Raw strings `r"…"`, `r#"…"#` and byte strings `b"…"`, `br#"…"#`.
                if matches!(word, b"r" | b"br") && matches!(b.get(i), Some(b'"' | b'#')) {
                    i = raw_string(b, i).filter(|r| r.closed)?.end;
                    if !each(at, Lexeme::Other) {
                        return Some(());
                    }
                } else if word == b"b" && b.get(i) == Some(&b'"') {
                    i = quoted(b, i + 1, b'"')?;
                    if !each(at, Lexeme::Other) {
                        return Some(());
                    }
                } else {
                    if !each(at, Lexeme::Word(at, i)) {
                        return Some(());
                    }
                }
            }
            _ => {
                // Numbers, signs and any other character (a multi-byte one whole).
                i += 1;
                while i < b.len() && b[i] & 0xC0 == 0x80 {
                    i += 1;
                }
                if !each(at, Lexeme::Other) {
                    return Some(());
                }
            }
        }
    }
    Some(())
}

/// The lexemes of `text` with their byte offsets, or `None` for text that does not lex (for the
/// small texts an edit touches).
fn lex(text: &str) -> Option<Vec<(usize, Lexeme)>> {
    let mut out = Vec::new();
    lex_each(text, |at, l| {
        out.push((at, l));
        true
    })?;
    Some(out)
}

/// The offset past the closing `quote` of a string or character whose contents start at `i`
/// (backslash escapes skipped), or `None` if it is not closed.
fn quoted(b: &[u8], mut i: usize, quote: u8) -> Option<usize> {
    while i < b.len() {
        match b[i] {
            b'\\' => i += 2,
            c if c == quote => return Some(i + 1),
            _ => i += 1,
        }
    }
    None
}

/// Spans of the items of a comma-separated run of values at depth 0 (`Entity(…)` or `(…)`),
/// each from its first byte to past its closing bracket; `None` unless the run is exactly such
/// items, one comma between each two and none before the first or after the last.
fn list_items(run: &str) -> Option<Vec<Range<usize>>> {
    let lexemes = lex(run)?;
    let mut items = Vec::new();
    let mut k = 0;
    loop {
        let (start, end, next) = value(run, &lexemes, k)?;
        items.push(start..end);
        match lexemes.get(next) {
            None => return Some(items),
            Some((_, Lexeme::Comma)) if next + 1 < lexemes.len() => k = next + 1,
            _ => return None,
        }
    }
}

/// The entity value starting at lexeme `k`: `Entity(…)` or `(…)`, as (start offset, end offset,
/// index of the next lexeme).
fn value(text: &str, lexemes: &[(usize, Lexeme)], mut k: usize) -> Option<(usize, usize, usize)> {
    let start = lexemes.get(k)?.0;
    if let (_, Lexeme::Word(a, b)) = lexemes[k] {
        if text.get(a..b) != Some("Entity") {
            return None;
        }
        k += 1;
    }
    if lexemes.get(k)?.1 != Lexeme::Open {
        return None;
    }
    let mut depth = 0usize;
    while let Some(&(at, l)) = lexemes.get(k) {
        k += 1;
        match l {
            Lexeme::Open => depth += 1,
            Lexeme::Close => {
                depth -= 1;
                if depth == 0 {
                    return Some((start, at + 1, k));
                }
            }
            _ => {}
        }
    }
    None
}

/// Spans of the entities of a scene text's `entities` list and of the list itself, or `None` if
/// the text uses RON attributes or its list is not found as expected. One pass over the
/// lexemes, none kept: `entities` `:` `[` at depth 1 of the scene's parentheses (once), then
/// `Entity(…)` or `(…)` items separated by commas up to the list's `]`.
fn entity_spans(text: &str) -> Option<Spans> {
    /// Where the scan stands.
    #[derive(Clone, Copy)]
    enum Phase {
        /// Before the list, looking for `entities`.
        Seek,
        /// After `entities`, before `:`.
        Word,
        /// After `entities :`, before `[`.
        Colon,
        /// In the list, where an item or its `]` may start.
        Item,
        /// After `Entity` (its offset), before `(`.
        Named(usize),
        /// Inside an item that started at this offset.
        Inside(usize),
        /// After an item, before `,` or `]`.
        After,
        /// After the list: the rest must not name `entities` again.
        Done,
    }
    if text.contains("#!") {
        return None;
    }
    let (mut phase, mut depth, mut list_at) = (Phase::Seek, 0usize, 0);
    let (mut entities, mut list, mut good) = (Vec::new(), None, true);
    lex_each(text, |at, l| {
        let level = depth;
        match l {
            Lexeme::Open => depth += 1,
            Lexeme::Close => match depth.checked_sub(1) {
                Some(d) => depth = d,
                None => {
                    good = false;
                    return false;
                }
            },
            _ => {}
        }
        let entities_word =
            matches!(l, Lexeme::Word(a, b) if level == 1 && &text[a..b] == "entities");
        phase = match (phase, l) {
            (Phase::Seek, _) if entities_word => Phase::Word,
            (Phase::Done, _) if entities_word => {
                good = false;
                return false;
            }
            (p @ (Phase::Seek | Phase::Done), _) => p,
            (Phase::Word, Lexeme::Colon) => Phase::Colon,
            (Phase::Colon, Lexeme::Open) => {
                list_at = at;
                Phase::Item
            }
            (Phase::Item | Phase::After, Lexeme::Close) => {
                list = Some(list_at..at + 1);
                Phase::Done
            }
            (Phase::Item, Lexeme::Word(a, b)) if &text[a..b] == "Entity" => Phase::Named(at),
            (Phase::Item, Lexeme::Open) => Phase::Inside(at),
            (Phase::Named(start), Lexeme::Open) => Phase::Inside(start),
            (Phase::Inside(start), Lexeme::Close) if depth == 2 => {
                entities.push(start..at + 1);
                Phase::After
            }
            (p @ Phase::Inside(_), _) => p,
            (Phase::After, Lexeme::Comma) => Phase::Item,
            _ => {
                good = false;
                return false;
            }
        };
        true
    })?;
    let list = list.filter(|_| good)?;
    Some(Spans { entities, list })
}

#[cfg(test)]
mod tests {
    use super::*;

    const SCENE: &str = r#"Scene(
    camera: Camera(position: (0, 0, -5), look_at: (0, 0, 0)),
    materials: { "m": Diffuse(albedo: Constant((0.5, 0.5, 0.5))) },
    entities: [
        Entity(name: "a", material: "m", shape: Sphere(center: (0, 0, 0), radius: 1)),
        // a comment with ( and "
        Entity(name: "b)", material: "m", shape: Sphere(center: (2, 0, 0), radius: 1)), /* ( */
        (name: "c", material: "m", shape: Sphere(center: (4, 0, 0), radius: 1)),
    ],
)"#;

    fn full(text: &str) -> SceneDesc {
        parse(Path::new("s.ron"), text).expect("parses")
    }

    /// `SCENE` parsed, then `edited` parsed from it: the description (as text), the entities
    /// parsed and the spans kept, or the error's text.
    fn after_edit(edited: &str) -> Result<(String, usize, Option<Spans>), String> {
        let path = Path::new("s.ron");
        let mut kept = None;
        parse_scene_text(path, SCENE.to_string(), &mut kept).expect("parses");
        parse_scene_text(path, edited.to_string(), &mut kept)
            .map(|(p, n)| (format!("{:?}", p.desc()), n, p.spans.clone()))
            .map_err(|e| e.to_string())
    }

    /// A full parse of `edited`: the description (as text), or the error's text.
    fn full_parse(edited: &str) -> Result<String, String> {
        parse::<SceneDesc>(Path::new("s.ron"), edited)
            .map(|d| format!("{d:?}"))
            .map_err(|e| e.to_string())
    }

    #[test]
    fn entity_spans_cover_each_entity_whatever_the_comments_and_strings() {
        let spans = entity_spans(SCENE).expect("found");
        let texts: Vec<&str> = spans.entities.iter().map(|r| &SCENE[r.clone()]).collect();
        let list = &SCENE[spans.list];
        assert!(list.starts_with("[\n        Entity(name: \"a\"") && list.ends_with(']'));
        assert_eq!(texts.len(), 3);
        assert!(texts[0].starts_with("Entity(name: \"a\"") && texts[0].ends_with("radius: 1))"));
        assert!(texts[1].starts_with("Entity(name: \"b)\""));
        assert!(texts[2].starts_with("(name: \"c\"") && texts[2].ends_with("radius: 1))"));
    }

    #[test]
    fn an_edit_inside_one_entity_reparses_only_it_and_equals_a_full_parse() {
        let path = Path::new("s.ron");
        let mut kept = None;
        let (_, n) = parse_scene_text(path, SCENE.to_string(), &mut kept).expect("parses");
        assert_eq!(n, 3);
        let edited = SCENE.replace(
            "center: (2, 0, 0), radius: 1",
            "center: (2, 1, 0), radius: 0.5",
        );
        let (_, n) = parse_scene_text(path, edited.clone(), &mut kept).expect("parses");
        assert_eq!(n, 1, "only the edited entity is parsed");
        let reference = full(&edited);
        let desc = |kept: &Option<ParsedScene>| format!("{:?}", kept.as_ref().map(|p| p.desc()));
        assert_eq!(desc(&kept), format!("{:?}", Some(reference)));
        // A second edit, of another entity, works from the spliced parse.
        let again = edited.replace("\"c\"", "\"cc\"");
        let (_, n) = parse_scene_text(path, again.clone(), &mut kept).expect("parses");
        assert_eq!(n, 1);
        assert_eq!(desc(&kept), format!("{:?}", Some(full(&again))));
    }

    #[test]
    fn edits_outside_whole_entities_parse_the_whole_file() {
        let path = Path::new("s.ron");
        let cases = [
            // Between entities: a new one.
            SCENE.replace("/* ( */", "Entity(name: \"d\", material: \"m\", shape: Sphere(center: (6, 0, 0), radius: 1)),"),
            // Outside the list (read around it: see the next test).
            SCENE.replace("(0.5, 0.5, 0.5)", "(0.25, 0.5, 0.5)"),
            // A trailing comma inside the run would read as a list but not in the file.
            SCENE.replace("radius: 1)), /* ( */", "radius: 1)),, /* ( */"),
            // One entity split into two.
            SCENE.replace(
                "Entity(name: \"a\", material: \"m\", shape: Sphere(center: (0, 0, 0), radius: 1))",
                "Entity(name: \"a\", material: \"m\", shape: Sphere(center: (0, 0, 0), radius: 1)), Entity(name: \"a2\", material: \"m\", shape: Sphere(center: (0, 3, 0), radius: 1))",
            ),
        ];
        for edited in cases {
            match (after_edit(&edited), full_parse(&edited)) {
                (Ok((ours, _, _)), Ok(reference)) => assert_eq!(ours, reference),
                (Err(a), Err(b)) => assert_eq!(a, b),
                (a, b) => panic!("{edited}: {a:?} against {b:?}"),
            }
        }
        let mut kept = None;
        parse_scene_text(path, SCENE.to_string(), &mut kept).expect("parses");
        let split = SCENE.replace("(name: \"c\"", "Entity(name: \"c\"");
        let (_, n) = parse_scene_text(path, split, &mut kept).expect("parses");
        assert_eq!(
            n, 1,
            "renaming the struct of one entity is an edit inside it"
        );
    }

    #[test]
    fn a_broken_entity_is_the_error_a_full_parse_gives_and_keeps_the_last_good_parse() {
        let path = Path::new("s.ron");
        let mut kept = None;
        parse_scene_text(path, SCENE.to_string(), &mut kept).expect("parses");
        let broken = SCENE.replace("(4, 0, 0), radius: 1", "(4, 0, 0), radius: oops");
        let e = parse_scene_text(path, broken.clone(), &mut kept)
            .err()
            .expect("fails");
        let reference = parse::<SceneDesc>(path, &broken).expect_err("fails too");
        assert_eq!(e.to_string(), reference.to_string());
        // The mended save starts from the parse before the broken one.
        let mended = SCENE.replace("(4, 0, 0), radius: 1", "(4, 0, 0), radius: 2");
        let (_, n) = parse_scene_text(path, mended.clone(), &mut kept).expect("parses");
        assert_eq!(n, 1, "one entity parsed after the broken save");
        let desc = kept.as_ref().map(|p| format!("{:?}", p.desc()));
        assert_eq!(desc, Some(format!("{:?}", full(&mended))));
    }

    #[test]
    fn an_edit_outside_the_list_parses_no_entity_and_equals_a_full_parse() {
        let cases = [
            // A material, before the list: the spans move.
            SCENE.replace("(0.5, 0.5, 0.5)", "(0.25, 0.5, 0.5)"),
            SCENE.replace("(0.5, 0.5, 0.5)", "(0.5, 0.5, 0.5), roughness: 1"),
            // The camera, and a comment after the list.
            SCENE.replace("(0, 0, -5)", "(0, 1, -50)"),
            SCENE.replace("    ],\n)", "    ], // done\n)"),
        ];
        for edited in cases {
            match (after_edit(&edited), full_parse(&edited)) {
                (Ok((ours, n, spans)), Ok(reference)) => {
                    assert_eq!(n, 0, "no entity parsed: {edited}");
                    assert_eq!(ours, reference);
                    assert_eq!(spans, entity_spans(&edited));
                }
                (Err(a), Err(b)) => assert_eq!(a, b),
                (a, b) => panic!("{edited}: {a:?} against {b:?}"),
            }
        }
        // Text before the list that would swallow it (an open raw string, a comment) is not
        // read around it: the whole file is parsed, as a full parse reads it.
        for opener in ["r#\"", "/*", "\""] {
            let edited = SCENE.replace("camera:", &format!("{opener}camera:"));
            match (after_edit(&edited), full_parse(&edited)) {
                (Ok((ours, n, _)), Ok(reference)) => {
                    assert_eq!(ours, reference);
                    assert_eq!(n, 3, "parsed in full");
                }
                (Err(a), Err(b)) => assert_eq!(a, b),
                (a, b) => panic!("{opener}: {a:?} against {b:?}"),
            }
        }
    }

    #[test]
    fn random_edits_parse_as_a_full_parse_does() {
        let path = Path::new("s.ron");
        let entity = |i: usize| {
            format!(
                "        Entity(name: \"e{i}\", material: \"m\", shape: Sphere(center: ({i}, 0, 0), radius: 0.{i}1)),\n"
            )
        };
        let mut text = String::from(
            "Scene(\n    camera: Camera(position: (0, 0, -5), look_at: (0, 0, 0)),\n    materials: { \"m\": Diffuse(albedo: Constant((0.5, 0.5, 0.5))) },\n    entities: [\n",
        );
        for i in 0..30 {
            text += &entity(i);
        }
        text += "    ],\n)\n";
        let pieces = [
            "1", "9", ",", ")", "(", "\"", "Entity(", " ", "// x\n", "/*", "*/", "r#\"", "'",
        ];
        let mut rng = crate::shading::rng::Rng::new(7, 11);
        let mut below = |n: usize| rng.next_u32() as usize % n.max(1);
        let mut kept = None;
        parse_scene_text(path, text.clone(), &mut kept).expect("parses");
        let (mut reused, mut total) = (0, 0);
        for round in 0..3000 {
            let mut edited = text.clone();
            let at = below(edited.len());
            let at = (at..edited.len())
                .find(|&k| edited.is_char_boundary(k))
                .unwrap_or(0);
            match round % 4 {
                0 => edited.insert_str(at, pieces[below(pieces.len())]),
                1 => {
                    let end = (at + 1 + below(8)).min(edited.len());
                    if edited.is_char_boundary(end) {
                        edited.replace_range(at..end, "");
                    }
                }
                2 => {
                    // A digit changed: most such edits stay inside one entity.
                    if let Some(k) = edited[at..].find(|c: char| c.is_ascii_digit()) {
                        let k = at + k;
                        edited.replace_range(k..k + 1, &below(10).to_string());
                    }
                }
                _ => edited.insert_str(at, &entity(100 + round)),
            }
            let full = parse::<SceneDesc>(path, &edited);
            match parse_scene_text(path, edited.clone(), &mut kept) {
                Ok((parsed, n)) => {
                    let full = full.as_ref().expect("a full parse succeeds too");
                    assert_eq!(
                        format!("{:?}", parsed.desc()),
                        format!("{full:?}"),
                        "round {round}: {edited}"
                    );
                    // The spans carried over are those a fresh scan finds.
                    if parsed.spans.is_some() {
                        assert_eq!(parsed.spans, entity_spans(&parsed.text), "round {round}");
                    }
                    total += 1;
                    if n < parsed.desc().entities.len() {
                        reused += 1;
                    }
                    text = edited;
                }
                Err(e) => {
                    let full = full.as_ref().expect_err("a full parse fails too");
                    assert_eq!(e.to_string(), full.to_string(), "round {round}");
                    // The last good parse is kept: the next edit starts from `text` again.
                    let parsed = kept.as_ref().expect("kept");
                    assert_eq!(parsed.text, text, "round {round}");
                }
            }
        }
        assert!(
            reused > total / 4,
            "{reused} of {total} successful edits reused entities"
        );
    }
}
