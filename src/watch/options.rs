//! What a watch loop watches and renders.

use std::path::PathBuf;
use std::time::Duration;

use crate::app::Overrides;
use crate::geometry::layout::LayoutKind;

use super::files::DEBOUNCE;

/// What to watch and render.
#[derive(Clone, Debug)]
pub struct WatchOptions {
    /// The scene file.
    pub scene: PathBuf,
    /// The output image (`.png` or `.exr`), rewritten atomically after every pass; `None` to
    /// write no file (when an [`Observer`](super::Observer) shows the images instead: `watch --serve`).
    pub output: Option<PathBuf>,
    /// Render threads (all cores if `None`).
    pub threads: Option<usize>,
    /// Settings overrides applied to every load.
    pub overrides: Overrides,
    /// Geometry layout (speed only; images are identical).
    pub layout: LayoutKind,
    /// Samples of the first pass; later passes double the total up to the scene's spp.
    pub first_pass: u32,
    /// The quiet window (see [`DEBOUNCE`]).
    pub debounce: Duration,
    /// `--denoise` (`Some(true)`: the output is denoised too) or `--no-denoise` (`Some(false)`:
    /// nothing is); `None` follows the scene's `denoise` setting, whose absence denoises what
    /// the viewer shows only.
    pub denoise: Option<bool>,
}

impl WatchOptions {
    /// Defaults: all cores, no overrides, the default layout, a first pass of 1 sample, the
    /// [`DEBOUNCE`] window.
    pub fn new(scene: impl Into<PathBuf>, output: impl Into<PathBuf>) -> Self {
        Self {
            scene: scene.into(),
            output: Some(output.into()),
            threads: None,
            overrides: Overrides::default(),
            layout: LayoutKind::default(),
            first_pass: 1,
            debounce: DEBOUNCE,
            denoise: None,
        }
    }
}

/// What a watch denoises, from `--denoise` / `--no-denoise` or the scene's `denoise`: the
/// library is loaded only when asked for, so a viewer alone never loads it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) enum Denoising {
    /// Nothing.
    #[default]
    Off,
    /// The viewer's passes and the output file.
    Output,
}
