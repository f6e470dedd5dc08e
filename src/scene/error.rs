//! Scene errors: every one names the file and, where the input has one, the line and column.

use std::fmt;
use std::path::PathBuf;

/// A 1-based line and column in a scene file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Location {
    /// Line, from 1.
    pub line: usize,
    /// Column, from 1.
    pub col: usize,
}

impl Location {
    /// The location of byte `offset` in `source`.
    pub fn of_offset(source: &str, offset: usize) -> Self {
        let before = &source[..offset.min(source.len())];
        let line = before.matches('\n').count() + 1;
        let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
        Self { line, col }
    }
}

/// Why a scene could not be loaded.
#[derive(Debug, thiserror::Error)]
pub struct SceneError {
    /// The file at fault.
    pub path: PathBuf,
    /// Where in it, if known.
    pub location: Option<Location>,
    /// What is wrong.
    pub message: String,
}

impl SceneError {
    /// An error at a location of `path`.
    pub fn at(
        path: impl Into<PathBuf>,
        location: Option<Location>,
        message: impl Into<String>,
    ) -> Self {
        Self {
            path: path.into(),
            location,
            message: message.into(),
        }
    }

    /// The RON parse (or value validation) error of `path`.
    pub fn from_ron(path: impl Into<PathBuf>, error: &ron::error::SpannedError) -> Self {
        let p = error.span.start;
        Self::at(
            path,
            Some(Location {
                line: p.line,
                col: p.col,
            }),
            error.code.to_string(),
        )
    }
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.path.display())?;
        if let Some(l) = self.location {
            write!(f, ":{}:{}", l.line, l.col)?;
        }
        write!(f, ": {}", self.message)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_map_to_one_based_lines_and_columns() {
        let s = "ab\ncdé\nf";
        assert_eq!(Location::of_offset(s, 0), Location { line: 1, col: 1 });
        assert_eq!(Location::of_offset(s, 4), Location { line: 2, col: 2 });
        assert_eq!(
            Location::of_offset(s, s.len()),
            Location { line: 3, col: 2 }
        );
    }
}
