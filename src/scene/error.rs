//! Scene errors: every one names the file and, where the input has one, the line and column.

use std::fmt;
use std::path::PathBuf;

use serde_path_to_error::Segment;

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

    /// The RON parse or value-validation error of `path`, whose text is `source`, raised while
    /// parsing the value at `at` (the field path, outermost first; empty if unknown).
    pub(crate) fn from_ron(
        path: impl Into<PathBuf>,
        source: &str,
        error: &ron::error::SpannedError,
        at: &[Segment],
    ) -> Self {
        let p = error.span.start;
        Self::at(
            path,
            Some(Location {
                line: p.line,
                col: p.col,
            }),
            describe(&error.code, at, source),
        )
    }
}

/// How the value validators of `format.rs` start their messages; replaced by the field's name
/// when the field is known ("the value must be > 0" becomes "radius must be > 0").
pub(crate) const VALUE: &str = "the value";

/// The message of a RON error at `at`: `context: message`, where the context is the entity or
/// material (or `camera`, `settings`) holding the value, and the message names the field.
fn describe(error: &ron::Error, at: &[Segment], source: &str) -> String {
    let (context, rest) = match at {
        [first, Segment::Seq { index }, rest @ ..] if key(first) == Some("entities") => {
            let name = entity_name(source, *index).unwrap_or_else(|| format!("#{index}"));
            (Some(format!("entity \"{name}\"")), rest)
        }
        [first, Segment::Map { key: name }, rest @ ..] if key(first) == Some("materials") => {
            (Some(format!("material \"{name}\"")), rest)
        }
        [first, rest @ ..] if matches!(key(first), Some("camera" | "settings")) => {
            (key(first).map(str::to_string), rest)
        }
        _ => (None, at),
    };
    let field = rest.iter().rev().find_map(key);
    let message = match error {
        ron::Error::Message(m) => match (m.strip_prefix(VALUE), field) {
            (Some(tail), Some(field)) => format!("{field}{tail}"),
            _ => m.clone(),
        },
        ron::Error::NoSuchEnumVariant {
            expected,
            found,
            outer,
        } => format!(
            "unknown {} \"{found}\" (expected {})",
            kind_of(outer.as_deref()),
            one_of(
                expected
                    .iter()
                    .filter(|v| v.starts_with(char::is_uppercase))
            )
        ),
        ron::Error::NoSuchStructField {
            expected,
            found,
            outer,
        } => format!(
            "unknown field `{found}`{} (expected {})",
            within(outer.as_deref()),
            one_of(expected.iter())
        ),
        ron::Error::MissingStructField { field, outer } => {
            format!("missing field `{field}`{}", within(outer.as_deref()))
        }
        ron::Error::DuplicateStructField { field, outer } => {
            format!("field `{field}` given twice{}", within(outer.as_deref()))
        }
        other => match field {
            Some(field) => format!("{field}: {other}"),
            None => other.to_string(),
        },
    };
    match context {
        Some(context) => format!("{context}: {message}"),
        None => message,
    }
}

/// The field name or map key of a path segment.
fn key(s: &Segment) -> Option<&str> {
    match s {
        Segment::Map { key } => Some(key),
        _ => None,
    }
}

/// What the user calls the values of one of the format's enums.
fn kind_of(outer: Option<&str>) -> String {
    match outer {
        Some("MaterialDesc") => "material kind".into(),
        Some("RawShape") => "shape kind".into(),
        Some("TextureDesc") => "texture kind".into(),
        Some("Method") => "method".into(),
        Some(other) => format!("{other} variant"),
        None => "variant".into(),
    }
}

/// ` in Outer` for a named struct, nothing for an anonymous one.
fn within(outer: Option<&str>) -> String {
    outer.map_or_else(String::new, |o| format!(" in {o}"))
}

/// `a, b or c`.
fn one_of<'a>(names: impl Iterator<Item = &'a &'a str>) -> String {
    let names: Vec<&str> = names.copied().collect();
    match names.split_last() {
        None => "nothing".into(),
        Some((last, [])) => (*last).to_string(),
        Some((last, init)) => format!("{} or {last}", init.join(", ")),
    }
}

/// The `name` of the `index`-th entity of a file that parses as RON but not as a scene (the
/// value error being reported is inside that entity).
fn entity_name(source: &str, index: usize) -> Option<String> {
    use ron::Value;
    let field = |v: &Value, name: &str| match v {
        Value::Map(m) => m.get(&Value::String(name.into())).cloned(),
        _ => None,
    };
    let root: Value = ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
        .from_str(source)
        .ok()?;
    let Value::Seq(entities) = field(&root, "entities")? else {
        return None;
    };
    match field(entities.get(index)?, "name")? {
        Value::String(s) => Some(s),
        Value::Option(Some(s)) => match *s {
            Value::String(s) => Some(s),
            _ => None,
        },
        _ => None,
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
