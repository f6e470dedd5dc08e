//! The text of the viewer's events: times in milliseconds, file names, what a reload changed,
//! and messages cut to a bound (see the event list in `feed.rs`).

use std::path::PathBuf;
use std::time::Duration;

use crate::ecs::resources::ChangeSummary;

/// The longest error message (and file name) an event carries, in bytes.
pub const MAX_MESSAGE: usize = 4096;

/// The longest source line an error event quotes, in characters.
pub const MAX_SOURCE_LINE: usize = 512;

/// What ends a message or source line that was cut.
pub const CUT: &str = " …[cut]";

/// `d` in milliseconds, to the microsecond.
pub(super) fn ms(d: Duration) -> f64 {
    (d.as_secs_f64() * 1e6).round() / 1e3
}

/// The file names of `paths` (the whole path where it has none).
pub(super) fn names(paths: &[PathBuf]) -> Vec<String> {
    paths
        .iter()
        .map(|p| {
            p.file_name()
                .map_or_else(|| p.display().to_string(), |n| n.to_string_lossy().into())
        })
        .collect()
}

/// What a reload changed, in words: `materials`, `2 entities changed, camera`, `nothing`.
pub fn changed_text(c: &ChangeSummary) -> String {
    let counts = [
        (c.added, "added"),
        (c.changed, "changed"),
        (c.removed, "removed"),
    ]
    .into_iter()
    .filter(|(n, _)| *n > 0)
    .map(|(n, what)| format!("{n} {} {what}", if n == 1 { "entity" } else { "entities" }));
    let flags = [
        (c.materials, "materials"),
        (c.camera, "camera"),
        (c.settings, "settings"),
        (c.sky, "sky"),
        (c.lights, "lights"),
        (c.reordered, "order"),
    ]
    .into_iter()
    .filter(|(on, _)| *on)
    .map(|(_, what)| what.to_string());
    let parts: Vec<String> = counts.chain(flags).collect();
    if parts.is_empty() {
        "nothing".into()
    } else {
        parts.join(", ")
    }
}

/// `text` if it has at most `max` bytes, else its longest start of at most `max` bytes that
/// ends on a character boundary, followed by [`CUT`].
pub(super) fn bounded(text: &str, max: usize) -> String {
    if text.len() <= max {
        return text.to_string();
    }
    let end = (0..=max)
        .rev()
        .find(|&i| text.is_char_boundary(i))
        .unwrap_or(0);
    format!("{}{CUT}", &text[..end])
}

/// `text` if it has at most `max` characters, else its first `max` followed by [`CUT`].
pub(super) fn bounded_chars(text: &str, max: usize) -> String {
    match text.char_indices().nth(max) {
        Some((end, _)) => format!("{}{CUT}", &text[..end]),
        None => text.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_texts_are_cut_on_a_character_boundary() {
        assert_eq!(bounded("short", 5), "short");
        assert_eq!(bounded("ééé", 3), format!("é{CUT}"));
        assert_eq!(bounded("ééé", 1), CUT);
        let long = "x".repeat(10 * MAX_MESSAGE);
        assert_eq!(bounded(&long, MAX_MESSAGE).len(), MAX_MESSAGE + CUT.len());
        assert_eq!(bounded_chars("ééé", 3), "ééé");
        assert_eq!(bounded_chars("éééé", 3), format!("ééé{CUT}"));
    }
}
