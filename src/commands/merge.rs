//! `rondo merge`: partials into one image.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};

use rondo::cli::check_output_file;

/// `rondo merge`: checks the partials, reports missing samples, merges and writes.
pub fn run(inputs: &[PathBuf], output: &Path, spp: Option<u32>, allow_gaps: bool) -> Result<()> {
    check_output_file(output)?;
    let plan = rondo::partial::plan_merge(inputs, spp)?;
    if !plan.missing.is_empty() {
        let missing = rondo::partial::format_ranges(&plan.missing).replace(',', ", ");
        if !allow_gaps {
            bail!(
                "missing samples {missing} (render them, or merge what is there with --allow-gaps)"
            );
        }
        eprintln!("warning: missing samples {missing}; the image averages the samples present");
    }
    let start = std::time::Instant::now();
    let sums = rondo::partial::merge(inputs, &plan)?;
    rondo::partial::write_output(output, &plan.meta, &sums.colour, sums.features.as_ref())
        .with_context(|| format!("{}: cannot write", output.display()))?;
    eprintln!(
        "merged {} partials ({}x{}, samples {}, {}) into {} in {:.2} s",
        inputs.len(),
        plan.meta.width,
        plan.meta.height,
        rondo::partial::format_ranges(&plan.meta.ranges),
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
