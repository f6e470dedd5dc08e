//! Runtime CPU dispatch for the render loop: the one module with `unsafe` code.
//!
//! The release binary is built for baseline x86-64 (SSE2) so it runs on any x86-64 machine.
//! The render loop is compiled a second time with the instructions of x86-64-v3 (AVX2, FMA,
//! BMI1/2, LZCNT, MOVBE), and [`Isa::selected`] picks that copy when the CPU has them. Both copies
//! are the same Rust code, and Rust never fuses a multiply and an add on its own (no
//! floating-point contraction), so they compute the same bits: images do not depend on which
//! copy ran (tested in `tests/cpu.rs`). `RONDO_CPU=baseline` forces the baseline copy.
//!
//! What the dispatched copy reaches is what the compiler inlines into it: the integrator, the
//! BVH traversal, the triangle and box tests, the samplers and the materials (the hot functions
//! are `#[inline]` and called from one place each), and what it hands to
//! [`Lanes::out_of_line`]: a function of its own compiled with the same features, for work too
//! big to inline (instanced meshes, alpha-masked rays). Code written once for both copies stays
//! 4 lanes wide (SSE2) in both; where 8 lanes pay, the kernel is written over a [`Lanes`] type,
//! and the x86-64-v3 copy gets [`Avx`], whose operations are AVX intrinsics: so far the slab
//! test of a BVH node's eight boxes (`RayQuery::enter_boxes`).
#![allow(unsafe_code)]

use std::sync::OnceLock;

use glam::Vec4;

/// An instruction set the render loop is compiled for. Only [`Isa::BASELINE`] can be named;
/// any other value comes from [`Isa::detect`], so holding one proves the CPU can run it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Isa(Level);

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Level {
    Baseline,
    X86_64V3,
}

impl Isa {
    /// Baseline x86-64 (SSE2), or whatever the target guarantees on other architectures.
    pub const BASELINE: Isa = Isa(Level::Baseline);

    /// The copy this process renders with: the best one [`Isa::detect`] finds, unless the
    /// environment variable `RONDO_CPU` is `baseline`. Decided once per process.
    pub fn selected() -> Isa {
        static SELECTED: OnceLock<Isa> = OnceLock::new();
        *SELECTED.get_or_init(|| {
            if std::env::var("RONDO_CPU").is_ok_and(|v| v.eq_ignore_ascii_case("baseline")) {
                Isa::BASELINE
            } else {
                Isa::detect()
            }
        })
    }

    /// The best copy this CPU can run: x86-64-v3 (AVX2, FMA, BMI1, BMI2, LZCNT, MOVBE: Haswell,
    /// Zen and later) if it has all of those, else the baseline.
    pub fn detect() -> Isa {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma")
                && std::arch::is_x86_feature_detected!("bmi1")
                && std::arch::is_x86_feature_detected!("bmi2")
                && std::arch::is_x86_feature_detected!("lzcnt")
                && std::arch::is_x86_feature_detected!("movbe")
                && std::arch::is_x86_feature_detected!("popcnt")
            {
                return Isa(Level::X86_64V3);
            }
        }
        Isa::BASELINE
    }

    /// The name reports print.
    pub const fn name(self) -> &'static str {
        match self.0 {
            Level::Baseline => "baseline",
            Level::X86_64V3 => "x86-64-v3",
        }
    }

    /// Runs `kernel`, compiled for this instruction set.
    #[inline(always)]
    pub fn run<K: Kernel>(self, kernel: K) -> K::Output {
        match self.0 {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `Level::X86_64V3` is only ever made by `detect`, after the CPU reported
            // every feature `run_v3` is compiled with.
            Level::X86_64V3 => unsafe { run_v3(kernel) },
            _ => kernel.run(Sse),
        }
    }
}

/// Work that [`Isa::run`] compiles once per instruction set. Implementations mark
/// [`Kernel::run`] `#[inline(always)]`, so that each copy inlines it (a closure would be
/// compiled once, for the baseline, and called).
pub trait Kernel {
    /// What the work returns.
    type Output;
    /// Does the work, with the widest [`Lanes`] of the copy.
    fn run<W: Lanes>(self, lanes: W) -> Self::Output;
}

/// Eight `f32` lanes whose registers depend on the copy of the render loop: [`Sse`] (two SSE
/// registers, any x86-64 CPU, and every other target) or [`Avx`] (one AVX register, only in the
/// x86-64-v3 copy). Each operation is the same IEEE operation per lane in both, so kernels
/// written once over `Lanes` compute the same bits in either copy.
pub trait Lanes: Copy {
    /// How many lanes one instruction processes.
    const WIDTH: usize;
    /// Eight lanes.
    type F8: Copy;

    /// The lanes of `row`.
    fn load(self, row: &[f32; 8]) -> Self::F8;
    /// `x` in every lane.
    fn splat(self, x: f32) -> Self::F8;
    /// `a − b` per lane.
    fn sub(self, a: Self::F8, b: Self::F8) -> Self::F8;
    /// `a · b` per lane.
    fn mul(self, a: Self::F8, b: Self::F8) -> Self::F8;
    /// `minps`/`vminps`: the smaller, or `b` when either is NaN.
    fn min(self, a: Self::F8, b: Self::F8) -> Self::F8;
    /// `maxps`/`vmaxps`: the larger, or `b` when either is NaN.
    fn max(self, a: Self::F8, b: Self::F8) -> Self::F8;
    /// Bit `k` set where lane `k` of `a` is `≤` lane `k` of `b` (false on NaN).
    fn le_mask(self, a: Self::F8, b: Self::F8) -> u32;
    /// The lanes as an array.
    fn to_array(self, a: Self::F8) -> [f32; 8];
    /// `f(self)` in a function of its own that is compiled for this copy's instruction set:
    /// for work too big to inline into the render loop (where each inlined copy grows the loop
    /// and its compile time) that must still run with the copy's instructions. A plain
    /// out-of-line function would be compiled for the baseline, where an `Avx` method is a call.
    fn out_of_line<R>(self, f: impl FnOnce(Self) -> R) -> R;
}

/// Eight lanes as two of glam's `Vec4` (SSE2 on x86-64, scalar code elsewhere).
#[derive(Clone, Copy, Debug, Default)]
pub struct Sse;

impl Lanes for Sse {
    const WIDTH: usize = 4;
    type F8 = [Vec4; 2];

    #[inline(always)]
    fn load(self, row: &[f32; 8]) -> [Vec4; 2] {
        [Vec4::from_slice(&row[..4]), Vec4::from_slice(&row[4..])]
    }
    #[inline(always)]
    fn splat(self, x: f32) -> [Vec4; 2] {
        [Vec4::splat(x); 2]
    }
    #[inline(always)]
    fn sub(self, [a0, a1]: [Vec4; 2], [b0, b1]: [Vec4; 2]) -> [Vec4; 2] {
        [a0 - b0, a1 - b1]
    }
    #[inline(always)]
    fn mul(self, [a0, a1]: [Vec4; 2], [b0, b1]: [Vec4; 2]) -> [Vec4; 2] {
        [a0 * b0, a1 * b1]
    }
    #[inline(always)]
    fn min(self, [a0, a1]: [Vec4; 2], [b0, b1]: [Vec4; 2]) -> [Vec4; 2] {
        [a0.min(b0), a1.min(b1)]
    }
    #[inline(always)]
    fn max(self, [a0, a1]: [Vec4; 2], [b0, b1]: [Vec4; 2]) -> [Vec4; 2] {
        [a0.max(b0), a1.max(b1)]
    }
    #[inline(always)]
    fn le_mask(self, [a0, a1]: [Vec4; 2], [b0, b1]: [Vec4; 2]) -> u32 {
        a0.cmple(b0).bitmask() | a1.cmple(b1).bitmask() << 4
    }
    #[inline(always)]
    fn to_array(self, [a0, a1]: [Vec4; 2]) -> [f32; 8] {
        let ([a, b, c, d], [e, f, g, h]) = (a0.to_array(), a1.to_array());
        [a, b, c, d, e, f, g, h]
    }
    #[inline(always)]
    fn out_of_line<R>(self, f: impl FnOnce(Self) -> R) -> R {
        sse_out_of_line(self, f)
    }
}

/// [`Lanes::out_of_line`] of [`Sse`].
#[inline(never)]
fn sse_out_of_line<R>(lanes: Sse, f: impl FnOnce(Sse) -> R) -> R {
    f(lanes)
}

/// Eight lanes in one AVX register. Only [`Isa::run`] makes one, in the copy of the kernel it
/// compiles for x86-64-v3 after [`Isa::detect`] found the CPU's features: holding an `Avx`
/// proves the CPU has AVX. The intrinsics are called in these always-inlined methods, not
/// through `#[target_feature]` functions, which the compiler would not inline into the
/// traversal loops: once a method is inlined into the x86-64-v3 copy, its intrinsic is.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug)]
pub struct Avx(());

#[cfg(target_arch = "x86_64")]
impl Lanes for Avx {
    const WIDTH: usize = 8;
    type F8 = std::arch::x86_64::__m256;

    // SAFETY (every method): an `Avx` exists only on a CPU with AVX (see the type); the loads
    // and stores access eight contiguous `f32`s, which unaligned loads and stores may.
    #[inline(always)]
    fn load(self, row: &[f32; 8]) -> Self::F8 {
        unsafe { std::arch::x86_64::_mm256_loadu_ps(row.as_ptr()) }
    }
    #[inline(always)]
    fn splat(self, x: f32) -> Self::F8 {
        unsafe { std::arch::x86_64::_mm256_set1_ps(x) }
    }
    #[inline(always)]
    fn sub(self, a: Self::F8, b: Self::F8) -> Self::F8 {
        unsafe { std::arch::x86_64::_mm256_sub_ps(a, b) }
    }
    #[inline(always)]
    fn mul(self, a: Self::F8, b: Self::F8) -> Self::F8 {
        unsafe { std::arch::x86_64::_mm256_mul_ps(a, b) }
    }
    #[inline(always)]
    fn min(self, a: Self::F8, b: Self::F8) -> Self::F8 {
        unsafe { std::arch::x86_64::_mm256_min_ps(a, b) }
    }
    #[inline(always)]
    fn max(self, a: Self::F8, b: Self::F8) -> Self::F8 {
        unsafe { std::arch::x86_64::_mm256_max_ps(a, b) }
    }
    #[inline(always)]
    fn le_mask(self, a: Self::F8, b: Self::F8) -> u32 {
        use std::arch::x86_64::{_CMP_LE_OQ, _mm256_cmp_ps, _mm256_movemask_ps};
        unsafe { _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(a, b)) as u32 }
    }
    #[inline(always)]
    fn to_array(self, a: Self::F8) -> [f32; 8] {
        let mut out = [0.0f32; 8];
        unsafe { std::arch::x86_64::_mm256_storeu_ps(out.as_mut_ptr(), a) };
        out
    }
    #[inline(always)]
    fn out_of_line<R>(self, f: impl FnOnce(Self) -> R) -> R {
        // SAFETY: an `Avx` exists only on a CPU with every feature of `run_v3` (see the type).
        unsafe { avx_out_of_line(self, f) }
    }
}

/// [`Lanes::out_of_line`] of [`Avx`]: `f` compiled with the x86-64-v3 features, as `run_v3`.
///
/// # Safety
/// The CPU must support every feature listed in the attribute.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,lzcnt,movbe,popcnt")]
#[inline(never)]
unsafe fn avx_out_of_line<R>(lanes: Avx, f: impl FnOnce(Avx) -> R) -> R {
    f(lanes)
}

/// `kernel.run()` compiled with the x86-64-v3 features.
///
/// # Safety
/// The CPU must support every feature listed in the attribute.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,lzcnt,movbe,popcnt")]
unsafe fn run_v3<K: Kernel>(kernel: K) -> K::Output {
    kernel.run(Avx(()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_selected_copy_is_one_this_cpu_can_run() {
        let selected = Isa::selected();
        assert!(selected == Isa::BASELINE || selected == Isa::detect());
        // Running it, and its out-of-line function, must work (an unsupported instruction would
        // kill the test process).
        struct Squares(u32);
        impl Kernel for Squares {
            type Output = u32;
            #[inline(always)]
            fn run<W: Lanes>(self, lanes: W) -> u32 {
                let n = self.0;
                lanes.out_of_line(|_| (1..=n).map(|x| x * x).sum())
            }
        }
        assert_eq!(selected.run(Squares(10)), 385);
    }
}
