//! `rondo bench accuracy`: error against a reference image as a function of render time, for
//! each light-transport method and sampler over a sweep of samples per pixel. Writes
//! `accuracy.csv`, `accuracy.svg` (log-log RMSE against seconds, one line per method and
//! sampler, spp at each point, fitted slope in the legend), `accuracy_relative.svg` (the same for √relMSE) and `summary.md` (the
//! equal-time comparison in both metrics).
//!
//! Why two metrics: RMSE weighs every pixel by its brightness, so a directly visible lamp of
//! radiance 1500 (whose edge pixels are noisy by antialiasing alone, the same for every method)
//! or a few caustic fireflies can decide it. √relMSE (relative MSE with ε = 0.01, see
//! [`crate::metrics`]) weighs every pixel alike; both fall as 1/√t.
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

use crate::metrics::{ErrorMetrics, Image, MetricsError, compare};
use crate::scene::error::SceneError;
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
}

/// Default first seed of a sweep: far from the small seeds references are made with.
pub const DEFAULT_SEED: u64 = 1_000_000;

/// One measured render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AccuracyRow {
    /// Method.
    pub method: Method,
    /// Sampler.
    pub sampler: SamplerKind,
    /// Samples per pixel.
    pub spp: u32,
    /// Seed of the render.
    pub seed: u64,
    /// Wall time of the render (scene update and BVH check included; the scene is already
    /// loaded and parsed).
    pub seconds: f64,
    /// Error against the reference.
    pub metrics: ErrorMetrics,
}

/// An error measure that falls as 1/√t for an unbiased Monte Carlo method.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Metric {
    /// Root mean squared error.
    Rmse,
    /// Square root of the relative MSE.
    RelRmse,
}

impl Metric {
    /// Both metrics, in the order reported.
    pub const ALL: [Self; 2] = [Self::Rmse, Self::RelRmse];

    /// The metric's value for one image.
    pub fn of(self, m: &ErrorMetrics) -> f64 {
        match self {
            Self::Rmse => m.rmse,
            Self::RelRmse => m.rel_mse.sqrt(),
        }
    }

    /// Its name in tables and charts.
    pub fn name(self) -> &'static str {
        match self {
            Self::Rmse => "RMSE",
            Self::RelRmse => "√relMSE",
        }
    }
}

/// The summary of one method's rows with one sampler in one metric.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MethodFit {
    /// Method.
    pub method: Method,
    /// Sampler.
    pub sampler: SamplerKind,
    /// Metric.
    pub metric: Metric,
    /// Least-squares slope of ln error against ln seconds (≈ −0.5 for Monte Carlo); `None`
    /// with fewer than two points of non-zero error.
    pub slope: Option<f64>,
    /// Geometric mean of error · √seconds over the rows: the error the method reaches in one
    /// second, if its error falls as 1/√t. 0 when the method is exact.
    pub at_one_second: f64,
}

/// What a sweep measured.
#[derive(Clone, Debug, PartialEq)]
pub struct AccuracyReport {
    /// Image width of the renders.
    pub width: u32,
    /// Image height of the renders.
    pub height: u32,
    /// Every render, in the order made.
    pub rows: Vec<AccuracyRow>,
    /// One summary per metric, method and sampler: the RMSE fits in the order the methods (then
    /// samplers) were asked, then the √relMSE fits.
    pub fits: Vec<MethodFit>,
}

/// What can go wrong in a sweep.
#[derive(Debug, thiserror::Error)]
pub enum AccuracyError {
    /// The reference could not be read.
    #[error(transparent)]
    Reference(#[from] MetricsError),
    /// The scene could not be loaded.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// Nothing to do.
    #[error("nothing to measure: give at least one spp value (all ≥ 1), method and sampler")]
    Empty,
    /// The thread pool could not be built.
    #[error("cannot start the thread pool: {0}")]
    Pool(#[from] rayon::ThreadPoolBuildError),
    /// A render produced NaN or infinite samples.
    #[error("{}: {method} at {spp} spp produced {count} non-finite samples", scene.display())]
    NonFinite {
        /// Scene file.
        scene: PathBuf,
        /// Method.
        method: Method,
        /// Samples per pixel.
        spp: u32,
        /// Dropped samples.
        count: u64,
    },
    /// An output file could not be written.
    #[error("{}: {message}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
}

/// Runs the sweep: renders every (spp, method) pair, interleaved, and compares each image with
/// the reference. `on_row` sees each row as it is measured. Writes nothing.
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
    let reference = Image::read(&options.reference)?;
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
    // Warm-up, not recorded: builds the BVH and touches every page once.
    renderer.set_overrides(overrides(curves[0], 1, options.seed));
    renderer.load(&options.scene)?;
    renderer.render_to_completion();

    let mut rows = Vec::new();
    let mut k = 0u64;
    for &spp in &options.spp_list {
        for &(method, sampler) in &curves {
            k += 1;
            let seed = options.seed.wrapping_add(k);
            renderer.set_overrides(overrides((method, sampler), spp, seed));
            renderer.load(&options.scene)?;
            let seconds = renderer.render_to_completion().as_secs_f64();
            let nonfinite = renderer.stats().nonfinite;
            if nonfinite > 0 {
                return Err(AccuracyError::NonFinite {
                    scene: options.scene.clone(),
                    method,
                    spp,
                    count: nonfinite,
                });
            }
            let image = Image::from_film(renderer.film());
            let metrics =
                compare(&image, &reference).ok_or_else(|| MetricsError::SizeMismatch {
                    path: options.scene.clone(),
                    size: (image.width, image.height),
                    reference: options.reference.clone(),
                    reference_size: (reference.width, reference.height),
                })?;
            let row = AccuracyRow {
                method,
                sampler,
                spp,
                seed,
                seconds,
                metrics,
            };
            on_row(&row);
            rows.push(row);
        }
    }
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

/// Least-squares slope of `y` against `x`; `None` with fewer than two distinct `x`.
pub fn slope(points: &[(f64, f64)]) -> Option<f64> {
    let n = points.len() as f64;
    if points.len() < 2 {
        return None;
    }
    let mx = points.iter().map(|p| p.0).sum::<f64>() / n;
    let my = points.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// The summary of the rows of `method` with `sampler` in `metric`.
pub fn fit(
    method: Method,
    sampler: SamplerKind,
    metric: Metric,
    rows: &[AccuracyRow],
) -> MethodFit {
    let mine: Vec<&AccuracyRow> = rows
        .iter()
        .filter(|r| (r.method, r.sampler) == (method, sampler))
        .collect();
    let logs: Vec<(f64, f64)> = mine
        .iter()
        .filter(|r| metric.of(&r.metrics) > 0.0 && r.seconds > 0.0)
        .map(|r| (r.seconds.ln(), metric.of(&r.metrics).ln()))
        .collect();
    let at_one_second = if mine.iter().all(|r| metric.of(&r.metrics) == 0.0) {
        0.0
    } else if logs.is_empty() {
        f64::NAN
    } else {
        (logs.iter().map(|(t, e)| e + 0.5 * t).sum::<f64>() / logs.len() as f64).exp()
    };
    MethodFit {
        method,
        sampler,
        metric,
        slope: slope(&logs),
        at_one_second,
    }
}

fn write_error(path: &Path) -> impl Fn(std::io::Error) -> AccuracyError + '_ {
    move |e| AccuracyError::Write {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// Writes `rows` as CSV with a header line.
pub fn write_csv(path: &Path, rows: &[AccuracyRow]) -> Result<(), AccuracyError> {
    // The sampler comes last, so the columns of files written before it keep their places.
    let mut text = String::from("method,spp,seed,seconds,rmse,rel_mse,mae,sampler\n");
    for r in rows {
        text += &format!(
            "{},{},{},{:.6},{:.6e},{:.6e},{:.6e},{}\n",
            r.method,
            r.spp,
            r.seed,
            r.seconds,
            r.metrics.rmse,
            r.metrics.rel_mse,
            r.metrics.mae,
            r.sampler
        );
    }
    crate::output_file::write_bytes(path, text.as_bytes()).map_err(write_error(path))
}

/// The equal-time comparison as Markdown, one table per metric: per method its slope and
/// error at one second, and against the best method its error ratio at equal time and time
/// ratio at equal error.
pub fn summary_markdown(report: &AccuracyReport) -> String {
    let mut s = String::new();
    for metric in Metric::ALL {
        let fits: Vec<&MethodFit> = report.fits.iter().filter(|f| f.metric == metric).collect();
        let best = fits
            .iter()
            .filter(|f| f.at_one_second.is_finite())
            .min_by(|a, b| a.at_one_second.total_cmp(&b.at_one_second));
        let name = metric.name();
        s += &format!(
            "| method, sampler | slope of ln {name} vs ln t | {name} · √s | error ÷ best, equal time | time ÷ best, equal error |\n|---|---|---|---|---|\n"
        );
        for f in &fits {
            let slope = f.slope.map_or("–".to_string(), |v| format!("{v:.2}"));
            let (ratio, time) = match best {
                Some(b) if b.at_one_second > 0.0 => {
                    let r = f.at_one_second / b.at_one_second;
                    (format!("{r:.2}"), format!("{:.1}", r * r))
                }
                Some(b) if f.at_one_second == b.at_one_second => ("1 (exact)".into(), "1".into()),
                _ => ("∞ (best is exact)".into(), "∞".into()),
            };
            s += &format!(
                "| {} | {slope} | {:.4e} | {ratio} | {time} |\n",
                curve_name(f),
                f.at_one_second
            );
        }
        s += "\n";
    }
    s
}

/// A curve's name in tables and legends: `mis sobol`.
fn curve_name(f: &MethodFit) -> String {
    format!("{} {}", f.method, f.sampler)
}

/// Colour of a curve: one hue per method, paler for the independent sampler.
fn colour(method: Method, sampler: SamplerKind) -> plotters::style::RGBColor {
    use plotters::style::RGBColor;
    let RGBColor(r, g, b) = match method {
        Method::Naive => RGBColor(214, 39, 40),
        Method::Nee => RGBColor(31, 119, 180),
        Method::Mis => RGBColor(44, 160, 44),
    };
    let pale = |c: u8| ((u16::from(c) + 2 * 255) / 3) as u8;
    match sampler {
        SamplerKind::Independent => RGBColor(pale(r), pale(g), pale(b)),
        SamplerKind::Sobol => RGBColor(r, g, b),
    }
}

/// Writes the log-log chart of `metric` against seconds (SVG). Rows with zero error cannot be
/// drawn on a log axis; a method that is exact everywhere is named in the legend instead.
pub fn write_chart(
    path: &Path,
    title: &str,
    metric: Metric,
    report: &AccuracyReport,
) -> Result<(), AccuracyError> {
    let mut svg = String::new();
    draw_chart(&mut svg, title, metric, report)
        .and_then(|()| Ok(crate::output_file::write_bytes(path, svg.as_bytes())?))
        .map_err(|e| AccuracyError::Write {
            path: path.to_path_buf(),
            message: e.to_string(),
        })
}

/// Draws the chart of [`write_chart`] as SVG text into `svg`.
fn draw_chart(
    svg: &mut String,
    title: &str,
    metric: Metric,
    report: &AccuracyReport,
) -> Result<(), Box<dyn std::error::Error>> {
    use plotters::prelude::*;
    let drawable: Vec<&AccuracyRow> = report
        .rows
        .iter()
        .filter(|r| metric.of(&r.metrics) > 0.0 && r.seconds > 0.0)
        .collect();
    let (mut t0, mut t1, mut e0, mut e1) = (f64::INFINITY, 0f64, f64::INFINITY, 0f64);
    for r in &drawable {
        t0 = t0.min(r.seconds);
        t1 = t1.max(r.seconds);
        e0 = e0.min(metric.of(&r.metrics));
        e1 = e1.max(metric.of(&r.metrics));
    }
    if drawable.is_empty() {
        // Everything exact: an empty frame with the legend says so.
        (t0, t1, e0, e1) = (0.01, 1.0, 1e-4, 1.0);
    }
    let root = SVGBackend::with_string(svg, (760, 520)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        // Axes in log10 units, labelled with the values: plotters' own log axis places its
        // labels unevenly.
        .build_cartesian_2d(
            (t0 / 1.6).log10()..(t1 * 1.6).log10(),
            (e0 / 1.6).log10()..(e1 * 1.6).log10(),
        )?;
    chart
        .configure_mesh()
        .x_desc("render time (s), log scale")
        .y_desc(format!(
            "{} against the reference, log scale",
            metric.name()
        ))
        .x_labels(8)
        .y_labels(8)
        .light_line_style(WHITE)
        .x_label_formatter(&|x| short(10f64.powf(*x)))
        .y_label_formatter(&|y| short(10f64.powf(*y)))
        .draw()?;
    for f in report.fits.iter().filter(|f| f.metric == metric) {
        let c = colour(f.method, f.sampler);
        let name = curve_name(f);
        let mine = |r: &AccuracyRow| (r.method, r.sampler) == (f.method, f.sampler);
        let mut points: Vec<(f64, f64, u32)> = drawable
            .iter()
            .filter(|r| mine(r))
            .map(|r| (r.seconds, metric.of(&r.metrics), r.spp))
            .collect();
        points.sort_by(|a, b| a.0.total_cmp(&b.0));
        let all = report.rows.iter().filter(|r| mine(r)).count();
        let exact = all - points.len();
        let mut label = match f.slope {
            _ if f.at_one_second == 0.0 => format!("{name}: exact (error 0, not drawn)"),
            Some(s) => format!("{name}: slope {s:.2}"),
            None => name,
        };
        if exact > 0 && f.at_one_second > 0.0 {
            label += &format!(" ({exact} of {all} renders exact, not drawn)");
        }
        chart
            .draw_series(LineSeries::new(
                points.iter().map(|p| (p.0.log10(), p.1.log10())),
                c.stroke_width(2),
            ))?
            .label(label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2)));
        chart.draw_series(points.iter().map(|&(t, e, spp)| {
            EmptyElement::at((t.log10(), e.log10()))
                + Circle::new((0, 0), 3, c.filled())
                + Text::new(
                    format!("{spp}"),
                    (4, -14),
                    ("sans-serif", 11).into_font().color(&c),
                )
        }))?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 13))
        .draw()?;
    root.present()?;
    Ok(())
}

/// A number with three significant digits, without an exponent between 0.001 and 10⁴.
fn short(v: f64) -> String {
    if v == 0.0 || !(1e-3..1e4).contains(&v.abs()) {
        return format!("{v:.2e}");
    }
    // The 1e-9 keeps 0.09999999… (= 10^−1 in floating point) in the decade of 0.1.
    let decimals = (2 - (v.abs() * (1.0 + 1e-9)).log10().floor() as i32).max(0) as usize;
    format!("{v:.decimals$}")
}

/// Runs [`measure`] and writes `accuracy.csv`, `accuracy.svg` and `summary.md` in
/// `options.out`. Returns the report.
pub fn run(
    options: &AccuracyOptions,
    on_row: impl FnMut(&AccuracyRow),
) -> Result<AccuracyReport, AccuracyError> {
    std::fs::create_dir_all(&options.out).map_err(write_error(&options.out))?;
    let report = measure(options, on_row)?;
    write_csv(&options.out.join("accuracy.csv"), &report.rows)?;
    let name = options
        .scene
        .file_stem()
        .map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned());
    let title = |metric: Metric| {
        format!(
            "{name}: {} against time ({}×{}, spp at each point)",
            metric.name(),
            report.width,
            report.height
        )
    };
    write_chart(
        &options.out.join("accuracy.svg"),
        &title(Metric::Rmse),
        Metric::Rmse,
        &report,
    )?;
    write_chart(
        &options.out.join("accuracy_relative.svg"),
        &title(Metric::RelRmse),
        Metric::RelRmse,
        &report,
    )?;
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

    fn row(method: Method, seconds: f64, rmse: f64) -> AccuracyRow {
        AccuracyRow {
            method,
            sampler: SamplerKind::Sobol,
            spp: 1,
            seed: 0,
            seconds,
            metrics: ErrorMetrics {
                rmse,
                ..Default::default()
            },
        }
    }

    #[test]
    fn fit_recovers_the_slope_and_the_error_at_one_second() {
        let rows: Vec<AccuracyRow> = [0.5, 1.0, 2.0, 4.0]
            .iter()
            .map(|&t: &f64| row(Method::Mis, t, 0.3 / t.sqrt()))
            .collect();
        let f = fit(Method::Mis, SamplerKind::Sobol, Metric::Rmse, &rows);
        assert!((f.slope.expect("slope") + 0.5).abs() < 1e-9);
        assert!((f.at_one_second - 0.3).abs() < 1e-9);
    }

    #[test]
    fn axis_labels_keep_three_significant_digits() {
        assert_eq!(short(0.012345), "0.0123");
        assert_eq!(short(1.5), "1.50");
        assert_eq!(short(250.0), "250");
        assert_eq!(short(1e-5), "1.00e-5");
        assert_eq!(short(10f64.powf(-1.0)), "0.100");
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
