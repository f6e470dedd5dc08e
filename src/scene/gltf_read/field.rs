//! The range check of a glTF material's numeric fields, shared by the readers of the core
//! material and of its extensions' layers.

use std::ops::RangeInclusive;

/// Checks that a material's field `field` holds `v`, a finite number within `range` (the
/// spec's range for it; the RON loader refuses the same quantities out of range).
pub(super) fn check_field(
    what: &dyn Fn() -> String,
    field: &str,
    v: f32,
    range: RangeInclusive<f32>,
) -> Result<(), String> {
    if v.is_finite() && range.contains(&v) {
        return Ok(());
    }
    let (lo, hi) = (range.start(), range.end());
    let within = if hi.is_finite() {
        format!("in [{lo}, {hi}]")
    } else if lo.is_finite() {
        format!("finite and at least {lo}")
    } else {
        "finite".into()
    };
    Err(format!("{}: {field} is {v}, must be {within}", what()))
}
