//! The open documents: the editor's buffers (not the files on disk), kept in sync by full or
//! incremental changes, and conversions between byte offsets and LSP positions (lines and
//! UTF-16 code units, LSP's default encoding).

use std::collections::HashMap;
use std::path::PathBuf;

use lsp_types::{Position, Range, TextDocumentContentChangeEvent};

/// Most documents open at once.
pub const MAX_DOCUMENTS: usize = 256;
/// Largest document, in bytes, after any change (a bound on what changes can grow).
pub const MAX_DOCUMENT_BYTES: usize = 64 << 20;

/// One open buffer.
pub struct Document {
    /// The path of its file (`None` for a document that is not a `file:` URI).
    pub path: Option<PathBuf>,
    /// Its text as the editor has it.
    pub text: String,
    /// The version the editor gave with the last change.
    pub version: i32,
    /// Byte offset of the start of every line.
    lines: Vec<usize>,
}

/// Why a change could not be applied.
#[derive(Debug, thiserror::Error)]
pub enum ChangeError {
    /// The document is not open.
    #[error("{0} is not open")]
    NotOpen(String),
    /// Too many documents, or a document too large.
    #[error("{0}")]
    Limit(String),
}

impl Document {
    /// A document holding `text`.
    pub fn new(path: Option<PathBuf>, text: String, version: i32) -> Self {
        let lines = line_starts(&text);
        Self {
            path,
            text,
            version,
            lines,
        }
    }

    /// Applies one change: a range replaced, or the whole text.
    fn apply(&mut self, change: TextDocumentContentChangeEvent) -> Result<(), ChangeError> {
        let range = change
            .range
            .map(|r| self.offset(r.start)..self.offset(r.end));
        let new_len = match &range {
            Some(r) => self.text.len() - r.end.saturating_sub(r.start) + change.text.len(),
            None => change.text.len(),
        };
        if new_len > MAX_DOCUMENT_BYTES {
            return Err(ChangeError::Limit(format!(
                "a document of {new_len} bytes (at most {MAX_DOCUMENT_BYTES})"
            )));
        }
        match range {
            Some(r) => {
                let r = r.start.min(r.end)..r.end.max(r.start);
                self.text.replace_range(r, &change.text);
            }
            None => self.text = change.text,
        }
        self.lines = line_starts(&self.text);
        Ok(())
    }

    /// The byte offset of `p`: past the end of its line, the line's end; past the last line,
    /// the end of the text; inside a character (a UTF-16 unit of a surrogate pair), before it.
    pub fn offset(&self, p: Position) -> usize {
        let Some(&start) = self.lines.get(p.line as usize) else {
            return self.text.len();
        };
        let end = self
            .lines
            .get(p.line as usize + 1)
            .map_or(self.text.len(), |&e| e);
        let line = &self.text[start..end];
        let mut units = 0u32;
        for (i, c) in line.char_indices() {
            if units + c.len_utf16() as u32 > p.character || c == '\n' || c == '\r' {
                return start + i;
            }
            units += c.len_utf16() as u32;
        }
        end
    }

    /// The position of byte `offset` (clamped to the text, moved back to a character boundary).
    pub fn position(&self, offset: usize) -> Position {
        let mut offset = offset.min(self.text.len());
        while !self.text.is_char_boundary(offset) {
            offset -= 1;
        }
        let line = self.lines.partition_point(|&s| s <= offset) - 1;
        let start = self.lines[line];
        let character: usize = self.text[start..offset].chars().map(char::len_utf16).sum();
        Position::new(line as u32, character as u32)
    }

    /// The range of bytes `r`.
    pub fn range(&self, r: std::ops::Range<usize>) -> Range {
        Range::new(self.position(r.start), self.position(r.end))
    }

    /// The byte offset of a 1-based line and column counted in characters, as scene errors
    /// give them (the end of the line if the column lies beyond it).
    pub fn offset_of_line_col(&self, line: usize, col: usize) -> usize {
        let Some(&start) = self.lines.get(line.saturating_sub(1)) else {
            return self.text.len();
        };
        let rest = &self.text[start..];
        let line_end = rest.find('\n').map_or(rest.len(), |e| e);
        rest[..line_end]
            .char_indices()
            .nth(col.saturating_sub(1))
            .map_or(start + line_end, |(i, _)| start + i)
    }
}

/// Byte offsets of the starts of the lines of `text`.
fn line_starts(text: &str) -> Vec<usize> {
    std::iter::once(0)
        .chain(text.match_indices('\n').map(|(i, _)| i + 1))
        .collect()
}

/// The open documents by URI.
#[derive(Default)]
pub struct Documents {
    open: HashMap<String, Document>,
}

impl Documents {
    /// Opens (or replaces) the document `uri`.
    pub fn open(&mut self, uri: &str, document: Document) -> Result<(), ChangeError> {
        if self.open.len() >= MAX_DOCUMENTS && !self.open.contains_key(uri) {
            return Err(ChangeError::Limit(format!(
                "more than {MAX_DOCUMENTS} open documents"
            )));
        }
        if document.text.len() > MAX_DOCUMENT_BYTES {
            return Err(ChangeError::Limit(format!(
                "a document of {} bytes (at most {MAX_DOCUMENT_BYTES})",
                document.text.len()
            )));
        }
        self.open.insert(uri.to_string(), document);
        Ok(())
    }

    /// Applies `changes` in order to `uri`, which then has `version`. A change that fails closes
    /// the document: its text is no longer the editor's.
    pub fn change(
        &mut self,
        uri: &str,
        version: i32,
        changes: Vec<TextDocumentContentChangeEvent>,
    ) -> Result<(), ChangeError> {
        let doc = self
            .open
            .get_mut(uri)
            .ok_or_else(|| ChangeError::NotOpen(uri.to_string()))?;
        for change in changes {
            if let Err(e) = doc.apply(change) {
                self.open.remove(uri);
                return Err(e);
            }
        }
        doc.version = version;
        Ok(())
    }

    /// Closes `uri`.
    pub fn close(&mut self, uri: &str) -> Option<Document> {
        self.open.remove(uri)
    }

    /// The document `uri`, if open.
    pub fn get(&self, uri: &str) -> Option<&Document> {
        self.open.get(uri)
    }

    /// The URIs of the open documents.
    pub fn uris(&self) -> impl Iterator<Item = &String> {
        self.open.keys()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn change(
        range: Option<((u32, u32), (u32, u32))>,
        text: &str,
    ) -> TextDocumentContentChangeEvent {
        TextDocumentContentChangeEvent {
            range: range
                .map(|((a, b), (c, d))| Range::new(Position::new(a, b), Position::new(c, d))),
            range_length: None,
            text: text.into(),
        }
    }

    #[test]
    fn positions_count_utf16_units() {
        let d = Document::new(None, "aé𝄞b\r\nxy\n".into(), 0);
        // a(1) é(1) 𝄞(2 units) b
        assert_eq!(d.offset(Position::new(0, 4)), "aé𝄞".len());
        assert_eq!(d.position("aé𝄞".len()), Position::new(0, 4));
        assert_eq!(
            d.offset(Position::new(0, 99)),
            "aé𝄞b".len(),
            "clamped before \\r"
        );
        assert_eq!(d.offset(Position::new(1, 1)), "aé𝄞b\r\nx".len());
        assert_eq!(d.offset(Position::new(7, 0)), d.text.len());
        assert_eq!(d.position(d.text.len()), Position::new(2, 0));
        assert_eq!(d.offset_of_line_col(1, 4), "aé𝄞".len());
        assert_eq!(d.offset_of_line_col(2, 2), "aé𝄞b\r\nx".len());
    }

    #[test]
    fn incremental_changes_edit_the_buffer() {
        let mut docs = Documents::default();
        docs.open("u", Document::new(None, "one\ntwo\n".into(), 1))
            .expect("open");
        docs.change(
            "u",
            2,
            vec![
                change(Some(((1, 0), (1, 3))), "2"),
                change(Some(((0, 3), (0, 3))), "!"),
            ],
        )
        .expect("change");
        assert_eq!(docs.get("u").map(|d| d.text.as_str()), Some("one!\n2\n"));
        docs.change("u", 3, vec![change(None, "all")])
            .expect("full");
        let d = docs.get("u").expect("open");
        assert_eq!((d.text.as_str(), d.version), ("all", 3));
        assert_eq!(d.position(3), Position::new(0, 3));
    }
}
