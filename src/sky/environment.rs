//! An equirectangular (latitude–longitude) environment map with the distribution that
//! importance-samples it. No ECS here.
//!
//! # Convention
//!
//! The same as Mitsuba 3's `envmap` at an identity transform, so images compare 1:1: y is up,
//! and a direction `d` pointing away from the scene reads the map at
//! `u = atan2(d.x, −d.z) / 2π` (wrapped into [0, 1)) and `v = acos(d.y) / π`; column 0 is
//! `u = 0`, row 0 is `v = 0`:
//!
//! ```text
//!          u = 0          0.25          0.5          0.75          1
//!   v = 0    +-------------------------------------------------------+   row 0: straight up (+y)
//!            |                                                       |
//!   v = ½    |  −z           +x            +z           −x           |   the horizon
//!            |                                                       |
//!   v = 1    +-------------------------------------------------------+   last row: straight down (−y)
//! ```
//!
//! A texel is a patch of the sphere (φ in its column's range, θ in its row's); the map's
//! radiance is constant over it (nearest lookup), so evaluation and sampling see the same
//! function.
//!
//! # Sampling
//!
//! A texel is chosen with probability proportional to its luminance times its solid angle
//! (pbrt-v4 §12.5's luminance × sin θ, integrated over the texel's rows): first its row from the
//! marginal table, then its column from the row's conditional table, each held as cumulative
//! counts out of 2²⁴, the resolution of the sampler's numbers, as the emitter table does
//! ([`crate::lights`]). So a texel's probability is exactly the frequency with which 24-bit
//! numbers pick it, and a texel whose count rounds to 0 is never picked and has density 0 (BSDF
//! sampling finds it at full weight). Within the texel the direction is uniform in solid angle
//! (φ uniform, cos θ uniform between the row's edges), from a second, independent pair of
//! numbers, so the density is the texel's probability over its solid angle: constant over the
//! texel, like the radiance.
//!
//! # Memory
//!
//! 16 bytes per texel, the distribution included: the radiance as three `f32` and one `u32` of
//! cumulative counts. A row's first `width − 1` counts are its columns' (the last column's is
//! 2²⁴ by construction); its last slot holds the marginal table's count through that row.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};
use rayon::prelude::*;

/// Resolution of the tables: cumulative counts out of 2²⁴.
const SCALE: u32 = 1 << 24;

/// Most texels a map may have (a 8192 × 4096 map): 512 MiB at 16 bytes each.
pub const MAX_TEXELS: u64 = 1 << 25;

/// Relative luminance of linear Rec. 709 RGB.
#[inline]
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// An environment map in map space (see the module docs for the convention).
#[derive(Debug)]
pub struct EnvironmentMap {
    width: u32,
    height: u32,
    /// Linear RGB radiance, three floats per texel, row-major from row 0 (up).
    texels: Vec<f32>,
    /// Per row: the cumulative counts of its first `width − 1` columns, then the marginal
    /// cumulative count through the row.
    counts: Vec<u32>,
    /// Solid-angle mean of the radiance over the sphere.
    mean: Vec3,
    /// Largest channel of any texel.
    max: f32,
    /// Whether any texel has luminance > 0 (otherwise there is nothing to sample).
    lit: bool,
    /// A row's angular height, π / height.
    row_angle: f32,
    /// A texel's solid angle over the sine of its row's mid-angle: 2π / width · 2 sin(π / 2h).
    texel_scale: f32,
}

/// Cumulative counts out of [`SCALE`] through each of the first `out.len()` of `weights`
/// (which sum to `total` > 0 over all of them), written to `out`. A table of every weight but
/// the last leaves the last its share: the count through all of them is [`SCALE`].
fn cumulative(weights: impl Iterator<Item = f64>, total: f64, out: &mut [u32]) {
    let mut acc = 0.0f64;
    for (o, w) in out.iter_mut().zip(weights) {
        acc += w;
        *o = ((acc / total) * f64::from(SCALE))
            .round()
            .min(f64::from(SCALE)) as u32;
    }
}

/// The index that the 24-bit reading of `u` ∈ [0, 1) picks from `n` cumulative counts given by
/// `at` (non-decreasing, the last one implicitly [`SCALE`]): the first whose count exceeds it.
#[inline]
fn pick(n: usize, u: f32, at: impl Fn(usize) -> u32) -> usize {
    let g = ((u * SCALE as f32) as u32).min(SCALE - 1);
    // Binary search over [0, n − 1): index n − 1 is the answer if none before it exceeds g.
    let (mut lo, mut hi) = (0usize, n.saturating_sub(1));
    while lo < hi {
        let mid = (lo + hi) / 2;
        if at(mid) <= g {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    lo
}

impl EnvironmentMap {
    /// A map of `width` × `height` texels from linear RGB floats, row-major from the top row
    /// (`3 · width · height` values). Refuses an empty or oversized map and a texel that is
    /// not finite; negative values (filtering ringing in some tools) are read as 0.
    pub fn from_linear(width: u32, height: u32, pixels: &[f32]) -> Result<Self, String> {
        Self::check_size(width, height, pixels.len())?;
        Self::from_linear_vec(width, height, pixels.to_vec())
    }

    /// [`EnvironmentMap::from_linear`] taking the floats by value: they become the map's
    /// texels in place (no copy of the map), validated and clamped rows in parallel.
    pub fn from_linear_vec(width: u32, height: u32, mut pixels: Vec<f32>) -> Result<Self, String> {
        Self::check_size(width, height, pixels.len())?;
        // The map holds what it says (`bytes`), not a decoder's spare capacity.
        pixels.shrink_to_fit();
        let w = width as usize;
        // The first texel that is not finite, in row-major order; negative values become 0.
        let bad = pixels
            .par_chunks_mut(3 * w)
            .enumerate()
            .filter_map(|(y, row)| {
                let mut first = None;
                for (k, v) in row.iter_mut().enumerate() {
                    if !v.is_finite() {
                        first = first.or(Some(k / 3));
                    }
                    *v = v.max(0.0);
                }
                first.map(|x| (y, x))
            })
            .min();
        if let Some((y, x)) = bad {
            return Err(format!(
                "texel ({x}, {y}) of the environment map is not finite"
            ));
        }
        Ok(Self::build(width, height, pixels))
    }

    /// Refuses an empty or oversized map and a number of floats other than 3 per texel.
    fn check_size(width: u32, height: u32, len: usize) -> Result<(), String> {
        let texel_count = u64::from(width) * u64::from(height);
        if texel_count == 0 {
            return Err("the environment map is empty".into());
        }
        if texel_count > MAX_TEXELS {
            return Err(format!(
                "the environment map has {width}×{height} texels; at most {MAX_TEXELS} are accepted"
            ));
        }
        if len as u64 != 3 * texel_count {
            return Err(format!(
                "the environment map has {len} values for {width}×{height} RGB texels"
            ));
        }
        Ok(())
    }

    /// Builds the tables of validated texels (finite, non-negative), rows in parallel.
    fn build(width: u32, height: u32, texels: Vec<f32>) -> Self {
        let w = width as usize;
        let mut counts = vec![0u32; texels.len() / 3];
        // Per row: the sum of its luminances and of its radiance (f64, so 4096 columns lose
        // nothing), its largest channel, and the row's conditional table.
        let rows: Vec<(f64, [f64; 3], f32)> = counts
            .par_chunks_mut(w)
            .zip(texels.par_chunks(3 * w))
            .map(|(row_counts, row)| {
                let lum = |t: &[f32]| f64::from(luminance(Vec3::from_slice(t)));
                let sum: f64 = row.chunks_exact(3).map(lum).sum();
                let mut rgb = [0.0f64; 3];
                let mut max = 0.0f32;
                for t in row.chunks_exact(3) {
                    for c in 0..3 {
                        rgb[c] += f64::from(t[c]);
                        max = max.max(t[c]);
                    }
                }
                let columns = &mut row_counts[..w - 1];
                if sum > 0.0 {
                    cumulative(row.chunks_exact(3).map(lum), sum, columns);
                } else {
                    // Never picked (its marginal count is 0); uniform for completeness.
                    cumulative(std::iter::repeat_n(1.0, w), w as f64, columns);
                }
                (sum, rgb, max)
            })
            .collect();
        let band = |i: usize| Self::band(height, i);
        let weights = || rows.iter().enumerate().map(|(i, r)| r.0 * band(i));
        let total: f64 = weights().sum();
        let mut marginal = vec![0u32; height as usize];
        let lit = total > 0.0 && total.is_finite();
        if lit {
            cumulative(weights(), total, &mut marginal);
            // Exactly: the counts are read up to the last row's.
            marginal[height as usize - 1] = SCALE;
        }
        for (i, m) in marginal.iter().enumerate() {
            counts[i * w + w - 1] = *m;
        }
        // Mean over the sphere: Σ L · ΔΩ / 4π, with ΔΩ = band(i) · 2π / width per texel.
        let mut mean = [0.0f64; 3];
        for (i, (_, rgb, _)) in rows.iter().enumerate() {
            for c in 0..3 {
                mean[c] += rgb[c] * band(i) * std::f64::consts::TAU / w as f64;
            }
        }
        let mean = Vec3::from_array(mean.map(|m| (m / (4.0 * std::f64::consts::PI)) as f32));
        let max = rows.iter().fold(0.0f32, |m, r| m.max(r.2));
        Self {
            width,
            height,
            texels,
            counts,
            mean,
            max,
            lit,
            row_angle: PI / height as f32,
            texel_scale: (std::f64::consts::TAU / w as f64
                * 2.0
                * (std::f64::consts::PI / (2.0 * f64::from(height))).sin())
                as f32,
        }
    }

    /// `cos θ_i − cos θ_{i+1}` of row `i` of `height`: its band's solid angle over 2π, as
    /// `2 sin(θ_mid) sin(Δθ / 2)` (no cancellation near the poles).
    fn band(height: u32, i: usize) -> f64 {
        let h = f64::from(height);
        let pi = std::f64::consts::PI;
        2.0 * (pi * (i as f64 + 0.5) / h).sin() * (pi / (2.0 * h)).sin()
    }

    /// Width in texels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Bytes held: texels and tables.
    pub fn bytes(&self) -> usize {
        std::mem::size_of_val(self.texels.as_slice())
            + std::mem::size_of_val(self.counts.as_slice())
    }

    /// Solid-angle mean of the radiance over the whole sphere.
    pub fn mean(&self) -> Vec3 {
        self.mean
    }

    /// The largest channel of any texel.
    pub fn max(&self) -> f32 {
        self.max
    }

    /// Whether the map has any light to sample.
    pub fn is_lit(&self) -> bool {
        self.lit
    }

    /// The texel (row, column) that direction `d` (map space, any length > 0) reads.
    #[inline]
    pub fn texel_of(&self, d: Vec3) -> (usize, usize) {
        let mut u = d.x.atan2(-d.z) * (0.5 / PI);
        if u < 0.0 {
            u += 1.0;
        }
        let theta = (d.x * d.x + d.z * d.z).sqrt().atan2(d.y);
        let column = ((u * self.width as f32) as usize).min(self.width as usize - 1);
        let row =
            ((theta * (1.0 / PI) * self.height as f32) as usize).min(self.height as usize - 1);
        (row, column)
    }

    /// Radiance along direction `d` (map space).
    #[inline]
    pub fn radiance(&self, d: Vec3) -> Vec3 {
        let (row, column) = self.texel_of(d);
        self.texel(row, column)
    }

    /// Radiance of texel `(row, column)`.
    #[inline]
    fn texel(&self, row: usize, column: usize) -> Vec3 {
        let i = 3 * (row * self.width as usize + column);
        Vec3::from_slice(&self.texels[i..i + 3])
    }

    /// Radiance along direction `d` (map space) and the density with which
    /// [`EnvironmentMap::sample`] gives it ([`EnvironmentMap::pdf`]), from one texel lookup.
    #[inline]
    pub fn lookup(&self, d: Vec3) -> (Vec3, f32) {
        let (row, column) = self.texel_of(d);
        (self.texel(row, column), self.texel_pdf(row, column))
    }

    /// Marginal cumulative count through row `i`.
    #[inline]
    fn marginal(&self, i: usize) -> u32 {
        self.counts[i * self.width as usize + self.width as usize - 1]
    }

    /// Cumulative count of row `i` through column `j`.
    #[inline]
    fn conditional(&self, i: usize, j: usize) -> u32 {
        if j + 1 == self.width as usize {
            SCALE
        } else {
            self.counts[i * self.width as usize + j]
        }
    }

    /// Probability that [`EnvironmentMap::sample`] picks texel `(row, column)`.
    #[inline]
    fn texel_probability(&self, row: usize, column: usize) -> f32 {
        let m = self.marginal(row) - if row == 0 { 0 } else { self.marginal(row - 1) };
        let c = self.conditional(row, column)
            - if column == 0 {
                0
            } else {
                self.conditional(row, column - 1)
            };
        (f64::from(m) * f64::from(c) / (f64::from(SCALE) * f64::from(SCALE))) as f32
    }

    /// Solid angle of a texel of row `row`.
    #[inline]
    fn texel_solid_angle(&self, row: usize) -> f32 {
        self.texel_scale * (self.row_angle * (row as f32 + 0.5)).sin()
    }

    /// Density per steradian of a direction in texel `(row, column)`.
    #[inline]
    fn texel_pdf(&self, row: usize, column: usize) -> f32 {
        if !self.lit {
            return 0.0;
        }
        self.texel_probability(row, column) / self.texel_solid_angle(row)
    }

    /// Density per steradian with which [`EnvironmentMap::sample`] gives direction `d` (map
    /// space): its texel's probability over the texel's solid angle.
    #[inline]
    pub fn pdf(&self, d: Vec3) -> f32 {
        let (row, column) = self.texel_of(d);
        self.texel_pdf(row, column)
    }

    /// A direction (map space, unit) sampled by the texel distribution: `u` picks the texel
    /// (`u.y` the row, `u.x` the column), `jitter` the direction within it. `None` for a map
    /// without light. Its density is [`EnvironmentMap::pdf`] of the direction.
    #[inline]
    pub fn sample(&self, u: Vec2, jitter: Vec2) -> Option<Vec3> {
        if !self.lit {
            return None;
        }
        let (w, h) = (self.width as usize, self.height);
        let row = pick(h as usize, u.y, |i| self.marginal(i));
        let column = pick(w, u.x, |j| self.conditional(row, j));
        let phi = 2.0 * PI * (column as f32 + jitter.x) / w as f32;
        // cos θ uniform over the row's band, from its top edge down by the band's height
        // (`texel_solid_angle` over the column's 2π / width).
        let top = (self.row_angle * row as f32).cos();
        let band = self.texel_solid_angle(row) * w as f32 / (2.0 * PI);
        let cos_theta = (top - jitter.y * band).clamp(-1.0, 1.0);
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        Some(Vec3::new(
            sin_theta * phi.sin(),
            cos_theta,
            -sin_theta * phi.cos(),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::rng::Rng;

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
            let d = m.sample(u, j).expect("lit map");
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
            let (row, column) = m.texel_of(m.sample(u, j).expect("lit map"));
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
                .expect("lit");
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
    fn bad_maps_are_refused_and_memory_is_sixteen_bytes_per_texel() {
        assert!(EnvironmentMap::from_linear(0, 4, &[]).is_err());
        assert!(EnvironmentMap::from_linear(2, 1, &[1.0; 5]).is_err());
        let mut p = vec![1.0; 6];
        p[4] = f32::NAN;
        let e = EnvironmentMap::from_linear(2, 1, &p).expect_err("NaN refused");
        assert!(e.contains("(1, 0)"), "{e}");
        let m = map(64, 32, |x, _| x as f32);
        assert_eq!(m.bytes(), 16 * 64 * 32);
        let black = map(4, 2, |_, _| 0.0);
        assert!(!black.is_lit());
        assert!(black.sample(Vec2::splat(0.5), Vec2::splat(0.5)).is_none());
        assert_eq!(black.pdf(Vec3::Y), 0.0);
    }

    #[test]
    fn the_floats_given_by_value_become_the_texels_without_a_copy() {
        let mut pixels = vec![0.5f32; 3 * 8 * 4];
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
    fn the_mean_is_the_solid_angle_average() {
        // Upper half 2, lower half 0: mean 1 (each hemisphere is half the sphere).
        let m = map(8, 6, |_, y| if y < 3 { 2.0 } else { 0.0 });
        assert!((m.mean() - Vec3::ONE).length() < 1e-5, "{}", m.mean());
    }
}
