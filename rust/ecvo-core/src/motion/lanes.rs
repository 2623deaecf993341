//! Fixed-width lanes for MOTION's sums.
//!
//! The per-point loops are structure-of-arrays: one `f32` slice per quantity. Loops
//! that only map points to points are plain slice loops that the compiler
//! vectorises; loops that sum over points work on blocks of [`LANES`] points, each
//! lane keeping its own partial sums, which are added in lane order at the end. The
//! lane count is fixed (not the machine's vector width), so every lane sees the same
//! operations in the same order on every target: the sums have the same bits on
//! x86_64 (SSE2, and its AVX2 copies) and aarch64 (NEON). FMA is never used.
//!
//! [`V`] is two 4-lane vectors written with the target's intrinsics (SSE2 on x86_64,
//! NEON on aarch64; both in the baseline of their targets), an array elsewhere (or
//! with `--cfg ecvo_portable_lanes`). Plain
//! arrays were tried first: the compiler vectorised the arithmetic but kept the
//! loop-carried sums as scalars and rebuilt vectors from them every block.

/// Points per block of a summing loop.
pub(super) const LANES: usize = 8;

#[cfg(test)]
pub(super) use imp::to_array;
pub(super) use imp::{
    M, V, W, acc, add, div, finite, flush, load, mul, neg, select, splat, sub, sum,
};

#[cfg(all(target_arch = "x86_64", not(ecvo_portable_lanes)))]
#[allow(unused_unsafe)]
mod imp {
    //! SSE2 (baseline on x86_64). The intrinsics used are safe to call where SSE2 is
    //! enabled, which it always is; the `unsafe` blocks are for older compilers
    //! and the unaligned loads.
    use std::arch::x86_64::*;

    /// Eight `f32` lanes.
    #[derive(Clone, Copy, Debug)]
    pub(in super::super) struct V(__m128, __m128);
    /// A lane mask (all ones or all zeros per lane).
    #[derive(Clone, Copy, Debug)]
    pub(in super::super) struct M(__m128, __m128);
    /// Eight `f64` lanes.
    #[derive(Clone, Copy, Debug)]
    pub(in super::super) struct W([__m128d; 4]);

    macro_rules! binary {
        ($($name:ident = $op:ident),*) => {$(
            #[doc = concat!("`", stringify!($op), "` lane by lane.")]
            #[inline(always)]
            pub(in super::super) fn $name(a: V, b: V) -> V {
                unsafe { V($op(a.0, b.0), $op(a.1, b.1)) }
            }
        )*};
    }
    binary!(
        add = _mm_add_ps,
        sub = _mm_sub_ps,
        mul = _mm_mul_ps,
        div = _mm_div_ps
    );

    /// `[x; 8]`.
    #[inline(always)]
    pub(in super::super) fn splat(x: f32) -> V {
        unsafe { V(_mm_set1_ps(x), _mm_set1_ps(x)) }
    }

    /// The 8 values of `s` at `b`.
    #[inline(always)]
    pub(in super::super) fn load(s: &[f32], b: usize) -> V {
        let s = &s[b..b + 8];
        // SAFETY: `s` has 8 elements; the loads are unaligned.
        unsafe { V(_mm_loadu_ps(s.as_ptr()), _mm_loadu_ps(s.as_ptr().add(4))) }
    }

    /// The lanes as an array.
    #[cfg(test)]
    pub(in super::super) fn to_array(v: V) -> [f32; 8] {
        let mut o = [0.0; 8];
        // SAFETY: `o` has 8 elements; the stores are unaligned.
        unsafe {
            _mm_storeu_ps(o.as_mut_ptr(), v.0);
            _mm_storeu_ps(o.as_mut_ptr().add(4), v.1);
        }
        o
    }

    /// `-a` (the sign bit flipped, as scalar negation does).
    #[inline(always)]
    pub(in super::super) fn neg(a: V) -> V {
        unsafe {
            let s = _mm_set1_ps(-0.0);
            V(_mm_xor_ps(a.0, s), _mm_xor_ps(a.1, s))
        }
    }

    /// True where `x` is finite (`|x| < ∞`, false for NaN).
    #[inline(always)]
    pub(in super::super) fn finite(x: V) -> M {
        unsafe {
            let (s, inf) = (_mm_set1_ps(-0.0), _mm_set1_ps(f32::INFINITY));
            M(
                _mm_cmplt_ps(_mm_andnot_ps(s, x.0), inf),
                _mm_cmplt_ps(_mm_andnot_ps(s, x.1), inf),
            )
        }
    }

    /// `m ? a : b` lane by lane.
    #[inline(always)]
    pub(in super::super) fn select(m: M, a: V, b: V) -> V {
        unsafe {
            V(
                _mm_or_ps(_mm_and_ps(m.0, a.0), _mm_andnot_ps(m.0, b.0)),
                _mm_or_ps(_mm_and_ps(m.1, a.1), _mm_andnot_ps(m.1, b.1)),
            )
        }
    }

    /// `a += x` lane by lane.
    #[inline(always)]
    pub(in super::super) fn acc(a: &mut V, x: V) {
        *a = add(*a, x);
    }

    impl Default for W {
        fn default() -> Self {
            unsafe { W([_mm_setzero_pd(); 4]) }
        }
    }

    /// `a += x` lane by lane in double precision.
    #[inline(always)]
    pub(in super::super) fn flush(a: &mut W, x: &V) {
        unsafe {
            let w = [
                _mm_cvtps_pd(x.0),
                _mm_cvtps_pd(_mm_movehl_ps(x.0, x.0)),
                _mm_cvtps_pd(x.1),
                _mm_cvtps_pd(_mm_movehl_ps(x.1, x.1)),
            ];
            for k in 0..4 {
                a.0[k] = _mm_add_pd(a.0[k], w[k]);
            }
        }
    }

    /// The lanes of `a` added in lane order.
    pub(in super::super) fn sum(a: &W) -> f64 {
        let mut o = [0.0f64; 8];
        for k in 0..4 {
            // SAFETY: two elements of `o` from `2 k`; the store is unaligned.
            unsafe { _mm_storeu_pd(o.as_mut_ptr().add(2 * k), a.0[k]) };
        }
        o.iter().fold(0.0, |s, &x| s + x)
    }
}

#[cfg(all(target_arch = "aarch64", not(ecvo_portable_lanes)))]
#[allow(unused_unsafe)]
mod imp {
    //! NEON (baseline on aarch64). The intrinsics used are safe to call where NEON is
    //! enabled, which it always is; the `unsafe` blocks are for older compilers
    //! and the loads and stores.
    use std::arch::aarch64::*;

    /// Eight `f32` lanes.
    #[derive(Clone, Copy, Debug)]
    pub(in super::super) struct V(float32x4_t, float32x4_t);
    /// A lane mask (all ones or all zeros per lane).
    #[derive(Clone, Copy, Debug)]
    pub(in super::super) struct M(uint32x4_t, uint32x4_t);
    /// Eight `f64` lanes.
    #[derive(Clone, Copy, Debug)]
    pub(in super::super) struct W([float64x2_t; 4]);

    macro_rules! binary {
        ($($name:ident = $op:ident),*) => {$(
            #[doc = concat!("`", stringify!($op), "` lane by lane.")]
            #[inline(always)]
            pub(in super::super) fn $name(a: V, b: V) -> V {
                unsafe { V($op(a.0, b.0), $op(a.1, b.1)) }
            }
        )*};
    }
    binary!(
        add = vaddq_f32,
        sub = vsubq_f32,
        mul = vmulq_f32,
        div = vdivq_f32
    );

    /// `[x; 8]`.
    #[inline(always)]
    pub(in super::super) fn splat(x: f32) -> V {
        unsafe { V(vdupq_n_f32(x), vdupq_n_f32(x)) }
    }

    /// The 8 values of `s` at `b`.
    #[inline(always)]
    pub(in super::super) fn load(s: &[f32], b: usize) -> V {
        let s = &s[b..b + 8];
        // SAFETY: `s` has 8 elements.
        unsafe { V(vld1q_f32(s.as_ptr()), vld1q_f32(s.as_ptr().add(4))) }
    }

    /// The lanes as an array.
    #[cfg(test)]
    pub(in super::super) fn to_array(v: V) -> [f32; 8] {
        let mut o = [0.0; 8];
        // SAFETY: `o` has 8 elements.
        unsafe {
            vst1q_f32(o.as_mut_ptr(), v.0);
            vst1q_f32(o.as_mut_ptr().add(4), v.1);
        }
        o
    }

    /// `-a`.
    #[inline(always)]
    pub(in super::super) fn neg(a: V) -> V {
        unsafe { V(vnegq_f32(a.0), vnegq_f32(a.1)) }
    }

    /// True where `x` is finite (`|x| < ∞`, false for NaN).
    #[inline(always)]
    pub(in super::super) fn finite(x: V) -> M {
        unsafe {
            let inf = vdupq_n_f32(f32::INFINITY);
            M(
                vcltq_f32(vabsq_f32(x.0), inf),
                vcltq_f32(vabsq_f32(x.1), inf),
            )
        }
    }

    /// `m ? a : b` lane by lane.
    #[inline(always)]
    pub(in super::super) fn select(m: M, a: V, b: V) -> V {
        unsafe { V(vbslq_f32(m.0, a.0, b.0), vbslq_f32(m.1, a.1, b.1)) }
    }

    /// `a += x` lane by lane.
    #[inline(always)]
    pub(in super::super) fn acc(a: &mut V, x: V) {
        *a = add(*a, x);
    }

    impl Default for W {
        fn default() -> Self {
            unsafe { W([vdupq_n_f64(0.0); 4]) }
        }
    }

    /// `a += x` lane by lane in double precision.
    #[inline(always)]
    pub(in super::super) fn flush(a: &mut W, x: &V) {
        unsafe {
            let w = [
                vcvt_f64_f32(vget_low_f32(x.0)),
                vcvt_high_f64_f32(x.0),
                vcvt_f64_f32(vget_low_f32(x.1)),
                vcvt_high_f64_f32(x.1),
            ];
            for k in 0..4 {
                a.0[k] = vaddq_f64(a.0[k], w[k]);
            }
        }
    }

    /// The lanes of `a` added in lane order.
    pub(in super::super) fn sum(a: &W) -> f64 {
        let mut o = [0.0f64; 8];
        for k in 0..4 {
            // SAFETY: two elements of `o` from `2 k`.
            unsafe { vst1q_f64(o.as_mut_ptr().add(2 * k), a.0[k]) };
        }
        o.iter().fold(0.0, |s, &x| s + x)
    }
}

#[cfg(any(
    ecvo_portable_lanes,
    not(any(target_arch = "x86_64", target_arch = "aarch64"))
))]
mod imp {
    //! Plain arrays elsewhere, and everywhere with `--cfg ecvo_portable_lanes` (to
    //! measure the intrinsics against them).

    /// Eight `f32` lanes.
    pub(in super::super) type V = [f32; 8];
    /// A lane mask.
    pub(in super::super) type M = [bool; 8];
    /// Eight `f64` lanes.
    pub(in super::super) type W = [f64; 8];

    fn zip(a: V, b: V, f: impl Fn(f32, f32) -> f32) -> V {
        std::array::from_fn(|l| f(a[l], b[l]))
    }
    /// `a + b` lane by lane.
    pub(in super::super) fn add(a: V, b: V) -> V {
        zip(a, b, |x, y| x + y)
    }
    /// `a - b` lane by lane.
    pub(in super::super) fn sub(a: V, b: V) -> V {
        zip(a, b, |x, y| x - y)
    }
    /// `a * b` lane by lane.
    pub(in super::super) fn mul(a: V, b: V) -> V {
        zip(a, b, |x, y| x * y)
    }
    /// `a / b` lane by lane.
    pub(in super::super) fn div(a: V, b: V) -> V {
        zip(a, b, |x, y| x / y)
    }
    /// `[x; 8]`.
    pub(in super::super) fn splat(x: f32) -> V {
        [x; 8]
    }
    /// The 8 values of `s` at `b`.
    pub(in super::super) fn load(s: &[f32], b: usize) -> V {
        s[b..b + 8].try_into().expect("8 values")
    }
    /// The lanes as an array.
    #[cfg(test)]
    pub(in super::super) fn to_array(v: V) -> [f32; 8] {
        v
    }
    /// `-a`.
    pub(in super::super) fn neg(a: V) -> V {
        a.map(|x| -x)
    }
    /// True where `x` is finite.
    pub(in super::super) fn finite(x: V) -> M {
        x.map(f32::is_finite)
    }
    /// `m ? a : b` lane by lane.
    pub(in super::super) fn select(m: M, a: V, b: V) -> V {
        std::array::from_fn(|l| if m[l] { a[l] } else { b[l] })
    }
    /// `a += x` lane by lane.
    pub(in super::super) fn acc(a: &mut V, x: V) {
        *a = add(*a, x);
    }
    /// `a += x` lane by lane in double precision.
    pub(in super::super) fn flush(a: &mut W, x: &V) {
        for l in 0..8 {
            a[l] += x[l] as f64;
        }
    }
    /// The lanes of `a` added in lane order.
    pub(in super::super) fn sum(a: &W) -> f64 {
        a.iter().fold(0.0, |s, &x| s + x)
    }
}
