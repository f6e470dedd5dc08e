//! Where the cursor is in RON text that may not parse: the brackets around it, the field or map
//! key each is at, and the string or word under it.
//!
//! The loader's parser says what a whole file means, or where it first goes wrong; an editor
//! asks about a buffer being typed, which is broken most of the time (an unclosed string, a
//! missing bracket). So this reads tokens only, forgiving everything: an unclosed string or
//! comment runs to the end of the text, an unmatched closing bracket is ignored. What the
//! brackets *mean* is left to the format's own types ([`super::probe`]).

use std::ops::Range;

use crate::scene::locate::block_comment_end;

/// What a token is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// `(`, `[` or `{`.
    Open(u8),
    /// `)`, `]` or `}`.
    Close,
    /// `,`
    Comma,
    /// `:`
    Colon,
    /// An identifier.
    Word,
    /// A string literal; `closed` unless the text ends inside it.
    Str {
        /// Whether its closing quote is there.
        closed: bool,
        /// Bytes before its contents: 1 for `"`, 2 + hashes for `r#"`.
        open: u8,
        /// Bytes after its contents (0 when not closed).
        close: u8,
    },
    /// A number, a character or any other sign.
    Other,
}

/// One token and its bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Token {
    /// What it is.
    pub kind: Kind,
    /// Its first byte.
    pub start: usize,
    /// Past its last byte.
    pub end: usize,
}

impl Token {
    /// A string's contents (raw: escapes as written); the whole token for other kinds.
    pub fn contents(&self) -> Range<usize> {
        match self.kind {
            Kind::Str { open, close, .. } => {
                self.start + open as usize
                    ..(self.end - close as usize).max(self.start + open as usize)
            }
            _ => self.start..self.end,
        }
    }
}

/// Calls `each` on every token of `text`, in order, until it returns `false`.
pub fn tokens(text: &str, mut each: impl FnMut(Token) -> bool) {
    let b = text.as_bytes();
    let mut i = 0;
    while i < b.len() {
        let start = i;
        let kind = match b[i] {
            c if c.is_ascii_whitespace() => {
                i += 1;
                continue;
            }
            b'/' if b.get(i + 1) == Some(&b'/') => {
                i = b[i..]
                    .iter()
                    .position(|&c| c == b'\n')
                    .map_or(b.len(), |p| i + p);
                continue;
            }
            b'/' if b.get(i + 1) == Some(&b'*') => {
                i = block_comment_end(b, i).unwrap_or(b.len());
                continue;
            }
            b'"' => {
                let (end, closed) = quoted(b, i + 1, b'"');
                i = end;
                Kind::Str {
                    closed,
                    open: 1,
                    close: u8::from(closed),
                }
            }
            b'\'' => {
                i = quoted(b, i + 1, b'\'').0;
                Kind::Other
            }
            c @ (b'(' | b'[' | b'{') => {
                i += 1;
                Kind::Open(c)
            }
            b')' | b']' | b'}' => {
                i += 1;
                Kind::Close
            }
            b',' => {
                i += 1;
                Kind::Comma
            }
            b':' => {
                i += 1;
                Kind::Colon
            }
            c if c.is_ascii_alphabetic() || c == b'_' => {
                while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                    i += 1;
                }
                if &b[start..i] == b"r" && matches!(b.get(i), Some(b'"' | b'#')) {
                    raw_string(b, start, &mut i).unwrap_or(Kind::Word)
                } else {
                    Kind::Word
                }
            }
            _ => {
                i += 1;
                while i < b.len() && b[i] & 0xC0 == 0x80 {
                    i += 1;
                }
                Kind::Other
            }
        };
        if !each(Token {
            kind,
            start,
            end: i,
        }) {
            return;
        }
    }
}

/// The end of a string or character whose contents start at `i`, and whether it is closed.
fn quoted(b: &[u8], mut i: usize, quote: u8) -> (usize, bool) {
    while i < b.len() {
        match b[i] {
            b'\\' => i += 2,
            c if c == quote => return (i + 1, true),
            _ => i += 1,
        }
    }
    (b.len(), false)
}

/// A raw string `r#"…"#` whose `r` is at `start` (`*i` just past it): moves `*i` past it.
/// `None`, moving nothing, if no quote follows the hashes.
fn raw_string(b: &[u8], start: usize, i: &mut usize) -> Option<Kind> {
    let hashes = b[*i..].iter().take_while(|&&c| c == b'#').count();
    let open = *i + hashes;
    if b.get(open) != Some(&b'"') || hashes > 250 {
        return None;
    }
    let mut closing = vec![b'"'];
    closing.resize(hashes + 1, b'#');
    let found = b[open + 1..]
        .windows(closing.len())
        .position(|w| w == closing.as_slice());
    let prefix = (open + 1 - start) as u8;
    Some(match found {
        Some(p) => {
            *i = open + 1 + p + closing.len();
            Kind::Str {
                closed: true,
                open: prefix,
                close: closing.len() as u8,
            }
        }
        None => {
            *i = b.len();
            Kind::Str {
                closed: false,
                open: prefix,
                close: 0,
            }
        }
    })
}

/// An open bracket around a place in the text.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Frame {
    /// `(`, `[` or `{`.
    pub open: u8,
    /// Where it is.
    pub start: usize,
    /// The identifier right before it (`Entity` of `Entity(`), if any.
    pub name: Option<Range<usize>>,
    /// In a `(`: the field being written (its name's bytes); in a `{`: the key being written
    /// (a string's contents). Cleared by each comma.
    pub key: Option<Range<usize>>,
    /// Whether the key's `:` has been read: the place is in its value.
    pub value: bool,
}

/// The brackets open at a place, updated token by token.
#[derive(Default)]
pub struct Walker {
    /// Outermost first.
    pub stack: Vec<Frame>,
    last: Option<Token>,
}

impl Walker {
    /// Reads token `t` of `text`.
    pub fn step(&mut self, text: &str, t: Token) {
        match t.kind {
            Kind::Open(open) => {
                let name = self
                    .last
                    .filter(|w| w.kind == Kind::Word && text[w.end..t.start].trim().is_empty())
                    .map(|w| w.start..w.end);
                self.stack.push(Frame {
                    open,
                    start: t.start,
                    name,
                    key: None,
                    value: false,
                });
            }
            Kind::Close => {
                self.stack.pop();
            }
            Kind::Comma => {
                if let Some(f) = self.stack.last_mut() {
                    f.key = None;
                    f.value = false;
                }
            }
            Kind::Colon => {
                if let Some(f) = self.stack.last_mut() {
                    f.value = true;
                }
            }
            Kind::Word => {
                if let Some(f) = self.stack.last_mut().filter(|f| f.open == b'(' && !f.value) {
                    f.key = Some(t.start..t.end);
                }
            }
            Kind::Str { .. } => {
                if let Some(f) = self.stack.last_mut().filter(|f| f.open == b'{' && !f.value) {
                    f.key = Some(t.contents());
                }
            }
            Kind::Other => {}
        }
        self.last = Some(t);
    }
}

/// What surrounds byte `offset` of a text.
#[derive(Clone, Debug, Default)]
pub struct Context {
    /// The brackets open there, outermost first, as read up to the token under the cursor.
    pub frames: Vec<Frame>,
    /// The string or word the cursor is in (or right after, for a word being typed).
    pub token: Option<Token>,
}

/// What surrounds byte `offset` of `text`.
pub fn context_at(text: &str, offset: usize) -> Context {
    let mut w = Walker::default();
    let mut token = None;
    tokens(text, |t| {
        if t.start >= offset {
            return false;
        }
        let inside = match t.kind {
            Kind::Str { closed, .. } => offset < t.end || (!closed && offset == t.end),
            Kind::Word => offset <= t.end,
            _ => false,
        };
        if inside {
            token = Some(t);
            return false;
        }
        w.step(text, t);
        true
    });
    Context {
        frames: w.stack,
        token,
    }
}

/// The text of `r` in `text` (empty if `r` is not in it).
pub fn slice(text: &str, r: Option<Range<usize>>) -> &str {
    r.and_then(|r| text.get(r)).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kinds(text: &str) -> Vec<(Kind, &str)> {
        let mut out = Vec::new();
        tokens(text, |t| {
            out.push((t.kind, &text[t.start..t.end]));
            true
        });
        out
    }

    #[test]
    fn broken_text_still_tokenizes() {
        let s = kinds("A(b: \"x\\\"\", // c\n r#\"q\"# /* ) */ ]) \"open");
        let str_ = |closed, open, close| Kind::Str {
            closed,
            open,
            close,
        };
        assert_eq!(
            s,
            vec![
                (Kind::Word, "A"),
                (Kind::Open(b'('), "("),
                (Kind::Word, "b"),
                (Kind::Colon, ":"),
                (str_(true, 1, 1), "\"x\\\"\""),
                (Kind::Comma, ","),
                (str_(true, 3, 2), "r#\"q\"#"),
                (Kind::Close, "]"),
                (Kind::Close, ")"),
                (str_(false, 1, 0), "\"open"),
            ]
        );
    }

    #[test]
    fn the_context_names_the_field_and_the_brackets() {
        let text = r#"Scene(materials: {"a": Diffuse(albedo: X)}, entities: [Entity(name: "n", material: "")])"#;
        let at = text.find("material: \"").expect("material") + 11;
        let c = context_at(text, at);
        let names: Vec<&str> = c
            .frames
            .iter()
            .map(|f| slice(text, f.name.clone()))
            .collect();
        assert_eq!(names, ["Scene", "", "Entity"]);
        assert_eq!(slice(text, c.frames[0].key.clone()), "entities");
        assert_eq!(slice(text, c.frames[2].key.clone()), "material");
        assert!(c.frames[2].value);
        assert_eq!(c.token.map(|t| t.contents()), Some(at..at));
        let albedo = text.find("X)").expect("X") + 1;
        let c = context_at(text, albedo);
        assert_eq!(slice(text, c.frames[1].key.clone()), "a");
        assert_eq!(slice(text, c.frames[2].key.clone()), "albedo");
        assert_eq!(c.token.map(|t| &text[t.start..t.end]), Some("X"));
    }
}
