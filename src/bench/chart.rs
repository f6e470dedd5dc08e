//! The `bench layout` chart: one row per workload; on the left each layout's throughput, on the
//! right its ratio to AoS with the spread of the rounds. Primitive count on a log axis. SVG via
//! plotters' SVG backend (no font files: the viewer draws the text).

use std::error::Error;
use std::path::Path;

use plotters::prelude::*;

use super::layout_rows::{Kind, Row, WORKLOADS, spread};
use crate::geometry::layout::LayoutKind;

const KINDS: [Kind; 2] = [Kind::Sphere, Kind::Triangle];

fn colour(layout: LayoutKind) -> RGBColor {
    match layout {
        LayoutKind::Soa => RGBColor(31, 119, 180),
        LayoutKind::Aos => RGBColor(214, 39, 40),
        LayoutKind::SoaSimd => RGBColor(44, 160, 44),
        LayoutKind::Hybrid => RGBColor(148, 103, 189),
    }
}

/// Points of one series, ascending in count: `(count, median, min, max)` of `values(row)`.
fn series(
    rows: &[Row],
    workload: &str,
    kind: Kind,
    layout: LayoutKind,
    values: impl Fn(&Row) -> &[f64],
) -> Vec<(f64, f64, f64, f64)> {
    let mut points: Vec<_> = rows
        .iter()
        .filter(|r| r.workload == workload && r.kind == kind && r.layout == layout)
        .map(|r| {
            let (m, lo, hi) = spread(values(r));
            (r.count as f64, m, lo, hi)
        })
        .filter(|p| p.1.is_finite())
        .collect();
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    points
}

/// Draws one series: a line (dashed for triangles) with a marker per point (circles for
/// spheres, triangles for triangles), labelled for the legend.
fn draw_series<'a, DB: DrawingBackend + 'a, Y: Ranged<ValueType = f64>>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<LogCoord<f64>, Y>>,
    points: &[(f64, f64)],
    kind: Kind,
    layout: LayoutKind,
) -> Result<(), Box<dyn Error>>
where
    DB::ErrorType: 'static,
{
    let style = colour(layout).stroke_width(2);
    let label = format!("{} {}", layout.name(), kind.name());
    let c = colour(layout);
    match kind {
        Kind::Sphere => {
            chart
                .draw_series(LineSeries::new(points.iter().copied(), style))?
                .label(label)
                .legend(move |(x, y)| {
                    EmptyElement::at((x, y))
                        + PathElement::new(vec![(0, 0), (18, 0)], c.stroke_width(2))
                        + Circle::new((9, 0), 4, c.filled())
                });
        }
        Kind::Triangle => {
            chart
                .draw_series(DashedLineSeries::new(points.iter().copied(), 6, 4, style))?
                .label(label)
                .legend(move |(x, y)| {
                    EmptyElement::at((x, y))
                        + PathElement::new(vec![(0, 0), (5, 0)], c.stroke_width(2))
                        + PathElement::new(vec![(13, 0), (18, 0)], c.stroke_width(2))
                        + TriangleMarker::new((9, 0), 5, c.filled())
                });
        }
    }
    let fill = colour(layout).filled();
    match kind {
        Kind::Sphere => {
            chart.draw_series(points.iter().map(|&p| Circle::new(p, 4, fill)))?;
        }
        Kind::Triangle => {
            chart.draw_series(points.iter().map(|&p| TriangleMarker::new(p, 5, fill)))?;
        }
    }
    Ok(())
}

/// Writes the chart of `rows` to `path` (SVG).
pub fn layout_chart(path: &Path, rows: &[Row]) -> Result<(), Box<dyn Error>> {
    let mut svg = String::new();
    draw_layout_chart(&mut svg, rows)?;
    Ok(crate::output_file::write_bytes(path, svg.as_bytes())?)
}

/// Draws the chart of [`layout_chart`] as SVG text into `svg`.
fn draw_layout_chart(svg: &mut String, rows: &[Row]) -> Result<(), Box<dyn Error>> {
    let counts: Vec<f64> = rows.iter().map(|r| r.count as f64).collect();
    let (x_min, x_max) = counts
        .iter()
        .fold((f64::INFINITY, 0f64), |(a, b), &c| (a.min(c), b.max(c)));
    if !(x_min.is_finite() && x_max > 0.0) {
        return Err("no rows to chart".into());
    }
    let x_range = (x_min / 1.5)..(x_max * 1.5);

    let height = 360 * WORKLOADS.len() as u32 + 50;
    let root = SVGBackend::with_string(svg, (1300, height)).into_drawing_area();
    root.fill(&WHITE)?;
    let (title, body) = root.split_vertically(50);
    title.titled(
        "rondo bench layout: SoA vs AoS (and SoA with SIMD lanes, and the hybrid), one thread, CPU time",
        ("sans-serif", 24),
    )?;
    let panels = body.split_evenly((WORKLOADS.len(), 2));
    for (i, (workload, unit)) in WORKLOADS.iter().enumerate() {
        // Left: throughput, log-log.
        let mut lo = f64::INFINITY;
        let mut hi = 0f64;
        for r in rows.iter().filter(|r| r.workload == *workload) {
            let (m, _, _) = spread(&r.runs);
            if m.is_finite() && m > 0.0 {
                lo = lo.min(m);
                hi = hi.max(m);
            }
        }
        if !(lo.is_finite() && hi > 0.0) {
            continue;
        }
        let mut chart = ChartBuilder::on(&panels[2 * i])
            .caption(format!("{workload}: throughput"), ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(70)
            .build_cartesian_2d(
                x_range.clone().log_scale(),
                (lo / 1.5..hi * 1.5).log_scale(),
            )?;
        chart
            .configure_mesh()
            .x_desc("primitives")
            .y_desc(*unit)
            .y_labels(6)
            .x_label_formatter(&|x| format!("{x:.0e}"))
            .y_label_formatter(&|y| format!("{y:.0e}"))
            .draw()?;
        for kind in KINDS {
            for layout in LayoutKind::ALL {
                let points: Vec<(f64, f64)> = series(rows, workload, kind, layout, |r| &r.runs)
                    .iter()
                    .map(|p| (p.0, p.1))
                    .collect();
                draw_series(&mut chart, &points, kind, layout)?;
            }
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerLeft)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .label_font(("sans-serif", 12))
            .draw()?;

        // Right: ratio to AoS with [min, max] over the rounds.
        let mut lo = 1f64;
        let mut hi = 1f64;
        for r in rows.iter().filter(|r| r.workload == *workload) {
            let (_, a, b) = spread(&r.ratios);
            if a.is_finite() && b.is_finite() {
                lo = lo.min(a);
                hi = hi.max(b);
            }
        }
        let pad = 0.05 * (hi - lo).max(0.1);
        let mut chart = ChartBuilder::on(&panels[2 * i + 1])
            .caption(
                format!("{workload}: throughput / AoS (median, min–max of rounds)"),
                ("sans-serif", 18),
            )
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(50)
            .build_cartesian_2d(x_range.clone().log_scale(), (lo - pad)..(hi + pad))?;
        chart
            .configure_mesh()
            .x_desc("primitives")
            .y_desc("× AoS")
            .x_label_formatter(&|x| format!("{x:.0e}"))
            .draw()?;
        chart
            .draw_series(LineSeries::new(
                [(x_range.start, 1.0), (x_range.end, 1.0)],
                colour(LayoutKind::Aos).stroke_width(2),
            ))?
            .label("aos (= 1)")
            .legend(|(x, y)| {
                PathElement::new(
                    vec![(x, y), (x + 18, y)],
                    colour(LayoutKind::Aos).stroke_width(2),
                )
            });
        for kind in KINDS {
            for layout in [LayoutKind::Soa, LayoutKind::SoaSimd, LayoutKind::Hybrid] {
                let s = series(rows, workload, kind, layout, |r| &r.ratios);
                let points: Vec<(f64, f64)> = s.iter().map(|p| (p.0, p.1)).collect();
                draw_series(&mut chart, &points, kind, layout)?;
                chart.draw_series(s.iter().map(|&(x, m, a, b)| {
                    ErrorBar::new_vertical(x, a, m, b, colour(layout).stroke_width(1), 8)
                }))?;
            }
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .label_font(("sans-serif", 12))
            .draw()?;
    }
    root.present()?;
    Ok(())
}
