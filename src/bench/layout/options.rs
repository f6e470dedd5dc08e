//! What `rondo bench layout` measures and where it writes.

use std::path::PathBuf;
use std::time::Duration;

/// What to measure and where to write it.
#[derive(Clone, Debug)]
pub struct Options {
    /// Output directory for `layout.csv`, `layout.md` and `layout.svg`.
    pub out: PathBuf,
    /// Primitive counts, ascending.
    pub counts: Vec<usize>,
    /// Rounds per point at counts up to 10⁴ (fewer above: see [`Options::reps_at`]).
    pub reps: usize,
    /// Minimum duration of one run.
    pub min_run: Duration,
    /// Render resolution (square).
    pub render_size: u32,
    /// Rays per traversal run (before repetition).
    pub rays: usize,
    /// The command line that made these results, for the report.
    pub command: String,
    /// Workloads to run (names from [`WORKLOADS`](crate::bench::layout_rows::WORKLOADS)); empty for all.
    pub workloads: Vec<String>,
}

impl Options {
    /// The full sweep: 10² to `max_count` (powers of ten and their half-decades), `reps`
    /// rounds.
    pub fn full(out: PathBuf, max_count: usize, reps: usize) -> Self {
        let mut counts = Vec::new();
        let mut decade = 100usize;
        while decade <= max_count {
            counts.push(decade);
            let half = (decade as f64 * 10f64.sqrt()).round() as usize;
            if half <= max_count && decade * 10 <= max_count {
                counts.push(half);
            }
            decade *= 10;
        }
        Self {
            out,
            counts,
            reps: reps.max(1),
            min_run: Duration::from_millis(50),
            render_size: 64,
            rays: 20_000,
            command: String::new(),
            workloads: Vec::new(),
        }
    }

    /// Tiny sizes, two rounds, no minimum run time: checks that everything runs and writes its
    /// outputs; measures nothing worth reading.
    pub fn smoke(out: PathBuf) -> Self {
        Self {
            out,
            counts: vec![20, 300],
            reps: 2,
            min_run: Duration::ZERO,
            render_size: 8,
            rays: 200,
            command: String::new(),
            workloads: Vec::new(),
        }
    }

    /// Whether `workload` is to run.
    pub fn runs(&self, workload: &str) -> bool {
        self.workloads.is_empty() || self.workloads.iter().any(|w| w == workload)
    }

    /// Rounds at `count` primitives: fewer at the largest sizes, where one run is long and
    /// its spread small.
    pub fn reps_at(&self, count: usize) -> usize {
        match count {
            0..=10_000 => self.reps,
            10_001..=100_000 => self.reps.min(7),
            _ => self.reps.min(5),
        }
    }
}
