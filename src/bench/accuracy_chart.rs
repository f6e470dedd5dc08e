//! The `bench accuracy` chart: error against render time on log-log axes, one solid line per
//! method and sampler (its fitted slope in the legend, spp at each point) and, when the sweep
//! denoised, a dashed line of triangles beside it for the denoised renders ("mis sobol +
//! denoiser"). A denoised curve gets no slope: the denoiser is biased, so its error does not
//! fall as a power of time and a fitted slope would be no convergence rate. SVG via plotters'
//! SVG backend (no font files: the viewer draws the text).

use std::path::Path;

use plotters::element::DashedPathElement;
use plotters::prelude::*;

use super::accuracy_rows::{AccuracyError, AccuracyReport, AccuracyRow, Metric, curve_name};
use crate::scene::format::Method;
use crate::shading::sampler::SamplerKind;

/// Colour of a curve: one hue per method, paler for the independent sampler.
fn colour(method: Method, sampler: SamplerKind) -> RGBColor {
    let RGBColor(r, g, b) = match method {
        Method::Naive => RGBColor(214, 39, 40),
        Method::Nee => RGBColor(31, 119, 180),
        Method::Mis => RGBColor(44, 160, 44),
        Method::Caustics => RGBColor(148, 103, 189),
        Method::Photons => RGBColor(255, 127, 14),
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
    let drawable: Vec<&AccuracyRow> = report
        .rows
        .iter()
        .filter(|r| metric.of(r) > 0.0 && r.seconds > 0.0)
        .collect();
    let (mut t0, mut t1, mut e0, mut e1) = (f64::INFINITY, 0f64, f64::INFINITY, 0f64);
    for r in &drawable {
        t0 = t0.min(r.seconds);
        t1 = t1.max(r.seconds);
        e0 = e0.min(metric.of(r));
        e1 = e1.max(metric.of(r));
    }
    if drawable.is_empty() {
        // Everything exact: an empty frame with the legend says so.
        (t0, t1, e0, e1) = (0.01, 1.0, 1e-4, 1.0);
    }
    let root = SVGBackend::with_string(svg, (880, 560)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 16))
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
        let name = curve_name(f.method, f.sampler);
        let mine = |r: &AccuracyRow, denoised: bool| {
            (r.method, r.sampler, r.denoised) == (f.method, f.sampler, denoised)
        };
        let points = |denoised: bool| {
            let mut p: Vec<(f64, f64, u32)> = drawable
                .iter()
                .filter(|r| mine(r, denoised))
                .map(|r| (r.seconds, metric.of(r), r.spp))
                .collect();
            p.sort_by(|a, b| a.0.total_cmp(&b.0));
            p
        };
        let raw = points(false);
        let all = report.rows.iter().filter(|r| mine(r, false)).count();
        let exact = all - raw.len();
        let mut label = match f.slope {
            _ if f.at_one_second == 0.0 => format!("{name}: exact (error 0, not drawn)"),
            Some(s) => format!("{name}: slope {s:.2}"),
            None => name.clone(),
        };
        if exact > 0 && f.at_one_second > 0.0 {
            label += &format!(" ({exact} of {all} renders exact, not drawn)");
        }
        chart
            .draw_series(LineSeries::new(
                raw.iter().map(|p| (p.0.log10(), p.1.log10())),
                c.stroke_width(2),
            ))?
            .label(label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2)));
        chart.draw_series(raw.iter().map(|&(t, e, spp)| {
            EmptyElement::at((t.log10(), e.log10()))
                + Circle::new((0, 0), 3, c.filled())
                + Text::new(
                    format!("{spp}"),
                    (4, -14),
                    ("sans-serif", 11).into_font().color(&c),
                )
        }))?;
        let denoised = points(true);
        if denoised.is_empty() {
            continue;
        }
        chart
            .draw_series(DashedLineSeries::new(
                denoised.iter().map(|p| (p.0.log10(), p.1.log10())),
                8,
                5,
                c.stroke_width(2),
            ))?
            .label(format!("{name} + denoiser (biased: no slope)"))
            .legend(move |(x, y)| {
                DashedPathElement::new(vec![(x, y), (x + 18, y)], 5, 3, c.stroke_width(2))
            });
        chart.draw_series(denoised.iter().map(|&(t, e, spp)| {
            EmptyElement::at((t.log10(), e.log10()))
                + TriangleMarker::new((0, 0), 4, c.filled())
                + Text::new(
                    format!("{spp}"),
                    (4, 4),
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
pub fn short(v: f64) -> String {
    if v == 0.0 || !(1e-3..1e4).contains(&v.abs()) {
        return format!("{v:.2e}");
    }
    // The 1e-9 keeps 0.09999999… (= 10^−1 in floating point) in the decade of 0.1.
    let decimals = (2 - (v.abs() * (1.0 + 1e-9)).log10().floor() as i32).max(0) as usize;
    format!("{v:.decimals$}")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::accuracy_rows::MethodFit;

    #[test]
    fn axis_labels_keep_three_significant_digits() {
        assert_eq!(short(0.012345), "0.0123");
        assert_eq!(short(1.5), "1.50");
        assert_eq!(short(250.0), "250");
        assert_eq!(short(1e-5), "1.00e-5");
        assert_eq!(short(10f64.powf(-1.0)), "0.100");
    }

    #[test]
    fn denoised_renders_are_a_dashed_curve_without_a_slope() {
        let row = crate::bench::accuracy_rows::test_row;
        let fit = MethodFit {
            method: Method::Mis,
            sampler: SamplerKind::Sobol,
            metric: Metric::Rmse,
            slope: Some(-0.5),
            at_one_second: 0.1,
        };
        let mut report = AccuracyReport {
            width: 1,
            height: 1,
            rows: vec![row(false, 1, 1.0, 0.1), row(false, 4, 4.0, 0.05)],
            fits: vec![fit],
        };
        let mut raw_only = String::new();
        draw_chart(&mut raw_only, "t", Metric::Rmse, &report).expect("chart");
        assert!(!raw_only.contains("denoiser"), "{raw_only}");
        assert!(!raw_only.contains("stroke-dasharray"));
        report
            .rows
            .extend([row(true, 1, 1.2, 0.03), row(true, 4, 4.3, 0.02)]);
        let mut svg = String::new();
        draw_chart(&mut svg, "t", Metric::Rmse, &report).expect("chart");
        assert!(svg.contains("mis sobol: slope -0.50"), "{svg}");
        assert!(
            svg.contains("mis sobol + denoiser (biased: no slope)"),
            "{svg}"
        );
        // The denoised line is drawn in dashes: more line pieces than the raw curve's one.
        assert!(
            svg.matches("<polyline").count() > raw_only.matches("<polyline").count() + 2,
            "{svg}"
        );
    }
}
