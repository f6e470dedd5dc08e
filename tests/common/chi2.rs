//! Pearson's χ² test of observed counts against expected probabilities, as the sampling tests
//! use it (pbrt-v4's `bsdfs_test.cpp` does the same): bins expecting fewer than 5 samples are
//! pooled into one, and the statistic is held to its 99.9th percentile.

/// Upper χ² quantile for `k` degrees of freedom at the standard normal quantile `z`
/// (Wilson–Hilferty).
pub fn chi2_quantile(k: f64, z: f64) -> f64 {
    let a = 2.0 / (9.0 * k);
    k * (1.0 - a + z * a.sqrt()).powi(3)
}

/// The χ² statistic of `observed` counts (of `count` samples in all) against `expected`
/// probabilities, small bins pooled, and its limit at the 0.1 % level (z = 3.09): `Err` with
/// both if the statistic passes the limit.
pub fn chi2_test(expected: &[f64], observed: &[usize], count: usize) -> Result<f64, String> {
    let (mut chi2, mut dof, mut pool_e, mut pool_o) = (0.0, 0usize, 0.0, 0.0);
    for (e, &o) in expected.iter().zip(observed) {
        let e = e * count as f64;
        if e < 5.0 {
            pool_e += e;
            pool_o += o as f64;
        } else {
            chi2 += (o as f64 - e).powi(2) / e;
            dof += 1;
        }
    }
    if pool_e > 0.0 || pool_o > 0.0 {
        chi2 += (pool_o - pool_e).powi(2) / pool_e.max(1.0);
        dof += 1;
    }
    let limit = chi2_quantile(dof.saturating_sub(1).max(1) as f64, 3.09);
    if chi2 < limit {
        Ok(chi2)
    } else {
        Err(format!("χ² {chi2:.1} over {dof} bins (limit {limit:.1})"))
    }
}
