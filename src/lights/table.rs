//! Choosing a light by its power (pbrt-v4's `PowerLightSampler`). No ECS here.
//!
//! The table holds cumulative counts out of 2²⁴, the resolution of the random numbers
//! (`Rng::next_f32`): a light's probability is its count / 2²⁴, exactly the frequency with which a
//! 24-bit `u_select` picks it, within 2⁻²⁴ of its share of the power (the running sum is taken
//! in f64). A light whose count rounds to 0 is never picked and has density 0, so it is left to
//! BSDF sampling at full weight.

/// Resolution of the table: cumulative counts out of 2²⁴.
const SELECT_SCALE: u32 = 1 << 24;

/// Selection probabilities proportional to power.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PowerTable {
    /// Cumulative selection counts out of [`SELECT_SCALE`], ending at it.
    cdf: Vec<u32>,
}

impl PowerTable {
    /// The table of lights of power `powers` (a power that is not positive and finite counts as
    /// 0); empty if their sum is not positive and finite: nothing worth sampling.
    pub fn new(powers: &[f64]) -> Self {
        let powers: Vec<f64> = powers
            .iter()
            .map(|&p| if p > 0.0 && p.is_finite() { p } else { 0.0 })
            .collect();
        let total: f64 = powers.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            return Self::default();
        }
        let mut acc = 0.0f64;
        let mut cdf: Vec<u32> = powers
            .iter()
            .map(|p| {
                acc += p;
                ((acc / total) * f64::from(SELECT_SCALE)).round() as u32
            })
            .collect();
        if let Some(last) = cdf.last_mut() {
            *last = SELECT_SCALE;
        }
        Self { cdf }
    }

    /// Whether there is nothing to choose.
    pub fn is_empty(&self) -> bool {
        self.cdf.is_empty()
    }

    /// Probability that [`PowerTable::select`] picks light `k` (0 for an index out of range).
    #[inline]
    pub fn pmf(&self, k: usize) -> f32 {
        let Some(&hi) = self.cdf.get(k) else {
            return 0.0;
        };
        let lo = if k == 0 { 0 } else { self.cdf[k - 1] };
        (hi - lo) as f32 * (1.0 / SELECT_SCALE as f32)
    }

    /// The light that `u_select` ∈ [0, 1) picks, read at 24-bit resolution, with its
    /// selection probability; `None` if the table is empty.
    #[inline]
    pub fn select(&self, u_select: f32) -> Option<(usize, f32)> {
        if self.cdf.is_empty() {
            return None;
        }
        let g = ((u_select * SELECT_SCALE as f32) as u32).min(SELECT_SCALE - 1);
        let k = self.cdf.partition_point(|&c| c <= g);
        Some((k, self.pmf(k)))
    }
}
