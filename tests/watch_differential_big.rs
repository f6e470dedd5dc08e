//! The differential watch test (see `common/watch_diff.rs`) on a big generated scene: a scene
//! file of 10⁴ named entities (spheres, quads, prefab placements, a few unnamed, several
//! materials and lamps among them), edited as a user edits such a file: one or a few entities at
//! a time (moved, resized, given another material, renamed, inserted, deleted, duplicated,
//! swapped, commented out, broken then fixed), whitespace and comments, the camera or a material.
//! Edits favour the first and the last entity, some span two entities, and broken saves sit
//! between good ones. Reloads of such edits reuse what the edit left alone (the incremental
//! parse, the ECS update, the BVH); the watch must still show what a fresh render shows.
//!
//! Many edits are made visible at the tiny render size: entities move onto a stage in front of
//! the camera, grow large, or become lamps (whose power every pixel's light sampling sees); the
//! random test checks that a good share of its sequences changed the image (a third to
//! two thirds of them, by the seed).
//!
//! `RONDO_BIG_SEQUENCES` sets the number of random sequences (default 40), `RONDO_BIG_SEED` the
//! seed. A failure prints the seed, the sequence and the reports.

mod common;

use std::path::Path;
use std::time::{Duration, Instant};

use common::watch_diff::{Rng, Save, Watcher, env_number, fresh};
use rondo::ecs::resources::ChangeSummary;
use rondo::scene::assets::AssetCache;
use rondo::scene::load::load_scene;

/// Entities of the generated scene.
const ENTITIES: usize = 10_000;
/// Columns of the grid the entities are laid out on, in the plane z = 0 (about 4:3, like the
/// image).
const COLUMNS: usize = 116;
/// Material names: four diffuse colours and a lamp.
const MATERIALS: [&str; 5] = ["m0", "m1", "m2", "m3", "lamp"];
/// The diffuse colours of `m0`…`m3`, two palettes.
const PALETTES: [[&str; 4]; 2] = [
    [
        "(0.8, 0.2, 0.2)",
        "(0.2, 0.8, 0.2)",
        "(0.2, 0.2, 0.8)",
        "(0.7, 0.7, 0.7)",
    ],
    [
        "(0.9, 0.6, 0.1)",
        "(0.2, 0.8, 0.2)",
        "(0.1, 0.5, 0.9)",
        "(0.3, 0.3, 0.3)",
    ],
];
/// Camera positions (all looking at the origin, 125 units away in z).
const CAMERAS: [&str; 3] = ["(0, 0, -125)", "(1, 0.5, -125)", "(-2, 1, -125)"];
/// Intensities of the lamp material.
const LAMPS: [&str; 2] = ["6.0", "15.0"];
/// Sizes (hundredths): a sphere's radius, half a quad's side, a prefab placement's scale.
const SIZES: [i32; 4] = [10, 35, 150, 800];
/// The stage: 10 units in front of the camera, where an entity covers a few pixels.
const STAGE_Z: i32 = -11_500;

/// A number in hundredths, as RON.
fn num(v: i32) -> String {
    let sign = if v < 0 { "-" } else { "" };
    let a = v.unsigned_abs();
    format!("{sign}{}.{:02}", a / 100, a % 100)
}

/// A point in hundredths, as RON.
fn point(p: [i32; 3]) -> String {
    format!("({}, {}, {})", num(p[0]), num(p[1]), num(p[2]))
}

/// What an entity is: where (hundredths) and how large ([`SIZES`]).
#[derive(Clone, Debug, PartialEq)]
enum Body {
    Sphere([i32; 3], i32),
    /// A square facing the camera, by its centre and half side.
    Quad([i32; 3], i32),
    /// A placement of `prefabs/cluster.ron`, by its translation and scale.
    Prefab([i32; 3], i32),
}

impl Body {
    fn moved(&self, to: [i32; 3]) -> Self {
        match *self {
            Self::Sphere(_, s) => Self::Sphere(to, s),
            Self::Quad(_, s) => Self::Quad(to, s),
            Self::Prefab(_, s) => Self::Prefab(to, s),
        }
    }

    fn resized(&self, size: i32) -> Self {
        match *self {
            Self::Sphere(p, _) => Self::Sphere(p, size),
            Self::Quad(p, _) => Self::Quad(p, size),
            Self::Prefab(p, _) => Self::Prefab(p, size),
        }
    }
}

/// One entity of the list.
#[derive(Clone, Debug)]
struct Entity {
    name: Option<String>,
    material: usize,
    body: Body,
    /// Extra blanks after its commas (a whitespace-only edit inside the entity).
    spaced: bool,
    /// A block comment inside it.
    note: bool,
}

impl Entity {
    fn text(&self) -> String {
        let mut fields = Vec::new();
        if let Some(name) = &self.name {
            fields.push(format!("name: \"{name}\""));
        }
        let material = MATERIALS[self.material];
        match &self.body {
            Body::Sphere(c, r) => {
                fields.push(format!("material: \"{material}\""));
                fields.push(format!(
                    "shape: Sphere(center: {}, radius: {})",
                    point(*c),
                    num(*r)
                ));
            }
            Body::Quad(c, h) => {
                let corner = |dx: i32, dy: i32| point([c[0] + dx * h, c[1] + dy * h, c[2]]);
                fields.push(format!("material: \"{material}\""));
                fields.push(format!(
                    "shape: Quad(a: {}, b: {}, c: {}, d: {})",
                    corner(-1, -1),
                    corner(1, -1),
                    corner(1, 1),
                    corner(-1, 1)
                ));
            }
            Body::Prefab(t, s) => {
                fields.push("prefab: \"prefabs/cluster.ron\"".into());
                fields.push(format!("materials: {{ \"surface\": \"{material}\" }}"));
                fields.push(format!(
                    "transform: Transform(translate: {}, rotate: (0, 0, 0), scale: ({s}, {s}, {s}))",
                    point(*t),
                    s = num(*s)
                ));
            }
        }
        let note = if self.note { " /* tuned */" } else { "" };
        let comma = if self.spaced { ",   " } else { ", " };
        format!("Entity({}{note})", fields.join(comma))
    }
}

/// One line of the `entities` list.
#[derive(Clone, Debug)]
struct Item {
    entity: Entity,
    /// Written as a line comment.
    commented: bool,
    /// Blanks before it.
    indent: usize,
    /// A line comment after its comma.
    trailing: bool,
}

impl Item {
    fn line(&self) -> String {
        format!(
            "{:indent$}{}{},{}\n",
            "",
            if self.commented { "// " } else { "" },
            self.entity.text(),
            if self.trailing { " // keep" } else { "" },
            indent = self.indent
        )
    }
}

/// How a save of one entity is broken.
#[derive(Clone, Copy, Debug)]
enum Break {
    /// The entity's closing parenthesis missing (a syntax error).
    Unclosed,
    /// A material that is not defined.
    UnknownMaterial,
    /// A negative radius (a sphere), a coordinate too many (a quad, a placement's scale).
    Negative,
    /// A field that does not exist.
    UnknownField,
    /// The line duplicated: two entities of one name (valid if it is unnamed).
    Duplicate,
}

/// The generated scene file.
#[derive(Clone, Debug)]
struct BigScene {
    camera: usize,
    palette: usize,
    lamp: usize,
    fov: &'static str,
    items: Vec<Item>,
    /// The number of the next new name.
    next_name: usize,
}

impl BigScene {
    /// `n` entities on the grid: every 7th a quad, every 1000th a prefab placement, every 97th a
    /// lamp, every 131st unnamed; the middle one a backdrop behind the grid that the lamps light
    /// (seen between the entities: every pixel sees the lamps' powers).
    fn generate(n: usize) -> Self {
        let rows = n.div_ceil(COLUMNS);
        let items = (0..n)
            .map(|i| {
                let (col, row) = ((i % COLUMNS) as i32, (i / COLUMNS) as i32);
                let at = [
                    (col - COLUMNS as i32 / 2) * 100,
                    (rows as i32 / 2 - row) * 100,
                    0,
                ];
                let (body, prefix) = if i == n / 2 {
                    (Body::Quad([0, 0, 300], 7000), "backdrop")
                } else if i % 1000 == 500 {
                    (Body::Prefab(at, 30), "p")
                } else if i % 7 == 3 {
                    (Body::Quad(at, SIZES[1]), "q")
                } else {
                    (Body::Sphere(at, SIZES[1]), "s")
                };
                Item {
                    entity: Entity {
                        name: (i % 131 != 7).then(|| format!("{prefix}{i}")),
                        material: if i % 97 == 0 { 4 } else { i % 4 },
                        body,
                        spaced: false,
                        note: false,
                    },
                    commented: false,
                    indent: 8,
                    trailing: false,
                }
            })
            .collect();
        Self {
            camera: 0,
            palette: 0,
            lamp: 0,
            fov: "40.0",
            items,
            next_name: 0,
        }
    }

    fn header(&self) -> String {
        let palette = PALETTES[self.palette];
        format!(
            r#"// Generated: a grid of entities.
Scene(
    camera: Camera(position: {}, look_at: (0, 0, 0), fov: {}),
    settings: Settings(width: 32, height: 24, spp: 1, max_depth: 3, background: (0.2, 0.2, 0.25)),
    materials: {{
        "m0": Diffuse(albedo: Constant({})),
        "m1": Diffuse(albedo: Constant({})),
        "m2": Diffuse(albedo: Constant({})),
        "m3": Diffuse(albedo: Constant({})),
        "lamp": Light(emit: Constant((1.0, 0.9, 0.7)), intensity: {}),
    }},
    entities: [
"#,
            CAMERAS[self.camera],
            self.fov,
            palette[0],
            palette[1],
            palette[2],
            palette[3],
            LAMPS[self.lamp]
        )
    }

    fn text(&self) -> String {
        let mut text = self.header();
        for item in &self.items {
            text += &item.line();
        }
        text + "    ],\n)\n"
    }

    /// The text with item `k` broken as `how` says.
    fn broken_text(&self, k: usize, how: Break) -> String {
        let mut text = self.header();
        for (i, item) in self.items.iter().enumerate() {
            let line = item.line();
            if i != k {
                text += &line;
                continue;
            }
            text += &match how {
                Break::Unclosed => match line.rfind(')') {
                    Some(at) => format!("{}{}", &line[..at], &line[at + 1..]),
                    None => line,
                },
                Break::UnknownMaterial => {
                    let m = MATERIALS[item.entity.material];
                    line.replacen(&format!("\"{m}\""), "\"nope\"", 1)
                }
                // A quad has no size of its own and a placement may mirror: theirs is a
                // fourth coordinate.
                Break::Negative => line
                    .replacen("radius: ", "radius: -", 1)
                    .replacen("scale: (", "scale: (-1, ", 1)
                    .replacen("Quad(a: (", "Quad(a: (-1, ", 1),
                Break::UnknownField => line.replacen("Entity(", "Entity(colour: 1, ", 1),
                Break::Duplicate => format!("{line}{line}"),
            };
        }
        text + "    ],\n)\n"
    }

    fn fresh_name(&mut self) -> String {
        self.next_name += 1;
        format!("n{}", self.next_name)
    }

    /// An item index for an edit: the first or the last item half of the time.
    fn pick(&self, rng: &mut Rng) -> usize {
        let n = self.items.len();
        match rng.below(10) {
            0..=2 => 0,
            3..=4 => n - 1,
            5 => 1.min(n - 1),
            _ => rng.below(n),
        }
    }
}

/// A random position: on the stage in front of the camera (60 %) or a cell of the grid.
fn random_place(rng: &mut Rng) -> [i32; 3] {
    if rng.chance(60) {
        [
            rng.below(801) as i32 - 400,
            rng.below(601) as i32 - 300,
            STAGE_Z,
        ]
    } else {
        [
            (rng.below(COLUMNS) as i32 - COLUMNS as i32 / 2) * 100,
            (rng.below(87) as i32 - 43) * 100,
            0,
        ]
    }
}

/// One edit of the scene file, saved once.
#[derive(Clone, Debug)]
enum Edit {
    Move(usize, [i32; 3]),
    Resize(usize, i32),
    Material(usize, usize),
    /// Made a lamp of size 1.5 (a power all pixels' light samples see), or a lamp made diffuse.
    Glow(usize),
    /// A new name, or none.
    Rename(usize, Option<String>),
    /// A new sphere before item `k` (`k` = the length: at the end).
    Insert(usize, Entity),
    Delete(usize),
    /// The line duplicated after itself, the copy renamed.
    Duplicate(usize, String),
    Swap(usize, usize),
    /// The line commented out, or back in.
    ToggleComment(usize),
    /// Blanks inside the entity, or before it.
    Spaces(usize, bool),
    /// A block comment inside the entity, or a line comment after it.
    Note(usize, bool),
    /// Item `k` moved and item `k + 1` given another material, in one save.
    Pair(usize, [i32; 3], usize),
    Camera(usize),
    Fov(&'static str),
    Palette(usize),
    Lamp(usize),
    /// A broken save of item `k`; the scene as it was stays the last good one.
    Broken(usize, Break),
}

impl Edit {
    fn random(rng: &mut Rng, scene: &mut BigScene) -> Self {
        let k = scene.pick(rng);
        let n = scene.items.len();
        match rng.below(20) {
            0..=2 => Self::Move(k, random_place(rng)),
            3 | 4 => Self::Resize(k, SIZES[rng.below(SIZES.len())]),
            5 => Self::Material(k, rng.below(MATERIALS.len())),
            6 => Self::Glow(k),
            7 => Self::Rename(k, (!rng.chance(20)).then(|| scene.fresh_name())),
            8 => {
                let at = if rng.chance(50) { n } else { k };
                let entity = Entity {
                    name: Some(scene.fresh_name()),
                    material: rng.below(MATERIALS.len()),
                    body: Body::Sphere(random_place(rng), SIZES[rng.below(SIZES.len())]),
                    spaced: false,
                    note: false,
                };
                Self::Insert(at, entity)
            }
            9 => Self::Delete(k),
            10 => Self::Duplicate(k, scene.fresh_name()),
            11 => {
                let other = if rng.chance(50) {
                    if k + 1 < n { k + 1 } else { k - 1 }
                } else {
                    scene.pick(rng)
                };
                Self::Swap(k, other)
            }
            12 => Self::ToggleComment(k),
            13 => Self::Spaces(k, rng.chance(50)),
            14 => Self::Note(k, rng.chance(50)),
            15 => Self::Pair(k.min(n - 2), random_place(rng), rng.below(MATERIALS.len())),
            16 => match rng.below(4) {
                0 => Self::Camera(rng.below(CAMERAS.len())),
                1 => Self::Fov(["40.0", "37.5"][rng.below(2)]),
                2 => Self::Palette(rng.below(PALETTES.len())),
                _ => Self::Lamp(rng.below(LAMPS.len())),
            },
            _ => {
                let how = [
                    Break::Unclosed,
                    Break::UnknownMaterial,
                    Break::Negative,
                    Break::UnknownField,
                    Break::Duplicate,
                ];
                Self::Broken(k, how[rng.below(how.len())])
            }
        }
    }

    /// Applies the edit to `scene` and returns the text to save.
    fn apply(&self, scene: &mut BigScene) -> String {
        let items = &mut scene.items;
        match self {
            Self::Move(k, to) => items[*k].entity.body = items[*k].entity.body.moved(*to),
            Self::Resize(k, size) => items[*k].entity.body = items[*k].entity.body.resized(*size),
            Self::Material(k, m) => items[*k].entity.material = *m,
            Self::Glow(k) => {
                let entity = &mut items[*k].entity;
                if entity.material == 4 {
                    entity.material = 0;
                } else {
                    entity.material = 4;
                    entity.body = entity.body.resized(150);
                }
            }
            Self::Rename(k, name) => items[*k].entity.name.clone_from(name),
            Self::Insert(k, entity) => items.insert(
                *k,
                Item {
                    entity: entity.clone(),
                    commented: false,
                    indent: 8,
                    trailing: false,
                },
            ),
            Self::Delete(k) => {
                items.remove(*k);
            }
            Self::Duplicate(k, name) => {
                let mut copy = items[*k].clone();
                copy.entity.name = Some(name.clone());
                items.insert(*k + 1, copy);
            }
            Self::Swap(a, b) => items.swap(*a, *b),
            Self::ToggleComment(k) => items[*k].commented = !items[*k].commented,
            Self::Spaces(k, true) => items[*k].entity.spaced = !items[*k].entity.spaced,
            Self::Spaces(k, false) => items[*k].indent = if items[*k].indent == 8 { 4 } else { 8 },
            Self::Note(k, true) => items[*k].entity.note = !items[*k].entity.note,
            Self::Note(k, false) => items[*k].trailing = !items[*k].trailing,
            Self::Pair(k, to, m) => {
                items[*k].entity.body = items[*k].entity.body.moved(*to);
                items[*k + 1].entity.material = *m;
            }
            Self::Camera(c) => scene.camera = *c,
            Self::Fov(f) => scene.fov = f,
            Self::Palette(p) => scene.palette = *p,
            Self::Lamp(l) => scene.lamp = *l,
            Self::Broken(k, how) => return scene.broken_text(*k, *how),
        }
        scene.text()
    }
}

/// `prefabs/cluster.ron`: two spheres and a square of one material, `surface`.
const CLUSTER: &str = r#"Prefab(
    materials: { "surface": Diffuse(albedo: Constant((0.7, 0.7, 0.7))) },
    entities: [
        Entity(name: "a", material: "surface", shape: Sphere(center: (-1, 0, 0), radius: 0.8)),
        Entity(name: "b", material: "surface", shape: Sphere(center: (1, 0, 0), radius: 0.8)),
        Entity(name: "c", material: "surface", shape: Quad(a: (-1, -1, 1), b: (1, -1, 1), c: (1, 1, 1), d: (-1, 1, 1))),
    ],
)
"#;

/// A directory with the generated scene of `n` entities and its prefab.
fn scene_dir(name: &str, scene: &BigScene) -> common::TestDir {
    let dir = common::temp_dir(name);
    std::fs::create_dir(dir.join("prefabs")).expect("mkdir");
    std::fs::write(dir.join("prefabs/cluster.ron"), CLUSTER).expect("write prefab");
    std::fs::write(dir.join("scene.ron"), scene.text()).expect("write scene");
    dir
}

/// A watch of the big scene, with the model of its file.
struct Bench {
    watcher: Watcher,
    scene: BigScene,
}

impl Bench {
    fn new(name: &str) -> Self {
        let scene = BigScene::generate(ENTITIES);
        Self {
            watcher: Watcher::start(scene_dir(name, &scene)),
            scene,
        }
    }

    /// Saves each edit (in place), then waits for the watch to show what a fresh render shows.
    fn play(&mut self, edits: &[Edit]) -> Result<(), String> {
        let scene = &mut self.scene;
        self.watcher.play(&format!("after {edits:?}"), |dir| {
            for edit in edits {
                std::fs::write(dir.join("scene.ron"), edit.apply(scene)).expect("write scene");
            }
        })
    }

    /// [`Bench::play`] of one edit that changes the image (checked).
    fn play_change(&mut self, edit: Edit) -> Result<(), String> {
        let text = edit.apply(&mut self.scene);
        self.watcher.play_change(&format!("after {edit:?}"), |dir| {
            std::fs::write(dir.join("scene.ron"), text).expect("write scene");
        })
    }
}

/// A random sequence of 1–4 edits of `scene`, saved in random ways with gaps of 0–150 ms (a
/// third of them 0); a broken save is followed by a good one most of the time.
fn random_sequence(rng: &mut Rng, scene: &mut BigScene, dir: &Path) -> Vec<(Edit, u64)> {
    let n = 1 + rng.below(4);
    let mut edits = Vec::new();
    let mut i = 0;
    while i < n || matches!(edits.last(), Some((Edit::Broken(..), _))) && rng.chance(70) {
        let edit = Edit::random(rng, scene);
        let text = edit.apply(scene);
        Save::random(rng).write(&dir.join("scene.ron"), text.as_bytes());
        let gap = if rng.chance(33) {
            0
        } else {
            rng.below(151) as u64
        };
        std::thread::sleep(Duration::from_millis(gap));
        edits.push((edit, gap));
        i += 1;
    }
    edits
}

#[test]
fn random_edits_of_a_big_scene_end_in_what_a_fresh_render_shows() {
    let sequences = env_number("RONDO_BIG_SEQUENCES", 40);
    let seed = env_number("RONDO_BIG_SEED", 24);
    let start = Instant::now();
    let mut bench = Bench::new("big-random");
    let mut rng = Rng(seed);
    let mut changed = 0;
    for i in 0..sequences {
        bench.watcher.clear();
        let before = fresh(&bench.watcher.scene());
        let edits = random_sequence(&mut rng, &mut bench.scene, &bench.watcher.dir);
        let expected = fresh(&bench.watcher.scene());
        changed += u64::from(expected != before);
        if let Err(e) = bench.watcher.settle(&format!("sequence {i}: {edits:?}")) {
            panic!("seed {seed}: {e}");
        }
    }
    eprintln!(
        "{sequences} sequences ({changed} changed the fresh render) in {:.1} s",
        start.elapsed().as_secs_f64()
    );
    // The edits are made visible: a test whose edits left the image alone would test nothing
    // (a quarter is the floor; seeds 1–3 and 24 give 31–70 %).
    assert!(
        4 * changed >= sequences,
        "only {changed} of {sequences} sequences changed the image"
    );
}

impl Bench {
    /// Plays `edit`, then checks that the watch knows where items `then` now are: each is made
    /// or unmade a lamp ([`Edit::Glow`]), which changes the image.
    fn step(&mut self, edit: Edit, then: &[usize]) {
        self.play(&[edit]).unwrap_or_else(|e| panic!("{e}"));
        for &k in then {
            self.play_change(Edit::Glow(k))
                .unwrap_or_else(|e| panic!("{e}"));
        }
    }

    fn last(&self) -> usize {
        self.scene.items.len() - 1
    }
}

/// The named cases: edits at the first and the last entity, across two, reorderings, blanks
/// and comments inside and between entities, and broken saves between good ones.
#[test]
fn edits_at_the_ends_across_two_entities_of_blanks_and_comments_and_broken_between_good() {
    let mut b = Bench::new("big-scripted");
    let stage = |x: i32| [x, 0, STAGE_Z];
    let last = b.last();
    b.step(Edit::Move(0, stage(-200)), &[0]);
    b.step(Edit::Move(last, stage(200)), &[last]);
    b.step(Edit::Resize(0, 150), &[0]);
    b.step(Edit::Resize(last, 10), &[last]);
    b.step(Edit::Pair(0, stage(100), 2), &[0, 1]);
    b.step(Edit::Pair(last - 1, stage(-100), 2), &[last - 1, last]);
    b.step(Edit::Swap(0, 1), &[0, 1]);
    b.step(Edit::Swap(last - 1, last), &[last - 1, last]);
    b.step(Edit::Swap(0, last), &[0, last]);
    b.step(Edit::Delete(0), &[0]);
    let last = b.last();
    b.step(Edit::Delete(last), &[last - 1]);
    b.step(Edit::Insert(0, stage_sphere("first")), &[0, 1]);
    let end = b.last() + 1;
    b.step(Edit::Insert(end, stage_sphere("last")), &[end - 1, end]);
    b.step(Edit::Duplicate(0, "copy0".into()), &[0, 1]);
    let last = b.last();
    b.step(Edit::Duplicate(last, "copy1".into()), &[last, last + 1]);
    let last = b.last();
    b.step(Edit::Rename(0, Some("renamed".into())), &[0]);
    b.step(Edit::Rename(last, None), &[last]);
    b.step(Edit::ToggleComment(0), &[1]);
    b.step(Edit::ToggleComment(0), &[0]);
    b.step(Edit::ToggleComment(last), &[last - 1]);
    b.step(Edit::ToggleComment(last), &[last]);
    for edit in [
        Edit::Camera(1),
        Edit::Fov("37.5"),
        Edit::Palette(1),
        Edit::Lamp(1),
    ] {
        b.play_change(edit).unwrap_or_else(|e| panic!("{e}"));
    }
    // Blanks and comments, inside entities and between them.
    let mid = b.last() / 2;
    for k in [0, last, mid] {
        for inside in [true, false] {
            b.step(Edit::Spaces(k, inside), &[k]);
            b.step(Edit::Note(k, inside), &[k]);
        }
    }
    // A broken save between two good ones: each settled, and all three saved at once.
    for (k, how) in [
        (0, Break::Unclosed),
        (last, Break::UnknownMaterial),
        (mid, Break::Negative),
        (1, Break::UnknownField),
        (last - 1, Break::Duplicate),
    ] {
        b.play_change(Edit::Glow(k))
            .unwrap_or_else(|e| panic!("{e}"));
        b.play_change(Edit::Broken(k, how))
            .unwrap_or_else(|e| panic!("{e}"));
        b.play_change(Edit::Glow(k))
            .unwrap_or_else(|e| panic!("{e}"));
        b.play(&[
            Edit::Move(k, stage(-300)),
            Edit::Broken(k, how),
            Edit::Glow(k),
        ])
        .unwrap_or_else(|e| panic!("{e}"));
    }
}

/// A sphere of radius 1.5 on the stage.
fn stage_sphere(name: &str) -> Entity {
    Entity {
        name: Some(name.into()),
        material: 1,
        body: Body::Sphere([0, 0, STAGE_Z], 150),
        spaced: false,
        note: false,
    }
}

/// Work counted: a one-entity edit of the big scene parses one entity (also after a broken
/// save), changes one in the world and refits the BVH.
#[test]
fn a_one_entity_edit_of_a_big_scene_parses_and_changes_one_entity() {
    let mut scene = BigScene::generate(ENTITIES);
    let dir = scene_dir("big-counts", &scene);
    let path = dir.join("scene.ron");
    let mut cache = AssetCache::default();
    let first = load_scene(&path, &mut cache).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(first.stats.entities_parsed, ENTITIES as u64);
    let n = ENTITIES;
    let edits = [
        Edit::Move(0, [0, 0, STAGE_Z]),
        Edit::Resize(n - 1, 800),
        Edit::Material(n / 2, 4),
        Edit::Rename(7, Some("renamed".into())),
        Edit::Spaces(n - 1, true),
        Edit::Note(0, true),
        Edit::Move(500, [100, 0, STAGE_Z]),
    ];
    for edit in edits {
        std::fs::write(&path, edit.apply(&mut scene)).expect("write scene");
        let loaded = load_scene(&path, &mut cache).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(loaded.stats.entities_parsed, 1, "{edit:?}");
        let reference = load_scene(&path, &mut AssetCache::default()).expect("loads");
        assert!(loaded.entities == reference.entities, "{edit:?}");
        assert_eq!(loaded.materials, reference.materials, "{edit:?}");
        // A broken save of the entity between: the next good one is still compared with the
        // last good parse.
        std::fs::write(&path, Edit::Broken(1, Break::Unclosed).apply(&mut scene))
            .expect("write scene");
        assert!(load_scene(&path, &mut cache).is_err());
    }

    // In the watch: a move of one entity changes one entity of the world, refits the BVH for
    // the preview and reads no asset.
    let mut b = Bench::new("big-watch-counts");
    for (k, to) in [(0, [0, 0, STAGE_Z]), (n - 1, [150, 0, STAGE_Z])] {
        let refits = b
            .watcher
            .last_reload("start")
            .map(|r| r.counters.bvh_refits);
        let refits = refits.unwrap_or_else(|e| panic!("{e}"));
        b.play_change(Edit::Move(k, to))
            .unwrap_or_else(|e| panic!("{e}"));
        let report = b
            .watcher
            .last_reload("move")
            .unwrap_or_else(|e| panic!("{e}"));
        let one = ChangeSummary {
            changed: 1,
            ..ChangeSummary::default()
        };
        assert_eq!(report.changes, one, "{report}");
        assert_eq!(report.asset_bytes_read, 0, "{report}");
        assert!(report.bvh_refit, "{report}");
        assert_eq!(report.counters.bvh_refits, refits + 1, "{report}");
    }
}
