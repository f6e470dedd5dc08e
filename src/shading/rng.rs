//! A small deterministic random number generator, seeded per (scene seed, pixel, sample).

/// PCG32 (O'Neill, "PCG: A Family of Simple Fast Space-Efficient Statistically Good Algorithms for
/// Random Number Generation", 2014): 64-bit LCG state, 32-bit permuted output.
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
    inc: u64,
}

/// SplitMix64 finaliser: a bijective 64-bit mix used to derive seeds.
#[inline]
pub(crate) fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

impl Rng {
    /// A generator for one sample: the stream depends only on its arguments, never on which
    /// thread runs it, so renders are identical whatever the thread count.
    #[inline]
    pub fn for_sample(seed: u64, pixel: u64, sample: u64) -> Self {
        Self::for_pixel_sample(Self::pixel_seed(seed, pixel), sample)
    }

    /// The part of [`for_sample`](Self::for_sample)'s seeding that depends only on the pixel.
    #[inline]
    pub fn pixel_seed(seed: u64, pixel: u64) -> u64 {
        mix64(seed ^ mix64(pixel.wrapping_add(0x9e37_79b9_7f4a_7c15)))
    }

    /// `for_sample(seed, pixel, sample)` from `pixel_seed(seed, pixel)`.
    #[inline]
    pub fn for_pixel_sample(pixel_seed: u64, sample: u64) -> Self {
        Self::new(
            pixel_seed,
            mix64(pixel_seed ^ sample.wrapping_mul(0xd1b5_4a32_d192_ed03)),
        )
    }

    /// PCG32 with initial state `state` and stream `stream`.
    #[inline]
    pub fn new(state: u64, stream: u64) -> Self {
        let mut rng = Self {
            state: 0,
            inc: (stream << 1) | 1,
        };
        rng.next_u32();
        rng.state = rng.state.wrapping_add(state);
        rng.next_u32();
        rng
    }

    /// The next 32 random bits.
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in `[0, 1)`; 24 random bits, so never exactly 1.
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floats_are_in_the_unit_interval_with_the_right_mean() {
        let mut rng = Rng::for_sample(1, 2, 3);
        let n = 100_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let x = rng.next_f32();
            assert!((0.0..1.0).contains(&x));
            sum += f64::from(x);
        }
        // Mean 1/2, standard error sqrt(1/12 / n) ≈ 0.0009; allow 5σ.
        assert!((sum / n as f64 - 0.5).abs() < 0.0046);
    }

    #[test]
    fn neighbouring_samples_get_different_streams() {
        let a = Rng::for_sample(0, 10, 0).next_u32();
        let b = Rng::for_sample(0, 10, 1).next_u32();
        let c = Rng::for_sample(0, 11, 0).next_u32();
        let d = Rng::for_sample(1, 10, 0).next_u32();
        assert!(a != b && a != c && a != d && b != c);
    }
}
