//! `rondo bench accuracy`: error against a reference image as a function of render time, for
//! each light-transport method and sampler over a sweep of samples per pixel. Writes
//! `accuracy.csv`, `accuracy.svg` (log-log RMSE against seconds, one line per method and
//! sampler, spp at each point, fitted slope in the legend), `accuracy_relative.svg` and
//! `accuracy_lamp_out.svg` (the same for √relMSE and the lamp-out RMSE) and `summary.md` (the
//! equal-time comparison in every metric).
//!
//! Each row also counts its fireflies ([`crate::metrics::fireflies`]: pixels above 4× their
//! reference), where rare paths (caustics) fail; `summary.md` tabulates them per spp.
//!
//! Why three metrics: RMSE weighs every pixel by its brightness, so a directly visible lamp of
//! radiance 1500 (whose edge pixels are noisy by antialiasing alone, the same for every method)
//! or a few caustic fireflies can decide it. √relMSE (relative MSE with ε = 0.01, see
//! [`crate::metrics`]) weighs every pixel alike; both fall as 1/√t. The lamp-out RMSE
//! ([`crate::metrics::lamp_out_rmse`]: pixels whose reference exceeds 1 left out, both images
//! clamped to [0, 1]) is the error of the peer-renderer benches (Mitsuba, Cycles) and of the
//! figures in BENCHMARKS.md.
//!
//! With `denoise`, every render is made a second time with the feature buffers (albedo and
//! normal) and the same seed, so its colour is the raw render's to the bit, and denoised by
//! Open Image Denoise (quality high, guided by albedo and normal). Its row (`denoised` set)
//! times the render with the features plus the denoise (the film's means, the filter, its
//! output), wall clock; the library is loaded and run once before the sweep, as the scene is,
//! so neither load is timed. The denoiser is biased: its error does not fall as 1/√t, so its
//! curves get no slope and no "error · √s", and `summary.md` gives instead, per method and
//! sampler, the error level from which on the raw render is the better choice
//! ([`crossover`]).
//!
//! With `keep_images`, every image is written there as `<method>_<sampler>_<spp>spp.exr` (raw)
//! and `<method>_<sampler>_<spp>spp_denoised.exr` (the denoised colour, the raw colour as the
//! layer `raw`), and `accuracy.csv` names each row's image in its `image` column, which
//! `benches/flip/flip.py` matches to add FLIP.
//!
//! Renders are interleaved (for each spp, every method and sampler in turn) so that a change in machine
//! load during the sweep hits every method alike. Each render uses its own seed, `seed + k`,
//! never the reference's (the reference must be made with a seed outside that range, e.g. the
//! scene's default 0), so a render is never correlated with the reference it is compared to.
//!
//! Monte Carlo error falls as `c / √t` for a fixed method; `c` (the "RMSE · √seconds" column)
//! is the method's cost of accuracy, and the ratio of two methods' `c` is their error ratio at
//! equal time (its square, the time ratio at equal error).

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use glam::Vec3;

pub use super::accuracy_chart::write_chart;
use super::accuracy_rows::{AccuracyError, AccuracyReport, AccuracyRow, Metric, fit};
pub use super::accuracy_summary::{Crossover, crossover, raw_line, summary_markdown};
use crate::denoise::FilmImages;
use crate::denoise::{Denoiser, Quality};
use crate::film::{Durability, Layer, OutputImage, write_output};
use crate::metrics::{Image, MetricsError, compare, fireflies, lamp_out_rmse};
use crate::scene::format::Method;
use crate::shading::sampler::SamplerKind;
use crate::{Overrides, PassPlan, Renderer};

/// What to measure.
#[derive(Clone, Debug, PartialEq)]
pub struct AccuracyOptions {
    /// Scene file.
    pub scene: PathBuf,
    /// Reference image (linear EXR); the renders take its size.
    pub reference: PathBuf,
    /// Output directory (created if missing).
    pub out: PathBuf,
    /// Samples per pixel of each render.
    pub spp_list: Vec<u32>,
    /// Methods compared.
    pub methods: Vec<Method>,
    /// Samplers compared (each with every method).
    pub samplers: Vec<SamplerKind>,
    /// Worker threads (all cores if `None`).
    pub threads: Option<usize>,
    /// Rays per path (the scene's if `None`).
    pub max_depth: Option<u32>,
    /// First seed of the sweep; render `k` uses `seed + k`.
    pub seed: u64,
    /// Also measure each render denoised (see the module documentation).
    pub denoise: bool,
    /// Directory to write every image into, if any.
    pub keep_images: Option<PathBuf>,
}

/// Default first seed of a sweep: far from the small seeds references are made with.
pub const DEFAULT_SEED: u64 = 1_000_000;

/// Runs the sweep: renders every (spp, method) pair, interleaved, and compares each image with
/// the reference; with `denoise`, each render is followed by its denoised twin. `on_row` sees
/// each row as it is measured. Writes nothing but the kept images.
pub fn measure(
    options: &AccuracyOptions,
    mut on_row: impl FnMut(&AccuracyRow),
) -> Result<AccuracyReport, AccuracyError> {
    if options.methods.is_empty()
        || options.samplers.is_empty()
        || options.spp_list.is_empty()
        || options.spp_list.contains(&0)
    {
        return Err(AccuracyError::Empty);
    }
    let curves: Vec<(Method, SamplerKind)> = options
        .methods
        .iter()
        .flat_map(|&m| options.samplers.iter().map(move |&s| (m, s)))
        .collect();
    if options.keep_images.is_some() {
        check_distinct(&curves, &options.spp_list)?;
    }
    let reference = Image::read(&options.reference)?;
    // Loaded before the work starts: a sweep that cannot denoise is refused at once.
    let denoiser = if options.denoise {
        Some(Denoiser::shared()?)
    } else {
        None
    };
    let mut renderer = Renderer::new(options.threads, PassPlan::Single)?;
    let overrides = |(method, sampler): (Method, SamplerKind), spp: u32, seed: u64| Overrides {
        width: Some(reference.width),
        height: Some(reference.height),
        spp: Some(spp),
        max_depth: options.max_depth,
        seed: Some(seed),
        method: Some(method),
        sampler: Some(sampler),
    };
    // Warm-up, not recorded: builds the BVH and touches every page once; the denoiser's
    // device and filter are made once too.
    renderer.set_overrides(overrides(curves[0], 1, options.seed));
    renderer.set_features(denoiser.is_some());
    renderer.load(&options.scene)?;
    renderer.render_to_completion();
    if let Some(d) = denoiser {
        FilmImages::of(renderer.film()).denoise(d, Quality::High, &AtomicBool::new(false))?;
    }

    let mut rows = Vec::new();
    let mut k = 0u64;
    for &spp in &options.spp_list {
        for &(method, sampler) in &curves {
            k += 1;
            let seed = options.seed.wrapping_add(k);
            renderer.set_overrides(overrides((method, sampler), spp, seed));
            let mut passes = vec![None];
            passes.extend(denoiser.map(Some));
            for pass in passes {
                renderer.set_features(pass.is_some());
                renderer.load(&options.scene)?;
                let mut seconds = renderer.render_to_completion().as_secs_f64();
                let nonfinite = renderer.stats().nonfinite;
                if nonfinite > 0 {
                    return Err(AccuracyError::NonFinite {
                        scene: options.scene.clone(),
                        method,
                        spp,
                        count: nonfinite,
                    });
                }
                let (image, raw) = match pass {
                    None => (Image::from_film(renderer.film()), None),
                    Some(d) => {
                        let start = Instant::now();
                        let images = FilmImages::of(renderer.film());
                        let denoised = images.denoise(d, Quality::High, &AtomicBool::new(false))?;
                        seconds += start.elapsed().as_secs_f64();
                        let image = image_of(reference.width, reference.height, &denoised);
                        let count = image.data.iter().filter(|v| !v.is_finite()).count();
                        if count > 0 {
                            return Err(AccuracyError::DenoisedNonFinite {
                                scene: options.scene.clone(),
                                method,
                                spp,
                                count,
                            });
                        }
                        (image, Some(images.colour))
                    }
                };
                let mismatch = || MetricsError::SizeMismatch {
                    path: options.scene.clone(),
                    size: (image.width, image.height),
                    reference: options.reference.clone(),
                    reference_size: (reference.width, reference.height),
                };
                let row = AccuracyRow {
                    method,
                    sampler,
                    spp,
                    seed,
                    seconds,
                    metrics: compare(&image, &reference).ok_or_else(mismatch)?,
                    lamp_out_rmse: lamp_out_rmse(&image, &reference).ok_or_else(mismatch)?,
                    fireflies: fireflies(&image, &reference).ok_or_else(mismatch)?,
                    denoised: pass.is_some(),
                };
                if let Some(dir) = &options.keep_images {
                    keep_image(&dir.join(row.image_name()), &image, raw.as_deref())?;
                }
                on_row(&row);
                rows.push(row);
            }
        }
    }
    renderer.set_features(false);
    let fits = Metric::ALL
        .iter()
        .flat_map(|&metric| curves.iter().map(move |&c| (metric, c)))
        .map(|(metric, (m, s))| fit(m, s, metric, &rows))
        .collect::<Vec<_>>();
    Ok(AccuracyReport {
        width: reference.width,
        height: reference.height,
        rows,
        fits,
    })
}

/// Refuses a sweep in which two renders would write the same image file.
fn check_distinct(curves: &[(Method, SamplerKind)], spp_list: &[u32]) -> Result<(), AccuracyError> {
    let mut seen = std::collections::HashSet::new();
    for &spp in spp_list {
        for &(method, sampler) in curves {
            if !seen.insert((method, sampler, spp)) {
                return Err(AccuracyError::Duplicate {
                    method,
                    sampler,
                    spp,
                });
            }
        }
    }
    Ok(())
}

/// An [`Image`] of `width` × `height` pixels.
fn image_of(width: u32, height: u32, pixels: &[Vec3]) -> Image {
    Image {
        width,
        height,
        data: pixels.iter().flat_map(|p| p.to_array()).collect(),
    }
}

/// Writes `image` as an EXR at `path`, with `raw` as the layer `raw` if given.
fn keep_image(path: &Path, image: &Image, raw: Option<&[Vec3]>) -> Result<(), AccuracyError> {
    let colour: Vec<Vec3> = image
        .data
        .chunks_exact(3)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect();
    let layers: Vec<Layer> = raw
        .map(|pixels| Layer {
            name: "raw",
            pixels,
        })
        .into_iter()
        .collect();
    let image = OutputImage::of_linear(image.width, image.height, &colour, &layers);
    write_output(path, &image, Durability::Live).map_err(write_error(path))
}

fn write_error(path: &Path) -> impl Fn(std::io::Error) -> AccuracyError + '_ {
    move |e| AccuracyError::Write {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// Writes `rows` as CSV with a header line; `images` fills the `image` column with each row's
/// [`AccuracyRow::image_name`] (left empty otherwise).
pub fn write_csv(path: &Path, rows: &[AccuracyRow], images: bool) -> Result<(), AccuracyError> {
    crate::output_file::write_bytes(path, csv_text(rows, images).as_bytes())
        .map_err(write_error(path))
}

/// The text of [`write_csv`].
pub fn csv_text(rows: &[AccuracyRow], images: bool) -> String {
    // New columns come last, so the columns of files written before them keep their places.
    let mut text = String::from(
        "method,spp,seed,seconds,rmse,rel_mse,mae,sampler,denoised,lamp_out_rmse,image,fireflies\n",
    );
    for r in rows {
        text += &format!(
            "{},{},{},{:.6},{:.6e},{:.6e},{:.6e},{},{},{:.6e},{},{}\n",
            r.method,
            r.spp,
            r.seed,
            r.seconds,
            r.metrics.rmse,
            r.metrics.rel_mse,
            r.metrics.mae,
            r.sampler,
            r.denoised,
            r.lamp_out_rmse,
            if images {
                r.image_name()
            } else {
                String::new()
            },
            r.fireflies
        );
    }
    text
}

/// Runs [`measure`] and writes `accuracy.csv`, a chart per metric (`accuracy.svg`,
/// `accuracy_relative.svg`, `accuracy_lamp_out.svg`) and `summary.md` in `options.out`.
/// Returns the report.
pub fn run(
    options: &AccuracyOptions,
    on_row: impl FnMut(&AccuracyRow),
) -> Result<AccuracyReport, AccuracyError> {
    std::fs::create_dir_all(&options.out).map_err(write_error(&options.out))?;
    if let Some(dir) = &options.keep_images {
        std::fs::create_dir_all(dir).map_err(write_error(dir))?;
    }
    let report = measure(options, on_row)?;
    write_csv(
        &options.out.join("accuracy.csv"),
        &report.rows,
        options.keep_images.is_some(),
    )?;
    let name = options
        .scene
        .file_stem()
        .map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned());
    let denoised = report.rows.iter().any(|r| r.denoised);
    let title = |metric: Metric| {
        format!(
            "{name} {}×{}: {} against time, spp at each point{}",
            report.width,
            report.height,
            metric.name(),
            if denoised {
                "; dashed: denoised (the denoiser is biased)"
            } else {
                ""
            }
        )
    };
    for metric in Metric::ALL {
        write_chart(
            &options.out.join(metric.chart_file()),
            &title(metric),
            metric,
            &report,
        )?;
    }
    let summary = options.out.join("summary.md");
    let text = format!(
        "{}\n\nscene `{}`, reference `{}`\n\n{}\n",
        title(Metric::Rmse),
        options.scene.display(),
        options.reference.display(),
        summary_markdown(&report)
    );
    crate::output_file::write_bytes(&summary, text.as_bytes()).map_err(write_error(&summary))?;
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::accuracy_rows::test_method_row as row;

    #[test]
    fn the_csv_keeps_its_old_columns_and_adds_denoised_lamp_out_image_and_fireflies_at_the_end() {
        let raw = AccuracyRow {
            spp: 4,
            seed: 7,
            lamp_out_rmse: 0.25,
            fireflies: 3,
            ..row(Method::Mis, 1.5, 0.5)
        };
        let denoised = AccuracyRow {
            denoised: true,
            ..raw
        };
        let text = csv_text(&[raw, denoised], true);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(
            lines,
            [
                "method,spp,seed,seconds,rmse,rel_mse,mae,sampler,denoised,lamp_out_rmse,image,fireflies",
                "mis,4,7,1.500000,5.000000e-1,0.000000e0,0.000000e0,sobol,false,2.500000e-1,mis_sobol_4spp.exr,3",
                "mis,4,7,1.500000,5.000000e-1,0.000000e0,0.000000e0,sobol,true,2.500000e-1,mis_sobol_4spp_denoised.exr,3",
            ]
        );
        // Without kept images the column is there but empty.
        assert!(csv_text(&[raw], false).ends_with(",false,2.500000e-1,,3\n"));
    }

    #[test]
    fn lamp_out_rmse_leaves_out_bright_reference_pixels_and_clamps() {
        // Reference: pixel 0 (0.5, 0.5, 0.5); pixel 1 (2, 0, 0), left out (red above 1);
        // pixel 2 (1, 1, 1), kept (not above 1). Image: pixel 0 (0.75, 0.5, 0.25), pixel 1
        // anything, pixel 2 (3, 1, -1), clamped to (1, 1, 0).
        // Squared errors of the six kept values: 0.0625, 0, 0.0625, 0, 0, 1; sum 1.125.
        // Lamp-out RMSE = √(1.125 / 6) = 0.4330127…
        let r = Image {
            width: 3,
            height: 1,
            data: vec![0.5, 0.5, 0.5, 2.0, 0.0, 0.0, 1.0, 1.0, 1.0],
        };
        let a = Image {
            width: 3,
            height: 1,
            data: vec![0.75, 0.5, 0.25, 9.0, 9.0, 9.0, 3.0, 1.0, -1.0],
        };
        let got = lamp_out_rmse(&a, &r).expect("same size");
        assert!((got - 0.433_012_7).abs() < 1e-7, "{got}");
        let small = Image {
            width: 1,
            height: 1,
            data: vec![0.0; 3],
        };
        assert_eq!(lamp_out_rmse(&small, &r), None);
    }

    #[test]
    fn a_kept_image_sweep_refuses_two_renders_of_one_name() {
        let curves = [(Method::Mis, SamplerKind::Sobol)];
        assert!(check_distinct(&curves, &[1, 2, 4]).is_ok());
        let e = check_distinct(&curves, &[1, 2, 1]).expect_err("duplicate");
        assert!(e.to_string().contains("mis sobol at 1 spp"), "{e}");
    }

    #[test]
    fn an_exact_method_is_reported_as_exact() {
        let rows = [row(Method::Naive, 1.0, 0.0), row(Method::Nee, 1.0, 0.1)];
        let f = fit(Method::Naive, SamplerKind::Sobol, Metric::Rmse, &rows);
        assert_eq!((f.slope, f.at_one_second), (None, 0.0));
        let report = AccuracyReport {
            width: 1,
            height: 1,
            fits: vec![f, fit(Method::Nee, SamplerKind::Sobol, Metric::Rmse, &rows)],
            rows: rows.to_vec(),
        };
        let md = summary_markdown(&report);
        assert!(
            md.contains("| naive sobol | – | 0.0000e0 | 1 (exact) | 1 |"),
            "{md}"
        );
        assert!(
            md.contains("| nee sobol | – | 1.0000e-1 | ∞ (best is exact) | ∞ |"),
            "{md}"
        );
    }
}
