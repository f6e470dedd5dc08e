//! The measured rows of `rondo bench layout`: the primitive kinds, the workloads and one
//! measured point each, with the median and spread of its runs. Shared by the run
//! ([`super::layout`]) and its chart ([`super::chart`]).

use crate::geometry::layout::LayoutKind;

/// Primitive kind of a sweep.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Kind {
    /// Spheres.
    Sphere,
    /// Triangles.
    Triangle,
}

impl Kind {
    /// Name in the CSV.
    pub const fn name(self) -> &'static str {
        match self {
            Kind::Sphere => "sphere",
            Kind::Triangle => "triangle",
        }
    }
}

/// Workloads, in report order.
pub const WORKLOADS: [(&str, &str); 5] = [
    ("kernel", "tests/s"),
    ("traverse", "rays/s"),
    ("render", "rays/s"),
    ("extract", "prims/s"),
    ("pack", "prims/s"),
];

/// One measured point: a workload on one scene in one layout.
#[derive(Clone, Debug)]
pub struct Row {
    /// Workload name (see [`WORKLOADS`]).
    pub workload: &'static str,
    /// Primitive kind.
    pub kind: Kind,
    /// Primitive count.
    pub count: usize,
    /// Layout.
    pub layout: LayoutKind,
    /// Unit of the throughputs.
    pub unit: &'static str,
    /// Throughput of each run.
    pub runs: Vec<f64>,
    /// Throughput over AoS's in the same round, per round.
    pub ratios: Vec<f64>,
}

/// Median, minimum and maximum.
pub fn spread(values: &[f64]) -> (f64, f64, f64) {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return (f64::NAN, f64::NAN, f64::NAN);
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    let median = if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    };
    (median, v[0], v[n - 1])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_is_median_min_max() {
        assert_eq!(spread(&[3.0, 1.0, 2.0]), (2.0, 1.0, 3.0));
        assert_eq!(spread(&[4.0, 1.0, 2.0, 3.0]), (2.5, 1.0, 4.0));
        assert!(spread(&[]).0.is_nan());
    }
}
