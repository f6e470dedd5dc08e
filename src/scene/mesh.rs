//! Wavefront OBJ meshes: every object of the file, triangulated, with no hidden scale.
//!
//! The reader is rondo's own and parallel: the text is cut at line ends into chunks that are
//! parsed at the same time, then the chunks' faces are numbered into one vertex list in file
//! order. It reads the subset of OBJ rondo uses (`v`, `vt`, `vn`, `f`, `l`, `o`, `g`, `usemtl`;
//! other statements are skipped) and gives the same vertices and triangles as the `tobj` crate
//! with `triangulate` and `single_index` (the tests compare the two): a vertex is one distinct
//! `v/vt/vn` triple of an object, numbered in order of first use; faces are fans; points and
//! lines are zero-area triangles; indices may be negative (relative). Unlike `tobj` it ignores
//! vertex colours (`v x y z r g b`) instead of refusing files where only some vertices have them.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::bounded_read::{MAX_INPUT_BYTES, read_bounded};
use crate::model::MeshData;

/// Most triangles one OBJ file may produce (the limit of glTF files too).
pub const MAX_TRIANGLES: usize = crate::scene::gltf_read::MAX_TRIANGLES;

/// Bytes of text per chunk parsed on its own (the last line of a chunk runs on to its end).
const CHUNK_BYTES: usize = 1 << 20;

/// An index that was not given (`v//vn`, or `0`, as `tobj` reads it).
const MISSING: u32 = u32::MAX;
/// An index beyond anything a file can hold (negative past the start, or above `u32`).
const BEYOND: u32 = u32::MAX - 1;

/// Reads an OBJ file. Faces are triangulated; all its objects are merged into one mesh. Vertex
/// normals and texture coordinates (`vt`) are each kept when every object has one per vertex.
/// Malformed files, out-of-range indices, non-finite coordinates and empty meshes are errors
/// naming the line, never panics.
pub fn load_obj(path: &Path) -> Result<MeshData, String> {
    let (_, bytes) =
        read_bounded(path, MAX_INPUT_BYTES).map_err(|e| format!("cannot read OBJ: {e}"))?;
    parse_obj(&bytes)
}

/// Parses the bytes of an OBJ file, as [`load_obj`] (material libraries are not read: materials
/// come from the scene).
pub fn parse_obj(bytes: &[u8]) -> Result<MeshData, String> {
    parse_obj_in_chunks(bytes, CHUNK_BYTES)
}

/// [`parse_obj`], cutting the text into chunks of about `chunk_bytes` (at least 1) parsed in
/// parallel. The result does not depend on the size; tests cut small inputs into many chunks.
pub fn parse_obj_in_chunks(bytes: &[u8], chunk_bytes: usize) -> Result<MeshData, String> {
    let bounds = chunk_bounds(bytes, chunk_bytes.max(1));
    // Triangles still allowed, shared by the chunks so that none parses past the limit.
    let budget = AtomicUsize::new(MAX_TRIANGLES);
    let mut chunks: Vec<Chunk> = bounds
        .par_windows(2)
        .map(|w| parse_chunk(&bytes[w[0]..w[1]], &budget))
        .collect::<Vec<_>>()
        .into_iter()
        .zip(&bounds)
        .map(|(parsed, &start)| {
            parsed.map_err(|(at, reason)| {
                let line = 1 + bytes[..start + at].iter().filter(|&&b| b == b'\n').count();
                format!("cannot read OBJ: line {line}: {reason}")
            })
        })
        .collect::<Result<_, _>>()?;
    // Counts of `v`, `vt` and `vn` before each chunk: relative indices become absolute.
    let mut base = Counts::default();
    let mut bases = Vec::with_capacity(chunks.len());
    for c in &chunks {
        bases.push(base);
        base = base.plus(c.counts());
    }
    let total = base;
    chunks
        .par_iter_mut()
        .zip(&bases)
        .for_each(|(c, b)| c.resolve(b));
    let numbered = number_vertices(&chunks, &bases, total).map_err(|(corner, reason)| {
        let line = line_of_corner(bytes, &bounds, &chunks, corner);
        format!("cannot read OBJ: line {line}: {reason}")
    })?;
    gather(bytes, &chunks, numbered)
}

/// Chunk starts (and the end): cuts after a newline, at least `size` bytes apart.
fn chunk_bounds(bytes: &[u8], size: usize) -> Vec<usize> {
    let mut bounds = vec![0];
    let mut at = 0;
    while bytes.len() - at > size {
        match bytes[at + size..].iter().position(|&b| b == b'\n') {
            Some(i) => {
                at += size + i + 1;
                if at < bytes.len() {
                    bounds.push(at);
                }
            }
            None => break,
        }
    }
    bounds.push(bytes.len());
    bounds
}

/// Numbers of `v`, `vt` and `vn` statements.
#[derive(Clone, Copy, Default, Debug)]
struct Counts {
    positions: usize,
    texcoords: usize,
    normals: usize,
}

impl Counts {
    fn plus(self, o: Counts) -> Counts {
        Counts {
            positions: self.positions + o.positions,
            texcoords: self.texcoords + o.texcoords,
            normals: self.normals + o.normals,
        }
    }
}

/// An `o` or `g` statement that may end an object (if faces came since the last one).
#[derive(Clone, Copy, Debug)]
struct Break {
    /// Corners of the chunk before it.
    corner: usize,
    /// The chunk's statements before it.
    counts: Counts,
}

/// A corner index given relative to the statements before its face, resolved once the chunk's
/// place in the file is known.
#[derive(Clone, Copy, Debug)]
struct Relative {
    /// The corner, in the chunk.
    corner: u32,
    /// 0 for `v`, 1 for `vt`, 2 for `vn`.
    slot: u8,
    /// The chunk's count of that kind before the face plus the (negative) index.
    local: i64,
}

/// One chunk of the file, parsed.
#[derive(Default)]
struct Chunk {
    positions: Vec<Vec3>,
    texcoords: Vec<Vec2>,
    normals: Vec<Vec3>,
    /// Three per triangle: zero-based `v`, `vt`, `vn` ([`MISSING`] if not given).
    corners: Vec<[u32; 3]>,
    relative: Vec<Relative>,
    breaks: Vec<Break>,
}

impl Chunk {
    fn counts(&self) -> Counts {
        Counts {
            positions: self.positions.len(),
            texcoords: self.texcoords.len(),
            normals: self.normals.len(),
        }
    }

    /// Makes the relative indices absolute, given the counts before the chunk.
    fn resolve(&mut self, base: &Counts) {
        let bases = [base.positions, base.texcoords, base.normals];
        for r in &self.relative {
            let i = bases[usize::from(r.slot)] as i64 + r.local;
            self.corners[r.corner as usize][usize::from(r.slot)] = index(i);
        }
    }
}

/// A zero-based index as stored: -1 is [`MISSING`], anything outside `u32` [`BEYOND`].
fn index(i: i64) -> u32 {
    match i {
        -1 => MISSING,
        0..0xFFFF_FFFE => i as u32,
        _ => BEYOND,
    }
}

/// Parses one chunk, taking its triangles from `budget`; an error is its byte offset in the chunk and the reason.
fn parse_chunk(bytes: &[u8], budget: &AtomicUsize) -> Result<Chunk, (usize, String)> {
    let text = std::str::from_utf8(bytes)
        .map_err(|e| (e.valid_up_to(), "the file is not UTF-8 text".to_string()))?;
    let mut chunk = Chunk::default();
    let mut face = Vec::new();
    let mut at = 0;
    for raw in text.split_inclusive('\n') {
        let line = raw.strip_suffix('\n').unwrap_or(raw);
        let line = line.strip_suffix('\r').unwrap_or(line);
        parse_line(line, &mut chunk, &mut face, budget).map_err(|reason| (at, reason))?;
        at += raw.len();
    }
    Ok(chunk)
}

/// The words of a line, split at whitespace as [`str::split_whitespace`] does; without
/// decoding characters when the line is ASCII (nearly always).
enum Words<'a> {
    Ascii(&'a str),
    Other(std::str::SplitWhitespace<'a>),
}

impl<'a> Words<'a> {
    fn new(line: &'a str) -> Self {
        if line.is_ascii() {
            Words::Ascii(line)
        } else {
            Words::Other(line.split_whitespace())
        }
    }
}

impl<'a> Iterator for Words<'a> {
    type Item = &'a str;

    fn next(&mut self) -> Option<&'a str> {
        // The ASCII characters with Unicode's White_Space property.
        let space = |b: &u8| matches!(b, b'\t'..=b'\r' | b' ');
        match self {
            Words::Other(words) => words.next(),
            Words::Ascii(rest) => {
                let bytes = rest.as_bytes();
                let Some(start) = bytes.iter().position(|b| !space(b)) else {
                    *rest = "";
                    return None;
                };
                let end = bytes[start..]
                    .iter()
                    .position(space)
                    .map_or(bytes.len(), |n| start + n);
                // Byte offsets of an ASCII string are character boundaries.
                let word = &rest[start..end];
                *rest = &rest[end..];
                Some(word)
            }
        }
    }
}

/// Parses `n` floats from `words`.
fn floats<const N: usize>(words: &mut Words) -> Result<[f32; N], String> {
    let mut out = [0.0; N];
    for o in &mut out {
        let w = words.next().ok_or("too few numbers")?;
        *o = w.parse().map_err(|_| format!("\"{w}\" is not a number"))?;
    }
    Ok(out)
}

/// Parses one line (without its line end) into `chunk`; `face` is scratch space.
fn parse_line(
    line: &str,
    chunk: &mut Chunk,
    face: &mut Vec<[i64; 3]>,
    budget: &AtomicUsize,
) -> Result<(), String> {
    let mut words = Words::new(line);
    match words.next() {
        Some("v") => {
            let [x, y, z] = floats::<3>(&mut words).map_err(|e| format!("vertex: {e}"))?;
            let mut p = Vec3::new(x, y, z);
            let rest: [Option<&str>; 4] = std::array::from_fn(|_| words.next());
            match rest {
                [None, ..] | [Some(_), Some(_), Some(_), None] => {}
                [Some(w), None, ..] => {
                    let w: f32 = w
                        .parse()
                        .map_err(|_| format!("vertex: \"{w}\" is not a number"))?;
                    if w == 0.0 {
                        return Err("vertex: its w is 0".into());
                    }
                    p /= w;
                }
                _ => return Err("vertex: neither x y z [w] nor x y z r g b".into()),
            }
            chunk.positions.push(p);
        }
        Some("vt") => {
            let [u, v] = floats::<2>(&mut words).map_err(|e| format!("texture coordinate: {e}"))?;
            chunk.texcoords.push(Vec2::new(u, v));
        }
        Some("vn") => {
            let n = floats::<3>(&mut words).map_err(|e| format!("normal: {e}"))?;
            chunk.normals.push(Vec3::from_array(n));
        }
        Some("f" | "l") => {
            face.clear();
            for word in words {
                face.push(face_vertex(word)?);
            }
            let n = face.len();
            let triangles = match n {
                0 => return Err("a face with no vertices".into()),
                1..=3 => 1,
                _ => n - 2,
            };
            budget
                .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |left| {
                    left.checked_sub(triangles)
                })
                .map_err(|_| format!("more than {MAX_TRIANGLES} triangles in the file"))?;
            let counts = chunk.counts();
            let counts = [counts.positions, counts.texcoords, counts.normals];
            let corner = |chunk: &mut Chunk, k: usize| {
                let c = chunk.corners.len() as u32;
                let mut out = [0; 3];
                for (slot, (&i, o)) in face[k].iter().zip(&mut out).enumerate() {
                    if i < -1 {
                        // Relative (`-1` is the last one): one past the index is negative.
                        chunk.relative.push(Relative {
                            corner: c,
                            slot: slot as u8,
                            local: counts[slot] as i64 + i + 1,
                        });
                    } else {
                        *o = index(i);
                    }
                }
                chunk.corners.push(out);
            };
            match n {
                1 => (0..3).for_each(|_| corner(chunk, 0)),
                2 => [0, 1, 1].into_iter().for_each(|k| corner(chunk, k)),
                _ => {
                    for k in 1..n - 1 {
                        corner(chunk, 0);
                        corner(chunk, k);
                        corner(chunk, k + 1);
                    }
                }
            }
        }
        Some("o" | "g") => {
            let corner = chunk.corners.len();
            if chunk.breaks.last().is_none_or(|b| b.corner < corner) {
                chunk.breaks.push(Break {
                    corner,
                    counts: chunk.counts(),
                });
            }
        }
        // As `tobj`: the name is what follows the first space.
        Some("usemtl")
            if line
                .split_once(' ')
                .is_none_or(|(_, n)| n.trim().is_empty()) =>
        {
            return Err("usemtl without a material name".into());
        }
        _ => {}
    }
    Ok(())
}

/// One vertex of a face, `v`, `v/vt`, `v//vn` or `v/vt/vn`, as zero-based indices with `-1`
/// for one not given; relative (negative) indices are kept as `index - 1` (below -1).
fn face_vertex(word: &str) -> Result<[i64; 3], String> {
    let mut out = [-1; 3];
    for (k, part) in word.split('/').enumerate() {
        if part.is_empty() {
            continue;
        }
        let slot = out
            .get_mut(k)
            .ok_or_else(|| format!("face vertex \"{word}\" has more than three indices"))?;
        let i: i64 = part
            .parse()
            .map_err(|_| format!("face vertex \"{word}\": \"{part}\" is not an index"))?;
        // As `tobj`: a negative index counts back from the statements so far (kept as one
        // below it, resolved later), a positive one from 1; 0 means none (but for `v`).
        *slot = if i < 0 { i.saturating_sub(1) } else { i - 1 };
    }
    Ok(out)
}

/// The vertices of the mesh: for every new vertex its `v`, `vt` and `vn`, for every corner its
/// vertex, and whether every object had normals and texture coordinates for all its vertices
/// (for uvs: the first vertex of the first object without them).
struct Numbered {
    vertices: Vec<[u32; 3]>,
    triangles: Vec<[u32; 3]>,
    normals: bool,
    uvs_until: usize,
}

/// A hash of a vertex's three indices (the keys are small, known integers: no DoS concern for
/// a file the user chose, and the map only holds vertices sharing a `v` with another).
#[derive(Default)]
struct KeyHasher(u64);

impl Hasher for KeyHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }
    fn write_u32(&mut self, i: u32) {
        self.write_u64(u64::from(i));
    }
    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(5) ^ i).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

/// Numbers the distinct `v/vt/vn` triples of each object in order of first use; an error is
/// the corner's index in the file and the reason.
fn number_vertices(
    chunks: &[Chunk],
    bases: &[Counts],
    total: Counts,
) -> Result<Numbered, (usize, String)> {
    // The objects: the corner each starts at and the statements before its end.
    let mut objects: Vec<(usize, Counts)> = Vec::new();
    let mut corners = 0;
    let mut last_start = 0;
    for (c, b) in chunks.iter().zip(bases) {
        for br in &c.breaks {
            let at = corners + br.corner;
            if at > last_start {
                objects.push((last_start, b.plus(br.counts)));
                last_start = at;
            }
        }
        corners += c.corners.len();
    }
    objects.push((last_start, total));

    // For each `v`, the vertex numbered first for it and its object; the other vertices with
    // the same `v` (another `vt` or `vn`) in a map.
    let mut first: Vec<(u32, u32)> = vec![(u32::MAX, 0); total.positions];
    let mut others: HashMap<(u32, [u32; 3]), u32, BuildHasherDefault<KeyHasher>> =
        HashMap::default();
    let mut vertices: Vec<[u32; 3]> = Vec::new();
    let mut indices: Vec<u32> = Vec::with_capacity(corners);
    let mut normals = true;
    let mut uvs_until = None;
    let (mut object, mut object_start) = (0, 0);
    let (mut object_normals, mut object_uvs) = (true, true);
    let keys = chunks.iter().flat_map(|c| &c.corners);
    for (at, &key) in keys.enumerate() {
        while objects.get(object + 1).is_some_and(|o| o.0 == at) {
            normals &= object_normals;
            if !object_uvs && uvs_until.is_none() {
                uvs_until = Some(object_start);
            }
            object += 1;
            object_start = vertices.len();
            (object_normals, object_uvs) = (true, true);
        }
        let bound = objects[object].1;
        let [v, vt, vn] = key;
        if v as usize >= bound.positions {
            let n = bound.positions;
            return Err((at, format!("face vertex index out of range ({n} vertices)")));
        }
        let (owner, found) = first[v as usize];
        let existing = if owner != object as u32 {
            None
        } else if vertices[found as usize] == key {
            Some(found)
        } else {
            others.get(&(owner, key)).copied()
        };
        let vertex = match existing {
            Some(i) => i,
            None => {
                let (nt, nn) = (bound.texcoords, bound.normals);
                if nt > 0 && vt != MISSING && vt as usize >= nt {
                    let e = format!("texture coordinate index out of range ({nt} coordinates)");
                    return Err((at, e));
                }
                if nn > 0 && vn != MISSING && vn as usize >= nn {
                    return Err((at, format!("normal index out of range ({nn} normals)")));
                }
                object_normals &= nn > 0 && vn != MISSING;
                object_uvs &= nt > 0 && vt != MISSING;
                let i = vertices.len() as u32;
                vertices.push(key);
                if owner == object as u32 {
                    others.insert((owner, key), i);
                } else {
                    first[v as usize] = (object as u32, i);
                }
                i
            }
        };
        indices.push(vertex);
    }
    normals &= object_normals;
    if !object_uvs && uvs_until.is_none() {
        uvs_until = Some(object_start);
    }
    let triangles = indices
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .collect();
    Ok(Numbered {
        uvs_until: uvs_until.unwrap_or(vertices.len()),
        vertices,
        triangles,
        normals,
    })
}

/// Looks up the vertex data of the numbered vertices.
fn gather(bytes: &[u8], chunks: &[Chunk], numbered: Numbered) -> Result<MeshData, String> {
    if numbered.triangles.is_empty() {
        return Err("cannot read OBJ: the file has no faces".into());
    }
    let positions: Vec<Vec3> = chunks.iter().flat_map(|c| &c.positions).copied().collect();
    let positions: Vec<Vec3> = numbered
        .vertices
        .par_iter()
        .map(|k| positions[k[0] as usize])
        .collect();
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        let line = line_of_statement(bytes, "v", numbered.vertices[i][0] as usize);
        let p = positions[i];
        return Err(format!(
            "cannot read OBJ: line {line}: non-finite vertex {p}"
        ));
    }
    let normals = numbered.normals.then(|| {
        let normals: Vec<Vec3> = chunks.iter().flat_map(|c| &c.normals).copied().collect();
        numbered
            .vertices
            .par_iter()
            .map(|k| normals[k[2] as usize].normalize_or_zero())
            .collect()
    });
    let texcoords: Vec<Vec2> = chunks.iter().flat_map(|c| &c.texcoords).copied().collect();
    let uv_of = |k: &[u32; 3]| texcoords[k[1] as usize];
    if let Some(k) = numbered.vertices[..numbered.uvs_until]
        .iter()
        .find(|k| !uv_of(k).is_finite())
    {
        let (line, uv) = (line_of_statement(bytes, "vt", k[1] as usize), uv_of(k));
        return Err(format!(
            "cannot read OBJ: line {line}: non-finite texture coordinate {uv}"
        ));
    }
    let uvs = (numbered.uvs_until == numbered.vertices.len())
        .then(|| numbered.vertices.par_iter().map(uv_of).collect());
    Ok(MeshData {
        positions,
        normals,
        uvs,
        uvs1: None,
        triangles: numbered.triangles,
    })
}

/// The line (from 1) of the `nth` (from 0) statement `keyword` of the file.
fn line_of_statement(bytes: &[u8], keyword: &str, nth: usize) -> usize {
    let text = String::from_utf8_lossy(bytes);
    let mut left = nth;
    for (i, l) in text.split('\n').enumerate() {
        if l.split_whitespace().next() == Some(keyword) {
            if left == 0 {
                return i + 1;
            }
            left -= 1;
        }
    }
    0
}

/// The line (from 1) of the face that made corner `corner` of the file.
fn line_of_corner(bytes: &[u8], bounds: &[usize], chunks: &[Chunk], corner: usize) -> usize {
    let mut left = corner;
    let mut k = 0;
    while k + 1 < chunks.len() && left >= chunks[k].corners.len() {
        left -= chunks[k].corners.len();
        k += 1;
    }
    let start = bounds[k];
    let text = String::from_utf8_lossy(&bytes[start..bounds[k + 1]]);
    let mut line = 1 + bytes[..start].iter().filter(|&&b| b == b'\n').count();
    for l in text.split('\n') {
        let mut words = l.split_whitespace();
        if let Some("f" | "l") = words.next() {
            let n = words.count();
            let made = 3 * n.saturating_sub(2).max(1);
            if left < made {
                return line;
            }
            left -= made;
        }
        line += 1;
    }
    line
}
