//! The OBJ reader (src/scene/mesh.rs) against the `tobj` crate it replaced: the same vertices,
//! normals, texture coordinates and triangles on the repository's meshes and on random files,
//! cut into chunks of any size; errors where `tobj` has them, with the line.

mod common;

use glam::{Vec2, Vec3};
use rondo::scene::mesh::{parse_obj, parse_obj_in_chunks};
use rondo::shading::rng::Rng;

/// A mesh as read (the fields of rondo's `MeshData`, whose module the issue-24 house work moves).
#[derive(Default)]
struct MeshData {
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    uvs: Option<Vec<Vec2>>,
    triangles: Vec<[u32; 3]>,
}

/// The reader's result on `bytes` cut into chunks of `chunk` bytes.
fn read(bytes: &[u8], chunk: usize) -> Result<MeshData, String> {
    parse_obj_in_chunks(bytes, chunk).map(|m| MeshData {
        positions: m.positions,
        normals: m.normals,
        uvs: m.uvs,
        triangles: m.triangles,
    })
}

/// What rondo read from `tobj` (the conversion it did before its own reader), or `None` for a
/// file refused.
fn reference(bytes: &[u8]) -> Option<MeshData> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let (models, _) = tobj::load_obj_buf(&mut &bytes[..], &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .ok()?;
    let mut mesh = MeshData::default();
    let mut normals = Some(Vec::new());
    let mut uvs = Some(Vec::new());
    for model in &models {
        let m = &model.mesh;
        let base = mesh.positions.len() as u32;
        let count = m.positions.len() / 3;
        for p in m.positions.chunks_exact(3) {
            let v = Vec3::new(p[0], p[1], p[2]);
            if !v.is_finite() {
                return None;
            }
            mesh.positions.push(v);
        }
        match (&mut normals, m.normals.len() == m.positions.len()) {
            (Some(n), true) => n.extend(
                m.normals
                    .chunks_exact(3)
                    .map(|c| Vec3::new(c[0], c[1], c[2]).normalize_or_zero()),
            ),
            _ => normals = None,
        }
        match (&mut uvs, m.texcoords.len() == 2 * count) {
            (Some(t), true) => {
                for c in m.texcoords.chunks_exact(2) {
                    let uv = Vec2::new(c[0], c[1]);
                    if !uv.is_finite() {
                        return None;
                    }
                    t.push(uv);
                }
            }
            _ => uvs = None,
        }
        for f in m.indices.chunks_exact(3) {
            mesh.triangles.push([f[0], f[1], f[2]].map(|i| i + base));
        }
    }
    if mesh.triangles.is_empty() {
        return None;
    }
    mesh.normals = normals.filter(|n| n.len() == mesh.positions.len());
    mesh.uvs = uvs.filter(|t| t.len() == mesh.positions.len());
    Some(mesh)
}

/// Compares bit for bit (`-0.0` is not `0.0`; NaN normals are impossible after
/// `normalize_or_zero` of finite values but compared by bits all the same).
fn same(a: &MeshData, b: &MeshData) -> bool {
    let bits3 = |v: &[Vec3]| -> Vec<[u32; 3]> {
        v.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
    };
    let bits2 = |v: &[Vec2]| -> Vec<[u32; 2]> {
        v.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
    };
    a.triangles == b.triangles
        && bits3(&a.positions) == bits3(&b.positions)
        && a.normals.as_deref().map(bits3) == b.normals.as_deref().map(bits3)
        && a.uvs.as_deref().map(bits2) == b.uvs.as_deref().map(bits2)
}

/// Checks the reader against `tobj` on `bytes`, whole and cut into chunks of several sizes.
fn check(name: &str, bytes: &[u8]) {
    let want = reference(bytes);
    for chunk in [usize::MAX, 1, 7, 64, 1000] {
        let got = read(bytes, chunk);
        match (&want, &got) {
            (Some(w), Ok(g)) => assert!(
                same(w, g),
                "{name}, chunks of {chunk} bytes: differs from tobj\n{}",
                String::from_utf8_lossy(bytes)
            ),
            (None, Err(e)) => assert!(e.contains("line ") || e.contains("no faces"), "{e}"),
            (Some(_), Err(e)) => panic!(
                "{name}, chunks of {chunk} bytes: refused ({e}), tobj read it\n{}",
                String::from_utf8_lossy(bytes)
            ),
            (None, Ok(_)) => panic!(
                "{name}, chunks of {chunk} bytes: read, tobj refused it\n{}",
                String::from_utf8_lossy(bytes)
            ),
        }
    }
}

#[test]
fn repository_meshes_read_as_with_tobj() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/meshes");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).expect("scenes/meshes") {
        let path = entry.expect("entry").path();
        if path.extension().is_some_and(|e| e == "obj") {
            let bytes = std::fs::read(&path).expect("read");
            assert!(reference(&bytes).is_some(), "{}", path.display());
            check(&path.display().to_string(), &bytes);
            n += 1;
        }
    }
    assert!(n >= 2, "the bunny and the lamp");
    for smooth in [false, true] {
        check(
            "uv sphere",
            common::uv_sphere_obj(40, 20, smooth).as_bytes(),
        );
    }
}

/// A random number in `0..n`.
fn below(rng: &mut Rng, n: u32) -> u32 {
    rng.next_u32() % n
}

/// A number as OBJ files write them, in one of several spellings.
fn number(rng: &mut Rng) -> String {
    let x = (rng.next_f32() - 0.5) * 8.0;
    match below(rng, 6) {
        0 => format!("{x}"),
        1 => format!("{x:e}"),
        2 => format!("{}", x.round() as i32),
        3 => format!("+{:.3}", x.abs()),
        4 => format!("{x:.6}"),
        _ => "-0".to_string(),
    }
}

/// A face index into `count` statements so far (of `total` in the file): mostly valid, positive
/// or negative; now and then 0, missing or out of range.
fn face_index(rng: &mut Rng, count: u32, total: u32, wild: bool) -> String {
    if wild && below(rng, 40) == 0 {
        return ["0", "-0", "99999", "-99999", "x"][below(rng, 5) as usize].to_string();
    }
    if wild && below(rng, 30) == 0 {
        // A forward reference (valid for tobj in the last object only).
        return format!("{}", 1 + below(rng, total.max(1)));
    }
    if count == 0 {
        // Valid if the file has none of these (an index to nothing is ignored) or if they
        // come later in the last object.
        return "1".to_string();
    }
    let i = below(rng, count);
    if below(rng, 3) == 0 {
        format!("-{}", count - i)
    } else {
        format!("{}", i + 1)
    }
}

/// A random OBJ file: vertices, coordinates and normals interleaved with faces of 1 to 7
/// vertices in the four index styles, objects and groups, comments, blank lines, CRLF, and
/// (if `wild`) malformed statements now and then.
fn random_obj(rng: &mut Rng, wild: bool) -> String {
    let lines = 5 + below(rng, 60);
    let (mut v, mut vt, mut vn) = (0u32, 0u32, 0u32);
    let total = lines;
    // One index style for the whole file most of the time, so that normals and uvs are kept.
    let fixed_style = below(rng, 2) == 0;
    let style = below(rng, 4);
    let colours = below(rng, 4) == 0;
    let mut out = String::new();
    for _ in 0..lines {
        let end = if below(rng, 5) == 0 { "\r\n" } else { "\n" };
        // Whitespace of both kinds: ASCII (tab, vertical tab, form feed) and not (no-break
        // space, ideographic space).
        let sep = match below(rng, 16) {
            0 => "\t",
            1 => "\x0b",
            2 => "\x0c ",
            3 => "\u{a0}",
            4 => " \u{3000}",
            _ => " ",
        };
        let line = match below(rng, 20) {
            0..=5 => {
                v += 1;
                let mut l = format!("v{sep}{} {} {}", number(rng), number(rng), number(rng));
                if colours {
                    l += " 0.5 0.25 1";
                } else if below(rng, 10) == 0 {
                    l += [" 2", " 0.5", " -1"][below(rng, 3) as usize];
                }
                l
            }
            6 | 7 => {
                vt += 1;
                let w = if below(rng, 4) == 0 { " 0" } else { "" };
                format!("vt {} {}{w}", number(rng), number(rng))
            }
            8 | 9 => {
                vn += 1;
                format!("vn {} {} {}", number(rng), number(rng), number(rng))
            }
            10..=15 => {
                let n = 1 + below(rng, 7);
                let kind = if below(rng, 10) == 0 { "l" } else { "f" };
                let mut l = kind.to_string();
                for _ in 0..n {
                    let s = if fixed_style { style } else { below(rng, 4) };
                    let p = face_index(rng, v, total, wild);
                    let t = face_index(rng, vt, total, wild);
                    let q = face_index(rng, vn, total, wild);
                    l += sep;
                    l += &match s {
                        0 => p,
                        1 => format!("{p}/{t}"),
                        2 => format!("{p}//{q}"),
                        _ => format!("{p}/{t}/{q}"),
                    };
                }
                l
            }
            16 => ["o thing", "g", "g left right", "o"][below(rng, 4) as usize].to_string(),
            17 => ["# a comment", "", "s 1", "  ", "#v 1 2 3"][below(rng, 5) as usize].to_string(),
            18 => ["usemtl red", "mtllib m.mtl", "vp 1 2", "  f 1 1 1"][below(rng, 4) as usize]
                .to_string(),
            _ if wild => [
                "v 1 2",
                "v 1 2 3 4 5",
                "v 1 2 3 0",
                "vt 1",
                "vn 1 2 x",
                "f 1/2/3/4",
                "f 1//2/",
                "f",
                "usemtl",
                "usemtl\tx",
                "v nan 1 1",
                "v inf 0 0",
                "vt 1 nan",
                "f 1.5 2 3",
                "v 1 2 3 a b c",
            ][below(rng, 15) as usize]
                .to_string(),
            _ => String::new(),
        };
        out += &line;
        out += end;
    }
    if below(rng, 4) == 0 {
        out.pop();
    }
    out
}

#[test]
fn random_files_read_as_with_tobj() {
    let mut rng = Rng::new(24, 3);
    let (mut read, mut refused) = (0, 0);
    for i in 0..3000 {
        let obj = random_obj(&mut rng, i % 2 == 1);
        match reference(obj.as_bytes()) {
            Some(_) => read += 1,
            None => refused += 1,
        }
        check(&format!("random file {i}"), obj.as_bytes());
    }
    // Both kinds are exercised.
    assert!(
        read > 500 && refused > 500,
        "{read} read, {refused} refused"
    );
}

#[test]
fn errors_name_the_line() {
    let cases: [(&str, &str); 6] = [
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 9\n", "line 5"),
        ("v 0 0 0\nv 1 0 x\n", "line 2"),
        ("# a\r\nv 0 0 0\r\nf 1 1 1/2/3/4\r\n", "line 3"),
        ("v 0 0 0\nusemtl\nf 1 1 1\n", "line 2"),
        ("v 0 0 0\nf 1 1 1\nf\n", "line 3"),
        ("v 0 0 0\nvt 0 0\nf 1 1 1\ng\nf -1/-1 1/1 1/3\n", "line 5"),
    ];
    for (obj, line) in cases {
        for chunk in [1, 5, usize::MAX] {
            let e = parse_obj_in_chunks(obj.as_bytes(), chunk).expect_err(obj);
            assert!(e.contains(&format!("{line}:")), "{obj:?}: {e}");
        }
    }
    let e = parse_obj(b"v 0 0 0\nf 1 1 1\n\xff\n").expect_err("not UTF-8");
    assert!(e.contains("line 3:"), "{e}");
}
