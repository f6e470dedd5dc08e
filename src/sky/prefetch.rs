//! A hint to the CPU to bring a table entry into the cache ahead of its use: a sky texel's line
//! is a miss (the maps are megabytes), and a prefetch issued before other work lets the miss
//! overlap it. No ECS here.

/// Asks for the cache line holding `table[index]` (nothing if `index` is out of range). A hint
/// only: no effect on any value, and nothing on targets without a prefetch instruction.
#[inline(always)]
pub(super) fn prefetch<T>(table: &[T], index: usize) {
    if let Some(entry) = table.get(index) {
        line(std::ptr::from_ref(entry).cast());
    }
}

/// The prefetch instruction (`prefetcht0`, baseline on x86-64).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
#[expect(
    unsafe_code,
    reason = "`_mm_prefetch` is declared with `#[target_feature(enable = \"sse\")]`, baseline on \
              x86-64; a prefetch never dereferences its address, so any pointer is sound"
)]
fn line(p: *const u8) {
    // SAFETY: SSE is part of the x86-64 baseline, and a prefetch neither faults nor reads
    // into the program's state, whatever the address.
    unsafe {
        std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(p.cast());
    }
}

/// No prefetch instruction on this target: nothing to do.
#[cfg(not(target_arch = "x86_64"))]
#[inline(always)]
fn line(_p: *const u8) {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_index_out_of_range_asks_for_nothing() {
        // The hint reads nothing: out-of-range and wrapped indices are simply skipped.
        let table = [1.0f32; 8];
        for i in [0, 7, 8, usize::MAX] {
            prefetch(&table, i);
        }
        prefetch::<f32>(&[], 0);
        assert_eq!(table, [1.0; 8]);
    }
}
