//! Fixed-width lanes for MOTION's sums.
//!
//! The per-point loops are structure-of-arrays: one `f32` slice per quantity. Loops
//! that only map points to points are plain slice loops that the compiler
//! vectorises; loops that sum over points work on blocks of [`LANES`] points, each
//! lane keeping its own partial sums, which are added in lane order at the end of a
//! run. The lane count is fixed (not the machine's vector width), so every lane sees
//! the same operations in the same order on SSE2 (two 4-wide vectors), AVX2 (one
//! 8-wide vector) and NEON (two 4-wide vectors): the sums have the same bits on every
//! path. FMA is never enabled and Rust does not contract `a * b + c`.

/// Points per block of a summing loop.
pub(super) const LANES: usize = 8;

/// One value per lane.
pub(super) type V = [f32; LANES];

/// `[x; LANES]`.
#[inline(always)]
pub(super) fn splat(x: f32) -> V {
    [x; LANES]
}

/// The block of `LANES` values at `b` (a multiple of `LANES` inside `s`).
#[inline(always)]
pub(super) fn load(s: &[f32], b: usize) -> V {
    let mut o = [0.0; LANES];
    o.copy_from_slice(&s[b..b + LANES]);
    o
}

/// `f(a[l], b[l])` lane by lane.
#[inline(always)]
pub(super) fn zip(a: V, b: V, f: impl Fn(f32, f32) -> f32) -> V {
    let mut o = [0.0; LANES];
    for l in 0..LANES {
        o[l] = f(a[l], b[l]);
    }
    o
}

/// `a + b` lane by lane.
#[inline(always)]
pub(super) fn add(a: V, b: V) -> V {
    zip(a, b, |x, y| x + y)
}

/// `a - b` lane by lane.
#[inline(always)]
pub(super) fn sub(a: V, b: V) -> V {
    zip(a, b, |x, y| x - y)
}

/// `a * b` lane by lane.
#[inline(always)]
pub(super) fn mul(a: V, b: V) -> V {
    zip(a, b, |x, y| x * y)
}

/// `a / b` lane by lane.
#[inline(always)]
pub(super) fn div(a: V, b: V) -> V {
    zip(a, b, |x, y| x / y)
}

/// A lane mask: all ones where `x` is finite (not NaN, not infinite).
#[inline(always)]
pub(super) fn finite(x: V) -> [u32; LANES] {
    let mut o = [0; LANES];
    for l in 0..LANES {
        o[l] = if x[l].abs() < f32::INFINITY { !0 } else { 0 };
    }
    o
}

/// `m ? a : b` lane by lane (bitwise, so that it stays branch-free).
#[inline(always)]
pub(super) fn select(m: [u32; LANES], a: V, b: V) -> V {
    let mut o = [0.0; LANES];
    for l in 0..LANES {
        o[l] = f32::from_bits((a[l].to_bits() & m[l]) | (b[l].to_bits() & !m[l]));
    }
    o
}

/// `acc += x` lane by lane.
#[inline(always)]
pub(super) fn acc(a: &mut V, x: V) {
    for l in 0..LANES {
        a[l] += x[l];
    }
}

/// The lanes of `a` summed in double precision, in lane order.
#[inline(always)]
pub(super) fn sum64(a: &V) -> f64 {
    let mut s = 0.0f64;
    for &x in a {
        s += x as f64;
    }
    s
}
