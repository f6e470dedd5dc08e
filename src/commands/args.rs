//! Argument types shared by several commands: the render options and the value parsers.

use std::path::{Path, PathBuf};

use anyhow::Result;

use clap::Args;
use rondo::bench::layout_rows;
use rondo::film::OutputKind;
use rondo::geometry::layout::LayoutKind;
use rondo::scene::format::{MAX_DEPTH, MAX_SIDE, MAX_SPP, Method};
use rondo::shading::sampler::SamplerKind;
use rondo::watch::WatchOptions;
use rondo::{Overrides, PassPlan, Renderer};

#[derive(Args)]
pub struct RenderArgs {
    /// Samples per pixel (overrides the scene).
    #[arg(long, value_parser = at_most_u32(MAX_SPP))]
    pub spp: Option<u32>,
    /// Image width (overrides the scene).
    #[arg(long, value_parser = at_most_u32(MAX_SIDE))]
    pub width: Option<u32>,
    /// Image height (overrides the scene).
    #[arg(long, value_parser = at_most_u32(MAX_SIDE))]
    pub height: Option<u32>,
    /// Rays per path, camera ray included (overrides the scene).
    #[arg(long, value_parser = at_most_u32(MAX_DEPTH))]
    pub max_depth: Option<u32>,
    /// Random seed (overrides the scene).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = thread_count())]
    pub threads: Option<usize>,
    /// Light-transport method: naive, nee, mis, caustics or photons (overrides the scene; the default is caustics).
    #[arg(long)]
    pub method: Option<Method>,
    /// Sample generator: independent or sobol (overrides the scene).
    #[arg(long)]
    pub sampler: Option<SamplerKind>,
    /// Geometry layout: soa, aos or soa-simd. Images are bit-identical; only speed differs.
    #[arg(long, default_value_t = LayoutKind::default())]
    pub layout: LayoutKind,
    /// Denoise the image written (Open Image Denoise, guided by albedo and normal; see the
    /// README): an .exr keeps the raw colour as the layer `raw`. Overrides the scene's `denoise`.
    #[arg(long, conflicts_with = "no_denoise")]
    pub denoise: bool,
    /// Denoise nothing, not even what the viewer shows (overrides the scene's `denoise`).
    #[arg(long)]
    pub no_denoise: bool,
}

impl RenderArgs {
    /// The scene-setting overrides given on the command line.
    pub fn overrides(&self) -> Overrides {
        Overrides {
            width: self.width,
            height: self.height,
            spp: self.spp,
            max_depth: self.max_depth,
            seed: self.seed,
            method: self.method,
            sampler: self.sampler,
        }
    }

    /// `--denoise` / `--no-denoise`, if given: the scene's `denoise` setting overridden.
    pub fn denoise(&self) -> Option<bool> {
        match (self.denoise, self.no_denoise) {
            (true, _) => Some(true),
            (_, true) => Some(false),
            _ => None,
        }
    }

    pub fn renderer(&self) -> Result<Renderer> {
        let mut r = Renderer::new(self.threads, PassPlan::Single)?;
        r.set_overrides(self.overrides());
        r.set_layout(self.layout);
        Ok(r)
    }
}

/// `--spp`, `--width`, … : a whole number from 1 to `max`.
pub fn at_most_u32(max: u32) -> clap::builder::RangedI64ValueParser<u32> {
    clap::value_parser!(u32).range(1..=i64::from(max))
}

/// A whole number ≥ 1.
pub fn at_least_one_u32() -> clap::builder::RangedI64ValueParser<u32> {
    clap::value_parser!(u32).range(1..)
}

/// `--threads`: at least one.
pub fn thread_count() -> clap::builder::RangedU64ValueParser<usize> {
    clap::builder::RangedU64ValueParser::<usize>::new().range(1..)
}

/// An image output path: `.png` or `.exr`.
pub fn image_path(s: &str) -> Result<PathBuf, String> {
    let path = PathBuf::from(s);
    match OutputKind::from_path(&path) {
        Some(_) => Ok(path),
        None => Err("must end in .png or .exr".into()),
    }
}

/// A `.png` output path.
pub fn png_path(s: &str) -> Result<PathBuf, String> {
    let path = PathBuf::from(s);
    match OutputKind::from_path(&path) {
        Some(OutputKind::Png) => Ok(path),
        _ => Err("must end in .png".into()),
    }
}

/// The workloads `bench layout` knows.
pub fn workload_names() -> clap::builder::PossibleValuesParser {
    clap::builder::PossibleValuesParser::new(layout_rows::WORKLOADS.iter().map(|w| w.0))
}

impl RenderArgs {
    pub fn watch_options(
        &self,
        scene: &Path,
        output: &Path,
        first_spp: u32,
    ) -> Result<WatchOptions> {
        let mut options = WatchOptions::new(scene, output);
        options.threads = self.threads;
        options.first_pass = first_spp;
        options.layout = self.layout;
        options.overrides = self.overrides();
        options.denoise = self.denoise();
        Ok(options)
    }
}
