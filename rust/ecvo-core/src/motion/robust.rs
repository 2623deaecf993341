//! The t-distribution weights over a chunk of residuals: the fixed-point passes of
//! the scale fit and the robust cost ([`crate::scale`] has the model), in
//! [`LANES`]-wide blocks.
//!
//! A residual without depth (`r_Z` NaN) takes the one-dimensional branch through
//! lane masks instead of a jump: its `r_Z` is replaced by 0, its `L` by
//! `[[l1d, 0], [0, l22]]`, and every product that would involve the missing residual
//! is then 0, so each residual gets the bits [`Whitener::weigh`] gives it.

use super::lanes::{LANES, Lanes, lanes_multiversion};
use super::warp::Chunk;
use crate::config::Weighting;
use crate::scale::{PassSums, Whitener};

/// Points per run of single-precision sums (each lane adds `RUN / LANES` points)
/// before they are added into double precision: the normal equations' run, so that
/// the cost they add up has the bits of [`cost`]'s and [`pass`]'s.
pub(super) const RUN: usize = 128;

/// What the weight of a block of residuals needs.
pub(super) struct Weighed<L: Lanes> {
    /// Lanes with a depth residual.
    pub(super) two: L::M,
    /// `r_Z`, 0 where it is missing.
    pub(super) rz: L::V,
    /// The whitened photometric row's residual `l11 r_I + l12 r_Z` (`l1d r_I` without
    /// depth).
    pub(super) a: L::V,
    /// The whitened depth row's residual `l22 r_Z` (0 without depth).
    pub(super) b: L::V,
    /// `d² = a² + b²`.
    pub(super) d2: L::V,
    /// The weight `(ν + k) / (ν + d²)`.
    pub(super) w: L::V,
}

/// The weights of a block: the per-lane form of [`Whitener::weigh`].
#[inline(always)]
pub(super) fn weigh<L: Lanes>(l: L, wh: &Whitener, ri: L::V, rz: L::V) -> Weighed<L> {
    let two = l.finite(rz);
    let zero = l.splat(0.0);
    let rz = l.select(two, rz, zero);
    let l1 = l.select(two, l.splat(wh.l11), l.splat(wh.l1d));
    let l12 = l.select(two, l.splat(wh.l12), zero);
    let a = l.add(l.mul(l1, ri), l.mul(l12, rz));
    let b = l.mul(l.splat(wh.l22), rz);
    let d2 = l.add(l.mul(a, a), l.mul(b, b));
    let k = l.select(two, l.splat(2.0), l.splat(1.0));
    let w = l.div(l.add(l.splat(wh.nu), k), l.add(l.splat(wh.nu), d2));
    Weighed {
        two,
        rz,
        a,
        b,
        d2,
        w,
    }
}

/// One fixed-point pass over a chunk (see [`crate::scale::pass`]), and the chunk's
/// `Σ w d²` at the same scale (the bits of [`cost`]).
pub(super) fn pass(c: &Chunk, wh: &Whitener, weighting: Weighting) -> (PassSums, f64) {
    let n = c.padded();
    pass_sums(&c.ri[..n], &c.rz[..n], wh, weighting == Weighting::Scalar)
}

lanes_multiversion! {
    /// `Σ w r_I²`, `Σ w r_I r_Z`, `Σ w r_Z²` over the residuals with depth and
    /// `Σ w r_I²` over the others (`scalar`: half of `w (r_I² + r_Z²)` in the first
    /// and third), summed by lane in f32 over runs of [`RUN`] points, by lane in f64
    /// across runs, then lane after lane; and `Σ w d²`, summed alike.
    fn pass_sums(ri: &[f32], rz: &[f32], wh: &Whitener, scalar: bool) -> (PassSums, f64) = pass_kernel;
}

#[inline(always)]
fn pass_kernel<L: Lanes>(
    l: L,
    ri: &[f32],
    rz: &[f32],
    wh: &Whitener,
    scalar: bool,
) -> (PassSums, f64) {
    let mut total = [l.zero_w(); 4];
    let mut cost = l.zero_w();
    let n = ri.len();
    let rz = &rz[..n];
    let zero = l.splat(0.0);
    for start in (0..n).step_by(RUN) {
        let mut p = [zero; 4];
        let mut e = zero;
        for b in (start..n.min(start + RUN)).step_by(LANES) {
            let r = l.load(ri, b);
            let q = weigh(l, wh, r, l.load(rz, b));
            l.acc(&mut e, l.mul(q.w, q.d2));
            let wr = l.mul(q.w, r);
            let ii = l.mul(wr, r);
            if scalar {
                // σ² I over (r_I, λ r_Z): one scale for both.
                let e = l.mul(
                    l.mul(q.w, l.add(l.mul(r, r), l.mul(q.rz, q.rz))),
                    l.splat(0.5),
                );
                let e = l.select(q.two, e, zero);
                l.acc(&mut p[0], e);
                l.acc(&mut p[2], e);
            } else {
                l.acc(&mut p[0], l.select(q.two, ii, zero));
                l.acc(&mut p[1], l.mul(wr, q.rz));
                l.acc(&mut p[2], l.mul(l.mul(q.w, q.rz), q.rz));
            }
            l.acc(&mut p[3], l.select(q.two, zero, ii));
        }
        for k in 0..4 {
            l.flush(&mut total[k], &p[k]);
        }
        l.flush(&mut cost, &e);
    }
    (total.map(|t| l.sum(&t)), l.sum(&cost))
}

/// `Σ w d²` over a chunk at a fixed scale (summed like [`pass_sums`]).
pub(super) fn cost(c: &Chunk, wh: &Whitener) -> f64 {
    let n = c.padded();
    cost_sum(&c.ri[..n], &c.rz[..n], wh)
}

lanes_multiversion! {
    /// `Σ w d²` (see [`cost`]).
    fn cost_sum(ri: &[f32], rz: &[f32], wh: &Whitener) -> f64 = cost_kernel;
}

#[inline(always)]
fn cost_kernel<L: Lanes>(l: L, ri: &[f32], rz: &[f32], wh: &Whitener) -> f64 {
    let mut total = l.zero_w();
    let n = ri.len();
    let rz = &rz[..n];
    for start in (0..n).step_by(RUN) {
        let mut e = l.splat(0.0);
        for b in (start..n.min(start + RUN)).step_by(LANES) {
            let q = weigh(l, wh, l.load(ri, b), l.load(rz, b));
            l.acc(&mut e, l.mul(q.w, q.d2));
        }
        l.flush(&mut total, &e);
    }
    l.sum(&total)
}

/// The plain second moments of a chunk's residuals (weight 1 everywhere), in f64 and
/// point order, as [`crate::scale::initial_scale`] sums them.
pub(super) fn moments(c: &Chunk, weighting: Weighting) -> PassSums {
    let mut acc = [0.0f64; 4];
    for (&ri, &rz) in c.ri[..c.n].iter().zip(&c.rz[..c.n]) {
        crate::scale::add_moments(&mut acc, ri, rz, weighting);
    }
    acc
}
