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
//! function. The texel of a direction is found without inverse trigonometry: a polynomial
//! `atan2` guesses the row and the column, and the guess is corrected against tables of the
//! rows' and columns' edge directions (the sign of a 2-D cross product with the edge), so the
//! assignment is exact with respect to those tables; it can differ from the `atan2` / `acos`
//! formula above only within float rounding of an edge.
//!
//! # Sampling
//!
//! A texel is chosen with probability proportional to its luminance times its solid angle
//! (pbrt-v4 §12.5's luminance × sin θ, integrated over the texel's rows): first its row from the
//! marginal table, then its column from the row's conditional table, each held as cumulative
//! counts out of 2²⁴, the resolution of the sampler's numbers, as the emitter table does
//! ([`crate::lights`]). So a texel's probability is exactly the frequency with which 24-bit
//! numbers pick it, and a texel whose count rounds to 0 is never picked and has density 0 (BSDF
//! sampling finds it at full weight). The search for the count is O(1) expected: a guide table
//! (the cutpoint method) per table gives, for each of its equal slices of the 24-bit numbers,
//! the first entry the slice can pick, and a binary search runs only between the first entries
//! of a slice and of the next (a few entries on average, whatever the distribution). Within
//! the texel the direction is uniform in solid angle (φ uniform, cos θ uniform between the
//! row's edges), from a second, independent pair of numbers, so the density is the texel's
//! probability over its solid angle: constant over the texel, like the radiance. It is the
//! row's density per count (the row's probability over 2²⁴ and over a texel's solid angle,
//! computed in `f64`) times the texel's count: a sample returns the radiance and density of the
//! texel it picked, and [`EnvironmentMap::lookup`] reads both from one texel of 16 bytes (and
//! its left neighbour's count, usually in the same cache line).
//!
//! # Memory
//!
//! 16 bytes per texel, the distribution included: the radiance as three `f32` and the row's
//! cumulative count through the texel (an integer ≤ 2²⁴, exact as an `f32`). Besides: the
//! column guide tables, one `u32` per 8 to 16 texels (at most 1/2 byte per texel), and per
//! row and per column a few numbers: at most 36 bytes per row (its marginal count, density and
//! band, its edge, its share of the row guide), 8 per column (its edge) and 16 more. At
//! [`MAX_TEXELS`] that is at most 528 MiB (16.5 bytes per texel), the small tables aside.

use std::f32::consts::{FRAC_PI_2, PI};

use glam::{Vec2, Vec3};
use rayon::prelude::*;

/// Resolution of the tables: cumulative counts out of 2²⁴.
const SCALE: u32 = 1 << 24;

/// Most texels a map may have (a 8192 × 4096 map): at most 528 MiB at 16.5 bytes each.
pub const MAX_TEXELS: u64 = 1 << 25;

/// A column guide table has one entry per `2^COLUMN_GUIDE_SPARSITY` to twice as many columns
/// (a power of two): at most 1/2 byte per texel, and a search between two of its entries spans
/// at most 17 texels on average over the 24-bit numbers, 9 for a width that is a power of two
/// (a denser table, 2 bytes per texel, measured no faster: the cost is the miss on the picked
/// texel's line, which the search brings in).
const COLUMN_GUIDE_SPARSITY: u32 = 3;

/// At most this many corrections of a texel guess (the guess is off by at most one for maps
/// up to 2¹⁶ columns; the bound only keeps a degenerate direction, zero or NaN, from looping).
const MAX_CORRECTIONS: usize = 8;

/// Relative luminance of linear Rec. 709 RGB.
#[inline]
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// A map's row: its marginal count, its density per count and its band of cos θ.
#[derive(Clone, Copy, Debug, Default)]
struct Row {
    /// Marginal cumulative count through this row.
    cumulative: u32,
    /// Density per steradian of a texel of this row per unit of its conditional count: the
    /// row's probability over 2²⁴, over a texel's solid angle (0 for a map without light).
    density_per_count: f32,
    /// `1 ∓ cos θ` of the edge nearer its pole (top edge for the upper half, where `1 − cos θ`,
    /// bottom edge for the lower half, where `1 + cos θ`): `2 sin²` / `2 cos²` of half the
    /// angle, precise near the pole where `1 − cos θ` would cancel.
    from_pole: f32,
    /// `cos θ_top − cos θ_bottom`: the band's solid angle over 2π.
    band: f32,
    /// +1 for a row of the upper half (θ measured from +y), −1 for the lower half.
    sign: f32,
}

/// A direction sampled from the map, with the radiance and density of the texel it lies in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapSample {
    /// Unit direction (map space).
    pub direction: Vec3,
    /// Radiance of the texel.
    pub radiance: Vec3,
    /// Density per steradian: what [`EnvironmentMap::lookup`] gives for the direction (except
    /// within float rounding of the texel's edge, where the direction may read a neighbour).
    pub pdf: f32,
}

/// An environment map in map space (see the module docs for the convention).
#[derive(Debug)]
pub struct EnvironmentMap {
    width: u32,
    height: u32,
    /// Per texel, row-major from row 0 (up): linear RGB radiance, then the row's cumulative
    /// count through the texel as an `f32` (the last column's is 2²⁴).
    texels: Vec<f32>,
    /// Per row: marginal count, density and band.
    rows: Vec<Row>,
    /// Guide table of the marginal counts (see [`guided_pick`]).
    row_guide: Vec<u32>,
    /// Shift of a 24-bit number to its slice of `row_guide`.
    row_shift: u32,
    /// The rows' column guide tables, `column_guide_len` entries each.
    column_guide: Vec<u32>,
    /// Entries of a row's column guide table.
    column_guide_len: usize,
    /// Shift of a 24-bit number to its slice of a column guide table.
    column_shift: u32,
    /// `(sin θ_i, cos θ_i)` of the rows' edges, `θ_i = iπ / height`, `height + 1` of them.
    row_edges: Vec<[f32; 2]>,
    /// `(sin φ_j, cos φ_j)` of the columns' edges, `φ_j = 2πj / width`, `width + 1` of them
    /// (the last one is the first: the map wraps around).
    column_edges: Vec<[f32; 2]>,
    /// A column's angular width, 2π / width.
    column_angle: f32,
    /// Solid-angle mean of the radiance over the sphere.
    mean: Vec3,
    /// Largest channel of any texel.
    max: f32,
    /// Whether any texel has luminance > 0 (otherwise there is nothing to sample).
    lit: bool,
}

/// The cumulative count out of [`SCALE`] of a running sum `acc` of weights summing to `total`
/// (> 0): [`SCALE`] exactly at the `last` weight.
fn count(acc: f64, total: f64, last: bool) -> u32 {
    if last {
        SCALE
    } else {
        ((acc / total) * f64::from(SCALE))
            .round()
            .min(f64::from(SCALE)) as u32
    }
}

/// Bits of a guide table of at most `n / 2^sparsity` entries and more than half that (a
/// power of two, at most 2²⁴, at least 1).
fn guide_bits(n: usize, sparsity: u32) -> u32 {
    n.max(1).ilog2().saturating_sub(sparsity).min(24)
}

/// Fills `guide` (2^bits entries, shift `24 − bits`): entry `b` is the index that the 24-bit
/// number `b << shift` picks from the `n` non-decreasing cumulative counts `at` (the last one
/// [`SCALE`]), the first whose count exceeds it.
fn build_guide(guide: &mut [u32], shift: u32, n: usize, at: impl Fn(usize) -> u32) {
    let mut k = 0usize;
    for (b, g) in guide.iter_mut().enumerate() {
        let start = (b as u32) << shift;
        while k + 1 < n && at(k) <= start {
            k += 1;
        }
        *g = k as u32;
    }
}

/// The 24-bit reading of `u` ∈ [0, 1).
#[inline]
fn bits24(u: f32) -> u32 {
    ((u * SCALE as f32) as u32).min(SCALE - 1)
}

/// The index that the 24-bit number `g` picks from `n` cumulative counts `at` (non-decreasing,
/// the last one [`SCALE`]): the first whose count exceeds `g`. `guide` (from [`build_guide`])
/// bounds it: every index before `guide[b]` has a count ≤ `b << shift` ≤ `g`, and
/// `guide[b + 1]` has one > `(b + 1) << shift` > `g`; the binary search runs between them.
#[inline]
fn guided_pick(guide: &[u32], shift: u32, n: usize, g: u32, at: impl Fn(usize) -> f32) -> usize {
    let (mut lo, mut hi) = guide_bounds(guide, shift, n, g);
    // Counts are integers ≤ 2²⁴, exact as f32, and so is g.
    let g = g as f32;
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

/// The first and last index that the 24-bit number `g` can pick by `guide` of `n` counts.
#[inline]
fn guide_bounds(guide: &[u32], shift: u32, n: usize, g: u32) -> (usize, usize) {
    let b = (g >> shift) as usize;
    let lo = guide.get(b).map_or(0, |&k| k as usize);
    let hi = guide.get(b + 1).map_or(n - 1, |&k| k as usize);
    (lo, hi)
}

/// `atan2(y, x)` within 1e-5 rad (Abramowitz & Stegun 4.4.49 on the octant), without libm.
#[inline]
fn atan2_approx(y: f32, x: f32) -> f32 {
    let (ax, ay) = (x.abs(), y.abs());
    let (lo, hi) = (ax.min(ay), ax.max(ay));
    let t = if hi > 0.0 { lo / hi } else { 0.0 };
    let t2 = t * t;
    let mut a = t
        * (0.999_866
            + t2 * (-0.330_299_5 + t2 * (0.180_141 + t2 * (-0.085_133 + t2 * 0.020_835_1))));
    if ay > ax {
        a = FRAC_PI_2 - a;
    }
    if x < 0.0 {
        a = PI - a;
    }
    if y < 0.0 { -a } else { a }
}

/// `(sin δ, cos δ)` for 0 ≤ δ ≤ π/8 by Taylor polynomials (errors below 1e-9).
#[inline]
fn sin_cos_small(d: f32) -> (f32, f32) {
    let d2 = d * d;
    let s = d * (1.0 - d2 / 6.0 * (1.0 - d2 / 20.0 * (1.0 - d2 / 42.0)));
    let c = 1.0 - d2 / 2.0 * (1.0 - d2 / 12.0 * (1.0 - d2 / 30.0 * (1.0 - d2 / 56.0)));
    (s, c)
}

impl EnvironmentMap {
    /// A map of `width` × `height` texels from linear RGB floats, row-major from the top row
    /// (`3 · width · height` values). Refuses an empty or oversized map and a texel that is
    /// not finite; negative values (filtering ringing in some tools) are read as 0.
    pub fn from_linear(width: u32, height: u32, pixels: &[f32]) -> Result<Self, String> {
        Self::check_size(width, height, pixels.len())?;
        let mut v = Vec::with_capacity(4 * pixels.len() / 3);
        v.extend_from_slice(pixels);
        Self::from_linear_vec(width, height, v)
    }

    /// [`EnvironmentMap::from_linear`] taking the floats by value: they become the map's
    /// texels in place, validated and clamped rows in parallel, then widened to four floats per
    /// texel within the same buffer (grown by `realloc`, which moves a large block by remapping
    /// its pages, not by copying them; no copy at all if its capacity already holds four floats
    /// per texel).
    pub fn from_linear_vec(width: u32, height: u32, mut pixels: Vec<f32>) -> Result<Self, String> {
        Self::check_size(width, height, pixels.len())?;
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
        // Three floats per texel to four, from the last texel back: texel i moves from 3i to
        // 4i ≥ 3i, over texels already moved.
        let n = pixels.len() / 3;
        pixels.resize(4 * n, 0.0);
        for i in (0..n).rev() {
            let texel = [pixels[3 * i], pixels[3 * i + 1], pixels[3 * i + 2], 0.0];
            pixels[4 * i..4 * i + 4].copy_from_slice(&texel);
        }
        // The map holds what it says (`bytes`), not a decoder's spare capacity.
        pixels.shrink_to_fit();
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

    /// Builds the tables of validated texels (finite, non-negative; four floats per texel, the
    /// fourth free for the counts), rows in parallel.
    fn build(width: u32, height: u32, mut texels: Vec<f32>) -> Self {
        let (w, h) = (width as usize, height as usize);
        let column_bits = guide_bits(w, COLUMN_GUIDE_SPARSITY);
        let column_guide_len = 1usize << column_bits;
        let column_shift = 24 - column_bits;
        let mut column_guide = vec![0u32; h * column_guide_len];
        // Per row: the sum of its luminances and of its radiance (f64, so 4096 columns lose
        // nothing), its largest channel; its conditional counts and their guide table.
        let sums: Vec<(f64, [f64; 3], f32)> = texels
            .par_chunks_mut(4 * w)
            .zip(column_guide.par_chunks_mut(column_guide_len))
            .map(|(row, guide)| {
                // The luminances first go to the fourth float, then their counts replace them.
                let mut sum = 0.0f64;
                let mut rgb = [0.0f64; 3];
                let mut max = 0.0f32;
                for t in row.chunks_exact_mut(4) {
                    t[3] = luminance(Vec3::new(t[0], t[1], t[2]));
                    sum += f64::from(t[3]);
                    for c in 0..3 {
                        rgb[c] += f64::from(t[c]);
                        max = max.max(t[c]);
                    }
                }
                // A row without light is never picked (its marginal count is 0); uniform for
                // completeness.
                let total = if sum > 0.0 { sum } else { w as f64 };
                let mut acc = 0.0f64;
                for (k, t) in row.chunks_exact_mut(4).enumerate() {
                    acc += if sum > 0.0 { f64::from(t[3]) } else { 1.0 };
                    t[3] = count(acc, total, k + 1 == w) as f32;
                }
                build_guide(guide, column_shift, w, |k| row[4 * k + 3] as u32);
                (sum, rgb, max)
            })
            .collect();
        let band = |i: usize| Self::band(height, i);
        let weights = || sums.iter().enumerate().map(|(i, r)| r.0 * band(i));
        let total: f64 = weights().sum();
        let mut marginal = vec![0u32; h];
        let lit = total > 0.0 && total.is_finite();
        if lit {
            let mut acc = 0.0f64;
            for (k, weight) in weights().enumerate() {
                acc += weight;
                marginal[k] = count(acc, total, k + 1 == h);
            }
        }
        let row_bits = (guide_bits(h, 0) + 1).min(24);
        let row_shift = 24 - row_bits;
        let mut row_guide = vec![0u32; 1 << row_bits];
        build_guide(&mut row_guide, row_shift, h, |i| marginal[i]);
        let pi = std::f64::consts::PI;
        let tau = std::f64::consts::TAU;
        let theta = |i: usize| pi * i as f64 / h as f64;
        let rows = (0..h)
            .map(|i| {
                let count = marginal[i] - if i == 0 { 0 } else { marginal[i - 1] };
                let solid_angle = band(i) * tau / w as f64;
                let probability_per_count =
                    f64::from(count) / (f64::from(SCALE) * f64::from(SCALE));
                let upper = 2 * i < h;
                let from_pole = if upper {
                    2.0 * (0.5 * theta(i)).sin().powi(2)
                } else {
                    2.0 * (0.5 * theta(i + 1)).cos().powi(2)
                };
                Row {
                    cumulative: marginal[i],
                    density_per_count: (probability_per_count / solid_angle) as f32,
                    from_pole: from_pole as f32,
                    band: band(i) as f32,
                    sign: if upper { 1.0 } else { -1.0 },
                }
            })
            .collect();
        let row_edges = (0..=h)
            .map(|i| [theta(i).sin() as f32, theta(i).cos() as f32])
            .collect();
        let column_edges = (0..=w)
            .map(|j| {
                let phi = tau * (j % w) as f64 / w as f64;
                [phi.sin() as f32, phi.cos() as f32]
            })
            .collect();
        // Mean over the sphere: Σ L · ΔΩ / 4π, with ΔΩ = band(i) · 2π / width per texel.
        let mut mean = [0.0f64; 3];
        for (i, (_, rgb, _)) in sums.iter().enumerate() {
            for c in 0..3 {
                mean[c] += rgb[c] * band(i) * tau / w as f64;
            }
        }
        let mean = Vec3::from_array(mean.map(|m| (m / (4.0 * pi)) as f32));
        let max = sums.iter().fold(0.0f32, |m, r| m.max(r.2));
        Self {
            width,
            height,
            texels,
            rows,
            row_guide,
            row_shift,
            column_guide,
            column_guide_len,
            column_shift,
            row_edges,
            column_edges,
            column_angle: (tau / w as f64) as f32,
            mean,
            max,
            lit,
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
            + std::mem::size_of_val(self.rows.as_slice())
            + std::mem::size_of_val(self.row_guide.as_slice())
            + std::mem::size_of_val(self.column_guide.as_slice())
            + std::mem::size_of_val(self.row_edges.as_slice())
            + std::mem::size_of_val(self.column_edges.as_slice())
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

    /// The texel (row, column) that direction `d` (map space, any length > 0) reads: a guess
    /// from [`atan2_approx`], corrected against the edge tables. A direction is at or below
    /// row edge `i` when `sin(θ − θ_i) ≥ 0`, at or after column edge `j` when
    /// `sin(φ − φ_j) ≥ 0` (both 2-D cross products with the edge, valid within half a turn of
    /// it, which the guess is).
    #[inline]
    pub fn texel_of(&self, d: Vec3) -> (usize, usize) {
        let (w, h) = (self.width as usize, self.height as usize);
        let (a, b) = (d.x, -d.z);
        let r = (a * a + b * b).sqrt();
        let below = |i: usize| {
            let [s, c] = self.row_edges[i];
            r * c - d.y * s >= 0.0
        };
        let theta = atan2_approx(r, d.y);
        let mut row = ((theta * (h as f32 / PI)) as usize).min(h - 1);
        for _ in 0..MAX_CORRECTIONS {
            if row > 0 && !below(row) {
                row -= 1;
            } else if row + 1 < h && below(row + 1) {
                row += 1;
            } else {
                break;
            }
        }
        if w == 1 {
            return (row, 0);
        }
        let after = |j: usize| {
            let [s, c] = self.column_edges[j];
            a * c - b * s >= 0.0
        };
        let mut u = atan2_approx(a, b) * (w as f32 / (2.0 * PI));
        if u < 0.0 {
            u += w as f32;
        }
        let mut column = (u as usize).min(w - 1);
        for _ in 0..MAX_CORRECTIONS {
            if !after(column) {
                column = if column == 0 { w - 1 } else { column - 1 };
            } else if after(column + 1) {
                column = if column + 1 == w { 0 } else { column + 1 };
            } else {
                break;
            }
        }
        (row, column)
    }

    /// Radiance along direction `d` (map space).
    #[inline]
    pub fn radiance(&self, d: Vec3) -> Vec3 {
        let (row, column) = self.texel_of(d);
        self.texel(row, column).0
    }

    /// Radiance and density per steradian of texel `(row, column)`.
    #[inline]
    fn texel(&self, row: usize, column: usize) -> (Vec3, f32) {
        let i = 4 * (row * self.width as usize + column);
        let t = &self.texels[i..i + 4];
        let before = if column == 0 { 0.0 } else { self.texels[i - 1] };
        (
            Vec3::new(t[0], t[1], t[2]),
            (t[3] - before) * self.rows[row].density_per_count,
        )
    }

    /// Radiance along direction `d` (map space) and the density with which
    /// [`EnvironmentMap::sample`] gives it ([`EnvironmentMap::pdf`]), from one texel lookup.
    #[inline]
    pub fn lookup(&self, d: Vec3) -> (Vec3, f32) {
        let (row, column) = self.texel_of(d);
        self.texel(row, column)
    }

    /// Probability that [`EnvironmentMap::sample`] picks texel `(row, column)`, from the counts.
    #[cfg(test)]
    fn texel_probability(&self, row: usize, column: usize) -> f32 {
        let m = self.rows[row].cumulative
            - if row == 0 {
                0
            } else {
                self.rows[row - 1].cumulative
            };
        let at = |j: usize| self.texels[4 * (row * self.width as usize + j) + 3];
        let c = at(column) - if column == 0 { 0.0 } else { at(column - 1) };
        (f64::from(m) * f64::from(c) / (f64::from(SCALE) * f64::from(SCALE))) as f32
    }

    /// Density per steradian with which [`EnvironmentMap::sample`] gives direction `d` (map
    /// space): its texel's probability over the texel's solid angle.
    #[inline]
    pub fn pdf(&self, d: Vec3) -> f32 {
        self.lookup(d).1
    }

    /// A direction (map space, unit) sampled by the texel distribution, with its texel's
    /// radiance and density: `u` picks the texel (`u.y` the row, `u.x` the column), `jitter`
    /// the direction within it. `None` for a map without light.
    #[inline]
    pub fn sample(&self, u: Vec2, jitter: Vec2) -> Option<MapSample> {
        if !self.lit {
            return None;
        }
        let (w, h) = (self.width as usize, self.height as usize);
        let row = guided_pick(&self.row_guide, self.row_shift, h, bits24(u.y), |i| {
            self.rows[i].cumulative as f32
        });
        let guide = &self.column_guide[row * self.column_guide_len..][..self.column_guide_len];
        let base = 4 * row * w + 3;
        let column = guided_pick(guide, self.column_shift, w, bits24(u.x), |j| {
            self.texels[base + 4 * j]
        });
        let (radiance, pdf) = self.texel(row, column);
        // φ = φ_j + δ: the edge's sine and cosine from the table, δ's by polynomial (a
        // column of a map 16 or more texels wide spans at most π/8).
        let delta = jitter.x * self.column_angle;
        let (sd, cd) = if w >= 16 {
            sin_cos_small(delta)
        } else {
            delta.sin_cos()
        };
        let [s0, c0] = self.column_edges[column];
        let (sin_phi, cos_phi) = (s0 * cd + c0 * sd, c0 * cd - s0 * sd);
        // cos θ uniform over the row's band, as `sign · (1 − m)` with `m` the distance in
        // cos θ from the nearer pole, so that sin θ = √(m (2 − m)) keeps its precision there.
        let row_info = self.rows[row];
        let t = if row_info.sign > 0.0 {
            jitter.y
        } else {
            1.0 - jitter.y
        };
        let m = row_info.from_pole + t * row_info.band;
        let cos_theta = (row_info.sign * (1.0 - m)).clamp(-1.0, 1.0);
        let sin_theta = (m * (2.0 - m)).max(0.0).sqrt();
        Some(MapSample {
            direction: Vec3::new(sin_theta * sin_phi, cos_theta, -sin_theta * cos_phi),
            radiance,
            pdf,
        })
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
}
