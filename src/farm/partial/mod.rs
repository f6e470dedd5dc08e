//! Partial renders: the exact per-pixel sums of some sample ranges of a render (the colour's
//! and the feature buffers'), stored as an OpenEXR file with rondo's metadata (format in
//! `docs/partial-format.md`), and their merge.
//!
//! The sums are the film's fixed-point integers ([`crate::film::Pixel`]), so merging partials
//! adds integers: in any order the merged image (and its albedo and normal buffers) is the one a
//! single process rendering every sample makes, bit for bit.

mod read;
mod write;

use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};

use crate::film::{Features, Pixel};
use crate::scene::format::{Method, SettingsDesc};
use crate::shading::sampler::SamplerKind;

pub use read::{add_partial, read_meta, read_partial};
pub use write::{write_output, write_partial};

/// Value of the `rondo.format` attribute of a partial of this version of the format: three
/// layers, the colour's sums and the feature buffers' (albedo and normal).
pub const FORMAT: &str = "rondo-partial-3";

/// The format before the feature buffers: the colour's sums alone. Still read, and written for
/// the merge of such partials (whose result has no feature buffers either).
pub const FORMAT_2: &str = "rondo-partial-2";

/// The format before the sampler and the renderer's options were recorded (`rondo.settings`):
/// its partials cannot say whether they belong together, so they are refused with this reason.
const FORMAT_1: &str = "rondo-partial-1";

/// The names of the layers (EXR parts) of a [`FORMAT`] partial, in their order in the file: the
/// colour (with the `rondo.*` metadata), then the feature buffers.
pub const LAYERS: [&str; 3] = ["colour", "albedo", "normal"];

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
    /// Whether the partial carries the feature buffers ([`FORMAT`]; a [`FORMAT_2`] partial
    /// does not).
    pub features: bool,
    /// The albedo layer's fixed-point shift: [`crate::film::ALBEDO_SHIFT`], or `shift` in a
    /// partial written while the albedo took the colour's shift (still read and merged).
    pub albedo_shift: i32,
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

    /// The format a partial of this metadata is written in: [`FORMAT`] with the feature
    /// buffers, [`FORMAT_2`] without.
    pub fn format(&self) -> &'static str {
        if self.features { FORMAT } else { FORMAT_2 }
    }

    /// Pixels of the image.
    pub fn pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }
}

/// The sums a partial holds, row-major from the top-left: the colour's, in units of 2⁻shift of
/// its [`PartialMeta`], and the feature buffers' if it carries them (the albedo in units of
/// 2⁻`albedo_shift`, the normal in those of [`crate::film::NORMAL_SHIFT`], as a film's).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Sums {
    /// Sums of the colour samples.
    pub colour: Vec<Pixel>,
    /// Sums of the albedo and normal samples.
    pub features: Option<Features>,
}

impl Sums {
    /// Zero sums for a partial of `meta`: with feature buffers if it carries them.
    pub fn zero(meta: &PartialMeta) -> Self {
        let pixels = meta.pixels();
        Self {
            colour: vec![Pixel::ZERO; pixels],
            features: meta
                .features
                .then(|| Features::with_albedo_shift(pixels, meta.albedo_shift)),
        }
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
        denoise: _,
        // The environment's and the sun's parameters are in the scene file's text, and the
        // map's pixels in its file: both are dependencies, hashed by `image_hash`.
        environment: _,
        sun: _,
    } = settings;
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

/// What a merge found: the combined metadata and the samples missing below its end.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MergePlan {
    /// Metadata of the merged result.
    pub meta: PartialMeta,
    /// Samples of `0..end` held by no input.
    pub missing: Vec<Range<u32>>,
}

/// Checks that the partials at `paths` can merge: same size, seed, fixed-point shift, settings,
/// format (all with the feature buffers, or all without) and image hash, no sample in two of
/// them. Gaps (up to `expect_end` if given, else up to the last sample held) are reported in the
/// plan, not refused here.
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
        if meta.features && first.features && meta.albedo_shift != first.albedo_shift {
            return differs(
                "albedo fraction bits",
                meta.albedo_shift.to_string(),
                first.albedo_shift.to_string(),
            );
        }
        if let Some((key, mine, theirs)) = setting_difference(&meta.settings, &first.settings) {
            return differs(key, mine.into(), theirs.into());
        }
        if meta.features != first.features {
            // The formats hash differently too; this says why they do not belong together.
            let carries = |m: &PartialMeta| {
                let has = if m.features { "with" } else { "without" };
                format!(
                    "format {} ({has} the albedo and normal buffers)",
                    m.format()
                )
            };
            return Err(error(
                path,
                format!(
                    "{}, but {} has {}: partials of one format only (render the samples of the {FORMAT_2} ones again)",
                    carries(meta),
                    first_path.display(),
                    carries(first)
                ),
            ));
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

/// Merges the partials at `paths` (checked by [`plan_merge`]) into one image's sums: the
/// colour's, and the feature buffers' if the plan's partials carry them.
pub fn merge(paths: &[PathBuf], plan: &MergePlan) -> Result<Sums, PartialError> {
    let mut sums = Sums::zero(&plan.meta);
    for path in paths {
        add_partial(path, &mut sums)?;
    }
    Ok(sums)
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
