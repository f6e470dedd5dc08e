//! Scene errors: every one names the file and, where the input has one, the line and column.
//!
//! Everything in an error may come from a file (a name, a value, a whole line of text), so it is
//! made safe to print when the error is made: control characters are escaped
//! ([`escape_controls`]) and the message is bounded ([`MAX_MESSAGE`]), and the line quoted with
//! it ([`SceneError::source_line`]) is a window of at most [`MAX_SOURCE_LINE`] characters around
//! the column, taken only from the text of a scene or prefab file.

use std::borrow::Cow;
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

/// Longest error message, in bytes: the text after `file:line:col: `, and the whole error as
/// displayed. A longer one keeps its start and its end around a `…`.
pub const MAX_MESSAGE: usize = 4096;

/// Most characters of a quoted source line (escapes and `…` markers included).
pub const MAX_SOURCE_LINE: usize = 200;

/// Why a scene could not be loaded. Where it is (file, line and column, field) is kept in fields
/// of its own, so that a reader (the live viewer) never parses it back out of the text.
#[derive(Clone, Debug, thiserror::Error)]
pub struct SceneError {
    /// The file at fault.
    pub path: PathBuf,
    /// Where in it, if known.
    pub location: Option<Location>,
    /// The field whose value is at fault, as its path in the file (`materials.red.albedo`,
    /// `entities[2].shape.radius`), when the parser knows it: at most [`MAX_MESSAGE`] bytes,
    /// control characters escaped.
    pub field: Option<String>,
    /// What is wrong: at most [`MAX_MESSAGE`] bytes, control characters escaped.
    pub message: String,
    /// The line at [`SceneError::location`], when it is in a scene or prefab file: at most
    /// [`MAX_SOURCE_LINE`] characters around the column (`…` where the line goes on), control
    /// characters escaped and tabs shown as spaces (so columns still count).
    pub source_line: Option<String>,
}

impl SceneError {
    /// An error at a location of `path`, quoting no source line.
    pub fn at(
        path: impl Into<PathBuf>,
        location: Option<Location>,
        message: impl Into<String>,
    ) -> Self {
        Self {
            path: path.into(),
            location,
            message: printable(&message.into(), MAX_MESSAGE).into_owned(),
            field: None,
            source_line: None,
        }
    }

    /// The same error quoting its line from `source`, the text of its file, which must be a
    /// scene or a prefab file: never a mesh, an image or another file a path points to.
    pub fn quoting(mut self, source: &str) -> Self {
        self.source_line = self.location.and_then(|l| quote_line(source, l));
        self
    }

    /// The same error without its source line.
    pub fn unquoted(mut self) -> Self {
        self.source_line = None;
        self
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
        .in_field(at)
        .quoting(source)
    }

    /// The same error naming the field at `at` (outermost first), if `at` names one.
    fn in_field(mut self, at: &[Segment]) -> Self {
        let mut path = String::new();
        for segment in at {
            match segment {
                Segment::Map { key } if path.is_empty() => path.push_str(key),
                Segment::Map { key } => {
                    path.push('.');
                    path.push_str(key);
                }
                Segment::Seq { index } => path.push_str(&format!("[{index}]")),
                Segment::Enum { .. } | Segment::Unknown => {}
            }
        }
        if !path.is_empty() {
            self.field = Some(printable(&path, MAX_MESSAGE).into_owned());
        }
        self
    }
}

/// Whether `c` must not reach a terminal or a page as it is: C0 controls (tab and newline
/// included), DEL, C1 controls (some terminals take U+009B for an escape sequence), the line
/// and paragraph separators and the bidirectional overrides and isolates, which reorder what
/// is shown around them.
fn is_unsafe(c: char) -> bool {
    c.is_control()
        || matches!(c, '\u{2028}' | '\u{2029}' | '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}')
}

/// `text` with every character that is not safe to print (`is_unsafe`: controls, DEL,
/// separators and bidirectional overrides) written as a Rust escape, `\u{1b}`; every other
/// character, any script or emoji, is kept. Borrowed when nothing needs escaping.
pub fn escape_controls(text: &str) -> Cow<'_, str> {
    if !text.chars().any(is_unsafe) {
        return Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        push_escaped(&mut out, c);
    }
    Cow::Owned(out)
}

/// Appends `c`, escaped if it is unsafe to print.
fn push_escaped(out: &mut String, c: char) {
    use fmt::Write as _;
    if is_unsafe(c) {
        let _ = write!(out, "\\u{{{:x}}}", u32::from(c));
    } else {
        out.push(c);
    }
}

/// Bytes that `c` takes once escaped.
fn escaped_len(c: char) -> usize {
    if is_unsafe(c) {
        // `\u{` + hex digits + `}`
        let digits = (32 - u32::from(c).leading_zeros()).div_ceil(4).max(1) as usize;
        4 + digits
    } else {
        c.len_utf8()
    }
}

/// `text` made safe to print: control characters escaped ([`escape_controls`]) and, if the
/// result would be longer than `max` bytes, its first three quarters and its last quarter
/// around ` … `. Reads only as much of `text` as it keeps, however long `text` is.
pub fn printable(text: &str, max: usize) -> Cow<'_, str> {
    const MARK: &str = " … ";
    // The end of the longest start of `text` that fits `budget` bytes once escaped, and
    // whether that is all of it.
    let head = |budget: usize| {
        let mut used = 0;
        for (i, c) in text.char_indices() {
            used += escaped_len(c);
            if used > budget {
                return (i, false);
            }
        }
        (text.len(), true)
    };
    if let (_, true) = head(max) {
        return escape_controls(text);
    }
    let tail_budget = max.saturating_sub(MARK.len()) / 4;
    let (head_end, _) = head(max.saturating_sub(MARK.len() + tail_budget));
    let mut tail_start = text.len();
    let mut used = 0;
    for (i, c) in text[head_end..].char_indices().rev() {
        used += escaped_len(c);
        if used > tail_budget {
            break;
        }
        tail_start = head_end + i;
    }
    let mut out = escape_controls(&text[..head_end]).into_owned();
    out.push_str(MARK);
    out.push_str(&escape_controls(&text[tail_start..]));
    Cow::Owned(out)
}

/// The line of `source` at `at`, as [`SceneError::source_line`] holds it: the whole line if it
/// fits [`MAX_SOURCE_LINE`] characters once escaped, else the characters around the column that
/// fit, about a third of them before the column, with `…` where the line goes on. `None` past
/// the end of the text.
pub fn quote_line(source: &str, at: Location) -> Option<String> {
    let start = match at.line {
        0 | 1 => 0,
        n => source.match_indices('\n').nth(n - 2)?.0 + 1,
    };
    let line = source[start..].split('\n').next().unwrap_or_default();
    let line = line.strip_suffix('\r').unwrap_or(line);
    // The byte offset of the column (the end of the line if it lies beyond).
    let col = line
        .char_indices()
        .nth(at.col.saturating_sub(1))
        .map_or(line.len(), |(i, _)| i);
    // Escaped widths in characters; a tab is shown as one space.
    let width = |c: char| {
        if is_unsafe(c) && c != '\t' {
            escaped_len(c)
        } else {
            1
        }
    };
    // A line that fits is quoted whole, so the column indexes the quote.
    let fits = line
        .chars()
        .map(width)
        .try_fold(0, |total, w| {
            (total + w <= MAX_SOURCE_LINE).then_some(total + w)
        })
        .is_some();
    let (begin, budget) = if fits {
        (0, MAX_SOURCE_LINE)
    } else {
        let budget = MAX_SOURCE_LINE - 2; // room for a `…` at each end
        let (mut begin, mut before) = (col, 0);
        for (i, c) in line[..col].char_indices().rev() {
            if before + width(c) > budget / 3 {
                break;
            }
            before += width(c);
            begin = i;
        }
        (begin, budget)
    };
    let mut used = 0;
    let mut out = String::new();
    if begin > 0 {
        out.push('…');
    }
    let mut end = begin;
    for c in line[begin..].chars() {
        if used + width(c) > budget {
            break;
        }
        used += width(c);
        end += c.len_utf8();
        if c == '\t' {
            out.push(' ');
        } else {
            push_escaped(&mut out, c);
        }
    }
    if end < line.len() {
        out.push('…');
    }
    Some(out)
}

/// A number as errors print it: short whatever its size, and read back as the same value
/// (`0.5`, `-3`, `1e308`, `1.5e-7`, `inf`, `NaN`), never the 309 digits of `1e308` that `{}`
/// writes.
pub fn number<T: Copy + Into<f64> + fmt::Display + fmt::LowerExp>(v: T) -> String {
    let x: f64 = v.into();
    if x == 0.0 || !x.is_finite() || (1e-4..1e15).contains(&x.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// A vector as errors print it: `[x, y, z]`, each coordinate as [`number`] writes it.
pub fn vector(v: glam::Vec3) -> String {
    let [x, y, z] = v.to_array().map(number);
    format!("[{x}, {y}, {z}]")
}

/// How the validated numbers of `format/number.rs` start their messages; replaced by the field's name
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
        [first, Segment::Seq { index }, rest @ ..] if key(first) == Some("lights") => {
            (Some(format!("lights[{index}]")), rest)
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
        // ron's own text names its API (`ron::Options::recursion_limit`); say what it means.
        ron::Error::ExceededRecursionLimit => format!(
            "nesting deeper than {} levels (brackets, structs or textures inside one another)",
            ron::Options::default().recursion_limit.unwrap_or_default()
        ),
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
        Some("RawLight") => "light kind".into(),
        Some("SceneCamera") => "camera kind".into(),
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

/// `path:line:col: message` (or `path: message`), safe to print: escaped and at most
/// [`MAX_MESSAGE`] bytes. How errors and `rondo check` warnings are written.
pub fn write_located(
    f: &mut fmt::Formatter<'_>,
    path: &std::path::Path,
    location: Option<Location>,
    message: &str,
) -> fmt::Result {
    let mut text = path.display().to_string();
    if let Some(l) = location {
        text.push_str(&format!(":{}:{}", l.line, l.col));
    }
    text.push_str(": ");
    // Only as much of the message as can be shown is copied.
    let room = MAX_MESSAGE.saturating_sub(text.len());
    text.push_str(&printable(message, room.max(MAX_MESSAGE / 4)));
    f.write_str(&printable(&text, MAX_MESSAGE))
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write_located(f, &self.path, self.location, &self.message)
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

    #[test]
    fn controls_are_escaped_and_other_characters_kept() {
        assert!(matches!(escape_controls("plain é 猫 🦀"), Cow::Borrowed(_)));
        assert_eq!(
            escape_controls("a\u{1b}[2J\u{7}\n\t\u{7f}\u{85}\u{9b}\u{202e}é"),
            "a\\u{1b}[2J\\u{7}\\u{a}\\u{9}\\u{7f}\\u{85}\\u{9b}\\u{202e}é"
        );
        for c in ['\0', '\u{1b}', '\u{7f}', '\u{9f}', '\u{2028}'] {
            assert_eq!(
                escaped_len(c),
                escape_controls(&c.to_string()).len(),
                "{c:?}"
            );
        }
    }

    #[test]
    fn printable_text_is_bounded_keeping_its_start_and_end() {
        assert_eq!(printable("short", 10), "short");
        let long = format!("start{}é\u{1b}end", "x".repeat(100_000));
        let p = printable(&long, 400);
        assert!(p.len() <= 400, "{}", p.len());
        assert!(
            p.starts_with("startxx") && p.ends_with("xé\\u{1b}end"),
            "{p}"
        );
        assert!(p.contains(" … "));
        // Escapes count towards the bound.
        let controls = "\u{7}".repeat(1000);
        assert!(printable(&controls, 100).len() <= 100);
        assert!(!printable(&controls, 100).chars().any(char::is_control));
    }

    #[test]
    fn a_quoted_line_is_a_window_around_the_column() {
        let at = |line, col| Location { line, col };
        let text = "first\r\nsecond\tline\n";
        assert_eq!(quote_line(text, at(1, 1)).as_deref(), Some("first"));
        assert_eq!(quote_line(text, at(2, 3)).as_deref(), Some("second line"));
        assert_eq!(quote_line(text, at(3, 1)).as_deref(), Some(""));
        assert_eq!(quote_line(text, at(4, 1)), None);
        // A line that fits is quoted whole wherever the column is, so the column indexes it.
        let fitting = format!("{}x", "a".repeat(MAX_SOURCE_LINE - 1));
        assert_eq!(
            quote_line(&fitting, at(1, MAX_SOURCE_LINE)).as_deref(),
            Some(fitting.as_str())
        );
        let long = format!("{}HERE{}", "a".repeat(5000), "b".repeat(5000));
        let q = quote_line(&long, at(1, 5001)).expect("line 1");
        assert!(
            q.chars().count() <= MAX_SOURCE_LINE,
            "{}",
            q.chars().count()
        );
        assert!(q.starts_with("…a") && q.ends_with("b…"), "{q}");
        let before = q.find("HERE").expect("the column is shown");
        assert!((20..=80).contains(&before), "{before}");
    }

    #[test]
    fn numbers_are_short_and_exact() {
        assert_eq!(number(1e308), "1e308");
        assert_eq!(number(-3e38f32), "-3e38");
        assert_eq!(number(0.1f32), "0.1");
        assert_eq!(number(-4.0), "-4");
        assert_eq!(number(1.5e-7), "1.5e-7");
        assert_eq!(number(f64::INFINITY), "inf");
        assert_eq!(number(f32::NAN), "NaN");
        for v in [1e308, 1.2345678901234567e-300, 123456.789, f64::MAX] {
            assert_eq!(number(v).parse::<f64>().ok(), Some(v));
            assert!(number(v).len() <= 24, "{}", number(v));
        }
    }
}
