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
//! of a slice and of the next (a few entries on average, whatever the distribution), whose
//! lines are asked for all at once before it starts, so that their cache misses overlap. Within
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

use super::guide::{
    SCALE, bits24, build_guide, count, guide_bits, guide_bounds, guided_pick, search,
};
use super::prefetch::prefetch;

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
    /// from `atan2_approx`, corrected against the edge tables. A direction is at or below
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
        let g = bits24(u.x);
        let (lo, hi) = guide_bounds(guide, self.column_shift, w, g);
        // The search's first, middle and last counts (and the left neighbour's, for the
        // density) asked for at once: their lines' misses overlap instead of following one
        // another down the search.
        prefetch(&self.texels, (base + 4 * lo).wrapping_sub(4));
        prefetch(&self.texels, base + 2 * (lo + hi));
        prefetch(&self.texels, base + 4 * hi);
        let column = search(lo, hi, g, |j| self.texels[base + 4 * j]);
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
mod tests;
