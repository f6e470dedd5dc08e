//! Where the entities of a scene text are written: the byte span of each entity of its
//! `entities` list and of the list itself, found from the lexemes alone.

use std::ops::Range;

use super::lexer::{Lexeme, lex, lex_each};

/// Where a scene file's entities are written.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Spans {
    /// Byte span of each entity of the list.
    pub(super) entities: Vec<Range<usize>>,
    /// Byte span of the list, from its `[` to just after its `]`.
    pub(super) list: Range<usize>,
}

/// Spans of the items of a comma-separated run of values at depth 0 (`Entity(…)` or `(…)`),
/// each from its first byte to past its closing bracket; `None` unless the run is exactly such
/// items, one comma between each two and none before the first or after the last.
pub(super) fn list_items(run: &str) -> Option<Vec<Range<usize>>> {
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
pub(super) fn entity_spans(text: &str) -> Option<Spans> {
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
