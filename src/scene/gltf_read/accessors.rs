//! Accessors read into vertices and indices: buffer views checked against their buffers, strides,
//! normalised integers and sparse substitution, each bounded by the data it reads.

use glam::{Vec2, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;

use super::data::{MAX_TRIANGLES, MAX_VERTICES, MAX_ZERO_FILLED, SharedBytes};
use crate::model::MeshData;

/// The bytes of a buffer view, checked against its buffer.
pub(super) fn view_bytes<'b>(
    view: &gltf::buffer::View,
    buffers: &'b [SharedBytes],
) -> Result<&'b [u8], String> {
    let buffer = buffers.get(view.buffer().index()).ok_or("missing buffer")?;
    view.offset()
        .checked_add(view.length())
        .and_then(|end| buffer.get(view.offset()..end))
        .ok_or_else(|| format!("buffer view {} outside its buffer", view.index()))
}

/// The bytes of a buffer view, shared with its buffer.
pub(super) fn view_shared(
    view: &gltf::buffer::View,
    buffers: &[SharedBytes],
) -> Result<SharedBytes, String> {
    let buffer = buffers.get(view.buffer().index()).ok_or("missing buffer")?;
    view.offset()
        .checked_add(view.length())
        .and_then(|end| buffer.slice(view.offset()..end))
        .ok_or_else(|| format!("buffer view {} outside its buffer", view.index()))
}

/// The distance between elements of `size` bytes in `view`: its `byteStride`, which may not be
/// smaller than an element (elements would overlap), or the size when it has none.
pub(super) fn stride(view: &gltf::buffer::View, size: usize) -> Result<usize, String> {
    match view.stride() {
        None => Ok(size),
        Some(stride) if stride >= size => Ok(stride),
        Some(stride) => Err(format!(
            "buffer view {}: byteStride {stride} is smaller than an element ({size} bytes)",
            view.index()
        )),
    }
}

/// What is left of the file's vertex and triangle allowance.
pub(super) struct Budget {
    pub(super) vertices: usize,
    pub(super) triangles: usize,
}

/// The size in bytes of one component.
pub(super) fn component_size(t: DataType) -> usize {
    match t {
        DataType::I8 | DataType::U8 => 1,
        DataType::I16 | DataType::U16 => 2,
        DataType::U32 | DataType::F32 => 4,
    }
}

/// One component at the start of `b` as a float (normalised integers mapped to [0, 1] or
/// [-1, 1] as the spec says).
pub(super) fn component(b: &[u8], t: DataType, normalized: bool) -> f32 {
    let n = |v: f32, max: f32| {
        if normalized { (v / max).max(-1.0) } else { v }
    };
    match t {
        DataType::I8 => n(f32::from(b[0] as i8), 127.0),
        DataType::U8 => n(f32::from(b[0]), 255.0),
        DataType::I16 => n(f32::from(i16::from_le_bytes([b[0], b[1]])), 32767.0),
        DataType::U16 => n(f32::from(u16::from_le_bytes([b[0], b[1]])), 65535.0),
        DataType::U32 => n(
            u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
            4_294_967_295.0,
        ),
        DataType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
    }
}

/// An unsigned integer component at the start of `b` (`t` is `U8`, `U16` or `U32`).
pub(super) fn uint(b: &[u8], t: DataType) -> u32 {
    match t {
        DataType::U8 => u32::from(b[0]),
        DataType::U16 => u32::from(u16::from_le_bytes([b[0], b[1]])),
        _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
    }
}

/// A strided run of `count` elements of `size` bytes starting `offset` bytes into a view.
pub(super) fn elements(
    bytes: &[u8],
    offset: usize,
    stride: usize,
    size: usize,
    count: usize,
) -> Option<impl Iterator<Item = &[u8]>> {
    if count > 0 {
        let last = (count - 1).checked_mul(stride)?.checked_add(offset)?;
        bytes.get(last..last.checked_add(size)?)?;
    }
    Some((0..count).map(move |i| &bytes[offset + i * stride..offset + i * stride + size]))
}

/// The sparse substitutions of accessor `acc` (of `count` elements of `size` bytes): each
/// target element's index, checked to be below `count`, with its new value's bytes. Empty for an
/// accessor without sparse storage.
pub(super) fn sparse_values<'b>(
    acc: &gltf::Accessor,
    count: usize,
    size: usize,
    buffers: &'b [SharedBytes],
) -> Result<Vec<(usize, &'b [u8])>, String> {
    let i = acc.index();
    let Some(sparse) = acc.sparse() else {
        return Ok(Vec::new());
    };
    let n = sparse.count();
    let idx = sparse.indices();
    let it = match idx.index_type() {
        gltf::accessor::sparse::IndexType::U8 => DataType::U8,
        gltf::accessor::sparse::IndexType::U16 => DataType::U16,
        gltf::accessor::sparse::IndexType::U32 => DataType::U32,
    };
    let isize = component_size(it);
    let ibytes =
        view_bytes(&idx.view(), buffers).map_err(|e| format!("accessor {i} sparse: {e}"))?;
    let vals = sparse.values();
    let vbytes =
        view_bytes(&vals.view(), buffers).map_err(|e| format!("accessor {i} sparse: {e}"))?;
    let (Some(indices), Some(values)) = (
        elements(ibytes, idx.offset(), isize, isize, n),
        elements(vbytes, vals.offset(), size, size, n),
    ) else {
        return Err(format!(
            "accessor {i}: sparse data outside its buffer views"
        ));
    };
    indices
        .zip(values)
        .map(|(ib, vb)| {
            let target = uint(ib, it) as usize;
            if target < count {
                Ok((target, vb))
            } else {
                Err(format!(
                    "accessor {i}: sparse index {target} out of range (count {count})"
                ))
            }
        })
        .collect()
}

/// Reads accessor `acc` as `count × dims` floats, sparse substitution applied.
pub(super) fn read_floats(
    acc: &gltf::Accessor,
    dims: usize,
    buffers: &[SharedBytes],
) -> Result<Vec<f32>, String> {
    let i = acc.index();
    if acc.dimensions().multiplicity() != dims {
        return Err(format!(
            "accessor {i}: {:?}, expected {dims} components",
            acc.dimensions()
        ));
    }
    let t = acc.data_type();
    let csize = component_size(t);
    let size = csize * dims;
    let count = acc.count();
    let mut out = Vec::new();
    let read_elem = |e: &[u8], out: &mut Vec<f32>| {
        for k in 0..dims {
            out.push(component(&e[k * csize..], t, acc.normalized()));
        }
    };
    match acc.view() {
        Some(view) => {
            let bytes = view_bytes(&view, buffers).map_err(|e| format!("accessor {i}: {e}"))?;
            let stride = stride(&view, size).map_err(|e| format!("accessor {i}: {e}"))?;
            let items = elements(bytes, acc.offset(), stride, size, count).ok_or_else(|| {
                format!(
                    "accessor {i}: {count} elements outside buffer view {}",
                    view.index()
                )
            })?;
            out.reserve_exact(count * dims);
            for e in items {
                read_elem(e, &mut out);
            }
        }
        None => {
            if count > MAX_ZERO_FILLED {
                return Err(format!(
                    "accessor {i}: {count} elements without a buffer view, more than {MAX_ZERO_FILLED}"
                ));
            }
            out.resize(count * dims, 0.0);
        }
    }
    for (target, vb) in sparse_values(acc, count, size, buffers)? {
        let mut v = Vec::with_capacity(dims);
        read_elem(vb, &mut v);
        out[target * dims..(target + 1) * dims].copy_from_slice(&v);
    }
    Ok(out)
}

/// Reads an index accessor (unsigned integers, not normalised).
pub(super) fn read_indices(
    acc: &gltf::Accessor,
    buffers: &[SharedBytes],
) -> Result<Vec<u32>, String> {
    let i = acc.index();
    if !matches!(
        acc.data_type(),
        DataType::U8 | DataType::U16 | DataType::U32
    ) || acc.dimensions() != Dimensions::Scalar
        || acc.normalized()
    {
        return Err(format!(
            "accessor {i}: indices must be unsigned integer scalars"
        ));
    }
    // u32 values above 2^24 are not exact in f32: read integers directly.
    let t = acc.data_type();
    let size = component_size(t);
    let int = |b: &[u8]| uint(b, t);
    let count = acc.count();
    let mut out = match acc.view() {
        Some(view) => {
            let bytes = view_bytes(&view, buffers).map_err(|e| format!("accessor {i}: {e}"))?;
            let stride = stride(&view, size).map_err(|e| format!("accessor {i}: {e}"))?;
            elements(bytes, acc.offset(), stride, size, count)
                .ok_or_else(|| {
                    format!(
                        "accessor {i}: {count} elements outside buffer view {}",
                        view.index()
                    )
                })?
                .map(int)
                .collect()
        }
        None if count <= MAX_ZERO_FILLED => vec![0; count],
        None => {
            return Err(format!(
                "accessor {i}: {count} elements without a buffer view, more than {MAX_ZERO_FILLED}"
            ));
        }
    };
    for (target, vb) in sparse_values(acc, count, size, buffers)? {
        out[target] = int(vb);
    }
    Ok(out)
}

/// Reads one triangle primitive into a [`MeshData`], with texture coordinate sets `sets` (the
/// first as `uvs`, the second, if any, as `uvs1`; `TEXCOORD_0` when empty).
pub(super) fn read_primitive(
    prim: &gltf::Primitive,
    sets: &[u32],
    buffers: &[SharedBytes],
    budget: &mut Budget,
) -> Result<MeshData, String> {
    let pos = prim.get(&gltf::Semantic::Positions).ok_or("no POSITION")?;
    let n = pos.count();
    if n > budget.vertices {
        return Err(format!(
            "{n} vertices; at most {MAX_VERTICES} are read per file"
        ));
    }
    budget.vertices -= n;
    let positions: Vec<Vec3> = read_floats(&pos, 3, buffers)?
        .chunks_exact(3)
        .map(Vec3::from_slice)
        .collect();
    if let Some(k) = positions.iter().position(|p| !p.is_finite()) {
        return Err(format!("accessor {}: non-finite position {k}", pos.index()));
    }
    let normals = match prim.get(&gltf::Semantic::Normals) {
        None => None,
        Some(acc) if acc.count() == n => Some(
            read_floats(&acc, 3, buffers)?
                .chunks_exact(3)
                .map(|c| {
                    let v = Vec3::from_slice(c);
                    if v.is_finite() {
                        v.normalize_or_zero()
                    } else {
                        Vec3::ZERO
                    }
                })
                .collect(),
        ),
        Some(acc) => {
            return Err(format!(
                "accessor {}: {} normals for {n} positions",
                acc.index(),
                acc.count()
            ));
        }
    };
    let uvs = read_uvs(prim, sets.first().copied().unwrap_or(0), n, buffers)?;
    let uvs1 = match sets.get(1) {
        Some(&set) => read_uvs(prim, set, n, buffers)?,
        None => None,
    };
    let indices = match prim.indices() {
        Some(acc) => {
            let idx = read_indices(&acc, buffers)?;
            if let Some(&bad) = idx.iter().find(|&&v| v as usize >= n) {
                return Err(format!(
                    "accessor {}: index {bad} out of range ({n} vertices)",
                    acc.index()
                ));
            }
            idx
        }
        None => (0..n as u32).collect(),
    };
    let triangles = assemble(prim.mode(), &indices);
    if triangles.len() > budget.triangles {
        return Err(format!("more than {MAX_TRIANGLES} triangles in the file"));
    }
    budget.triangles -= triangles.len();
    Ok(MeshData {
        positions,
        normals,
        uvs,
        uvs1,
        triangles,
    })
}

/// Texture coordinate set `TEXCOORD_<set>` of a primitive of `n` vertices, stored as
/// `(u, 1 − v)`; `None` when the primitive has no such set.
fn read_uvs(
    prim: &gltf::Primitive,
    set: u32,
    n: usize,
    buffers: &[SharedBytes],
) -> Result<Option<Vec<Vec2>>, String> {
    match prim.get(&gltf::Semantic::TexCoords(set)) {
        None => Ok(None),
        Some(acc) if acc.count() == n => {
            // glTF's v runs down the image from its top row, rondo's up from the bottom row.
            let uv: Vec<Vec2> = read_floats(&acc, 2, buffers)?
                .chunks_exact(2)
                .map(|t| Vec2::new(t[0], 1.0 - t[1]))
                .collect();
            if let Some(k) = uv.iter().position(|t| !t.is_finite()) {
                return Err(format!(
                    "accessor {}: non-finite texture coordinate {k}",
                    acc.index()
                ));
            }
            Ok(Some(uv))
        }
        Some(acc) => Err(format!(
            "accessor {}: {} texture coordinates for {n} positions",
            acc.index(),
            acc.count()
        )),
    }
}

/// Triangles of a triangle list, strip or fan, each in the winding the spec gives (strips
/// alternate so that every triangle keeps the first one's orientation). Degenerate triangles
/// with repeated indices are dropped.
pub fn assemble(mode: Mode, idx: &[u32]) -> Vec<[u32; 3]> {
    let tris: Vec<[u32; 3]> = match mode {
        Mode::TriangleStrip => (0..idx.len().saturating_sub(2))
            .map(|i| {
                if i % 2 == 0 {
                    [idx[i], idx[i + 1], idx[i + 2]]
                } else {
                    [idx[i + 1], idx[i], idx[i + 2]]
                }
            })
            .collect(),
        Mode::TriangleFan => (1..idx.len().saturating_sub(1))
            .map(|i| [idx[0], idx[i], idx[i + 1]])
            .collect(),
        _ => idx.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
    };
    tris.into_iter()
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .collect()
}
