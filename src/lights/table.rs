//! Choosing a light: half by power, half uniformly over the scene's lights. No ECS here.
//!
//! Selection by power alone (pbrt-v4's `PowerLightSampler`) starves small lamps beside a bright
//! one: in `scenes/veach_mis.ron` the fill lamp holds 98 % of the power, so each of the four
//! lamps the glossy plates reflect was chosen 0.5 % of the time and their highlights were a heavy
//! tail of rare, huge next-event estimates. Uniform selection over lights (Mitsuba 3's) starves
//! nothing but spends as much on a dim light as on the sun. [`mixed_weights`] takes the mixture
//! of both (a defensive mixture: each light keeps at least half its power share and half its
//! uniform share, so the variance of either strategy at most doubles). A light is an entity's
//! emitting primitives taken together (the triangles of a mesh lamp, by their power within it)
//! or one distant light, so a finely tessellated lamp does not count as thousands of lights.
//!
//! The table holds cumulative counts out of 2²⁴, the resolution of the random numbers
//! (`Rng::next_f32`): a light's probability is its count / 2²⁴, exactly the frequency with which a
//! 24-bit `u_select` picks it, within 2⁻²⁴ of its share of the power (the running sum is taken
//! in f64). A light whose count rounds to 0 is never picked and has density 0, so it is left to
//! BSDF sampling at full weight.

/// Resolution of the table: cumulative counts out of 2²⁴.
const SELECT_SCALE: u32 = 1 << 24;

/// Share of the selection given uniformly over lights; the rest goes by power.
const UNIFORM_SHARE: f64 = 0.5;

/// Selection weights of emitters of power `powers`, emitter `k` belonging to light
/// `light_of[k]` (a dense index): half of the selection (`UNIFORM_SHARE`) spread evenly over the
/// lights of positive power (within a light by power), the rest by power. A power that is not
/// positive and finite counts as 0 and keeps weight 0.
pub fn mixed_weights(powers: &[f64], light_of: &[usize]) -> Vec<f64> {
    let power = |p: f64| if p > 0.0 && p.is_finite() { p } else { 0.0 };
    let lights = light_of.iter().map(|&l| l + 1).max().unwrap_or(0);
    let mut light_power = vec![0.0f64; lights];
    for (&p, &l) in powers.iter().zip(light_of) {
        light_power[l] += power(p);
    }
    let total: f64 = light_power.iter().sum();
    let lit = light_power.iter().filter(|&&p| p > 0.0).count();
    if !(total > 0.0 && total.is_finite()) {
        return vec![0.0; powers.len()];
    }
    powers
        .iter()
        .zip(light_of)
        .map(|(&p, &l)| {
            let p = power(p);
            if p == 0.0 {
                return 0.0;
            }
            (1.0 - UNIFORM_SHARE) * p / total + UNIFORM_SHARE * (p / light_power[l]) / lit as f64
        })
        .collect()
}

/// Selection probabilities proportional to weights.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SelectionTable {
    /// Cumulative selection counts out of [`SELECT_SCALE`], ending at it.
    cdf: Vec<u32>,
}

impl SelectionTable {
    /// The table of lights of weight `weights` (a weight that is not positive and finite counts
    /// as 0); empty if their sum is not positive and finite: nothing worth sampling.
    pub fn new(weights: &[f64]) -> Self {
        let weights: Vec<f64> = weights
            .iter()
            .map(|&w| if w > 0.0 && w.is_finite() { w } else { 0.0 })
            .collect();
        let total: f64 = weights.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            return Self::default();
        }
        let mut acc = 0.0f64;
        let mut cdf: Vec<u32> = weights
            .iter()
            .map(|w| {
                acc += w;
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

    /// Probability that [`SelectionTable::select`] picks light `k` (0 for an index out of range).
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_dominant_light_leaves_the_others_half_their_uniform_share() {
        // Veach's scene: a fill lamp of power 200 beside four lamps of power 1. By power alone
        // each small lamp would get 1/204; the mixture gives it 0.5/204 + 0.5/5.
        let w = mixed_weights(&[1.0, 1.0, 1.0, 1.0, 200.0], &[0, 1, 2, 3, 4]);
        for &small in &w[..4] {
            assert!((small - (0.5 / 204.0 + 0.1)).abs() < 1e-12, "{w:?}");
        }
        assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn a_tessellated_lamp_counts_as_one_light() {
        // A mesh lamp of 1,000 triangles of power 1 each (light 0) and a sphere of power 1,000
        // (light 1): equal powers, so each light gets half, whatever its primitive count.
        let mut powers = vec![1.0; 1000];
        let mut light_of = vec![0usize; 1000];
        powers.push(1000.0);
        light_of.push(1);
        let w = mixed_weights(&powers, &light_of);
        assert!((w[1000] - 0.5).abs() < 1e-12, "{}", w[1000]);
        assert!((w[..1000].iter().sum::<f64>() - 0.5).abs() < 1e-12);
    }

    #[test]
    fn dark_lights_keep_weight_zero_and_take_no_uniform_share() {
        let w = mixed_weights(&[0.0, f64::NAN, 3.0], &[0, 1, 2]);
        assert_eq!(w, vec![0.0, 0.0, 1.0]);
        assert_eq!(mixed_weights(&[0.0], &[0]), vec![0.0]);
        let table = SelectionTable::new(&w);
        assert_eq!((table.pmf(0), table.pmf(1), table.pmf(2)), (0.0, 0.0, 1.0));
    }
}
