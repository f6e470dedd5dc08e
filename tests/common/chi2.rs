//! Pearson's χ² tests of sampled counts against expected probabilities, as the sampling tests
//! use them (pbrt-v4's `bsdfs_test.cpp` does the same): bins expecting fewer than 5 samples are
//! pooled into one, and the statistic is held to its 99.9th percentile. [`chi2_test`] takes the
//! counts; [`chi_square_of_directions`] bins a material's sampled directions itself.

use std::f64::consts::PI;

use glam::{Vec2, Vec3};
use rondo::shading::material::Material;
use rondo::shading::rng::Rng;

/// Upper χ² quantile for `k` degrees of freedom at the standard normal quantile `z`
/// (Wilson–Hilferty).
pub fn chi2_quantile(k: f64, z: f64) -> f64 {
    let a = 2.0 / (9.0 * k);
    k * (1.0 - a + z * a.sqrt()).powi(3)
}

/// The χ² statistic of `observed` counts (of `count` samples in all) against `expected`
/// probabilities, small bins pooled, and its limit at the 0.1 % level (z = 3.09).
fn pooled_statistic(expected: &[f64], observed: &[usize], count: usize) -> (f64, f64) {
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
    (chi2, limit)
}

/// The χ² statistic of `observed` counts (of `count` samples in all) against `expected`
/// probabilities, small bins pooled: `Err` with the statistic and its limit at the 0.1 % level
/// if the statistic passes the limit.
pub fn chi2_test(expected: &[f64], observed: &[usize], count: usize) -> Result<f64, String> {
    let (chi2, limit) = pooled_statistic(expected, observed, count);
    if chi2 < limit {
        Ok(chi2)
    } else {
        Err(format!(
            "χ² {chi2:.1} over {} bins (limit {limit:.1})",
            expected.len()
        ))
    }
}

/// Direction of cell-centre `(i, j)` of an `n × m` grid over (cos θ ∈ [0,1], φ ∈ [0, 2π)), and
/// the solid angle of the cell.
pub fn cell(i: usize, j: usize, n: usize, m: usize) -> (Vec3, f64) {
    let c = (i as f64 + 0.5) / n as f64;
    let phi = (j as f64 + 0.5) / m as f64 * 2.0 * PI;
    let s = (1.0 - c * c).sqrt();
    let w = Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, c as f32);
    (w, 2.0 * PI / (n * m) as f64)
}

/// The χ² statistic of `count` directions sampled by `m` for a ray along `d` at the flat normal
/// +z, binned on a 20 × 20 (cos θ, φ) grid plus one bin for absorbed samples, against the
/// density of `eval` integrated over each bin (a 24 × 24 sub-grid: a 6 × 6 one is off by a few
/// per cent on a narrow lobe near the horizon, a χ² of 12,600 for `Pbr` at roughness 0.3, 80°);
/// bins expecting fewer than 5 samples are pooled. Returns the statistic and its 0.1 % critical
/// value.
pub fn chi_square_of_directions(m: &Material, d: Vec3, count: usize, seed: u64) -> (f64, f64) {
    let (nc, nphi, sub) = (20usize, 20usize, 24usize);
    let bsdf = m.bsdf_at(d, Vec3::Z, Vec2::ZERO);
    let mut expected = vec![0.0f64; nc * nphi + 1];
    for i in 0..nc * sub {
        for j in 0..nphi * sub {
            let (wi, dw) = cell(i, j, nc * sub, nphi * sub);
            let (_, pdf) = bsdf.eval(wi).expect("evaluable");
            expected[(i / sub) * nphi + j / sub] += f64::from(pdf) * dw;
        }
    }
    let upper: f64 = expected.iter().sum();
    expected[nc * nphi] = (1.0 - upper).max(0.0);
    let mut observed = vec![0usize; nc * nphi + 1];
    let mut rng = Rng::new(seed, 8);
    for _ in 0..count {
        let bin = match m.scatter(d, Vec3::Z, Vec2::ZERO, &mut rng) {
            None => nc * nphi,
            Some(s) => {
                let w = s.direction;
                let i = ((w.z as f64) * nc as f64).clamp(0.0, nc as f64 - 1.0) as usize;
                let phi = f64::from(w.y.atan2(w.x)).rem_euclid(2.0 * PI);
                let j = (phi / (2.0 * PI) * nphi as f64).min(nphi as f64 - 1.0) as usize;
                i * nphi + j
            }
        };
        observed[bin] += 1;
    }
    pooled_statistic(&expected, &observed, count)
}
