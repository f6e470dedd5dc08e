//! Partial renders: the exact per-pixel sums of some sample ranges of a render (the colour's
//! and the feature buffers'), stored as an OpenEXR file with rondo's metadata (format in
//! `docs/partial-format.md`), and their merge.
//!
//! The sums are the film's fixed-point integers ([`crate::film::Pixel`]), so merging partials
//! adds integers: in any order the merged image (and its albedo and normal buffers) is the one a
//! single process rendering every sample makes, bit for bit.

mod identity;
mod merge;
mod meta;
mod ranges;
mod read;
mod write;

pub use identity::{Tracing, image_hash, image_settings, setting_difference};
pub use merge::{MergePlan, merge, plan_merge};
pub use meta::{FORMAT, FORMAT_2, LAYERS, PartialError, PartialMeta, SUM_CHANNELS, Sums};
pub use ranges::{format_ranges, gaps, normalize, parse_range};
pub use read::{add_partial, read_meta, read_partial};
pub use write::{write_output, write_partial};
