//! The differential watch test (see `common/watch_diff.rs`) on big assets: a mesh of 10⁵
//! triangles (an OBJ written here) and an image texture of 1024² texels (3 MB), each rewritten
//! with the same bytes, changed in place keeping its size and modification time, truncated,
//! replaced by a rename, and touched; after each, the watch must show what a fresh render of the
//! files shows. And the work a reload counts: an edit of the scene alone reads no asset byte and
//! builds no mesh BVH.
//!
//! The mesh is the scene's lamp, so that a change of one vertex (the area of its triangles, and
//! so the light sampling of every pixel) shows in a tiny image; the texture is on a wall that
//! fills the view, and its edits change a band of rows.

mod common;

use std::path::Path;

use common::png_chunks::crc32;
use common::watch_diff::{Save, Watcher, fresh, set_mtime, stamp};

/// Quads per side of the mesh: 2 × 224² = 100,352 triangles.
const GRID: usize = 224;
/// Side of the texture.
const TEXELS: u32 = 1024;

/// The scene: the mesh a lamp overhead, the textured wall behind, a ball at `ball_x`.
fn scene_text(ball_x: f32) -> String {
    format!(
        r#"Scene(
    camera: Camera(position: (0, 0, -10), look_at: (0, 0, 0), fov: 40.0),
    settings: Settings(width: 32, height: 24, spp: 2, max_depth: 3),
    materials: {{
        "lamp": Light(emit: Constant((1.0, 0.95, 0.9)), intensity: 2.0, two_sided: true),
        "wall": Diffuse(albedo: Image(path: "tex/big.png")),
        "ball": Diffuse(albedo: Constant((0.6, 0.6, 0.6))),
    }},
    entities: [
        Entity(name: "ceiling", material: "lamp", shape: Mesh(path: "meshes/big.obj")),
        Entity(name: "wall", material: "wall", shape: Quad(a: (-6, -5, 4), b: (6, -5, 4), c: (6, 5, 4), d: (-6, 5, 4))),
        Entity(name: "ball", material: "ball", shape: Sphere(center: ({ball_x}, -1, 0), radius: 1)),
    ],
)
"#
    )
}

/// The mesh: a gently waved panel at y ≈ 3 over x in [-6, 6], z in [-4, 4], `GRID`² quads,
/// every coordinate written in one width (so that a vertex can change keeping the file's
/// size). With `spike`, the middle vertex hangs down to y = -2.
fn mesh_obj(spike: bool) -> Vec<u8> {
    let mut obj = String::new();
    let n = GRID + 1;
    for j in 0..n {
        for i in 0..n {
            let (u, v) = (i as f32 / GRID as f32, j as f32 / GRID as f32);
            let y = if spike && (i, j) == (GRID / 2, GRID / 2) {
                -2.0
            } else {
                3.0 + 0.05 * (9.0 * u).sin() * (7.0 * v).cos()
            };
            obj += &format!("v {:+.4} {:+.4} {:+.4}\n", 12.0 * u - 6.0, y, 8.0 * v - 4.0);
        }
    }
    for j in 0..GRID {
        for i in 0..GRID {
            let k = |i: usize, j: usize| j * n + i + 1;
            let (a, b, c, d) = (k(i, j), k(i + 1, j), k(i + 1, j + 1), k(i, j + 1));
            obj += &format!("f {a} {b} {c}\nf {a} {c} {d}\n");
        }
    }
    obj.into_bytes()
}

/// A PNG of 8-bit RGB `rows` (each `3 × width` bytes) with its image data stored, not
/// compressed: its size depends on its dimensions only, so that texels can change keeping it.
fn stored_png(width: u32, rows: &[Vec<u8>]) -> Vec<u8> {
    let raw: Vec<u8> = rows
        .iter()
        .flat_map(|row| std::iter::once(0).chain(row.iter().copied()))
        .collect();
    let mut zlib = vec![0x78, 0x01];
    let blocks = raw.chunks(65_535).collect::<Vec<_>>();
    for (k, block) in blocks.iter().enumerate() {
        let len = block.len() as u16;
        zlib.push(u8::from(k + 1 == blocks.len()));
        zlib.extend(len.to_le_bytes());
        zlib.extend((!len).to_le_bytes());
        zlib.extend_from_slice(block);
    }
    let (mut a, mut b) = (1u32, 0u32);
    for &byte in &raw {
        a = (a + u32::from(byte)) % 65_521;
        b = (b + a) % 65_521;
    }
    zlib.extend(((b << 16) | a).to_be_bytes());
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut chunk = |kind: &[u8], data: &[u8]| {
        png.extend((data.len() as u32).to_be_bytes());
        let body = [kind, data].concat();
        png.extend_from_slice(&body);
        png.extend(crc32(&body).to_be_bytes());
    };
    let mut header = width.to_be_bytes().to_vec();
    header.extend((rows.len() as u32).to_be_bytes());
    header.extend([8, 2, 0, 0, 0]);
    chunk(b"IHDR", &header);
    chunk(b"IDAT", &zlib);
    chunk(b"IEND", &[]);
    png
}

/// The texture: a colour gradient; with `band`, rows 300–499 red.
fn texture_png(band: bool) -> Vec<u8> {
    let rows: Vec<Vec<u8>> = (0..TEXELS)
        .map(|y| {
            (0..TEXELS)
                .flat_map(|x| {
                    if band && (300..500).contains(&y) {
                        [230, 20, 20]
                    } else {
                        [(x / 4) as u8, (y / 4) as u8, 128]
                    }
                })
                .collect()
        })
        .collect();
    stored_png(TEXELS, &rows)
}

/// A watch of the scene with the ball at x = -2, the mesh and the texture unchanged.
fn bench() -> Watcher {
    let dir = common::temp_dir("big-assets");
    for sub in ["meshes", "tex"] {
        std::fs::create_dir(dir.join(sub)).expect("mkdir");
    }
    std::fs::write(dir.join("meshes/big.obj"), mesh_obj(false)).expect("write mesh");
    std::fs::write(dir.join("tex/big.png"), texture_png(false)).expect("write texture");
    std::fs::write(dir.join("scene.ron"), scene_text(-2.0)).expect("write scene");
    Watcher::start(dir)
}

/// Moves the ball to `x` and checks that the reload read no asset byte, decoded no texture and
/// built no mesh BVH.
fn move_ball_reading_no_asset(w: &mut Watcher, x: f32) {
    let before = w.reloads.last().map(|r| r.counters.mesh_bvh_builds);
    w.play_change(&format!("the ball moved to {x}"), |dir| {
        std::fs::write(dir.join("scene.ron"), scene_text(x)).expect("write scene");
    })
    .unwrap_or_else(|e| panic!("{e}"));
    let report = w.last_reload("a move").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(report.asset_bytes_read, 0, "{report}");
    assert_eq!(report.textures_decoded, 0, "{report}");
    if let Some(builds) = before {
        assert_eq!(report.counters.mesh_bvh_builds, builds, "{report}");
    }
}

/// Saves `bytes` as the file `path` with `save`, keeping its size and modification time
/// (checked): only its contents tell the change.
fn write_keeping_stamp(path: &Path, bytes: &[u8], save: Save) {
    let before = stamp(path);
    save.write(path, bytes);
    set_mtime(path, before.1);
    assert_eq!(
        stamp(path),
        before,
        "{} kept its size and mtime",
        path.display()
    );
}

/// Writes `bytes` to a temporary file and renames it over `path`.
fn replace_by_rename(path: &Path, bytes: &[u8]) {
    Save::Rename.write(path, bytes);
}

/// The edits one big asset goes through, each checked against a fresh render: `changed` is
/// its contents after a change that keeps the size, `original` what the bench started with.
fn edit_asset(w: &mut Watcher, rel: &str, original: &[u8], changed: &[u8]) {
    let path = w.dir.join(rel);
    let size = original.len() as u64;
    assert_eq!(
        changed.len(),
        original.len(),
        "{rel}: the change keeps the size"
    );

    // The same bytes again: read again (an event named it), nothing else changes.
    let same = w
        .play_same(&format!("{rel} rewritten as it was"), |_| {
            std::fs::write(&path, original).expect("write");
        })
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(same.asset_bytes_read, size, "{same}");
    assert!(same.changes.is_empty(), "{same}");

    // Changed in place keeping the size and the mtime: only the event tells.
    w.play_change(&format!("{rel} changed, same size and mtime"), |_| {
        write_keeping_stamp(&path, changed, Save::KeepMtime);
    })
    .unwrap_or_else(|e| panic!("{e}"));

    // Truncated: an error, the last good image kept.
    w.play_change(&format!("{rel} truncated"), |_| {
        std::fs::write(&path, &original[..original.len() / 3]).expect("write");
    })
    .unwrap_or_else(|e| panic!("{e}"));
    assert!(fresh(&w.scene()).is_err(), "{rel} truncated is broken");

    // Restored by a rename over it (a new inode).
    w.play_change(&format!("{rel} restored by a rename"), |_| {
        replace_by_rename(&path, original);
    })
    .unwrap_or_else(|e| panic!("{e}"));

    // Touched: a metadata event only.
    w.play(&format!("{rel} touched"), |_| {
        set_mtime(&path, std::time::SystemTime::now());
    })
    .unwrap_or_else(|e| panic!("{e}"));

    // Replaced by a rename with the changed contents of the same size and mtime (another inode).
    w.play_change(&format!("{rel} replaced, same size and mtime"), |dir| {
        let other = dir.join("replacement.tmp");
        std::fs::write(&other, changed).expect("write");
        set_mtime(&other, stamp(&path).1);
        std::fs::rename(&other, &path).expect("rename");
    })
    .unwrap_or_else(|e| panic!("{e}"));

    // And back, in two halves with a pause (a slow writer).
    w.play_change(&format!("{rel} written back slowly"), |_| {
        Save::Split(60).write(&path, original);
    })
    .unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn big_mesh_edits_end_in_what_a_fresh_render_shows() {
    let mut w = bench();
    move_ball_reading_no_asset(&mut w, 2.0);
    edit_asset(&mut w, "meshes/big.obj", &mesh_obj(false), &mesh_obj(true));
    move_ball_reading_no_asset(&mut w, -1.0);
    move_ball_reading_no_asset(&mut w, 1.0);
}

#[test]
fn big_texture_edits_end_in_what_a_fresh_render_shows() {
    let mut w = bench();
    move_ball_reading_no_asset(&mut w, 2.0);
    edit_asset(
        &mut w,
        "tex/big.png",
        &texture_png(false),
        &texture_png(true),
    );
    move_ball_reading_no_asset(&mut w, -1.0);
    move_ball_reading_no_asset(&mut w, 1.0);
}
