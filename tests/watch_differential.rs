//! Differential test of live editing: random sequences of edits (scene, prefab, mesh, texture,
//! environment map, glTF model (its file, buffer and image) and directory operations, valid and broken, saved in the ways editors save,
//! with random gaps of 0–100 ms) are played against a running watch; after each sequence the
//! watch must show what a fresh render of the files on disk shows: the same pixels, or the same
//! error. The scene is sometimes lit by an environment map (`env/sky.exr` or `env/sky.hdr`) and
//! a sun.
//!
//! The driver and the oracle are in `common/watch_diff.rs` (shared with the big scenes and
//! assets of `watch_differential_big.rs`). The watch runs in-process on the real notify watcher:
//! the `rondo watch` binary adds only the printing of report lines, so running it would test
//! nothing more.
//!
//! `RONDO_DIFF_SEQUENCES` sets the number of random sequences (default 240, split over four
//! watch sessions); `RONDO_DIFF_SEED` the seed. A failure prints the seed, the sequence and the
//! reports; every sequence that ever failed is kept below as a named regression case.

mod common;

use std::path::Path;
use std::time::{Duration, Instant};

use common::watch_diff::{Rng, Save, Watcher, env_number};

const COLOURS: [(&str, [u8; 3]); 3] = [
    ("(1.0, 0.0, 0.0)", [255, 0, 0]),
    ("(0.0, 0.0, 1.0)", [0, 0, 255]),
    ("(0.0, 1.0, 0.0)", [0, 255, 0]),
];

/// Two meshes of the same byte count: a light triangle over the centre of the image, or aside.
const MESHES: [&str; 2] = [
    "v -2 -2 0\nv 2 -2 0\nv 0 3 0\nf 1 2 3\n",
    "v -2 -2 0\nv 2 -2 0\nv 9 3 0\nf 1 2 3\n",
];
const BROKEN_MESH: &str = "v 0 0 0\nf 1 2 9\n";

/// Two buffers of `models/m.gltf` of one byte count: a triangle over the centre, or aside (three
/// positions, then three texture coordinates).
fn gltf_buffer(variant: Option<usize>) -> Vec<u8> {
    let dx = match variant {
        Some(v) => [0.0, 3.0][v % 2],
        None => return b"short".to_vec(),
    };
    let floats = [
        -1.0 + dx,
        -1.0,
        2.0,
        1.0 + dx,
        -1.0,
        2.0,
        dx,
        1.0,
        2.0,
        0.0,
        1.0,
        1.0,
        1.0,
        0.5,
        0.0f32,
    ];
    floats.iter().flat_map(|f| f.to_le_bytes()).collect()
}

/// `models/m.gltf`: the triangle of [`gltf_buffer`] emitting `COLOURS[v]` times its emissive
/// texture `img.png`, placed by a node translated by 0 or 0.5 along y; or not JSON.
fn gltf_text(variant: Option<usize>) -> String {
    let Some(v) = variant else {
        return "{ \"asset\": ".into();
    };
    let (colour, dy) = (
        COLOURS[v % COLOURS.len()].0,
        [0.0, 0.5][v / COLOURS.len() % 2],
    );
    let colour = colour.trim_matches(|c| c == '(' || c == ')');
    format!(
        r#"{{"asset": {{"version": "2.0"}},
 "buffers": [{{"uri": "m.bin", "byteLength": 60}}],
 "bufferViews": [{{"buffer": 0, "byteLength": 36}}, {{"buffer": 0, "byteOffset": 36, "byteLength": 24}}],
 "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}},
               {{"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}}],
 "images": [{{"uri": "img.png"}}], "textures": [{{"source": 0}}],
 "materials": [{{"name": "glow", "emissiveFactor": [{colour}], "emissiveTexture": {{"index": 0}},
                 "pbrMetallicRoughness": {{"baseColorFactor": [0.3, 0.3, 0.3, 1], "metallicFactor": 0}}}}],
 "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "TEXCOORD_0": 1}}, "material": 0}}]}}],
 "nodes": [{{"name": "tri", "mesh": 0, "translation": [0, {dy}, 0]}}], "scenes": [{{"nodes": [0]}}]}}"#
    )
}

/// The environment map files in `env/`: OpenEXR and Radiance, each written in its own format.
const MAP_FILES: [&str; 2] = ["sky.exr", "sky.hdr"];
/// Map sizes, width × height.
const MAP_SIZES: [(u32, u32); 3] = [(8, 4), (16, 8), (32, 16)];
/// Number of texel patterns of [`map_texel`].
const MAP_PATTERNS: usize = 4;

/// `strength` and `rotate` values of the environment.
const STRENGTHS: [&str; 3] = ["1.0", "0.4", "2.5"];
const ROTATIONS: [&str; 3] = ["(0, 0, 0)", "(0, 90, 0)", "(30, -45, 0)"];
/// `direction`, `angular_diameter` and power of the sun.
const SUN_DIRECTIONS: [&str; 3] = ["(0.3, 1, -0.2)", "(-1, 0.5, -1)", "(0.2, -0.3, -1)"];
const SUN_DIAMETERS: [&str; 3] = ["0.53", "5", "20"];
const SUN_POWERS: [&str; 3] = [
    "irradiance: 3.0",
    "radiance: 40.0",
    "irradiance: 1.5, colour: (1, 0.6, 0.3)",
];

/// What the scene file says.
#[derive(Clone, Debug)]
struct SceneText {
    /// Wall colour (index into [`COLOURS`]) when the wall is inline.
    wall: usize,
    /// The wall comes from `prefabs/wall.ron` instead.
    wall_prefab: bool,
    /// The ball's albedo is `tex/ball.png` instead of grey.
    textured: bool,
    /// The mesh entity `meshes/tri.obj` is in the scene.
    mesh: bool,
    /// The glTF model `models/m.gltf` is placed in the scene.
    gltf: bool,
    /// The ball comes before the wall.
    swapped: bool,
    /// Samples per pixel (1 or 4).
    spp: u32,
    /// `settings.environment`, else maybe a `background`.
    environment: Option<EnvText>,
    /// A grey `background` (only without an environment).
    background: bool,
    /// `settings.sun`.
    sun: Option<SunText>,
    /// A syntax error (or, if `truncated`, only the first half of the text).
    broken: bool,
    truncated: bool,
}

impl SceneText {
    fn random(rng: &mut Rng) -> Self {
        let broken = rng.chance(15);
        Self {
            wall: rng.below(COLOURS.len()),
            wall_prefab: rng.chance(40),
            textured: rng.chance(40),
            mesh: rng.chance(40),
            gltf: rng.chance(40),
            swapped: rng.chance(30),
            spp: if rng.chance(20) { 1 } else { 4 },
            environment: rng.chance(50).then(|| EnvText {
                file: rng.below(MAP_FILES.len()),
                strength: rng.below(STRENGTHS.len()),
                rotate: rng.below(ROTATIONS.len()),
            }),
            background: rng.chance(50),
            sun: rng.chance(35).then(|| SunText {
                direction: rng.below(SUN_DIRECTIONS.len()),
                diameter: rng.below(SUN_DIAMETERS.len()),
                power: rng.below(SUN_POWERS.len()),
            }),
            broken,
            truncated: broken && rng.chance(50),
        }
    }

    fn text(&self) -> String {
        let wall = if self.wall_prefab {
            r#"Entity(name: "wall", prefab: "prefabs/wall.ron")"#.to_string()
        } else {
            r#"Entity(name: "wall", material: "wall", shape: Quad(a: (-10, -10, 5), b: (10, -10, 5), c: (10, 10, 5), d: (-10, 10, 5)))"#.to_string()
        };
        let ball = r#"Entity(name: "ball", material: "ball", shape: Sphere(center: (0.4, 0.6, 0), radius: 0.8))"#;
        let mut entities = if self.swapped {
            vec![ball.to_string(), wall]
        } else {
            vec![wall, ball.to_string()]
        };
        if self.mesh {
            entities.push(
                r#"Entity(name: "tri", material: "tri", shape: Mesh(path: "meshes/tri.obj"))"#
                    .into(),
            );
        }
        if self.gltf {
            entities.push(r#"Entity(name: "model", gltf: "models/m.gltf")"#.into());
        }
        let albedo = if self.textured {
            r#"Image(path: "tex/ball.png")"#
        } else {
            "Constant((0.5, 0.5, 0.5))"
        };
        let mut sky = match (&self.environment, self.background) {
            (Some(e), _) => format!(
                r#", environment: Environment(path: "env/{}", strength: {}, rotate: {})"#,
                MAP_FILES[e.file], STRENGTHS[e.strength], ROTATIONS[e.rotate]
            ),
            (None, true) => ", background: (0.3, 0.3, 0.3)".to_string(),
            (None, false) => String::new(),
        };
        if let Some(s) = &self.sun {
            sky += &format!(
                ", sun: Sun(direction: {}, angular_diameter: {}, {})",
                SUN_DIRECTIONS[s.direction], SUN_DIAMETERS[s.diameter], SUN_POWERS[s.power]
            );
        }
        let text = format!(
            r#"Scene(
    camera: Camera(position: (0, 0, -5), look_at: (0, 0, 0), fov: 40.0),
    settings: Settings(width: 32, height: 32, spp: {spp}, max_depth: 3{sky}),
    materials: {{
        "wall": Light(emit: Constant({wall}), intensity: 1.0, two_sided: true),
        "ball": Diffuse(albedo: {albedo}),
        "tri": Light(emit: Constant((0.2, 0.9, 0.2)), intensity: 1.0, two_sided: true),
    }},
    entities: [ {entities} ],
)
"#,
            spp = self.spp,
            wall = COLOURS[self.wall].0,
            entities = entities.join(",\n        "),
        );
        if self.truncated {
            text[..text.len() / 2].to_string()
        } else if self.broken {
            text.replace("intensity: 1.0,", "intensity: 1.0 oops,")
        } else {
            text
        }
    }
}

/// `settings.environment` of the scene: `env/MAP_FILES[file]` at `STRENGTHS[strength]`,
/// `ROTATIONS[rotate]`.
#[derive(Clone, Debug)]
struct EnvText {
    file: usize,
    strength: usize,
    rotate: usize,
}

/// `settings.sun` of the scene, as indices into [`SUN_DIRECTIONS`], [`SUN_DIAMETERS`] and
/// [`SUN_POWERS`].
#[derive(Clone, Debug)]
struct SunText {
    direction: usize,
    diameter: usize,
    power: usize,
}

/// The directories the scene's files live in.
const DIRS: [&str; 5] = ["prefabs", "tex", "meshes", "env", "models"];

/// One edit.
#[derive(Clone, Debug)]
enum Op {
    Scene(SceneText, Save),
    /// `prefabs/wall.ron`: a wall of a colour, or broken.
    Prefab(Option<usize>, Save),
    /// `tex/ball.png`: a colour, or not an image.
    Texture(Option<usize>, Save),
    /// `linked/real.png` in a colour, and `tex/ball.png` made a symlink to it (later in-place
    /// texture writes then edit the target, in another directory).
    LinkTexture(usize),
    /// `meshes/tri.obj`: one of [`MESHES`], or broken.
    Mesh(Option<usize>, Save),
    /// `env/MAP_FILES[file]`: new contents.
    Map(usize, MapBytes, Save),
    /// `rm env/MAP_FILES[file]`.
    RemoveMap(usize),
    /// `models/m.gltf`: a variant of [`gltf_text`], or broken.
    Gltf(Option<usize>, Save),
    /// `models/m.bin`: a variant of [`gltf_buffer`], or too short.
    GltfBuffer(Option<usize>, Save),
    /// `models/img.png`: a colour, or not an image.
    GltfImage(Option<usize>, Save),
    /// `linked/real.exr` of a pattern, and `env/sky.exr` made a symlink to it (later in-place
    /// writes of the map then edit the target, in another directory).
    LinkMap(usize),
    /// `rm -rf DIR`.
    RemoveDir(usize),
    /// `mkdir DIR` and write its file (a valid one).
    CreateDir(usize, usize),
    /// `mv DIR DIR.old && cp -r DIR.old DIR && rm -rf DIR.old`, then rewrite its file.
    ReplaceDir(usize, usize),
    /// Wait before the next edit.
    Gap(u64),
}

fn prefab_text(colour: Option<usize>) -> String {
    match colour {
        Some(c) => format!(
            r#"Prefab(
    materials: {{ "wall": Light(emit: Constant({}), intensity: 1.0, two_sided: true) }},
    entities: [ Entity(name: "w", material: "wall", shape: Quad(a: (-10, -10, 5), b: (10, -10, 5), c: (10, 10, 5), d: (-10, 10, 5))) ],
)
"#,
            COLOURS[c].0
        ),
        None => "Prefab(entities: [ Entity(name: \"w\", prefab: \"wall.ron\") ])".into(),
    }
}

fn png_bytes(colour: Option<usize>) -> Vec<u8> {
    match colour {
        Some(c) => {
            let mut bytes = Vec::new();
            image::RgbImage::from_pixel(4, 4, image::Rgb(COLOURS[c].1))
                .write_to(
                    &mut std::io::Cursor::new(&mut bytes),
                    image::ImageFormat::Png,
                )
                .expect("encode png");
            bytes
        }
        None => b"not a png".to_vec(),
    }
}

/// Contents of a map file.
#[derive(Clone, Copy, Debug)]
enum MapBytes {
    /// Texel pattern `p` of [`map_texel`] at size `MAP_SIZES[s]`: `Valid(p, s)`.
    Valid(usize, usize),
    /// Not an image.
    Garbage,
    /// The first half of the bytes of `Valid(p, s)`.
    Truncated(usize, usize),
}

impl MapBytes {
    fn random(rng: &mut Rng) -> Self {
        let (p, s) = (rng.below(MAP_PATTERNS), rng.below(MAP_SIZES.len()));
        match rng.below(10) {
            0 => Self::Garbage,
            1 => Self::Truncated(p, s),
            _ => Self::Valid(p, s),
        }
    }
}

/// Radiance of texel (x, y) of a `w` × `h` map of pattern `p`: two uniform skies (whose OpenEXR
/// files are of one size, see `environment_map_swapped_keeping_size_and_mtime`), a gradient, and
/// a single bright texel.
fn map_texel(p: usize, x: u32, y: u32, w: u32, h: u32) -> [f32; 3] {
    match p {
        0 => [0.8, 0.8, 0.8],
        // Every channel's float differs from 0.8 in its exponent byte only.
        1 => [0.2, 0.8, 3.2],
        2 => [
            0.2 + 2.0 * x as f32 / w as f32,
            0.5,
            1.0 - y as f32 / h as f32,
        ],
        _ if (x, y) == (w / 4, h / 3) => [80.0, 60.0, 40.0],
        _ => [0.05, 0.1, 0.2],
    }
}

/// The bytes of map file `MAP_FILES[file]` (OpenEXR or Radiance, by its name) of `contents`.
fn map_bytes(file: usize, contents: MapBytes) -> Vec<u8> {
    let (p, s, truncated) = match contents {
        MapBytes::Garbage => return b"not an environment map".to_vec(),
        MapBytes::Valid(p, s) => (p, s, false),
        MapBytes::Truncated(p, s) => (p, s, true),
    };
    let (w, h) = MAP_SIZES[s];
    let texels: Vec<[f32; 3]> = (0..h)
        .flat_map(|y| (0..w).map(move |x| map_texel(p, x, y, w, h)))
        .collect();
    let mut bytes = Vec::new();
    if MAP_FILES[file].ends_with(".hdr") {
        let rgb: Vec<image::Rgb<f32>> = texels.into_iter().map(image::Rgb).collect();
        image::codecs::hdr::HdrEncoder::new(&mut bytes)
            .encode(&rgb, w as usize, h as usize)
            .expect("encode hdr");
    } else {
        image::Rgb32FImage::from_raw(w, h, texels.concat())
            .expect("buffer size")
            .write_to(
                &mut std::io::Cursor::new(&mut bytes),
                image::ImageFormat::OpenExr,
            )
            .expect("encode exr");
    }
    if truncated {
        bytes.truncate(bytes.len() / 2);
    }
    bytes
}

fn mesh_text(variant: Option<usize>) -> &'static str {
    variant.map_or(BROKEN_MESH, |v| MESHES[v])
}

/// The file of directory `d` and its valid contents for variant `v`.
fn dir_file(d: usize, v: usize) -> (&'static str, Vec<u8>) {
    match d {
        0 => (
            "wall.ron",
            prefab_text(Some(v % COLOURS.len())).into_bytes(),
        ),
        1 => ("ball.png", png_bytes(Some(v % COLOURS.len()))),
        3 => (
            MAP_FILES[0],
            map_bytes(0, MapBytes::Valid(v % MAP_PATTERNS, v % MAP_SIZES.len())),
        ),
        4 => match v % 3 {
            0 => ("m.gltf", gltf_text(Some(v)).into_bytes()),
            1 => ("m.bin", gltf_buffer(Some(v))),
            _ => ("img.png", png_bytes(Some(v % COLOURS.len()))),
        },
        _ => (
            "tri.obj",
            mesh_text(Some(v % MESHES.len())).as_bytes().to_vec(),
        ),
    }
}

impl Op {
    fn random(rng: &mut Rng, dir: &Path) -> Self {
        let d = rng.below(DIRS.len());
        let exists = dir.join(DIRS[d]).is_dir();
        match rng.below(13) {
            0..=2 => Self::Scene(SceneText::random(rng), Save::random(rng)),
            3 => Self::Prefab(
                (!rng.chance(20)).then(|| rng.below(COLOURS.len())),
                Save::random(rng),
            ),
            4 => Self::Texture(
                (!rng.chance(20)).then(|| rng.below(COLOURS.len())),
                Save::random(rng),
            ),
            5 if rng.chance(30) => Self::LinkTexture(rng.below(COLOURS.len())),
            5 => Self::Mesh(
                (!rng.chance(20)).then(|| rng.below(MESHES.len())),
                Save::random(rng),
            ),
            6 | 7 if !exists => Self::CreateDir(d, rng.below(6)),
            6 => Self::RemoveDir(d),
            7 => Self::ReplaceDir(d, rng.below(6)),
            8 | 9 => {
                let file = rng.below(MAP_FILES.len());
                match rng.below(10) {
                    0 => Self::RemoveMap(file),
                    1 => Self::LinkMap(rng.below(MAP_PATTERNS)),
                    _ => Self::Map(file, MapBytes::random(rng), Save::random(rng)),
                }
            }
            10 => {
                let variant = |rng: &mut Rng, n| (!rng.chance(20)).then(|| rng.below(n));
                match rng.below(3) {
                    0 => Self::Gltf(variant(rng, 2 * COLOURS.len()), Save::random(rng)),
                    1 => Self::GltfBuffer(variant(rng, 2), Save::random(rng)),
                    _ => Self::GltfImage(variant(rng, COLOURS.len()), Save::random(rng)),
                }
            }
            _ => Self::Gap(rng.below(101) as u64),
        }
    }

    fn apply(&self, dir: &Path) {
        let file = |sub: &str, name: &str| {
            let d = dir.join(sub);
            d.is_dir().then(|| d.join(name))
        };
        match self {
            Self::Scene(text, save) => save.write(&dir.join("scene.ron"), text.text().as_bytes()),
            Self::Prefab(c, save) => {
                if let Some(path) = file("prefabs", "wall.ron") {
                    save.write(&path, prefab_text(*c).as_bytes());
                }
            }
            Self::Texture(c, save) => {
                if let Some(path) = file("tex", "ball.png") {
                    save.write(&path, &png_bytes(*c));
                }
            }
            Self::LinkTexture(c) => {
                std::fs::create_dir_all(dir.join("linked")).expect("mkdir");
                std::fs::write(dir.join("linked/real.png"), png_bytes(Some(*c))).expect("write");
                if let Some(path) = file("tex", "ball.png") {
                    let _ = std::fs::remove_file(&path);
                    std::os::unix::fs::symlink("../linked/real.png", &path).expect("symlink");
                }
            }
            Self::Mesh(v, save) => {
                if let Some(path) = file("meshes", "tri.obj") {
                    save.write(&path, mesh_text(*v).as_bytes());
                }
            }
            Self::Map(f, contents, save) => {
                if let Some(path) = file("env", MAP_FILES[*f]) {
                    save.write(&path, &map_bytes(*f, *contents));
                }
            }
            Self::Gltf(v, save) => {
                if let Some(path) = file("models", "m.gltf") {
                    save.write(&path, gltf_text(*v).as_bytes());
                }
            }
            Self::GltfBuffer(v, save) => {
                if let Some(path) = file("models", "m.bin") {
                    save.write(&path, &gltf_buffer(*v));
                }
            }
            Self::GltfImage(c, save) => {
                if let Some(path) = file("models", "img.png") {
                    save.write(&path, &png_bytes(*c));
                }
            }
            Self::RemoveMap(f) => {
                let _ = std::fs::remove_file(dir.join("env").join(MAP_FILES[*f]));
            }
            Self::LinkMap(p) => {
                std::fs::create_dir_all(dir.join("linked")).expect("mkdir");
                let bytes = map_bytes(0, MapBytes::Valid(*p, 1));
                std::fs::write(dir.join("linked/real.exr"), bytes).expect("write");
                if let Some(path) = file("env", MAP_FILES[0]) {
                    let _ = std::fs::remove_file(&path);
                    std::os::unix::fs::symlink("../linked/real.exr", &path).expect("symlink");
                }
            }
            Self::RemoveDir(d) => {
                let _ = std::fs::remove_dir_all(dir.join(DIRS[*d]));
            }
            Self::CreateDir(d, v) => {
                let sub = dir.join(DIRS[*d]);
                std::fs::create_dir_all(&sub).expect("mkdir");
                let (name, bytes) = dir_file(*d, *v);
                std::fs::write(sub.join(name), bytes).expect("write");
            }
            Self::ReplaceDir(d, v) => {
                let sub = dir.join(DIRS[*d]);
                let old = dir.join(format!("{}.old", DIRS[*d]));
                let _ = std::fs::remove_dir_all(&old);
                std::fs::rename(&sub, &old).expect("mv");
                std::fs::create_dir(&sub).expect("mkdir");
                for entry in std::fs::read_dir(&old).expect("read dir").flatten() {
                    std::fs::copy(entry.path(), sub.join(entry.file_name())).expect("cp");
                }
                std::fs::remove_dir_all(&old).expect("rm -rf");
                let (name, bytes) = dir_file(*d, *v);
                std::fs::write(sub.join(name), bytes).expect("write");
            }
            Self::Gap(ms) => std::thread::sleep(Duration::from_millis(*ms)),
        }
    }
}

/// A watch session on a directory of its own, with the initial files.
struct Bench(Watcher);

impl std::ops::Deref for Bench {
    type Target = Watcher;
    fn deref(&self) -> &Watcher {
        &self.0
    }
}

impl std::ops::DerefMut for Bench {
    fn deref_mut(&mut self) -> &mut Watcher {
        &mut self.0
    }
}

impl Bench {
    fn new(name: &str) -> Self {
        let dir = common::temp_dir(&format!("diff-{name}"));
        for (d, sub) in DIRS.iter().enumerate() {
            std::fs::create_dir(dir.join(sub)).expect("mkdir");
            let (file, bytes) = dir_file(d, 0);
            std::fs::write(dir.join(sub).join(file), bytes).expect("write");
        }
        std::fs::write(
            dir.join("env").join(MAP_FILES[1]),
            map_bytes(1, MapBytes::Valid(2, 0)),
        )
        .expect("write map");
        // `dir_file(4, 0)` is the glTF file: its buffer over the centre and its image too.
        for v in [4, 2] {
            let (file, bytes) = dir_file(4, v);
            std::fs::write(dir.join("models").join(file), bytes).expect("write");
        }
        let text = SceneText {
            wall: 0,
            wall_prefab: true,
            textured: true,
            mesh: true,
            gltf: true,
            swapped: false,
            spp: 4,
            environment: Some(EnvText {
                file: 0,
                strength: 0,
                rotate: 0,
            }),
            background: false,
            sun: None,
            broken: false,
            truncated: false,
        };
        std::fs::write(dir.join("scene.ron"), text.text()).expect("write scene");
        Self(Watcher::start(dir))
    }

    /// [`Watcher::play_change`] of `ops`.
    fn play_change(&mut self, ops: &[Op]) -> Result<(), String> {
        self.0.play_change(&format!("after {ops:?}"), |dir| {
            for op in ops {
                op.apply(dir);
            }
        })
    }

    /// [`Watcher::play`] of `ops`.
    fn play(&mut self, ops: &[Op]) -> Result<(), String> {
        self.0.play(&format!("after {ops:?}"), |dir| {
            for op in ops {
                op.apply(dir);
            }
        })
    }
}

/// A random sequence of 1–6 edits, each followed by a gap of 0–100 ms (a third of them 0).
fn random_sequence(rng: &mut Rng, dir: &Path) -> Vec<Op> {
    let n = 1 + rng.below(6);
    let mut ops = Vec::new();
    for _ in 0..n {
        let op = Op::random(rng, dir);
        // Directory operations are applied at once below, so the next op sees their effect.
        op.apply(dir);
        ops.push(op);
        let gap = if rng.chance(33) {
            0
        } else {
            rng.below(101) as u64
        };
        std::thread::sleep(Duration::from_millis(gap));
        ops.push(Op::Gap(gap));
    }
    ops
}

#[test]
fn random_edit_sequences_end_in_what_a_fresh_render_shows() {
    const SESSIONS: u64 = 4;
    let sequences = env_number("RONDO_DIFF_SEQUENCES", 240);
    let seed = env_number("RONDO_DIFF_SEED", 14);
    let start = Instant::now();
    let workers: Vec<_> = (0..SESSIONS)
        .map(|w| {
            std::thread::spawn(move || {
                let mut bench = Bench::new(&format!("random{w}"));
                let mut rng = Rng(seed ^ (w + 1).wrapping_mul(0x2545_f491_4f6c_dd1d));
                for i in 0..sequences.div_ceil(SESSIONS) {
                    bench.reports.clear();
                    let ops = random_sequence(&mut rng, &bench.dir);
                    if let Err(e) = bench.settle(&format!("sequence {i} of session {w}: {ops:?}")) {
                        return Err(format!("seed {seed}: {e}"));
                    }
                }
                Ok(())
            })
        })
        .collect();
    let failures: Vec<String> = workers
        .into_iter()
        .filter_map(|w| w.join().expect("worker").err())
        .collect();
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
    eprintln!(
        "{sequences} sequences in {:.1} s",
        start.elapsed().as_secs_f64()
    );
}

// ------------------------------------------------------------------------------------------------
// Regression cases: sequences that once failed.

fn scene_text(wall: usize) -> SceneText {
    SceneText {
        wall,
        wall_prefab: false,
        textured: false,
        mesh: false,
        gltf: false,
        swapped: false,
        spp: 4,
        environment: None,
        background: false,
        sun: None,
        broken: false,
        truncated: false,
    }
}

#[test]
fn regression_spp_one_after_a_preview() {
    let mut b = Bench::new("spp-one");
    let text = SceneText {
        spp: 1,
        ..scene_text(1)
    };
    b.play(&[Op::Scene(text, Save::InPlace)])
        .unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn regression_directory_removed_then_created_with_new_contents() {
    let mut b = Bench::new("dir-recreated");
    b.play(&[Op::RemoveDir(0), Op::Gap(30)])
        .unwrap_or_else(|e| panic!("{e}"));
    b.play(&[Op::CreateDir(0, 2)])
        .unwrap_or_else(|e| panic!("{e}"));
    b.play(&[Op::Prefab(Some(1), Save::InPlace)])
        .unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn regression_directory_replaced_then_edited_at_once() {
    let mut b = Bench::new("dir-replaced");
    b.play(&[Op::ReplaceDir(1, 1), Op::Texture(Some(2), Save::Rename)])
        .unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn regression_mesh_swapped_keeping_size_and_mtime() {
    let mut b = Bench::new("mesh-stamp");
    b.play(&[Op::Mesh(Some(1), Save::KeepMtime)])
        .unwrap_or_else(|e| panic!("{e}"));
    b.play(&[Op::Mesh(Some(0), Save::KeepMtime)])
        .unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn regression_symlinked_texture_edited_through_the_link() {
    let mut b = Bench::new("symlink");
    b.play(&[Op::LinkTexture(1)])
        .unwrap_or_else(|e| panic!("{e}"));
    b.play(&[Op::Texture(Some(2), Save::InPlace)])
        .unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn regression_broken_then_fixed_within_a_window() {
    let mut b = Bench::new("broken-fixed");
    let broken = SceneText {
        broken: true,
        ..scene_text(2)
    };
    b.play(&[
        Op::Scene(broken, Save::InPlace),
        Op::Gap(10),
        Op::Scene(scene_text(1), Save::Split(60)),
    ])
    .unwrap_or_else(|e| panic!("{e}"));
}

// ------------------------------------------------------------------------------------------------
// The environment map's file, edited alone: every step changes the fresh render, so a watch that
// did not follow the file would keep showing the previous result.

#[test]
fn environment_map_swapped_keeping_size_and_mtime() {
    // The bench starts lit by `env/sky.exr` of pattern 0 at size 0.
    let mut b = Bench::new("map-stamp");
    let path = b.dir.join("env").join(MAP_FILES[0]);
    let stamp = |p: &Path| {
        let meta = std::fs::metadata(p).expect("stat");
        (meta.len(), meta.modified().expect("mtime"))
    };
    for pattern in [1, 0] {
        let before = stamp(&path);
        b.play_change(&[Op::Map(0, MapBytes::Valid(pattern, 0), Save::KeepMtime)])
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(stamp(&path), before, "the swap kept the size and the mtime");
    }
}

#[test]
fn environment_map_edited_through_a_symlink() {
    let mut b = Bench::new("map-symlink");
    b.play_change(&[Op::LinkMap(2)])
        .unwrap_or_else(|e| panic!("{e}"));
    b.play_change(&[Op::Map(0, MapBytes::Valid(3, 1), Save::InPlace)])
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(b.dir.join("env").join(MAP_FILES[0]).is_symlink());
}

#[test]
fn environment_map_broken_deleted_restored_then_a_radiance_map_edited() {
    let mut b = Bench::new("map-broken");
    for op in [
        Op::Map(0, MapBytes::Truncated(2, 2), Save::InPlace),
        Op::Map(0, MapBytes::Garbage, Save::Rename),
        Op::RemoveMap(0),
        Op::Map(0, MapBytes::Valid(2, 2), Save::Recreate),
    ] {
        b.play_change(&[op]).unwrap_or_else(|e| panic!("{e}"));
    }
    let hdr = SceneText {
        environment: Some(EnvText {
            file: 1,
            strength: 0,
            rotate: 1,
        }),
        ..scene_text(0)
    };
    b.play_change(&[Op::Scene(hdr, Save::InPlace)])
        .unwrap_or_else(|e| panic!("{e}"));
    b.play_change(&[Op::Map(1, MapBytes::Valid(1, 1), Save::Split(40))])
        .unwrap_or_else(|e| panic!("{e}"));
}

// A glTF model's file, buffer and image, each edited alone (every step changes the fresh render),
// and its directory replaced.
#[test]
fn gltf_model_image_buffer_and_file_edits() {
    let mut b = Bench::new("gltf");
    let with_model = SceneText {
        gltf: true,
        ..scene_text(1)
    };
    let steps = [
        vec![Op::Scene(with_model, Save::InPlace)],
        vec![Op::GltfImage(Some(0), Save::KeepMtime)],
        vec![Op::GltfBuffer(Some(1), Save::Rename)],
        vec![Op::GltfBuffer(None, Save::InPlace)],
        vec![Op::GltfBuffer(Some(0), Save::Split(30))],
        vec![Op::Gltf(Some(4), Save::Recreate)],
        vec![Op::Gltf(None, Save::InPlace)],
        vec![Op::ReplaceDir(4, 3)],
    ];
    for ops in &steps {
        b.play_change(ops).unwrap_or_else(|e| panic!("{e}"));
    }
}
