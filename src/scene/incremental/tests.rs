//! Tests of the incremental parse: an edit parses as a full parse does.

use super::*;

const SCENE: &str = r#"Scene(
    camera: Camera(position: (0, 0, -5), look_at: (0, 0, 0)),
    materials: { "m": Diffuse(albedo: Constant((0.5, 0.5, 0.5))) },
    entities: [
        Entity(name: "a", material: "m", shape: Sphere(center: (0, 0, 0), radius: 1)),
        // a comment with ( and "
        Entity(name: "b)", material: "m", shape: Sphere(center: (2, 0, 0), radius: 1)), /* ( */
        (name: "c", material: "m", shape: Sphere(center: (4, 0, 0), radius: 1)),
    ],
)"#;

fn full(text: &str) -> SceneDesc {
    parse(Path::new("s.ron"), text).expect("parses")
}

/// `SCENE` parsed, then `edited` parsed from it: the description (as text), the entities
/// parsed and the spans kept, or the error's text.
fn after_edit(edited: &str) -> Result<(String, usize, Option<Spans>), String> {
    let path = Path::new("s.ron");
    let mut kept = None;
    parse_scene_text(path, SCENE.to_string(), &mut kept).expect("parses");
    parse_scene_text(path, edited.to_string(), &mut kept)
        .map(|(p, n)| (format!("{:?}", p.desc()), n, p.spans.clone()))
        .map_err(|e| e.to_string())
}

/// A full parse of `edited`: the description (as text), or the error's text.
fn full_parse(edited: &str) -> Result<String, String> {
    parse::<SceneDesc>(Path::new("s.ron"), edited)
        .map(|d| format!("{d:?}"))
        .map_err(|e| e.to_string())
}

#[test]
fn entity_spans_cover_each_entity_whatever_the_comments_and_strings() {
    let spans = entity_spans(SCENE).expect("found");
    let texts: Vec<&str> = spans.entities.iter().map(|r| &SCENE[r.clone()]).collect();
    let list = &SCENE[spans.list];
    assert!(list.starts_with("[\n        Entity(name: \"a\"") && list.ends_with(']'));
    assert_eq!(texts.len(), 3);
    assert!(texts[0].starts_with("Entity(name: \"a\"") && texts[0].ends_with("radius: 1))"));
    assert!(texts[1].starts_with("Entity(name: \"b)\""));
    assert!(texts[2].starts_with("(name: \"c\"") && texts[2].ends_with("radius: 1))"));
}

#[test]
fn an_edit_inside_one_entity_reparses_only_it_and_equals_a_full_parse() {
    let path = Path::new("s.ron");
    let mut kept = None;
    let (_, n) = parse_scene_text(path, SCENE.to_string(), &mut kept).expect("parses");
    assert_eq!(n, 3);
    let edited = SCENE.replace(
        "center: (2, 0, 0), radius: 1",
        "center: (2, 1, 0), radius: 0.5",
    );
    let (_, n) = parse_scene_text(path, edited.clone(), &mut kept).expect("parses");
    assert_eq!(n, 1, "only the edited entity is parsed");
    let reference = full(&edited);
    let desc = |kept: &Option<ParsedScene>| format!("{:?}", kept.as_ref().map(|p| p.desc()));
    assert_eq!(desc(&kept), format!("{:?}", Some(reference)));
    // A second edit, of another entity, works from the spliced parse.
    let again = edited.replace("\"c\"", "\"cc\"");
    let (_, n) = parse_scene_text(path, again.clone(), &mut kept).expect("parses");
    assert_eq!(n, 1);
    assert_eq!(desc(&kept), format!("{:?}", Some(full(&again))));
}

#[test]
fn edits_outside_whole_entities_parse_the_whole_file() {
    let path = Path::new("s.ron");
    let cases = [
            // Between entities: a new one.
            SCENE.replace("/* ( */", "Entity(name: \"d\", material: \"m\", shape: Sphere(center: (6, 0, 0), radius: 1)),"),
            // Outside the list (read around it: see the next test).
            SCENE.replace("(0.5, 0.5, 0.5)", "(0.25, 0.5, 0.5)"),
            // A trailing comma inside the run would read as a list but not in the file.
            SCENE.replace("radius: 1)), /* ( */", "radius: 1)),, /* ( */"),
            // One entity split into two.
            SCENE.replace(
                "Entity(name: \"a\", material: \"m\", shape: Sphere(center: (0, 0, 0), radius: 1))",
                "Entity(name: \"a\", material: \"m\", shape: Sphere(center: (0, 0, 0), radius: 1)), Entity(name: \"a2\", material: \"m\", shape: Sphere(center: (0, 3, 0), radius: 1))",
            ),
        ];
    for edited in cases {
        match (after_edit(&edited), full_parse(&edited)) {
            (Ok((ours, _, _)), Ok(reference)) => assert_eq!(ours, reference),
            (Err(a), Err(b)) => assert_eq!(a, b),
            (a, b) => panic!("{edited}: {a:?} against {b:?}"),
        }
    }
    let mut kept = None;
    parse_scene_text(path, SCENE.to_string(), &mut kept).expect("parses");
    let split = SCENE.replace("(name: \"c\"", "Entity(name: \"c\"");
    let (_, n) = parse_scene_text(path, split, &mut kept).expect("parses");
    assert_eq!(
        n, 1,
        "renaming the struct of one entity is an edit inside it"
    );
}

#[test]
fn a_broken_entity_is_the_error_a_full_parse_gives_and_keeps_the_last_good_parse() {
    let path = Path::new("s.ron");
    let mut kept = None;
    parse_scene_text(path, SCENE.to_string(), &mut kept).expect("parses");
    let broken = SCENE.replace("(4, 0, 0), radius: 1", "(4, 0, 0), radius: oops");
    let e = parse_scene_text(path, broken.clone(), &mut kept)
        .err()
        .expect("fails");
    let reference = parse::<SceneDesc>(path, &broken).expect_err("fails too");
    assert_eq!(e.to_string(), reference.to_string());
    // The mended save starts from the parse before the broken one.
    let mended = SCENE.replace("(4, 0, 0), radius: 1", "(4, 0, 0), radius: 2");
    let (_, n) = parse_scene_text(path, mended.clone(), &mut kept).expect("parses");
    assert_eq!(n, 1, "one entity parsed after the broken save");
    let desc = kept.as_ref().map(|p| format!("{:?}", p.desc()));
    assert_eq!(desc, Some(format!("{:?}", full(&mended))));
}

#[test]
fn an_edit_outside_the_list_parses_no_entity_and_equals_a_full_parse() {
    let cases = [
        // A material, before the list: the spans move.
        SCENE.replace("(0.5, 0.5, 0.5)", "(0.25, 0.5, 0.5)"),
        SCENE.replace("(0.5, 0.5, 0.5)", "(0.5, 0.5, 0.5), roughness: 1"),
        // The camera, and a comment after the list.
        SCENE.replace("(0, 0, -5)", "(0, 1, -50)"),
        SCENE.replace("    ],\n)", "    ], // done\n)"),
    ];
    for edited in cases {
        match (after_edit(&edited), full_parse(&edited)) {
            (Ok((ours, n, spans)), Ok(reference)) => {
                assert_eq!(n, 0, "no entity parsed: {edited}");
                assert_eq!(ours, reference);
                assert_eq!(spans, entity_spans(&edited));
            }
            (Err(a), Err(b)) => assert_eq!(a, b),
            (a, b) => panic!("{edited}: {a:?} against {b:?}"),
        }
    }
    // Text before the list that would swallow it (an open raw string, a comment) is not
    // read around it: the whole file is parsed, as a full parse reads it.
    for opener in ["r#\"", "/*", "\""] {
        let edited = SCENE.replace("camera:", &format!("{opener}camera:"));
        match (after_edit(&edited), full_parse(&edited)) {
            (Ok((ours, n, _)), Ok(reference)) => {
                assert_eq!(ours, reference);
                assert_eq!(n, 3, "parsed in full");
            }
            (Err(a), Err(b)) => assert_eq!(a, b),
            (a, b) => panic!("{opener}: {a:?} against {b:?}"),
        }
    }
}

#[test]
fn random_edits_parse_as_a_full_parse_does() {
    let path = Path::new("s.ron");
    let entity = |i: usize| {
        format!(
            "        Entity(name: \"e{i}\", material: \"m\", shape: Sphere(center: ({i}, 0, 0), radius: 0.{i}1)),\n"
        )
    };
    let mut text = String::from(
        "Scene(\n    camera: Camera(position: (0, 0, -5), look_at: (0, 0, 0)),\n    materials: { \"m\": Diffuse(albedo: Constant((0.5, 0.5, 0.5))) },\n    entities: [\n",
    );
    for i in 0..30 {
        text += &entity(i);
    }
    text += "    ],\n)\n";
    let pieces = [
        "1", "9", ",", ")", "(", "\"", "Entity(", " ", "// x\n", "/*", "*/", "r#\"", "'",
    ];
    let mut rng = crate::shading::rng::Rng::new(7, 11);
    let mut below = |n: usize| rng.next_u32() as usize % n.max(1);
    let mut kept = None;
    parse_scene_text(path, text.clone(), &mut kept).expect("parses");
    let (mut reused, mut total) = (0, 0);
    for round in 0..3000 {
        let mut edited = text.clone();
        let at = below(edited.len());
        let at = (at..edited.len())
            .find(|&k| edited.is_char_boundary(k))
            .unwrap_or(0);
        match round % 4 {
            0 => edited.insert_str(at, pieces[below(pieces.len())]),
            1 => {
                let end = (at + 1 + below(8)).min(edited.len());
                if edited.is_char_boundary(end) {
                    edited.replace_range(at..end, "");
                }
            }
            2 => {
                // A digit changed: most such edits stay inside one entity.
                if let Some(k) = edited[at..].find(|c: char| c.is_ascii_digit()) {
                    let k = at + k;
                    edited.replace_range(k..k + 1, &below(10).to_string());
                }
            }
            _ => edited.insert_str(at, &entity(100 + round)),
        }
        let full = parse::<SceneDesc>(path, &edited);
        match parse_scene_text(path, edited.clone(), &mut kept) {
            Ok((parsed, n)) => {
                let full = full.as_ref().expect("a full parse succeeds too");
                assert_eq!(
                    format!("{:?}", parsed.desc()),
                    format!("{full:?}"),
                    "round {round}: {edited}"
                );
                // The spans carried over are those a fresh scan finds.
                if parsed.spans.is_some() {
                    assert_eq!(parsed.spans, entity_spans(&parsed.text), "round {round}");
                }
                total += 1;
                if n < parsed.desc().entities.len() {
                    reused += 1;
                }
                text = edited;
            }
            Err(e) => {
                let full = full.as_ref().expect_err("a full parse fails too");
                assert_eq!(e.to_string(), full.to_string(), "round {round}");
                // The last good parse is kept: the next edit starts from `text` again.
                let parsed = kept.as_ref().expect("kept");
                assert_eq!(parsed.text, text, "round {round}");
            }
        }
    }
    assert!(
        reused > total / 4,
        "{reused} of {total} successful edits reused entities"
    );
}
