//! `rondo merge`: partials into one image.

use std::path::{Path, PathBuf};

use std::sync::atomic::AtomicBool;

use anyhow::{Context, Result, bail};

use rondo::Film;
use rondo::cli::check_output_file;
use rondo::denoise::FilmImages;
use rondo::denoise::{Denoiser, Quality};
use rondo::film::{Durability, OutputImage, OutputKind, write_output};

/// `rondo merge`: checks the partials, reports missing samples, merges and writes (denoised,
/// with `denoise`, to a `.png`).
pub fn run(
    inputs: &[PathBuf],
    output: &Path,
    spp: Option<u32>,
    allow_gaps: bool,
    denoise: bool,
) -> Result<()> {
    check_output_file(output)?;
    let denoiser = if denoise {
        if OutputKind::from_path(output) != Some(OutputKind::Png) {
            bail!(
                "{}: --denoise writes a .png; an .exr merge is a partial of the raw sums",
                output.display()
            );
        }
        Some(Denoiser::shared()?)
    } else {
        None
    };
    let plan = rondo::farm::partial::plan_merge(inputs, spp)?;
    if denoise && !plan.meta.features {
        bail!(
            "--denoise needs the partials' albedo and normal buffers, which rondo-partial-2             files do not have"
        );
    }
    if !plan.missing.is_empty() {
        let missing = rondo::farm::partial::format_ranges(&plan.missing).replace(',', ", ");
        if !allow_gaps {
            bail!(
                "missing samples {missing} (render them, or merge what is there with --allow-gaps)"
            );
        }
        eprintln!("warning: missing samples {missing}; the image averages the samples present");
    }
    let start = std::time::Instant::now();
    let sums = rondo::farm::partial::merge(inputs, &plan)?;
    match denoiser {
        Some(d) => {
            let film = Film {
                width: plan.meta.width,
                height: plan.meta.height,
                sum: sums.colour,
                samples: u32::try_from(plan.meta.count()).context("too many samples")?,
                start: 0,
                shift: plan.meta.shift,
                features: sums.features,
            };
            let images = FilmImages::of(&film);
            let image = images.denoise(d, Quality::High, &AtomicBool::new(false))?;
            let image = OutputImage::of_linear(film.width, film.height, &image, &[]);
            write_output(output, &image, Durability::Synced)
        }
        None => rondo::farm::partial::write_output(
            output,
            &plan.meta,
            &sums.colour,
            sums.features.as_ref(),
        ),
    }
    .with_context(|| format!("{}: cannot write", output.display()))?;
    eprintln!(
        "merged {} partials ({}x{}, samples {}, {}) into {} in {:.2} s",
        inputs.len(),
        plan.meta.width,
        plan.meta.height,
        rondo::farm::partial::format_ranges(&plan.meta.ranges),
        if plan.meta.features {
            "with the albedo and normal buffers"
        } else {
            "without feature buffers (rondo-partial-2)"
        },
        output.display(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
