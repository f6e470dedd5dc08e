//! What a partial file holds: its format versions, layers and sum channels, its metadata, and
//! the sums themselves; and the error every step of reading, writing and merging reports.

use std::fmt;
use std::ops::Range;
use std::path::Path;

use crate::film::{Features, Pixel};

/// Value of the `rondo.format` attribute of a partial of this version of the format: three
/// layers, the colour's sums and the feature buffers' (albedo and normal).
pub const FORMAT: &str = "rondo-partial-3";

/// The format before the feature buffers: the colour's sums alone. Still read, and written for
/// the merge of such partials (whose result has no feature buffers either).
pub const FORMAT_2: &str = "rondo-partial-2";

/// The format before the sampler and the renderer's options were recorded (`rondo.settings`):
/// its partials cannot say whether they belong together, so they are refused with this reason.
pub(super) const FORMAT_1: &str = "rondo-partial-1";

/// The names of the layers (EXR parts) of a [`FORMAT`] partial, in their order in the file: the
/// colour (with the `rondo.*` metadata), then the feature buffers.
pub const LAYERS: [&str; 3] = ["colour", "albedo", "normal"];

/// Longest `rondo.scene` attribute read (a file name).
pub(super) const MAX_SCENE_NAME: usize = 255;

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

pub(super) fn error(path: &Path, message: impl fmt::Display) -> PartialError {
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
    /// [`image_hash`](super::image_hash) of the scene, its files and the settings.
    pub hash: u64,
    /// The sample ranges held, sorted, disjoint and not adjacent.
    pub ranges: Vec<Range<u32>>,
    /// The scene's file name (for people; not checked).
    pub scene: String,
    /// The film's fixed-point shift: sums are in units of 2⁻shift ([`crate::film::shift_for`]).
    pub shift: i32,
    /// Every other setting the pixels depend on, as [`image_settings`](super::image_settings) writes them
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
