//! `rondo diff`: an image against a reference.

use rondo::cli::print_line;
use std::path::Path;

use anyhow::Result;

use rondo::cli::check_output_file;

/// `rondo diff`: prints the metrics of `image` against `reference`, one per line.
pub fn run(image: &Path, reference: &Path, error_image: Option<&Path>) -> Result<()> {
    if let Some(path) = error_image {
        check_output_file(path)?;
    }
    let d = rondo::metrics::diff_files(image, reference, error_image)?;
    let m = d.metrics;
    print_line(format_args!("rmse     {:.6e}", m.rmse))?;
    print_line(format_args!(
        "rel_mse  {:.6e}   (mean of (a - r)^2 / (r^2 + {}))",
        m.rel_mse,
        rondo::metrics::REL_EPSILON
    ))?;
    print_line(format_args!("mae      {:.6e}", m.mae))?;
    if let (Some(path), Some(scale)) = (error_image, d.error_scale) {
        eprintln!(
            "error image {}: |a - r| averaged over channels, dark blue = 0, yellow >= {scale:.4e} (99th percentile)",
            path.display()
        );
    }
    Ok(())
}
