//! The bytes behind a glTF file: the `.glb` container, data URIs and external buffer files, each
//! source held once and all of them bounded by [`MAX_BUFFER_BYTES`] before they are allocated.

use std::collections::HashMap;
use std::ops::Range;
use std::sync::Arc;

use super::data::{GltfImage, SharedBytes};

/// Most bytes the buffers of one file may hold: its `.glb` binary chunk, its decoded data URIs
/// and its external buffer files, each source counted once however many buffers or images name
/// it (the file itself is bounded by the asset reader).
pub const MAX_BUFFER_BYTES: u64 = 1 << 30;

/// The file's buffers, each source read once and counted against `max_bytes`: the binary
/// chunk (for buffer 0 only, as the spec says), data URIs and external files.
pub(super) fn read_buffers(
    doc: &gltf::Document,
    file: &SharedBytes,
    blob: Option<Range<usize>>,
    max_bytes: u64,
    mut load_buffer: impl FnMut(&str, u64) -> Result<Vec<u8>, String>,
) -> Result<(Vec<SharedBytes>, u64), String> {
    let mut left = max_bytes;
    let take = |i: usize, n: usize, left: &mut u64| {
        *left = left.checked_sub(n as u64).ok_or_else(|| {
            format!("buffer {i}: the file's buffers hold more than {max_bytes} bytes")
        })?;
        Ok::<(), String>(())
    };
    let mut files: HashMap<String, SharedBytes> = HashMap::new();
    let mut buffers = Vec::new();
    for buffer in doc.buffers() {
        let i = buffer.index();
        let data = match buffer.source() {
            gltf::buffer::Source::Bin if i > 0 => {
                return Err(format!(
                    "buffer {i}: only buffer 0 may use the .glb's binary chunk"
                ));
            }
            gltf::buffer::Source::Bin => {
                let range = blob
                    .clone()
                    .ok_or_else(|| format!("buffer {i}: no binary chunk"))?;
                take(i, range.len(), &mut left)?;
                file.slice(range)
                    .ok_or("the binary chunk is outside the file")?
            }
            gltf::buffer::Source::Uri(uri) => match decode_data_uri(uri) {
                // Decoded before it is counted: it is smaller than its text, which the file holds.
                Some(r) => {
                    let (bytes, _) = r.map_err(|e| format!("buffer {i}: {e}"))?;
                    take(i, bytes.len(), &mut left)?;
                    SharedBytes::whole(Arc::new(bytes))
                }
                None => {
                    let rel = relative_uri(uri).map_err(|e| format!("buffer {i}: {e}"))?;
                    match files.get(&rel) {
                        Some(shared) => shared.clone(),
                        None => {
                            let bytes = load_buffer(&rel, left)
                                .map_err(|e| format!("buffer {i} ({rel}): {e}"))?;
                            take(i, bytes.len(), &mut left)?;
                            let shared = SharedBytes::whole(Arc::new(bytes));
                            files.insert(rel, shared.clone());
                            shared
                        }
                    }
                }
            },
        };
        if data.len() < buffer.length() {
            return Err(format!(
                "buffer {i}: {} bytes, shorter than its byteLength {}",
                data.len(),
                buffer.length()
            ));
        }
        buffers.push(data);
    }
    Ok((buffers, max_bytes - left))
}

/// Splits a `.glb` into the ranges of its JSON chunk and of its binary chunk, if any.
pub(super) fn split_glb(bytes: &[u8]) -> Result<(Range<usize>, Option<Range<usize>>), String> {
    let word = |at: usize| -> Option<u32> {
        let b = bytes.get(at..at.checked_add(4)?)?;
        Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let truncated = || "truncated .glb".to_string();
    let version = word(4).ok_or_else(truncated)?;
    if version != 2 {
        return Err(format!(".glb version {version}, only 2 is read"));
    }
    let length = word(8).ok_or_else(truncated)? as usize;
    if length > bytes.len() {
        return Err(format!("truncated .glb: {} bytes of {length}", bytes.len()));
    }
    let chunk = |at: usize| -> Result<(u32, Range<usize>, usize), String> {
        let len = word(at).ok_or_else(truncated)? as usize;
        let kind = word(at + 4).ok_or_else(truncated)?;
        let start = at + 8;
        let end = start
            .checked_add(len)
            .filter(|&e| e <= length)
            .ok_or_else(truncated)?;
        Ok((kind, start..end, end.next_multiple_of(4)))
    };
    let (kind, json, next) = chunk(12)?;
    if kind != 0x4E4F_534A {
        return Err(".glb: the first chunk is not JSON".into());
    }
    let bin = if next + 8 <= length {
        let (kind, bin, _) = chunk(next)?;
        (kind == 0x004E_4942).then_some(bin)
    } else {
        None
    };
    Ok((json, bin))
}

/// Decodes a `data:` URI (base64 only): `None` if `uri` is not one, else its bytes and MIME type.
pub(super) fn decode_data_uri(uri: &str) -> Option<Result<(Vec<u8>, String), String>> {
    let rest = uri.strip_prefix("data:")?;
    Some((|| {
        let (head, data) = rest.split_once(',').ok_or("data URI without a comma")?;
        let mime = head
            .strip_suffix(";base64")
            .ok_or("data URI not in base64")?;
        Ok((base64(data)?, mime.to_owned()))
    })())
}

/// Decodes standard base64 (padding optional).
pub(super) fn base64(text: &str) -> Result<Vec<u8>, String> {
    let digit = |c: u8| -> Result<u32, String> {
        Ok(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            _ => return Err(format!("invalid base64 character {:?}", c as char)),
        }
        .into())
    };
    let text = text.trim_end_matches('=').as_bytes();
    let mut out = Vec::with_capacity(text.len() / 4 * 3 + 3);
    for group in text.chunks(4) {
        let mut n = 0u32;
        for (k, &c) in group.iter().enumerate() {
            n |= digit(c)? << (18 - 6 * k);
        }
        let bytes = n.to_be_bytes();
        match group.len() {
            1 => return Err("truncated base64".into()),
            len => out.extend_from_slice(&bytes[1..len]),
        }
    }
    Ok(out)
}

/// A URI of an external buffer or image as a relative path below the glTF file's directory:
/// percent-decoded; absolute paths, other schemes, backslashes and `..` components are errors.
pub fn relative_uri(uri: &str) -> Result<String, String> {
    let mut bytes = Vec::with_capacity(uri.len());
    let mut it = uri.bytes();
    while let Some(b) = it.next() {
        if b == b'%' {
            let hex = [it.next(), it.next()];
            let v = match hex {
                [Some(h), Some(l)] => std::str::from_utf8(&[h, l])
                    .ok()
                    .and_then(|s| u8::from_str_radix(s, 16).ok()),
                _ => None,
            };
            bytes.push(v.ok_or_else(|| format!("bad percent escape in URI {uri:?}"))?);
        } else {
            bytes.push(b);
        }
    }
    let path = String::from_utf8(bytes).map_err(|_| format!("URI {uri:?} is not UTF-8"))?;
    let bad = path.is_empty()
        || path.starts_with('/')
        || path.contains('\\')
        || path.contains(':')
        || path.split('/').any(|c| c == "..");
    if bad {
        return Err(format!(
            "URI {uri:?} is not a relative path below the file's directory"
        ));
    }
    Ok(path)
}

/// Copies out, once per buffer, the span that its images' views cover (at most the buffer), and
/// points the images into it: images outlive the read, the rest of a buffer (mesh data, decoded
/// by then, and a `.glb`'s JSON) is not held with them.
pub(super) fn detach_images(images: &mut [GltfImage]) {
    let mut spans: HashMap<usize, Range<usize>> = HashMap::new();
    for image in images.iter() {
        if let GltfImage::Bytes { bytes, .. } = image {
            let span = spans
                .entry(Arc::as_ptr(&bytes.data) as usize)
                .or_insert(bytes.range.clone());
            *span = span.start.min(bytes.range.start)..span.end.max(bytes.range.end);
        }
    }
    let mut copies: HashMap<usize, SharedBytes> = HashMap::new();
    for image in images.iter_mut() {
        if let GltfImage::Bytes { bytes, .. } = image {
            let id = Arc::as_ptr(&bytes.data) as usize;
            let span = spans[&id].clone();
            if span.len() == bytes.data.len() {
                continue;
            }
            let copy = copies
                .entry(id)
                .or_insert_with(|| SharedBytes::whole(Arc::new(bytes.data[span.clone()].to_vec())));
            let start = bytes.range.start - span.start;
            *bytes = SharedBytes {
                data: copy.data.clone(),
                range: start..start + bytes.range.len(),
            };
        }
    }
}
