//! Exact fixed point: every sample is scaled by a power of two chosen for the scene
//! ([`shift_for`]), rounded once to an integer and added as one, so a sum does not depend on the
//! order its samples were added in.

use glam::Vec3;

/// Bits of headroom above the scene's brightest radiance: a sample may reach 2²⁴ (1.7·10⁷)
/// times the brightest emitter or background before it is clamped.
pub const HEADROOM_BITS: i32 = 24;

/// Magnitude bound of one sample in fixed point: 2⁶², so rounding never overflows an `i64`, and
/// with at most 2³² samples per pixel a sum needs at most 94 bits and a sign
/// ([`Pixel::WORDS`] words).
const SAMPLE_LIMIT: f64 = (1u64 << 62) as f64;

/// The shift of a scene whose brightest radiance (emission or background, any channel) is
/// `max_radiance`: samples are rounded to multiples of 2⁻shift, and a sample may reach
/// 2^[`HEADROOM_BITS`] times the brightest radiance (rounded up to a power of two) before it is
/// clamped. A scene with nothing brighter than 1 uses the shift of 1 (38: a resolution of
/// 3.6·10⁻¹², a range to 1.7·10⁷). Deterministic in `max_radiance` alone, so every process
/// that renders part of a scene picks the same one.
pub fn shift_for(max_radiance: f32) -> i32 {
    let m = if max_radiance.is_finite() && max_radiance > 1.0 {
        max_radiance
    } else if max_radiance.is_finite() && max_radiance > 0.0 {
        max_radiance.max(f32::MIN_POSITIVE)
    } else {
        1.0
    };
    // ⌈log2 m⌉ from the bits: m is normal, so its exponent is exact.
    let bits = m.to_bits();
    let exponent = ((bits >> 23) & 0xff) as i32 - 127;
    let ceil_log2 = exponent + i32::from(bits & 0x7f_ffff != 0);
    62 - HEADROOM_BITS - ceil_log2
}

/// The shift a film starts with before a scene sets its own: that of radiance 1.
pub const DEFAULT_SHIFT: i32 = 62 - HEADROOM_BITS;

/// The fixed-point scale of a film: samples are multiplied by 2^shift and rounded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FixedPoint {
    scale: f64,
}

impl FixedPoint {
    /// The scale 2^`shift`.
    pub fn new(shift: i32) -> Self {
        Self {
            scale: 2f64.powi(shift),
        }
    }

    /// One channel of a sample in fixed point, rounded to nearest (ties away from zero), and
    /// whether it had to be clamped to the representable range. Exact and cheap: the scaled
    /// value fits an `i64`, and the truncation remainder is computed exactly.
    #[inline]
    fn fixed(self, c: f32) -> (i64, bool) {
        let x = f64::from(c) * self.scale;
        let (x, clamped) = if x.abs() < SAMPLE_LIMIT {
            (x, false)
        } else {
            (SAMPLE_LIMIT.copysign(x), true)
        };
        let t = x as i64;
        let r = x - t as f64;
        let v = if r >= 0.5 {
            t + 1
        } else if r <= -0.5 {
            t - 1
        } else {
            t
        };
        (v, clamped)
    }

    /// The fixed-point value of one sample (`l` must be finite), and whether any channel was
    /// clamped to the range.
    #[inline]
    pub fn pixel(self, l: Vec3) -> (Pixel, bool) {
        let (x, cx) = self.fixed(l.x);
        let (y, cy) = self.fixed(l.y);
        let (z, cz) = self.fixed(l.z);
        (
            Pixel([i128::from(x), i128::from(y), i128::from(z)]),
            cx | cy | cz,
        )
    }

    /// The mean of `count` samples whose sum is `sum` (zero for no samples).
    #[inline]
    pub fn mean(self, sum: &Pixel, count: u64) -> Vec3 {
        let scale = 1.0 / (self.scale * count.max(1) as f64);
        Vec3::new(
            (sum.0[0] as f64 * scale) as f32,
            (sum.0[1] as f64 * scale) as f32,
            (sum.0[2] as f64 * scale) as f32,
        )
    }
}

/// The exact sum of a pixel's samples, per channel, in units of 2⁻shift of its film.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Pixel(pub [i128; 3]);

impl Pixel {
    /// A zero sum.
    pub const ZERO: Self = Self([0; 3]);

    /// 32-bit words a channel's sum is stored in (two's complement, least significant first).
    pub const WORDS: usize = 3;

    /// Adds one sample (`l` must be finite) in `fixed` point; true if a channel was clamped.
    #[inline]
    pub fn add(&mut self, l: Vec3, fixed: FixedPoint) -> bool {
        let (p, clamped) = fixed.pixel(l);
        self.merge(&p);
        clamped
    }

    /// Adds another sum (exact, so in any order).
    #[inline]
    pub fn merge(&mut self, other: &Self) {
        for (a, b) in self.0.iter_mut().zip(other.0) {
            *a += b;
        }
    }

    /// The sum of this and `other`, or `None` if a channel's leaves the [`Pixel::WORDS`] words
    /// it is stored in (sums read from files, which anyone may have written).
    pub fn checked_merge(&self, other: &Self) -> Option<Self> {
        const BOUND: i128 = 1 << (32 * Pixel::WORDS - 1);
        let mut sum = Self::ZERO;
        for ((s, a), b) in sum.0.iter_mut().zip(self.0).zip(other.0) {
            *s = a.checked_add(b).filter(|v| (-BOUND..BOUND).contains(v))?;
        }
        Some(sum)
    }

    /// Channel `c`'s sum as [`Pixel::WORDS`] 32-bit words, least significant first.
    #[inline]
    pub fn words(&self, c: usize) -> [u32; Self::WORDS] {
        let v = self.0[c];
        [v as u32, (v >> 32) as u32, (v >> 64) as u32]
    }

    /// Channel `c`'s sum from its words (the inverse of [`Pixel::words`]).
    #[inline]
    pub fn set_words(&mut self, c: usize, w: [u32; Self::WORDS]) {
        let raw = u128::from(w[0]) | (u128::from(w[1]) << 32) | (u128::from(w[2]) << 64);
        // Sign-extend from 96 bits.
        self.0[c] = ((raw << 32) as i128) >> 32;
    }
}

/// The fixed-point shift of the normal feature buffer: normals are unit vectors, so the shift of
/// radiance 1.
pub const NORMAL_SHIFT: i32 = DEFAULT_SHIFT;

/// The fixed-point shift of the albedo feature buffer: albedos are reflectances, at most 1 (an
/// emitter's or the sky's may be more, up to 2^[`HEADROOM_BITS`] before it is clamped), so the
/// shift of radiance 1, whatever the colour's: the colour's shift of a scene lit at 10⁻¹⁰ leaves
/// a range of about 10⁻³, which would clamp every albedo, and that of a scene lit at 10³⁸ a
/// resolution of about 10³¹, which would round every albedo to zero.
pub const ALBEDO_SHIFT: i32 = DEFAULT_SHIFT;

/// The fixed point of [`NORMAL_SHIFT`], made once rather than per sample.
pub(super) const NORMAL_FIXED: FixedPoint = FixedPoint {
    scale: (1u64 << NORMAL_SHIFT) as f64,
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checked_merges_stop_at_the_96_bits_a_sum_is_stored_in() {
        let top = (1i128 << 95) - 1;
        let at = |v: i128| Pixel([v, 0, 0]);
        assert_eq!(at(top - 1).checked_merge(&at(1)), Some(at(top)));
        assert_eq!(at(top).checked_merge(&at(1)), None);
        assert_eq!(at(-top).checked_merge(&at(-1)), Some(at(-top - 1)));
        assert_eq!(at(-top - 1).checked_merge(&at(-1)), None);
        assert_eq!(Pixel([0, top, 0]).checked_merge(&Pixel([0, top, 0])), None);
        // What fits reads back from its words.
        let mut back = Pixel::ZERO;
        back.set_words(0, at(-top - 1).words(0));
        assert_eq!(back, at(-top - 1));
    }

    #[test]
    fn fixed_point_rounds_to_nearest_and_sums_in_any_order() {
        let fixed = FixedPoint::new(32);
        let unit = 2f32.powi(-32);
        let one = |c: f32| fixed.fixed(c);
        assert_eq!(one(1.0), (1 << 32, false));
        assert_eq!(one(-0.25), (-(1 << 30), false));
        assert_eq!(one(unit * 0.49), (0, false));
        assert_eq!(one(unit * 0.5), (1, false));
        assert_eq!(one(-unit * 0.5), (-1, false));
        // Beyond 2^62 units (2^30 at shift 32) a channel is clamped, and says so.
        assert_eq!(one(f32::MAX), (1 << 62, true));
        assert_eq!(one(-f32::MAX), (-(1 << 62), true));
        assert_eq!(
            one(2f32.powi(30) * 0.999),
            (
                (f64::from(2f32.powi(30) * 0.999) * 2f64.powi(32)) as i64,
                false
            )
        );
        // Values that do not add associatively in floating point.
        let samples = [1e8f32, 1e-3, -1e8, 3.7e-5, 0.1, 12345.678];
        let mut forward = Pixel::ZERO;
        samples.iter().for_each(|&s| {
            forward.add(Vec3::splat(s), fixed);
        });
        let mut backward = Pixel::ZERO;
        samples.iter().rev().for_each(|&s| {
            backward.add(Vec3::splat(s), fixed);
        });
        assert_eq!(forward, backward);
        let f: f32 = samples.iter().sum();
        let b: f32 = samples.iter().rev().sum();
        assert_ne!(f, b, "the samples must not be associative in f32");
    }

    #[test]
    fn the_shift_gives_every_brightness_its_headroom_and_precision() {
        assert_eq!(shift_for(1.0), DEFAULT_SHIFT);
        assert_eq!(
            shift_for(0.0),
            DEFAULT_SHIFT,
            "a black scene keeps the default"
        );
        assert_eq!(shift_for(f32::NAN), DEFAULT_SHIFT);
        assert_eq!(shift_for(2.0), DEFAULT_SHIFT - 1);
        assert_eq!(
            shift_for(2.5),
            DEFAULT_SHIFT - 2,
            "rounded up to a power of two"
        );
        assert_eq!(shift_for(0.5), DEFAULT_SHIFT + 1);
        for m in [
            1e-30f32,
            1e-10,
            3e-10,
            0.7,
            17.0,
            1.6e9,
            5e9,
            1e30,
            f32::MAX,
        ] {
            let fixed = FixedPoint::new(shift_for(m));
            // The brightest radiance, and 2^HEADROOM_BITS times it less an ulp, are not clamped;
            // four times beyond the headroom is.
            let headroom = 2f32.powi(HEADROOM_BITS);
            assert!(!fixed.pixel(Vec3::splat(m)).1, "{m}");
            if (m * headroom).is_finite() {
                assert!(!fixed.pixel(Vec3::splat(m * headroom * 0.999)).1, "{m}");
            }
            if (m * headroom * 4.0).is_finite() {
                assert!(fixed.pixel(Vec3::splat(m * headroom * 4.0)).1, "{m}");
            }
            // One sample at 10⁻⁶ of the brightest value is kept to 2⁻³⁸ of the brightest
            // (rounded up to a power of two): a relative error below 10⁻⁵.
            let small = m * 1e-6;
            let mean = fixed.mean(&fixed.pixel(Vec3::splat(small)).0, 1);
            let rel = ((mean.x - small) / small).abs();
            assert!(rel < 1e-5, "{m}: {rel}");
        }
    }

    #[test]
    fn words_round_trip_negative_and_large_sums() {
        for v in [
            0i128,
            1,
            -1,
            i128::from(i64::MAX) * 3,
            -(1i128 << 94),
            (1 << 94) - 1,
        ] {
            let p = Pixel([v, -v, v / 7]);
            let mut q = Pixel::ZERO;
            for c in 0..3 {
                q.set_words(c, p.words(c));
            }
            assert_eq!(p, q);
        }
    }
}
