//! Line and column of entities and strings in a scene file, found by one scan of its text.
//!
//! Loading never searches the text: locations are needed only for an error or a `rondo check`
//! warning, and then a [`Locator`] reads the file once, indexing the start of every line, every
//! `Entity(` and every string literal. Each query afterwards costs a hash lookup or a binary
//! search plus at most [`CHECKPOINT`] bytes, so locating k things in a file of n bytes costs
//! O(n + k log n), never O(n · k).
//!
//! Comments (`//`, nested `/* */`), string escapes, raw strings (`r#"…"#`) and character
//! literals are skipped by the scan, so a quote or an `Entity(` inside them is not taken for one.

use std::cell::Cell;
use std::collections::HashMap;
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::error::Location;

/// The text of a file a scene was read from.
#[derive(Clone)]
pub struct SourceText {
    /// The file.
    pub path: PathBuf,
    /// Its contents.
    pub text: Arc<str>,
}

impl fmt::Debug for SourceText {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} ({} bytes)", self.path.display(), self.text.len())
    }
}

/// The locators of a scene's files, each built when first asked for.
pub struct Places<'a> {
    sources: &'a [SourceText],
    locators: Vec<Option<Locator<'a>>>,
}

impl<'a> Places<'a> {
    /// No file scanned yet.
    pub fn new(sources: &'a [SourceText]) -> Self {
        Self {
            sources,
            locators: sources.iter().map(|_| None).collect(),
        }
    }

    /// The locator of file `file`, scanning it on first use.
    pub fn locator(&mut self, file: u32) -> Option<&Locator<'a>> {
        let sources = self.sources;
        let slot = self.locators.get_mut(file as usize)?;
        Some(slot.get_or_insert_with(|| Locator::new(&sources[file as usize].text)))
    }

    /// The path of file `file`.
    pub fn path(&self, file: u32) -> Option<&'a Path> {
        self.sources.get(file as usize).map(|s| s.path.as_path())
    }

    /// `path:line:col` (or `path` without a location) of a place in file `file`.
    pub fn describe(&self, file: u32, location: Option<Location>) -> String {
        let path = self.path(file).unwrap_or(Path::new("?")).display();
        match location {
            Some(l) => format!("{path}:{}:{}", l.line, l.col),
            None => path.to_string(),
        }
    }

    /// Bytes scanned by every locator built so far.
    pub fn bytes_scanned(&self) -> u64 {
        self.locators
            .iter()
            .flatten()
            .map(Locator::bytes_scanned)
            .sum()
    }
}

/// Longest stretch of a line counted character by character for a column: a scene written on
/// one line gets a checkpoint every this many bytes.
pub const CHECKPOINT: usize = 1024;

/// The index of one file's text.
pub struct Locator<'a> {
    source: &'a str,
    /// `(byte offset, line, column)` at the start of every line and every [`CHECKPOINT`] bytes
    /// within a line, at character boundaries, in increasing offset.
    marks: Vec<(usize, u32, u32)>,
    /// First and second offset (of the opening quote) of each string literal's raw contents.
    strings: HashMap<&'a str, (usize, Option<usize>)>,
    /// Offset of the first string literal with each raw contents that is a map's key (followed
    /// by `:`): a material's definition in a `materials` map.
    keys: HashMap<&'a str, usize>,
    /// Offsets of every `Entity(` (the `E`), in order.
    entities: Vec<usize>,
    /// Bytes read so far: the two scans, then every query.
    scanned: Cell<u64>,
}

/// One lexical item the scan reports.
enum Token<'a> {
    /// A string literal starting at the offset, with its raw (still escaped) contents, and
    /// whether a `:` follows it (a map's key).
    Str(usize, &'a str, bool),
    /// `Entity` followed by `(` at the offset.
    Entity(usize),
}

impl<'a> Locator<'a> {
    /// Scans `source` once for lines, entities and strings.
    pub fn new(source: &'a str) -> Self {
        let mut marks = vec![(0, 1, 1)];
        let (mut line, mut col, mut last) = (1u32, 1u32, 0usize);
        for (i, &b) in source.as_bytes().iter().enumerate() {
            if b == b'\n' {
                line += 1;
                col = 1;
                last = i + 1;
                marks.push((i + 1, line, 1));
            } else if b & 0xC0 != 0x80 {
                if i - last >= CHECKPOINT {
                    last = i;
                    marks.push((i, line, col));
                }
                col += 1;
            }
        }
        let mut strings = HashMap::new();
        let mut keys = HashMap::new();
        let mut entities = Vec::new();
        tokens(source, 0, |t| {
            match t {
                Token::Str(at, text, key) => {
                    if key {
                        keys.entry(text).or_insert(at);
                    }
                    strings
                        .entry(text)
                        .and_modify(|e: &mut (usize, Option<usize>)| {
                            e.1.get_or_insert(at);
                        })
                        .or_insert((at, None));
                }
                Token::Entity(at) => entities.push(at),
            }
            true
        });
        Self {
            source,
            marks,
            strings,
            keys,
            entities,
            scanned: Cell::new(2 * source.len() as u64),
        }
    }

    /// Bytes read so far (both scans and every query): the work counter of the scaling tests.
    pub fn bytes_scanned(&self) -> u64 {
        self.scanned.get()
    }

    /// Offset of the first string literal whose contents are `text`.
    pub fn first(&self, text: &str) -> Option<usize> {
        self.strings.get(text).map(|e| e.0)
    }

    /// Offset of the second string literal whose contents are `text`.
    pub fn second(&self, text: &str) -> Option<usize> {
        self.strings.get(text).and_then(|e| e.1)
    }

    /// Offset of the definition of material `name`: the first string literal of the name that
    /// is a map's key (followed by `:`), wherever entities name the material before it; else
    /// the first string literal of the name.
    pub fn material(&self, name: &str) -> Option<usize> {
        self.keys.get(name).copied().or_else(|| self.first(name))
    }

    /// Offset of the `index`-th `Entity(` of the file.
    pub fn entity(&self, index: usize) -> Option<usize> {
        self.entities.get(index).copied()
    }

    /// Offset of the string literal `text` within the file's `index`-th entity: after its
    /// `Entity(` and before the next one. Reads that entity's text up to the string.
    pub fn in_entity(&self, index: usize, text: &str) -> Option<usize> {
        let from = self.entity(index)?;
        let mut found = None;
        let read = tokens(self.source, from, |t| match t {
            Token::Str(at, s, _) if s == text => {
                found = Some(at);
                false
            }
            Token::Entity(at) => at == from,
            Token::Str(..) => true,
        });
        self.scanned.set(self.scanned.get() + read as u64);
        found
    }

    /// Offset of the first string literal `text` at or after `from`, which must be the start of
    /// a token (an entity or a string, as returned by the other queries). Reads from `from` on.
    pub fn after(&self, text: &str, from: usize) -> Option<usize> {
        let mut found = None;
        let read = tokens(self.source, from, |t| match t {
            Token::Str(at, s, _) if s == text => {
                found = Some(at);
                false
            }
            _ => true,
        });
        self.scanned.set(self.scanned.get() + read as u64);
        found
    }

    /// Line and column of byte `offset`, as [`Location::of_offset`] gives them.
    pub fn location(&self, offset: usize) -> Location {
        let offset = offset.min(self.source.len());
        let k = self.marks.partition_point(|m| m.0 <= offset) - 1;
        let (start, line, col) = self.marks[k];
        let between = self.source.get(start..offset).unwrap_or_default();
        self.scanned
            .set(self.scanned.get() + between.len() as u64 + 1);
        Location {
            line: line as usize,
            col: col as usize + between.chars().count(),
        }
    }
}

/// Calls `each` on every string literal and `Entity(` of `source` from byte `from` on, until it
/// returns `false`. Returns the number of bytes read.
fn tokens<'a>(source: &'a str, from: usize, mut each: impl FnMut(Token<'a>) -> bool) -> usize {
    let b = source.as_bytes();
    let mut i = from;
    // End of a quoted run starting after `i`: the offset of its closing quote (or the end).
    let close = |mut j: usize| {
        while j < b.len() && b[j] != b'"' {
            j += if b[j] == b'\\' { 2 } else { 1 };
        }
        j.min(b.len())
    };
    while i < b.len() {
        match b[i] {
            b'"' => {
                let end = close(i + 1);
                let text = source.get(i + 1..end).unwrap_or_default();
                if !each(Token::Str(i, text, colon_after(b, end + 1))) {
                    return end - from;
                }
                i = end + 1;
            }
            b'/' if b.get(i + 1) == Some(&b'/') => {
                i = b[i..]
                    .iter()
                    .position(|&c| c == b'\n')
                    .map_or(b.len(), |p| i + p);
            }
            b'/' if b.get(i + 1) == Some(&b'*') => i = block_comment_end(b, i).unwrap_or(b.len()),
            b'\'' => {
                // A character literal: `'x'` or `'\x'` (`'"'` would otherwise open a string).
                i += if b.get(i + 1) == Some(&b'\\') { 4 } else { 3 };
            }
            c if c.is_ascii_alphabetic() || c == b'_' => {
                let start = i;
                while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                    i += 1;
                }
                let word = &b[start..i];
                if word == b"r" && matches!(b.get(i), Some(b'"' | b'#')) {
                    if let Some(raw) = raw_string(b, i) {
                        let end = raw.contents.end;
                        let text = source.get(raw.contents).unwrap_or_default();
                        if !each(Token::Str(start, text, colon_after(b, raw.end))) {
                            return end - from;
                        }
                        i = raw.end;
                    }
                } else if word == b"Entity" {
                    let next = b[i..].iter().position(|c| !c.is_ascii_whitespace());
                    if next.is_some_and(|p| b[i + p] == b'(') && !each(Token::Entity(start)) {
                        return i - from;
                    }
                }
            }
            _ => i += 1,
        }
    }
    b.len().saturating_sub(from)
}

/// Whether the first byte at or after `at` outside whitespace and comments is a `:`.
fn colon_after(b: &[u8], mut at: usize) -> bool {
    while let Some(&c) = b.get(at) {
        match c {
            c if c.is_ascii_whitespace() => at += 1,
            b'/' if b.get(at + 1) == Some(&b'/') => {
                at = b[at..]
                    .iter()
                    .position(|&c| c == b'\n')
                    .map_or(b.len(), |p| at + p);
            }
            b'/' if b.get(at + 1) == Some(&b'*') => {
                at = block_comment_end(b, at).unwrap_or(b.len());
            }
            c => return c == b':',
        }
    }
    false
}

/// The offset past the `*/` that closes the (nestable) block comment opening at `from`, or
/// `None` if the text ends first.
pub(crate) fn block_comment_end(b: &[u8], from: usize) -> Option<usize> {
    let (mut i, mut depth) = (from, 0usize);
    while i < b.len() {
        if b[i..].starts_with(b"/*") {
            depth += 1;
            i += 2;
        } else if b[i..].starts_with(b"*/") {
            depth -= 1;
            i += 2;
            if depth == 0 {
                return Some(i);
            }
        } else {
            i += 1;
        }
    }
    None
}

/// A raw string's contents and end.
pub(super) struct RawString {
    /// Its contents (no escapes); they run to the end of the text if it is not closed.
    pub contents: std::ops::Range<usize>,
    /// The offset past its closing quote and hashes (the end of the text if not closed).
    pub end: usize,
    /// Whether it is closed.
    pub closed: bool,
}

/// The raw string `r#"…"#` whose hashes (or quote) start at `at`, just after its `r`: no
/// escapes, closed by a quote and as many hashes. `None` if no quote follows the hashes.
pub(super) fn raw_string(b: &[u8], at: usize) -> Option<RawString> {
    let hashes = b[at..].iter().take_while(|&&c| c == b'#').count();
    let open = at + hashes;
    if b.get(open) != Some(&b'"') {
        return None;
    }
    let mut closing = vec![b'"'];
    closing.extend(std::iter::repeat_n(b'#', hashes));
    let found = b[open + 1..]
        .windows(closing.len())
        .position(|w| w == closing.as_slice());
    Some(match found {
        Some(p) => RawString {
            contents: open + 1..open + 1 + p,
            end: open + 1 + p + closing.len(),
            closed: true,
        },
        None => RawString {
            contents: open + 1..b.len(),
            end: b.len(),
            closed: false,
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locations_match_a_count_from_the_start() {
        let long = "x".repeat(3 * CHECKPOINT + 7);
        let s = format!("ab\ncdé\n{long}é\"q\"\r\nf");
        let l = Locator::new(&s);
        for offset in (0..=s.len()).filter(|&o| s.is_char_boundary(o)) {
            assert_eq!(
                l.location(offset),
                Location::of_offset(&s, offset),
                "{offset}"
            );
        }
    }

    #[test]
    fn strings_and_entities_are_indexed_outside_comments() {
        let s = r##"// "a" Entity(
Entity(name: "a"), /* "b" /* nested "b" */ Entity( */ Entity (name: "b\"", x: '"'),
Entity(name: r#"a"#, m: "a")"##;
        let l = Locator::new(s);
        assert_eq!(l.first("a"), Some(s.find("\"a\")").expect("a")));
        assert_eq!(l.second("a"), Some(s.find("r#").expect("raw")));
        assert_eq!(l.first("b\\\""), Some(s.find("\"b\\").expect("b")));
        assert_eq!(l.first("b"), None, "strings in comments are not strings");
        let entities: Vec<usize> = s.match_indices("Entity").map(|m| m.0).collect();
        assert_eq!(
            (0..4).map(|i| l.entity(i)).collect::<Vec<_>>(),
            vec![
                Some(entities[1]),
                Some(entities[3]),
                Some(entities[4]),
                None
            ]
        );
        let second = l.entity(1).expect("second entity");
        assert_eq!(l.after("a", second), l.second("a"));
        assert_eq!(l.after("a", l.first("a").expect("first")), l.first("a"));
        assert_eq!(l.in_entity(2, "a"), l.second("a"));
        assert_eq!(l.in_entity(0, "a"), l.first("a"));
        assert_eq!(
            l.in_entity(1, "a"),
            None,
            "the next entity's strings are not its own"
        );
        assert_eq!(l.in_entity(3, "a"), None);
    }

    #[test]
    fn a_material_is_found_at_its_key_after_entities_that_name_it() {
        let s = r#"Scene(entities: [Entity(name: "gold", material: "gold")],
    materials: { "gold" /* the key */ : Metal(albedo: Constant((1, 0.8, 0.3))), "tin": Metal() })"#;
        let l = Locator::new(s);
        assert_eq!(
            l.material("gold"),
            Some(s.find("\"gold\" /*").expect("key"))
        );
        assert_eq!(l.material("tin"), Some(s.find("\"tin\"").expect("key")));
        assert_eq!(l.material("lead"), None);
    }
}
