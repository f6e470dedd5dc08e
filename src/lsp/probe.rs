//! Which fields a struct at the cursor takes, and which kinds a value there can be, asked of
//! the scene format's own types: the brackets around the cursor are written out again around a
//! field or variant name that exists nowhere, and the loader's parser is asked to read it. Its
//! error lists what it expected (`unknown field … expected name, material, shape, …`), from the
//! same serde definitions that loading uses, so completion never disagrees with the loader and
//! needs no list of its own.
//!
//! ```text
//! Scene(entities: [Entity(name: "a", sh|        →  Scene(entities: [Entity(rondo_probe_: 0)])
//!                                                   → expected name, material, shape, prefab, …
//! Scene(entities: [Entity(shape: |              →  Scene(entities: [Entity(shape: RondoProbe)])
//!                                                   → expected Sphere, Plane, Triangle, …
//! ```

use crate::scene::format::{PrefabDesc, SceneDesc};

use super::syntax::{Frame, slice};

/// What the cursor is about to write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Slot {
    /// A field name of the struct it is in.
    Field,
    /// The value of the field (or map key, or list item) it is at.
    Value,
}

/// A field name that no struct of the format has.
const FIELD: &str = "rondo_probe_";
/// A variant name that no enum of the format has.
const VARIANT: &str = "RondoProbe";

/// The names the format accepts at `slot` inside `frames` (outermost first, as read from
/// `text`): field names for [`Slot::Field`], kind names (variants) for [`Slot::Value`]. Empty
/// when the place takes neither (a number, a string, a tuple).
pub fn expected(text: &str, frames: &[Frame], slot: Slot, prefab: bool) -> Vec<&'static str> {
    let Some(probe) = probe_text(text, frames, slot) else {
        return Vec::new();
    };
    let options =
        ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
    let error = if prefab {
        options.from_str::<PrefabDesc>(&probe).err()
    } else {
        options.from_str::<SceneDesc>(&probe).err()
    };
    let Some(error) = error else {
        return Vec::new();
    };
    match (error.code, slot) {
        (
            ron::Error::NoSuchStructField {
                expected, found, ..
            },
            Slot::Field,
        ) if found == FIELD => expected.to_vec(),
        (
            ron::Error::NoSuchEnumVariant {
                expected, found, ..
            },
            Slot::Value,
        ) if found == VARIANT => {
            // Lower-case names are serde aliases kept for old files; offer the written form.
            expected
                .iter()
                .copied()
                .filter(|v| v.starts_with(char::is_uppercase))
                .collect()
        }
        _ => Vec::new(),
    }
}

/// The brackets of `frames` written out again around the probe: `Name(` and the field being
/// written (`key: `) for each `(`, `"k": ` for each map, nothing for a list; then the probe and
/// the closing brackets. `None` when the innermost bracket does not take `slot` there.
fn probe_text(text: &str, frames: &[Frame], slot: Slot) -> Option<String> {
    let (last, outer) = frames.split_last()?;
    let mut s = String::with_capacity(128);
    for f in outer {
        s.push_str(slice(text, f.name.clone()));
        s.push(f.open as char);
        match f.open {
            b'(' => {
                if let Some(key) = f.key.clone().filter(|_| f.value) {
                    s.push_str(slice(text, Some(key)));
                    s.push_str(": ");
                }
            }
            b'{' => s.push_str("\"k\": "),
            _ => {}
        }
    }
    s.push_str(slice(text, last.name.clone()));
    s.push(last.open as char);
    match (last.open, slot) {
        (b'(', Slot::Field) => {
            s.push_str(FIELD);
            s.push_str(": 0");
        }
        (b'(', Slot::Value) => {
            let key = slice(text, last.key.clone().filter(|_| last.value));
            if key.is_empty() {
                return None;
            }
            s.push_str(key);
            s.push_str(": ");
            s.push_str(VARIANT);
        }
        (b'{', Slot::Value) if last.value => {
            s.push_str("\"k\": ");
            s.push_str(VARIANT);
        }
        (b'[', Slot::Value) => s.push_str(VARIANT),
        _ => return None,
    }
    for f in frames.iter().rev() {
        s.push(match f.open {
            b'(' => ')',
            b'[' => ']',
            _ => '}',
        });
    }
    Some(s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lsp::syntax::context_at;

    fn at(text: &str, slot: Slot) -> Vec<&'static str> {
        let c = context_at(text, text.len());
        expected(text, &c.frames, slot, false)
    }

    #[test]
    fn fields_and_kinds_come_from_the_format() {
        let mut fields = at("Scene(entities: [Entity(name: \"a\", ", Slot::Field);
        fields.sort_unstable();
        assert_eq!(
            fields,
            [
                "gltf",
                "material",
                "materials",
                "name",
                "prefab",
                "shape",
                "transform"
            ]
        );
        assert_eq!(
            at("Scene(entities: [Entity(shape: ", Slot::Value),
            ["Sphere", "Plane", "Triangle", "Quad", "Box", "Mesh"]
        );
        assert_eq!(
            at("Scene(entities: [Entity(shape: Sphere(", Slot::Field),
            ["center", "radius"]
        );
        let materials = at("Scene(materials: { \"a\": ", Slot::Value);
        assert_eq!(
            materials,
            ["Diffuse", "Metal", "Glossy", "Dielectric", "Light", "Pbr"]
        );
        assert_eq!(
            at("Scene(materials: { \"a\": Diffuse(albedo: ", Slot::Value),
            ["Constant", "Checker", "Image"]
        );
        assert!(at("Scene(entities: [Entity(name: ", Slot::Value).is_empty());
    }
}
