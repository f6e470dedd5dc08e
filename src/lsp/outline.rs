//! What a scene or prefab text defines and where: its materials and its top-level entities,
//! read by one pass of [`super::syntax`] (so a broken buffer still has an outline up to where it
//! breaks, and past it as far as its brackets allow).
//!
//! ```ron
//! Scene(                                                     // top: "Scene"
//!     materials: { "copper": Metal(albedo: …) },            // materials[0]: "copper"
//!     entities: [ Entity(name: "tall", prefab: "box.ron") ], // entities[0]: "tall", its prefab
//! )
//! ```

use std::ops::Range;

use super::syntax::{Kind, Walker, slice, tokens};

/// A material defined by the file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MaterialDef {
    /// Its name.
    pub name: String,
    /// Its name's string literal, quotes included.
    pub key: Range<usize>,
    /// The whole entry, name to the end of the value.
    pub range: Range<usize>,
    /// The first word of the value: its kind (`Diffuse`).
    pub kind: Option<String>,
}

/// One of the file's top-level entities.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct EntityDef {
    /// Its `name`, if written.
    pub name: Option<String>,
    /// Its `name`'s string literal.
    pub name_token: Option<Range<usize>>,
    /// The entity, `Entity(` to `)`.
    pub range: Range<usize>,
    /// `material`, `prefab` and `gltf` as written, each with its string's contents' bytes.
    pub material: Option<(String, Range<usize>)>,
    /// The prefab placed.
    pub prefab: Option<(String, Range<usize>)>,
    /// The glTF file placed.
    pub gltf: Option<(String, Range<usize>)>,
    /// The shape's kind (`Sphere`), if it has one.
    pub shape: Option<String>,
}

/// A file's materials and entities.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Outline {
    /// The outermost struct's name: `Scene`, `Prefab` (or empty when not written).
    pub top: String,
    /// The `materials` map's entries, in order.
    pub materials: Vec<MaterialDef>,
    /// The `entities` list's items, in order.
    pub entities: Vec<EntityDef>,
}

impl Outline {
    /// The definition of the material `name`.
    pub fn material(&self, name: &str) -> Option<&MaterialDef> {
        self.materials.iter().find(|m| m.name == name)
    }

    /// The entity whose text holds byte `offset`.
    pub fn entity_at(&self, offset: usize) -> Option<&EntityDef> {
        let k = self.entities.partition_point(|e| e.range.end < offset);
        self.entities.get(k).filter(|e| e.range.contains(&offset))
    }

    /// Whether the file is a prefab.
    pub fn is_prefab(&self) -> bool {
        self.top == "Prefab"
    }

    /// The material names the file's entities use, in first-use order, each once.
    pub fn used_materials(&self) -> Vec<&str> {
        let mut out: Vec<&str> = Vec::new();
        for (m, _) in self.entities.iter().filter_map(|e| e.material.as_ref()) {
            if !out.contains(&m.as_str()) {
                out.push(m);
            }
        }
        out
    }
}

/// The name of the outermost struct of `text` (`Scene`, `Prefab`; empty when not written),
/// reading only up to its bracket.
pub fn top_name(text: &str) -> &str {
    let (mut last, mut found) = (None, "");
    tokens(text, |t| match t.kind {
        Kind::Open(_) => {
            if let Some(w) = last.take() {
                found = &text[w];
            }
            false
        }
        Kind::Word => {
            last = Some(t.start..t.end);
            true
        }
        _ => {
            last = None;
            true
        }
    });
    found
}

/// The outline of `text`.
pub fn outline(text: &str) -> Outline {
    let mut out = Outline::default();
    let mut w = Walker::default();
    // The material entry being read, and the entity being read.
    let mut material: Option<MaterialDef> = None;
    let mut entity: Option<EntityDef> = None;
    let key_of = |w: &Walker, depth: usize| {
        w.stack
            .get(depth)
            .map_or("", |f| slice(text, f.key.clone()))
            .to_string()
    };
    tokens(text, |t| {
        let depth = w.stack.len();
        let in_materials = depth == 2 && w.stack[1].open == b'{' && key_of(&w, 0) == "materials";
        let in_entities = depth == 2 && w.stack[1].open == b'[' && key_of(&w, 0) == "entities";
        match t.kind {
            Kind::Str { .. } if in_materials && !w.stack[1].value => {
                finish(&mut out, &mut material, t.start);
                material = Some(MaterialDef {
                    name: text[t.contents()].to_string(),
                    key: t.start..t.end,
                    range: t.start..t.end,
                    kind: None,
                });
            }
            Kind::Word if in_materials && w.stack[1].value => {
                if let Some(m) = material.as_mut().filter(|m| m.kind.is_none()) {
                    m.kind = Some(text[t.start..t.end].to_string());
                }
            }
            Kind::Comma | Kind::Close if depth == 2 && material.is_some() => {
                finish(&mut out, &mut material, t.start);
            }
            Kind::Open(b'(') if in_entities => {
                let start = entity_start(text, t.start);
                entity = Some(EntityDef {
                    range: start..text.len(),
                    ..EntityDef::default()
                });
            }
            Kind::Close if depth == 3 => {
                if let Some(mut e) = entity.take() {
                    e.range.end = t.end;
                    out.entities.push(e);
                }
            }
            Kind::Str { .. } if depth == 3 && w.stack[2].value => {
                if let Some(e) = entity.as_mut() {
                    let value = (text[t.contents()].to_string(), t.contents());
                    match key_of(&w, 2).as_str() {
                        "name" => {
                            e.name = Some(value.0);
                            e.name_token = Some(t.start..t.end);
                        }
                        "material" => e.material = Some(value),
                        "prefab" => e.prefab = Some(value),
                        "gltf" => e.gltf = Some(value),
                        _ => {}
                    }
                }
            }
            Kind::Word if depth == 3 && w.stack[2].value && key_of(&w, 2) == "shape" => {
                if let Some(e) = entity.as_mut().filter(|e| e.shape.is_none()) {
                    e.shape = Some(text[t.start..t.end].to_string());
                }
            }
            _ => {}
        }
        w.step(text, t);
        if depth == 0
            && let Some(f) = w.stack.first()
            && out.top.is_empty()
        {
            out.top = slice(text, f.name.clone()).to_string();
        }
        true
    });
    finish(&mut out, &mut material, text.len());
    if let Some(e) = entity {
        out.entities.push(e);
    }
    out
}

/// Ends the material entry being read at `end` (blanks before it left out).
fn finish(out: &mut Outline, material: &mut Option<MaterialDef>, end: usize) {
    if let Some(mut m) = material.take() {
        m.range.end = end.max(m.key.end);
        out.materials.push(m);
    }
}

/// The start of the entity whose `(` is at `open`: its `Entity` word if written.
fn entity_start(text: &str, open: usize) -> usize {
    let before = text[..open].trim_end();
    if before.ends_with("Entity") {
        before.len() - "Entity".len()
    } else {
        open
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn materials_and_entities_are_found_with_their_text() {
        let text = r#"Scene(
    materials: { "a": Diffuse(albedo: Constant((1, 1, 1))), "b": Light(emit: Constant((1, 1, 1))) },
    entities: [
        Entity(name: "x", material: "a", shape: Sphere(center: (0, 0, 0), radius: 1)),
        (prefab: "p.ron", materials: { "s": "b" }),
        Entity(name: "broken", material: "#;
        let text = &format!("{text}\"");
        let o = outline(text);
        assert_eq!(o.top, "Scene");
        assert_eq!(top_name(text), "Scene");
        assert_eq!(top_name("// c\n Prefab (x: 1)"), "Prefab");
        assert_eq!(top_name("(x: 1)"), "");
        let names: Vec<&str> = o.materials.iter().map(|m| m.name.as_str()).collect();
        assert_eq!(names, ["a", "b"]);
        assert_eq!(
            &text[o.materials[0].range.clone()],
            "\"a\": Diffuse(albedo: Constant((1, 1, 1)))"
        );
        assert_eq!(o.materials[1].kind.as_deref(), Some("Light"));
        assert_eq!(o.entities.len(), 3);
        let x = &o.entities[0];
        assert_eq!(x.name.as_deref(), Some("x"));
        assert_eq!(x.material.as_ref().map(|m| m.0.as_str()), Some("a"));
        assert_eq!(x.shape.as_deref(), Some("Sphere"));
        assert!(
            text[x.range.clone()].starts_with("Entity(") && text[x.range.clone()].ends_with("1))")
        );
        assert_eq!(
            o.entities[1].prefab.as_ref().map(|p| p.0.as_str()),
            Some("p.ron")
        );
        assert_eq!(
            o.entities[1].material, None,
            "a map's strings are not the entity's material"
        );
        assert_eq!(o.entities[2].name.as_deref(), Some("broken"));
        assert_eq!(o.used_materials(), ["a", ""]);
        let inside = text.find("radius").expect("radius");
        assert_eq!(
            o.entity_at(inside).and_then(|e| e.name.as_deref()),
            Some("x")
        );
    }
}
