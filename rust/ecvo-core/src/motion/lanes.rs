//! Fixed-width lanes for MOTION's sums.
//!
//! The per-point loops are structure-of-arrays: one `f32` slice per quantity. Loops
//! that only map points to points are plain slice loops that the compiler
//! vectorises; loops that sum over points work on blocks of [`LANES`] points, each
//! lane keeping its own partial sums, which are added in lane order at the end. The
//! lane count is fixed (not the machine's vector width), so every lane sees the same
//! operations in the same order on every target: the sums have the same bits on
//! x86_64 (SSE2 and AVX) and aarch64 (NEON). FMA is never used.
//!
//! The summing kernels are generic over [`Lanes`], a zero-sized token whose methods
//! are the vector operations:
//! - [`Sse2`]: two 4-lane SSE2 vectors (baseline on x86_64);
//! - [`Avx`]: one 8-lane AVX vector, on x86_64 CPUs with AVX2 (a token exists only
//!   where [`Avx::detect`] found it); half the instructions of the SSE2 pair and
//!   fewer register spills in the normal equations' 27 running sums; on CPUs with
//!   AVX-512 the same kernels are compiled again with it enabled, for its 32 vector
//!   registers (the operations, and so the bits, are the same);
//! - [`Neon`]: two 4-lane NEON vectors (baseline on aarch64);
//! - [`Portable`]: plain arrays elsewhere, and everywhere with `--cfg
//!   ecvo_portable_lanes` (to measure the intrinsics against them). Plain arrays
//!   were tried first: the compiler vectorised the arithmetic but kept the
//!   loop-carried sums as scalars and rebuilt vectors from them every block.
//!
//! [`Base`] is the target's baseline and [`lanes_multiversion!`] calls a kernel
//! with [`Avx`] when the CPU has it, with [`Base`] otherwise.

/// Points per block of a summing loop.
pub(super) const LANES: usize = 8;

/// The vector operations of the summing loops on [`LANES`] `f32` lanes. Every
/// implementation performs, lane by lane, the IEEE operation its name says.
pub(super) trait Lanes: Copy {
    /// Eight `f32` lanes.
    type V: Copy;
    /// A lane mask (all ones or all zeros per lane).
    type M: Copy;
    /// Eight `f64` lanes.
    type W: Copy;
    /// `a + b`.
    fn add(self, a: Self::V, b: Self::V) -> Self::V;
    /// `a - b`.
    fn sub(self, a: Self::V, b: Self::V) -> Self::V;
    /// `a * b`.
    fn mul(self, a: Self::V, b: Self::V) -> Self::V;
    /// `a / b`.
    fn div(self, a: Self::V, b: Self::V) -> Self::V;
    /// `[x; 8]`.
    fn splat(self, x: f32) -> Self::V;
    /// The 8 values of `s` at `b`.
    fn load(self, s: &[f32], b: usize) -> Self::V;
    /// `-a` (the sign bit flipped, as scalar negation does).
    fn neg(self, a: Self::V) -> Self::V;
    /// True where `x` is finite (`|x| < ∞`, false for NaN).
    fn finite(self, x: Self::V) -> Self::M;
    /// `m ? a : b`.
    fn select(self, m: Self::M, a: Self::V, b: Self::V) -> Self::V;
    /// `a += x`.
    #[inline(always)]
    fn acc(self, a: &mut Self::V, x: Self::V) {
        *a = self.add(*a, x);
    }
    /// Eight zeros in double precision.
    fn zero_w(self) -> Self::W;
    /// `a += x` in double precision.
    fn flush(self, a: &mut Self::W, x: &Self::V);
    /// The lanes of `a` added in lane order.
    fn sum(self, a: &Self::W) -> f64;
    /// The lanes as an array.
    #[cfg(test)]
    fn to_array(self, v: Self::V) -> [f32; 8];
}

#[cfg(all(target_arch = "x86_64", not(ecvo_portable_lanes)))]
pub(super) use x86::{Avx, Sse2 as Base};

#[cfg(all(target_arch = "aarch64", not(ecvo_portable_lanes)))]
pub(super) use arm::Neon as Base;

#[cfg(any(
    ecvo_portable_lanes,
    not(any(target_arch = "x86_64", target_arch = "aarch64"))
))]
pub(super) use portable::Portable as Base;

/// Defines `pub(crate) fn $name($args) -> $ret` that calls the kernel
/// `$kernel::<L: Lanes>(l, $args)` (`#[inline(always)]`) with [`Avx`] in a copy
/// compiled for AVX-512 or AVX2 when the CPU has it (the same 8-lane operations, so
/// the same bits), with [`Base`] otherwise.
macro_rules! lanes_multiversion {
    ($(#[$m:meta])* fn $name:ident($($a:ident: $t:ty),* $(,)?) $(-> $ret:ty)? = $kernel:ident;) => {
        $(#[$m])*
        pub(crate) fn $name($($a: $t),*) $(-> $ret)? {
            #[cfg(all(target_arch = "x86_64", not(ecvo_portable_lanes)))]
            {
                #[target_feature(enable = "avx2")]
                unsafe fn avx2(l: $crate::motion::lanes::Avx, $($a: $t),*) $(-> $ret)? {
                    $kernel(l, $($a),*)
                }
                // The same 8-lane AVX operations, with the 32 vector registers of
                // AVX-512 VL to hold the running sums (fewer spills).
                #[target_feature(enable = "avx2,avx512f,avx512vl,avx512bw,avx512dq")]
                unsafe fn avx512(l: $crate::motion::lanes::Avx, $($a: $t),*) $(-> $ret)? {
                    $kernel(l, $($a),*)
                }
                if let Some(l) = $crate::motion::lanes::Avx::detect() {
                    if $crate::prepare::simd::avx512() {
                        // SAFETY: the CPU has these features (checked at run time).
                        return unsafe { avx512(l, $($a),*) };
                    }
                    // SAFETY: the token exists only where the CPU has AVX2.
                    return unsafe { avx2(l, $($a),*) };
                }
            }
            $kernel($crate::motion::lanes::Base, $($a),*)
        }
    };
}
pub(crate) use lanes_multiversion;

#[cfg(all(target_arch = "x86_64", not(ecvo_portable_lanes)))]
#[allow(unused_unsafe)]
mod x86 {
    //! SSE2 (baseline on x86_64) and AVX. The SSE2 intrinsics are safe to call where
    //! SSE2 is enabled, which it always is; the AVX ones only where the CPU has AVX,
    //! which holds wherever an [`Avx`] token exists.
    use super::Lanes;
    use std::arch::x86_64::*;

    /// The SSE2 lanes: two 4-lane vectors.
    #[derive(Clone, Copy, Debug)]
    pub(in super::super) struct Sse2;

    impl Lanes for Sse2 {
        type V = (__m128, __m128);
        type M = (__m128, __m128);
        type W = [__m128d; 4];

        #[inline(always)]
        fn add(self, a: Self::V, b: Self::V) -> Self::V {
            unsafe { (_mm_add_ps(a.0, b.0), _mm_add_ps(a.1, b.1)) }
        }
        #[inline(always)]
        fn sub(self, a: Self::V, b: Self::V) -> Self::V {
            unsafe { (_mm_sub_ps(a.0, b.0), _mm_sub_ps(a.1, b.1)) }
        }
        #[inline(always)]
        fn mul(self, a: Self::V, b: Self::V) -> Self::V {
            unsafe { (_mm_mul_ps(a.0, b.0), _mm_mul_ps(a.1, b.1)) }
        }
        #[inline(always)]
        fn div(self, a: Self::V, b: Self::V) -> Self::V {
            unsafe { (_mm_div_ps(a.0, b.0), _mm_div_ps(a.1, b.1)) }
        }
        #[inline(always)]
        fn splat(self, x: f32) -> Self::V {
            unsafe { (_mm_set1_ps(x), _mm_set1_ps(x)) }
        }
        #[inline(always)]
        fn load(self, s: &[f32], b: usize) -> Self::V {
            let s = &s[b..b + 8];
            // SAFETY: `s` has 8 elements; the loads are unaligned.
            unsafe { (_mm_loadu_ps(s.as_ptr()), _mm_loadu_ps(s.as_ptr().add(4))) }
        }
        #[inline(always)]
        fn neg(self, a: Self::V) -> Self::V {
            unsafe {
                let s = _mm_set1_ps(-0.0);
                (_mm_xor_ps(a.0, s), _mm_xor_ps(a.1, s))
            }
        }
        #[inline(always)]
        fn finite(self, x: Self::V) -> Self::M {
            unsafe {
                let (s, inf) = (_mm_set1_ps(-0.0), _mm_set1_ps(f32::INFINITY));
                (
                    _mm_cmplt_ps(_mm_andnot_ps(s, x.0), inf),
                    _mm_cmplt_ps(_mm_andnot_ps(s, x.1), inf),
                )
            }
        }
        #[inline(always)]
        fn select(self, m: Self::M, a: Self::V, b: Self::V) -> Self::V {
            unsafe {
                (
                    _mm_or_ps(_mm_and_ps(m.0, a.0), _mm_andnot_ps(m.0, b.0)),
                    _mm_or_ps(_mm_and_ps(m.1, a.1), _mm_andnot_ps(m.1, b.1)),
                )
            }
        }
        #[inline(always)]
        fn zero_w(self) -> Self::W {
            unsafe { [_mm_setzero_pd(); 4] }
        }
        #[inline(always)]
        fn flush(self, a: &mut Self::W, x: &Self::V) {
            unsafe {
                let w = [
                    _mm_cvtps_pd(x.0),
                    _mm_cvtps_pd(_mm_movehl_ps(x.0, x.0)),
                    _mm_cvtps_pd(x.1),
                    _mm_cvtps_pd(_mm_movehl_ps(x.1, x.1)),
                ];
                for k in 0..4 {
                    a[k] = _mm_add_pd(a[k], w[k]);
                }
            }
        }
        fn sum(self, a: &Self::W) -> f64 {
            let mut o = [0.0f64; 8];
            for k in 0..4 {
                // SAFETY: two elements of `o` from `2 k`; the store is unaligned.
                unsafe { _mm_storeu_pd(o.as_mut_ptr().add(2 * k), a[k]) };
            }
            o.iter().fold(0.0, |s, &x| s + x)
        }
        #[cfg(test)]
        fn to_array(self, v: Self::V) -> [f32; 8] {
            let mut o = [0.0; 8];
            // SAFETY: `o` has 8 elements; the stores are unaligned.
            unsafe {
                _mm_storeu_ps(o.as_mut_ptr(), v.0);
                _mm_storeu_ps(o.as_mut_ptr().add(4), v.1);
            }
            o
        }
    }

    /// The AVX lanes: one 8-lane vector. Only [`Avx::detect`] makes one, on a CPU
    /// with AVX2 (the kernels that use it are compiled with AVX2 enabled).
    #[derive(Clone, Copy, Debug)]
    pub(in super::super) struct Avx(());

    impl Avx {
        /// The token, when the AVX2 copies may run ([`crate::prepare::simd::avx2`]:
        /// the CPU has AVX2 and `ECVO_NO_AVX2` is unset).
        #[inline]
        pub(in super::super) fn detect() -> Option<Avx> {
            crate::prepare::simd::avx2().then_some(Avx(()))
        }
    }

    // SAFETY (every `unsafe` block below): an `Avx` exists only on a CPU with AVX2,
    // which includes AVX; loads and stores are unaligned and in bounds.
    impl Lanes for Avx {
        type V = __m256;
        type M = __m256;
        type W = [__m256d; 2];

        #[inline(always)]
        fn add(self, a: __m256, b: __m256) -> __m256 {
            unsafe { _mm256_add_ps(a, b) }
        }
        #[inline(always)]
        fn sub(self, a: __m256, b: __m256) -> __m256 {
            unsafe { _mm256_sub_ps(a, b) }
        }
        #[inline(always)]
        fn mul(self, a: __m256, b: __m256) -> __m256 {
            unsafe { _mm256_mul_ps(a, b) }
        }
        #[inline(always)]
        fn div(self, a: __m256, b: __m256) -> __m256 {
            unsafe { _mm256_div_ps(a, b) }
        }
        #[inline(always)]
        fn splat(self, x: f32) -> __m256 {
            unsafe { _mm256_set1_ps(x) }
        }
        #[inline(always)]
        fn load(self, s: &[f32], b: usize) -> __m256 {
            let s = &s[b..b + 8];
            unsafe { _mm256_loadu_ps(s.as_ptr()) }
        }
        #[inline(always)]
        fn neg(self, a: __m256) -> __m256 {
            unsafe { _mm256_xor_ps(a, _mm256_set1_ps(-0.0)) }
        }
        #[inline(always)]
        fn finite(self, x: __m256) -> __m256 {
            unsafe {
                let (s, inf) = (_mm256_set1_ps(-0.0), _mm256_set1_ps(f32::INFINITY));
                _mm256_cmp_ps::<_CMP_LT_OQ>(_mm256_andnot_ps(s, x), inf)
            }
        }
        #[inline(always)]
        fn select(self, m: __m256, a: __m256, b: __m256) -> __m256 {
            unsafe { _mm256_blendv_ps(b, a, m) }
        }
        #[inline(always)]
        fn zero_w(self) -> Self::W {
            unsafe { [_mm256_setzero_pd(); 2] }
        }
        #[inline(always)]
        fn flush(self, a: &mut Self::W, x: &__m256) {
            unsafe {
                let lo = _mm256_cvtps_pd(_mm256_castps256_ps128(*x));
                let hi = _mm256_cvtps_pd(_mm256_extractf128_ps::<1>(*x));
                a[0] = _mm256_add_pd(a[0], lo);
                a[1] = _mm256_add_pd(a[1], hi);
            }
        }
        #[inline(always)]
        fn sum(self, a: &Self::W) -> f64 {
            let mut o = [0.0f64; 8];
            unsafe {
                _mm256_storeu_pd(o.as_mut_ptr(), a[0]);
                _mm256_storeu_pd(o.as_mut_ptr().add(4), a[1]);
            }
            o.iter().fold(0.0, |s, &x| s + x)
        }
        #[cfg(test)]
        fn to_array(self, v: __m256) -> [f32; 8] {
            let mut o = [0.0; 8];
            unsafe { _mm256_storeu_ps(o.as_mut_ptr(), v) };
            o
        }
    }
}

#[cfg(all(target_arch = "aarch64", not(ecvo_portable_lanes)))]
#[allow(unused_unsafe)]
mod arm {
    //! NEON (baseline on aarch64). The intrinsics used are safe to call where NEON is
    //! enabled, which it always is; the `unsafe` blocks are for older compilers
    //! and the loads and stores.
    use super::Lanes;
    use std::arch::aarch64::*;

    /// The NEON lanes: two 4-lane vectors.
    #[derive(Clone, Copy, Debug)]
    pub(in super::super) struct Neon;

    impl Lanes for Neon {
        type V = (float32x4_t, float32x4_t);
        type M = (uint32x4_t, uint32x4_t);
        type W = [float64x2_t; 4];

        #[inline(always)]
        fn add(self, a: Self::V, b: Self::V) -> Self::V {
            unsafe { (vaddq_f32(a.0, b.0), vaddq_f32(a.1, b.1)) }
        }
        #[inline(always)]
        fn sub(self, a: Self::V, b: Self::V) -> Self::V {
            unsafe { (vsubq_f32(a.0, b.0), vsubq_f32(a.1, b.1)) }
        }
        #[inline(always)]
        fn mul(self, a: Self::V, b: Self::V) -> Self::V {
            unsafe { (vmulq_f32(a.0, b.0), vmulq_f32(a.1, b.1)) }
        }
        #[inline(always)]
        fn div(self, a: Self::V, b: Self::V) -> Self::V {
            unsafe { (vdivq_f32(a.0, b.0), vdivq_f32(a.1, b.1)) }
        }
        #[inline(always)]
        fn splat(self, x: f32) -> Self::V {
            unsafe { (vdupq_n_f32(x), vdupq_n_f32(x)) }
        }
        #[inline(always)]
        fn load(self, s: &[f32], b: usize) -> Self::V {
            let s = &s[b..b + 8];
            // SAFETY: `s` has 8 elements.
            unsafe { (vld1q_f32(s.as_ptr()), vld1q_f32(s.as_ptr().add(4))) }
        }
        #[inline(always)]
        fn neg(self, a: Self::V) -> Self::V {
            unsafe { (vnegq_f32(a.0), vnegq_f32(a.1)) }
        }
        #[inline(always)]
        fn finite(self, x: Self::V) -> Self::M {
            unsafe {
                let inf = vdupq_n_f32(f32::INFINITY);
                (
                    vcltq_f32(vabsq_f32(x.0), inf),
                    vcltq_f32(vabsq_f32(x.1), inf),
                )
            }
        }
        #[inline(always)]
        fn select(self, m: Self::M, a: Self::V, b: Self::V) -> Self::V {
            unsafe { (vbslq_f32(m.0, a.0, b.0), vbslq_f32(m.1, a.1, b.1)) }
        }
        #[inline(always)]
        fn zero_w(self) -> Self::W {
            unsafe { [vdupq_n_f64(0.0); 4] }
        }
        #[inline(always)]
        fn flush(self, a: &mut Self::W, x: &Self::V) {
            unsafe {
                let w = [
                    vcvt_f64_f32(vget_low_f32(x.0)),
                    vcvt_high_f64_f32(x.0),
                    vcvt_f64_f32(vget_low_f32(x.1)),
                    vcvt_high_f64_f32(x.1),
                ];
                for k in 0..4 {
                    a[k] = vaddq_f64(a[k], w[k]);
                }
            }
        }
        fn sum(self, a: &Self::W) -> f64 {
            let mut o = [0.0f64; 8];
            for k in 0..4 {
                // SAFETY: two elements of `o` from `2 k`.
                unsafe { vst1q_f64(o.as_mut_ptr().add(2 * k), a[k]) };
            }
            o.iter().fold(0.0, |s, &x| s + x)
        }
        #[cfg(test)]
        fn to_array(self, v: Self::V) -> [f32; 8] {
            let mut o = [0.0; 8];
            // SAFETY: `o` has 8 elements.
            unsafe {
                vst1q_f32(o.as_mut_ptr(), v.0);
                vst1q_f32(o.as_mut_ptr().add(4), v.1);
            }
            o
        }
    }
}

#[cfg(any(
    ecvo_portable_lanes,
    not(any(target_arch = "x86_64", target_arch = "aarch64"))
))]
mod portable {
    //! Plain arrays.
    use super::Lanes;

    /// The portable lanes: `[f32; 8]`.
    #[derive(Clone, Copy, Debug)]
    pub(in super::super) struct Portable;

    fn zip(a: [f32; 8], b: [f32; 8], f: impl Fn(f32, f32) -> f32) -> [f32; 8] {
        std::array::from_fn(|l| f(a[l], b[l]))
    }

    impl Lanes for Portable {
        type V = [f32; 8];
        type M = [bool; 8];
        type W = [f64; 8];

        fn add(self, a: Self::V, b: Self::V) -> Self::V {
            zip(a, b, |x, y| x + y)
        }
        fn sub(self, a: Self::V, b: Self::V) -> Self::V {
            zip(a, b, |x, y| x - y)
        }
        fn mul(self, a: Self::V, b: Self::V) -> Self::V {
            zip(a, b, |x, y| x * y)
        }
        fn div(self, a: Self::V, b: Self::V) -> Self::V {
            zip(a, b, |x, y| x / y)
        }
        fn splat(self, x: f32) -> Self::V {
            [x; 8]
        }
        fn load(self, s: &[f32], b: usize) -> Self::V {
            s[b..b + 8].try_into().expect("8 values")
        }
        fn neg(self, a: Self::V) -> Self::V {
            a.map(|x| -x)
        }
        fn finite(self, x: Self::V) -> Self::M {
            x.map(f32::is_finite)
        }
        fn select(self, m: Self::M, a: Self::V, b: Self::V) -> Self::V {
            std::array::from_fn(|l| if m[l] { a[l] } else { b[l] })
        }
        fn zero_w(self) -> Self::W {
            [0.0; 8]
        }
        fn flush(self, a: &mut Self::W, x: &Self::V) {
            for l in 0..8 {
                a[l] += x[l] as f64;
            }
        }
        fn sum(self, a: &Self::W) -> f64 {
            a.iter().fold(0.0, |s, &x| s + x)
        }
        #[cfg(test)]
        fn to_array(self, v: Self::V) -> [f32; 8] {
            v
        }
    }
}
