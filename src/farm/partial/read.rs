//! Reading partials: the metadata, checked before anything is allocated for the pixels, and
//! the sums, decoded block by block.

use std::fs::File;
use std::io::BufReader;
use std::path::Path;

use exr::block::UncompressedBlock;
use exr::block::chunk::Chunk;
use exr::block::reader::ChunksReader;
use exr::meta::BlockDescription;
use exr::meta::attribute::{AttributeValue, ChannelList, LevelMode, SampleType, Text};
use exr::meta::header::Header;
use rayon::prelude::*;

use super::identity::check_settings;
use super::meta::{
    FORMAT, FORMAT_1, FORMAT_2, LAYERS, MAX_SCENE_NAME, PartialError, PartialMeta, SUM_CHANNELS,
    Sums, error,
};
use super::ranges::{normalize, parse_range};
use crate::film::{ALBEDO_SHIFT, NORMAL_SHIFT, Pixel};
use crate::scene::bounded_read::open_regular;
use crate::scene::format::{MAX_SPP, SettingsDesc};

fn open(path: &Path) -> Result<exr::block::reader::Reader<BufReader<File>>, PartialError> {
    let (file, _) = open_regular(path).map_err(|e| error(path, format!("cannot open: {e}")))?;
    exr::block::read(BufReader::new(file), false)
        .map_err(|e| error(path, format!("not an OpenEXR file: {e}")))
}

/// The metadata of the partial at `path`, checked: its layers with the sum channels, and every
/// rondo attribute present and well-formed.
pub fn read_meta(path: &Path) -> Result<PartialMeta, PartialError> {
    meta_of(path, open(path)?.headers())
}

fn meta_of(path: &Path, headers: &[Header]) -> Result<PartialMeta, PartialError> {
    let Some(header) = headers.first() else {
        return Err(error(path, "a partial has at least one layer"));
    };
    let attr = |name: &str| -> Result<String, PartialError> {
        match header.own_attributes.other.get(&Text::from(name)) {
            Some(AttributeValue::Text(t)) => Ok(t.to_string()),
            _ => Err(error(
                path,
                format!(
                    "not a rondo partial (no {name} attribute; make one with `rondo render --samples A..B`)"
                ),
            )),
        }
    };
    let format = attr("rondo.format")?;
    if format == FORMAT_1 {
        return Err(error(
            path,
            format!(
                "partial format {FORMAT_1:?} is an older rondo's, which did not record the sampler and the renderer's options, so it cannot be checked: render it again"
            ),
        ));
    }
    let features = match format.as_str() {
        FORMAT => true,
        FORMAT_2 => false,
        _ => {
            return Err(error(
                path,
                format!(
                    "partial format {}, this rondo reads {FORMAT:?} and {FORMAT_2:?}",
                    shown(&format)
                ),
            ));
        }
    };
    // The colour alone, or the colour and the feature buffers, in this order and by name.
    let names: &[&str] = if features { &LAYERS } else { &[] };
    let layers = names.len().max(1);
    if headers.len() != layers {
        let expected = if features {
            format!("{layers} layers ({})", LAYERS.join(", "))
        } else {
            "one layer".into()
        };
        return Err(error(
            path,
            format!(
                "a {format} partial has {expected}, this file has {}",
                headers.len()
            ),
        ));
    }
    for (i, h) in headers.iter().enumerate() {
        check_layer(path, h, names.get(i).copied())?;
    }
    let bad = |what: &str, v: &str, why: &str| {
        error(path, format!("bad {what} attribute {}: {why}", shown(v)))
    };
    let bits = attr("rondo.fraction_bits")?;
    let shift = bits
        .parse::<i32>()
        .ok()
        .filter(|s| SHIFTS.contains(s))
        .ok_or_else(|| {
            bad(
                "rondo.fraction_bits",
                &bits,
                &format!("expected a whole number in {SHIFTS:?}"),
            )
        })?;
    let settings = attr("rondo.settings")?;
    let max_depth =
        check_settings(&settings).map_err(|why| bad("rondo.settings", &settings, &why))?;
    let samples = attr("rondo.samples")?;
    if samples.len() > MAX_SAMPLES_TEXT || !samples.bytes().all(|b| b"0123456789.,".contains(&b)) {
        return Err(bad(
            "rondo.samples",
            &samples,
            &format!("ranges A..B joined by commas, at most {MAX_SAMPLES_TEXT} characters"),
        ));
    }
    if samples.is_empty() {
        return Err(bad(
            "rondo.samples",
            &samples,
            "a partial holds at least one sample range",
        ));
    }
    let ranges = samples
        .split(',')
        .map(parse_range)
        .collect::<Result<Vec<_>, _>>()
        .map_err(|why| bad("rondo.samples", &samples, &why))?;
    let ranges = normalize(ranges);
    if ranges.windows(2).any(|w| w[0].end > w[1].start) {
        return Err(bad("rondo.samples", &samples, "the ranges overlap"));
    }
    let end = ranges.last().map_or(0, |r| r.end);
    // The limits a render is held to, checked before anything is allocated for the pixels: a
    // partial is a file anyone may have written.
    let size = header.layer_size;
    let side = |v: usize| u32::try_from(v).unwrap_or(u32::MAX);
    let (width, height) = (side(size.width()), side(size.height()));
    let limits = SettingsDesc {
        width,
        height,
        spp: end,
        max_depth,
        ..SettingsDesc::default()
    };
    limits.validate().map_err(|why| {
        error(
            path,
            format!(
                "{}x{} pixels, samples up to {end}: beyond what rondo renders ({why})",
                size.width(),
                size.height()
            ),
        )
    })?;
    let seed = attr("rondo.seed")?;
    let seed = seed
        .parse()
        .map_err(|_| bad("rondo.seed", &seed, "not a whole number below 2^64"))?;
    let hash = attr("rondo.hash")?;
    let hash = Some(&hash)
        .filter(|h| h.len() == 16 && h.bytes().all(|b| b.is_ascii_hexdigit()))
        .and_then(|h| u64::from_str_radix(h, 16).ok())
        .ok_or_else(|| bad("rondo.hash", &hash, "not 16 hexadecimal digits"))?;
    let scene = match header.own_attributes.other.get(&Text::from("rondo.scene")) {
        None => String::new(),
        Some(AttributeValue::Text(t))
            if t.as_slice().len() <= MAX_SCENE_NAME
                && t.as_slice()
                    .iter()
                    .all(|b| *b == b' ' || b.is_ascii_graphic()) =>
        {
            t.to_string()
        }
        Some(_) => {
            return Err(error(
                path,
                format!("bad rondo.scene attribute: at most {MAX_SCENE_NAME} printable characters"),
            ));
        }
    };
    // The feature layers: the colour's size, each in its own fixed point, as their
    // `rondo.fraction_bits` say: the albedo in ALBEDO_SHIFT's (or in the colour's, as partials
    // were written before the albedo had a scale of its own), the normal in NORMAL_SHIFT's.
    let mut albedo_shift = ALBEDO_SHIFT;
    for ((h, name), expected) in headers
        .iter()
        .zip(names)
        .skip(1)
        .zip([ALBEDO_SHIFT, NORMAL_SHIFT])
    {
        if h.layer_size != size {
            return Err(error(
                path,
                format!(
                    "layer {name} is {}x{} pixels, the colour {width}x{height}",
                    h.layer_size.width(),
                    h.layer_size.height()
                ),
            ));
        }
        let bits = match h
            .own_attributes
            .other
            .get(&Text::from("rondo.fraction_bits"))
        {
            Some(AttributeValue::Text(t)) => t.to_string(),
            _ => String::new(),
        };
        if *name == LAYERS[1] && bits == shift.to_string() {
            albedo_shift = shift;
        } else if bits != expected.to_string() {
            let colours = if *name == LAYERS[1] {
                format!(" (or the colour's {shift:?})")
            } else {
                String::new()
            };
            return Err(error(
                path,
                format!(
                    "layer {name}: rondo.fraction_bits {}, expected {expected:?}{colours}",
                    shown(&bits)
                ),
            ));
        }
    }
    Ok(PartialMeta {
        width,
        height,
        seed,
        hash,
        ranges,
        scene,
        shift,
        settings,
        features,
        albedo_shift,
    })
}

/// Checks one layer of a partial: a flat image of one resolution level, named `name` if given,
/// with exactly the channels `R`, `G`, `B` and the sums (u32). Anything else would be decoded
/// for nothing (a block's memory grows with the channel count) or means another kind of file.
fn check_layer(path: &Path, header: &Header, name: Option<&str>) -> Result<(), PartialError> {
    let layer = name.map(|n| format!("layer {n}: ")).unwrap_or_default();
    if let Some(name) = name
        && header
            .own_attributes
            .layer_name
            .as_ref()
            .map(Text::to_string)
            .as_deref()
            != Some(name)
    {
        let found = header
            .own_attributes
            .layer_name
            .as_ref()
            .map(Text::to_string);
        return Err(error(
            path,
            format!(
                "expected the layer {name:?} where {} is",
                found.map_or("an unnamed layer".into(), |f| shown(&f))
            ),
        ));
    }
    let one_level = match header.blocks {
        BlockDescription::ScanLines => true,
        BlockDescription::Tiles(t) => t.level_mode == LevelMode::Singular,
    };
    if header.deep || !one_level {
        return Err(error(
            path,
            format!(
                "{layer}a partial is a flat image of one resolution level, not deep data or mipmaps"
            ),
        ));
    }
    for c in &header.channels.list {
        let name = c.name.to_string();
        if !["R", "G", "B"].contains(&name.as_str())
            && !SUM_CHANNELS.iter().flatten().any(|n| **n == name)
        {
            return Err(error(
                path,
                format!("{layer}a partial has no channel {}", shown(&name)),
            ));
        }
    }
    for name in SUM_CHANNELS.iter().flatten() {
        let found = header
            .channels
            .list
            .iter()
            .any(|c| c.name == **name && c.sample_type == SampleType::U32);
        if !found {
            return Err(error(
                path,
                format!("{layer}partial has no u32 channel {name}"),
            ));
        }
    }
    Ok(())
}

/// `text` for an error message: quoted, and cut after 64 characters (an attribute may be long).
fn shown(text: &str) -> String {
    const MAX: usize = 64;
    match text.char_indices().nth(MAX) {
        Some((at, _)) => format!("{:?}…", &text[..at]),
        None => format!("{text:?}"),
    }
}

/// Longest `rondo.samples` a render writes: sorted ranges that do not touch, so at most one per
/// two samples below [`MAX_SPP`], each two numbers of at most its digits, `..` and a comma.
const MAX_SAMPLES_TEXT: usize = MAX_SPP as usize / 2 * (2 * digits(MAX_SPP) + 3);

/// The decimal digits of `n`.
const fn digits(mut n: u32) -> usize {
    let mut d = 1;
    while n >= 10 {
        n /= 10;
        d += 1;
    }
    d
}

/// The fixed-point shifts [`crate::film::shift_for`] can give, for any finite radiance.
const SHIFTS: std::ops::RangeInclusive<i32> = -128..=200;

/// One layer of a partial being read: where its sums go, which sum word each of its channels
/// holds, and its grid of blocks with whether each was read.
struct Part<'a> {
    target: &'a mut [Pixel],
    channels: ChannelList,
    /// Per channel of the layer: the colour and word it holds, if a sum.
    roles: Vec<Option<(usize, usize)>>,
    /// A block's size: a tile, or a row of scanlines.
    block: (usize, usize),
    /// Blocks per row of the grid.
    columns: usize,
    /// Per cell of the grid, whether its block was read.
    seen: Vec<bool>,
}

/// Adds the sums of the partial at `path` into `sums` (the colour's and, if the partial carries
/// them, the feature buffers', which `sums` must hold exactly then). Returns the partial's
/// metadata. The file is decoded block by block (blocks in parallel), never held whole. Every
/// block of every layer (tile or scanlines) must be in the file exactly once (a crafted file
/// could repeat one, or leave one out, and silently brighten or darken the image); on an error,
/// `sums` holds part of the file.
pub fn add_partial(path: &Path, sums: &mut Sums) -> Result<PartialMeta, PartialError> {
    let reader = open(path)?;
    let meta = meta_of(path, reader.headers())?;
    let pixels = meta.pixels();
    if meta.features != sums.features.is_some() {
        return Err(error(
            path,
            if meta.features {
                "carries the feature buffers (albedo, normal), which the image it is added to lacks"
            } else {
                "has no feature buffers (albedo, normal), which the image it is added to has"
            },
        ));
    }
    let Sums { colour, features } = sums;
    let targets = std::iter::once(&mut colour[..])
        .chain(
            features
                .iter_mut()
                .flat_map(|f| [&mut f.albedo[..], &mut f.normal[..]]),
        )
        .collect::<Vec<_>>();
    if targets.iter().any(|t| t.len() != pixels) {
        return Err(error(
            path,
            format!(
                "size {}x{} differs from the image's",
                meta.width, meta.height
            ),
        ));
    }
    let (width, height) = (meta.width as usize, meta.height as usize);
    // A render clamps each sample to 2^62 in its fixed point, so no sum it writes is larger.
    let limit = u128::from(meta.count()) << 62;
    // The layers are as many as the targets (checked by `meta_of`). Each grid has at most one
    // cell per pixel, so at most 2²⁶ (as the pixels are limited).
    let mut parts = Vec::with_capacity(targets.len());
    for (header, target) in reader.headers().iter().zip(targets) {
        let roles = header
            .channels
            .list
            .iter()
            .map(|c| {
                SUM_CHANNELS.iter().enumerate().find_map(|(colour, words)| {
                    words
                        .iter()
                        .position(|n| c.name == **n)
                        .map(|word| (colour, word))
                })
            })
            .collect();
        let block = match header.blocks {
            BlockDescription::ScanLines => (width, header.compression.scan_lines_per_block()),
            BlockDescription::Tiles(t) => (t.tile_size.width(), t.tile_size.height()),
        };
        if block.0 == 0 || block.1 == 0 {
            return Err(error(path, "blocks of no pixels"));
        }
        let columns = width.div_ceil(block.0);
        parts.push(Part {
            target,
            channels: header.channels.clone(),
            roles,
            block,
            columns,
            seen: vec![false; columns * height.div_ceil(block.1)],
        });
    }
    // Where an error is: the layer's name in a partial of several.
    let in_layer = |layer: usize| {
        if meta.features {
            format!(" of layer {}", LAYERS.get(layer).unwrap_or(&"?"))
        } else {
            String::new()
        }
    };
    let fail = |e: exr::error::Error| error(path, format!("cannot decode: {e}"));
    let mut chunks = reader.all_chunks(false).map_err(fail)?;
    let meta_data = chunks.meta_data().clone();
    loop {
        let batch: Vec<Chunk> = chunks
            .by_ref()
            .take(64)
            .collect::<Result<_, _>>()
            .map_err(fail)?;
        if batch.is_empty() {
            break;
        }
        let blocks: Vec<UncompressedBlock> = batch
            .into_par_iter()
            .map(|c| UncompressedBlock::decompress_chunk(c, &meta_data, false))
            .collect::<Result<_, _>>()
            .map_err(fail)?;
        for b in &blocks {
            let layer = b.index.layer;
            let part = parts.get_mut(layer).ok_or_else(|| {
                error(
                    path,
                    format!("a block of layer {layer}, which is not there"),
                )
            })?;
            // A block is one cell of its layer's grid (its every channel), clipped at the
            // image's edge.
            let block = part.block;
            let (x, y) = (b.index.pixel_position.x(), b.index.pixel_position.y());
            let size = (b.index.pixel_size.width(), b.index.pixel_size.height());
            let expected = (
                block.0.min(width.saturating_sub(x)),
                block.1.min(height.saturating_sub(y)),
            );
            if b.index.level != exr::math::Vec2(0, 0)
                || x % block.0 != 0
                || y % block.1 != 0
                || size != expected
                || x >= width
                || y >= height
            {
                return Err(error(
                    path,
                    format!("a block{} lies outside the image's grid", in_layer(layer)),
                ));
            }
            let cell = &mut part.seen[y / block.1 * part.columns + x / block.0];
            if *cell {
                return Err(error(
                    path,
                    format!(
                        "the block at row {y}, column {x}{} appears twice",
                        in_layer(layer)
                    ),
                ));
            }
            *cell = true;
            // The block's sums, put together from their words, checked, then added.
            let mut local = vec![Pixel::ZERO; size.0 * size.1];
            for line in b.lines(&part.channels) {
                let Some(&Some((colour, word))) = part.roles.get(line.location.channel) else {
                    continue;
                };
                let (lx, ly) = (line.location.position.x(), line.location.position.y());
                let pixels = lx
                    .checked_sub(x)
                    .zip(ly.checked_sub(y))
                    .map(|(dx, dy)| dy * size.0 + dx)
                    .and_then(|start| local.get_mut(start..start + line.location.sample_count))
                    .ok_or_else(|| error(path, "a line lies outside its block"))?;
                // Samples are little-endian u32 (OpenEXR's byte order).
                let values = line.value.chunks_exact(4);
                if values.len() != pixels.len() {
                    return Err(error(path, "a line has the wrong length"));
                }
                for (pixel, bytes) in pixels.iter_mut().zip(values) {
                    let v = u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]);
                    let mut words = pixel.words(colour);
                    words[word] = v;
                    pixel.set_words(colour, words);
                }
            }
            for (i, pixel) in local.iter().enumerate() {
                let (px, py) = (x + i % size.0, y + i / size.0);
                if let Some(c) = (0..3).find(|&c| pixel.0[c].unsigned_abs() > limit) {
                    return Err(error(
                        path,
                        format!(
                            "the {} sum of pixel ({px}, {py}){} is {}, beyond what {} samples reach (at most 2^62 each)",
                            ["R", "G", "B"][c],
                            in_layer(layer),
                            pixel.0[c],
                            meta.count()
                        ),
                    ));
                }
                let target = &mut part.target[py * width + px];
                *target = target.checked_merge(pixel).ok_or_else(|| {
                    error(
                        path,
                        format!(
                            "pixel ({px}, {py}){}: its sums and those added before overflow {} bits",
                            in_layer(layer),
                            32 * Pixel::WORDS
                        ),
                    )
                })?;
            }
        }
    }
    for (layer, part) in parts.iter().enumerate() {
        if let Some(missing) = part.seen.iter().position(|cell| !cell) {
            let (y, x) = (
                missing / part.columns * part.block.1,
                missing % part.columns * part.block.0,
            );
            return Err(error(
                path,
                format!(
                    "the block at row {y}, column {x}{} is missing",
                    in_layer(layer)
                ),
            ));
        }
    }
    Ok(meta)
}

/// The checked metadata and the sums of the partial at `path`, read whole.
pub fn read_partial(path: &Path) -> Result<(PartialMeta, Sums), PartialError> {
    let meta = read_meta(path)?;
    let mut sums = Sums::zero(&meta);
    add_partial(path, &mut sums)?;
    Ok((meta, sums))
}
