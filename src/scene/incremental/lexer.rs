//! A lexer for RON text, just enough to find where values start and end: brackets, commas,
//! colons and identifiers, with blanks, comments and the insides of strings and characters
//! skipped.

use crate::scene::locate::{block_comment_end, raw_string};

/// One significant lexical item of RON text: blanks, comments and the insides of strings and
/// characters are skipped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(in crate::scene) enum Lexeme {
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
pub(in crate::scene) fn lex_each(
    text: &str,
    mut each: impl FnMut(usize, Lexeme) -> bool,
) -> Option<()> {
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
pub(super) fn lex(text: &str) -> Option<Vec<(usize, Lexeme)>> {
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
