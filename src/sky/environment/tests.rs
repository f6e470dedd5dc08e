//! Unit tests of the environment map's tables and mappings.

use super::*;
use crate::shading::rng::Rng;
use crate::sky::guide::guide_bounds;

/// A map whose texel (x, y) has radiance `f(x, y)` (grey).
fn map(width: u32, height: u32, f: impl Fn(u32, u32) -> f32) -> EnvironmentMap {
    let mut pixels = Vec::new();
    for y in 0..height {
        for x in 0..width {
            pixels.extend([f(x, y); 3]);
        }
    }
    EnvironmentMap::from_linear(width, height, &pixels).expect("valid map")
}

#[test]
fn directions_read_the_texels_of_the_documented_convention() {
    // Every texel holds its own index; the axes land where the module docs draw them.
    let m = map(8, 4, |x, y| (y * 8 + x) as f32);
    let at = |d: Vec3| m.radiance(d.normalize()) as Vec3;
    // −z: u = 0 (column 0), horizon: v = ½ (row 2 of 4, just below the middle edge).
    assert_eq!(at(Vec3::new(0.0, -0.01, -1.0)).x, (2 * 8) as f32);
    assert_eq!(
        at(Vec3::new(1.0, -0.01, 0.0)).x,
        (2 * 8 + 2) as f32,
        "+x at u = 0.25"
    );
    assert_eq!(
        at(Vec3::new(0.0, -0.01, 1.0)).x,
        (2 * 8 + 4) as f32,
        "+z at u = 0.5"
    );
    assert_eq!(
        at(Vec3::new(-1.0, -0.01, 0.0)).x,
        (2 * 8 + 6) as f32,
        "−x at u = 0.75"
    );
    assert_eq!(at(Vec3::new(0.1, 1.0, -0.1)).y, 1.0, "up is row 0");
    assert!(
        at(Vec3::new(0.1, -1.0, -0.1)).x >= 24.0,
        "down is the last row"
    );
}

#[test]
fn the_density_integrates_to_one_and_matches_luminance_times_solid_angle() {
    // Brute-force quadrature of the density over the sphere (a fine grid in (φ, cos θ),
    // which is uniform in solid angle), on a map with a bright spot and a dim gradient.
    let m = map(16, 8, |x, y| {
        if (x, y) == (5, 2) {
            200.0
        } else {
            0.1 + 0.05 * x as f32
        }
    });
    let n = 800;
    let mut integral = 0.0f64;
    for a in 0..n {
        for b in 0..n {
            let phi = 2.0 * std::f64::consts::PI * (a as f64 + 0.5) / n as f64;
            let z = 1.0 - 2.0 * (b as f64 + 0.5) / n as f64;
            let s = (1.0 - z * z).sqrt();
            let d = Vec3::new((s * phi.sin()) as f32, z as f32, (-s * phi.cos()) as f32);
            integral += f64::from(m.pdf(d));
        }
    }
    integral *= 4.0 * std::f64::consts::PI / (n * n) as f64;
    assert!((integral - 1.0).abs() < 2e-3, "∫ pdf dω = {integral}");
    // The bright texel's probability is its share of luminance × solid angle.
    let weight = |x: u32, y: u32| {
        let l = if (x, y) == (5, 2) {
            200.0
        } else {
            0.1 + 0.05 * x as f64
        };
        l * EnvironmentMap::band(8, y as usize)
    };
    let total: f64 = (0..8)
        .flat_map(|y| (0..16).map(move |x| (x, y)))
        .map(|(x, y)| weight(x, y))
        .sum();
    let expected = weight(5, 2) / total;
    let got = f64::from(m.texel_probability(2, 5));
    assert!((got - expected).abs() < 1e-6, "{got} vs {expected}");
}

#[test]
fn sampled_directions_follow_the_density_chi_square() {
    // 12 × 6 texels with varied radiance (two of them zero, never sampled); 200 000
    // samples binned per texel against the expected counts P · N.
    let m = map(12, 6, |x, y| match (x + 3 * y) % 7 {
        0 => 0.0,
        k => k as f32 * if y == 1 { 10.0 } else { 1.0 },
    });
    let n = 200_000u32;
    let mut bins = vec![0u32; 72];
    let mut rng = Rng::new(7, 11);
    for _ in 0..n {
        let u = Vec2::new(rng.next_f32(), rng.next_f32());
        let j = Vec2::new(rng.next_f32(), rng.next_f32());
        let d = m.sample(u, j).expect("lit map").direction;
        assert!((d.length() - 1.0).abs() < 1e-5);
        let (row, column) = m.texel_of(d);
        bins[row * 12 + column] += 1;
    }
    let mut chi2 = 0.0f64;
    let mut dof = 0;
    for row in 0..6 {
        for column in 0..12 {
            let expected = f64::from(m.texel_probability(row, column)) * f64::from(n);
            let observed = f64::from(bins[row * 12 + column]);
            if expected == 0.0 {
                assert_eq!(observed, 0.0, "texel ({column}, {row}) has probability 0");
                continue;
            }
            chi2 += (observed - expected).powi(2) / expected;
            dof += 1;
        }
    }
    // 99.9th percentile of χ² with ~60 degrees of freedom is about 99.6.
    let dof = f64::from(dof - 1);
    let limit = dof + 3.1 * (2.0 * dof).sqrt() + 10.0;
    assert!(
        chi2 < limit,
        "χ² = {chi2:.1} with {dof} dof (limit {limit:.1})"
    );
}

#[test]
fn every_texel_is_sampled_in_proportion_to_its_luminance_times_solid_angle() {
    // Bright texels in the last column and the last row, where the tables end; the
    // expected probabilities come from the texels alone: grey radiance (luminance = value)
    // times the texel's solid angle, (cos θ_top − cos θ_bottom) · 2π / width.
    let (w, h) = (12u32, 6u32);
    let radiance = |x: u32, y: u32| match (x, y) {
        (11, 2) => 300.0,
        (4, 5) => 200.0,
        (11, 5) => 50.0,
        _ => 0.5 + ((x * 7 + y * 3) % 5) as f64,
    };
    let m = map(w, h, |x, y| radiance(x, y) as f32);
    let solid_angle = |y: u32| {
        let theta = |k: u32| std::f64::consts::PI * f64::from(k) / f64::from(h);
        (theta(y).cos() - theta(y + 1).cos()) * std::f64::consts::TAU / f64::from(w)
    };
    let weight = |x: u32, y: u32| radiance(x, y) * solid_angle(y);
    let total: f64 = (0..h).flat_map(|y| (0..w).map(move |x| weight(x, y))).sum();
    let n = 400_000u32;
    let mut bins = vec![0u32; (w * h) as usize];
    let mut rng = Rng::new(5, 17);
    for _ in 0..n {
        let u = Vec2::new(rng.next_f32(), rng.next_f32());
        let j = Vec2::new(rng.next_f32(), rng.next_f32());
        let (row, column) = m.texel_of(m.sample(u, j).expect("lit map").direction);
        bins[row * w as usize + column] += 1;
    }
    let mut chi2 = 0.0f64;
    for y in 0..h {
        for x in 0..w {
            let p = weight(x, y) / total;
            // The tables hold counts out of 2²⁴: each of the two factors within 2⁻²⁴.
            let table = f64::from(m.texel_probability(y as usize, x as usize));
            assert!(
                (table - p).abs() < 4e-7 + 1e-6 * p,
                "texel ({x}, {y}): probability {table}, expected {p}"
            );
            let expected = p * f64::from(n);
            chi2 += (f64::from(bins[(y * w + x) as usize]) - expected).powi(2) / expected;
        }
    }
    // 71 degrees of freedom: the 99.9th percentile of χ² is about 115.
    assert!(chi2 < 115.0, "χ² = {chi2:.1} over {} texels", w * h);
}

#[test]
fn a_sample_within_a_texel_is_uniform_in_solid_angle() {
    // One lit texel row near the pole, where φ and θ spacing differ most: the mean of
    // cos θ over the samples is the mean over the band (its midpoint in cos θ).
    let m = map(4, 16, |_, y| if y == 1 { 1.0 } else { 0.0 });
    let top = (PI / 16.0).cos();
    let bottom = (2.0 * PI / 16.0).cos();
    let mut rng = Rng::new(3, 4);
    let n = 100_000;
    let mut mean = 0.0f64;
    for _ in 0..n {
        let d = m
            .sample(
                Vec2::new(rng.next_f32(), rng.next_f32()),
                Vec2::new(rng.next_f32(), rng.next_f32()),
            )
            .expect("lit")
            .direction;
        assert!(d.y <= top + 1e-6 && d.y >= bottom - 1e-6, "{d}");
        mean += f64::from(d.y) / f64::from(n);
    }
    let expected = 0.5 * f64::from(top + bottom);
    // Uniform in cos θ over a band of width w: σ = w/√12 per sample.
    let sigma = f64::from(top - bottom) / 12f64.sqrt() / f64::from(n).sqrt();
    assert!(
        (mean - expected).abs() < 4.0 * sigma,
        "{mean} vs {expected}"
    );
}

#[test]
fn bad_maps_are_refused_and_memory_is_sixteen_bytes_per_texel_and_small_tables() {
    assert!(EnvironmentMap::from_linear(0, 4, &[]).is_err());
    assert!(EnvironmentMap::from_linear(2, 1, &[1.0; 5]).is_err());
    let mut p = vec![1.0; 6];
    p[4] = f32::NAN;
    let e = EnvironmentMap::from_linear(2, 1, &p).expect_err("NaN refused");
    assert!(e.contains("(1, 0)"), "{e}");
    let m = map(64, 32, |x, _| x as f32);
    // 16 bytes per texel; a column guide of 64 / 8 entries per row, a row guide of 2 · 32
    // entries, 20 bytes per row and 8 per row and column edge.
    assert_eq!(
        m.bytes(),
        16 * 64 * 32 + 4 * 8 * 32 + 4 * 64 + 20 * 32 + 8 * (33 + 65)
    );
    let black = map(4, 2, |_, _| 0.0);
    assert!(!black.is_lit());
    assert!(black.sample(Vec2::splat(0.5), Vec2::splat(0.5)).is_none());
    assert_eq!(black.pdf(Vec3::Y), 0.0);
}

#[test]
fn the_floats_given_by_value_become_the_texels_without_a_copy() {
    // Room for four floats per texel: widened where they lie.
    let mut pixels = Vec::with_capacity(4 * 8 * 4);
    pixels.resize(3 * 8 * 4, 0.5f32);
    pixels[3 * 9 + 1] = -2.0;
    pixels[3 * 30 + 2] = 7.0;
    let start = pixels.as_ptr();
    let m = EnvironmentMap::from_linear_vec(8, 4, pixels).expect("valid map");
    assert_eq!(m.texels.as_ptr(), start, "the map copied its texels");
    assert_eq!(m.max(), 7.0);
    assert_eq!(
        m.radiance(Vec3::new(0.924, 0.4, -0.383)),
        Vec3::new(0.5, 0.0, 0.5)
    );
    // Rows are validated in parallel; the error still names the first bad texel.
    let mut pixels = vec![1.0f32; 3 * 8 * 4];
    pixels[3 * 21] = f32::INFINITY;
    pixels[3 * 11 + 2] = f32::NAN;
    let e = EnvironmentMap::from_linear_vec(8, 4, pixels).expect_err("NaN refused");
    assert!(e.contains("(3, 1)"), "{e}");
}

#[test]
fn a_pick_searches_a_few_entries_whatever_the_distribution() {
    // 4096 columns, one of them 10⁴ times brighter: a binary search over the whole row
    // would span 4096 entries; between two guide entries, (4096 + 511) / 512 < 9 on average.
    let w = 4096;
    let m = map(
        w,
        4,
        |x, _| {
            if x == 1000 { 1e4 } else { 1.0 + (x % 3) as f32 }
        },
    );
    let guide = &m.column_guide[..m.column_guide_len];
    // Every slice of the 24-bit numbers is as likely: the mean over slices is exact.
    let slices = 1u32 << (24 - m.column_shift);
    let spanned: usize = (0..slices)
        .map(|b| {
            let (lo, hi) = guide_bounds(guide, m.column_shift, w as usize, b << m.column_shift);
            hi - lo + 1
        })
        .sum();
    let mean = spanned as f64 / f64::from(slices);
    assert!(mean <= 9.0, "{mean} entries searched on average");
    // The rows' guide, likewise.
    let (lo, hi) = guide_bounds(&m.row_guide, m.row_shift, 4, bits24(0.3));
    assert!(hi - lo <= 1, "{lo}..={hi}");
}

#[test]
fn the_mean_is_the_solid_angle_average() {
    // Upper half 2, lower half 0: mean 1 (each hemisphere is half the sphere).
    let m = map(8, 6, |_, y| if y < 3 { 2.0 } else { 0.0 });
    assert!((m.mean() - Vec3::ONE).length() < 1e-5, "{}", m.mean());
}
