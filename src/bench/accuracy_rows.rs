//! The measured rows of `rondo bench accuracy` and what is computed from them: the error
//! metrics, the fit of each curve, the report and the sweep's errors. Shared by the run
//! ([`super::accuracy`]), its chart ([`super::accuracy_chart`]) and its summary
//! ([`super::accuracy_summary`]).

use std::path::PathBuf;

use crate::denoise::DenoiseError;
use crate::metrics::{ErrorMetrics, MetricsError};
use crate::scene::error::SceneError;
use crate::scene::format::Method;
use crate::shading::sampler::SamplerKind;

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
    /// loaded and parsed), plus that of the denoise for a denoised row.
    pub seconds: f64,
    /// Error against the reference.
    pub metrics: ErrorMetrics,
    /// Lamp-out clamped RMSE against the reference
    /// ([`lamp_out_rmse`](crate::metrics::lamp_out_rmse)).
    pub lamp_out_rmse: f64,
    /// Pixels far brighter than the reference's ([`fireflies`](crate::metrics::fireflies)).
    pub fireflies: usize,
    /// Whether the image measured is the denoised one.
    pub denoised: bool,
}

impl AccuracyRow {
    /// The file name of the row's image in `keep_images`:
    /// `<method>_<sampler>_<spp>spp[_denoised].exr`.
    pub fn image_name(&self) -> String {
        format!(
            "{}_{}_{}spp{}.exr",
            self.method,
            self.sampler,
            self.spp,
            if self.denoised { "_denoised" } else { "" }
        )
    }
}

/// An error measure that falls as 1/√t for an unbiased Monte Carlo method.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Metric {
    /// Root mean squared error.
    Rmse,
    /// Square root of the relative MSE.
    RelRmse,
    /// Lamp-out clamped RMSE ([`lamp_out_rmse`](crate::metrics::lamp_out_rmse)).
    LampOutRmse,
}

impl Metric {
    /// Every metric, in the order reported.
    pub const ALL: [Self; 3] = [Self::Rmse, Self::RelRmse, Self::LampOutRmse];

    /// The metric's value for one row.
    pub fn of(self, r: &AccuracyRow) -> f64 {
        match self {
            Self::Rmse => r.metrics.rmse,
            Self::RelRmse => r.metrics.rel_mse.sqrt(),
            Self::LampOutRmse => r.lamp_out_rmse,
        }
    }

    /// Its name in tables and charts.
    pub fn name(self) -> &'static str {
        match self {
            Self::Rmse => "RMSE",
            Self::RelRmse => "√relMSE",
            Self::LampOutRmse => "lamp-out RMSE",
        }
    }

    /// The chart's file name.
    pub fn chart_file(self) -> &'static str {
        match self {
            Self::Rmse => "accuracy.svg",
            Self::RelRmse => "accuracy_relative.svg",
            Self::LampOutRmse => "accuracy_lamp_out.svg",
        }
    }
}

/// The summary of one method's raw rows with one sampler in one metric.
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
    /// One summary per metric, method and sampler of the raw rows: the RMSE fits in the order
    /// the methods (then samplers) were asked, then the √relMSE fits, then the lamp-out ones.
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
    /// Two renders would write the same image file.
    #[error(
        "{method} {sampler} at {spp} spp is asked twice: --keep-images names each image by them"
    )]
    Duplicate {
        /// Method.
        method: Method,
        /// Sampler.
        sampler: SamplerKind,
        /// Samples per pixel.
        spp: u32,
    },
    /// The denoiser could not be loaded or failed.
    #[error(transparent)]
    Denoise(#[from] DenoiseError),
    /// The denoiser gave NaN or infinite values.
    #[error("{}: the denoised image of {method} at {spp} spp has {count} non-finite values", scene.display())]
    DenoisedNonFinite {
        /// Scene file.
        scene: PathBuf,
        /// Method.
        method: Method,
        /// Samples per pixel.
        spp: u32,
        /// Channel values.
        count: usize,
    },
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

/// The summary of the raw rows of `method` with `sampler` in `metric`.
pub fn fit(
    method: Method,
    sampler: SamplerKind,
    metric: Metric,
    rows: &[AccuracyRow],
) -> MethodFit {
    let mine: Vec<&AccuracyRow> = rows
        .iter()
        .filter(|r| (r.method, r.sampler, r.denoised) == (method, sampler, false))
        .collect();
    let logs: Vec<(f64, f64)> = mine
        .iter()
        .filter(|r| metric.of(r) > 0.0 && r.seconds > 0.0)
        .map(|r| (r.seconds.ln(), metric.of(r).ln()))
        .collect();
    let at_one_second = if mine.iter().all(|r| metric.of(r) == 0.0) {
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

/// A curve's name in tables and legends: `mis sobol`.
pub fn curve_name(method: Method, sampler: SamplerKind) -> String {
    format!("{method} {sampler}")
}

/// A row of the `mis`, Sobol' curve with every error metric at `rmse`, for the tests of the
/// chart and the summary.
#[cfg(test)]
pub(crate) fn test_row(denoised: bool, spp: u32, seconds: f64, rmse: f64) -> AccuracyRow {
    AccuracyRow {
        method: Method::Mis,
        sampler: SamplerKind::Sobol,
        spp,
        seed: 0,
        seconds,
        metrics: ErrorMetrics {
            rmse,
            ..Default::default()
        },
        lamp_out_rmse: rmse,
        fireflies: 0,
        denoised,
    }
}

/// A raw 1-spp row of `method` taking `seconds`, every error metric at `rmse`, for tests.
#[cfg(test)]
pub(crate) fn test_method_row(method: Method, seconds: f64, rmse: f64) -> AccuracyRow {
    AccuracyRow {
        method,
        ..test_row(false, 1, seconds, rmse)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use test_method_row as row;

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
    fn fit_leaves_the_denoised_rows_out() {
        // Raw: 0.3/√t, slope −0.5. A denoised row far below the line would pull both the slope
        // and the error at one second if it were counted.
        let mut rows: Vec<AccuracyRow> = [1.0, 4.0]
            .iter()
            .map(|&t: &f64| row(Method::Mis, t, 0.3 / t.sqrt()))
            .collect();
        rows.push(AccuracyRow {
            denoised: true,
            ..row(Method::Mis, 2.0, 0.001)
        });
        let f = fit(Method::Mis, SamplerKind::Sobol, Metric::Rmse, &rows);
        assert!((f.slope.expect("slope") + 0.5).abs() < 1e-9, "{f:?}");
        assert!((f.at_one_second - 0.3).abs() < 1e-9, "{f:?}");
    }

    #[test]
    fn image_names_are_those_flip_matches() {
        let r = AccuracyRow {
            spp: 16,
            sampler: SamplerKind::Independent,
            ..row(Method::Nee, 1.0, 0.1)
        };
        assert_eq!(r.image_name(), "nee_independent_16spp.exr");
        let d = AccuracyRow {
            denoised: true,
            ..r
        };
        assert_eq!(d.image_name(), "nee_independent_16spp_denoised.exr");
    }
}
