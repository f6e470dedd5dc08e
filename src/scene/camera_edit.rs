//! Rewriting the camera of a scene file: the text of the top-level `camera:` field's value is
//! replaced by a new `Camera(…)`, and every other byte of the file (comments, blanks, the order
//! of fields) stays as it was. This is how the viewer's "Save camera" writes the camera a user
//! framed.
//!
//! ```ron
//! Scene(
//!     // the key light is behind the camera
//!     camera: Camera(
//!         position: (0, 1.25, -4.5),
//!         look_at: (0, 1, 0),
//!         up: (0, 1, 0),
//!         fov: 40,
//!         aperture: 0,
//!         focus_distance: 4.5069394,
//!     ),
//!     settings: …
//! ```
//!
//! The value is found with the scene lexer of [`crate::scene::incremental`] (comments and
//! strings skipped): the field `camera` at the first level of the scene's parentheses. Only a
//! scene's own `Camera(…)` is rewritten; a `Gltf(…)` camera, or none, is refused. The new value
//! writes all six numbers of [`CameraValues`] (`direction` and `focus_on` give way to `look_at`
//! and `focus_distance`), one field per line with the indentation of the old value's first
//! field (or the `camera:` line's plus four spaces), each number as the shortest decimal that
//! reads back as the same `f32`. Comments inside the old value go with it.

use std::ops::Range;
use std::path::Path;

use glam::Vec3;

use super::error::number;
use super::format::{CameraDesc, SceneCamera, parse};
use super::incremental::lexer::{Lexeme, lex_each};

/// A camera as the viewer frames it: the numbers written into `Camera(…)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraValues {
    /// Eye position.
    pub position: Vec3,
    /// The point looked at.
    pub look_at: Vec3,
    /// Up vector, not parallel to `look_at − position`.
    pub up: Vec3,
    /// Vertical field of view in degrees, in (0, 180).
    pub fov: f32,
    /// Radius of the thin lens, ≥ 0 (0: a pinhole).
    pub aperture: f32,
    /// Distance of the plane of focus, > 0.
    pub focus_distance: f32,
}

/// Why the camera cannot be rewritten.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CameraEditError {
    /// The text does not lex (an unterminated string or comment) or its brackets do not match.
    #[error("the scene file does not read as RON (an unclosed string, comment or bracket)")]
    Unreadable,
    /// No top-level `camera:` field.
    #[error("the scene file has no top-level `camera:` field")]
    Absent,
    /// More than one top-level `camera:` field.
    #[error("the scene file has more than one top-level `camera:` field")]
    Repeated,
    /// The camera is not the scene's own `Camera(…)`; the name it has instead, if any.
    #[error(
        "the scene's camera is {}, not `Camera(…)`: only a camera of the scene's own can be written",
        match .0 { Some(name) => format!("`{name}(…)`"), None => "not a named value".to_string() }
    )]
    NotOwn(Option<String>),
    /// The new camera breaks a rule of the scene format.
    #[error("invalid camera: {0}")]
    Invalid(String),
}

/// Where the camera is written in a scene file.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraSpan {
    /// The value `Camera(…)`, from its name to just past its `)`.
    pub value: Range<usize>,
    /// The indentation of the `camera:` line (empty if other text precedes `camera` on it).
    pub indent: String,
    /// The indentation of the value's first field, if it starts a line of its own.
    pub field_indent: Option<String>,
}

/// Finds the value of the top-level `camera:` field of the scene text `text`: a `Camera(…)`,
/// else an error (none, two, a `Gltf(…)` or another value, text that does not lex).
pub fn camera_span(text: &str) -> Result<CameraSpan, CameraEditError> {
    /// Where the scan stands.
    #[derive(Clone, Copy)]
    enum Phase {
        /// Looking for `camera` at the scene's first level.
        Seek,
        /// After `camera` (its offset), before `:`.
        Word(usize),
        /// After `camera :`, before the value.
        Colon(usize),
        /// After the value's name (its range), before its `(`.
        Named(usize, usize, usize),
        /// Inside the value that started at this offset.
        Inside(usize, usize),
    }
    // `scene` is whether the first level is inside `(`: not an attribute's `#![…]`.
    let (mut phase, mut depth, mut scene) = (Phase::Seek, 0usize, false);
    let mut found: Option<Result<(usize, Range<usize>), CameraEditError>> = None;
    let mut error = None;
    let b = text.as_bytes();
    let lexed = lex_each(text, |at, l| {
        let level = depth;
        match l {
            Lexeme::Open => {
                if depth == 0 {
                    scene = b[at] == b'(';
                }
                depth += 1;
            }
            Lexeme::Close => match depth.checked_sub(1) {
                Some(d) => depth = d,
                None => {
                    error = Some(CameraEditError::Unreadable);
                    return false;
                }
            },
            _ => {}
        }
        phase = match (phase, l) {
            (Phase::Seek, Lexeme::Word(s, e)) if level == 1 && scene && &text[s..e] == "camera" => {
                if found.is_some() {
                    error = Some(CameraEditError::Repeated);
                    return false;
                }
                Phase::Word(s)
            }
            (Phase::Seek, _) => Phase::Seek,
            (Phase::Word(w), Lexeme::Colon) => Phase::Colon(w),
            // `camera` not followed by `:` is not the field.
            (Phase::Word(_), _) => Phase::Seek,
            (Phase::Colon(w), Lexeme::Word(s, e)) => Phase::Named(w, s, e),
            (Phase::Colon(_), _) => {
                found = Some(Err(CameraEditError::NotOwn(None)));
                Phase::Seek
            }
            (Phase::Named(w, s, e), Lexeme::Open) if &text[s..e] == "Camera" => Phase::Inside(w, s),
            (Phase::Named(_, s, e), _) => {
                found = Some(Err(CameraEditError::NotOwn(Some(text[s..e].to_string()))));
                Phase::Seek
            }
            (Phase::Inside(w, s), Lexeme::Close) if depth == 1 => {
                found = Some(Ok((w, s..at + 1)));
                Phase::Seek
            }
            (p @ Phase::Inside(..), _) => p,
        };
        true
    });
    if let Some(e) = error {
        return Err(e);
    }
    if lexed.is_none() || depth != 0 || matches!(phase, Phase::Inside(..)) {
        return Err(CameraEditError::Unreadable);
    }
    let (word, value) = found.ok_or(CameraEditError::Absent)??;
    Ok(CameraSpan {
        indent: line_indent(text, word).unwrap_or_default().to_string(),
        field_indent: first_field_indent(text, &value).map(str::to_string),
        value,
    })
}

/// The blanks from the start of the line holding `at` to `at`, if only blanks precede it.
fn line_indent(text: &str, at: usize) -> Option<&str> {
    let start = text[..at].rfind('\n').map_or(0, |n| n + 1);
    let indent = &text[start..at];
    indent
        .bytes()
        .all(|c| c == b' ' || c == b'\t')
        .then_some(indent)
}

/// The indentation of the first lexeme inside the value `Camera(…)` at `value`, if it starts a
/// line of its own (after the value's `(`).
fn first_field_indent<'a>(text: &'a str, value: &Range<usize>) -> Option<&'a str> {
    let open = value.start + text[value.clone()].find('(')?;
    let inner = &text[open + 1..value.end - 1];
    let mut first = None;
    lex_each(inner, |at, _| {
        first = Some(open + 1 + at);
        false
    })?;
    let at = first?;
    let indent = line_indent(text, at)?;
    (at - indent.len() > open).then_some(indent)
}

/// A number written so that it reads back as the same `f32` (`-0` as `0`).
fn write_number(v: f32) -> String {
    number(if v == 0.0 { 0.0 } else { v })
}

fn write_vector(v: Vec3) -> String {
    let [x, y, z] = v.to_array().map(write_number);
    format!("({x}, {y}, {z})")
}

/// The text `Camera(…)` of `camera`, one field per line indented by `field_indent`, its `)` by
/// `indent`.
pub fn camera_text(camera: &CameraValues, indent: &str, field_indent: &str) -> String {
    let fields = [
        ("position", write_vector(camera.position)),
        ("look_at", write_vector(camera.look_at)),
        ("up", write_vector(camera.up)),
        ("fov", write_number(camera.fov)),
        ("aperture", write_number(camera.aperture)),
        ("focus_distance", write_number(camera.focus_distance)),
    ];
    let mut out = String::from("Camera(\n");
    for (name, value) in fields {
        out.push_str(&format!("{field_indent}{name}: {value},\n"));
    }
    out.push_str(indent);
    out.push(')');
    out
}

/// Checks `camera` by the rules of the scene format (the text [`camera_text`] writes, read as a
/// scene's camera is) and returns the camera it reads as. Its position, fov, aperture and focus
/// distance must read back as the same numbers.
pub fn check_camera(camera: &CameraValues) -> Result<CameraDesc, CameraEditError> {
    let text = camera_text(camera, "", "");
    let desc = match parse::<SceneCamera>(Path::new("camera"), &text) {
        Ok(SceneCamera::Camera(desc)) => desc,
        Ok(SceneCamera::Gltf(_)) => return Err(CameraEditError::NotOwn(Some("Gltf".into()))),
        Err(e) => return Err(CameraEditError::Invalid(e.message)),
    };
    let same = desc.position == camera.position
        && desc.fov == camera.fov
        && desc.aperture == camera.aperture
        && desc.focus_distance == camera.focus_distance;
    if !same {
        return Err(CameraEditError::Invalid(
            "the numbers do not read back as written".into(),
        ));
    }
    Ok(desc)
}

/// The scene text `text` with the value of its top-level `camera:` replaced by `camera`
/// (checked by [`check_camera`]); every byte before and after the value is kept.
pub fn replace_camera(text: &str, camera: &CameraValues) -> Result<String, CameraEditError> {
    check_camera(camera)?;
    let span = camera_span(text)?;
    let field_indent = span
        .field_indent
        .clone()
        .unwrap_or_else(|| format!("{}    ", span.indent));
    let value = camera_text(camera, &span.indent, &field_indent);
    let mut out = String::with_capacity(text.len() + value.len());
    out.push_str(&text[..span.value.start]);
    out.push_str(&value);
    out.push_str(&text[span.value.end..]);
    Ok(out)
}

/// The scene text `text` with the value of its top-level `camera:` replaced by `value`, as
/// written (an undo puts a camera's earlier text back, comments and all). `value` must read as
/// a scene's own `Camera(…)` and end where the value ends: nothing in it may swallow the text
/// that follows (a trailing `//` comment would hide the field's comma).
pub fn restore_camera(text: &str, value: &str) -> Result<String, CameraEditError> {
    match parse::<SceneCamera>(Path::new("camera"), value) {
        Ok(SceneCamera::Camera(_)) => {}
        Ok(SceneCamera::Gltf(_)) => return Err(CameraEditError::NotOwn(Some("Gltf".into()))),
        Err(e) => return Err(CameraEditError::Invalid(e.message)),
    }
    let span = camera_span(text)?;
    let mut out = String::with_capacity(text.len() + value.len());
    out.push_str(&text[..span.value.start]);
    out.push_str(value);
    out.push_str(&text[span.value.end..]);
    let end = span.value.start + value.len();
    if camera_span(&out).ok().map(|s| s.value) != Some(span.value.start..end) {
        return Err(CameraEditError::Invalid(
            "the camera's text does not end where its value ends".into(),
        ));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::format::SceneDesc;

    #[test]
    fn a_camera_s_text_goes_back_byte_for_byte_and_cannot_swallow_what_follows() {
        let old = "Camera(\n        // the eye\n        position: (0, 1, -5),\n        direction: (0, 0, 1), focus_on: (0, 0, 3), aperture: 0.1,\n    )";
        let written = replace_camera(SCENE, &values()).expect("written");
        assert_ne!(written, SCENE);
        assert_eq!(restore_camera(&written, old).as_deref(), Ok(SCENE));
        for bad in [
            "Camera(position: (0, 1, -5)) // hides the comma",
            "Camera(position: (0, 1, -5)) /* unclosed",
            "Gltf(placement: \"x\")",
            "Camera(position: (0, 1, -5)), materials: {}",
            "Camera(fov: 200, position: (0, 0, 0))",
        ] {
            assert!(restore_camera(&written, bad).is_err(), "{bad}");
        }
    }

    const SCENE: &str = r#"#![enable(implicit_some)]
// A scene: the camera below is rewritten, nothing else.
Scene(
    /* camera: Gltf(placement: "x") in a comment */
    settings: Settings(width: 8, height: 8, spp: 1), // "camera": not the field
    camera: Camera(
        // the eye
        position: (0, 1, -5),
        direction: (0, 0, 1), focus_on: (0, 0, 3), aperture: 0.1,
    ),
    materials: {
        "camera": Diffuse(albedo: Constant((0.5, 0.5, 0.5))), // camera: Camera(
    },
    entities: [
        Entity(name: "camera", material: "camera", shape: Sphere(center: (0, 0, 0), radius: 1)),
    ],
)
"#;

    fn values() -> CameraValues {
        CameraValues {
            position: Vec3::new(0.1, -2.5e-7, 123456.79),
            look_at: Vec3::new(1.0 / 3.0, 0.0, -7.25),
            up: Vec3::new(0.0, 1.0, 1e-3),
            fov: 33.333332,
            aperture: 0.05,
            focus_distance: 7.1,
        }
    }

    #[test]
    fn only_the_camera_value_changes() {
        let new = replace_camera(SCENE, &values()).expect("replaced");
        let start = SCENE.find("Camera(\n        // the eye").expect("value");
        let end = SCENE.find("\n    materials").expect("after") - 1;
        assert_eq!(&SCENE[end - 5..end], "    )");
        assert_eq!(new[..start], SCENE[..start]);
        let tail = SCENE.len() - end;
        assert_eq!(new[new.len() - tail..], SCENE[end..]);
        // The fields take the old value's indentation, the `)` the `camera:` line's.
        assert!(
            new.contains("    camera: Camera(\n        position: (0.1, -2.5e-7, 123456.79),\n"),
            "{new}"
        );
        assert!(
            new.contains("        focus_distance: 7.1,\n    ),\n    materials"),
            "{new}"
        );
        assert!(!new.contains("focus_on") && !new.contains("direction"));
    }

    #[test]
    fn the_new_text_loads_as_the_camera_given() {
        let v = values();
        let new = replace_camera(SCENE, &v).expect("replaced");
        let scene: SceneDesc = parse(Path::new("scene.ron"), &new).expect("parses");
        let SceneCamera::Camera(c) = scene.camera else {
            panic!("a Camera")
        };
        assert_eq!(c.position, v.position);
        // The loader keeps the direction scaled by its largest component.
        let d = v.look_at - v.position;
        assert_eq!(c.direction, d / d.abs().max_element());
        assert_eq!(c.up, v.up);
        assert_eq!(
            (c.fov, c.aperture, c.focus_distance),
            (v.fov, v.aperture, v.focus_distance)
        );
        assert_eq!(scene.entities.len(), 1);
        assert!(scene.materials.contains_key("camera"));
    }

    #[test]
    fn every_f32_reads_back_exactly() {
        // A deterministic sweep of bit patterns (xorshift), all finite values of every
        // exponent, plus the edges.
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut values = vec![
            f32::MIN_POSITIVE,
            f32::MAX,
            1e-45,
            16777217.0,
            0.1,
            1e16,
            1e-5,
        ];
        while values.len() < 3000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let v = f32::from_bits(state as u32);
            if v.is_finite() {
                values.push(v);
            }
        }
        for chunk in values.chunks(3) {
            let [x, y, z] = [0, 1, 2].map(|i| chunk.get(i).copied().unwrap_or(1.0));
            let text = format!("[{}]", write_vector(Vec3::new(x, y, z)));
            let read: Vec<[f32; 3]> = parse(Path::new("v"), &text).expect("reads");
            let same = read[0]
                .iter()
                .zip([x, y, z])
                .all(|(a, b)| a.to_bits() == b.to_bits() || (*a == 0.0 && b == 0.0));
            assert!(same, "{text} read as {read:?}, not {:?}", [x, y, z]);
        }
    }

    #[test]
    fn a_one_line_camera_becomes_one_field_per_line() {
        let text =
            "Scene(\n  camera: Camera(position: (0, 0, -5), look_at: (0, 0, 0), fov: 40),\n)\n";
        let new = replace_camera(text, &values()).expect("replaced");
        assert!(
            new.starts_with("Scene(\n  camera: Camera(\n      position: ("),
            "{new}"
        );
        assert!(new.ends_with(",\n  ),\n)\n"), "{new}");
        let one_line = "(camera: Camera(position: (0, 0, -5), look_at: (0, 0, 0)))";
        let new = replace_camera(one_line, &values()).expect("replaced");
        assert!(new.starts_with("(camera: Camera(\n    position:"), "{new}");
        assert!(new.ends_with("\n))"), "{new}");
        parse::<SceneDesc>(Path::new("s"), &new).expect("parses");
    }

    #[test]
    fn only_a_camera_of_the_scene_s_own_is_rewritten() {
        let gltf = "Scene(camera: Gltf(placement: \"helmet\"), entities: [])";
        assert_eq!(
            replace_camera(gltf, &values()),
            Err(CameraEditError::NotOwn(Some("Gltf".into())))
        );
        let absent = "Scene(settings: Settings(camera: 1), entities: [])";
        assert_eq!(
            replace_camera(absent, &values()),
            Err(CameraEditError::Absent)
        );
        let commented = "Scene(\n// camera: Camera(position: (0, 0, 0)),\n)";
        assert_eq!(
            replace_camera(commented, &values()),
            Err(CameraEditError::Absent)
        );
        let twice = "Scene(camera: Camera(), camera: Camera())";
        assert_eq!(
            replace_camera(twice, &values()),
            Err(CameraEditError::Repeated)
        );
        let unnamed = "Scene(camera: (position: (0, 0, 0)))";
        assert_eq!(
            replace_camera(unnamed, &values()),
            Err(CameraEditError::NotOwn(None))
        );
        for broken in [
            "Scene(camera: Camera(position: (0, 0, 0))",
            "Scene(camera: Camera(\"), )",
            "))(",
        ] {
            assert_eq!(
                replace_camera(broken, &values()),
                Err(CameraEditError::Unreadable),
                "{broken}"
            );
        }
    }

    #[test]
    fn cameras_are_checked_by_the_scene_format_s_rules() {
        let v = values();
        let bad = [
            CameraValues { fov: 180.0, ..v },
            CameraValues { fov: 0.0, ..v },
            CameraValues {
                aperture: -0.1,
                ..v
            },
            CameraValues {
                focus_distance: 0.0,
                ..v
            },
            CameraValues {
                position: Vec3::new(f32::NAN, 0.0, 0.0),
                ..v
            },
            CameraValues {
                look_at: Vec3::new(0.0, f32::INFINITY, 0.0),
                ..v
            },
            CameraValues {
                look_at: v.position,
                ..v
            },
            CameraValues {
                up: v.look_at - v.position,
                ..v
            },
            CameraValues {
                up: Vec3::ZERO,
                ..v
            },
            CameraValues {
                position: Vec3::new(1e30, 0.0, 0.0),
                ..v
            },
        ];
        for camera in bad {
            let refused = replace_camera(SCENE, &camera);
            assert!(
                matches!(refused, Err(CameraEditError::Invalid(_))),
                "{camera:?}: {refused:?}"
            );
        }
    }
}
