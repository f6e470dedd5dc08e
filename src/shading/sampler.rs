//! Sample generators for the integrator: independent PCG32 numbers, or Owen-scrambled Sobol'
//! points with a fixed dimension layout.
//!
//! A path asks its [`Sampler`] for 1D and 2D values; the integrator [`Sampler::seek`]s to a fixed
//! dimension before each use (pixel, then per bounce: light choice, light point, BSDF, roulette),
//! so a dimension means the same decision in every sample of a pixel whatever the path did
//! before. The independent sampler ignores `seek` and draws the next numbers of its stream.
//!
//! # The Sobol' sampler
//!
//! Every dimension of the layout is a *padded* 1D or 2D Sobol' pattern (Burley, "Practical
//! Hash-based Owen Scrambling", JCGT 9(4), 2020): the first two Sobol' dimensions (van der
//! Corput and the Pascal-matrix dimension), with the sample index shuffled and both coordinates
//! Owen-scrambled by seeds hashed from (seed, pixel, dimension). So:
//!
//! - each pixel and each dimension gets its own independent randomisation (no structure between
//!   pixels, no correlation between dimensions), and every single sample is uniform over the
//!   whole hypercube: estimates are unbiased;
//! - the index shuffle is a nested permutation that maps `[0, 2ᵏ)` onto itself for every `k`, so
//!   the first 2ᵏ samples of a pixel are the first 2ᵏ Sobol' points, a (0, k, 2)-net in every 2D
//!   dimension (one point in each elementary interval of area 2⁻ᵏ), and stratified into 2ᵏ
//!   intervals in every 1D dimension; Owen scrambling keeps both properties;
//! - a sample's values depend only on (seed, pixel, sample index, dimension): images are
//!   bit-identical for any thread count and any split of the samples into passes.
//!
//! Owen scrambling is the hash-based nested uniform scramble of Laine and Karras (2011), with the
//! improved hash constants of Vegdahl ("Building a Better LK Hash", 2021): every operation of the
//! hash changes a bit only as a function of the bits below it, which is what makes it a nested
//! scramble once the bits are reversed.

use std::fmt;
use std::str::FromStr;

use glam::Vec2;
use serde::Deserialize;

use super::rng::{Rng, mix64};

/// Which sample generator a render uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Deserialize)]
pub enum SamplerKind {
    /// Independent uniform numbers (PCG32 per sample): error falls as N^(−1/2).
    #[serde(alias = "independent")]
    Independent,
    /// Owen-scrambled Sobol' points, padded per dimension (the default): stratified at every
    /// power-of-two sample count.
    #[default]
    #[serde(alias = "sobol")]
    Sobol,
}

impl SamplerKind {
    /// Every sampler, in the order reports list them.
    pub const ALL: [SamplerKind; 2] = [SamplerKind::Independent, SamplerKind::Sobol];

    /// The name `--sampler` accepts and reports print.
    pub const fn name(self) -> &'static str {
        match self {
            SamplerKind::Independent => "independent",
            SamplerKind::Sobol => "sobol",
        }
    }
}

impl fmt::Display for SamplerKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for SamplerKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let s = s.to_ascii_lowercase();
        Self::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| format!("unknown sampler {s:?} (independent or sobol)"))
    }
}

/// A source of sample values for one path.
pub trait Sampler {
    /// Moves to dimension `dimension` of the layout; the next value comes from there.
    fn seek(&mut self, dimension: u32);
    /// A value uniform in `[0, 1)` from the current dimension; moves to the next one.
    fn next_1d(&mut self) -> f32;
    /// A point uniform in `[0, 1)²` from the current dimension; moves to the next one.
    fn next_2d(&mut self) -> Vec2;
}

/// The generators of one pixel's samples: what they share (the pixel's seeds) is derived once
/// per pixel and kept from one sample to the next. A sample's values depend only on (seed, pixel,
/// sample index), never on which samples the pixel served before.
pub trait PixelSampler {
    /// The generator of one sample, borrowing what the pixel keeps.
    type Path<'a>: Sampler
    where
        Self: 'a;
    /// The samples of pixel `pixel` under `seed`.
    fn for_pixel(seed: u64, pixel: u64) -> Self;
    /// The generator of sample `sample` of the pixel, at dimension 0.
    fn start_sample(&mut self, sample: u32) -> Self::Path<'_>;
}

impl Sampler for Rng {
    /// Independent numbers need no layout: the stream just goes on.
    #[inline]
    fn seek(&mut self, _dimension: u32) {}

    #[inline]
    fn next_1d(&mut self) -> f32 {
        self.next_f32()
    }

    #[inline]
    fn next_2d(&mut self) -> Vec2 {
        let x = self.next_f32();
        let y = self.next_f32();
        Vec2::new(x, y)
    }
}

/// Independent numbers per sample: the stream of [`Rng::for_sample`] for (seed, pixel, sample),
/// with the pixel's part of the seeding done once per pixel.
#[derive(Clone, Copy, Debug)]
pub struct IndependentPixel {
    /// The pixel's stream seed ([`Rng::pixel_seed`]).
    pixel_seed: u64,
}

impl PixelSampler for IndependentPixel {
    type Path<'a> = Rng;

    #[inline]
    fn for_pixel(seed: u64, pixel: u64) -> Self {
        Self {
            pixel_seed: Rng::pixel_seed(seed, pixel),
        }
    }

    #[inline]
    fn start_sample(&mut self, sample: u32) -> Rng {
        Rng::for_pixel_sample(self.pixel_seed, u64::from(sample))
    }
}

/// The Owen-scrambled Sobol' samples of one pixel (see the module docs): the root of its
/// scrambling seeds, and each dimension's seeds once a sample has drawn from it.
#[derive(Clone, Debug)]
pub struct SobolPixel {
    /// Hash of (seed, pixel): the root of every dimension's scrambling seeds.
    pixel_seed: u64,
    /// The seeds of the first [`CACHED_DIMENSIONS`] dimensions, each derived the first time a
    /// sample of the pixel draws from it (they are the same for every sample of the pixel).
    seeds: [DimensionSeeds; CACHED_DIMENSIONS],
    /// Bit `d` set once `seeds[d]` holds dimension `d`'s seeds.
    cached: u64,
}

impl SobolPixel {
    /// The seeds of dimension `d`.
    #[inline(always)]
    fn seeds(&mut self, d: u32) -> DimensionSeeds {
        match self.seeds.get_mut(d as usize) {
            Some(slot) => {
                if self.cached & (1 << d) == 0 {
                    *slot = DimensionSeeds::derive(self.pixel_seed, d);
                    self.cached |= 1 << d;
                }
                *slot
            }
            None => DimensionSeeds::derive(self.pixel_seed, d),
        }
    }
}

/// Padded Owen-scrambled Sobol' values of one sample of a [`SobolPixel`].
#[derive(Debug)]
pub struct SobolSampler<'a> {
    /// The pixel, which keeps the dimensions' seeds.
    pixel: &'a mut SobolPixel,
    /// Sample index within the pixel, bit-reversed (the form the index shuffle starts from).
    index_reversed: u32,
    /// The next dimension to draw from.
    dimension: u32,
}

/// How many dimensions' seeds a [`SobolPixel`] keeps (at most 64, the bits of its mask): every
/// dimension a path of the default depth 8 draws from (the pixel, then the integrator's five
/// per bounce: 1 + 8 · 5).
const CACHED_DIMENSIONS: usize = 41;

/// The seeds of one dimension: the index shuffle's, its value at index 0, and the two
/// coordinates' scrambles.
#[derive(Clone, Copy, Debug, Default)]
struct DimensionSeeds {
    shuffle: u32,
    shuffle_zero: u32,
    x: u32,
    y: u32,
}

impl DimensionSeeds {
    /// The seeds of dimension `dimension` of the pixel whose root seed is `pixel_seed`.
    #[inline]
    fn derive(pixel_seed: u64, dimension: u32) -> Self {
        let a = mix64(pixel_seed ^ u64::from(dimension).wrapping_mul(0x9e37_79b9_7f4a_7c15));
        let b = mix64(a);
        let shuffle = a as u32;
        Self {
            shuffle,
            shuffle_zero: laine_karras(0, shuffle),
            x: (a >> 32) as u32,
            y: b as u32,
        }
    }
}

/// Direction numbers of Sobol' dimension 1 (generator matrix: Pascal's triangle mod 2), column
/// `j` for bit `j` of the index, most significant output bit first: `v₀ = 1`, `vⱼ = vⱼ₋₁ ⊕ (vⱼ₋₁ ≫ 1)`.
const PASCAL: [u32; 32] = {
    let mut v = [0u32; 32];
    v[0] = 1 << 31;
    let mut j = 1;
    while j < 32 {
        v[j] = v[j - 1] ^ (v[j - 1] >> 1);
        j += 1;
    }
    v
};

/// Sobol' dimension 1 of `index`, as a 32-bit fraction (the definition; the sampler uses
/// [`pascal_reversed`]).
#[cfg(test)]
fn sobol_pascal(mut index: u32) -> u32 {
    let mut x = 0;
    while index != 0 {
        x ^= PASCAL[index.trailing_zeros() as usize];
        index &= index - 1;
    }
    x
}

/// [`pascal_reversed`] byte by byte: entry `[k][v]` is the XOR of the reversed direction numbers
/// that the set bits of `v`, placed as byte `k` of a bit-reversed index, select.
const PASCAL_REVERSED: [[u32; 256]; 4] = {
    let mut t = [[0u32; 256]; 4];
    let mut k = 0;
    while k < 4 {
        let mut v = 0;
        while v < 256 {
            let mut x = 0u32;
            let mut bit = 0;
            while bit < 8 {
                if (v >> bit) & 1 == 1 {
                    // Bit `8k + bit` of the reversed index is bit `31 − 8k − bit` of the index.
                    x ^= PASCAL[31 - 8 * k - bit].reverse_bits();
                }
                bit += 1;
            }
            t[k][v] = x;
            v += 1;
        }
        k += 1;
    }
    t
};

/// `sobol_pascal(i).reverse_bits()` from `reversed = i.reverse_bits()`: the generator matrix is
/// linear over bits, so the result is the XOR of four table entries, one per byte, with no
/// loop over the index's bits and no bit reversal.
#[inline]
fn pascal_reversed(reversed: u32) -> u32 {
    let [b0, b1, b2, b3] = reversed.to_le_bytes();
    PASCAL_REVERSED[0][usize::from(b0)]
        ^ PASCAL_REVERSED[1][usize::from(b1)]
        ^ PASCAL_REVERSED[2][usize::from(b2)]
        ^ PASCAL_REVERSED[3][usize::from(b3)]
}

/// Laine–Karras permutation with Vegdahl's constants: bit `j` of the result depends only on
/// bits `0..=j` of `x`, so applied to bit-reversed values it is a nested uniform scramble.
#[inline]
fn laine_karras(mut x: u32, seed: u32) -> u32 {
    x ^= x.wrapping_mul(0x3d20_adea);
    x = x.wrapping_add(seed);
    x = x.wrapping_mul((seed >> 16) | 1);
    x ^= x.wrapping_mul(0x0552_6c56);
    x ^= x.wrapping_mul(0x53a2_2864);
    x
}

/// Owen scrambling of the 32-bit fraction `x`: each bit flipped by a hash of the bits above it.
#[cfg(test)]
fn owen(x: u32, seed: u32) -> u32 {
    laine_karras(x.reverse_bits(), seed).reverse_bits()
}

/// A nested permutation of sample indices that maps `[0, 2ᵏ)` onto itself for every `k`: the
/// Owen scramble of the index (bit `j` flipped by a hash of the bits above it), with the flips
/// that do not depend on the index (those of the zero bits above its top bit) taken back out.
#[cfg(test)]
fn shuffle(index: u32, seed: u32) -> u32 {
    (laine_karras(index.reverse_bits(), seed) ^ laine_karras(0, seed)).reverse_bits()
}

/// The index shuffle in bit-reversed form: from `index.reverse_bits()` to the reversed result
/// (the sampler's form of `shuffle`, the definition the tests hold it to), given the dimension's
/// seeds (with `laine_karras(0, seeds.shuffle)` precomputed).
#[inline]
fn shuffle_reversed(index_reversed: u32, seeds: &DimensionSeeds) -> u32 {
    laine_karras(index_reversed, seeds.shuffle) ^ seeds.shuffle_zero
}

/// Owen-scrambled van der Corput of the shuffled index given bit-reversed: `owen(vdc(i)) =
/// reverse(lk(i))`, as a 32-bit fraction.
#[inline]
fn scrambled_vdc(i_reversed: u32, seed: u32) -> u32 {
    laine_karras(i_reversed.reverse_bits(), seed).reverse_bits()
}

/// The top 24 bits of a 32-bit fraction as an `f32` in `[0, 1)` (exact, never 1).
#[inline]
fn to_unit(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

impl SobolSampler<'_> {
    /// The seeds of the current dimension, then moves to the next dimension.
    #[inline(always)]
    fn dimension_seeds(&mut self) -> DimensionSeeds {
        let d = self.dimension;
        self.dimension += 1;
        self.pixel.seeds(d)
    }
}

impl Sampler for SobolSampler<'_> {
    #[inline(always)]
    fn seek(&mut self, dimension: u32) {
        self.dimension = dimension;
    }

    #[inline(always)]
    fn next_1d(&mut self) -> f32 {
        let seeds = self.dimension_seeds();
        to_unit(scrambled_vdc(
            shuffle_reversed(self.index_reversed, &seeds),
            seeds.x,
        ))
    }

    /// `(owen(vdc(i), sx), owen(pascal(i), sy))` for the shuffled index `i`, computed with three
    /// bit reversals instead of five: `owen(x) = reverse(lk(reverse(x)))`, `vdc(i) = reverse(i)`,
    /// and `reverse(pascal(i))` comes straight from `reverse(i)` (`pascal_reversed`).
    #[inline(always)]
    fn next_2d(&mut self) -> Vec2 {
        let seeds = self.dimension_seeds();
        let i_reversed = shuffle_reversed(self.index_reversed, &seeds);
        Vec2::new(
            to_unit(scrambled_vdc(i_reversed, seeds.x)),
            to_unit(laine_karras(pascal_reversed(i_reversed), seeds.y).reverse_bits()),
        )
    }
}

impl PixelSampler for SobolPixel {
    type Path<'a> = SobolSampler<'a>;

    #[inline]
    fn for_pixel(seed: u64, pixel: u64) -> Self {
        Self {
            pixel_seed: mix64(seed ^ mix64(pixel.wrapping_add(0xd1b5_4a32_d192_ed03))),
            seeds: [DimensionSeeds::default(); CACHED_DIMENSIONS],
            cached: 0,
        }
    }

    #[inline(always)]
    fn start_sample(&mut self, sample: u32) -> SobolSampler<'_> {
        SobolSampler {
            pixel: self,
            index_reversed: sample.reverse_bits(),
            dimension: 0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Whether `points` (n = 2ᵐ of them) have exactly one point in every elementary interval
    /// `[a/2ᵏ, (a+1)/2ᵏ) × [b/2ᵐ⁻ᵏ, (b+1)/2ᵐ⁻ᵏ)`, for every k in 0..=m: a (0, m, 2)-net.
    fn is_net(points: &[Vec2]) -> bool {
        let n = points.len();
        let m = n.trailing_zeros();
        assert!(n.is_power_of_two());
        (0..=m).all(|k| {
            let (cols, rows) = (1usize << k, 1usize << (m - k));
            let mut seen = vec![false; n];
            points.iter().all(|p| {
                let (x, y) = (p.x * cols as f32, p.y * rows as f32);
                let cell = (y as usize).min(rows - 1) * cols + (x as usize).min(cols - 1);
                !std::mem::replace(&mut seen[cell], true)
            })
        })
    }

    /// Whether the n values fall one into each of n equal intervals.
    fn is_stratified(values: &[f32]) -> bool {
        let n = values.len();
        let mut seen = vec![false; n];
        values
            .iter()
            .all(|&v| !std::mem::replace(&mut seen[((v * n as f32) as usize).min(n - 1)], true))
    }

    fn draw_2d<P: PixelSampler>(seed: u64, pixel: u64, dimension: u32, n: u32) -> Vec<Vec2> {
        (0..n)
            .map(|i| {
                let mut p = P::for_pixel(seed, pixel);
                let mut s = p.start_sample(i);
                s.seek(dimension);
                s.next_2d()
            })
            .collect()
    }

    fn draw_1d<P: PixelSampler>(seed: u64, pixel: u64, dimension: u32, n: u32) -> Vec<f32> {
        (0..n)
            .map(|i| {
                let mut p = P::for_pixel(seed, pixel);
                let mut s = p.start_sample(i);
                s.seek(dimension);
                s.next_1d()
            })
            .collect()
    }

    #[test]
    fn pascal_directions_are_the_binomial_coefficients_mod_2() {
        // Column j, output bit k (from the top): C(j, k) mod 2 = 1 iff k ⊆ j (Lucas).
        for (j, &v) in PASCAL.iter().enumerate() {
            for k in 0..32 {
                assert_eq!((v >> (31 - k)) & 1 == 1, k & j == k, "j {j} k {k}");
            }
        }
    }

    #[test]
    fn the_sampler_computes_the_definition_of_its_points() {
        // The sampler's shortcuts (reversed index, table-driven Pascal dimension, three bit
        // reversals) against the definition: shuffle, then Owen-scramble van der Corput and
        // the Pascal dimension.
        let mut rng = Rng::new(3, 8);
        for _ in 0..20_000 {
            let (seed, pixel, sample) = (
                u64::from(rng.next_u32()),
                u64::from(rng.next_u32()),
                rng.next_u32() >> (rng.next_u32() % 32),
            );
            let dimension = rng.next_u32() % 64;
            let mut p = SobolPixel::for_pixel(seed, pixel);
            let mut s = p.start_sample(sample);
            s.seek(dimension);
            let seeds = s.dimension_seeds();
            let i = shuffle(sample, seeds.shuffle);
            let expected = Vec2::new(
                to_unit(owen(i.reverse_bits(), seeds.x)),
                to_unit(owen(sobol_pascal(i), seeds.y)),
            );
            s.seek(dimension);
            assert_eq!(
                s.next_2d(),
                expected,
                "sample {sample} dimension {dimension}"
            );
            s.seek(dimension);
            assert_eq!(
                s.next_1d(),
                expected.x,
                "sample {sample} dimension {dimension}"
            );
        }
    }

    /// Every value of `S` for (seed, pixel, sample, dimension) drawn by one generator serving
    /// the samples of a pixel in a random order, each with random seeks, against a fresh
    /// generator per draw: what the pixel's generator keeps between samples changes nothing.
    fn served_in_any_order_equals_fresh<P: PixelSampler>() {
        let mut rng = Rng::new(11, 2);
        for pixel in 0..50 {
            let mut served_pixel = P::for_pixel(9, pixel);
            for _ in 0..40 {
                let sample = rng.next_u32() % 16;
                let mut served = served_pixel.start_sample(sample);
                let mut fresh_pixel = P::for_pixel(9, pixel);
                let mut fresh = fresh_pixel.start_sample(sample);
                for _ in 0..6 {
                    let dimension = rng.next_u32() % 48;
                    served.seek(dimension);
                    fresh.seek(dimension);
                    assert_eq!(
                        served.next_2d(),
                        fresh.next_2d(),
                        "pixel {pixel} sample {sample}"
                    );
                    assert_eq!(
                        served.next_1d(),
                        fresh.next_1d(),
                        "pixel {pixel} sample {sample}"
                    );
                }
            }
        }
    }

    #[test]
    fn a_pixel_s_generator_serves_each_sample_as_a_fresh_one_would() {
        served_in_any_order_equals_fresh::<SobolPixel>();
        served_in_any_order_equals_fresh::<IndependentPixel>();
    }

    #[test]
    fn shuffle_permutes_every_power_of_two_prefix() {
        for seed in [0u32, 1, 0xdead_beef, 12345] {
            for m in 0..=10 {
                let n = 1u32 << m;
                let mut seen = vec![false; n as usize];
                for i in 0..n {
                    let j = shuffle(i, seed);
                    assert!(j < n, "seed {seed}: {i} -> {j} outside [0, {n})");
                    assert!(!std::mem::replace(&mut seen[j as usize], true));
                }
            }
        }
    }

    #[test]
    fn every_power_of_two_prefix_is_a_net_in_2d_and_stratified_in_1d() {
        for (seed, pixel, dimension) in [(0, 0, 0), (7, 123, 1), (99, 4095, 6), (1, 77, 37)] {
            for m in 0..=10 {
                let n = 1 << m;
                let p = draw_2d::<SobolPixel>(seed, pixel, dimension, n);
                assert!(
                    is_net(&p),
                    "2D seed {seed} pixel {pixel} dim {dimension}, n {n}"
                );
                let v = draw_1d::<SobolPixel>(seed, pixel, dimension, n);
                assert!(
                    is_stratified(&v),
                    "1D seed {seed} pixel {pixel} dim {dimension}, n {n}"
                );
            }
        }
    }

    #[test]
    fn the_net_check_rejects_independent_points() {
        // The check can fail: independent points are not nets beyond a handful of samples.
        let failures = (0..20)
            .filter(|&pixel| !is_net(&draw_2d::<IndependentPixel>(3, pixel, 0, 64)))
            .count();
        assert_eq!(failures, 20);
        assert!(!is_stratified(&draw_1d::<IndependentPixel>(3, 0, 0, 64)));
    }

    #[test]
    fn values_are_uniform_and_dimensions_and_pixels_independent() {
        // Over many pixels (independent randomisations), sample 5 of two different dimensions:
        // E[x] = 1/2, E[x·y] = 1/4 across dimensions and across the two axes of one dimension.
        let n = 20_000;
        let (mut sx, mut sxy, mut sab) = (0.0f64, 0.0f64, 0.0f64);
        for pixel in 0..n {
            let mut p = SobolPixel::for_pixel(42, pixel);
            let mut s = p.start_sample(5);
            s.seek(3);
            let a = s.next_2d();
            s.seek(9);
            let b = s.next_1d();
            sx += f64::from(a.x);
            sxy += f64::from(a.x * a.y);
            sab += f64::from(a.y * b);
        }
        let n = n as f64;
        // Standard errors: √(1/12 / n) for the mean, √(7/144 / n) for the products; 5σ.
        assert!(
            (sx / n - 0.5).abs() < 5.0 * (1.0 / 12.0 / n).sqrt(),
            "{}",
            sx / n
        );
        let se = (7.0 / 144.0 / n).sqrt();
        assert!((sxy / n - 0.25).abs() < 5.0 * se, "{}", sxy / n);
        assert!((sab / n - 0.25).abs() < 5.0 * se, "{}", sab / n);
    }

    #[test]
    fn neighbouring_pixels_and_dimensions_are_scrambled_differently() {
        let a = draw_2d::<SobolPixel>(0, 10, 0, 4);
        assert_ne!(a, draw_2d::<SobolPixel>(0, 11, 0, 4));
        assert_ne!(a, draw_2d::<SobolPixel>(0, 10, 1, 4));
        assert_ne!(a, draw_2d::<SobolPixel>(1, 10, 0, 4));
    }

    #[test]
    fn independent_sampler_draws_its_stream_in_order() {
        let mut rng = Rng::for_sample(5, 6, 7);
        let mut p = IndependentPixel::for_pixel(5, 6);
        let mut s = p.start_sample(7);
        s.seek(40);
        let (x, y, z) = (rng.next_f32(), rng.next_f32(), rng.next_f32());
        assert_eq!(s.next_2d(), Vec2::new(x, y));
        assert_eq!(s.next_1d(), z);
    }

    #[test]
    fn names_round_trip() {
        for k in SamplerKind::ALL {
            assert_eq!(k.name().parse::<SamplerKind>(), Ok(k));
        }
        assert!("halton".parse::<SamplerKind>().is_err());
    }
}
