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
//! are `#[inline]` and called from one place each).
#![allow(unsafe_code)]

use std::sync::OnceLock;

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
            _ => kernel.run(),
        }
    }
}

/// Work that [`Isa::run`] compiles once per instruction set. Implementations mark
/// [`Kernel::run`] `#[inline(always)]`, so that each copy inlines it (a closure would be
/// compiled once, for the baseline, and called).
pub trait Kernel {
    /// What the work returns.
    type Output;
    /// Does the work.
    fn run(self) -> Self::Output;
}

/// `kernel.run()` compiled with the x86-64-v3 features.
///
/// # Safety
/// The CPU must support every feature listed in the attribute.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,lzcnt,movbe,popcnt")]
unsafe fn run_v3<K: Kernel>(kernel: K) -> K::Output {
    kernel.run()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_selected_copy_is_one_this_cpu_can_run() {
        let selected = Isa::selected();
        assert!(selected == Isa::BASELINE || selected == Isa::detect());
        // Running it must work (an unsupported instruction would kill the test process).
        struct Squares(u32);
        impl Kernel for Squares {
            type Output = u32;
            #[inline(always)]
            fn run(self) -> u32 {
                (1..=self.0).map(|x| x * x).sum()
            }
        }
        assert_eq!(selected.run(Squares(10)), 385);
    }
}
