//! `rondo render`: one image, a sample range or a resumed partial, and its summary line.

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use super::args::RenderArgs;
use rondo::Renderer;
use rondo::cli::check_output_file;
use rondo::denoise::FilmImages;
use rondo::denoise::{Denoiser, Quality};
use rondo::film::{Aov, Durability, Layer, OutputImage, OutputKind, write_output};

pub fn run(
    scene: &Path,
    output: &Path,
    options: &RenderArgs,
    aov: &[Aov],
    samples: Option<Range<u32>>,
    resume: Option<PathBuf>,
) -> Result<()> {
    check_output_file(output)?;
    let part = match (samples, resume) {
        (Some(range), _) => Some(rondo::farm::Samples::Range(range)),
        (None, Some(path)) => Some(rondo::farm::Samples::Resume(path)),
        (None, None) => None,
    };
    if !aov.is_empty() && OutputKind::from_path(output) != Some(OutputKind::Exr) {
        bail!(
            "{}: --aov writes layers, which only an .exr holds",
            output.display()
        );
    }
    if part.is_some() && (options.denoise || !aov.is_empty()) {
        bail!(
            "--denoise and --aov make a finished image; a partial (--samples, --resume) holds \
            the raw sums and always the feature buffers: denoise the merged image instead \
            (`rondo merge … -o x.png --denoise`)"
        );
    }
    let mut r = options.renderer()?;
    let part = match &part {
        Some(p) => Some(rondo::farm::prepare(
            &mut r,
            options.overrides(),
            scene,
            output,
            p,
        )?),
        None => None,
    };
    let s = match &part {
        Some(p) => p.settings.clone(),
        None => {
            let info = r.load(scene)?;
            for w in &info.warnings {
                eprintln!("warning: {w}");
            }
            info.settings
        }
    };
    let denoise = part.is_none() && options.denoise().or(s.denoise).unwrap_or(false);
    // The library is loaded before the work starts: a render that cannot be denoised is refused.
    let denoiser = if denoise {
        Some(Denoiser::shared()?)
    } else {
        None
    };
    let layered = denoise || !aov.is_empty();
    if layered {
        r.set_features(true);
    } else if part.is_none() {
        r.set_output(Some(output), false);
    }
    let bar =
        ProgressBar::with_draw_target(Some(u64::from(s.height)), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template("{spinner} rendering [{bar:40}] {percent}% eta {eta}")
            .context("progress template")?,
    );
    r.set_progress(Some(bar.clone()));
    let wall = r.render_to_completion();
    bar.finish_and_clear();
    if let Some(e) = &r.output().last_error {
        bail!("{e}");
    }
    if let Some(part) = part {
        let ranges = rondo::farm::partial::format_ranges(part.ranges());
        part.finish(&mut r)?;
        eprintln!("{} holds samples {ranges}", output.display());
    }
    eprintln!("{}", summary(&r, wall));
    if layered {
        write_layered(&r, output, denoiser, aov)?;
    }
    Ok(())
}

/// Writes the render's colour, denoised if `denoiser` is given (an .exr then keeps the raw
/// colour as the layer `raw`), and the `aov` layers.
fn write_layered(
    r: &Renderer,
    output: &Path,
    denoiser: Option<&Denoiser>,
    aov: &[Aov],
) -> Result<()> {
    let images = FilmImages::of(r.film());
    let denoised = match denoiser {
        Some(d) => {
            let start = Instant::now();
            let quality = Quality::High;
            let image = images.denoise(d, quality, &r.cancel_flag())?;
            eprintln!(
                "denoised in {:.2} s (Open Image Denoise {}, quality {quality}, guided by albedo and normal)",
                start.elapsed().as_secs_f64(),
                d.version()
            );
            Some(image)
        }
        None => None,
    };
    let mut layers = Vec::new();
    if denoised.is_some() {
        layers.push(Layer {
            name: "raw",
            pixels: &images.colour,
        });
    }
    for a in aov {
        let pixels = match a {
            Aov::Albedo => images.albedo.as_deref(),
            Aov::Normal => images.normal.as_deref(),
        };
        layers.push(Layer {
            name: a.name(),
            pixels: pixels.context("the film collected no feature buffers")?,
        });
    }
    let colour = denoised.as_deref().unwrap_or(&images.colour);
    let image = OutputImage::of_linear(images.width, images.height, colour, &layers);
    write_output(output, &image, Durability::Synced)
        .with_context(|| format!("{}: cannot write image", output.display()))
}

/// The one-line summary printed after a render: the samples per pixel and the rate are those
/// this process rendered (`--samples 1023..1024` renders 1 spp, a resume the samples after its
/// partial's), with their range when it does not start at 0.
pub fn summary(r: &Renderer, wall: Duration) -> String {
    let s = r.settings();
    let film = r.film();
    let stats = r.stats();
    let secs = wall.as_secs_f64().max(1e-9);
    let spp = film.count();
    let samples = f64::from(s.width) * f64::from(s.height) * spp as f64;
    let range = if film.start > 0 {
        format!(" (samples {}..{})", film.start, film.samples)
    } else {
        String::new()
    };
    format!(
        "{}x{}, {spp} spp{range}, {:.2} s, {:.2} M samples/s, {:.2} M rays/s, BVH {:.2} ms ({} primitives), {} non-finite samples (dropped), {} beyond the film's range (clamped)",
        s.width,
        s.height,
        secs,
        samples / secs / 1e6,
        stats.rays as f64 / secs / 1e6,
        r.timings().bvh.as_secs_f64() * 1e3,
        r.primitive_count(),
        stats.nonfinite,
        stats.clamped,
    )
}
