//! Cumulative-count tables out of 2²⁴ and their guide tables: the environment map's texel
//! choice ([`super::environment`]). A 24-bit number picks the first index whose count exceeds
//! it, so an index's probability is exactly its share of the counts; a guide table of
//! `2^bits` entries bounds that search to a few entries in O(1) (the cutpoint method). No ECS
//! here.

/// Resolution of the tables: cumulative counts out of 2²⁴.
pub(super) const SCALE: u32 = 1 << 24;

/// The cumulative count out of [`SCALE`] of a running sum `acc` of weights summing to `total`
/// (> 0): [`SCALE`] exactly at the `last` weight.
pub(super) fn count(acc: f64, total: f64, last: bool) -> u32 {
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
pub(super) fn guide_bits(n: usize, sparsity: u32) -> u32 {
    n.max(1).ilog2().saturating_sub(sparsity).min(24)
}

/// Fills `guide` (2^bits entries, shift `24 − bits`): entry `b` is the index that the 24-bit
/// number `b << shift` picks from the `n` non-decreasing cumulative counts `at` (the last one
/// [`SCALE`]), the first whose count exceeds it.
pub(super) fn build_guide(guide: &mut [u32], shift: u32, n: usize, at: impl Fn(usize) -> u32) {
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
pub(super) fn bits24(u: f32) -> u32 {
    ((u * SCALE as f32) as u32).min(SCALE - 1)
}

/// The index that the 24-bit number `g` picks from `n` cumulative counts `at` (non-decreasing,
/// the last one [`SCALE`]): the first whose count exceeds `g`. `guide` (from [`build_guide`])
/// bounds it: every index before `guide[b]` has a count ≤ `b << shift` ≤ `g`, and
/// `guide[b + 1]` has one > `(b + 1) << shift` > `g`; the binary search runs between them.
#[inline]
pub(super) fn guided_pick(
    guide: &[u32],
    shift: u32,
    n: usize,
    g: u32,
    at: impl Fn(usize) -> f32,
) -> usize {
    let (lo, hi) = guide_bounds(guide, shift, n, g);
    search(lo, hi, g, at)
}

/// The first index in `lo..=hi` whose count `at` exceeds the 24-bit number `g`, `hi` if none
/// before it does (the bounds of [`guide_bounds`]).
#[inline]
pub(super) fn search(mut lo: usize, mut hi: usize, g: u32, at: impl Fn(usize) -> f32) -> usize {
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
pub(super) fn guide_bounds(guide: &[u32], shift: u32, n: usize, g: u32) -> (usize, usize) {
    let b = (g >> shift) as usize;
    let lo = guide.get(b).map_or(0, |&k| k as usize);
    let hi = guide.get(b + 1).map_or(n - 1, |&k| k as usize);
    (lo, hi)
}
