//! The t-distribution weights over a chunk of residuals: the fixed-point passes of
//! the scale fit and the robust cost ([`crate::scale`] has the model), in
//! [`LANES`]-wide blocks.
//!
//! A residual without depth (`r_Z` NaN) takes the one-dimensional branch through
//! lane masks instead of a jump: its `r_Z` is replaced by 0, its `L` by
//! `[[l1d, 0], [0, l22]]`, and every product that would involve the missing residual
//! is then 0, so each residual gets the bits [`Whitener::weigh`] gives it.

use super::lanes::{self, LANES, V};
use super::warp::Chunk;
use crate::config::Weighting;
use crate::prepare::simd::multiversion;
use crate::scale::{PassSums, Whitener};

/// Points per run of single-precision sums (each lane adds `RUN / LANES` points)
/// before they are added into double precision.
const RUN: usize = 256;

/// What the weight of a block of residuals needs.
pub(super) struct Weighed {
    /// Lanes with a depth residual.
    pub(super) two: lanes::M,
    /// `r_Z`, 0 where it is missing.
    pub(super) rz: V,
    /// The whitened photometric row's residual `l11 r_I + l12 r_Z` (`l1d r_I` without
    /// depth).
    pub(super) a: V,
    /// The whitened depth row's residual `l22 r_Z` (0 without depth).
    pub(super) b: V,
    /// `d² = a² + b²`.
    pub(super) d2: V,
    /// The weight `(ν + k) / (ν + d²)`.
    pub(super) w: V,
}

/// The weights of a block: the per-lane form of [`Whitener::weigh`].
#[inline(always)]
pub(super) fn weigh(wh: &Whitener, ri: V, rz: V) -> Weighed {
    let two = lanes::finite(rz);
    let zero = lanes::splat(0.0);
    let rz = lanes::select(two, rz, zero);
    let l1 = lanes::select(two, lanes::splat(wh.l11), lanes::splat(wh.l1d));
    let l12 = lanes::select(two, lanes::splat(wh.l12), zero);
    let a = lanes::add(lanes::mul(l1, ri), lanes::mul(l12, rz));
    let b = lanes::mul(lanes::splat(wh.l22), rz);
    let d2 = lanes::add(lanes::mul(a, a), lanes::mul(b, b));
    let k = lanes::select(two, lanes::splat(2.0), lanes::splat(1.0));
    let w = lanes::div(
        lanes::add(lanes::splat(wh.nu), k),
        lanes::add(lanes::splat(wh.nu), d2),
    );
    Weighed {
        two,
        rz,
        a,
        b,
        d2,
        w,
    }
}

/// One fixed-point pass over a chunk (see [`crate::scale::pass`]).
pub(super) fn pass(c: &Chunk, wh: &Whitener, weighting: Weighting) -> PassSums {
    let n = c.padded();
    pass_sums(&c.ri[..n], &c.rz[..n], wh, weighting == Weighting::Scalar)
}

multiversion! {
    /// `Σ w r_I²`, `Σ w r_I r_Z`, `Σ w r_Z²` over the residuals with depth and
    /// `Σ w r_I²` over the others (`scalar`: half of `w (r_I² + r_Z²)` in the first
    /// and third), summed by lane in f32 over runs of [`RUN`] points, by lane in f64
    /// across runs, then lane after lane.
    fn pass_sums(ri: &[f32], rz: &[f32], wh: &Whitener, scalar: bool) -> PassSums = pass_kernel;
}

#[inline(always)]
fn pass_kernel(ri: &[f32], rz: &[f32], wh: &Whitener, scalar: bool) -> PassSums {
    let mut total = [lanes::W::default(); 4];
    let n = ri.len();
    let rz = &rz[..n];
    let zero = lanes::splat(0.0);
    for start in (0..n).step_by(RUN) {
        let mut p = [zero; 4];
        for b in (start..n.min(start + RUN)).step_by(LANES) {
            let r = lanes::load(ri, b);
            let q = weigh(wh, r, lanes::load(rz, b));
            let wr = lanes::mul(q.w, r);
            let ii = lanes::mul(wr, r);
            if scalar {
                // σ² I over (r_I, λ r_Z): one scale for both.
                let e = lanes::mul(
                    lanes::mul(q.w, lanes::add(lanes::mul(r, r), lanes::mul(q.rz, q.rz))),
                    lanes::splat(0.5),
                );
                let e = lanes::select(q.two, e, zero);
                lanes::acc(&mut p[0], e);
                lanes::acc(&mut p[2], e);
            } else {
                lanes::acc(&mut p[0], lanes::select(q.two, ii, zero));
                lanes::acc(&mut p[1], lanes::mul(wr, q.rz));
                lanes::acc(&mut p[2], lanes::mul(lanes::mul(q.w, q.rz), q.rz));
            }
            lanes::acc(&mut p[3], lanes::select(q.two, zero, ii));
        }
        for k in 0..4 {
            lanes::flush(&mut total[k], &p[k]);
        }
    }
    total.map(|t| lanes::sum(&t))
}

/// `Σ w d²` over a chunk at a fixed scale (summed like [`pass_sums`]).
pub(super) fn cost(c: &Chunk, wh: &Whitener) -> f64 {
    let n = c.padded();
    cost_sum(&c.ri[..n], &c.rz[..n], wh)
}

multiversion! {
    /// `Σ w d²` (see [`cost`]).
    fn cost_sum(ri: &[f32], rz: &[f32], wh: &Whitener) -> f64 = cost_kernel;
}

#[inline(always)]
fn cost_kernel(ri: &[f32], rz: &[f32], wh: &Whitener) -> f64 {
    let mut total = lanes::W::default();
    let n = ri.len();
    let rz = &rz[..n];
    for start in (0..n).step_by(RUN) {
        let mut e = lanes::splat(0.0);
        for b in (start..n.min(start + RUN)).step_by(LANES) {
            let q = weigh(wh, lanes::load(ri, b), lanes::load(rz, b));
            lanes::acc(&mut e, lanes::mul(q.w, q.d2));
        }
        lanes::flush(&mut total, &e);
    }
    lanes::sum(&total)
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
