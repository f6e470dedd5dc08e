//! Partial renders: the exact per-pixel sums of some sample ranges of a render, stored as an
//! OpenEXR file with rondo's metadata (format in `docs/partial-format.md`), and their merge.
//!
//! The sums are the film's fixed-point integers ([`crate::film::Pixel`]), so merging partials
//! adds integers: in any order the merged image is the one a single process rendering every
//! sample makes, bit for bit.

use std::fmt;
use std::fs::File;
use std::io::BufReader;
use std::ops::Range;
use std::path::{Path, PathBuf};

use exr::block::UncompressedBlock;
use exr::block::chunk::Chunk;
use exr::block::reader::ChunksReader;
use exr::meta::BlockDescription;
use exr::meta::attribute::{AttributeValue, LevelMode, Text};
use rayon::prelude::*;

use crate::film::{FixedPoint, OutputKind, Pixel, write_atomically, write_image};
use crate::scene::format::{Method, SettingsDesc};
use crate::shading::sampler::SamplerKind;

/// Value of the `rondo.format` attribute of a partial of this version of the format.
pub const FORMAT: &str = "rondo-partial-2";

/// The format before the sampler and the renderer's options were recorded (`rondo.settings`):
/// its partials cannot say whether they belong together, so they are refused with this reason.
const FORMAT_1: &str = "rondo-partial-1";

/// Longest `rondo.scene` attribute read (a file name).
const MAX_SCENE_NAME: usize = 255;

/// The channels of a partial besides `R`, `G`, `B` (the mean): per colour, the sum's words,
/// least significant first.
pub const SUM_CHANNELS: [[&str; Pixel::WORDS]; 3] = [
    ["sum.R.0", "sum.R.1", "sum.R.2"],
    ["sum.G.0", "sum.G.1", "sum.G.2"],
    ["sum.B.0", "sum.B.1", "sum.B.2"],
];

/// An error about partials, saying which file and what.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PartialError(pub String);

impl fmt::Display for PartialError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for PartialError {}

fn error(path: &Path, message: impl fmt::Display) -> PartialError {
    PartialError(format!("{}: {message}", path.display()))
}

/// What a partial says about itself.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PartialMeta {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// The render's seed.
    pub seed: u64,
    /// [`image_hash`] of the scene, its files and the settings.
    pub hash: u64,
    /// The sample ranges held, sorted, disjoint and not adjacent.
    pub ranges: Vec<Range<u32>>,
    /// The scene's file name (for people; not checked).
    pub scene: String,
    /// The film's fixed-point shift: sums are in units of 2⁻shift ([`crate::film::shift_for`]).
    pub shift: i32,
    /// Every other setting the pixels depend on, as [`image_settings`] writes them
    /// (`max_depth=8 method=mis sampler=sobol …`).
    pub settings: String,
}

impl PartialMeta {
    /// Samples per pixel held.
    pub fn count(&self) -> u64 {
        self.ranges.iter().map(|r| u64::from(r.end - r.start)).sum()
    }

    /// One past the last sample held (0 if none).
    pub fn end(&self) -> u32 {
        self.ranges.last().map_or(0, |r| r.end)
    }
}

/// 64-bit FNV-1a, a stable hash (unlike std's, whose algorithm may change).
struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
    fn bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
    fn field(&mut self, bytes: &[u8]) {
        self.bytes(&(bytes.len() as u64).to_le_bytes());
        self.bytes(bytes);
    }
}

/// How a renderer traces, beyond the scene's settings, where it changes an image's bits
/// (thread count and geometry layout never do, so they are not here).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tracing {
    /// Russian roulette on ([`crate::Renderer::set_roulette`]).
    pub roulette: bool,
    /// Meshes placed as instances ([`crate::Renderer::set_instancing`]).
    pub instancing: bool,
}

impl Default for Tracing {
    /// What `rondo render` does: roulette and instancing on.
    fn default() -> Self {
        Self {
            roulette: true,
            instancing: true,
        }
    }
}

/// The keys of [`image_settings`], in order.
const SETTING_KEYS: [&str; 6] = [
    "max_depth",
    "method",
    "sampler",
    "background",
    "roulette",
    "instancing",
];

/// Every setting besides the size, seed and samples that changes an image's pixels, as words
/// `key=value` in a fixed order: `max_depth=8 method=mis sampler=sobol background=0,0,0
/// roulette=on instancing=on`. Stored as a partial's `rondo.settings` and hashed, so partials
/// of renders that differ in any of them neither merge nor resume, and the refusal names it.
pub fn image_settings(settings: &SettingsDesc, tracing: Tracing) -> String {
    // Every field by name: a setting added to `SettingsDesc` fails to compile here until it is
    // either part of a partial's identity or known to leave the pixels alone.
    let SettingsDesc {
        width: _,
        height: _,
        spp: _,
        max_depth,
        background,
        seed: _,
        method,
        sampler,
    } = *settings;
    let Tracing {
        roulette,
        instancing,
    } = tracing;
    let on = |b: bool| if b { "on" } else { "off" };
    // `{}` of an f32 is the shortest text that reads back to the same bits.
    format!(
        "max_depth={max_depth} method={method} sampler={sampler} background={},{},{} roulette={} instancing={}",
        background.x,
        background.y,
        background.z,
        on(roulette),
        on(instancing)
    )
}

/// The first setting two [`image_settings`] texts differ in: its key and both values.
pub fn setting_difference<'a>(a: &'a str, b: &'a str) -> Option<(&'a str, &'a str, &'a str)> {
    a.split(' ').zip(b.split(' ')).find_map(|(x, y)| {
        let (key, mine) = x.split_once('=')?;
        let theirs = y.strip_prefix(key)?.strip_prefix('=')?;
        (mine != theirs).then_some((key, mine, theirs))
    })
}

/// Checks a `rondo.settings` text: the keys of [`image_settings`] in its order, each value
/// well-formed and within the limits a render accepts; gives the `max_depth`.
fn check_settings(text: &str) -> Result<u32, String> {
    let words: Vec<&str> = text.split(' ').collect();
    if words.len() != SETTING_KEYS.len() {
        return Err(format!("expected the keys {}", SETTING_KEYS.join(", ")));
    }
    let mut values = [""; SETTING_KEYS.len()];
    for ((word, key), value) in words.iter().zip(SETTING_KEYS).zip(&mut values) {
        *value = word
            .strip_prefix(key)
            .and_then(|v| v.strip_prefix('='))
            .ok_or_else(|| format!("expected {key}=… where {word:?} is"))?;
    }
    let [max_depth, method, sampler, background, roulette, instancing] = values;
    let max_depth: u32 = max_depth
        .parse()
        .map_err(|_| format!("max_depth {max_depth:?} is not a whole number"))?;
    let method: Method = method.parse()?;
    let sampler: SamplerKind = sampler.parse()?;
    let background: Vec<f32> = background
        .split(',')
        .map(|c| c.parse::<f32>().ok().filter(|c| c.is_finite()))
        .collect::<Option<_>>()
        .filter(|b: &Vec<f32>| b.len() == 3)
        .ok_or_else(|| format!("background {background:?} is not three finite numbers"))?;
    let flag = |key: &str, v: &str| match v {
        "on" => Ok(true),
        "off" => Ok(false),
        _ => Err(format!("{key} {v:?} is neither on nor off")),
    };
    let settings = SettingsDesc {
        max_depth,
        background: glam::Vec3::new(background[0], background[1], background[2]),
        method,
        sampler,
        ..SettingsDesc::default()
    };
    settings.validate()?;
    let tracing = Tracing {
        roulette: flag("roulette", roulette)?,
        instancing: flag("instancing", instancing)?,
    };
    // One text per identity, so that comparing texts compares settings.
    if image_settings(&settings, tracing) != text {
        return Err("not in the canonical form rondo writes".into());
    }
    Ok(max_depth)
}

/// Hash of everything an image depends on but the sample range: the format, rondo's version,
/// the contents of every file the scene loads (the scene file first, in load order; paths are
/// left out, so the same scene in another directory hashes the same), the size, the seed and
/// the [`image_settings`] text `settings`.
pub fn image_hash(
    dependencies: &[PathBuf],
    size: (u32, u32),
    seed: u64,
    settings: &str,
) -> Result<u64, PartialError> {
    let mut h = Fnv::new();
    h.field(FORMAT.as_bytes());
    h.field(env!("CARGO_PKG_VERSION").as_bytes());
    for path in dependencies {
        let data = std::fs::read(path).map_err(|e| error(path, format!("cannot read: {e}")))?;
        h.field(&data);
    }
    h.field(&size.0.to_le_bytes());
    h.field(&size.1.to_le_bytes());
    h.field(&seed.to_le_bytes());
    h.field(settings.as_bytes());
    Ok(h.0)
}

/// Parses a sample range `A..B` (A < B).
pub fn parse_range(text: &str) -> Result<Range<u32>, String> {
    let bad = || format!("sample range {text:?} must be A..B with whole numbers A < B");
    let (a, b) = text.split_once("..").ok_or_else(bad)?;
    let (a, b): (u32, u32) = (
        a.trim().parse().map_err(|_| bad())?,
        b.trim().parse().map_err(|_| bad())?,
    );
    if a >= b {
        return Err(bad());
    }
    Ok(a..b)
}

/// Ranges as `0..256,512..768`.
pub fn format_ranges(ranges: &[Range<u32>]) -> String {
    ranges
        .iter()
        .map(|r| format!("{}..{}", r.start, r.end))
        .collect::<Vec<_>>()
        .join(",")
}

/// Sorts ranges and joins the adjacent ones (they must not overlap).
pub fn normalize(mut ranges: Vec<Range<u32>>) -> Vec<Range<u32>> {
    ranges.sort_by_key(|r| r.start);
    let mut out: Vec<Range<u32>> = Vec::with_capacity(ranges.len());
    for r in ranges {
        match out.last_mut() {
            Some(last) if last.end == r.start => last.end = r.end,
            _ => out.push(r),
        }
    }
    out
}

/// The samples of `0..end` that `ranges` (normalized) do not hold.
pub fn gaps(ranges: &[Range<u32>], end: u32) -> Vec<Range<u32>> {
    let mut out = Vec::new();
    let mut at = 0;
    for r in ranges {
        if r.start > at {
            out.push(at..r.start);
        }
        at = at.max(r.end);
    }
    if at < end {
        out.push(at..end);
    }
    out
}

/// Writes a partial: the means (`R`, `G`, `B`, so any EXR viewer shows the image), the exact
/// sums and the metadata, atomically.
pub fn write_partial(path: &Path, meta: &PartialMeta, sum: &[Pixel]) -> std::io::Result<()> {
    use exr::prelude::*;
    let (w, h) = (meta.width as usize, meta.height as usize);
    if sum.len() != w * h {
        return Err(std::io::Error::other(format!(
            "{}: {} pixels for a {w}x{h} partial",
            path.display(),
            sum.len()
        )));
    }
    let (count, fixed) = (meta.count(), FixedPoint::new(meta.shift));
    let [r, g, b] = SUM_CHANNELS;
    let channels = SpecificChannels::build()
        .with_channel("R")
        .with_channel("G")
        .with_channel("B")
        .with_channel(r[0])
        .with_channel(r[1])
        .with_channel(r[2])
        .with_channel(g[0])
        .with_channel(g[1])
        .with_channel(g[2])
        .with_channel(b[0])
        .with_channel(b[1])
        .with_channel(b[2])
        .with_pixel_fn(|p: Vec2<usize>| {
            let s = &sum[p.y() * w + p.x()];
            let m = fixed.mean(s, count);
            let [r0, r1, r2] = s.words(0);
            let [g0, g1, g2] = s.words(1);
            let [b0, b1, b2] = s.words(2);
            (m.x, m.y, m.z, r0, r1, r2, g0, g1, g2, b0, b1, b2)
        });
    let mut attributes = LayerAttributes::default();
    let text = |s: &str| AttributeValue::Text(Text::from(s));
    let other = &mut attributes.other;
    other.insert(Text::from("rondo.format"), text(FORMAT));
    other.insert(
        Text::from("rondo.samples"),
        text(&format_ranges(&meta.ranges)),
    );
    other.insert(Text::from("rondo.seed"), text(&meta.seed.to_string()));
    other.insert(
        Text::from("rondo.hash"),
        text(&format!("{:016x}", meta.hash)),
    );
    other.insert(
        Text::from("rondo.fraction_bits"),
        text(&meta.shift.to_string()),
    );
    other.insert(Text::from("rondo.settings"), text(&meta.settings));
    let scene: String = meta
        .scene
        .chars()
        .filter(|c| c.is_ascii_graphic() || *c == ' ')
        .take(MAX_SCENE_NAME)
        .collect();
    other.insert(Text::from("rondo.scene"), text(&scene));
    let layer = Layer::new((w, h), attributes, Encoding::FAST_LOSSLESS, channels);
    write_atomically(path, |out| {
        Image::from_layer(layer)
            .write()
            .to_buffered(out)
            .map_err(std::io::Error::other)
    })
}

/// Writes a merge result: a partial if `path` ends in `.exr`, an 8-bit image if `.png`.
pub fn write_output(path: &Path, meta: &PartialMeta, sum: &[Pixel]) -> std::io::Result<()> {
    match OutputKind::from_path(path) {
        Some(OutputKind::Exr) => write_partial(path, meta, sum),
        _ => {
            let fixed = FixedPoint::new(meta.shift);
            write_image(path, meta.width, meta.height, sum, meta.count(), fixed)
        }
    }
}

fn open(path: &Path) -> Result<exr::block::reader::Reader<BufReader<File>>, PartialError> {
    let file = File::open(path).map_err(|e| error(path, format!("cannot open: {e}")))?;
    exr::block::read(BufReader::new(file), false)
        .map_err(|e| error(path, format!("not an OpenEXR file: {e}")))
}

/// The metadata of the partial at `path`, checked: one layer with the sum channels, and every
/// rondo attribute present and well-formed.
pub fn read_meta(path: &Path) -> Result<PartialMeta, PartialError> {
    meta_of(path, open(path)?.headers())
}

fn meta_of(
    path: &Path,
    headers: &[exr::meta::header::Header],
) -> Result<PartialMeta, PartialError> {
    let [header] = headers else {
        return Err(error(path, "a partial has one layer"));
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
    if format != FORMAT {
        return Err(error(
            path,
            format!(
                "partial format {}, this rondo reads {FORMAT:?}",
                shown(&format)
            ),
        ));
    }
    // One flat layer, one resolution level, of the known channels: anything else would be
    // decoded for nothing (a block's memory grows with the channel count) or means another kind
    // of file.
    let one_level = match header.blocks {
        BlockDescription::ScanLines => true,
        BlockDescription::Tiles(t) => t.level_mode == LevelMode::Singular,
    };
    if header.deep || !one_level {
        return Err(error(
            path,
            "a partial is a flat image of one resolution level, not deep data or mipmaps",
        ));
    }
    for c in &header.channels.list {
        let name = c.name.to_string();
        if !["R", "G", "B"].contains(&name.as_str())
            && !SUM_CHANNELS.iter().flatten().any(|n| **n == name)
        {
            return Err(error(
                path,
                format!("a partial has no channel {}", shown(&name)),
            ));
        }
    }
    for name in SUM_CHANNELS.iter().flatten() {
        let found =
            header.channels.list.iter().any(|c| {
                c.name == **name && c.sample_type == exr::meta::attribute::SampleType::U32
            });
        if !found {
            return Err(error(path, format!("partial has no u32 channel {name}")));
        }
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
    Ok(PartialMeta {
        width,
        height,
        seed,
        hash,
        ranges,
        scene,
        shift,
        settings,
    })
}

/// `text` for an error message: quoted, and cut after 64 characters (an attribute may be long).
fn shown(text: &str) -> String {
    const MAX: usize = 64;
    match text.char_indices().nth(MAX) {
        Some((at, _)) => format!("{:?}…", &text[..at]),
        None => format!("{text:?}"),
    }
}

/// The fixed-point shifts [`crate::film::shift_for`] can give, for any finite radiance.
const SHIFTS: std::ops::RangeInclusive<i32> = -128..=200;

/// Adds the sums of the partial at `path` into `sum` (a `width` × `height` image, row-major).
/// Returns the partial's metadata. The file is decoded block by block (blocks in parallel), never
/// held whole. Every block of the image (tile or scanlines) must be in the file exactly once (a
/// crafted file could repeat one, or leave one out, and silently brighten or darken the image);
/// on an error, `sum` holds part of the file.
pub fn add_partial(path: &Path, sum: &mut [Pixel]) -> Result<PartialMeta, PartialError> {
    let reader = open(path)?;
    let meta = meta_of(path, reader.headers())?;
    if sum.len() != meta.width as usize * meta.height as usize {
        return Err(error(
            path,
            format!(
                "size {}x{} differs from the image's",
                meta.width, meta.height
            ),
        ));
    }
    let header = &reader.headers()[0];
    // Per channel of the file: the colour and word it holds, if a sum.
    let roles: Vec<Option<(usize, usize)>> = header
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
    let channels = header.channels.clone();
    let (width, height) = (meta.width as usize, meta.height as usize);
    // The grid of blocks: tiles, or rows of scanlines; whether each block was added. The grid
    // has at most one cell per pixel, so at most 2²⁶ (as the pixels are limited).
    let block = match header.blocks {
        BlockDescription::ScanLines => (width, header.compression.scan_lines_per_block()),
        BlockDescription::Tiles(t) => (t.tile_size.width(), t.tile_size.height()),
    };
    if block.0 == 0 || block.1 == 0 {
        return Err(error(path, "blocks of no pixels"));
    }
    let columns = width.div_ceil(block.0);
    let mut seen = vec![false; columns * height.div_ceil(block.1)];
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
            // A block is one cell of the grid (its every channel), clipped at the image's edge.
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
                return Err(error(path, "a block lies outside the image's grid"));
            }
            let cell = &mut seen[y / block.1 * columns + x / block.0];
            if *cell {
                return Err(error(
                    path,
                    format!("the block at row {y}, column {x} appears twice"),
                ));
            }
            *cell = true;
            for line in b.lines(&channels) {
                let Some((colour, word)) = roles[line.location.channel] else {
                    continue;
                };
                let (x, y) = (line.location.position.x(), line.location.position.y());
                let start = y * width + x;
                let pixels = sum
                    .get_mut(start..start + line.location.sample_count)
                    .ok_or_else(|| error(path, "a block lies outside the image"))?;
                // Samples are little-endian u32 (OpenEXR's byte order).
                let values = line.value.chunks_exact(4);
                if values.len() != pixels.len() {
                    return Err(error(path, "a line has the wrong length"));
                }
                let shift = 32 * word;
                // Two's complement in 96 bits: the top word carries the sign.
                let signed = word + 1 == Pixel::WORDS;
                for (pixel, bytes) in pixels.iter_mut().zip(values) {
                    let v = u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]);
                    let part = if signed {
                        i128::from(v as i32)
                    } else {
                        i128::from(v)
                    };
                    pixel.0[colour] += part << shift;
                }
            }
        }
    }
    if let Some(missing) = seen.iter().position(|cell| !cell) {
        let (y, x) = (missing / columns * block.1, missing % columns * block.0);
        return Err(error(
            path,
            format!("the block at row {y}, column {x} is missing"),
        ));
    }
    Ok(meta)
}

/// The checked metadata and the sums of the partial at `path`, read whole.
pub fn read_partial(path: &Path) -> Result<(PartialMeta, Vec<Pixel>), PartialError> {
    let meta = read_meta(path)?;
    let mut sum = vec![Pixel::ZERO; meta.width as usize * meta.height as usize];
    add_partial(path, &mut sum)?;
    Ok((meta, sum))
}

/// What a merge found: the combined metadata and the samples missing below its end.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MergePlan {
    /// Metadata of the merged result.
    pub meta: PartialMeta,
    /// Samples of `0..end` held by no input.
    pub missing: Vec<Range<u32>>,
}

/// Checks that the partials at `paths` can merge: same size, seed, fixed-point shift, settings
/// and image hash, no sample in two of them. Gaps (up to `expect_end` if given, else up to the last sample held) are reported
/// in the plan, not refused here.
pub fn plan_merge(paths: &[PathBuf], expect_end: Option<u32>) -> Result<MergePlan, PartialError> {
    let Some(first_path) = paths.first() else {
        return Err(PartialError("merge: no partials given".into()));
    };
    let metas = paths
        .iter()
        .map(|p| read_meta(p))
        .collect::<Result<Vec<_>, _>>()?;
    let first = &metas[0];
    let mut owned: Vec<(Range<u32>, &Path)> = Vec::new();
    for (meta, path) in metas.iter().zip(paths) {
        let differs = |what: &str, mine: String, theirs: String| {
            Err(error(
                path,
                format!(
                    "{what} {mine}, but {} has {what} {theirs}: partials of one render only",
                    first_path.display()
                ),
            ))
        };
        if (meta.width, meta.height) != (first.width, first.height) {
            return differs(
                "resolution",
                format!("{}x{}", meta.width, meta.height),
                format!("{}x{}", first.width, first.height),
            );
        }
        if meta.seed != first.seed {
            return differs("seed", meta.seed.to_string(), first.seed.to_string());
        }
        if meta.shift != first.shift {
            return differs(
                "fraction bits",
                meta.shift.to_string(),
                first.shift.to_string(),
            );
        }
        if let Some((key, mine, theirs)) = setting_difference(&meta.settings, &first.settings) {
            return differs(key, mine.into(), theirs.into());
        }
        if meta.hash != first.hash {
            return differs(
                "scene/settings hash",
                format!("{:016x}", meta.hash),
                format!("{:016x}", first.hash),
            );
        }
        owned.extend(meta.ranges.iter().map(|r| (r.clone(), path.as_path())));
    }
    owned.sort_by_key(|(r, _)| r.start);
    for w in owned.windows(2) {
        let ((a, pa), (b, pb)) = (&w[0], &w[1]);
        if a.end > b.start {
            return Err(error(
                pb,
                format!(
                    "samples {}..{} overlap samples {}..{} of {}",
                    b.start,
                    b.end,
                    a.start,
                    a.end,
                    pa.display()
                ),
            ));
        }
    }
    let ranges = normalize(owned.into_iter().map(|(r, _)| r).collect());
    let end = expect_end
        .unwrap_or(0)
        .max(ranges.last().map_or(0, |r| r.end));
    let missing = gaps(&ranges, end);
    let meta = PartialMeta {
        ranges,
        ..first.clone()
    };
    Ok(MergePlan { meta, missing })
}

/// Merges the partials at `paths` (checked by [`plan_merge`]) into one image's sums.
pub fn merge(paths: &[PathBuf], plan: &MergePlan) -> Result<Vec<Pixel>, PartialError> {
    let meta = &plan.meta;
    let mut sum = vec![Pixel::ZERO; meta.width as usize * meta.height as usize];
    for path in paths {
        add_partial(path, &mut sum)?;
    }
    Ok(sum)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_parse_normalize_and_show_gaps() {
        assert_eq!(parse_range("0..256"), Ok(0..256));
        assert!(parse_range("5..5").is_err());
        assert!(parse_range("7..3").is_err());
        assert!(parse_range("1-3").is_err());
        let r = normalize(vec![512..768, 0..256, 256..300]);
        assert_eq!(r, vec![0..300, 512..768]);
        assert_eq!(gaps(&r, 1024), vec![300..512, 768..1024]);
        assert_eq!(format_ranges(&r), "0..300,512..768");
    }

    #[test]
    fn settings_text_reads_back_only_in_its_canonical_form() {
        let s = SettingsDesc {
            background: glam::Vec3::new(0.1, 1e-10, 5e9),
            sampler: SamplerKind::Independent,
            ..SettingsDesc::default()
        };
        let off = Tracing {
            roulette: false,
            ..Tracing::default()
        };
        let text = image_settings(&s, off);
        assert_eq!(
            text,
            "max_depth=8 method=mis sampler=independent background=0.1,0.0000000001,5000000000 roulette=off instancing=on"
        );
        assert_eq!(check_settings(&text), Ok(8));
        let on = image_settings(&s, Tracing::default());
        assert_eq!(
            setting_difference(&text, &on),
            Some(("roulette", "off", "on"))
        );
        for bad in [
            "",
            "max_depth=8",
            &text.replace("max_depth=8", "max_depth=08"),
            &text.replace("max_depth=8", "max_depth=2000"),
            &text.replace("sampler=independent", "sampler=halton"),
            &text.replace("0.1,", "NaN,"),
            &text.replace(" roulette", "  roulette"),
            &text.replace("roulette=off", "roulette=no"),
        ] {
            assert!(check_settings(bad).is_err(), "{bad:?}");
        }
    }
}
