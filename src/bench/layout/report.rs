//! The outputs of `rondo bench layout`: the CSV of every run and the Markdown table.

use std::fmt::Write as _;
use std::time::Duration;

use super::options::Options;
use crate::bench::layout_rows::{Kind, Row, WORKLOADS, spread};
use crate::geometry::layout::LayoutKind;

/// What a point measured besides the rows.
#[derive(Clone, Copy, Debug)]
pub(super) struct Note {
    pub(super) kind: Kind,
    pub(super) count: usize,
    /// BVH build time (both kinds' BVHs; one kind is empty).
    pub(super) bvh: Duration,
    /// Mean primitives per BVH leaf visited.
    pub(super) mean_leaf: f64,
}

pub(super) fn write_csv(options: &Options, rows: &[Row]) -> std::io::Result<()> {
    let mut csv = String::from(
        "workload,kind,count,layout,unit,runs,median,min,max,\
         ratio_vs_aos_median,ratio_vs_aos_min,ratio_vs_aos_max\n",
    );
    for r in rows {
        let (m, lo, hi) = spread(&r.runs);
        let (rm, rlo, rhi) = spread(&r.ratios);
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{},{m:.6e},{lo:.6e},{hi:.6e},{rm:.4},{rlo:.4},{rhi:.4}",
            r.workload,
            r.kind.name(),
            r.count,
            r.layout.name(),
            r.unit,
            r.runs.len(),
        );
    }
    crate::output_file::write_bytes(&options.out.join("layout.csv"), csv.as_bytes())
}

/// The model name of the first CPU, from `/proc/cpuinfo` where there is one.
pub(super) fn cpu_name() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|s| s.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into())
}

/// `layout.md`: per workload and kind, each layout's ratio to AoS at every count.
pub(super) fn markdown(
    options: &Options,
    rows: &[Row],
    notes: &[Note],
    elapsed: Duration,
) -> String {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut md = String::new();
    let _ = writeln!(
        md,
        "Measured by `{}` on {} ({} hardware threads; every workload runs on one), {} build, \
         {:.0} s in all. Cells: throughput ratio to AoS, median of the rounds [min, max]; \
         > 1 means faster than AoS. Rounds per point: {} up to 10⁴ primitives, {} up to 10⁵, \
         {} above.\n",
        if options.command.is_empty() {
            "rondo bench layout"
        } else {
            &options.command
        },
        cpu_name(),
        threads,
        if cfg!(debug_assertions) {
            "debug"
        } else {
            "release"
        },
        elapsed.as_secs_f64(),
        options.reps_at(1),
        options.reps_at(100_000),
        options.reps_at(usize::MAX),
    );
    let _ = write!(md, "| workload | kind | layout |");
    for c in &options.counts {
        let _ = write!(md, " {c} |");
    }
    let _ = write!(md, "\n|---|---|---|");
    for _ in &options.counts {
        let _ = write!(md, "---|");
    }
    md.push('\n');
    for (workload, _) in WORKLOADS {
        for kind in [Kind::Sphere, Kind::Triangle] {
            for layout in [LayoutKind::Soa, LayoutKind::SoaSimd, LayoutKind::Hybrid] {
                let _ = write!(
                    md,
                    "| {workload} | {} | {}/aos |",
                    kind.name(),
                    layout.name()
                );
                for &c in &options.counts {
                    let cell = rows
                        .iter()
                        .find(|r| {
                            r.workload == workload
                                && r.kind == kind
                                && r.count == c
                                && r.layout == layout
                        })
                        .map(|r| {
                            let (m, lo, hi) = spread(&r.ratios);
                            format!("{m:.2} [{lo:.2}, {hi:.2}]")
                        })
                        .unwrap_or_default();
                    let _ = write!(md, " {cell} |");
                }
                md.push('\n');
            }
        }
    }
    let _ = write!(
        md,
        "\nAoS throughput (median):\n\n| workload | kind | unit |"
    );
    for c in &options.counts {
        let _ = write!(md, " {c} |");
    }
    let _ = write!(md, "\n|---|---|---|");
    for _ in &options.counts {
        let _ = write!(md, "---|");
    }
    md.push('\n');
    for (workload, unit) in WORKLOADS {
        for kind in [Kind::Sphere, Kind::Triangle] {
            let _ = write!(md, "| {workload} | {} | {unit} |", kind.name());
            for &c in &options.counts {
                let cell = rows
                    .iter()
                    .find(|r| {
                        r.workload == workload
                            && r.kind == kind
                            && r.count == c
                            && r.layout == LayoutKind::Aos
                    })
                    .map(|r| format!("{:.3e}", spread(&r.runs).0))
                    .unwrap_or_default();
                let _ = write!(md, " {cell} |");
            }
            md.push('\n');
        }
    }
    let _ = write!(
        md,
        "\nBVH build (the same for every layout, not in `extract`) in ms, and mean primitives per \
         leaf visited:"
    );
    for n in notes {
        let _ = write!(
            md,
            " {} {}: {:.1} ms, {:.2};",
            n.kind.name(),
            n.count,
            n.bvh.as_secs_f64() * 1e3,
            n.mean_leaf
        );
    }
    md.push('\n');
    md
}
