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
//! are `#[inline]` and called from one place each). Code written once for both copies stays
//! 4 lanes wide (SSE2) in both; where 8 lanes pay, the kernel takes a [`Lanes`] type, and the
//! x86-64-v3 copy gets [`Avx`], whose operations are AVX intrinsics: so far the slab test of a
//! BVH node's eight boxes ([`Lanes::enter_boxes`]).
#![allow(unsafe_code)]

use std::sync::OnceLock;

use glam::{Vec3A, Vec4};

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

/// SIMD operations whose width depends on the copy of the render loop: [`Sse`] (4 lanes, any
/// x86-64 CPU, and every other target) or [`Avx`] (8 lanes, only in the x86-64-v3 copy). Both
/// compute the same bits.
pub trait Lanes: Copy {
    /// How many `f32` lanes one operation processes.
    const WIDTH: usize;

    /// The robust slab test of eight boxes for a ray from `origin` with inverse direction
    /// `inv_dir`, both finite: `b` holds the boxes lane by lane (`[min_x, min_y, min_z, max_x,
    /// max_y, max_z]`). Per box, `near = max(min(t0, t1) over the axes, 0)` and `far =
    /// min(min(max(t0, t1) over the axes) · widen, t_max)`, with `t0 = (min − o) · inv` and `t1
    /// = (max − o) · inv` per axis, each `min`/`max` the SSE instruction's (the second operand
    /// when either is NaN). Bit `k` of the mask is set if `near ≤ far` for box `k`; lane `k` of
    /// the array is its `near`.
    fn enter_boxes(
        self,
        b: &[[f32; 8]; 6],
        origin: Vec3A,
        inv_dir: Vec3A,
        widen: f32,
        t_max: f32,
    ) -> (u32, [f32; 8]);
}

/// Four lanes at a time: SSE2 through glam's `Vec4` on x86-64, scalar code elsewhere.
#[derive(Clone, Copy, Debug, Default)]
pub struct Sse;

impl Lanes for Sse {
    const WIDTH: usize = 4;

    #[inline(always)]
    fn enter_boxes(
        self,
        b: &[[f32; 8]; 6],
        origin: Vec3A,
        inv_dir: Vec3A,
        widen: f32,
        t_max: f32,
    ) -> (u32, [f32; 8]) {
        let half = |h: usize| {
            let lanes = |axis: usize| Vec4::from_slice(&b[axis][4 * h..4 * h + 4]);
            let slab = |axis: usize| {
                let (o, inv) = (Vec4::splat(origin[axis]), Vec4::splat(inv_dir[axis]));
                let t0 = (lanes(axis) - o) * inv;
                let t1 = (lanes(3 + axis) - o) * inv;
                (t0.min(t1), t0.max(t1))
            };
            let (nx, fx) = slab(0);
            let (ny, fy) = slab(1);
            let (nz, fz) = slab(2);
            let near = nx.max(ny).max(nz).max(Vec4::ZERO);
            let far = (fx.min(fy).min(fz) * widen).min(Vec4::splat(t_max));
            (near.cmple(far).bitmask(), near.to_array())
        };
        let ((mask_low, [a, b, c, d]), (mask_high, [e, f, g, h])) = (half(0), half(1));
        (mask_low | mask_high << 4, [a, b, c, d, e, f, g, h])
    }
}

/// Eight lanes at a time with AVX. Only [`Isa::run`] makes one, in the copy of the kernel it
/// compiles for x86-64-v3 after [`Isa::detect`] found the CPU's features: holding an `Avx`
/// proves the CPU has AVX.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug)]
pub struct Avx(());

#[cfg(target_arch = "x86_64")]
impl Lanes for Avx {
    const WIDTH: usize = 8;

    /// The same operations as [`Sse`]'s, eight lanes per instruction (`vminps`/`vmaxps` return
    /// the second operand on NaN, like `minps`/`maxps`). The intrinsics are called directly,
    /// not through a `#[target_feature]` function, which the compiler would not inline into the
    /// traversal loops: once this method is inlined into the x86-64-v3 copy, each of them is.
    #[inline(always)]
    fn enter_boxes(
        self,
        b: &[[f32; 8]; 6],
        origin: Vec3A,
        inv_dir: Vec3A,
        widen: f32,
        t_max: f32,
    ) -> (u32, [f32; 8]) {
        use std::arch::x86_64::{
            _CMP_LE_OQ, _mm256_cmp_ps, _mm256_loadu_ps, _mm256_max_ps, _mm256_min_ps,
            _mm256_movemask_ps, _mm256_mul_ps, _mm256_set1_ps, _mm256_setzero_ps, _mm256_storeu_ps,
            _mm256_sub_ps,
        };
        // SAFETY: an `Avx` exists only on a CPU with AVX (see the type), and every row of `b`
        // and `out` is eight contiguous `f32`s, which unaligned loads and stores may access.
        unsafe {
            macro_rules! slab {
                ($axis:expr) => {{
                    let o = _mm256_set1_ps(origin[$axis]);
                    let inv = _mm256_set1_ps(inv_dir[$axis]);
                    let t0 =
                        _mm256_mul_ps(_mm256_sub_ps(_mm256_loadu_ps(b[$axis].as_ptr()), o), inv);
                    let t1 = _mm256_mul_ps(
                        _mm256_sub_ps(_mm256_loadu_ps(b[3 + $axis].as_ptr()), o),
                        inv,
                    );
                    (_mm256_min_ps(t0, t1), _mm256_max_ps(t0, t1))
                }};
            }
            let (nx, fx) = slab!(0);
            let (ny, fy) = slab!(1);
            let (nz, fz) = slab!(2);
            let near = _mm256_max_ps(
                _mm256_max_ps(_mm256_max_ps(nx, ny), nz),
                _mm256_setzero_ps(),
            );
            let far = _mm256_min_ps(
                _mm256_mul_ps(
                    _mm256_min_ps(_mm256_min_ps(fx, fy), fz),
                    _mm256_set1_ps(widen),
                ),
                _mm256_set1_ps(t_max),
            );
            let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(near, far)) as u32;
            let mut out = [0.0f32; 8];
            _mm256_storeu_ps(out.as_mut_ptr(), near);
            (mask, out)
        }
    }
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
        // Running it must work (an unsupported instruction would kill the test process).
        struct Squares(u32);
        impl Kernel for Squares {
            type Output = u32;
            #[inline(always)]
            fn run<W: Lanes>(self, _lanes: W) -> u32 {
                (1..=self.0).map(|x| x * x).sum()
            }
        }
        assert_eq!(selected.run(Squares(10)), 385);
    }
}
