//! `summary.md` of `bench accuracy`: the equal-time comparison of the raw renders in every
//! metric and, when the sweep denoised, the denoised measurements and the error level from
//! which on the raw render is the better choice ([`crossover`]).

use super::accuracy_chart::short;
use super::accuracy_rows::{AccuracyReport, AccuracyRow, MethodFit, Metric, curve_name, slope};
use crate::scene::format::Method;
use crate::shading::sampler::SamplerKind;

/// Where, for one method and sampler in one metric, the raw render becomes the better choice.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Crossover {
    /// At `spp`, the smallest swept value at which the denoised render's error (`error`, after
    /// `denoised_seconds` of render and denoise) is no lower than the raw renders' fitted line
    /// at the same time. The raw line reaches `error` after `raw_seconds`: from `error` down,
    /// the raw render is the better choice.
    At {
        /// Samples per pixel of the denoised render.
        spp: u32,
        /// Its error.
        error: f64,
        /// Its time, render and denoise.
        denoised_seconds: f64,
        /// The time at which the raw fitted line reaches `error`.
        raw_seconds: f64,
    },
    /// The denoised render is the better choice at every spp of the sweep.
    NotWithinSweep,
    /// No falling line fits the raw renders (none with a non-zero error, or an error that does
    /// not fall with time).
    NoFit,
}

/// The raw renders' fitted line of `method` with `sampler` in `metric`, as `(a, b)` with
/// `ln error = a + b · ln seconds`: least squares over the raw rows of non-zero error; with a
/// single time, the 1/√t line through its rows. `None` without such rows, or if the line does
/// not fall.
pub fn raw_line(
    method: Method,
    sampler: SamplerKind,
    metric: Metric,
    rows: &[AccuracyRow],
) -> Option<(f64, f64)> {
    let logs: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| (r.method, r.sampler, r.denoised) == (method, sampler, false))
        .filter(|r| metric.of(r) > 0.0 && metric.of(r).is_finite() && r.seconds > 0.0)
        .map(|r| (r.seconds.ln(), metric.of(r).ln()))
        .collect();
    if logs.is_empty() {
        return None;
    }
    let n = logs.len() as f64;
    let mx = logs.iter().map(|p| p.0).sum::<f64>() / n;
    let my = logs.iter().map(|p| p.1).sum::<f64>() / n;
    let b = slope(&logs).unwrap_or(-0.5);
    (b < 0.0).then_some((my - b * mx, b))
}

/// Where the raw render of `method` with `sampler` becomes the better choice than its denoised
/// twin in `metric`: the smallest swept spp at which the denoised error is at least the raw
/// fitted line's ([`raw_line`]) at the denoised render's time. `None` without denoised rows.
pub fn crossover(
    method: Method,
    sampler: SamplerKind,
    metric: Metric,
    rows: &[AccuracyRow],
) -> Option<Crossover> {
    let mut denoised: Vec<&AccuracyRow> = rows
        .iter()
        .filter(|r| (r.method, r.sampler, r.denoised) == (method, sampler, true))
        .collect();
    if denoised.is_empty() {
        return None;
    }
    let Some((a, b)) = raw_line(method, sampler, metric, rows) else {
        return Some(Crossover::NoFit);
    };
    denoised.sort_by_key(|r| r.spp);
    let found = denoised
        .iter()
        .find(|r| r.seconds > 0.0 && metric.of(r) >= (a + b * r.seconds.ln()).exp());
    Some(match found {
        Some(r) => Crossover::At {
            spp: r.spp,
            error: metric.of(r),
            denoised_seconds: r.seconds,
            raw_seconds: ((metric.of(r).ln() - a) / b).exp(),
        },
        None => Crossover::NotWithinSweep,
    })
}

/// The sentence of `summary.md` for a crossover.
fn crossover_text(c: Crossover) -> String {
    match c {
        Crossover::At {
            spp,
            error,
            denoised_seconds,
            raw_seconds,
        } => format!(
            "from error {e} on (≤ {e}, reached by raw at about {t} s), the raw render is the \
             better choice (denoised at {spp} spp: {e} after {d} s)",
            e = short(error),
            t = short(raw_seconds),
            d = short(denoised_seconds),
        ),
        Crossover::NotWithinSweep => {
            "not within the sweep: the denoised render is better at every spp measured".into()
        }
        Crossover::NoFit => "no falling line fits the raw renders: no crossover".into(),
    }
}

/// The equal-time comparison as Markdown, one table per metric: per method its slope and
/// error at one second, and against the best method its error ratio at equal time and time
/// ratio at equal error; then, if the sweep denoised, the denoised rows and per metric the
/// crossover of each method and sampler.
pub fn summary_markdown(report: &AccuracyReport) -> String {
    let mut s = String::new();
    for metric in Metric::ALL {
        let fits: Vec<&MethodFit> = report.fits.iter().filter(|f| f.metric == metric).collect();
        if fits.is_empty() {
            continue;
        }
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
                curve_name(f.method, f.sampler),
                f.at_one_second
            );
        }
        s += "\n";
    }
    s += &fireflies_markdown(report);
    if report.rows.iter().any(|r| r.denoised) {
        s += &denoised_markdown(report);
    }
    s
}

/// The fireflies of the raw renders ([`crate::metrics::fireflies`]) as a Markdown table: a
/// row per method and sampler, a column per spp.
fn fireflies_markdown(report: &AccuracyReport) -> String {
    let raw = || report.rows.iter().filter(|r| !r.denoised);
    let mut spps: Vec<u32> = raw().map(|r| r.spp).collect();
    spps.sort_unstable();
    spps.dedup();
    let mut curves: Vec<(Method, SamplerKind)> = Vec::new();
    for r in raw() {
        if !curves.contains(&(r.method, r.sampler)) {
            curves.push((r.method, r.sampler));
        }
    }
    if curves.is_empty() {
        return String::new();
    }
    let mut s = String::from(
        "Fireflies: pixels whose channel mean exceeds 4× the reference's (and it by more than \
         0.1).\n\n| method, sampler |",
    );
    for spp in &spps {
        s += &format!(" {spp} spp |");
    }
    s += &format!("\n|---|{}\n", "---|".repeat(spps.len()));
    for (m, sampler) in curves {
        s += &format!("| {} |", curve_name(m, sampler));
        for &spp in &spps {
            match raw().find(|r| (r.method, r.sampler, r.spp) == (m, sampler, spp)) {
                Some(r) => s += &format!(" {} |", r.fireflies),
                None => s += " – |",
            }
        }
        s += "\n";
    }
    s + "\n"
}

/// The denoised part of [`summary_markdown`].
fn denoised_markdown(report: &AccuracyReport) -> String {
    let mut s = String::from(
        "## Denoised (Open Image Denoise, quality high, guided by albedo and normal)\n\n\
         The denoiser is biased: its error does not fall as 1/√t, so its renders get no slope \
         and no error · √s. Each time is the render with the feature buffers plus the denoise, \
         wall clock; each image is the raw render of the same seed, denoised.\n\n",
    );
    s += "| method, sampler | spp | render + denoise (s) |";
    for metric in Metric::ALL {
        s += &format!(" {} |", metric.name());
    }
    s += "\n|---|---|---|---|---|---|\n";
    for r in report.rows.iter().filter(|r| r.denoised) {
        s += &format!(
            "| {} | {} | {:.3} |",
            curve_name(r.method, r.sampler),
            r.spp,
            r.seconds
        );
        for metric in Metric::ALL {
            s += &format!(" {:.4e} |", metric.of(r));
        }
        s += "\n";
    }
    s += "\n### When the raw render is the better choice\n\n\
          Per metric: the smallest swept spp at which the denoised error is no lower than the \
          raw renders' fitted line (ln error against ln time) at the same time.\n\n\
          | method, sampler | metric | crossover |\n|---|---|---|\n";
    let mut curves: Vec<(Method, SamplerKind)> = Vec::new();
    for r in report.rows.iter().filter(|r| r.denoised) {
        if !curves.contains(&(r.method, r.sampler)) {
            curves.push((r.method, r.sampler));
        }
    }
    for metric in Metric::ALL {
        for &(m, sampler) in &curves {
            if let Some(c) = crossover(m, sampler, metric, &report.rows) {
                s += &format!(
                    "| {} | {} | {} |\n",
                    curve_name(m, sampler),
                    metric.name(),
                    crossover_text(c)
                );
            }
        }
    }
    s + "\n"
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::bench::accuracy_rows::test_row as row;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-9 * b.abs().max(1.0)
    }

    fn at(c: Option<Crossover>) -> (u32, f64, f64, f64) {
        match c {
            Some(Crossover::At {
                spp,
                error,
                denoised_seconds,
                raw_seconds,
            }) => (spp, error, denoised_seconds, raw_seconds),
            other => panic!("no crossover: {other:?}"),
        }
    }

    #[test]
    fn the_crossover_is_the_first_spp_where_the_raw_line_is_no_worse() {
        // Raw: 0.1 after 1 s, 0.05 after 4 s: the line 0.1 / √t.
        // Denoised: 1 spp, 0.05 after 0.5 s (raw line there: 0.1 / √0.5 = 0.1414, worse);
        // 2 spp, 0.08 after 1 s (raw 0.1, worse); 4 spp, 0.08 after 2 s (raw 0.0707, better:
        // the crossover); 8 spp, 0.01 after 4 s (raw 0.05, worse); 16 spp, 0.05 after 8 s (raw
        // 0.0354, better: a crossover too, but not the first).
        // The raw line reaches 0.08 at t = (0.1 / 0.08)² = 1.5625 s.
        let rows = [
            row(false, 1, 1.0, 0.1),
            row(false, 4, 4.0, 0.05),
            row(true, 1, 0.5, 0.05),
            row(true, 2, 1.0, 0.08),
            row(true, 4, 2.0, 0.08),
            row(true, 8, 4.0, 0.01),
            row(true, 16, 8.0, 0.05),
        ];
        let (spp, error, denoised, raw) = at(crossover(
            Method::Mis,
            SamplerKind::Sobol,
            Metric::Rmse,
            &rows,
        ));
        assert_eq!(spp, 4);
        assert!(
            close(error, 0.08) && close(denoised, 2.0),
            "{error} {denoised}"
        );
        assert!(close(raw, 1.5625), "{raw}");
        // The same in the lamp-out metric (equal values here).
        let (spp, ..) = at(crossover(
            Method::Mis,
            SamplerKind::Sobol,
            Metric::LampOutRmse,
            &rows,
        ));
        assert_eq!(spp, 4);
    }

    #[test]
    fn the_crossover_uses_the_fitted_slope_not_one_over_root_t() {
        // Raw: 0.1 after 1 s, 0.01 after 10 s: slope −1, the line 0.1 / t.
        // Denoised: 0.03 after 5 s; the raw line there is 0.02, better. The raw line reaches
        // 0.03 at t = 0.1 / 0.03 = 3.333… s (a 1/√t line through the rows, 0.0562 / √t, would
        // give 3.51 s).
        let rows = [
            row(false, 1, 1.0, 0.1),
            row(false, 10, 10.0, 0.01),
            row(true, 4, 5.0, 0.03),
        ];
        let line = raw_line(Method::Mis, SamplerKind::Sobol, Metric::Rmse, &rows).expect("line");
        assert!(
            close(line.0, 0.1f64.ln()) && close(line.1, -1.0),
            "{line:?}"
        );
        let (spp, _, _, raw) = at(crossover(
            Method::Mis,
            SamplerKind::Sobol,
            Metric::Rmse,
            &rows,
        ));
        assert_eq!(spp, 4);
        assert!(close(raw, 0.1 / 0.03), "{raw}");
    }

    #[test]
    fn a_denoiser_better_everywhere_has_no_crossover_within_the_sweep() {
        let rows = [
            row(false, 1, 1.0, 0.1),
            row(false, 4, 4.0, 0.05),
            row(true, 1, 0.5, 0.05),
            row(true, 2, 1.0, 0.08),
        ];
        let c = crossover(Method::Mis, SamplerKind::Sobol, Metric::Rmse, &rows);
        assert_eq!(c, Some(Crossover::NotWithinSweep));
        assert_eq!(
            crossover(Method::Nee, SamplerKind::Sobol, Metric::Rmse, &rows),
            None
        );
    }

    #[test]
    fn the_summary_says_the_denoiser_is_biased_and_gives_the_crossover() {
        let rows = vec![
            row(false, 1, 1.0, 0.1),
            row(false, 4, 4.0, 0.05),
            row(true, 1, 0.5, 0.05),
            row(true, 4, 2.0, 0.08),
        ];
        let fits = Metric::ALL
            .iter()
            .map(|&m| super::super::accuracy_rows::fit(Method::Mis, SamplerKind::Sobol, m, &rows))
            .collect();
        let md = summary_markdown(&AccuracyReport {
            width: 1,
            height: 1,
            rows,
            fits,
        });
        assert!(md.contains("The denoiser is biased"), "{md}");
        assert!(
            md.contains(
                "| mis sobol | lamp-out RMSE | from error 0.0800 on (≤ 0.0800, reached by raw at \
                 about 1.56 s), the raw render is the better choice (denoised at 4 spp: 0.0800 \
                 after 2.00 s) |"
            ),
            "{md}"
        );
        // The raw table holds the raw curve only, its slope untouched by the denoised rows.
        assert!(
            md.contains("| mis sobol | -0.50 | 1.0000e-1 | 1.00 | 1.0 |"),
            "{md}"
        );
    }

    #[test]
    fn the_summary_counts_each_curves_fireflies_per_spp() {
        // mis at 1 and 4 spp with 9 and 2 fireflies; caustics at 4 spp only, with none; a
        // denoised row (its 50 not counted).
        let mis = |spp, fireflies| AccuracyRow {
            fireflies,
            ..row(false, spp, 1.0, 0.1)
        };
        let rows = vec![
            mis(1, 9),
            mis(4, 2),
            AccuracyRow {
                method: Method::Caustics,
                ..mis(4, 0)
            },
            AccuracyRow {
                fireflies: 50,
                ..row(true, 4, 1.0, 0.1)
            },
        ];
        let md = summary_markdown(&AccuracyReport {
            width: 1,
            height: 1,
            rows,
            fits: Vec::new(),
        });
        assert!(md.contains("| method, sampler | 1 spp | 4 spp |"), "{md}");
        assert!(md.contains("| mis sobol | 9 | 2 |"), "{md}");
        assert!(md.contains("| caustics sobol | – | 0 |"), "{md}");
    }
}
